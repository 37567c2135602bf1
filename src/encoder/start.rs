//! Where the levels stop and the refinement starts (spec/refinement.md §9).
//!
//! The first level holds 64 samples: its first bytes are the smallest previews, which the
//! levels draw better than a wavelet can. Each further level doubles the samples. It is kept
//! when the file is better with it a little later: at four times the level's bytes past the
//! levels before it, the picture of the levels with it and the refinement after them is
//! closer to the image than that of the levels without it and the refinement after those.
//! (Comparing at the level's own bytes would favour the level: a refinement's first bytes
//! buy less than its next ones.) The levels stop at the first level that does not pay.
//!
//! The pictures compared are real decodes of the first passes, on the image itself up to
//! 2^15 pixels and on an area-averaged copy of that size beyond (the first levels and the
//! refinement's first bytes draw the same coarse picture at any size: a copy of 2^15 pixels
//! decides as the image did, byte for byte, on the eight dev photographs, the bundled images,
//! a 12-megapixel photo and four synthetic pictures, and takes a third of a 651×450 encode's
//! instructions less than one of 2^17; MEASUREMENTS.md).

use super::levels;
use crate::container::{Coding, Header, Layout};
use crate::refinement::encode as refine;
use crate::refinement::Kernel;
use crate::sampling::{SampleColour, SourceImage};
use crate::sites::Quasicrystal;
use crate::Result;

/// The first level's size.
pub(crate) const FIRST_LEVEL: u64 = 64;
/// The most levels before a refinement.
const MOST_LEVELS: u32 = 3;
/// The largest picture the comparison is made on.
const PROXY_PIXELS: u64 = 1 << 15;
/// How far past a level the pictures with and without it are compared, in its bytes.
const HORIZON: usize = 4;
/// Bytes the refinement's header and first layer's framing take.
const FRAMING: usize = 16;

/// The samples of the levels of a file of `pixels` (`layout`, `width × height`) before its
/// refinement (`kernel`, `frac`): `FIRST_LEVEL · 2^k` for the k chosen.
#[allow(clippy::too_many_arguments)]
pub(crate) fn samples_before_refinement(
    pixels: &[u8],
    width: u32,
    height: u32,
    layout: Layout,
    coding: &Coding,
    colour: SampleColour,
    kernel: Kernel,
    frac: u32,
) -> Result<u64> {
    let channels = layout.channels() as usize;
    let area = width as u64 * height as u64;
    let (proxy, pw, ph) = if area > PROXY_PIXELS {
        let f = (area as f64 / PROXY_PIXELS as f64).sqrt();
        let pw = ((width as f64 / f) as u32).max(1);
        let ph = ((height as f64 / f) as u32).max(1);
        (shrink(pixels, width, height, channels, pw, ph), pw, ph)
    } else {
        (pixels.to_vec(), width, height)
    };
    let parea = pw as u64 * ph as u64;
    if parea < FIRST_LEVEL << 2 {
        return Ok(FIRST_LEVEL.min(area));
    }
    let seq = Quasicrystal::new(pw, ph).map_err(super::frame_error)?;
    let source = SourceImage::new(&proxy, pw, ph, channels)?;
    let t = refine::transform(
        &proxy,
        pw,
        ph,
        channels,
        kernel,
        frac,
        refine::default_levels(pw, ph),
    );
    // Only the refinement's first passes matter here: those above a low quality.
    let key = super::quality_key(20);
    let error = |picture: &[u8]| -> f64 {
        picture
            .iter()
            .zip(&proxy)
            .map(|(&a, &b)| (a as f64 - b as f64).powi(2))
            .sum()
    };
    // Levels of n samples: their bytes (header and chunks), and the refinement after them.
    let candidate = |n: u64| -> Result<(usize, refine::Early<'_>)> {
        let mut header = Header::new(pw, ph, layout, n, FIRST_LEVEL, coding.clone());
        header.refinement = true;
        let coded = levels::code(&source, &seq, &header, colour)?;
        let bytes = header.encode()?.len()
            + coded.payloads.iter().map(|p| p.len() + 7).sum::<usize>()
            + FRAMING;
        Ok((bytes, t.early(&coded.fixed, &coded.decoded, key)))
    };
    let mut n = FIRST_LEVEL;
    let (mut bytes, mut without) = candidate(n)?;
    for _ in 1..MOST_LEVELS {
        let next = 2 * n;
        if next > parea {
            break;
        }
        let (next_bytes, with) = candidate(next)?;
        let at = next_bytes + HORIZON * (next_bytes - bytes);
        let better = error(&with.picture(at - next_bytes)) < error(&without.picture(at - bytes));
        if !better {
            break;
        }
        (n, bytes, without) = (next, next_bytes, with);
    }
    // On a copy, the same number of samples: they draw the same coarse picture.
    Ok(n.min(area))
}

/// An area-averaged copy of `pixels` at `w × h`.
fn shrink(pixels: &[u8], width: u32, height: u32, channels: usize, w: u32, h: u32) -> Vec<u8> {
    crate::refinement::resample::resample(
        pixels,
        width as usize,
        height as usize,
        channels,
        0,
        (width as usize, height as usize),
        w as usize,
        h as usize,
    )
}
