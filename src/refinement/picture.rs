//! Pixels ↔ coefficient planes (spec/format.md, *Refinement: channels* and *the picture*).
//!
//! The coded channels are those of the predictive coding: grey (and alpha) as they are, R, G, B
//! as YCoCg-R (`Co = R − B`, `t = B + (Co >> 1)`, `Cg = G − t`, `Y = t + (Cg >> 1)`), then
//! alpha. Channels with the range 0..=255 (grey, Y, alpha) are centred by subtracting 128;
//! every value is then multiplied by 2^F, F the file's fraction bits (lossy files code a
//! little below the integer grid, where the 9/7 steps round).

use super::bitplane::StreamState;
use super::wavelet::{inverse, low_size, Kernel};

/// Whether coded channel `c` of a layout with `channels` channels ranges over 0..=255 (and is
/// centred), rather than −255..=255 (Co, Cg).
fn centred(channels: usize, c: usize) -> bool {
    !(channels >= 3 && (c == 1 || c == 2))
}

/// Pixels (interleaved, `channels` per pixel) → one plane per coded channel, times 2^frac.
pub(crate) fn to_planes(pixels: &[u8], channels: usize, frac: u32) -> Vec<Vec<i32>> {
    let n = pixels.len() / channels;
    let mut planes = vec![Vec::with_capacity(n); channels];
    for px in pixels.chunks_exact(channels) {
        let coded = coded_channels(px);
        for (c, plane) in planes.iter_mut().enumerate() {
            plane.push(coded[c] << frac);
        }
    }
    planes
}

/// One pixel's coded channel values (centred), from its layout channel values.
pub(crate) fn coded_channels(px: &[u8]) -> [i32; 4] {
    let mut out = [0; 4];
    if px.len() >= 3 {
        let (r, g, b) = (px[0] as i32, px[1] as i32, px[2] as i32);
        let co = r - b;
        let t = b + (co >> 1);
        let cg = g - t;
        out[0] = t + (cg >> 1) - 128;
        out[1] = co;
        out[2] = cg;
        if px.len() == 4 {
            out[3] = px[3] as i32 - 128;
        }
    } else {
        for (o, &v) in out.iter_mut().zip(px) {
            *o = v as i32 - 128;
        }
    }
    out
}

/// Coded channel values (centred, integer) → a pixel's layout values, clamped to 0..=255.
#[inline]
fn layout_values(coded: &[i32], out: &mut [u8]) {
    let clamp = |v: i64| v.clamp(0, 255) as u8;
    let coded: [i64; 4] = std::array::from_fn(|c| coded.get(c).copied().unwrap_or(0) as i64);
    if out.len() >= 3 {
        let t = coded[0] + 128 - (coded[2] >> 1);
        let g = coded[2] + t;
        let b = t - (coded[1] >> 1);
        let r = b + coded[1];
        out[0] = clamp(r);
        out[1] = clamp(g);
        out[2] = clamp(b);
        if out.len() == 4 {
            out[3] = clamp(coded[3] + 128);
        }
    } else {
        for (o, &v) in out.iter_mut().zip(&coded) {
            *o = clamp(v + 128);
        }
    }
}

/// The inverse of the gain of the low-low band of k levels of the integer 9/7 on a
/// constant, in 16.16 fixed point, for k = 0..=15: round(2^16 / g^(2k)) with
/// g = 1.2298828545 the gain of the four steps (with their rounded weights) on a constant.
pub(crate) const LOW_GAIN_97_INVERSE: [i64; 16] = [
    65536, 43326, 28643, 18936, 12519, 8276, 5472, 3617, 2391, 1581, 1045, 691, 457, 302, 200, 132,
];

/// `LOW_GAIN_97_INVERSE` for `kernel` (the 5/3 keeps a constant as it is).
pub(crate) fn low_gain_inverse(kernel: Kernel, levels: u32) -> i64 {
    match kernel {
        Kernel::Reversible53 => 1 << 16,
        Kernel::Integer97 => LOW_GAIN_97_INVERSE[levels as usize],
    }
}

/// What the picture is drawn from: the transform, the fraction bits and each channel's
/// low-low prediction.
pub(crate) struct Source<'a> {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub kernel: Kernel,
    pub levels: u32,
    pub frac: u32,
    /// Per channel, the low-low band's predicted values (row-major, its own width).
    pub prediction: &'a [Vec<i32>],
}

/// The picture at level `stop` of the transform (0: the image size; k: the low-low band of
/// level k, about 1/2^k of each side), interleaved in the file's layout, from the streams
/// decoded so far (`streams[s]` is `None` for a stream not decoded; a picture at level k
/// needs streams 0..=levels − k).
pub(crate) fn picture(src: &Source, streams: &[Option<&StreamState>], stop: u32) -> Vec<u8> {
    let stop = stop.min(src.levels);
    let (w, h) = (src.width, src.height);
    let mut planes = vec![vec![0i32; w * h]; src.channels];
    // The low-low band starts from its prediction.
    let (lw, lh) = low_size(w, h, src.levels);
    for (plane, pred) in planes.iter_mut().zip(src.prediction) {
        for y in 0..lh {
            plane[y * w..y * w + lw].copy_from_slice(&pred[y * lw..(y + 1) * lw]);
        }
    }
    let mut values = Vec::new();
    for st in streams.iter().flatten() {
        for (k, b) in st.bands.iter().enumerate() {
            let c = st.channel_of(k);
            let plane = &mut planes[c];
            values.resize(b.band.w, 0);
            for y in 0..b.band.h {
                let row = (b.band.y0 + y) * w + b.band.x0;
                b.row_values(y, &mut values);
                for (v, &add) in plane[row..row + b.band.w].iter_mut().zip(&values) {
                    *v = v.wrapping_add(add);
                }
            }
        }
    }
    let (pw, ph) = low_size(w, h, stop);
    // The picture's values are 2^frac · gain(stop) times the pixels'.
    let inverse_gain = low_gain_inverse(src.kernel, stop);
    let shift = 16 + src.frac;
    let round = 1i64 << (shift - 1);
    for plane in &mut planes {
        inverse(src.kernel, plane, w, h, src.levels, stop);
    }
    let mut out = vec![0u8; pw * ph * src.channels];
    let mut coded = [0i32; 4];
    for y in 0..ph {
        for x in 0..pw {
            for (c, plane) in planes.iter().enumerate() {
                let v = plane[y * w + x] as i64;
                // Divide by gain · 2^frac, rounding to nearest (halves up).
                coded[c] = ((v * inverse_gain + round) >> shift) as i32;
            }
            let o = (y * pw + x) * src.channels;
            layout_values(&coded[..src.channels], &mut out[o..o + src.channels]);
        }
    }
    let _ = centred;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_round_trips() {
        for px in [
            [0u8, 0, 0, 0],
            [255, 255, 255, 255],
            [255, 0, 128, 7],
            [3, 200, 77, 128],
        ] {
            for n in 1..=4 {
                let c = coded_channels(&px[..n]);
                let mut back = [0u8; 4];
                layout_values(&c[..n], &mut back[..n]);
                assert_eq!(back[..n], px[..n], "{n} channels");
            }
        }
    }

    #[test]
    fn the_low_gain_table_is_the_transform_s() {
        // Transform a constant and read the low-low band.
        for levels in 0..=7u32 {
            let n = 8usize << levels.max(1);
            let mut p = vec![1 << 12; n * n];
            super::super::wavelet::forward(Kernel::Integer97, &mut p, n, n, levels);
            let got = p[0] as f64 / 4096.0;
            let want = 65536.0 / LOW_GAIN_97_INVERSE[levels as usize] as f64;
            assert!((got / want - 1.0).abs() < 4e-3, "{levels}: {got} vs {want}");
        }
    }
}
