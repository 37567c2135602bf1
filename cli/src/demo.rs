//! `qcs demo`: encode an image and write the pictures of growing prefixes of its file.

use super::Ctx;
use anyhow::{Context, Result};
use clap::Args;
use qcs::{DecodeOptions, EncodeOptions};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// An image to encode.
    pub input: PathBuf,
    /// Directory for the .qcs file and the previews.
    pub out_dir: PathBuf,
    /// Total number of samples (default: one per 4 pixels).
    #[arg(long, value_parser = super::parse_count_u64)]
    pub samples: Option<u64>,
}

pub fn demo(a: DemoArgs, ctx: &Ctx) -> Result<()> {
    let quiet = ctx.quiet;
    let img = super::open_image(&a.input, ctx)?;
    std::fs::create_dir_all(&a.out_dir)
        .with_context(|| format!("cannot create {}", a.out_dir.display()))?;
    // The table goes to stdout only once every file is written: a reader that closes the
    // pipe early (`| head -1`) must not cut the work short.
    let mut report = String::new();
    macro_rules! note {
        ($($arg:tt)*) => {{
            use std::fmt::Write as _;
            writeln!(report, $($arg)*).expect("writing to a String");
        }};
    }
    let opts = EncodeOptions {
        samples: a.samples,
        ..Default::default()
    };
    let bytes = qcs::encode(&img, &opts)?;
    let stem = a
        .input
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("image")
        .to_string();
    let qcs_path = a.out_dir.join(format!("{stem}.qcs"));
    std::fs::write(&qcs_path, &bytes)
        .with_context(|| format!("cannot write {}", qcs_path.display()))?;
    let reference = img.to_rgb8();
    let (w, h) = reference.dimensions();
    let mut strip = image::RgbImage::new(w * 4, h);
    if !quiet {
        note!(
            "{}: {} bytes ({} samples)",
            qcs_path.display(),
            bytes.len(),
            opts.sample_count(w, h)
        );
        note!(
            "{:>7} {:>8} {:>8} {:>8}  file",
            "share",
            "bytes",
            "samples",
            "PSNR dB"
        );
    }
    for (i, pct) in [1usize, 5, 25, 100].into_iter().enumerate() {
        let cut = (bytes.len() * pct).div_ceil(100);
        let d = qcs::decode(
            &bytes,
            &DecodeOptions {
                max_bytes: Some(cut),
                ..Default::default()
            },
        );
        // A small file's first 1 % can end inside the header: nothing to show yet, a neutral
        // grey picture, as `qcs decode` draws it.
        let (rgb, samples, said) = match d {
            Ok(d) => (d.image.to_rgb8(), d.samples_used, ""),
            Err(qcs::Error::NeedMoreData) => (
                image::RgbImage::from_pixel(w, h, image::Rgb([128; 3])),
                0,
                "  (neutral grey: the bytes end inside the header)",
            ),
            Err(e) => return Err(e.into()),
        };
        let path = a.out_dir.join(format!("{stem}-{pct:03}pct.png"));
        rgb.save(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        image::imageops::replace(&mut strip, &rgb, (i as u32 * w) as i64, 0);
        if !quiet {
            note!(
                "{:>6}% {:>8} {:>8} {:>8.2}  {}{said}",
                pct,
                cut,
                samples,
                qcs_lab::eval::psnr(&reference, &rgb)?,
                path.display()
            );
        }
    }
    let path = a.out_dir.join(format!("{stem}-strip.png"));
    strip
        .save(&path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    if !quiet {
        note!("side by side: {}", path.display());
    }
    use std::io::Write as _;
    std::io::stdout().write_all(report.as_bytes())?;
    Ok(())
}
