//! How far point samples can go: the PSNR of the Gouraud render from the first N samples
//! when their colours are exact (lossless coding, so no quantisation at all), as a mean over
//! a set of photographs, and what that says about a byte budget.
//!
//! ```text
//! cargo run --release -p qcs-lab --example bound -- ../shared/corpus/dev/*.png
//! ```
//!
//! For each budget of the peers' table where JPEG 2000 leads, it prints the N at which exact
//! samples first reach JPEG 2000's PSNR (log-linear between the measured counts) and the bits
//! per sample the budget then leaves for a colour. Any coding of point samples rendered by
//! Gouraud needs at least that N to tie JPEG 2000, and its colours cost more than nothing.
//!
//! The colours are the encoder's default choice (`SampleColour::Fitted`); the README also
//! gives the figures of the progressive area means, from before that was the default.

use qcs::coding::predictive::Params;
use qcs::{DecodeOptions, EncodeOptions};

const COUNTS: [u64; 8] = [1000, 2000, 4000, 8000, 16000, 32000, 64000, 128000];

/// JPEG 2000 (18 quality layers, OpenJPEG) on the dev photographs, from
/// `../shared/peers-dev.md`: (budget in bytes, mean PSNR).
const J2K: [(u64, f64); 5] = [
    (512, 19.13),
    (1024, 21.80),
    (2048, 23.82),
    (4096, 25.77),
    (8192, 28.13),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    let opts = EncodeOptions {
        coding: Params::lossless().coding(),
        density: 1.0,
        ..Default::default()
    };
    let mut mean = [0.0f64; COUNTS.len()];
    println!("image,samples,psnr");
    for path in &paths {
        let rgb = image::open(path)?.to_rgb8();
        let bytes = qcs::encode(&image::DynamicImage::ImageRgb8(rgb.clone()), &opts)?;
        for (m, &n) in mean.iter_mut().zip(&COUNTS) {
            let d = qcs::decode(
                &bytes,
                &DecodeOptions {
                    max_samples: Some(n),
                    ..Default::default()
                },
            )?;
            let p = qcs_lab::eval::psnr_bytes(&d.image.to_rgb8().into_raw(), rgb.as_raw())?;
            println!("{path},{n},{p:.2}");
            *m += p / paths.len().max(1) as f64;
        }
    }
    println!();
    println!(
        "| exact samples | {} |",
        COUNTS.map(|n| n.to_string()).join(" | ")
    );
    println!("|---{}|", "|---".repeat(COUNTS.len()));
    println!(
        "| mean PSNR (dB) | {} |",
        mean.map(|p| format!("{p:.2}")).join(" | ")
    );
    println!();
    println!("| budget | JPEG 2000 | exact samples to tie it | bits per sample left |");
    println!("|---|---|---|---|");
    for (budget, target) in J2K {
        let last = COUNTS.len() - 1;
        match mean.iter().position(|&p| p >= target) {
            Some(0) => println!("| {budget} B | {target:.2} | at most {} | |", COUNTS[0]),
            Some(k) => {
                let t = (target - mean[k - 1]) / (mean[k] - mean[k - 1]);
                let (a, b) = ((COUNTS[k - 1] as f64).ln(), (COUNTS[k] as f64).ln());
                let n = (a + t * (b - a)).exp();
                let bits = 8.0 * budget as f64 / n;
                println!("| {budget} B | {target:.2} | {n:.0} | {bits:.2} |");
            }
            None => println!(
                "| {budget} B | {target:.2} | more than {} | below {:.2} |",
                COUNTS[last],
                8.0 * budget as f64 / COUNTS[last] as f64
            ),
        }
    }
    Ok(())
}
