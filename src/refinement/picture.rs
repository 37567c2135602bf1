//! Pixels ↔ coefficient planes (spec/refinement.md §1 and §8).
//!
//! The coded channels are those of the predictive coding: grey (and alpha) as they are, R, G, B
//! as YCoCg-R (`Co = R − B`, `t = B + (Co >> 1)`, `Cg = G − t`, `Y = t + (Cg >> 1)`), then
//! alpha, all computed on the layout values times 2^F, F the file's fraction bits (lossy files
//! code a little below the integer grid, where the 9/7 steps round). Channels with the range
//! 0..=255 (grey, Y, alpha) are centred by subtracting 128·2^F. The picture undoes YCoCg-R on
//! the same fixed-point values, so the two are exact inverses at every F: a flat colour's
//! planes and picture agree, and no channel is biased by YCoCg-R's floors.

use super::bitplane::{BandState, StreamState};
use super::resample::Folded;
use super::schedule::Orient;
use super::wavelet::{
    inverse, inverse_but_rows, inverse_columns_window, inverse_row_into, low_size, splits, Kernel,
    WINDOW_MARGIN,
};
use rayon::prelude::*;
use std::borrow::Borrow;

/// Pixels (interleaved, `channels` per pixel) → one plane per coded channel, times 2^frac.
pub(crate) fn to_planes(pixels: &[u8], channels: usize, frac: u32) -> Vec<Vec<i32>> {
    let n = pixels.len() / channels;
    let mut planes: Vec<Vec<i32>> = (0..channels).map(|_| Vec::with_capacity(n)).collect();
    for px in pixels.chunks_exact(channels) {
        let coded = coded_channels(px, frac);
        for (c, plane) in planes.iter_mut().enumerate() {
            plane.push(coded[c]);
        }
    }
    planes
}

/// One pixel's coded channel values (centred, with `f` fraction bits), from its layout
/// channel values.
pub(crate) fn coded_channels(px: &[u8], f: u32) -> [i32; 4] {
    let v = |k: usize| (px[k] as i32) << f;
    let centre = 128 << f;
    let mut out = [0; 4];
    if px.len() >= 3 {
        let (r, g, b) = (v(0), v(1), v(2));
        let co = r - b;
        let t = b + (co >> 1);
        let cg = g - t;
        out[0] = t + (cg >> 1) - centre;
        out[1] = co;
        out[2] = cg;
        if px.len() == 4 {
            out[3] = v(3) - centre;
        }
    } else {
        for (k, o) in out.iter_mut().take(px.len()).enumerate() {
            *o = v(k) - centre;
        }
    }
    out
}

/// Coded channel values (centred, with `f` fraction bits) → a pixel's layout values: YCoCg-R
/// undone on the fixed-point values, doubled first when `f ≥ 1` so that its floors are exact
/// halves, then each layout channel rounded to nearest (halves to even) and clamped to
/// 0..=255 (spec/refinement.md §8). Undone so, a lossy picture has no bias: the floors of
/// YCoCg-R, or rounding halves up, would each add about a tenth of a level to the mean.
#[inline]
fn layout_values(coded: &[i32], out: &mut [u8], f: u32) {
    let (d, s) = doubling(f);
    let (below, odd) = rounding(s);
    let (below, odd) = (below as i64, odd as i64);
    let level = |v: i64| ((v + below + ((v >> s) & odd)) >> s).clamp(0, 255) as u8;
    let centre = 128i64 << s;
    let coded: [i64; 4] = std::array::from_fn(|c| (coded.get(c).copied().unwrap_or(0) as i64) << d);
    if out.len() >= 3 {
        let t = coded[0] + centre - (coded[2] >> 1);
        let g = coded[2] + t;
        let b = t - (coded[1] >> 1);
        let r = b + coded[1];
        out[0] = level(r);
        out[1] = level(g);
        out[2] = level(b);
        if out.len() == 4 {
            out[3] = level(coded[3] + centre);
        }
    } else {
        for (o, &v) in out.iter_mut().zip(&coded) {
            *o = level(v + centre);
        }
    }
}

/// The doubling of the picture's inverse YCoCg-R for `f` fraction bits: the shift `d` of the
/// coded values (1 when `f ≥ 1`) and the fraction bits `s = f + d` of the result.
fn doubling(f: u32) -> (u32, u32) {
    let d = (f != 0) as u32;
    (d, f + d)
}

/// The terms of `v / 2^s` rounded to nearest, halves to the even neighbour, as
/// `(v + below + ((v >> s) & odd)) >> s`: `below = 2^(s−1) − 1` and `odd = 1` for s ≥ 1,
/// both 0 for s = 0 (`v` itself). Branch-free, so that a run of pixels vectorises.
fn rounding(s: u32) -> (i32, i32) {
    let odd = (s != 0) as i32;
    (((1 << s) >> 1) - odd, odd)
}

/// The inverse of the gain on a constant of n one-dimensional splits of the integer 9/7,
/// 16.16 fixed point, for n = 0..=30: round(2^16 / g^n) with g = 1.2298828545 the gain of the
/// four steps (with their rounded weights) on a constant.
pub(crate) const LOW_GAIN_97_INVERSE: [i64; 31] = [
    65536, 53286, 43326, 35228, 28643, 23290, 18936, 15397, 12519, 10179, 8276, 6729, 5472, 4449,
    3617, 2941, 2391, 1944, 1581, 1285, 1045, 850, 691, 562, 457, 371, 302, 246, 200, 162, 132,
];

/// `LOW_GAIN_97_INVERSE` for `kernel` and the low-low band of `levels` levels of a `w × h`
/// plane (the 5/3 keeps a constant as it is).
pub(crate) fn low_gain_inverse(kernel: Kernel, w: usize, h: usize, levels: u32) -> i64 {
    match kernel {
        Kernel::Reversible53 => 1 << 16,
        Kernel::Integer97 => LOW_GAIN_97_INVERSE[splits(w, h, levels) as usize],
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
    draw(src, stop, bands_by_channel(src, streams))
}

/// [`picture`], taking the band states out of the streams and freeing each channel's as
/// soon as its plane is made (a one-shot decode's last step: the states and the planes are
/// not all held at once).
pub(crate) fn picture_releasing(
    src: &Source,
    streams: &mut [Option<&mut StreamState>],
    stop: u32,
) -> Vec<u8> {
    let mut bands: Vec<Vec<BandState>> = (0..src.channels).map(|_| Vec::new()).collect();
    for st in streams.iter_mut().flatten() {
        let channels: Vec<usize> = (0..st.bands.len()).map(|k| st.channel_of(k)).collect();
        for (b, c) in std::mem::take(&mut st.bands).into_iter().zip(channels) {
            bands[c].push(b);
        }
    }
    draw(src, stop, bands)
}

/// Each channel's bands in `streams`.
fn bands_by_channel<'a>(
    src: &Source,
    streams: &[Option<&'a StreamState>],
) -> Vec<Vec<&'a BandState>> {
    let mut bands = vec![Vec::new(); src.channels];
    for st in streams.iter().flatten() {
        for (k, b) in st.bands.iter().enumerate() {
            bands[st.channel_of(k)].push(b);
        }
    }
    bands
}

/// Coded channel `c` before the inverse transform, `w × h` (the low-low band of level
/// `stop`, which holds every band of the coarser levels): the prediction plus `bands`, the
/// channel's (those outside the region are left out), each dropped once taken. The plane
/// is written as the bands are taken (the low-low band added to the prediction, the others
/// written in place), so that its memory grows as theirs is freed.
fn channel_plane<B: Borrow<BandState>>(
    src: &Source,
    c: usize,
    bands: Vec<B>,
    w: usize,
    h: usize,
) -> Vec<i32> {
    let mut plane = vec![0i32; w * h];
    let (lw, lh) = low_size(src.width, src.height, src.levels);
    let pred = &src.prediction[c];
    for y in 0..lh {
        plane[y * w..y * w + lw].copy_from_slice(&pred[y * lw..(y + 1) * lw]);
    }
    for b in bands {
        let b = b.borrow();
        let band = &b.band;
        if band.x0 + band.w > w || band.y0 + band.h > h {
            continue;
        }
        let add = band.orient == Orient::LowLow;
        for y in 0..band.h {
            let row = (band.y0 + y) * w + band.x0;
            b.row_values(y, &mut plane[row..row + band.w], add);
        }
    }
    plane
}

/// The picture at level `stop` from each channel's bands: at the image's size, by strips
/// ([`draw_by_strips`]); at a coarser level, from whole planes.
fn draw<B: Borrow<BandState> + Send + Sync>(
    src: &Source,
    stop: u32,
    bands: Vec<Vec<B>>,
) -> Vec<u8> {
    if stop == 0 && src.levels > 0 {
        return draw_by_strips(src, bands);
    }
    draw_planes(src, stop, bands)
}

/// The picture at level `stop` from each channel's bands, each channel's whole plane made
/// first (the channels in parallel).
pub(crate) fn draw_planes<B: Borrow<BandState> + Send>(
    src: &Source,
    stop: u32,
    bands: Vec<Vec<B>>,
) -> Vec<u8> {
    let stop = stop.min(src.levels);
    let (w, h) = low_size(src.width, src.height, stop);
    // The low-low band of level `stop` is an image of its own, of levels − stop levels.
    let levels = src.levels - stop;
    let planes: Vec<Vec<i32>> = (bands.into_par_iter().enumerate())
        .map(|(c, bands)| {
            let mut p = channel_plane(src, c, bands, w, h);
            inverse_but_rows(src.kernel, &mut p, w, h, levels);
            p
        })
        .collect();
    interleave(src, stop, &planes, w, (levels > 0).then_some(src.kernel))
}

/// Picture rows drawn at a time by [`draw_by_strips`] (even, so that a strip starts with a
/// low row).
const STRIP_ROWS: usize = 32;

/// The picture at the image's size without a whole plane per channel: each channel's low-low
/// band of level 1 is made and inverse-transformed whole (a quarter of the picture), then the
/// finest level is undone a strip of rows at a time, its rows read from the band states, and
/// converted to pixels at once. The values are those of [`draw_planes`]: each strip's column
/// synthesis runs on a window [`WINDOW_MARGIN`] rows wider on each side, and keeps only the
/// rows that the window's own edges cannot reach. Strips in parallel.
fn draw_by_strips<B: Borrow<BandState> + Send + Sync>(src: &Source, bands: Vec<Vec<B>>) -> Vec<u8> {
    let (w, h) = (src.width, src.height);
    let (w1, h1) = low_size(w, h, 1);
    let within = |b: &B| {
        let b = &b.borrow().band;
        b.x0 + b.w <= w1 && b.y0 + b.h <= h1
    };
    let parts: Vec<(Vec<i32>, Vec<B>)> = (bands.into_par_iter().enumerate())
        .map(|(c, bands)| {
            let (coarse, fine): (Vec<B>, Vec<B>) = bands.into_iter().partition(within);
            let mut low = channel_plane(src, c, coarse, w1, h1);
            inverse(src.kernel, &mut low, w1, h1, src.levels - 1, 0);
            (low, fine)
        })
        .collect();
    let norm = Normalise::new(src, 0);
    let mut out = vec![0u8; w * h * src.channels];
    if w == 0 {
        return out;
    }
    match parts.len() {
        1 => strips::<1, B>(src.kernel, &parts, (w, h), norm, &mut out),
        2 => strips::<2, B>(src.kernel, &parts, (w, h), norm, &mut out),
        3 => strips::<3, B>(src.kernel, &parts, (w, h), norm, &mut out),
        _ => strips::<4, B>(src.kernel, &parts, (w, h), norm, &mut out),
    }
    out
}

/// [`draw_by_strips`]'s strips, for `N` channels, each given as its inverse-transformed
/// low-low band of level 1 and its bands of level 0.
fn strips<const N: usize, B: Borrow<BandState> + Sync>(
    kernel: Kernel,
    parts: &[(Vec<i32>, Vec<B>)],
    (w, h): (usize, usize),
    norm: Normalise,
    out: &mut [u8],
) {
    let (w1, h1) = low_size(w, h, 1);
    let (nl, nh) = (h1, h - h1);
    // Per thread: each channel's window of rows, the lifting's scratch row and the
    // synthesised rows of a picture row.
    let init = || (vec![Vec::new(); N], Vec::new(), vec![0i32; N * w]);
    let strip_bytes = STRIP_ROWS * w * N;
    (out.par_chunks_mut(strip_bytes).enumerate()).for_each_init(
        init,
        |(windows, tmp, row), (k, out)| {
            let (y0, y1) = (k * STRIP_ROWS, (k * STRIP_ROWS + STRIP_ROWS).min(h));
            // Rows a..b of each half make picture rows y0..y1; the window reaches past them.
            let (a, b) = (y0 / 2, y1.div_ceil(2));
            let lo = a.saturating_sub(WINDOW_MARGIN);
            let (s_end, d_end) = ((b + WINDOW_MARGIN).min(nl), (b + WINDOW_MARGIN).min(nh));
            let (ns, nd) = (s_end - lo, d_end.saturating_sub(lo));
            for ((low, fine), win) in parts.iter().zip(windows.iter_mut()) {
                win.resize((ns + nd) * w, 0);
                let (s, d) = win.split_at_mut(ns * w);
                for (i, r) in (lo..s_end).zip(s.chunks_exact_mut(w)) {
                    level_zero_row(r, i, Some(&low[i * w1..(i + 1) * w1]), fine);
                }
                for (i, r) in (lo..d_end).zip(d.chunks_exact_mut(w)) {
                    level_zero_row(r, h1 + i, None, fine);
                }
                inverse_columns_window(kernel, s, d, w);
            }
            for (y, out) in (y0..y1).zip(out.chunks_exact_mut(N * w)) {
                // Picture row 2i is the low half's row i, 2i + 1 the high half's.
                let at = if y % 2 == 0 {
                    y / 2 - lo
                } else {
                    ns + (y - 1) / 2 - lo
                };
                let source = |c: usize| &windows[c][at * w..(at + 1) * w];
                pixel_row::<N>(source, w, Some(kernel), norm, tmp, row, out);
            }
        },
    );
}

/// Row `r` of a channel's plane of level 0 (the Mallat layout), from `lead` (its first
/// values: the low-low band of level 1, if the row passes through it) and the bands of
/// level 0 crossing it; zero where no band was decoded.
fn level_zero_row<B: Borrow<BandState>>(
    row: &mut [i32],
    r: usize,
    lead: Option<&[i32]>,
    fine: &[B],
) {
    let crossing = || {
        (fine.iter().map(Borrow::borrow))
            .filter(move |b| (b.band.y0..b.band.y0 + b.band.h).contains(&r))
    };
    let covered = lead.map_or(0, <[i32]>::len) + crossing().map(|b| b.band.w).sum::<usize>();
    if covered < row.len() {
        row.fill(0);
    }
    if let Some(lead) = lead {
        row[..lead.len()].copy_from_slice(lead);
    }
    for b in crossing() {
        let x0 = b.band.x0;
        b.row_values(r - b.band.y0, &mut row[x0..x0 + b.band.w], false);
    }
}

/// A thumbnail of `tw × th` (informative): the picture with the bands finer than level
/// `decoded` taken as zero, averaged over each thumbnail pixel. Those bands being zero, the
/// rest of the inverse transform and the average fold into taps over the low-low band of
/// level `decoded` ([`Folded`]), applied to its rows, then to the columns of the result.
pub(crate) fn thumbnail(
    src: &Source,
    streams: &[Option<&StreamState>],
    decoded: u32,
    (tw, th): (usize, usize),
) -> Vec<u8> {
    let (w, h) = low_size(src.width, src.height, decoded);
    let fx = Folded::new(src.kernel, src.width, decoded, tw);
    let fy = Folded::new(src.kernel, src.height, decoded, th);
    let planes: Vec<Vec<i32>> = (bands_by_channel(src, streams).into_par_iter().enumerate())
        .map(|(c, bands)| {
            let mut p = channel_plane(src, c, bands, w, h);
            inverse(src.kernel, &mut p, w, h, src.levels - decoded, 0);
            let mut rows = vec![0; h * tw];
            for (row, o) in p.chunks_exact(w).zip(rows.chunks_exact_mut(tw)) {
                fx.line(row, o);
            }
            let mut columns = vec![0; tw * th];
            for (column, o) in transpose(&rows, tw)
                .chunks_exact(h)
                .zip(columns.chunks_exact_mut(th))
            {
                fy.line(column, o);
            }
            transpose(&columns, th)
        })
        .collect();
    interleave(src, 0, &planes, tw, None)
}

/// The transpose of `m`, rows of `w` values.
fn transpose(m: &[i32], w: usize) -> Vec<i32> {
    let h = m.len() / w;
    let mut t = vec![0; m.len()];
    for (y, row) in m.chunks_exact(w).enumerate() {
        for (x, &v) in row.iter().enumerate() {
            t[x * h + y] = v;
        }
    }
    t
}

/// The division of a plane of the picture of level `level` (2^frac · gain(level) times the
/// pixels') by gain, rounding to nearest (halves up): values with `frac` fraction bits, which
/// [`layout_values`] rounds to whole levels after undoing YCoCg-R.
#[derive(Clone, Copy)]
struct Normalise {
    inverse_gain: i64,
    frac: u32,
}

impl Normalise {
    fn new(src: &Source, level: u32) -> Normalise {
        Normalise {
            inverse_gain: low_gain_inverse(src.kernel, src.width, src.height, level),
            frac: src.frac,
        }
    }

    /// `out[i]` = `values[i]` divided.
    fn apply(self, values: &[i32], out: &mut [i32]) {
        if self.inverse_gain != 1 << 16 {
            let g = self.inverse_gain;
            (out.iter_mut().zip(values))
                .for_each(|(o, &v)| *o = ((v as i64 * g + (1 << 15)) >> 16) as i32);
        } else {
            out.copy_from_slice(values);
        }
    }
}

/// Pixels converted at a time: each channel's values of a run of this many pixels are
/// normalised into a buffer on the stack, then converted together.
const RUN: usize = 256;

/// Coded channel planes of rows `w` values long, of the picture of level `level` →
/// interleaved layout pixels; each row synthesised first by `rows` (the inverse transform's
/// last step, [`inverse_but_rows`]) if given. Rows in parallel.
fn interleave(
    src: &Source,
    level: u32,
    planes: &[Vec<i32>],
    w: usize,
    rows: Option<Kernel>,
) -> Vec<u8> {
    fn pixels<const N: usize>(
        planes: &[Vec<i32>],
        w: usize,
        rows: Option<Kernel>,
        norm: Normalise,
        out: &mut [u8],
    ) {
        // Per thread: the lifting's scratch row and the synthesised rows of the channels.
        let init = || {
            (
                Vec::new(),
                vec![0i32; if rows.is_some() { N * w } else { 0 }],
            )
        };
        out.par_chunks_mut(N * w)
            .enumerate()
            .for_each_init(init, |(tmp, row), (y, out)| {
                let source = |c: usize| &planes[c][y * w..(y + 1) * w];
                pixel_row::<N>(source, w, rows, norm, tmp, row, out);
            });
    }
    let norm = Normalise::new(src, level);
    let n = planes.first().map_or(0, Vec::len);
    let mut out = vec![0u8; n * planes.len()];
    if w == 0 {
        return out;
    }
    match planes.len() {
        1 => pixels::<1>(planes, w, rows, norm, &mut out),
        2 => pixels::<2>(planes, w, rows, norm, &mut out),
        3 => pixels::<3>(planes, w, rows, norm, &mut out),
        _ => pixels::<4>(planes, w, rows, norm, &mut out),
    }
    out
}

/// One picture row (`out`, `N` channels interleaved) from each channel's row of coded values
/// (`source(c)`, `w` of them): synthesised first by `rows` (into `row`) if given, then
/// normalised and converted a run of pixels at a time.
#[inline]
fn pixel_row<'a, const N: usize>(
    source: impl Fn(usize) -> &'a [i32],
    w: usize,
    rows: Option<Kernel>,
    norm: Normalise,
    tmp: &mut Vec<i32>,
    row: &mut [i32],
    out: &mut [u8],
) {
    if let Some(kernel) = rows {
        for (c, r) in row.chunks_exact_mut(w).enumerate() {
            inverse_row_into(kernel, source(c), tmp, r);
        }
    }
    let mut coded = [[0i32; RUN]; N];
    for (k, px) in out.chunks_mut(N * RUN).enumerate() {
        let (a, len) = (k * RUN, px.len() / N);
        for (c, v) in coded.iter_mut().enumerate() {
            let values = match rows {
                Some(_) => &row[c * w + a..c * w + a + len],
                None => &source(c)[a..a + len],
            };
            norm.apply(values, &mut v[..len]);
        }
        layout_run::<N>(&coded, px, norm.frac);
    }
}

/// [`layout_values`] for a run of pixels (`out.len() / N` of them), in 32 bits when every
/// value is below 2^24 in magnitude (where no step can overflow), as the compiler vectorises.
fn layout_run<const N: usize>(coded: &[[i32; RUN]; N], out: &mut [u8], f: u32) {
    let len = out.len() / N;
    let bits = coded
        .iter()
        .flat_map(|c| &c[..len])
        .fold(0u32, |b, &v| b | (v ^ (v >> 31)) as u32);
    if bits >= 1 << 24 {
        for (i, px) in out.chunks_exact_mut(N).enumerate() {
            let values: [i32; N] = std::array::from_fn(|c| coded[c][i]);
            layout_values(&values, px, f);
        }
        return;
    }
    let (d, s) = doubling(f);
    let centre = 128 << s;
    let (below, odd) = rounding(s);
    let level = |v: i32| ((v + below + ((v >> s) & odd)) >> s).clamp(0, 255) as u8;
    if N >= 3 {
        let mut rgb = [[0u8; RUN]; 3];
        for i in 0..len {
            let (y, co, cg) = (coded[0][i] << d, coded[1][i] << d, coded[2][i] << d);
            let t = y + centre - (cg >> 1);
            let b = t - (co >> 1);
            rgb[0][i] = level(b + co);
            rgb[1][i] = level(cg + t);
            rgb[2][i] = level(b);
        }
        for (i, px) in out.chunks_exact_mut(N).enumerate() {
            px[0] = rgb[0][i];
            px[1] = rgb[1][i];
            px[2] = rgb[2][i];
            if N == 4 {
                px[3] = level((coded[N - 1][i] << d) + centre);
            }
        }
    } else {
        for (i, px) in out.chunks_exact_mut(N).enumerate() {
            for (c, o) in px.iter_mut().enumerate() {
                *o = level((coded[c][i] << d) + centre);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every colour, at every fraction bit count: the coded channels and the picture's
    /// conversion back are exact inverses (for F = 1 the doubled inverse is a quarter level
    /// off, which the rounding takes back).
    #[test]
    fn colour_round_trips() {
        for f in 0..=3 {
            for rgb in 0..1u32 << 24 {
                let px = [
                    (rgb >> 16) as u8,
                    (rgb >> 8) as u8,
                    rgb as u8,
                    (rgb >> 5) as u8,
                ];
                let n = 3 + (rgb & 1) as usize;
                let c = coded_channels(&px[..n], f);
                let mut back = [0u8; 4];
                layout_values(&c[..n], &mut back[..n], f);
                assert_eq!(back[..n], px[..n], "{f} fraction bits");
            }
            for v in 0..=255u8 {
                for n in 1..=2 {
                    let px = [v, 255 - v];
                    let c = coded_channels(&px[..n], f);
                    let mut back = [0u8; 2];
                    layout_values(&c[..n], &mut back[..n], f);
                    assert_eq!(back[..n], px[..n], "{n} channels, {f} fraction bits");
                }
            }
        }
    }

    /// A lossy picture has no bias: over every fixed-point (Y, Co, Cg) of a range of whole
    /// levels, the mean of the layout values drawn minus the linear YCoCg inverse's exact
    /// values is below a hundredth of a level (rounding halves up gives +0.125 at f = 1, and
    /// YCoCg-R's floors without the doubling +0.25).
    #[test]
    fn lossy_pictures_are_not_biased() {
        for f in 1..=3u32 {
            let one = 1i32 << f;
            let (mut sum, mut n) = ([0f64; 3], 0f64);
            for y in (-20 * one)..(20 * one) {
                for co in (-9 * one)..(9 * one) {
                    for cg in (-9 * one)..(9 * one) {
                        let mut px = [0u8; 3];
                        layout_values(&[y, co, cg], &mut px, f);
                        let (y, co, cg) = (y as f64, co as f64, cg as f64);
                        let t = y + 128.0 * one as f64 - cg / 2.0;
                        let b = t - co / 2.0;
                        let exact = [b + co, cg + t, b].map(|v| v / one as f64);
                        for c in 0..3 {
                            sum[c] += px[c] as f64 - exact[c];
                        }
                        n += 1.0;
                    }
                }
            }
            for (c, s) in sum.iter().enumerate() {
                assert!(
                    (s / n).abs() < 0.01,
                    "f {f}, channel {c}: mean error {}",
                    s / n
                );
            }
        }
    }

    /// The run conversion (32-bit when it can) agrees with the per-pixel rule, near and far
    /// from the 2^24 bound and at the extremes a hostile file reaches.
    #[test]
    fn runs_convert_as_single_pixels_do() {
        fn check<const N: usize>(seed: &mut u64, scale: u32, f: u32) {
            let mut coded = [[0i32; RUN]; N];
            for c in coded.iter_mut() {
                for v in c.iter_mut() {
                    *seed = seed
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    let r = (*seed >> 32) as u32 as i32;
                    *v = if scale >= 31 { r } else { r >> (31 - scale) };
                }
            }
            let len = RUN - 3;
            let mut run = vec![0u8; N * len];
            layout_run::<N>(&coded, &mut run, f);
            for (i, px) in run.chunks_exact(N).enumerate() {
                let values: [i32; N] = std::array::from_fn(|c| coded[c][i]);
                let mut one = [0u8; N];
                layout_values(&values, &mut one, f);
                assert_eq!(px, one, "{N} channels, scale {scale}, f {f}, pixel {i}");
            }
        }
        let mut seed = 1;
        for scale in [4, 8, 9, 12, 23, 24, 25, 31] {
            for f in [0, 2] {
                check::<1>(&mut seed, scale, f);
                check::<2>(&mut seed, scale, f);
                check::<3>(&mut seed, scale, f);
                check::<4>(&mut seed, scale, f);
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
            let want = 65536.0 / LOW_GAIN_97_INVERSE[2 * levels as usize] as f64;
            assert!((got / want - 1.0).abs() < 4e-3, "{levels}: {got} vs {want}");
        }
    }
}
