//! The `qcs` command-line tool: command-line definitions (clap) and dispatch, one module per subcommand; what they share
//! (global options, exit codes, argument parsers, reading and writing files) is here and in
//! `input` (bounded reading) and `icc`.
#![forbid(unsafe_code)]

/// `println!` that returns stdout's error (e.g. a pipe closed by `head`) instead of
/// panicking; [`main`] ends quietly on a closed pipe.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

/// A usage error (exit 2): the command line asks for something qcs will not do.
macro_rules! usage {
    ($($arg:tt)*) => {
        anyhow::Error::new($crate::Refusal::Usage(format!($($arg)*)))
    };
}

mod decode;
mod demo;
mod encode;
mod eval;
mod exif;
mod icc;
mod info;
mod input;
mod preview;
mod render;
mod sites;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// qcs — progressive images on quasicrystal sample sites: any prefix of a file is a picture.
#[derive(Parser, Debug)]
#[command(name = "qcs", version, about, long_about = None)]
#[command(
    after_help = "Exit codes: 0 success, 1 I/O or other failure, 2 usage, 3 malformed input, 4 a limit exceeded."
)]
pub struct Cli {
    #[command(flatten)]
    pub global: Global,
    #[command(subcommand)]
    pub command: Command,
}

/// Options every subcommand takes.
#[derive(clap::Args, Debug, Clone)]
pub struct Global {
    /// Print only errors, and warnings that the output is not what was asked for (colours
    /// that will look wrong, a damaged file's dropped part).
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// Worker threads (default: one per core).
    #[arg(long, global = true, value_name = "N", value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// The largest image, and output picture, in pixels: default 268435456 (2^28); `none`
    /// lifts it (and the 32768-pixel side limit, to the format's 65535).
    #[arg(long, global = true, value_name = "N", value_parser = parse_limit)]
    pub max_pixels: Option<u64>,
    /// The most samples a decode decodes: default 4194304 (2^22, about 1.6 GB at peak);
    /// `none` lifts it. Lower it for untrusted input on a small machine.
    #[arg(long, global = true, value_name = "N", value_parser = parse_limit)]
    pub max_samples: Option<u64>,
    /// The most memory a decode may take by the decoder's account (see `qcs::Limits::max_alloc`):
    /// default 4G (K, M, G: binary multiples); `none` lifts it.
    #[arg(long, global = true, value_name = "BYTES", value_parser = parse_bytes)]
    pub max_memory: Option<u64>,
    /// The most input bytes read and held: default 64M (K, M, G: binary multiples); `none`
    /// lifts it. A longer input is refused (exit 4) with no more than that read.
    #[arg(long, global = true, value_name = "BYTES", value_parser = parse_bytes)]
    pub max_input: Option<u64>,
}

/// The default of `--max-input`: more than any file within the default limits holds (2^22
/// samples of 4 channels at 8 bits are 16 MiB, the metadata limit another 16 MiB).
pub const DEFAULT_MAX_INPUT: u64 = 64 << 20;

/// What the global options decide, for every subcommand.
#[derive(Clone, Debug)]
pub struct Ctx {
    /// `--quiet`.
    pub quiet: bool,
    /// The decoder's (and the encoder's checks') limits, with `--max-pixels`, `--max-samples`
    /// and `--max-memory` applied.
    pub limits: qcs::Limits,
    /// `--max-input`.
    pub max_input: u64,
}

impl Global {
    fn ctx(&self) -> Ctx {
        let mut limits = qcs::Limits::default();
        if let Some(p) = self.max_pixels {
            limits.max_image_pixels = p;
            limits.max_output_pixels = p;
            if p == u64::MAX {
                limits.max_dimension = qcs::Limits::none().max_dimension;
            }
        }
        if let Some(n) = self.max_samples {
            limits.max_samples = n;
        }
        if let Some(n) = self.max_memory {
            limits.max_alloc = n;
        }
        Ctx {
            quiet: self.quiet,
            limits,
            max_input: self.max_input.unwrap_or(DEFAULT_MAX_INPUT),
        }
    }
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Encode images (any format the image crate reads) to .qcs.
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  qcs encode photo.png photo.qcs      (the output must end in .qcs, or be -)\n  qcs encode photo.jpg -o photo.bin --samples 20000 --bits 6\n  qcs encode photo.png photo.qcs --psnr   (and the PSNR of the whole file)\n  qcs encode photos/ more/*.png --out-dir qcs/   (many files in parallel; folders recursively)\n  convert photo.tif png:- | qcs encode - - > photo.qcs   (standard input and output)"
    )]
    Encode(encode::EncodeArgs),
    /// Decode a .qcs file (or a prefix of one) to an image; the format follows the extension.
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  qcs decode photo.qcs photo.png\n  qcs decode photo.qcs thumb.png --size 120 --method shepard   (120 px wide)\n  qcs decode photo.qcs cut.png --bytes 2048   (as a cut download would; reads no more)\n  qcs decode photo.qcs --frames frames/ --every 4096\n  curl -s URL | qcs decode - - > photo.png   (standard input to PNG on standard output)"
    )]
    Decode(decode::DecodeArgs),
    /// Show a .qcs file's header, levels (byte offsets, sample ranges) and CRC status.
    #[command(after_help = "Example:\n  qcs info photo.qcs")]
    Info(info::InfoArgs),
    /// Print the first N sample sites of a sampler as CSV (index,x,y[,n0,n1,n2,n3]).
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  qcs sites --width 512 --height 512 --count 1089\n  qcs sites --width 640 --height 480 --count 500 --sampler halton"
    )]
    Sites(sites::SitesArgs),
    /// Write an animated GIF of a .qcs file sharpening as its bytes arrive (byte count in each frame).
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  qcs preview photo.qcs photo.gif   (the output must end in .gif, or be -)\n  qcs preview photo.qcs photo.gif --every 2048 --size 240"
    )]
    Preview(preview::PreviewArgs),
    /// Render a .qcs file (or an image sampled by any strategy) in a stylized way.
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  qcs render photo.qcs mosaic.png --style mosaic --samples 2000\n  qcs render --sampler halton --samples 4225 photo.png halton.png --style voronoi\n  qcs render photo.qcs spectrum.png --style spectrum"
    )]
    Render(render::RenderArgs),
    /// Reproduce the paper's evaluation of six sampling strategies on images.
    #[command(
        allow_negative_numbers = true,
        after_help = "Example:\n  qcs eval photos/*.png --out eval/"
    )]
    Eval(eval::EvalArgs),
    /// Encode an image and write previews decoded from growing prefixes of its file.
    #[command(
        allow_negative_numbers = true,
        after_help = "Example:\n  qcs demo assets/rocket.png out/"
    )]
    Demo(demo::DemoArgs),
}

/// A refusal with one of the README's exit codes: a usage error (2) or a limit (4).
#[derive(Debug)]
pub enum Refusal {
    /// The command line asks for something qcs will not do (exit 2).
    Usage(String),
    /// The input is larger than a limit allows (exit 4).
    Limit(String),
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Usage(m) | Refusal::Limit(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Refusal {}

/// Prints `msg` on standard error unless `quiet`.
pub fn eprintln_unless(quiet: bool, msg: impl std::fmt::Display) {
    if !quiet {
        eprintln!("{msg}");
    }
}

/// Prints a warning: that the output is not what was asked for. `--quiet` does not hide it.
pub fn warn(msg: impl std::fmt::Display) {
    eprintln!("qcs: warning: {msg}");
}

/// Whether `e` is stdout's reader having closed the pipe.
fn closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Exit codes: 0 success, 1 I/O or other failure, 2 usage, 3 malformed input, 4 limit exceeded.
fn exit_code(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if let Some(r) = cause.downcast_ref::<Refusal>() {
            return match r {
                Refusal::Usage(_) => 2,
                Refusal::Limit(_) => 4,
            };
        }
        if let Some(q) = cause.downcast_ref::<qcs::Error>() {
            return match q {
                qcs::Error::Format(_) => 3,
                qcs::Error::Limits(_) => 4,
                // A file cut inside its header is not malformed (README: a neutral grey
                // picture, exit 0) and every command draws it so: this reaching here is qcs's
                // own failure, not the input's.
                qcs::Error::NeedMoreData => 1,
                _ => 1,
            };
        }
        if let Some(ie) = cause.downcast_ref::<image::ImageError>() {
            return match ie {
                image::ImageError::IoError(_) => 1,
                image::ImageError::Limits(_) => 4,
                _ => 3,
            };
        }
    }
    1
}

/// Parses the command line and runs it.
fn main() -> ExitCode {
    let cli = Cli::parse();
    let ctx = cli.global.ctx();
    if let Some(n) = cli.global.threads {
        // Only fails if the pool was built already, which nothing here does first.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global();
    }
    let r = match cli.command {
        Command::Encode(a) => encode::encode(a, &ctx),
        Command::Decode(a) => decode::decode(a, &ctx),
        Command::Info(a) => info::info(a, &ctx),
        Command::Sites(a) => sites::run(a, &ctx),
        Command::Demo(a) => demo::demo(a, &ctx),
        Command::Preview(a) => preview::preview(a, &ctx),
        Command::Render(a) => render::render(a, &ctx),
        Command::Eval(a) => eval::eval(a, &ctx),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`qcs sites … | head`): nothing more to say, as for `yes`.
        Err(e) if closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            // The cause chain, each message once: `qcs::Error` prints only its own part
            // ("malformed file") and leaves the rest to its source, but the image crate's
            // errors also print their source, which `{e:#}` would then repeat: skip those.
            let mut msg = String::new();
            for cause in e.chain() {
                let s = cause.to_string();
                if !msg.ends_with(&s) {
                    if !msg.is_empty() {
                        msg.push_str(": ");
                    }
                    msg.push_str(&s);
                }
            }
            eprintln!("qcs: error: {msg}");
            ExitCode::from(exit_code(&e))
        }
    }
}

/// An output size: `WxH` exactly, or one side (`W`, `Wx` or `xH`) with the other following
/// the image's aspect ratio.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    /// The width asked for, if any.
    pub width: Option<u32>,
    /// The height asked for, if any.
    pub height: Option<u32>,
}

impl Size {
    /// The size for an image of `w × h` pixels (at least 1 × 1).
    pub fn resolve(self, w: u32, h: u32) -> (u32, u32) {
        let scale = |side: u32, num: u32, den: u32| {
            let v = (side as f64 * num as f64 / den.max(1) as f64).round();
            v.clamp(1.0, u32::MAX as f64) as u32
        };
        match (self.width, self.height) {
            (Some(x), Some(y)) => (x, y),
            (Some(x), None) => (x, scale(x, h, w)),
            (None, Some(y)) => (scale(y, w, h), y),
            (None, None) => (w.max(1), h.max(1)),
        }
    }
}

/// Parses `WxH`, `W`, `Wx` or `xH`.
pub fn parse_size(s: &str) -> Result<Size, String> {
    let bad = || {
        format!("expected WxH, or W, Wx or xH to keep the aspect ratio (whole numbers of at least 1), got {s:?}")
    };
    let side = |t: &str| -> Result<Option<u32>, String> {
        match t {
            "" => Ok(None),
            t => match t.parse::<u32>() {
                Ok(v) if v > 0 => Ok(Some(v)),
                _ => Err(bad()),
            },
        }
    };
    let (width, height) = match s.split_once(['x', 'X']) {
        Some((w, h)) => (side(w)?, side(h)?),
        None => (side(s)?, None),
    };
    if width.is_none() && height.is_none() {
        return Err(bad());
    }
    Ok(Size { width, height })
}

/// A scale factor for clap: finite and above 0.
pub fn parse_scale(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a finite number above 0, got {s:?}")),
    }
}

/// A whole number of at least `min` (clap's own message for "-5" is a hint about `--`).
fn whole(s: &str, min: u64) -> Result<u64, String> {
    match s.parse::<u64>() {
        Ok(v) if v >= min => Ok(v),
        _ => Err(format!(
            "expected a whole number of at least {min}, got {s:?}"
        )),
    }
}

/// A count for clap: an integer of at least 1.
pub fn parse_count(s: &str) -> Result<usize, String> {
    whole(s, 1).and_then(|v| usize::try_from(v).map_err(|_| format!("{s} is too large")))
}

/// A count for clap: an integer of at least 1.
pub fn parse_count_u64(s: &str) -> Result<u64, String> {
    whole(s, 1)
}

/// An image side for clap: 1 to 65535 pixels (the format's bound).
pub fn parse_side(s: &str) -> Result<u32, String> {
    match whole(s, 1) {
        Ok(v) if v <= 65535 => Ok(v as u32),
        _ => Err(format!(
            "expected a whole number of pixels from 1 to 65535, got {s:?}"
        )),
    }
}

/// `--threads`: 1 to 1024.
fn parse_threads(s: &str) -> Result<usize, String> {
    match whole(s, 1) {
        Ok(v) if v <= 1024 => Ok(v as usize),
        _ => Err(format!(
            "expected a number of threads from 1 to 1024, got {s:?}"
        )),
    }
}

/// A limit for clap: a whole number of at least 1, or `none` (no limit: `u64::MAX`).
pub fn parse_limit(s: &str) -> Result<u64, String> {
    if s.eq_ignore_ascii_case("none") {
        return Ok(u64::MAX);
    }
    whole(s, 1).map_err(|e| format!("{e} (or none)"))
}

/// A byte count for clap: a whole number, optionally with K, M or G (binary multiples).
pub fn parse_byte_count(s: &str) -> Result<u64, String> {
    let (num, shift) = match s.as_bytes().last().map(u8::to_ascii_uppercase) {
        Some(b'K') => (&s[..s.len() - 1], 10),
        Some(b'M') => (&s[..s.len() - 1], 20),
        Some(b'G') => (&s[..s.len() - 1], 30),
        _ => (s, 0),
    };
    num.parse::<u64>()
        .ok()
        .and_then(|v| v.checked_mul(1 << shift))
        .ok_or_else(|| {
            format!("expected a whole number of bytes (K, M, G: binary multiples), got {s:?}")
        })
}

/// `--max-input`: a byte count of at least 1, or `none`.
fn parse_bytes(s: &str) -> Result<u64, String> {
    if s.eq_ignore_ascii_case("none") {
        return Ok(u64::MAX);
    }
    match parse_byte_count(s)? {
        0 => Err(format!("expected at least 1 byte (or none), got {s:?}")),
        v => Ok(v),
    }
}

/// The samplers' CLI names, for clap's value parser.
pub const SAMPLERS: [&str; 6] = [
    "quasicrystal",
    "periodic",
    "jittered",
    "halton",
    "random",
    "farthest",
];

/// Whether a path argument is `-`: standard input as an input, standard output as an output.
pub fn is_stdio(p: &std::path::Path) -> bool {
    p.as_os_str() == "-"
}

/// Refuses `-` as an output when standard output is a terminal, where binary data would only
/// garble the screen (a usage error), and an output whose folder does not exist; call it
/// before the work that makes the output.
pub fn check_output(p: &std::path::Path) -> anyhow::Result<()> {
    use std::io::IsTerminal;
    if is_stdio(p) {
        if std::io::stdout().is_terminal() {
            return Err(usage!(
                "not writing binary data to a terminal: redirect standard output (qcs … - > FILE)"
            ));
        }
        return Ok(());
    }
    if p.is_dir() {
        return Err(usage!("{} is a folder, not a file to write", p.display()));
    }
    match p.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => {
            anyhow::bail!(
                "cannot write {}: there is no folder {}",
                p.display(),
                dir.display()
            )
        }
        _ => Ok(()),
    }
}

/// Writes `bytes` to the file `p`, or to standard output for `-`.
pub fn write_output(p: &std::path::Path, bytes: &[u8]) -> anyhow::Result<()> {
    use anyhow::Context;
    use std::io::Write;
    if is_stdio(p) {
        check_output(p)?;
        let mut out = std::io::stdout().lock();
        (out.write_all(bytes).and_then(|()| out.flush()))
            .context("cannot write standard output")?;
        return Ok(());
    }
    std::fs::write(p, bytes).with_context(|| format!("cannot write {}", p.display()))
}

/// Whether `p` names a .qcs file by its extension.
pub fn has_qcs_extension(p: &std::path::Path) -> bool {
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("qcs"))
}

/// Whether `bytes` begin like a .qcs file: the magic, or a prefix of it (an empty file too).
pub fn looks_like_qcs(bytes: &[u8]) -> bool {
    let m = qcs::container::MAGIC;
    bytes.starts_with(&m) || m.starts_with(bytes)
}

/// Reads an image (standard input for `-`), recognising its format by content (as `render`
/// does), not by extension, upright: its Exif orientation (a camera's "rotate 90°") is
/// applied to the pixels.
pub fn open_image(p: &std::path::Path, ctx: &Ctx) -> anyhow::Result<image::DynamicImage> {
    Ok(read_image(p, ctx)?.image)
}

/// An image read to be encoded: its pixels upright, and the metadata kept with them.
pub struct Photo {
    pub image: image::DynamicImage,
    pub icc: Option<Vec<u8>>,
    pub exif: Option<Vec<u8>>,
    /// The input was an animation, of which `image` is the first frame.
    pub animated: bool,
}

/// [`open_image`], and the image's ICC colour profile and Exif metadata if it has them (the
/// Exif's orientation set upright, as the pixels are).
///
/// Orientation, profile and Exif are metadata: one that cannot be read leaves the image as
/// it is (unrotated, sRGB, without Exif) rather than refusing it. A .qcs file is refused with
/// a hint: it is decoded, not encoded.
pub fn read_image(p: &std::path::Path, ctx: &Ctx) -> anyhow::Result<Photo> {
    use anyhow::Context;
    use image::ImageDecoder;
    use std::io::{BufRead, Seek};
    let ctx_msg = || format!("cannot read image {}", p.display());
    /// A decoder for the image `r` holds, its format guessed from its first bytes (or, when they
    /// name none, the one `r` was given).
    fn by_content<'a, R: BufRead + Seek + 'a>(
        r: image::ImageReader<R>,
        limits: &qcs::Limits,
    ) -> image::ImageResult<Box<dyn ImageDecoder + 'a>> {
        let mut r = r
            .with_guessed_format()
            .map_err(image::ImageError::IoError)?;
        let mut l = image::Limits::default();
        l.max_image_width = Some(limits.max_dimension);
        l.max_image_height = Some(limits.max_dimension);
        r.limits(l);
        Ok(Box::new(r.into_decoder()?))
    }
    let qcs_hint = |p: &std::path::Path| {
        usage!(
            "{} is a .qcs file already: decode it (qcs decode {} OUT.png), or give an image to encode",
            p.display(),
            p.display()
        )
    };
    let animated;
    let mut decoder = if is_stdio(p) {
        let mut src = input::Source::open(p)?;
        if src.peek(2)?.starts_with(&qcs::container::MAGIC) {
            return Err(qcs_hint(p));
        }
        input::check_image_start(&mut src)?;
        let bytes = input::read_all(src, ctx)?;
        animated = input::is_animation(std::io::Cursor::new(&bytes));
        by_content(
            image::ImageReader::new(std::io::Cursor::new(bytes)),
            &ctx.limits,
        )
    } else {
        let mut file = std::io::BufReader::new(std::fs::File::open(p).with_context(ctx_msg)?);
        let head = file.fill_buf().with_context(ctx_msg)?;
        if head.starts_with(&qcs::container::MAGIC) {
            return Err(qcs_hint(p));
        }
        input::check_image_head(head, p)?;
        animated = input::is_animation(&mut file);
        file.rewind().with_context(ctx_msg)?;
        // The extension's format stands when the content names none (a TGA has no signature).
        let mut reader = image::ImageReader::new(file);
        if let Ok(format) = image::ImageFormat::from_path(p) {
            reader.set_format(format);
        }
        by_content(reader, &ctx.limits)
    }
    .with_context(ctx_msg)?;
    let icc = decoder.icc_profile().ok().flatten();
    let mut exif = decoder.exif_metadata().ok().flatten();
    let orientation = decoder
        .orientation()
        .unwrap_or(image::metadata::Orientation::NoTransforms);
    let mut img = image::DynamicImage::from_decoder(decoder).with_context(ctx_msg)?;
    img.apply_orientation(orientation);
    // The pixels are upright now: so says the Exif kept, lest a viewer turn them again.
    if let Some(e) = &mut exif {
        exif::upright(e);
    }
    Ok(Photo {
        image: img,
        icc,
        exif,
        animated,
    })
}

/// The output extensions qcs writes, for its usage errors.
const WRITES: &str = "use .png, .jpg, .gif, .bmp, .tiff, .webp, .ppm, .pgm, .pam, .qoi or .tga";

/// The image format an output path's extension names; PNG for `-` (standard output, checked
/// with [`check_output`]). An unknown extension is a usage error, checked before the work.
pub fn output_format(path: &std::path::Path) -> anyhow::Result<image::ImageFormat> {
    check_output(path)?;
    if is_stdio(path) {
        return Ok(image::ImageFormat::Png);
    }
    let format = image::ImageFormat::from_path(path).map_err(|_| {
        let hint = match has_qcs_extension(path) {
            true => " (qcs encode writes .qcs files)",
            false => "",
        };
        usage!(
            "cannot write {}: unknown image format ({WRITES}){hint}",
            path.display()
        )
    })?;
    if !format.writing_enabled() {
        return Err(usage!(
            "cannot write {}: qcs writes no {format:?} ({WRITES})",
            path.display()
        ));
    }
    if extension(path) == "pbm" {
        return Err(usage!(
            "cannot write {}: a PBM holds black and white only (use .pgm, .ppm or .pam)",
            path.display()
        ));
    }
    Ok(format)
}

/// The lowercased extension of `path` ("" without one).
fn extension(path: &std::path::Path) -> String {
    let ext = path.extension().unwrap_or_default();
    ext.to_string_lossy().to_ascii_lowercase()
}

/// Writes `img` to `path` in the format of its extension, widening grey or grey+alpha to
/// RGB(A) for encoders that lack them (GIF, QOI, TIFF), and creating the file only once the
/// whole image is encoded (no empty or partial file on error).
pub fn save_image(img: &image::DynamicImage, path: &std::path::Path) -> anyhow::Result<()> {
    save_image_with(img, path, Meta::default()).map(|_| ())
}

/// Metadata an output carries where its format can.
#[derive(Clone, Copy, Debug, Default)]
pub struct Meta<'a> {
    /// An ICC colour profile: PNG, JPEG, TIFF and WebP hold one.
    pub icc: Option<&'a [u8]>,
    /// Exif metadata: PNG, JPEG and WebP hold it.
    pub exif: Option<&'a [u8]>,
}

impl<'a> Meta<'a> {
    /// The metadata of a decoded picture.
    pub fn of(d: &'a qcs::DecodedImage) -> Self {
        Meta {
            icc: d.icc.as_deref(),
            exif: d.exif.as_deref(),
        }
    }
}

/// What of a [`Meta`] an output's format could not hold.
#[derive(Clone, Copy, Debug, Default)]
pub struct Dropped {
    pub icc: bool,
    pub exif: bool,
    /// Transparency (an alpha channel not wholly opaque): JPEG, PPM and PGM hold none.
    pub alpha: bool,
}

/// [`save_image`] with `meta` embedded where the format can hold it. Returns what it could
/// not hold.
pub fn save_image_with(
    img: &image::DynamicImage,
    path: &std::path::Path,
    meta: Meta,
) -> anyhow::Result<Dropped> {
    use std::io::Write;
    let format = output_format(path)?;
    let cannot =
        |e: &dyn std::fmt::Display| anyhow::anyhow!("cannot write {}: {e}", path.display());
    if is_stdio(path) {
        // Standard output cannot seek, as some encoders need: the picture is made in memory.
        let mut bytes = Vec::new();
        let dropped = encode_image(img, |img| {
            bytes.clear();
            encode_into(img, format, "", meta, &mut std::io::Cursor::new(&mut bytes))
        })
        .map_err(|e| cannot(&e))?;
        write_output(path, &bytes)?;
        return Ok(dropped);
    }
    // Streamed into a file beside the output, which takes its name only when complete: an
    // error leaves no partial picture, and the encoded bytes are never all in memory.
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let part = path.with_file_name(format!(".{name}.{}.part", std::process::id()));
    let written = encode_image(img, |img| {
        let mut sink = std::io::BufWriter::with_capacity(1 << 16, std::fs::File::create(&part)?);
        let dropped = encode_into(img, format, &extension(path), meta, &mut sink)?;
        sink.flush()?;
        Ok(dropped)
    })
    .map_err(|e| cannot(&e))
    .and_then(|dropped| {
        std::fs::rename(&part, path).map_err(|e| cannot(&e))?;
        Ok(dropped)
    });
    if written.is_err() {
        let _ = std::fs::remove_file(&part);
    }
    written
}

/// `encode(img)`, and again in 8-bit RGB(A) if the format cannot hold `img`'s colour type.
fn encode_image<T>(
    img: &image::DynamicImage,
    mut encode: impl FnMut(&image::DynamicImage) -> image::ImageResult<T>,
) -> image::ImageResult<T> {
    match encode(img) {
        Err(image::ImageError::Unsupported(_)) => encode(&if img.color().has_alpha() {
            image::DynamicImage::ImageRgba8(img.to_rgba8())
        } else {
            image::DynamicImage::ImageRgb8(img.to_rgb8())
        }),
        r => r,
    }
}

/// The quality of a JPEG output (`image`'s scale). At 75, its default, the JPEG of a dev
/// photograph's default qcs file was 36.99 dB from the picture decoded, about as far as that
/// picture is from the photograph; at 90, 41.34 dB (and 1.6× the bytes).
const JPEG_QUALITY: u8 = 90;

/// Encodes `img` in `format` into `sink` (a file whose extension is `ext`), with `meta` where
/// the format can hold it. Returns what it could not hold.
fn encode_into<W: std::io::Write + std::io::Seek>(
    img: &image::DynamicImage,
    format: image::ImageFormat,
    ext: &str,
    meta: Meta,
    sink: &mut W,
) -> image::ImageResult<Dropped> {
    use image::codecs::{jpeg, png, tiff, webp};
    use image::{ImageEncoder, ImageFormat};
    /// Writes `img` with `enc`, carrying what of `meta` it takes.
    fn with<E: ImageEncoder>(
        img: &image::DynamicImage,
        mut enc: E,
        meta: Meta,
    ) -> image::ImageResult<Dropped> {
        let icc = meta
            .icc
            .is_some_and(|icc| enc.set_icc_profile(icc.to_vec()).is_err());
        let exif = meta
            .exif
            .is_some_and(|e| enc.set_exif_metadata(e.to_vec()).is_err());
        img.write_with_encoder(enc)?;
        Ok(Dropped {
            icc,
            exif,
            alpha: false,
        })
    }
    let none = Dropped {
        icc: meta.icc.is_some(),
        exif: meta.exif.is_some(),
        alpha: false,
    };
    let opaque_only = format == ImageFormat::Jpeg || ["ppm", "pgm"].contains(&ext);
    let alpha = opaque_only && translucent(img);
    let dropped = match format {
        ImageFormat::Png => with(img, png::PngEncoder::new(sink), meta),
        ImageFormat::Jpeg => with(
            img,
            jpeg::JpegEncoder::new_with_quality(sink, JPEG_QUALITY),
            meta,
        ),
        ImageFormat::Tiff => with(img, tiff::TiffEncoder::new(sink), meta),
        ImageFormat::WebP => with(img, webp::WebPEncoder::new_lossless(sink), meta),
        ImageFormat::Pnm => write_netpbm(img, ext, sink).map(|()| none),
        _ => img.write_to(sink, format).map(|()| none),
    };
    dropped.map(|d| Dropped { alpha, ..d })
}

/// Whether `img` has an alpha channel with a value below opaque.
fn translucent(img: &image::DynamicImage) -> bool {
    use image::DynamicImage as D;
    match img {
        D::ImageLumaA8(i) => i.pixels().any(|p| p.0[1] < u8::MAX),
        D::ImageRgba8(i) => i.pixels().any(|p| p.0[3] < u8::MAX),
        other => other.color().has_alpha() && other.to_rgba8().pixels().any(|p| p.0[3] < u8::MAX),
    }
}

/// Writes `img` as the netpbm file its extension `ext` names: `.ppm` binary PPM (P6) and
/// `.pgm` binary PGM (P5), without alpha, as JPEG; `.pnm` whichever of the two holds the
/// picture, or PAM with alpha; `.pam` PAM (P7), which few viewers read. (`image` writes PAM
/// whatever the name says.)
fn write_netpbm(
    img: &image::DynamicImage,
    ext: &str,
    sink: impl std::io::Write,
) -> image::ImageResult<()> {
    use image::codecs::pnm::{PnmEncoder, PnmSubtype, SampleEncoding::Binary};
    use image::{ColorType, DynamicImage};
    let enc = PnmEncoder::new(sink);
    let (colour, alpha) = (img.color().has_color(), img.color().has_alpha());
    let (kind, subtype) = match ext {
        "ppm" => (ColorType::Rgb8, PnmSubtype::Pixmap(Binary)),
        "pgm" => (ColorType::L8, PnmSubtype::Graymap(Binary)),
        "pnm" if !alpha && colour => (ColorType::Rgb8, PnmSubtype::Pixmap(Binary)),
        "pnm" if !alpha => (ColorType::L8, PnmSubtype::Graymap(Binary)),
        _ => return img.write_with_encoder(enc),
    };
    // Converted only if need be: a 12-megapixel copy costs 36 MB.
    match (img.color() == kind, kind) {
        (true, _) => img.write_with_encoder(enc.with_subtype(subtype)),
        (false, ColorType::Rgb8) => {
            DynamicImage::ImageRgb8(img.to_rgb8()).write_with_encoder(enc.with_subtype(subtype))
        }
        (false, _) => {
            DynamicImage::ImageLuma8(img.to_luma8()).write_with_encoder(enc.with_subtype(subtype))
        }
    }
}

/// A sampler by its CLI name (the quasicrystal included).
pub fn sampler_by_name(
    name: &str,
    seed: u64,
) -> Option<Box<dyn qcs_lab::samplers::Sampler + Send + Sync>> {
    if name == "quasicrystal" {
        return Some(Box::new(qcs::sites::Quasicrystal::new(1, 1).ok()?));
    }
    use qcs_lab::samplers::*;
    Some(match name {
        "periodic" => Box::new(Periodic),
        "jittered" => Box::new(Jittered { seed }),
        "halton" => Box::new(Halton),
        "random" => Box::new(Random { seed }),
        "farthest" => Box::new(FarthestPoint { seed }),
        _ => return None,
    })
}
