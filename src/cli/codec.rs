//! `qcs encode`, `qcs decode`, `qcs info`, `qcs demo`.

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use qcs::container::Coding;
use qcs::sampling::SampleColour;
use qcs::{DecodeOptions, EncodeOptions, Method, StreamDecoder};

use super::input::{QcsInput, ReadQcs};
use super::{Ctx, Size};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MethodArg {
    Gouraud,
    Shepard,
    Natural,
    Cubic,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::Gouraud => Method::Gouraud,
            MethodArg::Shepard => Method::Shepard,
            MethodArg::Natural => Method::Natural,
            MethodArg::Cubic => Method::Cubic,
        }
    }
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ColourArg {
    /// The pixel containing the site.
    Nearest,
    /// Bilinear between the four nearest pixel centres.
    Bilinear,
    /// Mean over the area one site covers in the whole file.
    Area,
    /// Mean over the area the site covers when it first appears.
    Progressive,
    /// Progressive, then corrected for the Gouraud picture of each level (best previews).
    Fitted,
}

pub use qcs::coding::predictive::DEFAULT_QUALITY;

#[derive(Args, Debug)]
pub struct EncodeArgs {
    /// The image to encode, then the .qcs file to write, whose name must end in .qcs (`-`:
    /// standard input or output); with --out-dir, images and folders (searched recursively).
    #[arg(required = true, num_args = 1.., value_name = "PATHS")]
    pub paths: Vec<PathBuf>,
    /// The .qcs file to write, under any name but an image format's (the input is then the
    /// only path).
    #[arg(short, long, conflicts_with = "out_dir")]
    pub output: Option<PathBuf>,
    /// Encode every input into this folder (as NAME.qcs, a folder's subfolders mirrored), in
    /// parallel.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Total number of samples (at most the image's pixels).
    #[arg(long, conflicts_with = "density", value_parser = super::parse_count_u64)]
    pub samples: Option<u64>,
    /// Samples per pixel (default 0.25).
    #[arg(long, value_parser = parse_density)]
    pub density: Option<f64>,
    /// Raw coding (coding 0) at this many bits per channel, 1–8, instead of the predictive coding.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8), conflicts_with_all = ["quality", "lossless"])]
    pub bits: Option<u8>,
    /// Predictive coding (coding 1) at this quality, 0–100 (the default, at 75): luma step
    /// 1 + ((100 − Q)² + 50)/100, chroma step 2·step − 1 (100 = lossless).
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=100), conflicts_with = "lossless")]
    pub quality: Option<u8>,
    /// Predictive coding with exact sample values (step 1).
    #[arg(long)]
    pub lossless: bool,
    /// What a sample's colour is.
    #[arg(long, value_enum, default_value = "fitted")]
    pub colour: ColourArg,
    /// Text comment to store.
    #[arg(long)]
    pub comment: Option<String>,
    /// Drop the input's ICC colour profile. By default it is stored (after the first level,
    /// so the first preview does not wait for it), unless it describes sRGB, which a file
    /// without a profile means anyway.
    #[arg(long)]
    pub strip_icc: bool,
    /// Also decode the file written (whole, at full size) and print its PSNR against the
    /// image (over RGB).
    #[arg(long)]
    pub psnr: bool,
}

fn parse_density(s: &str) -> Result<f64, String> {
    let d: f64 = s.parse().map_err(|_| format!("not a number: {s:?}"))?;
    if d > 0.0 && d <= 1.0 {
        Ok(d)
    } else {
        Err(format!("{s} is not in (0, 1] samples per pixel"))
    }
}

impl EncodeArgs {
    fn options(&self) -> EncodeOptions {
        let params = if self.lossless {
            qcs::coding::predictive::Params::lossless()
        } else {
            qcs::coding::predictive::Params::from_quality(self.quality.unwrap_or(DEFAULT_QUALITY))
        };
        let coding = match self.bits {
            Some(bits) => Coding::Raw { bits },
            None => params.coding(),
        };
        let mut o = EncodeOptions {
            samples: self.samples,
            coding,
            ..Default::default()
        };
        if let Some(d) = self.density {
            o.density = d;
        }
        o.colour = match self.colour {
            ColourArg::Nearest => SampleColour::Nearest,
            ColourArg::Bilinear => SampleColour::Bilinear,
            ColourArg::Area => SampleColour::Area,
            ColourArg::Progressive => SampleColour::Progressive,
            ColourArg::Fitted => SampleColour::Fitted,
        };
        if let Some(c) = &self.comment {
            o.text.push(("Comment".into(), c.clone()));
        }
        o
    }
}

/// What [`encode_file`] made: the summary `qcs encode` prints.
///
/// (Room for what later formats add, such as where the levels end or the size aimed at.)
struct Encoded {
    /// The input's size in bytes (unknown for standard input).
    input: Option<u64>,
    /// The output's size in bytes.
    output: u64,
    /// The image's size and the file's header.
    width: u32,
    height: u32,
    header: Option<qcs::container::Header>,
    /// The size of the ICC profile stored, if any.
    icc: Option<usize>,
    /// The samples the density asked for, when they were capped at the sample limit.
    capped_from: Option<u64>,
    /// With `--psnr`: the PSNR of the whole file decoded at full size, in dB.
    psnr: Option<f64>,
}

impl Encoded {
    /// One line: what was made, from what, and how well.
    fn summary(&self, input: &Path, output: &Path) -> String {
        use std::fmt::Write as _;
        let mut s = format!("{} → {}: ", input.display(), output.display());
        let (w, h) = (self.width, self.height);
        let px = (w as f64 * h as f64).max(1.0);
        let bits = self.output as f64 * 8.0;
        if let Some(hd) = &self.header {
            let _ = write!(
                s,
                "{w}×{h} {:?}, {} samples in {} levels, {}; ",
                hd.layout,
                hd.total_samples,
                hd.level_count(),
                hd.coding
            );
        }
        let _ = write!(s, "{} bytes", self.output);
        if let Some(n) = self.input {
            let _ = write!(s, " (from {n})");
        }
        let _ = write!(s, ", {:.3} bits per pixel", bits / px);
        if let Some(hd) = &self.header {
            let _ = write!(
                s,
                ", {:.2} per sample",
                bits / hd.total_samples.max(1) as f64
            );
        }
        if let Some(p) = self.psnr {
            let _ = write!(s, ", PSNR {p:.2} dB");
        }
        if let Some(n) = self.icc {
            let _ = write!(s, " (with its {n}-byte ICC profile)");
        }
        s
    }
}

/// Encodes the image `input` into `output`, with the checks `qcs decode` (with the same
/// limits) would apply to the file.
fn encode_file(
    input: &Path,
    output: &Path,
    opts: &EncodeOptions,
    (strip_icc, density_given, psnr): (bool, bool, bool),
    ctx: &Ctx,
) -> Result<Encoded> {
    let (img, icc) = super::read_image(input, ctx)?;
    let mut opts = opts.clone();
    opts.icc = icc.filter(|icc| !strip_icc && !super::is_srgb(icc));
    // A file `qcs decode` would refuse is not worth writing.
    let limits = &ctx.limits;
    let (w, h) = (img.width(), img.height());
    limits
        .check_image(w as u64, h as u64)
        .map_err(qcs::Error::from)
        .with_context(|| format!("cannot encode {}", input.display()))?;
    let px = w as u64 * h as u64;
    if let Some(n) = opts.samples.filter(|&n| n > px) {
        return Err(usage!(
            "cannot encode {}: --samples {n} is more than its {px} pixels ({w}×{h})",
            input.display()
        ));
    }
    // The default density's count is capped at the sample limit; an explicit --samples or
    // --density beyond it is refused.
    let asked = (opts.samples)
        .unwrap_or((opts.density * px as f64).floor() as u64)
        .min(px);
    let explicit = opts.samples.is_some() || density_given;
    // The encoder itself stops the default density at the default limit.
    let capped = !explicit && asked > limits.max_samples.min(qcs::Limits::default().max_samples);
    let mut capped_from = None;
    if capped {
        let n = asked.min(limits.max_samples);
        opts.samples = Some(n);
        capped_from = (n < asked).then_some(asked);
    }
    limits
        .check_samples(if capped { 0 } else { asked })
        .map_err(qcs::Error::from)
        .with_context(|| {
            format!(
                "cannot encode {}: `qcs decode` would refuse so many samples; \
                 lower --density or --samples",
                input.display()
            )
        })?;
    let metadata: usize = opts.icc.as_ref().map_or(0, Vec::len)
        + opts
            .text
            .iter()
            .map(|(k, v)| k.len() + 1 + v.len())
            .sum::<usize>();
    limits
        .check_metadata(metadata as u64)
        .map_err(qcs::Error::from)
        .with_context(|| {
            format!(
                "cannot encode {}: `qcs decode` would refuse so much metadata; \
                 use --strip-icc or a shorter --comment",
                input.display()
            )
        })?;
    let bytes =
        qcs::encode(&img, &opts).with_context(|| format!("cannot encode {}", input.display()))?;
    let psnr = match psnr {
        false => None,
        true => {
            let d = qcs::decode(
                &bytes,
                &DecodeOptions {
                    limits: limits.clone(),
                    ..Default::default()
                },
            )
            .with_context(|| format!("cannot decode what {} became", input.display()))?;
            Some(qcs::eval::psnr(&img.to_rgb8(), &d.image.to_rgb8())?)
        }
    };
    super::write_output(output, &bytes)?;
    Ok(Encoded {
        input: match super::is_stdio(input) {
            true => None,
            false => std::fs::metadata(input).ok().map(|m| m.len()),
        },
        output: bytes.len() as u64,
        width: w,
        height: h,
        header: qcs::container::Header::parse(&bytes).ok().map(|(h, _)| h),
        icc: opts.icc.as_ref().map(Vec::len),
        capped_from,
        psnr,
    })
}

/// Whether `a` and `b` name the same existing file.
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

fn is_image(p: &Path) -> bool {
    image::ImageFormat::from_path(p).is_ok()
}

/// The images in the folder `dir` and its subfolders (by extension), sorted, each with its
/// path relative to `dir`.
fn images_in(dir: &Path) -> Result<Vec<(PathBuf, PathBuf)>> {
    let mut found = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).with_context(|| format!("cannot list {}", d.display()))? {
            let p = e
                .with_context(|| format!("cannot list {}", d.display()))?
                .path();
            if p.is_dir() {
                todo.push(p);
            } else if p.is_file() && is_image(&p) {
                let rel = p.strip_prefix(dir).unwrap_or(&p).to_path_buf();
                found.push((p, rel));
            }
        }
    }
    found.sort();
    Ok(found)
}

/// Refuses to write .qcs data under a name that says it is an image.
fn refuse_image_name(out: &Path) -> Result<()> {
    if let Ok(f) = image::ImageFormat::from_path(out) {
        return Err(usage!(
            "{} names a {f:?} image: not writing .qcs data into it (give a name ending in .qcs)",
            out.display()
        ));
    }
    Ok(())
}

pub fn encode(a: EncodeArgs, ctx: &Ctx) -> Result<()> {
    let opts = a.options();
    let flags = (a.strip_icc, a.density.is_some(), a.psnr);
    if let Some(dir) = &a.out_dir {
        return encode_many(&a, dir, &opts, flags, ctx);
    }
    let (input, output) = match (&a.output, a.paths.as_slice()) {
        (Some(o), [i]) => {
            refuse_image_name(o)?;
            (i, o)
        }
        (Some(_), _) => {
            return Err(usage!(
                "with -o, give one input image; to encode several, use --out-dir DIR"
            ))
        }
        (None, [i]) => {
            return Err(usage!(
                "no output: give one (qcs encode {} OUT.qcs, or -o OUT), or --out-dir DIR",
                i.display()
            ))
        }
        (None, [i, o]) => {
            if !super::is_stdio(o) && !super::has_qcs_extension(o) {
                return Err(usage!(
                    "{} does not end in .qcs: not writing .qcs data into it{}. Give OUT.qcs \
                     (or -o NAME), or --out-dir DIR to encode several images",
                    o.display(),
                    if o.exists() { " (it exists)" } else { "" }
                ));
            }
            (i, o)
        }
        (None, many) => {
            return Err(usage!(
                "{} paths: give one input and one output (IN OUT.qcs), or --out-dir DIR to \
                 encode several images",
                many.len()
            ))
        }
    };
    if same_file(input, output) {
        return Err(usage!(
            "the output {} is the input image: give an output such as OUT.qcs",
            output.display()
        ));
    }
    super::check_output(output)?;
    let e = encode_file(input, output, &opts, flags, ctx)?;
    if let Some(asked) = e.capped_from {
        eprintln_unless(
            ctx.quiet,
            format!(
                "qcs: {}: {} samples, fewer than the {asked} of the density: the most \
                 `qcs decode` takes (--max-samples)",
                input.display(),
                ctx.limits.max_samples
            ),
        );
    }
    eprintln_unless(ctx.quiet, e.summary(input, output));
    Ok(())
}

/// Prints `msg` on standard error unless `quiet`.
fn eprintln_unless(quiet: bool, msg: impl std::fmt::Display) {
    if !quiet {
        eprintln!("{msg}");
    }
}

fn encode_many(
    a: &EncodeArgs,
    dir: &Path,
    opts: &EncodeOptions,
    flags: (bool, bool, bool),
    ctx: &Ctx,
) -> Result<()> {
    if a.paths.iter().any(|p| super::is_stdio(p)) {
        return Err(usage!(
            "standard input (-) is one image: encode it without --out-dir (qcs encode - OUT.qcs)"
        ));
    }
    // Every input and where it goes.
    let mut jobs: Vec<(PathBuf, PathBuf)> = Vec::new();
    for p in &a.paths {
        if p.is_dir() {
            for (img, rel) in images_in(p)? {
                jobs.push((img, dir.join(rel).with_extension("qcs")));
            }
        } else {
            let stem = p.file_stem().unwrap_or_default();
            jobs.push((p.clone(), dir.join(stem).with_extension("qcs")));
        }
    }
    if jobs.is_empty() {
        return Err(usage!(
            "nothing to encode: no image files (.png, .jpg, … by extension) in {}",
            a.paths
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let mut seen = std::collections::HashMap::new();
    for (p, out) in &jobs {
        if let Some(prev) = seen.insert(out.clone(), p.clone()) {
            return Err(usage!(
                "{} and {} would both be written to {}",
                prev.display(),
                p.display(),
                out.display()
            ));
        }
    }
    for (_, out) in &jobs {
        if let Some(d) = out.parent() {
            std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
        }
    }
    let start = Instant::now();
    let bar = if ctx.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(jobs.len() as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}").expect("valid template"),
    );
    let results: Vec<Result<Encoded>> = jobs
        .par_iter()
        .map(|(p, out)| {
            let r = encode_file(p, out, opts, flags, ctx);
            if let Ok(e) = &r {
                if !ctx.quiet {
                    bar.println(e.summary(p, out));
                }
            }
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();
    let (mut ok, mut bin, mut bout) = (0, 0, 0);
    let mut first_err = None;
    for ((p, _), r) in jobs.iter().zip(results) {
        match r {
            Ok(e) => {
                ok += 1;
                bin += e.input.unwrap_or(0);
                bout += e.output;
                if let Some(asked) = e.capped_from {
                    eprintln_unless(
                        ctx.quiet,
                        format!(
                            "qcs: {}: {} samples, fewer than the {asked} of the density: the \
                             most `qcs decode` takes (--max-samples)",
                            p.display(),
                            ctx.limits.max_samples
                        ),
                    );
                }
            }
            Err(e) => {
                eprintln!("qcs: {}: {e:#}", p.display());
                first_err.get_or_insert(e);
            }
        }
    }
    eprintln_unless(
        ctx.quiet,
        format!(
            "{ok} of {} files encoded, {bin} bytes in, {bout} bytes out, {:.2} s",
            jobs.len(),
            start.elapsed().as_secs_f64()
        ),
    );
    match first_err {
        Some(e) => Err(e.context(format!(
            "{} of {} files failed",
            jobs.len() - ok,
            jobs.len()
        ))),
        None => Ok(()),
    }
}

#[derive(Args, Debug)]
pub struct DecodeArgs {
    /// The .qcs file (`-`: standard input).
    pub input: PathBuf,
    /// The output image (PNG, JPEG, … by extension; `-`: PNG on standard output); optional
    /// with --frames.
    pub output: Option<PathBuf>,
    /// Reconstruction method.
    #[arg(long, value_enum, default_value = "gouraud")]
    pub method: MethodArg,
    /// Output size: WxH exactly, or W, Wx or xH keeping the aspect ratio (default: the
    /// image's own size).
    #[arg(long, value_parser = super::parse_size, conflicts_with = "scale")]
    pub size: Option<Size>,
    /// Output scale factor.
    #[arg(long, value_parser = super::parse_scale)]
    pub scale: Option<f64>,
    /// Use at most N samples (N ≥ 1).
    #[arg(long, conflicts_with_all = ["bytes", "frames"], value_parser = super::parse_count_u64)]
    pub samples: Option<u64>,
    /// Render at the output's pixel centres from every sample (or --samples), even for an
    /// output much smaller than the image, which is otherwise a thumbnail: from the first
    /// samples it needs, each pixel the mean of a square of subpixels (closer to the image,
    /// and faster).
    #[arg(long)]
    pub no_thumbnail: bool,
    /// Use only the first K bytes of the file, as a cut download would: no more is read (K,
    /// M, G suffixes: binary multiples).
    #[arg(long, value_name = "K", value_parser = super::parse_byte_count)]
    pub bytes: Option<u64>,
    /// Write a preview PNG into DIR every --every bytes (default: at each level), up to
    /// --bytes if given.
    #[arg(long)]
    pub frames: Option<PathBuf>,
    /// With --frames: bytes between previews.
    #[arg(long, requires = "frames", value_parser = super::parse_count)]
    pub every: Option<usize>,
    /// With --frames: the most frames to write (`none` lifts the cap); more is refused
    /// before any is written.
    #[arg(long, requires = "frames", value_name = "N", value_parser = super::parse_limit, default_value = "100")]
    pub max_frames: u64,
    /// Keep the longest verified prefix of a damaged file instead of failing; what was
    /// damaged, where, and what was kept is said on standard error.
    #[arg(long)]
    pub recover: bool,
}

fn output_size(size: Option<Size>, scale: Option<f64>, w: u32, h: u32) -> (u32, u32) {
    match (size, scale) {
        (Some(s), _) => s.resolve(w, h),
        // `--scale` is finite and above 0 (clap checks it).
        (None, f) => {
            let f = f.unwrap_or(1.0);
            (
                ((w as f64 * f).round() as u32).max(1),
                ((h as f64 * f).round() as u32).max(1),
            )
        }
    }
}

/// A stream decoder for pictures of `size`: one that decodes only the samples a thumbnail of
/// that size draws on when `thumbnail` (so it also takes a file with more samples than the
/// limits allow, if its first levels fit).
fn stream_decoder(size: (u32, u32), thumbnail: bool, recover: bool, ctx: &Ctx) -> StreamDecoder {
    let opts = qcs::container::ParserOptions::with_limits(ctx.limits.clone()).recover(recover);
    StreamDecoder::with_options(match thumbnail {
        true => opts.decode_before(qcs::thumbnail_samples(size.0, size.1)),
        false => opts,
    })
}

/// Checks that the samples a decode stopping at sample `k` decodes are within the limits,
/// with a hint at what decodes fewer.
fn check_decoded_samples(h: &qcs::container::Header, k: u64, ctx: &Ctx) -> Result<()> {
    let n = super::input::samples_of_levels_before(h, k);
    ctx.limits
        .check_samples(n)
        .map_err(qcs::Error::from)
        .context(
            "a smaller output (--size or --scale) or --samples N decodes only the samples it \
             needs; --max-samples raises the limit",
        )
}

/// A neutral grey picture: what a file that ends inside its header shows (spec/format.md,
/// Truncation: nothing to show yet, not an error).
fn grey(size: (u32, u32)) -> image::DynamicImage {
    image::DynamicImage::ImageLuma8(image::GrayImage::from_pixel(
        size.0,
        size.1,
        image::Luma([128]),
    ))
}

/// Says on standard error (even with `--quiet`: the picture is not the whole file) what
/// `--recover` dropped; an error if nothing before the damage could be kept.
fn report_damage(
    input: &Path,
    damage: &qcs::container::FormatError,
    h: &qcs::container::Header,
    verified: u64,
    levels: u32,
) -> Result<()> {
    if verified == 0 {
        return Err(qcs::Error::Format(damage.clone())).context(format!(
            "{} is damaged before anything could be kept (--recover keeps only verified levels)",
            input.display()
        ));
    }
    super::warn(format!(
        "{} is damaged: {damage}; kept what was verified before it: {verified} of {} samples \
         ({levels} of {} levels)",
        input.display(),
        h.total_samples,
        h.level_count()
    ));
    Ok(())
}

pub fn decode(a: DecodeArgs, ctx: &Ctx) -> Result<()> {
    // Everything about the outputs is checked before any byte is read.
    let Some(_) = a.output.as_ref().or(a.frames.as_ref()) else {
        return Err(usage!("give an output image path (or --frames DIR)"));
    };
    if let Some(out) = &a.output {
        super::output_format(out)?;
    }
    if let Some(dir) = &a.frames {
        if dir.exists() && !dir.is_dir() {
            return Err(usage!("--frames {}: not a folder", dir.display()));
        }
    }
    let what = || format!("cannot decode {}", a.input.display());
    let src = super::input::Source::open(&a.input)?;
    let how = ReadQcs {
        budget: a.bytes,
        recover: a.recover,
    };
    let input = super::input::read_qcs(src, &how, ctx, |h| {
        let size = output_size(a.size, a.scale, h.width, h.height);
        ctx.limits
            .check_output(size.0 as u64, size.1 as u64)
            .map_err(qcs::Error::from)?;
        if a.output.is_some() {
            check_decoded_samples(h, one_shot_samples(&a, size), ctx)?;
        }
        if a.frames.is_some() && a.no_thumbnail {
            check_decoded_samples(h, u64::MAX, ctx)?;
        }
        Ok(())
    })
    .with_context(what)?;
    let input = input.ok().with_context(what)?;
    let Some(header) = input.header.clone() else {
        // Nothing to show yet: a neutral grey picture (at --size, else 1 × 1).
        let size = output_size(a.size, None, 1, 1);
        let said = format!(
            "neutral grey {}×{}: the {} bytes end inside the header, nothing to show yet",
            size.0,
            size.1,
            input.bytes.len()
        );
        if let Some(dir) = &a.frames {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            let path = dir.join(format!("frame-000-{:08}B-preview.png", input.bytes.len()));
            super::save_image(&grey(size), &path)?;
            eprintln_unless(ctx.quiet, format!("{}: {said}", path.display()));
        }
        if let Some(out) = &a.output {
            super::save_image(&grey(size), out)?;
            eprintln_unless(ctx.quiet, format!("{}: {said}", out.display()));
        }
        return Ok(());
    };
    if let Some(dir) = &a.frames {
        frames(&a, &input, &header, dir, ctx).with_context(what)?;
    }
    let Some(out) = &a.output else {
        return Ok(());
    };
    let size = output_size(a.size, a.scale, header.width, header.height);
    let opts = DecodeOptions {
        method: a.method.into(),
        size: Some(size),
        max_samples: a.samples,
        max_bytes: None,
        thumbnail: !a.no_thumbnail,
        recover: a.recover,
        limits: ctx.limits.clone(),
    };
    let d = qcs::decode(&input.bytes, &opts).with_context(what)?;
    if let (Some(damage), None) = (&input.damage, &a.frames) {
        report_damage(
            &a.input,
            damage,
            &header,
            d.samples_verified,
            d.levels_complete,
        )?;
    }
    let kept = super::save_image_icc(&d.image, out, d.icc.as_deref())?;
    if !kept {
        super::warn(format!(
            "{} cannot hold the file's ICC colour profile: its colours are not sRGB and will \
             look wrong; write PNG, JPEG, TIFF or WebP to keep it",
            out.display()
        ));
    }
    // A thumbnail differs from the plain render from 2.25 samples per output pixel on
    // (2 × 2 subpixels each).
    let pixels = size.0 as f64 * size.1 as f64;
    let thumbnail = opts.thumbnail && d.samples_used as f64 >= 2.25 * pixels;
    eprintln_unless(
        ctx.quiet,
        format!(
            "{}: {}×{} from {} samples ({} verified, {} levels){}",
            out.display(),
            size.0,
            size.1,
            d.samples_used,
            d.samples_verified,
            d.levels_complete,
            if thumbnail {
                ", a thumbnail (--no-thumbnail for the plain render)"
            } else if d.is_final {
                ", final"
            } else {
                ", preview"
            }
        ),
    );
    Ok(())
}

/// The samples `qcs::decode` stops at for `a` at `size` (`DecodeOptions::max_samples`, and a
/// thumbnail's).
fn one_shot_samples(a: &DecodeArgs, size: (u32, u32)) -> u64 {
    let k = a.samples.unwrap_or(u64::MAX);
    match a.no_thumbnail {
        true => k,
        false => k.min(qcs::thumbnail_samples(size.0, size.1)),
    }
}

/// Where frames are cut: every `every` bytes, or at each level's end; the whole input last.
fn cuts(bytes: &[u8], every: Option<usize>) -> Vec<usize> {
    let mut cuts: Vec<usize> = match every {
        Some(k) => (1..)
            .map(|i| i * k)
            .take_while(|&c| c < bytes.len())
            .collect(),
        None => level_ends(bytes),
    };
    cuts.push(bytes.len());
    cuts.dedup();
    cuts
}

/// Refuses more frames than `--max-frames`, saying what would fit.
fn check_frame_count(n: usize, len: usize, every: Option<usize>, max: u64) -> Result<()> {
    if n as u64 <= max {
        return Ok(());
    }
    let fit = match every {
        Some(_) => format!("--every {} or more, or ", len.div_ceil(max.max(1) as usize)),
        None => String::new(),
    };
    Err(usage!(
        "{n} frames would be made, more than --max-frames {max}: use {fit}--max-frames {n} \
         (none lifts the cap)"
    ))
}

fn frames(
    a: &DecodeArgs,
    input: &QcsInput,
    h: &qcs::container::Header,
    dir: &Path,
    ctx: &Ctx,
) -> Result<()> {
    let bytes = &input.bytes[..];
    let cuts = cuts(bytes, a.every);
    check_frame_count(cuts.len(), bytes.len(), a.every, a.max_frames)?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let size = output_size(a.size, a.scale, h.width, h.height);
    let mut dec = stream_decoder(size, !a.no_thumbnail, a.recover, ctx);
    let mut fed = 0;
    let mut warned = false;
    for (n, cut) in cuts.into_iter().enumerate() {
        dec.push(&bytes[fed..cut])?;
        fed = cut;
        // Thumbnails where the output would be one, as the picture `qcs decode` writes.
        let pic = match a.no_thumbnail {
            true => dec.render(a.method.into(), size.0, size.1)?,
            false => dec.render_thumbnail(a.method.into(), size.0, size.1)?,
        };
        // A thumbnail of the whole file is final too, though it draws on fewer samples.
        let kind = if dec.is_complete() {
            "final"
        } else {
            "preview"
        };
        let path = dir.join(format!("frame-{n:03}-{cut:08}B-{kind}.png"));
        let d = pic.decoded();
        if let (Some(damage), false) = (dec.stopped(), warned) {
            report_damage(
                &a.input,
                damage,
                h,
                dec.samples_verified(),
                dec.levels_complete(),
            )?;
            warned = true;
        }
        // PNG holds the ICC profile.
        super::save_image_icc(&d.image, &path, d.icc.as_deref())?;
        eprintln_unless(
            ctx.quiet,
            format!("{}: {} samples", path.display(), d.samples_used),
        );
    }
    Ok(())
}

/// Byte offsets at which each level chunk ends (where the next chunk starts).
fn level_ends(bytes: &[u8]) -> Vec<usize> {
    let ins = qcs::container::inspect(bytes);
    let starts: Vec<u64> = ins
        .chunks
        .iter()
        .map(|c| c.chunk.offset)
        .chain([ins.file_len])
        .collect();
    ins.chunks
        .iter()
        .enumerate()
        .filter(|(_, c)| c.level.is_some())
        .map(|(i, _)| starts[i + 1] as usize)
        .collect()
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The .qcs file (`-`: standard input).
    pub input: PathBuf,
}

pub fn info(a: InfoArgs, ctx: &Ctx) -> Result<()> {
    let src = super::input::Source::open(&a.input)?;
    let how = ReadQcs {
        budget: None,
        recover: true,
    };
    let input = super::input::read_qcs(src, &how, ctx, |_| Ok(()))?;
    let ins = qcs::container::inspect(&input.bytes);
    match &input.refused {
        None => say!("file: {} ({} bytes)", a.input.display(), ins.file_len),
        Some(_) => say!(
            "file: {} ({} bytes read: reading stopped where it was refused)",
            a.input.display(),
            ins.file_len
        ),
    }
    if let Some(h) = &ins.header {
        say!(
            "version {}, {}×{} {:?}, {} samples, first level {}",
            qcs::container::VERSION,
            h.width,
            h.height,
            h.layout,
            h.total_samples,
            h.first_level
        );
        say!("coding: {}", h.coding);
        match h.lattice {
            Some(l) => say!(
                "lattice: root {} px, origin ({}, {}) px",
                l.root_length as f64 / 65536.0,
                l.origin_x as f64 / 65536.0,
                l.origin_y as f64 / 65536.0
            ),
            None => say!("lattice: default (1 px per root, origin at (-W/2, -H/3))"),
        }
        say!(
            "header: {} bytes, check byte ok (level 0's CRC covers it too)",
            ins.header_len.unwrap_or(0)
        );
    }
    say!(
        "{:>5} {:>5} {:>10} {:>19} {:>9} {:>9}  status",
        "chunk",
        "tag",
        "offset",
        "samples",
        "payload",
        "present"
    );
    for c in &ins.chunks {
        let lvl = c.level.and_then(|k| ins.levels.get(k as usize));
        let samples = lvl.map_or(String::from("-"), |l| {
            format!("{}..{}", l.samples.start, l.samples.end)
        });
        let present = lvl.map_or(String::from("-"), |l| l.payload_present.to_string());
        let status = match &c.status {
            qcs::container::ChunkStatus::Verified => "CRC ok".to_string(),
            qcs::container::ChunkStatus::Truncated => "truncated".to_string(),
            qcs::container::ChunkStatus::Bad(e) => format!("BAD: {e}"),
        };
        say!(
            "{:>5} {:>5} {:>10} {:>19} {:>9} {:>9}  {}",
            c.chunk.index,
            qcs::container::chunk::tag_name(c.chunk.tag),
            c.chunk.offset,
            samples,
            c.payload_len.map_or(String::from("?"), |l| l.to_string()),
            present,
            status
        );
    }
    let missing = ins.levels.iter().filter(|l| l.chunk.is_none()).count();
    if missing > 0 {
        say!("{missing} level(s) not in the file");
    }
    for m in &ins.metadata {
        match m {
            qcs::container::Metadata::Icc(p) => say!("ICC profile: {} bytes", p.len()),
            qcs::container::Metadata::Text { key, value } => say!("text: {key} = {value}"),
        }
    }
    say!(
        "samples: {} available, {} verified; end: {}",
        ins.samples_available,
        ins.samples_verified,
        ins.end
    );
    match (input.refused, ins.error) {
        (Some(e @ qcs::Error::Limits(_)), _) => Err(e).with_context(|| {
            format!(
                "{} exceeds the limits `qcs decode` applies (--max-pixels, --max-samples \
                 raise them)",
                a.input.display()
            )
        }),
        (Some(e), _) | (None, Some(e)) if ins.header.is_none() => {
            Err(e).with_context(|| format!("{} is not a .qcs file qcs can read", a.input.display()))
        }
        (Some(e), _) | (None, Some(e)) => {
            Err(e).with_context(|| format!("{} is damaged", a.input.display()))
        }
        (None, None) => Ok(()),
    }
}

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
        )?;
        let rgb = d.image.to_rgb8();
        let path = a.out_dir.join(format!("{stem}-{pct:03}pct.png"));
        rgb.save(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        image::imageops::replace(&mut strip, &rgb, (i as u32 * w) as i64, 0);
        if !quiet {
            note!(
                "{:>6}% {:>8} {:>8} {:>8.2}  {}",
                pct,
                cut,
                d.samples_used,
                qcs::eval::psnr(&reference, &rgb)?,
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

#[derive(Args, Debug)]
pub struct PreviewArgs {
    /// The .qcs file (`-`: standard input).
    pub input: PathBuf,
    /// The animated GIF to write: its name must end in .gif (`-`: standard output).
    pub output: PathBuf,
    /// Bytes between frames (default: one frame per level).
    #[arg(long, value_parser = super::parse_count)]
    pub every: Option<usize>,
    /// Frame size: WxH, or W, Wx or xH keeping the aspect ratio (default: the image's size,
    /// at most 512 px wide).
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<Size>,
    /// Delay per frame in milliseconds.
    #[arg(long, default_value_t = 400, value_parser = clap::value_parser!(u32).range(1..=65535))]
    pub delay_ms: u32,
    /// The most frames to make (`none` lifts the cap); more is refused before any is drawn.
    #[arg(long, value_name = "N", value_parser = super::parse_limit, default_value = "100")]
    pub max_frames: u64,
}

/// 3×5 pixel digits, one row per entry, bit 2 = left column.
const DIGITS: [[u8; 5]; 11] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 3, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
    [6, 5, 6, 5, 6], // B
];

/// Draws `text` (digits and 'B') at the bottom left, white on black, 2 px per font pixel.
fn stamp(img: &mut image::RgbaImage, text: &str) {
    let scale = 2u32;
    let glyphs: Vec<usize> = text
        .chars()
        .filter_map(|c| {
            if c == 'B' {
                Some(10)
            } else {
                c.to_digit(10).map(|d| d as usize)
            }
        })
        .collect();
    let (w, h) = img.dimensions();
    let box_w = (glyphs.len() as u32 * 4 + 1) * scale;
    let box_h = 7 * scale;
    if box_w > w || box_h > h {
        return;
    }
    for y in h - box_h..h {
        for x in 0..box_w {
            img.put_pixel(x, y, image::Rgba([0, 0, 0, 255]));
        }
    }
    for (i, &g) in glyphs.iter().enumerate() {
        for (row, bits) in DIGITS[g].iter().enumerate() {
            for col in 0..3u32 {
                if bits & (4 >> col) != 0 {
                    for dy in 0..scale {
                        for dx in 0..scale {
                            let x = (1 + i as u32 * 4 + col) * scale + dx;
                            let y = h - box_h + (1 + row as u32) * scale + dy;
                            img.put_pixel(x, y, image::Rgba([255, 255, 255, 255]));
                        }
                    }
                }
            }
        }
    }
}

pub fn preview(a: PreviewArgs, ctx: &Ctx) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    use image::{Delay, Frame};
    let gif_name = a
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    if !super::is_stdio(&a.output) && !gif_name {
        return Err(usage!(
            "{}: qcs preview writes an animated GIF; give a name ending in .gif (or - for \
             standard output)",
            a.output.display()
        ));
    }
    super::check_output(&a.output)?;
    let what = || format!("cannot decode {}", a.input.display());
    let frame_size = |h: &qcs::container::Header| {
        a.size.map_or_else(
            || {
                let f = (512.0 / h.width as f64).min(1.0);
                output_size(None, Some(f), h.width, h.height)
            },
            |s| s.resolve(h.width, h.height),
        )
    };
    let src = super::input::Source::open(&a.input)?;
    let how = ReadQcs {
        budget: None,
        recover: false,
    };
    let input = super::input::read_qcs(src, &how, ctx, |h| {
        let size = frame_size(h);
        ctx.limits
            .check_output(size.0 as u64, size.1 as u64)
            .map_err(qcs::Error::from)?;
        Ok(())
    })
    .with_context(what)?;
    let input = input.ok().with_context(what)?;
    let bytes = &input.bytes[..];
    let mut gif_bytes = Vec::new();
    let mut gif = GifEncoder::new_with_speed(&mut gif_bytes, 10);
    gif.set_repeat(Repeat::Infinite)?;
    let delay = |ms: u32| Delay::from_numer_denom_ms(ms, 1);
    let Some(h) = &input.header else {
        // Nothing to show yet: one neutral grey frame (at --size, else 1 × 1).
        let size = a.size.map_or((1, 1), |s| s.resolve(1, 1));
        gif.encode_frame(Frame::from_parts(
            grey(size).to_rgba8(),
            0,
            0,
            delay(a.delay_ms),
        ))?;
        drop(gif);
        super::write_output(&a.output, &gif_bytes)?;
        eprintln_unless(
            ctx.quiet,
            format!(
                "{}: 1 neutral grey frame: the {} bytes end inside the header, nothing to show yet",
                a.output.display(),
                bytes.len()
            ),
        );
        return Ok(());
    };
    let cuts = cuts(bytes, a.every);
    check_frame_count(cuts.len(), bytes.len(), a.every, a.max_frames)?;
    let size = frame_size(h);
    let mut dec = stream_decoder(size, true, false, ctx);
    let mut fed = 0;
    let mut frames = 0;
    for cut in cuts {
        dec.push(&bytes[fed..cut]).with_context(what)?;
        fed = cut;
        // As `qcs decode` draws an output much smaller than the image.
        let pic = dec
            .render_thumbnail(Method::Gouraud, size.0, size.1)
            .with_context(what)?;
        let mut rgba = pic.decoded().image.to_rgba8();
        stamp(&mut rgba, &format!("{cut}B"));
        let ms = if dec.is_complete() {
            a.delay_ms.saturating_mul(4)
        } else {
            a.delay_ms
        };
        gif.encode_frame(Frame::from_parts(rgba, 0, 0, delay(ms)))?;
        frames += 1;
    }
    drop(gif);
    super::write_output(&a.output, &gif_bytes)?;
    eprintln_unless(
        ctx.quiet,
        format!("{}: {frames} frames", a.output.display()),
    );
    Ok(())
}
