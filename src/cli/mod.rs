//! Command-line definitions (clap) and dispatch; one module per subcommand.

/// `println!` that returns stdout's error (e.g. a pipe closed by `head`) instead of
/// panicking; [`main`] ends quietly on a closed pipe.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

mod codec;
mod render;
mod sites;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// qcs — progressive images on quasicrystal sample sites: any prefix of a file is a picture.
#[derive(Parser, Debug)]
#[command(name = "qcs", version, about, long_about = None)]
pub struct Cli {
    /// Print nothing but errors.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Encode images (any format the image crate reads) to .qcs.
    #[command(
        after_help = "Examples:\n  qcs encode photo.png photo.qcs\n  qcs encode photo.jpg photo.qcs --samples 20000 --bits 6\n  qcs encode photos/ *.png --out-dir qcs/   (many files in parallel)\n  convert photo.tif png:- | qcs encode - - > photo.qcs   (standard input and output)"
    )]
    Encode(codec::EncodeArgs),
    /// Decode a .qcs file (or a prefix of one) to an image; the format follows the extension.
    #[command(
        after_help = "Examples:\n  qcs decode photo.qcs photo.png\n  qcs decode photo.qcs thumb.png --size 120x80 --method shepard\n  qcs decode photo.qcs cut.png --bytes 2048   (as a cut download would)\n  qcs decode photo.qcs --frames frames/ --every 4096\n  curl -s URL | qcs decode - - > photo.png   (standard input to PNG on standard output)"
    )]
    Decode(codec::DecodeArgs),
    /// Show a .qcs file's header, levels (byte offsets, sample ranges) and CRC status.
    #[command(after_help = "Example:\n  qcs info photo.qcs")]
    Info(codec::InfoArgs),
    /// Print the first N sample sites of a sampler as CSV (index,x,y[,n0,n1,n2,n3]).
    #[command(
        after_help = "Examples:\n  qcs sites --width 512 --height 512 --count 1089\n  qcs sites --width 640 --height 480 --count 500 --sampler halton"
    )]
    Sites(sites::SitesArgs),
    /// Write an animated GIF of a .qcs file sharpening as its bytes arrive (byte count in each frame).
    #[command(
        after_help = "Examples:\n  qcs preview photo.qcs photo.gif\n  qcs preview photo.qcs photo.gif --every 2048 --size 240x160"
    )]
    Preview(codec::PreviewArgs),
    /// Render a .qcs file (or an image sampled by any strategy) in a stylized way.
    #[command(
        after_help = "Examples:\n  qcs render photo.qcs mosaic.png --style mosaic --samples 2000\n  qcs render --sampler halton --samples 4225 photo.png halton.png --style voronoi\n  qcs render photo.qcs spectrum.png --style spectrum"
    )]
    Render(render::RenderArgs),
    /// Reproduce the paper's evaluation of six sampling strategies on images.
    #[command(after_help = "Example:\n  qcs eval photos/*.png --out eval/")]
    Eval(render::EvalArgs),
    /// Encode an image and write previews decoded from growing prefixes of its file.
    #[command(after_help = "Example:\n  qcs demo assets/rocket.png out/")]
    Demo(codec::DemoArgs),
}

/// Whether `e` is stdout's reader having closed the pipe.
fn closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Exit codes: 0 success, 1 I/O or other failure, 2 usage (clap), 3 malformed input, 4 limit exceeded.
fn exit_code(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if let Some(q) = cause.downcast_ref::<qcs::Error>() {
            return match q {
                qcs::Error::Format(_) | qcs::Error::NeedMoreData => 3,
                qcs::Error::Limits(_) => 4,
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
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let quiet = cli.quiet;
    let r = match cli.command {
        Command::Encode(a) => codec::encode(a, quiet),
        Command::Decode(a) => codec::decode(a, quiet),
        Command::Info(a) => codec::info(a),
        Command::Sites(a) => sites::run(a),
        Command::Demo(a) => codec::demo(a, quiet),
        Command::Preview(a) => codec::preview(a, quiet),
        Command::Render(a) => render::render(a, quiet),
        Command::Eval(a) => render::eval(a, quiet),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`qcs sites … | head`): nothing more to say, as for `yes`.
        Err(e) if closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            // `{e:#}` repeats a cause whose parent already prints it (`thiserror`'s
            // "malformed file: {0}" with `#[from]`, the image crate's errors): skip those.
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

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got {s:?}"))?;
    let w: u32 = w.parse().map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h.parse().map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 {
        return Err(format!("empty size {s:?}"));
    }
    Ok((w, h))
}

/// A scale factor for clap: finite and above 0.
pub fn parse_scale(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a finite number above 0, got {s:?}")),
    }
}

/// A count for clap: an integer of at least 1.
pub fn parse_count(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(v) if v > 0 => Ok(v),
        _ => Err(format!("expected an integer of at least 1, got {s:?}")),
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

/// The bytes of the file `p`, or of standard input for `-` (to its end: a cut pipe is a
/// prefix like any other).
pub fn read_input(p: &std::path::Path) -> anyhow::Result<Vec<u8>> {
    use anyhow::Context;
    use std::io::Read;
    if is_stdio(p) {
        let mut bytes = Vec::new();
        (std::io::stdin().lock().read_to_end(&mut bytes)).context("cannot read standard input")?;
        return Ok(bytes);
    }
    std::fs::read(p).with_context(|| format!("cannot read {}", p.display()))
}

/// Refuses `-` as an output when standard output is a terminal, where binary data would only
/// garble the screen; call it before the work that makes the output.
pub fn check_output(p: &std::path::Path) -> anyhow::Result<()> {
    use std::io::IsTerminal;
    if is_stdio(p) && std::io::stdout().is_terminal() {
        anyhow::bail!(
            "not writing binary data to a terminal: redirect standard output (qcs … - > FILE)"
        );
    }
    Ok(())
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

/// Reads an image (standard input for `-`), recognising its format by content (as `render`
/// does), not by extension, upright: its Exif orientation (a camera's "rotate 90°") is
/// applied to the pixels.
pub fn open_image(p: &std::path::Path) -> anyhow::Result<image::DynamicImage> {
    Ok(read_image(p)?.0)
}

/// [`open_image`], and the image's ICC colour profile if it has one.
///
/// Orientation and profile are metadata: one that cannot be read leaves the image as it
/// is (unrotated, sRGB) rather than refusing it.
pub fn read_image(p: &std::path::Path) -> anyhow::Result<(image::DynamicImage, Option<Vec<u8>>)> {
    use anyhow::Context;
    use image::ImageDecoder;
    let ctx = || format!("cannot read image {}", p.display());
    /// A decoder for the image `r` holds, its format guessed from its first bytes.
    fn by_content<'a, R: std::io::BufRead + std::io::Seek + 'a>(
        r: image::ImageReader<R>,
    ) -> image::ImageResult<Box<dyn ImageDecoder + 'a>> {
        let r = r
            .with_guessed_format()
            .map_err(image::ImageError::IoError)?;
        Ok(Box::new(r.into_decoder()?))
    }
    let mut decoder = if is_stdio(p) {
        by_content(image::ImageReader::new(std::io::Cursor::new(read_input(
            p,
        )?)))
    } else {
        image::ImageReader::open(p)
            .map_err(image::ImageError::IoError)
            .and_then(by_content)
    }
    .with_context(ctx)?;
    let icc = decoder.icc_profile().ok().flatten();
    let orientation = decoder
        .orientation()
        .unwrap_or(image::metadata::Orientation::NoTransforms);
    let mut img = image::DynamicImage::from_decoder(decoder).with_context(ctx)?;
    img.apply_orientation(orientation);
    Ok((img, icc))
}

/// Whether an ICC profile describes sRGB (an RGB profile whose description names it, as
/// "sRGB IEC61966-2.1" or "sRGB built-in" do): storing it would only repeat what a file
/// without a profile means. Reads the `desc` tag, ICC v2 (`desc`) or v4 (`mluc`, UTF-16).
pub fn is_srgb(icc: &[u8]) -> bool {
    let u32_at = |at: usize| -> Option<usize> {
        let b = icc.get(at..at.checked_add(4)?)?;
        Some(u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let desc = || -> Option<String> {
        if icc.get(16..20)? != b"RGB " {
            return None;
        }
        let tags = u32_at(128)?;
        let (at, len) = (0..tags.min(1024)).find_map(|i| {
            let e = 132 + 12 * i;
            if icc.get(e..e + 4)? != b"desc" {
                return None;
            }
            Some((u32_at(e + 4)?, u32_at(e + 8)?))
        })?;
        let tag = icc.get(at..at.checked_add(len)?)?;
        match tag.get(..4)? {
            b"desc" => {
                let n = u32_at(at + 8)?;
                Some(String::from_utf8_lossy(tag.get(12..12usize.checked_add(n)?)?).into())
            }
            b"mluc" => {
                // The first record: its length and offset from the tag's start.
                let (n, off) = (u32_at(at + 20)?, u32_at(at + 24)?);
                let text = tag.get(off..off.checked_add(n)?)?;
                let units = text
                    .chunks_exact(2)
                    .map(|c| u16::from_be_bytes([c[0], c[1]]));
                Some(
                    char::decode_utf16(units)
                        .map(|c| c.unwrap_or('?'))
                        .collect(),
                )
            }
            _ => None,
        }
    };
    desc().is_some_and(|d| d.contains("sRGB"))
}

/// The image format an output path's extension names; PNG for `-` (standard output, checked
/// with [`check_output`]).
pub fn output_format(path: &std::path::Path) -> anyhow::Result<image::ImageFormat> {
    if is_stdio(path) {
        check_output(path)?;
        return Ok(image::ImageFormat::Png);
    }
    image::ImageFormat::from_path(path).map_err(|_| {
        anyhow::anyhow!(
            "cannot write {}: unknown image format (use .png, .jpg, .gif, .bmp, .tiff, .webp, .pnm, .qoi or .tga)",
            path.display()
        )
    })
}

/// Writes `img` to `path` in the format of its extension, widening grey or grey+alpha to
/// RGB(A) for encoders that lack them (GIF, QOI, TIFF), and creating the file only once the
/// whole image is encoded (no empty or partial file on error).
pub fn save_image(img: &image::DynamicImage, path: &std::path::Path) -> anyhow::Result<()> {
    save_image_icc(img, path, None).map(|_| ())
}

/// [`save_image`] with an ICC colour profile, embedded when the format can hold one (PNG,
/// JPEG, TIFF, WebP). Returns whether the profile was written (`true` without one).
pub fn save_image_icc(
    img: &image::DynamicImage,
    path: &std::path::Path,
    icc: Option<&[u8]>,
) -> anyhow::Result<bool> {
    use image::codecs::{jpeg, png, tiff, webp};
    use image::{ImageEncoder, ImageFormat};
    /// Writes `img` with `enc` carrying `icc`, or `None` if `enc` refuses profiles.
    fn with_icc<E: ImageEncoder>(
        img: &image::DynamicImage,
        mut enc: E,
        icc: &[u8],
    ) -> Option<image::ImageResult<()>> {
        enc.set_icc_profile(icc.to_vec()).ok()?;
        Some(img.write_with_encoder(enc))
    }
    let format = output_format(path)?;
    let write = |img: &image::DynamicImage| -> (Vec<u8>, image::ImageResult<()>, bool) {
        let mut buf = std::io::Cursor::new(Vec::new());
        let embedded = icc.and_then(|icc| match format {
            ImageFormat::Png => with_icc(img, png::PngEncoder::new(&mut buf), icc),
            ImageFormat::Jpeg => with_icc(img, jpeg::JpegEncoder::new(&mut buf), icc),
            ImageFormat::Tiff => with_icc(img, tiff::TiffEncoder::new(&mut buf), icc),
            ImageFormat::WebP => with_icc(img, webp::WebPEncoder::new_lossless(&mut buf), icc),
            _ => None,
        });
        let (result, kept) = match embedded {
            Some(r) => (r, true),
            None => (img.write_to(&mut buf, format), icc.is_none()),
        };
        (buf.into_inner(), result, kept)
    };
    let (mut bytes, mut result, mut kept) = write(img);
    if matches!(result, Err(image::ImageError::Unsupported(_))) {
        let wide = if img.color().has_alpha() {
            image::DynamicImage::ImageRgba8(img.to_rgba8())
        } else {
            image::DynamicImage::ImageRgb8(img.to_rgb8())
        };
        (bytes, result, kept) = write(&wide);
    }
    result.map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
    write_output(path, &bytes)?;
    Ok(kept)
}

/// A sampler by its CLI name (the quasicrystal included).
pub fn sampler_by_name(
    name: &str,
    seed: u64,
) -> Option<Box<dyn qcs::sites::Sampler + Send + Sync>> {
    if name == "quasicrystal" {
        return Some(Box::new(qcs::sites::Quasicrystal::new(1, 1).ok()?));
    }
    use qcs::sites::strategies::*;
    Some(match name {
        "periodic" => Box::new(Periodic),
        "jittered" => Box::new(Jittered { seed }),
        "halton" => Box::new(Halton),
        "random" => Box::new(Random { seed }),
        "farthest" => Box::new(FarthestPoint { seed }),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::is_srgb;

    /// A minimal RGB profile whose only tag is `desc`, holding `tag`.
    fn profile(tag: &[u8]) -> Vec<u8> {
        let mut p = vec![0u8; 128];
        p[16..20].copy_from_slice(b"RGB ");
        p.extend_from_slice(&1u32.to_be_bytes());
        p.extend_from_slice(b"desc");
        p.extend_from_slice(&144u32.to_be_bytes());
        p.extend_from_slice(&(tag.len() as u32).to_be_bytes());
        p.extend_from_slice(tag);
        p
    }

    /// A v2 `desc` tag.
    fn v2(text: &str) -> Vec<u8> {
        let mut t = b"desc\0\0\0\0".to_vec();
        t.extend_from_slice(&(text.len() as u32 + 1).to_be_bytes());
        t.extend_from_slice(text.as_bytes());
        t.push(0);
        profile(&t)
    }

    /// A v4 `mluc` tag with one record.
    fn v4(text: &str) -> Vec<u8> {
        let utf16: Vec<u8> = text.encode_utf16().flat_map(u16::to_be_bytes).collect();
        let mut t = b"mluc\0\0\0\0".to_vec();
        for n in [1u32, 12] {
            t.extend_from_slice(&n.to_be_bytes());
        }
        t.extend_from_slice(b"enUS");
        t.extend_from_slice(&(utf16.len() as u32).to_be_bytes());
        t.extend_from_slice(&28u32.to_be_bytes());
        t.extend_from_slice(&utf16);
        profile(&t)
    }

    #[test]
    fn srgb_profiles_are_recognised_by_their_description() {
        assert!(is_srgb(&v2("sRGB IEC61966-2.1")));
        assert!(is_srgb(&v4("sRGB built-in")));
        assert!(!is_srgb(&v2("Display P3")));
        assert!(!is_srgb(&v4("Adobe RGB (1998)")));
        // A grey profile is not sRGB whatever it says.
        let mut grey = v2("sRGB");
        grey[16..20].copy_from_slice(b"GRAY");
        assert!(!is_srgb(&grey));
        // Cut or garbled profiles are not sRGB (and do not panic).
        let whole = v4("sRGB built-in");
        for n in 0..whole.len() {
            assert!(!is_srgb(&whole[..n]), "cut at {n}");
        }
        let mut far = v2("sRGB");
        far[136..140].copy_from_slice(&u32::MAX.to_be_bytes());
        assert!(!is_srgb(&far));
        assert!(!is_srgb(b"not a profile"));
    }
}
