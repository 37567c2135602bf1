//! The paper's evaluation: PSNR of sampling strategies × reconstructions,
//! PSNR-vs-samples curves, stylized panels and a browsable report.
//!
//! [`run`] is what `qcs eval` calls. It takes decoded images, a list of samplers
//! (the lead puts the quasicrystal first, then [`crate::samplers::all`]),
//! an output folder and [`EvalOptions`], reports progress through a callback,
//! writes CSV tables, plots, panels and `index.html`, and returns a [`Report`]
//! with every number and the checked claims.
//!
//! ```no_run
//! use qcs_lab::eval::{run, EvalOptions};
//! let img = image::open("tests/data/seashore-100x100.png").unwrap().to_rgb8();
//! let samplers = qcs_lab::samplers::all(0);
//! let report = run(&[("seashore".into(), img)], &samplers, "out".as_ref(),
//!                  &EvalOptions::default(), &mut |p| eprintln!("{}/{} {}", p.done, p.total, p.stage)).unwrap();
//! println!("{} rows", report.rows.len());
//! ```

mod metrics;
mod plots;
mod report;

pub use metrics::{psnr, psnr_bytes, roughness};
pub use report::{Claim, Report, Row};

use std::path::Path;

use image::RgbImage;
use rayon::prelude::*;

use crate::samplers::Sampler;
use crate::{Error, Result};
use qcs::reconstruction::{self, Method};
use qcs::sites::Point;

/// PSNR used in place of `+∞` (identical pictures) when averaging and plotting.
pub const PSNR_CAP: f64 = 100.0;

/// What [`run`] measures and draws.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Counts of the PSNR table (the paper's 1089, 4225, 16641).
    pub table_counts: Vec<usize>,
    /// Counts of the PSNR-vs-samples curve ([`curve_counts`]`(256, 32768, 40)`).
    pub curve_counts: Vec<usize>,
    /// Reconstructions to measure (Gouraud and Shepard).
    pub methods: Vec<Method>,
    /// Number of sites in the mosaic, Voronoi and sites panels, and in the spectra.
    pub panel_count: usize,
    /// Longest side, in pixels, of the mosaic, Voronoi and sites panels.
    pub panel_size: u32,
    /// Side of the spectrum grid (and of the square domain the spectrum's sites fill).
    pub spectrum_size: usize,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            table_counts: vec![1089, 4225, 16641],
            curve_counts: curve_counts(256, 32768, 40),
            methods: vec![Method::Gouraud, Method::Shepard],
            panel_count: 1089,
            panel_size: 512,
            spectrum_size: 256,
        }
    }
}

/// One step of [`run`], for a progress bar.
#[derive(Clone, Debug)]
pub struct Step<'a> {
    /// Steps finished.
    pub done: usize,
    /// Steps in all.
    pub total: usize,
    /// What was just finished (`"seashore/periodic/Gouraud"`, `"panels/halton"`, …).
    pub stage: &'a str,
}

/// The counts of a PSNR-vs-samples curve: every square count `(2^k+1)²` in
/// `[min, max]` plus `between` log-spaced counts from `min` to `max`, sorted, distinct.
///
/// ```
/// let c = qcs_lab::eval::curve_counts(256, 32768, 40);
/// assert_eq!((c[0], *c.last().unwrap()), (256, 32768));
/// for sq in [289, 1089, 4225, 16641] { assert!(c.contains(&sq)); }
/// assert!(c.len() >= 40);
/// ```
pub fn curve_counts(min: usize, max: usize, between: usize) -> Vec<usize> {
    let (min, max) = (min.max(1), max.max(min.max(1)));
    let mut out = Vec::new();
    for k in 0..31u32 {
        let s = ((1usize << k) + 1).pow(2);
        if s > max {
            break;
        }
        if s >= min {
            out.push(s);
        }
    }
    if between >= 2 {
        let (a, b) = ((min as f64).ln(), (max as f64).ln());
        for i in 0..between {
            let t = i as f64 / (between - 1) as f64;
            out.push((a + t * (b - a)).exp().round() as usize);
        }
    } else {
        out.push(min);
        out.push(max);
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The colour of each site: the RGB of the pixel containing it (clamped to the image).
///
/// ```
/// let img = image::RgbImage::from_fn(4, 4, |x, y| image::Rgb([x as u8, y as u8, 7]));
/// assert_eq!(qcs_lab::eval::sample_colours(&img, &[[2.7, 1.2], [9.0, -1.0]]), vec![2, 1, 7, 3, 0, 7]);
/// ```
pub fn sample_colours(img: &RgbImage, positions: &[Point]) -> Vec<u8> {
    let (w, h) = img.dimensions();
    let mut out = Vec::with_capacity(positions.len() * 3);
    if w == 0 || h == 0 {
        out.resize(positions.len() * 3, 0);
        return out;
    }
    for p in positions {
        let x = if p[0].is_finite() {
            p[0].floor().clamp(0.0, (w - 1) as f64) as u32
        } else {
            0
        };
        let y = if p[1].is_finite() {
            p[1].floor().clamp(0.0, (h - 1) as f64) as u32
        } else {
            0
        };
        out.extend_from_slice(&img.get_pixel(x, y).0);
    }
    out
}

/// Reconstructs `img` from the first `count` of `sites` with `method` and
/// returns the PSNR against `img` (`+∞` when identical).
///
/// ```
/// use qcs_lab::samplers::{Sampler, Halton};
/// let img = image::RgbImage::from_pixel(16, 16, image::Rgb([9, 99, 199]));
/// let sites = Halton.sites(16, 16, 30);
/// let colours = qcs_lab::eval::sample_colours(&img, &sites);
/// let p = qcs_lab::eval::reconstruction_psnr(&img, &sites, &colours, qcs::reconstruction::Method::Shepard).unwrap();
/// assert_eq!(p, f64::INFINITY);
/// ```
pub fn reconstruction_psnr(
    img: &RgbImage,
    sites: &[Point],
    colours: &[u8],
    method: Method,
) -> Result<f64> {
    if colours.len() != sites.len() * 3 {
        return Err(crate::invalid(
            "colours",
            format_args!("{} bytes for {} sites", colours.len(), sites.len()),
            "3 bytes per site",
        ));
    }
    let (w, h) = img.dimensions();
    let out = reconstruction::render((w, h), 3, sites, colours, method, w, h);
    psnr_bytes(img.as_raw(), &out)
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Gouraud => "gouraud",
        Method::Shepard => "shepard",
        Method::Natural => "natural",
        Method::Cubic => "cubic",
    }
}

/// Runs the evaluation and writes its files into `out_dir` (created if needed).
///
/// For every image, sampler and method, the PSNR of the reconstruction from
/// the first `N` sites is measured for every `N` of `table_counts ∪ curve_counts`
/// (the sites are generated once at the largest count and cut, which the
/// samplers' prefix property makes exact). Then, for every sampler, panels from
/// the first image at `panel_count` sites and a spectrum are drawn.
///
/// Files: `psnr.csv` (every measurement), `mean.csv` (mean over images),
/// `table.csv` (mean at the table counts, one column per sampler), `claims.csv`,
/// `curve-<method>.svg` / `.png` `<sampler>-sites.png`,
/// `<sampler>-mosaic.png`, `<sampler>-voronoi.png`, `<sampler>-spectrum.png`,
/// and `index.html` linking them all. [`Report::files`] lists what was written.
///
/// `progress` is called after each (image, sampler, method) and each sampler's panels.
pub fn run(
    images: &[(String, RgbImage)],
    samplers: &[Box<dyn Sampler + Send + Sync>],
    out_dir: &Path,
    options: &EvalOptions,
    progress: &mut dyn FnMut(Step),
) -> Result<Report> {
    if images.is_empty() || samplers.is_empty() {
        return Err(crate::invalid(
            "images and samplers",
            format_args!("{} images, {} samplers", images.len(), samplers.len()),
            "at least one of each",
        ));
    }
    if let Some((name, _)) = images
        .iter()
        .find(|(_, i)| i.width() == 0 || i.height() == 0)
    {
        return Err(crate::invalid(
            "image",
            format_args!("{name}, empty"),
            "at least 1×1 pixels",
        ));
    }
    let limits = qcs::Limits::default();
    let mut counts: Vec<usize> = options
        .table_counts
        .iter()
        .chain(&options.curve_counts)
        .copied()
        .collect();
    counts.retain(|&c| c > 0);
    counts.sort_unstable();
    counts.dedup();
    let max_count = counts.last().copied().unwrap_or(0);
    limits.check_samples(max_count as u64)?;
    if options.panel_size == 0 || options.spectrum_size < 2 {
        return Err(crate::invalid(
            "EvalOptions panel_size, spectrum_size",
            format_args!("{}, {}", options.panel_size, options.spectrum_size),
            "panel_size ≥ 1 and spectrum_size ≥ 2",
        ));
    }
    std::fs::create_dir_all(out_dir)?;

    let total = images.len() * samplers.len() * options.methods.len() + samplers.len();
    let mut done = 0usize;
    let mut rows = Vec::new();
    for (name, img) in images {
        let (w, h) = img.dimensions();
        for s in samplers {
            let sites = s.sites(w, h, max_count);
            let colours = sample_colours(img, &sites);
            for &method in &options.methods {
                let measured: Vec<Result<Row>> = counts
                    .par_iter()
                    .map(|&n| {
                        let n = n.min(sites.len());
                        let p = reconstruction_psnr(img, &sites[..n], &colours[..3 * n], method)?;
                        Ok(Row {
                            image: name.clone(),
                            sampler: s.name().to_string(),
                            method,
                            count: n,
                            psnr: p,
                        })
                    })
                    .collect();
                for r in measured {
                    rows.push(r?);
                }
                done += 1;
                let stage = format!("{name}/{}/{}", s.name(), method_name(method));
                progress(Step {
                    done,
                    total,
                    stage: &stage,
                });
            }
        }
    }

    let mut files = Vec::new();
    // Panels from the first image.
    let (_, first) = &images[0];
    let (w, h) = first.dimensions();
    let scale = options.panel_size as f64 / w.max(h) as f64;
    let out = (
        ((w as f64 * scale).round() as u32).max(1),
        ((h as f64 * scale).round() as u32).max(1),
    );
    let n = options.spectrum_size;
    for s in samplers {
        let sites = s.sites(w, h, options.panel_count);
        let colours = sample_colours(first, &sites);
        let name = s.name();
        // The mosaic runs off the frame, as `qcs render` draws it.
        let (cells, _, cell_colours) =
            crate::styles::with_mirror_images(&sites, None, &colours, (w, h));
        let panels = [
            ("sites", crate::styles::order(&sites, (w, h), out)?),
            (
                "mosaic",
                crate::styles::mosaic(&cells, &cell_colours, (w, h), out)?,
            ),
            (
                "voronoi",
                crate::styles::voronoi(&sites, &colours, (w, h), out)?,
            ),
        ];
        for (kind, img) in panels {
            let path = out_dir.join(format!("{name}-{kind}.png"));
            save(&img, &path)?;
            files.push(path);
        }
        let square = s.sites(n as u32, n as u32, options.panel_count);
        let spec = crate::styles::spectrum(&square, (n as u32, n as u32), n)?;
        let path = out_dir.join(format!("{name}-spectrum.png"));
        spec.save(&path).map_err(image_err)?;
        files.push(path);
        done += 1;
        let stage = format!("panels/{name}");
        progress(Step {
            done,
            total,
            stage: &stage,
        });
    }

    let mut report = Report::new(
        rows,
        options,
        samplers.iter().map(|s| s.name().to_string()).collect(),
    );
    report.files = files;
    report.write(out_dir)?;
    Ok(report)
}

fn image_err(e: image::ImageError) -> Error {
    match e {
        image::ImageError::IoError(io) => Error::Io(io),
        other => Error::Io(std::io::Error::other(other)),
    }
}

fn save(img: &RgbImage, path: &Path) -> Result<()> {
    img.save(path).map_err(image_err)
}
