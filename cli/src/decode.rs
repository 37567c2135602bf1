//! `qcs decode`: a .qcs file (or a prefix of one) to an image, or to a preview per level and refinement layer
//! (`--frames`); the stream helpers `qcs preview` shares.

use super::input::{QcsInput, ReadQcs};
use super::{eprintln_unless, Ctx, Size};
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use qcs::{DecodeOptions, Method, StreamDecoder};
use std::path::{Path, PathBuf};

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

pub(super) fn output_size(size: Option<Size>, scale: Option<f64>, w: u32, h: u32) -> (u32, u32) {
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
pub(super) fn stream_decoder(
    size: (u32, u32),
    thumbnail: bool,
    recover: bool,
    ctx: &Ctx,
) -> StreamDecoder {
    StreamDecoder::with_options(qcs::format::ParserOptions {
        limits: ctx.limits.clone(),
        recover,
        max_samples: thumbnail.then(|| qcs::thumbnail_samples(size.0, size.1)),
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
pub(super) fn grey(size: (u32, u32)) -> image::DynamicImage {
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
    let dropped = super::save_image_with(&d.image, out, super::Meta::of(&d))?;
    if dropped.icc {
        super::warn(format!(
            "{} cannot hold the file's ICC colour profile: its colours are not sRGB and will \
             look wrong; write PNG, JPEG, TIFF or WebP to keep it",
            out.display()
        ));
    }
    if dropped.alpha {
        super::warn(format!(
            "{} cannot hold the picture's transparency: its transparent parts show the colours \
             under them; write PNG, WebP or TIFF to keep it",
            out.display()
        ));
    }
    if dropped.exif {
        eprintln_unless(
            ctx.quiet,
            format!(
                "qcs: {} cannot hold the file's Exif metadata (camera, date, place): write \
                 PNG, JPEG or WebP to keep it",
                out.display()
            ),
        );
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
pub(super) fn cuts(bytes: &[u8], every: Option<usize>) -> Vec<usize> {
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
pub(super) fn check_frame_count(
    n: usize,
    len: usize,
    every: Option<usize>,
    max: u64,
) -> Result<()> {
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
        // PNG holds the ICC profile and the Exif.
        super::save_image_with(&d.image, &path, super::Meta::of(d))?;
        eprintln_unless(
            ctx.quiet,
            format!("{}: {} samples", path.display(), d.samples_used),
        );
    }
    Ok(())
}

/// Byte offsets at which each level chunk and each refinement layer ends, with the metadata
/// chunks after it: where the next level or layer starts, or the file ends. (A frame then
/// carries the ICC profile that follows level 0, and the last one the Exif at the end.)
fn level_ends(bytes: &[u8]) -> Vec<usize> {
    let ins = qcs::container::inspect(bytes);
    let pictures: Vec<u64> = (ins.chunks.iter())
        .filter(|c| c.level.is_some() || c.layer.is_some())
        .map(|c| c.chunk.offset)
        .chain([ins.file_len])
        .collect();
    pictures[1..].iter().map(|&end| end as usize).collect()
}
