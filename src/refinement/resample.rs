//! Exact resampling of a picture to another size (spec/refinement.md §8). The source is the picture of transform level k, whose sample i
//! (along an axis) stands at the centre of image pixel i·2^k. At level 0, a smaller output
//! averages the source over each output pixel's footprint (a box filter with exact overlaps);
//! otherwise each output pixel centre interpolates linearly between the two nearest source
//! samples. Weights are integers, the result is rounded once.

use super::wavelet::{inverse_row, low_size, Kernel};

/// Per output pixel along one axis: the source indices and integer weights (their sum is
/// the pixel's divisor).
pub(crate) struct Axis {
    taps: Vec<Vec<(usize, u64)>>,
}

impl Axis {
    /// `src` samples of level `level` of an image side of `full` pixels, to `dst` pixels.
    ///
    /// Sample i stands for the cell of 2^level pixels centred at the centre of pixel
    /// i·2^level. A smaller output (`dst < src`) weighs each sample by the overlap of its cell
    /// with the output pixel (a box filter); otherwise the output pixel's centre interpolates
    /// linearly between the two nearest samples' centres (clamped to the first and last).
    pub(crate) fn new(src: usize, dst: usize, full: usize, level: u32) -> Axis {
        let half = 1u64 << level; // a cell is 2·half long in units of half a pixel
        if dst < src {
            // Coordinates in units of 1/(2·dst) pixel: output pixel j is [2j·full, 2(j+1)·full),
            // sample i's cell [(2^(k+1)·i + 1 − 2^k)·dst, (2^(k+1)·i + 1 + 2^k)·dst).
            let d = dst as u64;
            let taps = (0..dst as u64)
                .map(|j| {
                    let (a, b) = (2 * j * full as u64, 2 * (j + 1) * full as u64);
                    // Cells meeting [a, b): i from ⌈(a/d − 1 − half)/(2·half)⌉ on.
                    let lo = (a / d).saturating_sub(1 + half) / (2 * half);
                    (lo as usize..src)
                        .map(|i| {
                            let c0 = ((2 * half * i as u64 + 1) as i64 - half as i64) * d as i64;
                            let c1 = (2 * half * i as u64 + 1 + half) * d;
                            let from = (a as i64).max(c0);
                            let to = b.min(c1) as i64;
                            (i, (to - from).max(0) as u64, c0 >= b as i64)
                        })
                        .take_while(|&(_, _, past)| !past)
                        .filter(|&(_, w, _)| w > 0)
                        .map(|(i, w, _)| (i, w))
                        .collect()
                })
                .collect();
            return Axis { taps };
        }
        // Output centre j is at image coordinate (j + ½)·full/dst; sample i at i·2^k + ½: in
        // samples, t = ((2j + 1)·full − dst) / (2·dst·2^k), clamped to the samples.
        let d = (2 * dst as u64) << level;
        let last = (src as u64 - 1) * d;
        let taps = (0..dst as u64)
            .map(|j| {
                let num = ((2 * j + 1) * full as u64)
                    .saturating_sub(dst as u64)
                    .min(last);
                let x = (num / d) as usize;
                let frac = num % d;
                let mut t = vec![(x, d - frac)];
                if frac > 0 {
                    t.push((x + 1, frac));
                }
                t
            })
            .collect();
        Axis { taps }
    }

    /// The taps as windows of one length `k` over `src` samples: per output pixel, the first
    /// sample of its window, and all the weights, `k` per pixel (zero where the pixel has no
    /// tap). A window stays within the samples.
    fn windows(&self, src: usize) -> (Vec<usize>, usize, Vec<u64>) {
        let span = |t: &[(usize, u64)]| t.last().map_or(0, |l| l.0 + 1 - t[0].0);
        let k = self
            .taps
            .iter()
            .map(|t| span(t))
            .max()
            .unwrap_or(0)
            .min(src);
        let mut weights = vec![0; self.taps.len() * k];
        let starts = (self.taps.iter().zip(weights.chunks_exact_mut(k.max(1))))
            .map(|(t, w)| {
                let start = t.first().map_or(0, |f| f.0).min(src - k);
                for &(x, wx) in t {
                    w[x - start] = wx;
                }
                start
            })
            .collect();
        (starts, k, weights)
    }
}

/// The picture synthesised from a low band alone (the `from` finer levels' bands taken as
/// zero) along one axis of `full` pixels and averaged over `dst` output pixels (an [`Axis`]
/// at level 0), folded into taps over the low band's samples: what a thumbnail draws without
/// making the image-size lines. Linear but for the lifting's roundings, which the taps leave
/// out (they move an output by at most two coefficient units).
pub(crate) struct Folded {
    /// Per output pixel: the first of the low band's samples it weighs, and their weights
    /// in 1/2^FOLD_BITS.
    taps: Vec<(usize, Vec<i64>)>,
}

/// Fraction bits of a [`Folded`] weight.
const FOLD_BITS: u32 = 24;

impl Folded {
    pub(crate) fn new(kernel: Kernel, full: usize, from: u32, dst: usize) -> Folded {
        // Low-band samples this far apart are synthesised in one line: each one's response
        // (about 3 samples to either side, however many levels) meets no other's, so every
        // image-size sample belongs to the impulse nearest to it.
        const APART: usize = 16;
        const SCALE: i32 = 1 << 16;
        let n = low_size(full, 1, from).0;
        let axis = Axis::new(full, dst, full, 0);
        let mut weights: Vec<Vec<(usize, f64)>> = vec![Vec::new(); dst];
        let (mut line, mut tmp) = (vec![0; full], Vec::new());
        for r in 0..APART.min(n) {
            line.fill(0);
            (line[r..n].iter_mut().step_by(APART)).for_each(|v| *v = SCALE);
            for l in (0..from).rev() {
                inverse_row(kernel, &mut line[..low_size(full, 1, l).0], &mut tmp);
            }
            let last = r + (n - 1 - r) / APART * APART;
            for (taps, weights) in axis.taps.iter().zip(&mut weights) {
                let total = taps.iter().map(|t| t.1).sum::<u64>() as f64 * SCALE as f64;
                for &(i, w) in taps.iter().filter(|&&(i, _)| line[i] != 0) {
                    // Image-size sample i stands at low-band sample i / 2^from.
                    let at = (i + (1 << from >> 1)) >> from;
                    let k = (at + APART / 2).saturating_sub(r) / APART;
                    let j = (r + k * APART).min(last);
                    let add = w as f64 * line[i] as f64 / total;
                    match weights.iter_mut().find(|t| t.0 == j) {
                        Some(t) => t.1 += add,
                        None => weights.push((j, add)),
                    }
                }
            }
        }
        let one = (1u64 << FOLD_BITS) as f64;
        let taps = (weights.into_iter())
            .map(|ws| {
                let (first, last) = ws.iter().fold((n, 0), |(a, b), t| (a.min(t.0), b.max(t.0)));
                let mut t = vec![0; (last + 1).saturating_sub(first)];
                for (j, w) in ws {
                    t[j - first] = (w * one).round() as i64;
                }
                (first.min(n - 1), t)
            })
            .collect();
        Folded { taps }
    }

    /// One line of the low band (`n` samples) to `dst` output values, rounded to nearest.
    pub(crate) fn line(&self, src: &[i32], out: &mut [i32]) {
        for (o, (first, weights)) in out.iter_mut().zip(&self.taps) {
            let taps = src[*first..].iter().zip(weights);
            let sum: i64 = taps.map(|(&v, &w)| w * v as i64).sum();
            *o = ((sum + (1 << (FOLD_BITS - 1))) >> FOLD_BITS) as i32;
        }
    }
}

/// The picture of transform level `level` (`sw × sh` samples, `channels` interleaved) of a
/// `width × height` image, resampled to `dw × dh`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn resample(
    pixels: &[u8],
    sw: usize,
    sh: usize,
    channels: usize,
    level: u32,
    (width, height): (usize, usize),
    dw: usize,
    dh: usize,
) -> Vec<u8> {
    if level == 0 && (sw, sh) == (dw, dh) {
        return pixels.to_vec();
    }
    let ax = Axis::new(sw, dw, width, level);
    let ay = Axis::new(sh, dh, height, level);
    // A source row's sums under an output column's taps fit 32 bits at any size a decode
    // draws (their weights sum to twice the image side at most); the 64-bit path is for the
    // rest.
    let weights = |a: &Axis| {
        a.taps
            .iter()
            .map(|t| t.iter().map(|t| t.1).sum::<u64>())
            .max()
    };
    let narrow = weights(&ax).unwrap_or(0) * 255 <= u32::MAX as u64
        && weights(&ay).unwrap_or(0) <= u32::MAX as u64;
    match (channels, narrow) {
        (1, true) => by_axes::<1, u32>(pixels, sw, &ax, &ay),
        (2, true) => by_axes::<2, u32>(pixels, sw, &ax, &ay),
        (3, true) => by_axes::<3, u32>(pixels, sw, &ax, &ay),
        (_, true) => by_axes::<4, u32>(pixels, sw, &ax, &ay),
        (1, false) => by_axes::<1, u64>(pixels, sw, &ax, &ay),
        (2, false) => by_axes::<2, u64>(pixels, sw, &ax, &ay),
        (3, false) => by_axes::<3, u64>(pixels, sw, &ax, &ay),
        (_, false) => by_axes::<4, u64>(pixels, sw, &ax, &ay),
    }
}

/// A source row's sum under an output column's taps, as [`by_axes`] keeps it (and makes it:
/// its weights and products are of the same width).
trait RowSum:
    Copy + Default + From<u8> + std::ops::Add<Output = Self> + std::ops::Mul<Output = Self>
{
    fn of(v: u64) -> Self;
    /// `w · self`, for a weight `w` that fits the type too.
    fn times(self, w: u64) -> u64;
}

impl RowSum for u32 {
    #[inline(always)]
    fn of(v: u64) -> u32 {
        v as u32
    }
    #[inline(always)]
    fn times(self, w: u64) -> u64 {
        // Both factors 32-bit: one widening multiply, which vectorises.
        (w as u32 as u64) * self as u64
    }
}

impl RowSum for u64 {
    #[inline(always)]
    fn of(v: u64) -> u64 {
        v
    }
    #[inline(always)]
    fn times(self, w: u64) -> u64 {
        w * self
    }
}

/// [`resample`] of `C`-channel pixels (`sw` wide) along the two axes' taps, a source row's
/// sums kept as `S`.
fn by_axes<const C: usize, S: RowSum>(pixels: &[u8], sw: usize, ax: &Axis, ay: &Axis) -> Vec<u8> {
    let (c, dw, dh) = (C, ax.taps.len(), ay.taps.len());
    let mut out = vec![0u8; dw * dh * c];
    // One axis at a time, exactly: a source row's sums under each output column's taps
    // (unrounded), then those rows' sums under the output row's taps, rounded once: the same
    // sums as the products of the two taps, at a fraction of the work. Output rows take
    // source rows in increasing order, neighbours sharing some: each row's sums are made
    // once, into a ring that holds an output row's worth of them and the next one's.
    let ring = ay.taps.iter().map(Vec::len).max().unwrap_or(0) + 1;
    let mut sums = vec![S::default(); ring * dw * c];
    let mut held = vec![usize::MAX; ring];
    let mut acc = vec![0u64; dw * c];
    let x_total: Vec<u64> = ax
        .taps
        .iter()
        .map(|t| t.iter().map(|t| t.1).sum())
        .collect();
    let (starts, span, x_weights) = ax.windows(sw);
    let x_weights: Vec<S> = x_weights.into_iter().map(S::of).collect();
    let mut by = Divisor::new(1);
    for (ty, out) in ay.taps.iter().zip(out.chunks_exact_mut(dw * c)) {
        for (i, &(y, wy)) in ty.iter().enumerate() {
            let row = &mut sums[(y % ring) * dw * c..][..dw * c];
            if held[y % ring] != y {
                held[y % ring] = y;
                let src = &pixels[y * sw * c..(y + 1) * sw * c];
                // Windows of a known length unroll (a smaller output has 2 to 5 taps a
                // pixel up to a fourth of the size, a larger one 2).
                let mut sum_row = |k| row_sums::<C, S>(src, k, &starts, &x_weights, row);
                match span {
                    0 | 1 => sum_row(1),
                    2 => sum_row(2),
                    3 => sum_row(3),
                    4 => sum_row(4),
                    5 => sum_row(5),
                    k => sum_row(k),
                }
            }
            // The first row's products are written, the others added.
            let row = &*row;
            if i == 0 {
                acc.iter_mut().zip(row).for_each(|(a, &r)| *a = r.times(wy));
            } else {
                acc.iter_mut()
                    .zip(row)
                    .for_each(|(a, &r)| *a += r.times(wy));
            }
        }
        let y_total: u64 = ty.iter().map(|t| t.1).sum();
        for ((o, a), &xt) in (out.chunks_exact_mut(c).zip(acc.chunks_exact(c))).zip(&x_total) {
            let total = y_total * xt;
            // Every pixel's taps weigh the same at level 0 (its footprint, or the distance
            // between two samples): the divisor is made once.
            if 2 * total != by.d {
                by = Divisor::new(2 * total);
            }
            for (o, &a) in o.iter_mut().zip(a) {
                *o = by.quotient(2 * a + total) as u8;
            }
        }
    }
    out
}

/// Division by `d` as a multiplication by its reciprocal and a correction: exact, and a
/// few times faster than a 64-bit division.
struct Divisor {
    d: u64,
    /// ⌊(2^64 − 1) / d⌋.
    m: u64,
}

impl Divisor {
    fn new(d: u64) -> Divisor {
        Divisor { d, m: u64::MAX / d }
    }

    /// ⌊n / d⌋.
    #[inline(always)]
    fn quotient(&self, n: u64) -> u64 {
        // q is at most 2 below the quotient: m·d > 2^64 − 1 − d, so n·m/2^64 > n/d − 2.
        let mut q = ((n as u128 * self.m as u128) >> 64) as u64;
        let mut r = n - q * self.d;
        while r >= self.d {
            q += 1;
            r -= self.d;
        }
        q
    }
}

/// A source row's sums under each output pixel's window of `k` weights (`starts` and
/// `weights` from [`Axis::windows`]), into `row`. Inlined where `k` is a constant, so that
/// its loop unrolls.
#[inline(always)]
fn row_sums<const C: usize, S: RowSum>(
    src: &[u8],
    k: usize,
    starts: &[usize],
    weights: &[S],
    row: &mut [S],
) {
    let windows = starts.iter().zip(weights.chunks_exact(k));
    for ((&x, w), sums) in windows.zip(row.chunks_exact_mut(C)) {
        let mut s = [S::default(); C];
        for (px, &w) in src[x * C..][..k * C].chunks_exact(C).zip(w) {
            let px: &[u8; C] = px.try_into().expect("C channels");
            for (a, &v) in s.iter_mut().zip(px) {
                *a = *a + w * S::from(v);
            }
        }
        sums.copy_from_slice(&s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spec's rule as written (§8): each output pixel the rounded mean under the products
    /// of the two axes' weights.
    fn by_products(pixels: &[u8], sw: usize, channels: usize, ax: &Axis, ay: &Axis) -> Vec<u8> {
        let mut out = Vec::new();
        for ty in &ay.taps {
            for tx in &ax.taps {
                for k in 0..channels {
                    let (mut a, mut total) = (0u64, 0u64);
                    for &(y, wy) in ty {
                        for &(x, wx) in tx {
                            a += wx * wy * pixels[(y * sw + x) * channels + k] as u64;
                            total += wx * wy;
                        }
                    }
                    out.push(((2 * a + total) / (2 * total)) as u8);
                }
            }
        }
        out
    }

    #[test]
    fn one_axis_at_a_time_is_the_products_rule() {
        let mut next = crate::testing::xorshift(5);
        for (sw, sh, c, level, dw, dh) in [
            (13, 7, 3, 0, 5, 3),
            (13, 7, 1, 0, 40, 2),
            (13, 7, 4, 2, 20, 11),
            (100, 60, 3, 0, 7, 90),
            (33, 20, 2, 1, 33, 20),
            (1, 1, 3, 0, 9, 4),
            // Windows of 5 and of 1 sample, and weights past 32-bit sums (the 64-bit path).
            (10, 4, 3, 0, 2, 1),
            (4, 3, 3, 1, 4, 3),
            (3, 2, 1, 14, 600, 3),
        ] {
            let px: Vec<u8> = (0..sw * sh * c).map(|_| next() as u8).collect();
            let full = (sw << level, sh << level);
            assert_eq!(
                resample(&px, sw, sh, c, level, full, dw, dh),
                by_products(
                    &px,
                    sw,
                    c,
                    &Axis::new(sw, dw, full.0, level),
                    &Axis::new(sh, dh, full.1, level)
                ),
                "{sw}x{sh}x{c} level {level} to {dw}x{dh}"
            );
        }
    }

    #[test]
    fn divisor_quotients_are_exact() {
        let mut next = crate::testing::xorshift(9);
        for d in (1..300).chain([1 << 32, u64::MAX / 3, u64::MAX]) {
            let by = Divisor::new(d);
            for n in [
                0,
                1,
                d - 1,
                d,
                d.saturating_add(1),
                u64::MAX,
                u64::MAX - 1,
                next(),
                next() >> 20,
            ] {
                assert_eq!(by.quotient(n), n / d, "{n} / {d}");
            }
        }
    }

    #[test]
    fn halving_averages_pairs() {
        // 10 20 30 41 over 50 60 70 80: (10 + 20 + 50 + 60) / 4 = 35, (30 + 41 + 70 + 80) / 4
        // = 55.25.
        let src = [10u8, 20, 30, 41, 50, 60, 70, 80];
        assert_eq!(resample(&src, 4, 2, 1, 0, (4, 2), 2, 1), vec![35, 55]);
    }

    #[test]
    fn a_constant_stays_constant_at_any_size() {
        let src = vec![77u8; 13 * 7 * 3];
        for (dw, dh) in [(1, 1), (5, 3), (13, 7), (20, 11), (40, 2)] {
            assert!(
                resample(&src, 13, 7, 3, 0, (13, 7), dw, dh)
                    .iter()
                    .all(|&v| v == 77),
                "{dw}x{dh}"
            );
            assert!(
                resample(&src, 13, 7, 3, 2, (50, 28), dw, dh)
                    .iter()
                    .all(|&v| v == 77),
                "{dw}x{dh} from level 2"
            );
        }
    }

    #[test]
    fn enlarging_interpolates_between_centres() {
        // 2 pixels to 4: centres at 0.25 and 0.75 of the way → clamped ends, then 1/4, 3/4.
        let out = resample(&[0u8, 100], 2, 1, 1, 0, (2, 1), 4, 1);
        assert_eq!(out, vec![0, 25, 75, 100]);
    }

    #[test]
    fn a_coarser_level_is_read_at_its_sample_positions() {
        // Level 1 of an 8-pixel side: samples at the centres of pixels 0, 2, 4, 6. Four output
        // pixels have their centres at those of pixels 0.5, 2.5, 4.5, 6.5: a quarter of the
        // way from a sample to the next (the last clamped).
        let out = resample(&[0u8, 40, 80, 120], 4, 1, 1, 1, (8, 1), 4, 1);
        assert_eq!(out, vec![10, 50, 90, 120]);
    }

    /// The folded taps draw what synthesising the image-size line and averaging it do, to
    /// within two units (the lifting's roundings; a quarter of a pixel level at the
    /// encoder's 3 fraction bits), at the edges too.
    #[test]
    fn folded_taps_average_the_synthesised_line() {
        let mut seed = 7u64;
        for kernel in [Kernel::Integer97, Kernel::Reversible53] {
            for (full, from, dst) in [(4000, 2, 500), (651, 1, 100), (97, 3, 5), (33, 2, 4)] {
                let n = low_size(full, 1, from).0;
                let row: Vec<i32> = (0..n)
                    .map(|_| {
                        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
                        ((seed >> 40) % 40000) as i32 - 20000
                    })
                    .collect();
                let mut line = row.clone();
                line.resize(full, 0);
                let mut tmp = Vec::new();
                for l in (0..from).rev() {
                    inverse_row(kernel, &mut line[..low_size(full, 1, l).0], &mut tmp);
                }
                let axis = Axis::new(full, dst, full, 0);
                let mut got = vec![0; dst];
                Folded::new(kernel, full, from, dst).line(&row, &mut got);
                for (o, taps) in axis.taps.iter().enumerate() {
                    let total: u64 = taps.iter().map(|t| t.1).sum();
                    let sum: f64 = taps.iter().map(|&(i, w)| w as f64 * line[i] as f64).sum();
                    let want = sum / total as f64;
                    assert!(
                        (got[o] as f64 - want).abs() <= 2.0,
                        "{kernel:?} {full} from {from} to {dst}, output {o}: {} vs {want}",
                        got[o]
                    );
                }
            }
        }
    }

    #[test]
    fn thirds_weigh_overlaps() {
        // 3 pixels to 2: output 0 covers source 0 and half of 1.
        let out = resample(&[0u8, 90, 180], 3, 1, 1, 0, (3, 1), 2, 1);
        assert_eq!(out, vec![30, 150]);
    }
}
