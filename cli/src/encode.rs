//! `qcs encode`: images to .qcs files, one or many (in parallel), with a summary of each.

use super::{eprintln_unless, Ctx};
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use qcs::container::Coding;
use qcs::sampling::SampleColour;
use qcs::{DecodeOptions, EncodeOptions};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    /// Quality, 0–100 (default 85), as cjpeg's and cwebp's: how faithful the whole file is, from
    /// the smallest files to nearly lossless. With --levels-only, the quality of the levels'
    /// predictive coding (default 75).
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=100), conflicts_with = "lossless")]
    pub quality: Option<u8>,
    /// Exactly the input's pixels, every channel, at 8 bits per channel (a deeper input is
    /// stored as 8, with a warning; with --levels-only: exact sample values).
    #[arg(long)]
    pub lossless: bool,
    /// The best picture in at most this many bytes (the whole file), as cwebp's -size.
    #[arg(long, value_parser = super::parse_count_u64, conflicts_with_all = ["quality", "lossless", "levels_only"])]
    pub target_size: Option<u64>,
    /// Only the quasicrystal levels, no refinement (a format version 2 file, one sample per 4
    /// pixels unless --samples or --density say otherwise): the paper's sampling.
    #[arg(long)]
    pub levels_only: bool,
    /// Samples in the levels (at most the image's pixels). By default the encoder chooses
    /// where the levels stop and the refinement begins (a first level of 64 samples, and each
    /// doubling that pays for its bytes); with --levels-only one per 4 pixels.
    #[arg(long, conflicts_with = "density", value_parser = super::parse_count_u64)]
    pub samples: Option<u64>,
    /// Samples per pixel in the levels (with --levels-only; default 0.25).
    #[arg(long, value_parser = parse_density, requires = "levels_only")]
    pub density: Option<f64>,
    /// Raw coding (coding 0) of the levels at this many bits per channel, 1–8, instead of the
    /// predictive coding.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub bits: Option<u8>,
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
    /// Drop the input's Exif metadata (camera, date, place). By default it is stored at the
    /// end of the file (no preview waits for it), its orientation set upright as the pixels
    /// are.
    #[arg(long)]
    pub strip_exif: bool,
    /// Also decode the file written (whole, at full size) and print its PSNR against the
    /// image (over RGB).
    #[arg(long)]
    pub psnr: bool,
}

/// What `encode_file` takes from the command line besides the encoder's options.
#[derive(Clone, Copy)]
struct Flags {
    strip_icc: bool,
    strip_exif: bool,
    /// `--density` was given (a count beyond the sample limit is then refused, not capped).
    density_given: bool,
    psnr: bool,
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
        let mut o = EncodeOptions {
            samples: self.samples,
            ..Default::default()
        };
        if self.levels_only {
            let params = if self.lossless {
                qcs::coding::predictive::Params::lossless()
            } else {
                qcs::coding::predictive::Params::from_quality(
                    self.quality.unwrap_or(DEFAULT_QUALITY),
                )
            };
            o.coding = params.coding();
            o.target = qcs::Target::LevelsOnly;
        } else {
            o.target = match (self.lossless, self.target_size) {
                (true, _) => qcs::Target::Lossless,
                (_, Some(size)) => qcs::Target::Size(size),
                _ => qcs::Target::Quality(self.quality.unwrap_or(qcs::DEFAULT_QUALITY)),
            };
        }
        if let Some(bits) = self.bits {
            o.coding = Coding::Raw { bits };
        }
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
    /// The size of the Exif metadata stored, if any.
    exif: Option<usize>,
    /// What the file is not that was asked for (printed unless `--quiet`).
    warnings: Vec<String>,
    /// With `--psnr`: the PSNR of the whole file decoded at full size, in dB.
    psnr: Option<f64>,
    /// Where the levels end and the refinement begins and ends (byte offsets; metadata may
    /// follow it), and its layers.
    refinement: Option<(u64, u64, u32)>,
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
                "{w}×{h} {:?}, {} samples in {} level{}, {}; ",
                hd.layout,
                hd.total_samples,
                hd.level_count(),
                if hd.level_count() == 1 { "" } else { "s" },
                hd.coding
            );
        }
        if let Some((at, end, layers)) = self.refinement {
            let _ = write!(
                s,
                "levels in bytes 0..{at}, then a refinement of {} bytes in {layers} layer{}; ",
                end - at,
                if layers == 1 { "" } else { "s" }
            );
        }
        let _ = write!(s, "{} bytes", self.output);
        if let Some(n) = self.input {
            let _ = write!(s, " (from {n})");
        }
        let _ = write!(s, ", {:.3} bits per pixel", bits / px);
        // Of a file of levels only: the samples carry the whole picture.
        if let (Some(hd), None) = (&self.header, self.refinement) {
            let _ = write!(
                s,
                ", {:.2} per sample",
                bits / hd.total_samples.max(1) as f64
            );
        }
        if let Some(p) = self.psnr {
            let _ = write!(s, ", PSNR {p:.2} dB");
        }
        let icc = self.icc.map(|n| format!("{n}-byte ICC profile"));
        let kept: Vec<String> = [icc, self.exif.map(|n| format!("{n}-byte Exif"))]
            .into_iter()
            .flatten()
            .collect();
        if !kept.is_empty() {
            let _ = write!(s, " (with its {})", kept.join(" and "));
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
    flags: Flags,
    ctx: &Ctx,
) -> Result<Encoded> {
    let super::Photo {
        image: img,
        icc,
        exif,
        animated,
    } = super::read_image(input, ctx)?;
    let mut opts = opts.clone();
    opts.icc = icc.filter(|icc| !flags.strip_icc && !super::icc::is_srgb(icc));
    opts.exif = exif.filter(|_| !flags.strip_exif);
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
    // The default density's count (levels only) is capped at the sample limit; an explicit
    // --samples or --density beyond it is refused.
    let asked = match (opts.samples, opts.target) {
        (Some(n), _) => n,
        (None, qcs::Target::LevelsOnly) => (opts.density * px as f64).floor() as u64,
        (None, _) => opts.sample_count(w, h),
    }
    .min(px);
    let explicit = opts.samples.is_some() || flags.density_given;
    // The encoder itself stops the default density at the default limit.
    let capped = !explicit && asked > limits.max_samples.min(qcs::Limits::default().max_samples);
    let mut warnings = Vec::new();
    if capped {
        let n = asked.min(limits.max_samples);
        opts.samples = Some(n);
        if n < asked {
            warnings.push(format!(
                "qcs: {}: {n} samples, fewer than the {asked} of the density: the most `qcs \
                 decode` takes (--max-samples)",
                input.display()
            ));
        }
    }
    let colour = img.color();
    let bits = colour.bits_per_pixel() / colour.channel_count() as u16;
    if bits > 8 {
        warnings.push(format!(
            "qcs: {}: {bits} bits per channel, stored as 8 (qcs keeps 8-bit pictures)",
            input.display()
        ));
    }
    if animated {
        warnings.push(format!(
            "qcs: {}: an animation; qcs stores its first frame",
            input.display()
        ));
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
        + opts.exif.as_ref().map_or(0, Vec::len)
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
    // The decoder's memory account is checked at the header: a file whose decode would
    // exceed --max-memory is not written.
    qcs::StreamDecoder::new(limits.clone())
        .push(&bytes[..bytes.len().min(64)])
        .with_context(|| {
            format!(
                "cannot encode {}: `qcs decode` would refuse the file; raise --max-memory",
                input.display()
            )
        })?;
    if let qcs::Target::Size(size) = opts.target {
        if bytes.len() as u64 > size {
            warnings.push(format!(
                "qcs: {}: {} bytes, over --target-size {size}: the levels and the metadata \
                 alone take more (--strip-exif, --strip-icc)",
                input.display(),
                bytes.len()
            ));
        }
    }
    let psnr = match flags.psnr {
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
            Some(qcs_lab::eval::psnr(&img.to_rgb8(), &d.image.to_rgb8())?)
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
        exif: opts.exif.as_ref().map(Vec::len),
        warnings,
        psnr,
        refinement: {
            let info = qcs::container::inspect(&bytes);
            let layers = info.refinement.as_ref().map(|r| r.layers);
            info.refinement_bytes()
                .zip(layers)
                .map(|(r, n)| (r.start, r.end, n))
        },
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
    // Also the photos qcs cannot read (a phone's HEIC, JPEG XL, JPEG 2000): each is then
    // reported with how to convert it, not passed over in silence.
    let ext = p.extension().unwrap_or_default().to_ascii_lowercase();
    image::ImageFormat::from_path(p).is_ok()
        || ["heic", "heif", "jxl", "jp2", "j2k"]
            .iter()
            .any(|e| ext == *e)
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
    let flags = Flags {
        strip_icc: a.strip_icc,
        strip_exif: a.strip_exif,
        density_given: a.density.is_some(),
        psnr: a.psnr,
    };
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
    for w in &e.warnings {
        eprintln_unless(ctx.quiet, w);
    }
    eprintln_unless(ctx.quiet, e.summary(input, output));
    Ok(())
}

fn encode_many(
    a: &EncodeArgs,
    dir: &Path,
    opts: &EncodeOptions,
    flags: Flags,
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
                for w in &e.warnings {
                    eprintln_unless(ctx.quiet, w);
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
