//! `qcs render`: stylized renderings of a .qcs file, or of an image sampled by any strategy.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use qcs::lattice::ZZeta;
use qcs::reconstruction::SampleSet;
use qcs::sampling::{SampleColour, SourceImage};
use qcs::sites::{Frame, Point};
use qcs::{Method, StreamDecoder};
use qcs_lab::styles;
use std::path::PathBuf;

use super::input::{QcsInput, ReadQcs, Source};
use super::{Ctx, Size};

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
    /// Number of samples (default: all of a .qcs file of levels only; 4225 for an image or
    /// the picture of a .qcs file with a refinement, sampled at the sites of --sampler).
    #[arg(long, value_parser = super::parse_count)]
    pub samples: Option<usize>,
    /// Output size: WxH, or W, Wx or xH keeping the aspect ratio (default: the image's size;
    /// see the spectrum and phase styles).
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<Size>,
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

    /// The samples and their mirror images across the image's edges
    /// ([`styles::with_mirror_images`]): the cells a decode draws at the edges.
    fn with_mirror_images(&self) -> Samples {
        let exact = self.exact.as_ref().map(|(l, f)| (l.as_slice(), *f));
        let (pos, lattice, col) =
            styles::with_mirror_images(&self.pos, exact, &self.col, self.source);
        Samples {
            pos,
            col,
            source: self.source,
            exact: lattice.zip(self.exact.as_ref().map(|e| e.1)),
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

/// The samples of a .qcs file, or `None` if it ends inside its header (nothing to draw).
fn qcs_samples(a: &RenderArgs, input: QcsInput, ctx: &Ctx) -> Result<Option<Samples>> {
    let Some(h) = input.header.clone() else {
        return Ok(None);
    };
    let k = a.samples.map_or(u64::MAX, |n| n as u64);
    let mut d = StreamDecoder::with_options(qcs::format::ParserOptions {
        limits: ctx.limits.clone(),
        recover: false,
        max_samples: Some(k),
    });
    d.push(&input.bytes)
        .with_context(|| format!("cannot decode {}", a.input.display()))?;
    let c = h.layout.channels() as usize;
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
    Ok(Some(Samples {
        pos: pos.iter().map(|s| s.pos).collect(),
        col: rgb,
        source: (h.width, h.height),
        exact: Some((pos.iter().map(|s| s.lattice).collect(), frame)),
    }))
}

/// The samples to draw: a .qcs file's (by its content, or its name: an empty `x.qcs` is a
/// file that ends inside its header), or an image's sampled with `--sampler`; `None` if a
/// .qcs file has nothing to draw yet.
fn samples(a: &RenderArgs, ctx: &Ctx) -> Result<Option<Samples>> {
    let mut src = Source::open(&a.input)?;
    let qcs_file = super::looks_like_qcs(src.peek(2)?) || super::has_qcs_extension(&a.input);
    if qcs_file {
        let what = || format!("cannot decode {}", a.input.display());
        let how = ReadQcs {
            budget: None,
            recover: false,
        };
        let input = super::input::read_qcs(src, &how, ctx, |h| {
            let size = a
                .size
                .map_or((h.width, h.height), |s| s.resolve(h.width, h.height));
            ctx.limits
                .check_output(size.0 as u64, size.1 as u64)
                .map_err(qcs::Error::from)?;
            Ok(())
        })
        .with_context(what)?
        .ok()
        .with_context(what)?;
        if !input.header.as_ref().is_some_and(|h| h.refinement) {
            return qcs_samples(a, input, ctx);
        }
        // A file with a refinement has few samples of its own: its picture is sampled as an
        // image is.
        let opts = qcs::DecodeOptions {
            limits: ctx.limits.clone(),
            ..Default::default()
        };
        let picture = qcs::decode(&input.bytes, &opts).with_context(what)?;
        return sampled(a, picture.image.to_rgb8(), ctx).map(Some);
    }
    super::input::check_image_start(&mut src)?;
    let bytes = super::input::read_all(src, ctx)?;
    let img = image::load_from_memory(&bytes)
        .with_context(|| format!("cannot read image {}", a.input.display()))?
        .to_rgb8();
    sampled(a, img, ctx).map(Some)
}

/// An image's samples, at the sites of `--sampler`, coloured by the area each site covers.
fn sampled(a: &RenderArgs, img: image::RgbImage, ctx: &Ctx) -> Result<Samples> {
    let (w, h) = img.dimensions();
    let n = a.samples.unwrap_or(4225);
    ctx.limits
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

pub fn render(a: RenderArgs, ctx: &Ctx) -> Result<()> {
    // The output's format (and, for `-`, that it is no terminal) before any work.
    super::output_format(&a.output)?;
    if a.style == Style::Phase {
        let size = a.size.map_or((512, 512), |s| s.resolve(512, 512));
        let window = styles::PhaseWindow::centred(1.5);
        let contour = styles::phase_contour(window, size)?;
        let level = styles::phase_level_set(window, size, 2.0)?;
        let mut both = image::RgbImage::new(size.0 * 2, size.1);
        image::imageops::replace(&mut both, &contour, 0, 0);
        image::imageops::replace(&mut both, &level, size.0 as i64, 0);
        super::save_image(&image::DynamicImage::ImageRgb8(both), &a.output)?;
        return Ok(());
    }
    let Some(samples) = samples(&a, ctx)? else {
        // A .qcs file that ends inside its header: nothing to draw yet (not an error).
        let size = a.size.map_or((1, 1), |s| s.resolve(1, 1));
        let grey = image::GrayImage::from_pixel(size.0, size.1, image::Luma([128]));
        super::save_image(&image::DynamicImage::ImageLuma8(grey), &a.output)?;
        if !ctx.quiet {
            eprintln!(
                "{}: neutral grey {}×{}: {} ends inside its header, nothing to draw yet",
                a.output.display(),
                size.0,
                size.1,
                a.input.display()
            );
        }
        return Ok(());
    };
    let (pos, col, source) = (&samples.pos, &samples.col, samples.source);
    let size = a.size.map_or(source, |s| s.resolve(source.0, source.1));
    ctx.limits
        .check_output(size.0 as u64, size.1 as u64)
        .map_err(qcs::Error::from)?;
    let sites = samples.sites();
    // The cell-based styles draw the cells at the edges too.
    let mirrored = matches!(a.style, Style::Mosaic | Style::Strokes | Style::Delaunay)
        .then(|| samples.with_mirror_images());
    let (cells, cell_col) = mirrored
        .as_ref()
        .map_or((sites, col), |m| (m.sites(), &m.col));
    let img = match a.style {
        Style::Mosaic => styles::mosaic(cells, cell_col, source, size)?,
        Style::Strokes => styles::strokes(cells, cell_col, source, size)?,
        Style::Voronoi => styles::voronoi(sites, col, source, size)?,
        Style::Delaunay => styles::delaunay_over(cells, source, &samples.gouraud(size))?,
        Style::Sites => styles::order(pos, source, size)?,
        Style::Spectrum => {
            let n = size.0.max(size.1).clamp(16, 2048) as usize;
            image::DynamicImage::ImageLuma8(styles::spectrum(pos, source, n)?).to_rgb8()
        }
        Style::Phase => unreachable!("handled above"),
    };
    super::save_image(&image::DynamicImage::ImageRgb8(img), &a.output)?;
    if !ctx.quiet {
        eprintln!(
            "{}: {:?} of {} samples",
            a.output.display(),
            a.style,
            pos.len()
        );
    }
    Ok(())
}
