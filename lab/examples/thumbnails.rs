//! The README's thumbnail table: pictures much smaller than the image, rendered plainly (every
//! sample at the pixel centres) or as thumbnails (`DecodeOptions::thumbnail`), against an
//! area-averaged downscale of the photograph (`image`'s `thumbnail_exact`). Mean PSNR over a
//! folder of photographs, each encoded at the defaults.
//!
//! ```text
//! cargo run --release -p qcs-lab --example thumbnails -- ../shared/corpus/dev
//! ```

use qcs::{decode, encode, DecodeOptions, EncodeOptions, Method};

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths = common::photo_paths()?;
    let files = paths
        .iter()
        .map(|p| {
            let img = image::open(p)?;
            let bytes = encode(&img, &EncodeOptions::default())?;
            Ok((img, bytes))
        })
        .collect::<Result<Vec<_>, Box<dyn std::error::Error>>>()?;
    println!(
        "| output | Gouraud, plain | Gouraud, thumbnail | Shepard, plain | Shepard, thumbnail |"
    );
    println!("|---|---|---|---|---|");
    for f in [2u32, 3, 4, 6, 8, 12, 16] {
        let mut sum = [0.0f64; 4];
        for (img, bytes) in &files {
            let (w, h) = ((img.width() / f).max(1), (img.height() / f).max(1));
            let reference = img.thumbnail_exact(w, h).to_rgb8();
            for (m, method) in [Method::Gouraud, Method::Shepard].into_iter().enumerate() {
                let thumb = DecodeOptions {
                    method,
                    ..DecodeOptions::thumbnail(w, h)
                };
                let all = DecodeOptions {
                    thumbnail: false,
                    ..thumb.clone()
                };
                for (k, opts) in [all, thumb].iter().enumerate() {
                    let pic = decode(bytes, opts)?.image.to_rgb8();
                    sum[2 * m + k] += qcs_lab::eval::psnr(&pic, &reference)?;
                }
            }
        }
        let n = files.len() as f64;
        let cells: Vec<String> = sum.iter().map(|s| format!("{:.2} dB", s / n)).collect();
        println!("| 1/{f} | {} |", cells.join(" | "));
    }
    Ok(())
}
