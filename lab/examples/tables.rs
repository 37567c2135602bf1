//! The measurement tables of the README: what a sample's colour should be, and the PSNR of
//! each reconstruction at the paper's sample counts, as means over a folder of photographs.
//!
//! ```text
//! cargo run --release -p qcs-lab --example tables -- ../shared/corpus/dev
//! ```

use qcs::reconstruction::{render, Method};
use qcs::sampling::{SampleColour, SourceImage};
use qcs::sites::Quasicrystal;

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths = common::photo_paths()?;
    let rules = [
        ("nearest", SampleColour::Nearest),
        ("bilinear", SampleColour::Bilinear),
        ("area", SampleColour::Area),
        ("progressive", SampleColour::Progressive),
        ("fitted (first level 127)", SampleColour::Fitted),
    ];
    let shares = [0.01, 0.05, 0.25, 1.0];
    let counts = [1089usize, 4225, 16641];
    let methods = [
        Method::Gouraud,
        Method::Shepard,
        Method::Natural,
        Method::Cubic,
    ];
    let mut colour_table = vec![[0.0f64; 4]; rules.len()];
    let mut recon_table = vec![[0.0f64; 3]; methods.len()];
    for path in &paths {
        let img = image::open(path)?.to_rgb8();
        let (w, h) = img.dimensions();
        let n = (w as usize * h as usize) / 8;
        let seq = Quasicrystal::new(w, h)?;
        let exact = seq.first(n);
        let sites: Vec<_> = exact.iter().map(|s| s.pos).collect();
        let src = SourceImage::new(img.as_raw(), w, h, 3)?;
        for (r, (_, rule)) in rules.iter().enumerate() {
            let colours = match rule {
                SampleColour::Fitted => src.fitted(&exact, seq.frame(), 127, n),
                _ => src.colours(&sites, *rule, n),
            };
            for (s, share) in shares.iter().enumerate() {
                let k = ((n as f64 * share) as usize).max(3);
                let px = render(
                    (w, h),
                    3,
                    &sites[..k],
                    &colours[..k * 3],
                    Method::Gouraud,
                    w,
                    h,
                );
                colour_table[r][s] +=
                    qcs_lab::eval::psnr_bytes(img.as_raw(), &px)? / paths.len() as f64;
            }
        }
        for (c, &k) in counts.iter().enumerate() {
            let colours = src.colours(&sites[..k], SampleColour::Area, k);
            for (m, method) in methods.iter().enumerate() {
                let px = render((w, h), 3, &sites[..k], &colours, *method, w, h);
                recon_table[m][c] +=
                    qcs_lab::eval::psnr_bytes(img.as_raw(), &px)? / paths.len() as f64;
            }
        }
        eprintln!("{}", path.display());
    }
    println!("Sample colour (raw 8-bit, N = W·H/8, Gouraud), mean PSNR over {} photos, at a share of the N samples:\n", paths.len());
    println!("| sample colour | 1% | 5% | 25% | 100% |\n|---|---|---|---|---|");
    for (r, (name, _)) in rules.iter().enumerate() {
        let v = colour_table[r];
        println!(
            "| {name} | {:.2} | {:.2} | {:.2} | {:.2} |",
            v[0], v[1], v[2], v[3]
        );
    }
    println!("\nReconstruction (quasicrystal sites, area-mean colours), mean PSNR:\n");
    println!("| method | 1089 | 4225 | 16641 |\n|---|---|---|---|");
    for (m, method) in methods.iter().enumerate() {
        let v = recon_table[m];
        println!("| {method:?} | {:.2} | {:.2} | {:.2} |", v[0], v[1], v[2]);
    }
    Ok(())
}
