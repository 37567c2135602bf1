//! `qcs encode`, `qcs decode`, `qcs info`, `qcs demo`.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use qcs::container::Coding;
use qcs::sampling::SampleColour;
use qcs::{DecodeOptions, EncodeOptions, Method, StreamDecoder};
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
    /// Input image(s) or directories, then the output .qcs when encoding one file without
    /// --out-dir (`-`: standard input or output).
    #[arg(required = true, num_args = 1..)]
    pub paths: Vec<PathBuf>,
    /// Encode every input into this directory (as NAME.qcs), in parallel.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Total number of samples.
    #[arg(long, conflicts_with = "density", value_parser = clap::value_parser!(u64).range(1..))]
    pub samples: Option<u64>,
    /// Samples per pixel (default 0.25).
    #[arg(long, value_parser = parse_density)]
    pub density: Option<f64>,
    /// Raw coding (coding 0) at this many bits per channel, 1–8, instead of the predictive coding.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8), conflicts_with_all = ["quality", "lossless"])]
    pub bits: Option<u8>,
    /// Quality, 0–100 (default 85), as cjpeg's and cwebp's: how faithful the whole file is.
    /// With --levels-only, the quality of the levels' predictive coding (default 75).
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=100), conflicts_with = "lossless")]
    pub quality: Option<u8>,
    /// Exactly the input's pixels (with --levels-only: exact sample values).
    #[arg(long)]
    pub lossless: bool,
    /// The best picture in at most this many bytes (the whole file).
    #[arg(long, conflicts_with_all = ["quality", "lossless", "levels_only"])]
    pub target_size: Option<u64>,
    /// Only the quasicrystal levels, no refinement (a format version 2 file; one sample per
    /// 4 pixels unless --samples or --density say otherwise).
    #[arg(long)]
    pub levels_only: bool,
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

/// What [`encode_file`] wrote: the input's and the output's size, and the size of the ICC
/// profile stored, if any.
struct Encoded {
    input: u64,
    output: u64,
    icc: Option<usize>,
    /// The samples the density asked for, when they were capped at the default limit.
    capped_from: Option<u64>,
}

fn encode_file(
    input: &Path,
    output: &Path,
    opts: &EncodeOptions,
    (strip_icc, density_given): (bool, bool),
) -> Result<Encoded> {
    let (img, icc) = super::read_image(input)?;
    let mut opts = opts.clone();
    opts.icc = icc.filter(|icc| !strip_icc && !super::is_srgb(icc));
    // A file `qcs decode` would refuse (default limits) is not worth writing.
    let limits = qcs::Limits::default();
    limits
        .check_image(img.width() as u64, img.height() as u64)
        .map_err(qcs::Error::from)
        .with_context(|| format!("cannot encode {}", input.display()))?;
    // The default density's count is capped at the limit (`EncodeOptions::density`); an
    // explicit --samples or --density beyond it is refused.
    let px = img.width() as u64 * img.height() as u64;
    let asked = (opts.samples)
        .unwrap_or((opts.density * px as f64).floor() as u64)
        .min(px);
    let capped = opts.samples.is_none() && !density_given && asked > limits.max_samples;
    let capped_from = capped.then_some(asked);
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
    super::write_output(output, &bytes)?;
    Ok(Encoded {
        input: std::fs::metadata(input).map_or(0, |m| m.len()),
        output: bytes.len() as u64,
        icc: opts.icc.as_ref().map(Vec::len),
        capped_from,
    })
}

fn out_path(dir: &Path, input: &Path) -> PathBuf {
    let stem = input
        .file_stem()
        .map(|s| s.to_os_string())
        .unwrap_or_default();
    dir.join(stem).with_extension("qcs")
}

/// Whether `a` and `b` name the same existing file.
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

fn is_image(p: &Path) -> bool {
    let ext = p
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    image::ImageFormat::from_extension(&ext).is_some()
}

pub fn encode(a: EncodeArgs, quiet: bool) -> Result<()> {
    let opts = a.options();
    let flags = (a.strip_icc, a.density.is_some());
    let Some(dir) = &a.out_dir else {
        if a.paths.len() != 2 {
            bail!(
                "give one input and one output (IN OUT.qcs), or use --out-dir DIR for many inputs"
            );
        }
        if same_file(&a.paths[0], &a.paths[1]) {
            bail!(
                "the output {} is the input image: give an output such as OUT.qcs",
                a.paths[1].display()
            );
        }
        super::check_output(&a.paths[1])?;
        let e = encode_file(&a.paths[0], &a.paths[1], &opts, flags)?;
        if !quiet {
            eprintln!(
                "{} → {}: {}{} bytes{}",
                a.paths[0].display(),
                a.paths[1].display(),
                // Standard input has no size to tell.
                match super::is_stdio(&a.paths[0]) {
                    true => String::new(),
                    false => format!("{} → ", e.input),
                },
                e.output,
                e.icc
                    .map(|n| format!(" (with its {n}-byte ICC profile)"))
                    .unwrap_or_default()
            );
            if let Some(asked) = e.capped_from {
                eprintln!(
                    "  {} samples, not the {asked} of the density: the most `qcs decode` takes \
                     by default",
                    qcs::Limits::default().max_samples
                );
            }
        }
        return Ok(());
    };
    if a.paths.iter().any(|p| super::is_stdio(p)) {
        bail!(
            "standard input (-) is one image: encode it without --out-dir (qcs encode - OUT.qcs)"
        );
    }
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut inputs = Vec::new();
    for p in &a.paths {
        if p.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("cannot list {}", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file() && is_image(p))
                .collect();
            v.sort();
            inputs.extend(v);
        } else {
            inputs.push(p.clone());
        }
    }
    let mut seen = std::collections::HashMap::new();
    for p in &inputs {
        let out = out_path(dir, p);
        if let Some(prev) = seen.insert(out.clone(), p.clone()) {
            bail!(
                "{} and {} would both be written to {}",
                prev.display(),
                p.display(),
                out.display()
            );
        }
    }
    let start = Instant::now();
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(inputs.len() as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}").expect("valid template"),
    );
    let results: Vec<Result<Encoded>> = inputs
        .par_iter()
        .map(|p| {
            let r = encode_file(p, &out_path(dir, p), &opts, flags);
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();
    let (mut ok, mut bin, mut bout) = (0, 0, 0);
    let mut first_err = None;
    for (p, r) in inputs.iter().zip(results) {
        match r {
            Ok(e) => {
                ok += 1;
                bin += e.input;
                bout += e.output;
                if e.capped_from.is_some() && !quiet {
                    eprintln!(
                        "qcs: {}: {} samples, fewer than the density's: the most `qcs decode` \
                         takes by default",
                        p.display(),
                        qcs::Limits::default().max_samples
                    );
                }
            }
            Err(e) => {
                eprintln!("qcs: {}: {e:#}", p.display());
                first_err.get_or_insert(e);
            }
        }
    }
    if !quiet {
        eprintln!(
            "{ok} of {} files encoded, {bin} bytes in, {bout} bytes out, {:.2} s",
            inputs.len(),
            start.elapsed().as_secs_f64()
        );
    }
    match first_err {
        Some(e) => Err(e.context(format!(
            "{} of {} files failed",
            inputs.len() - ok,
            inputs.len()
        ))),
        None => Ok(()),
    }
}

#[derive(Args, Debug)]
pub struct DecodeArgs {
    /// The .qcs file (`-`: standard input, read to its end).
    pub input: PathBuf,
    /// The output image (PNG, JPEG, … by extension; `-`: PNG on standard output); optional
    /// with --frames.
    pub output: Option<PathBuf>,
    /// Reconstruction method.
    #[arg(long, value_enum, default_value = "gouraud")]
    pub method: MethodArg,
    /// Output size WxH (default: the image's own size).
    #[arg(long, value_parser = super::parse_size, conflicts_with = "scale")]
    pub size: Option<(u32, u32)>,
    /// Output scale factor.
    #[arg(long, value_parser = super::parse_scale)]
    pub scale: Option<f64>,
    /// Use at most N samples.
    #[arg(long, conflicts_with_all = ["bytes", "frames"])]
    pub samples: Option<u64>,
    /// Render at the output's pixel centres from every sample (or --samples), even for an
    /// output much smaller than the image, which is otherwise a thumbnail: from the first
    /// samples it needs, each pixel the mean of a square of subpixels (closer to the image,
    /// and faster).
    #[arg(long)]
    pub no_thumbnail: bool,
    /// Use only the first K bytes of the file, as a cut download would.
    #[arg(long)]
    pub bytes: Option<usize>,
    /// Write a preview PNG into DIR every --every bytes (default: at each level), up to
    /// --bytes if given.
    #[arg(long)]
    pub frames: Option<PathBuf>,
    /// With --frames: bytes between previews.
    #[arg(long, requires = "frames", value_parser = super::parse_count)]
    pub every: Option<usize>,
    /// Return the longest verified prefix of a damaged file instead of failing.
    #[arg(long)]
    pub recover: bool,
}

fn output_size(size: Option<(u32, u32)>, scale: Option<f64>, w: u32, h: u32) -> (u32, u32) {
    // `--scale` is finite and above 0 (clap checks it).
    let f = scale.unwrap_or(1.0);
    size.unwrap_or((
        ((w as f64 * f).round() as u32).max(1),
        ((h as f64 * f).round() as u32).max(1),
    ))
}

/// The file's header, as `qcs::decode` reports a file that has none: it sets the default
/// output size before the decode, which checks it against the limits.
fn header(bytes: &[u8]) -> qcs::Result<qcs::container::Header> {
    match qcs::container::Header::parse(bytes) {
        Ok((h, _)) => Ok(h),
        Err(qcs::container::FormatError::TruncatedHeader { .. }) => Err(qcs::Error::NeedMoreData),
        Err(e) => Err(qcs::Error::Format(e)),
    }
}

/// A stream decoder for pictures of `size`: one that decodes only the samples a thumbnail of
/// that size draws on when `thumbnail` (so it also takes a file with more samples than the
/// limits allow, if its first levels fit).
fn stream_decoder(size: (u32, u32), thumbnail: bool, recover: bool) -> StreamDecoder {
    let opts = qcs::container::ParserOptions::with_limits(qcs::Limits::default()).recover(recover);
    StreamDecoder::with_options(match thumbnail {
        true => opts.decode_before(qcs::thumbnail_samples(size.0, size.1)),
        false => opts,
    })
}

pub fn decode(a: DecodeArgs, quiet: bool) -> Result<()> {
    let bytes = super::read_input(&a.input)?;
    let ctx = || format!("cannot decode {}", a.input.display());
    if let Some(dir) = &a.frames {
        frames(&a, &bytes, dir, quiet).with_context(ctx)?;
        if a.output.is_none() {
            return Ok(());
        }
    }
    let Some(out) = &a.output else {
        bail!("give an output image path (or --frames DIR)")
    };
    // An output the image crate cannot write is refused before the decode.
    super::output_format(out)?;
    let header = header(&bytes).with_context(ctx)?;
    let size = output_size(a.size, a.scale, header.width, header.height);
    let opts = DecodeOptions {
        method: a.method.into(),
        size: Some(size),
        max_samples: a.samples,
        max_bytes: a.bytes,
        thumbnail: !a.no_thumbnail,
        recover: a.recover,
        ..Default::default()
    };
    let d = match qcs::decode(&bytes, &opts) {
        Err(e @ qcs::Error::Limits(qcs::limits::LimitError::Samples(..))) => {
            return Err(e).with_context(|| {
                format!(
                    "{} (a smaller output, --size or --scale, or --samples N decodes only the \
                     samples it needs)",
                    ctx()
                )
            })
        }
        d => d.with_context(ctx)?,
    };
    let kept = super::save_image_icc(&d.image, out, d.icc.as_deref())?;
    if !kept && !quiet {
        eprintln!(
            "qcs: warning: {} cannot hold the file's ICC colour profile: its colours are not sRGB \
             and will look wrong; write PNG, JPEG, TIFF or WebP to keep it",
            out.display()
        );
    }
    if !quiet {
        // A thumbnail differs from the plain render from 2.25 samples per output pixel on
        // (2 × 2 subpixels each).
        let pixels = size.0 as f64 * size.1 as f64;
        let thumbnail = opts.thumbnail && d.samples_used as f64 >= 2.25 * pixels;
        eprintln!(
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
        );
    }
    Ok(())
}

fn frames(a: &DecodeArgs, bytes: &[u8], dir: &Path, quiet: bool) -> Result<()> {
    let bytes = &bytes[..a.bytes.unwrap_or(usize::MAX).min(bytes.len())];
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let h = header(bytes)?;
    let size = output_size(a.size, a.scale, h.width, h.height);
    let mut dec = stream_decoder(size, !a.no_thumbnail, a.recover);
    let mut cuts: Vec<usize> = match a.every {
        Some(k) => (1..)
            .map(|i| i * k)
            .take_while(|&c| c < bytes.len())
            .collect(),
        None => level_ends(bytes),
    };
    cuts.push(bytes.len());
    cuts.dedup();
    let mut fed = 0;
    let mut n = 0;
    for cut in cuts {
        dec.push(&bytes[fed..cut])?;
        fed = cut;
        if dec.header().is_none() {
            continue;
        }
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
        super::save_image_icc(&d.image, &path, d.icc.as_deref())?;
        if !quiet {
            eprintln!("{}: {} samples", path.display(), pic.decoded().samples_used);
        }
        n += 1;
    }
    if n == 0 {
        return Err(qcs::Error::NeedMoreData.into());
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

pub fn info(a: InfoArgs) -> Result<()> {
    let bytes = super::read_input(&a.input)?;
    let ins = qcs::container::inspect(&bytes);
    say!("file: {} ({} bytes)", a.input.display(), ins.file_len);
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
    if let Some(e) = ins.error {
        return Err(e).with_context(|| format!("{} is damaged", a.input.display()));
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// An image to encode.
    pub input: PathBuf,
    /// Directory for the .qcs file and the previews.
    pub out_dir: PathBuf,
    /// Total number of samples (default: one per 4 pixels).
    #[arg(long)]
    pub samples: Option<u64>,
}

pub fn demo(a: DemoArgs, quiet: bool) -> Result<()> {
    let img = super::open_image(&a.input)?;
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
    /// The animated GIF to write (`-`: standard output).
    pub output: PathBuf,
    /// Bytes between frames (default: one frame per level).
    #[arg(long, value_parser = super::parse_count)]
    pub every: Option<usize>,
    /// Frame size WxH (default: the image's size, at most 512 px wide).
    #[arg(long, value_parser = super::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Delay per frame in milliseconds.
    #[arg(long, default_value_t = 400)]
    pub delay_ms: u32,
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

pub fn preview(a: PreviewArgs, quiet: bool) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    use image::{Delay, Frame};
    super::check_output(&a.output)?;
    let bytes = super::read_input(&a.input)?;
    let ctx = || format!("cannot decode {}", a.input.display());
    let mut cuts: Vec<usize> = match a.every {
        Some(k) => (1..)
            .map(|i| i * k)
            .take_while(|&c| c < bytes.len())
            .collect(),
        None => level_ends(&bytes),
    };
    cuts.push(bytes.len());
    cuts.dedup();
    let mut gif_bytes = Vec::new();
    let mut gif = GifEncoder::new_with_speed(&mut gif_bytes, 10);
    gif.set_repeat(Repeat::Infinite)?;
    let h = header(&bytes).with_context(ctx)?;
    let size = a.size.unwrap_or_else(|| {
        let f = (512.0 / h.width as f64).min(1.0);
        output_size(None, Some(f), h.width, h.height)
    });
    let mut dec = stream_decoder(size, true, false);
    let mut fed = 0;
    let mut frames = 0;
    for cut in cuts {
        dec.push(&bytes[fed..cut]).with_context(ctx)?;
        fed = cut;
        if dec.header().is_none() {
            continue;
        }
        // As `qcs decode` draws an output much smaller than the image.
        let pic = dec
            .render_thumbnail(Method::Gouraud, size.0, size.1)
            .with_context(ctx)?;
        let mut rgba = pic.decoded().image.to_rgba8();
        stamp(&mut rgba, &format!("{cut}B"));
        let delay = if dec.is_complete() {
            a.delay_ms.saturating_mul(4)
        } else {
            a.delay_ms
        };
        gif.encode_frame(Frame::from_parts(
            rgba,
            0,
            0,
            Delay::from_numer_denom_ms(delay, 1),
        ))?;
        frames += 1;
    }
    drop(gif);
    if frames == 0 {
        return Err(qcs::Error::NeedMoreData).with_context(ctx);
    }
    super::write_output(&a.output, &gif_bytes)?;
    if !quiet {
        eprintln!("{}: {frames} frames", a.output.display());
    }
    Ok(())
}
