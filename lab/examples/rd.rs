//! Rate–distortion of the quasicrystal levels alone (format version 2, `Target::LevelsOnly`)
//! beside a progressive JPEG: the levels' table of MEASUREMENTS.md. `lab/examples/peers.py`
//! measures the encoder's default files (levels, then the refinement) against the peers.
//!
//! ```text
//! cargo run --release -p qcs-lab --example rd -- [--quality Q | --lossless] [--density D] [--first L0]
//!     [--colour fitted|progressive|area|nearest|bilinear] [--method gouraud|cubic|shepard|natural]
//!     IMAGE...
//! ```
//!
//! Defaults: predictive coding at quality 50, density 1/4, first level 127 (MEASUREMENTS.md's table).
//!
//! For each image: the PSNR (dB, MSE pooled over R, G, B) of the full-size render (Gouraud
//! unless `--method` says otherwise) of the
//! first B bytes of the qcs file, B = 32, 64, …, 8192 and the whole file; and the same for a
//! progressive JPEG (jpeg-encoder, quality 75) decoded cut with `image` (zune-jpeg). A cut that
//! does not decode counts as flat grey (128). Prints CSV rows, then the mean over the images as
//! a Markdown table (the layout of peers-dev.md).

use qcs::coding::predictive::Params;
use qcs::container::Coding;
use qcs::sampling::SampleColour;
use qcs::{DecodeOptions, EncodeOptions, Method, Target};

/// The quality of the levels' rate–distortion table (the other settings are the levels-only
/// defaults: density 1/4, first level 127).
const RD_QUALITY: u8 = 50;

const BUDGETS: [usize; 9] = [32, 64, 128, 256, 512, 1024, 2048, 4096, 8192];

fn psnr(a: &[u8], b: &[u8]) -> f64 {
    // Identical pictures print as 100 dB, as in the peers' table.
    qcs_lab::eval::psnr_bytes(a, b)
        .expect("pictures of the same size")
        .min(100.0)
}

fn qcs_at(bytes: &[u8], budget: usize, reference: &[u8], method: Method) -> f64 {
    let opts = DecodeOptions {
        max_bytes: Some(budget),
        method,
        ..Default::default()
    };
    match qcs::decode(bytes, &opts) {
        Ok(d) => psnr(&d.image.to_rgb8().into_raw(), reference),
        Err(_) => psnr(&vec![128u8; reference.len()], reference),
    }
}

fn jpeg_at(jpg: &[u8], budget: usize, reference: &[u8], w: u32, h: u32) -> f64 {
    let cut = &jpg[..budget.min(jpg.len())];
    match image::load_from_memory_with_format(cut, image::ImageFormat::Jpeg) {
        Ok(img) if img.width() == w && img.height() == h => {
            psnr(&img.to_rgb8().into_raw(), reference)
        }
        _ => psnr(&vec![128u8; reference.len()], reference),
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mut opts = EncodeOptions {
        coding: Params::from_quality(RD_QUALITY).coding(),
        target: Target::LevelsOnly,
        ..Default::default()
    };
    let mut paths = Vec::new();
    let mut method = Method::Gouraud;
    while let Some(a) = args.next() {
        let mut val = || args.next().expect("a value after the flag");
        match a.as_str() {
            "--quality" => {
                let q: u8 = val().parse().expect("quality 0..=100");
                opts.coding = Params::from_quality(q).coding();
            }
            "--lossless" => opts.coding = Params::lossless().coding(),
            "--raw" => opts.coding = Coding::Raw { bits: 8 },
            "--density" => opts.density = val().parse().expect("density"),
            "--first" => opts.first_level = val().parse().expect("first level size"),
            "--colour" => {
                opts.colour = match val().as_str() {
                    "progressive" => SampleColour::Progressive,
                    "fitted" => SampleColour::Fitted,
                    "area" => SampleColour::Area,
                    "nearest" => SampleColour::Nearest,
                    "bilinear" => SampleColour::Bilinear,
                    other => panic!("unknown colour rule {other}"),
                }
            }
            "--method" => {
                method = match val().as_str() {
                    "gouraud" => Method::Gouraud,
                    "cubic" => Method::Cubic,
                    "shepard" => Method::Shepard,
                    "natural" => Method::Natural,
                    other => panic!("unknown method {other}"),
                }
            }
            _ => paths.push(a),
        }
    }
    println!("image,codec,budget,bytes,psnr");
    let n = BUDGETS.len() + 1;
    let mut sum_q = vec![0.0; n];
    let mut sum_j = vec![0.0; n];
    let (mut size_q, mut size_j, mut samples) = (0usize, 0usize, 0u64);
    for path in &paths {
        let img = image::open(path).expect("readable image");
        let rgb = img.to_rgb8();
        let (w, h) = rgb.dimensions();
        let reference = rgb.as_raw().clone();
        let img = image::DynamicImage::ImageRgb8(rgb);
        let bytes = qcs::encode(&img, &opts).expect("encode");
        let mut jpg = Vec::new();
        let mut enc = jpeg_encoder::Encoder::new(&mut jpg, 75);
        enc.set_progressive(true);
        enc.encode(&reference, w as u16, h as u16, jpeg_encoder::ColorType::Rgb)
            .expect("jpeg encode");
        let name = std::path::Path::new(path)
            .file_stem()
            .map_or_else(|| path.clone(), |s| s.to_string_lossy().into_owned());
        for (i, &b) in BUDGETS.iter().chain([&usize::MAX]).enumerate() {
            let q = qcs_at(&bytes, b, &reference, method);
            let j = jpeg_at(&jpg, b, &reference, w, h);
            let label = if b == usize::MAX {
                "full".to_string()
            } else {
                b.to_string()
            };
            println!("{name},qcs,{label},{},{q:.2}", b.min(bytes.len()));
            println!("{name},jpeg-prog-q75,{label},{},{j:.2}", b.min(jpg.len()));
            sum_q[i] += q;
            sum_j[i] += j;
        }
        size_q += bytes.len();
        size_j += jpg.len();
        samples += opts.sample_count(w, h);
    }
    let k = paths.len().max(1) as f64;
    println!();
    println!("| codec | 32 B | 64 B | 128 B | 256 B | 512 B | 1024 B | 2048 B | 4096 B | 8192 B | full file | mean size | bytes/sample |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (name, sums, size) in [
        ("qcs", &sum_q, size_q),
        ("jpeg-prog-q75 (jpeg-encoder, zune-jpeg)", &sum_j, size_j),
    ] {
        let cols: Vec<String> = sums.iter().map(|s| format!("{:.2}", s / k)).collect();
        let bps = if name == "qcs" {
            format!("{:.3}", size as f64 / samples.max(1) as f64)
        } else {
            String::new()
        };
        println!(
            "| {name} | {} | {:.0} B | {bps} |",
            cols.join(" | "),
            size as f64 / k
        );
    }
}
