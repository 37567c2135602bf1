//! `qcs render` (stylized renderings) and `qcs eval` (the paper's evaluation).

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use qcs::lattice::ZZeta;
use qcs::reconstruction::SampleSet;
use qcs::sampling::{SampleColour, SourceImage};
use qcs::sites::{Frame, Point};
use qcs::{styles, Method, StreamDecoder};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum Style {
    Mosaic,
    Strokes,
    Voronoi,
    Delaunay,
    Sites,
    /// The sites' power spectrum: a square of the larger --size side, 16–2048 px.
    Spectrum,
    /// The star map's phase field, contour and level panels side by side, each --size
    /// (default 512x512); it depends on no image, so INPUT is not read.
    Phase,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// A .qcs file, or an ordinary image to sample with --sampler (`-`: standard input).
    pub input: PathBuf,
    /// The output PNG (`-`: standard output).
    pub output: PathBuf,
    /// The rendering style.
    #[arg(long, value_enum, default_value = "mosaic")]
    pub style: Style,
    /// Number of samples (default: all of a .qcs file; 4225 for an image).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Output size WxH (default: the image's size; see the spectrum and phase styles).
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Sampler for an ordinary image: quasicrystal, periodic, jittered, halton, random, farthest.
    #[arg(long, default_value = "quasicrystal", value_parser = clap::builder::PossibleValuesParser::new(super::SAMPLERS))]
    pub sampler: String,
    /// Seed of the random samplers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// The samples to draw: positions, RGB colours, the source size and, for quasicrystal
/// sites, their lattice points and frame (so cells are exact and Gouraud is the decoder's).
struct Samples {
    pos: Vec<Point>,
    col: Vec<u8>,
    source: (u32, u32),
    exact: Option<(Vec<ZZeta>, Frame)>,
}

impl Samples {
    fn sites(&self) -> styles::Sites<'_> {
        match &self.exact {
            Some((lattice, _)) => styles::Sites::exact(&self.pos, lattice),
            None => self.pos.as_slice().into(),
        }
    }

    /// The Gouraud picture of the samples at `size`, as the decoder draws it.
    fn gouraud(&self, size: (u32, u32)) -> image::RgbImage {
        let (w, h) = self.source;
        let mut set = SampleSet::new(w, h, 3);
        if let Some((_, frame)) = &self.exact {
            set = set.with_frame(*frame);
        }
        for (k, p) in self.pos.iter().enumerate() {
            let c = &self.col[3 * k..3 * k + 3];
            match &self.exact {
                Some((lattice, _)) => set.push_exact(*p, lattice[k], c),
                None => set.push(*p, c),
            }
        }
        let px = set.render(Method::Gouraud, size.0, size.1);
        image::RgbImage::from_raw(size.0, size.1, px).expect("render size")
    }
}

fn samples(a: &RenderArgs) -> Result<Samples> {
    let bytes = super::read_input(&a.input)?;
    if bytes.starts_with(&qcs::container::MAGIC) {
        let mut d = StreamDecoder::new(qcs::Limits::default());
        d.push(&bytes)
            .with_context(|| format!("cannot decode {}", a.input.display()))?;
        let h = d.header().cloned().ok_or(qcs::Error::NeedMoreData)?;
        let c = h.layout.channels() as usize;
        let k = a.samples.map_or(u64::MAX, |n| n as u64);
        let frame = qcs::sites::Quasicrystal::with_frame(
            h.width,
            h.height,
            h.lattice
                .map_or(Frame::default_for(h.width, h.height), |l| Frame {
                    root_len: l.root_length,
                    origin: [l.origin_x, l.origin_y],
                }),
        )?
        .frame();
        let (pos, col) = d.samples(k);
        let rgb = col
            .chunks_exact(c)
            .flat_map(|p| {
                if c >= 3 {
                    [p[0], p[1], p[2]]
                } else {
                    [p[0]; 3]
                }
            })
            .collect();
        return Ok(Samples {
            pos: pos.iter().map(|s| s.pos).collect(),
            col: rgb,
            source: (h.width, h.height),
            exact: Some((pos.iter().map(|s| s.lattice).collect(), frame)),
        });
    }
    let img = image::load_from_memory(&bytes)
        .with_context(|| format!("cannot read image {}", a.input.display()))?
        .to_rgb8();
    let (w, h) = img.dimensions();
    let n = a.samples.unwrap_or(4225);
    qcs::Limits::default()
        .check_samples(n as u64)
        .map_err(qcs::Error::from)?;
    let Some(sampler) = super::sampler_by_name(&a.sampler, a.seed) else {
        bail!("unknown sampler {:?}", a.sampler);
    };
    let (pos, exact) = if a.sampler == "quasicrystal" {
        let seq = qcs::sites::Quasicrystal::new(w, h)?;
        let sites = seq.first(n);
        let lattice = sites.iter().map(|s| s.lattice).collect();
        (
            sites.iter().map(|s| s.pos).collect(),
            Some((lattice, seq.frame())),
        )
    } else {
        (sampler.sites(w, h, n), None)
    };
    let col = SourceImage::new(img.as_raw(), w, h, 3)?.colours(&pos, SampleColour::Area, n);
    Ok(Samples {
        pos,
        col,
        source: (w, h),
        exact,
    })
}

pub fn render(a: RenderArgs, quiet: bool) -> Result<()> {
    // The output's format (and, for `-`, that it is no terminal) before any work.
    super::output_format(&a.output)?;
    if a.style == Style::Phase {
        let size = a.size.unwrap_or((512, 512));
        let window = styles::PhaseWindow::centred(1.5);
        let contour = styles::phase_contour(window, size)?;
        let level = styles::phase_level_set(window, size, 2.0)?;
        let mut both = image::RgbImage::new(size.0 * 2, size.1);
        image::imageops::replace(&mut both, &contour, 0, 0);
        image::imageops::replace(&mut both, &level, size.0 as i64, 0);
        super::save_image(&image::DynamicImage::ImageRgb8(both), &a.output)?;
        return Ok(());
    }
    let samples = samples(&a)?;
    let (pos, col, source) = (&samples.pos, &samples.col, samples.source);
    let size = a.size.unwrap_or(source);
    qcs::Limits::default()
        .check_output(size.0 as u64, size.1 as u64)
        .map_err(qcs::Error::from)?;
    let sites = samples.sites();
    let img = match a.style {
        Style::Mosaic => styles::mosaic(sites, col, source, size)?,
        Style::Strokes => styles::strokes(sites, col, source, size)?,
        Style::Voronoi => styles::voronoi(sites, col, source, size)?,
        Style::Delaunay => styles::delaunay_over(sites, source, &samples.gouraud(size))?,
        Style::Sites => styles::order(pos, source, size)?,
        Style::Spectrum => {
            let n = size.0.max(size.1).clamp(16, 2048) as usize;
            image::DynamicImage::ImageLuma8(styles::spectrum(pos, source, n)?).to_rgb8()
        }
        Style::Phase => unreachable!("handled above"),
    };
    super::save_image(&image::DynamicImage::ImageRgb8(img), &a.output)?;
    if !quiet {
        eprintln!(
            "{}: {:?} of {} samples",
            a.output.display(),
            a.style,
            pos.len()
        );
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Images to evaluate on.
    #[arg(required = true)]
    pub images: Vec<PathBuf>,
    /// Output directory (CSV, plots, panels, index.html).
    #[arg(long)]
    pub out: PathBuf,
    /// Fewer curve points and smaller panels, for a quick look.
    #[arg(long)]
    pub quick: bool,
    /// Seed of the random samplers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

pub fn eval(a: EvalArgs, quiet: bool) -> Result<()> {
    let mut images = Vec::new();
    for p in &a.images {
        let img = super::open_image(p)?.to_rgb8();
        let name = p
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("image")
            .to_string();
        images.push((name, img));
    }
    let mut samplers: Vec<Box<dyn qcs::sites::Sampler + Send + Sync>> =
        vec![super::sampler_by_name("quasicrystal", a.seed).expect("quasicrystal")];
    samplers.extend(qcs::sites::strategies::all(a.seed));
    let mut opts = qcs::eval::EvalOptions::default();
    if a.quick {
        opts.curve_counts = qcs::eval::curve_counts(256, 8192, 12);
        opts.panel_size = 256;
    }
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}").expect("valid template"),
    );
    let report = qcs::eval::run(&images, &samplers, &a.out, &opts, &mut |p| {
        bar.set_length(p.total as u64);
        bar.set_position(p.done as u64);
        bar.set_message(p.stage.to_string());
    })
    .with_context(|| format!("cannot write the evaluation into {}", a.out.display()))?;
    bar.finish_and_clear();
    if !quiet {
        for c in &report.claims {
            let v = match c.holds {
                Some(true) => "holds",
                Some(false) => "does not hold",
                None => "not checked",
            };
            say!("{v:>14}: {} ({})", c.statement, c.evidence);
        }
        say!("report: {}", a.out.join("index.html").display());
    }
    Ok(())
}
