//! `qcs preview`: an animated GIF of a .qcs file sharpening as its bytes arrive.

use super::decode::{check_frame_count, cuts, grey, output_size, stream_decoder};
use super::input::ReadQcs;
use super::{eprintln_unless, Ctx, Size};
use anyhow::{Context, Result};
use clap::Args;
use qcs::Method;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct PreviewArgs {
    /// The .qcs file (`-`: standard input).
    pub input: PathBuf,
    /// The animated GIF to write: its name must end in .gif (`-`: standard output).
    pub output: PathBuf,
    /// Bytes between frames (default: one frame per level and refinement layer).
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
