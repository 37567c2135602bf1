//! Integer lifting wavelets (spec/refinement.md §2).
//!
//! Two kernels, both computed in integers only, so that every decoder inverts them to the same
//! values:
//!
//! * [`Kernel::Reversible53`], JPEG 2000's reversible 5/3: exactly invertible, for lossless
//!   files;
//! * [`Kernel::Integer97`], the CDF 9/7 lifting steps with 12-bit fixed-point weights and
//!   rounding after each step (also exactly invertible), without the final scaling of the
//!   low and high bands: the coder orders bit-planes by each band's weight instead.
//!
//! A level splits a `w × h` region into its low half `⌈w/2⌉` (even samples) and high half
//! `⌊w/2⌋` (odd samples), rows first, then columns, and the next level transforms the low-low
//! quarter again (the Mallat layout). The signal is extended symmetrically at both ends
//! (whole-sample symmetry), which for these symmetric lifting steps means a neighbour index
//! past either end is clamped to the last valid one.

/// A lifting kernel: the format's [`Wavelet`](crate::container::Wavelet).
pub(crate) use crate::container::Wavelet as Kernel;

/// The 9/7 lifting weights, times 4096 and rounded: α, β, γ, δ.
pub(crate) const W97: [i32; 4] = [-6497, -217, 3616, 1817];

#[derive(Clone, Copy)]
enum Step {
    /// 5/3 predict: `d −= (a + b) >> 1`.
    Predict53,
    /// 5/3 update: `s += (a + b + 2) >> 2`.
    Update53,
    /// 9/7: `x += (c·(a + b) + 2048) >> 12`.
    Fixed(i32),
}

impl Step {
    /// The step's term, computed in 64 bits and taken modulo 2^32: exact for every file an
    /// encoder writes, and defined (wrapping) for the rest.
    #[inline(always)]
    fn delta(self, a: i32, b: i32) -> i32 {
        let sum = a as i64 + b as i64;
        (match self {
            Step::Predict53 => -(sum >> 1),
            Step::Update53 => (sum + 2) >> 2,
            Step::Fixed(c) => (c as i64 * sum + 2048) >> 12,
        }) as i32
    }
}

/// The lifting steps of a kernel, in forward order; `true` for an update step (low band
/// from its high neighbours), `false` for a predict step (high band from its low neighbours).
fn steps(kernel: Kernel) -> &'static [(bool, Step)] {
    match kernel {
        Kernel::Reversible53 => &[(false, Step::Predict53), (true, Step::Update53)],
        Kernel::Integer97 => &[
            (false, Step::Fixed(W97[0])),
            (true, Step::Fixed(W97[1])),
            (false, Step::Fixed(W97[2])),
            (true, Step::Fixed(W97[3])),
        ],
    }
}

/// Applies one lifting step to the two halves of a 1-D signal: `s` (low, `⌈n/2⌉`) and `d`
/// (high, `⌊n/2⌋ ≥ 1`), adding (`sign = 1`) or subtracting (`-1`) the step's delta.
#[inline(always)]
fn lift_1d(update: bool, step: Step, s: &mut [i32], d: &mut [i32], sign: i32, small: bool) {
    let (nl, nh) = (s.len(), d.len());
    let one =
        |t: &mut i32, a: i32, b: i32| *t = t.wrapping_add(sign.wrapping_mul(step.delta(a, b)));
    if update {
        // s[i] ±= f(d[i − 1], d[i]), indices clamped to 0..nh.
        one(&mut s[0], d[0], d[0]);
        let m = nh.min(nl);
        lift_row(step, &mut s[1..m], &d[..m - 1], &d[1..m], sign, small);
        for i in m.max(1)..nl {
            one(&mut s[i], d[i - 1], d[nh - 1]);
        }
    } else {
        // d[i] ±= f(s[i], s[i + 1]), indices clamped to 0..nl.
        let m = nh.min(nl - 1);
        lift_row(step, &mut d[..m], &s[..m], &s[1..m + 1], sign, small);
        for i in m..nh {
            one(&mut d[i], s[i], s[nl - 1]);
        }
    }
}

/// `target[k] ±= f(a[k], b[k])` for one step, over rows of a strip. Rows whose values and
/// sums stay within ±2^18 (every file an encoder writes, but for the low band of very deep
/// transforms) are done in 32 bits, which the compiler vectorises; for the others that is
/// undone and the exact 64-bit step taken. `small`: the signal the steps run on was
/// [`small`], so every row is within those bounds and none is checked.
#[inline(always)]
fn lift_row(step: Step, target: &mut [i32], a: &[i32], b: &[i32], sign: i32, small: bool) {
    // A loop each way: multiplying by the sign cost a vector multiply a value.
    if sign > 0 {
        lift_row_signed::<true>(step, target, a, b, small)
    } else {
        lift_row_signed::<false>(step, target, a, b, small)
    }
}

/// [`lift_row`] adding (`ADD`) or subtracting.
#[inline(always)]
fn lift_row_signed<const ADD: bool>(
    step: Step,
    target: &mut [i32],
    a: &[i32],
    b: &[i32],
    small: bool,
) {
    let put = |t: &mut i32, v: i32| {
        *t = if ADD {
            t.wrapping_add(v)
        } else {
            t.wrapping_sub(v)
        }
    };
    if let Step::Fixed(c) = step {
        // |c| < 2^13, so c·(a + b) + 2048 stays within 32 bits when |a + b| ≤ 2^18.
        let fast = |x: i32, y: i32| c.wrapping_mul(x.wrapping_add(y)).wrapping_add(2048) >> 12;
        if small {
            for ((t, &x), &y) in target.iter_mut().zip(a).zip(b) {
                put(t, fast(x, y));
            }
            return;
        }
        let mut bits = 0u32;
        for ((t, &x), &y) in target.iter_mut().zip(a).zip(b) {
            let s = x.wrapping_add(y);
            // At least |s| − 1 and |x| − 1: under 2^18 if both are at most 2^18.
            bits |= (s ^ (s >> 31)) as u32 | (x ^ (x >> 31)) as u32;
            put(t, fast(x, y));
        }
        if bits < 1 << 18 {
            return;
        }
        for ((t, &x), &y) in target.iter_mut().zip(a).zip(b) {
            put(t, fast(x, y).wrapping_neg());
        }
    }
    for ((t, &x), &y) in target.iter_mut().zip(a).zip(b) {
        put(t, step.delta(x, y));
    }
}

/// The same step on whole rows: `s_rows` and `d_rows` hold `nl` and `nh` rows of `width`
/// values each.
fn lift_rows(
    update: bool,
    step: Step,
    s_rows: &mut [i32],
    d_rows: &mut [i32],
    width: usize,
    sign: i32,
    small: bool,
) {
    let nl = s_rows.len() / width;
    let nh = d_rows.len() / width;
    if update {
        for i in 0..nl {
            let (ia, ib) = (i.saturating_sub(1), i.min(nh - 1));
            let target = &mut s_rows[i * width..(i + 1) * width];
            let a = &d_rows[ia * width..(ia + 1) * width];
            let b = &d_rows[ib * width..(ib + 1) * width];
            lift_row(step, target, a, b, sign, small);
        }
    } else {
        for i in 0..nh {
            let ib = (i + 1).min(nl - 1);
            let target = &mut d_rows[i * width..(i + 1) * width];
            let a = &s_rows[i * width..(i + 1) * width];
            let b = &s_rows[ib * width..(ib + 1) * width];
            lift_row(step, target, a, b, sign, small);
        }
    }
}

/// Whether every value of a signal is below 2^12 in magnitude. Then none of the 9/7's
/// four lifting steps, forward or inverse, takes a value past 2^17: a step adds at most
/// 2·|c|/4096 times the largest magnitude of the other half, plus 1 for its rounding, and
/// over the four steps in either order the largest magnitude grows less than 12-fold
/// (α: |c| = 6497, β: 217, γ: 3616, δ: 1817). So each step's sums stay within 2^18.
fn small(v: &[i32]) -> bool {
    v.iter().fold(0u32, |b, &x| b | (x ^ (x >> 31)) as u32) < 1 << 12
}

/// Columns are lifted in strips this wide, so that a strip stays in the cache.
const STRIP: usize = 64;

/// Forward transform of one row in place: the result is the low half then the high half.
fn forward_row(kernel: Kernel, row: &mut [i32], tmp: &mut Vec<i32>) {
    let n = row.len();
    if n < 2 {
        return;
    }
    let nl = n.div_ceil(2);
    tmp.clear();
    tmp.resize(n, 0);
    let (s, d) = tmp.split_at_mut(nl);
    // Even samples to the low half, odd ones to the high half, a pair at a time.
    for ((a, b), pair) in s.iter_mut().zip(d.iter_mut()).zip(row.chunks_exact(2)) {
        *a = pair[0];
        *b = pair[1];
    }
    if n % 2 == 1 {
        s[nl - 1] = row[n - 1];
    }
    let small = small(tmp);
    let (s, d) = tmp.split_at_mut(nl);
    for &(update, step) in steps(kernel) {
        lift_1d(update, step, s, d, 1, small);
    }
    row.copy_from_slice(tmp);
}

/// Inverse of [`forward_row`].
pub(crate) fn inverse_row(kernel: Kernel, row: &mut [i32], tmp: &mut Vec<i32>) {
    tmp.clear();
    tmp.extend_from_slice(row);
    lift_row_back(kernel, tmp, row);
}

/// Inverse of [`forward_row`] of `row` into `out` (as long).
pub(crate) fn inverse_row_into(kernel: Kernel, row: &[i32], tmp: &mut Vec<i32>, out: &mut [i32]) {
    tmp.clear();
    tmp.extend_from_slice(row);
    lift_row_back(kernel, tmp, out);
}

/// The inverse lifting of a row's low and high halves (`t`, clobbered), interleaved into
/// `out`.
#[inline(always)]
fn lift_row_back(kernel: Kernel, t: &mut [i32], out: &mut [i32]) {
    let n = t.len();
    if n < 2 {
        return out.copy_from_slice(t);
    }
    let small = small(t);
    let (s, d) = t.split_at_mut(n.div_ceil(2));
    for &(update, step) in steps(kernel).iter().rev() {
        lift_1d(update, step, s, d, -1, small);
    }
    let (pairs, last) = out.split_at_mut(2 * d.len());
    for ((o, &a), &b) in pairs.chunks_exact_mut(2).zip(&*s).zip(&*d) {
        o[0] = a;
        o[1] = b;
    }
    if let Some(o) = last.first_mut() {
        *o = s[s.len() - 1];
    }
}

/// Forward transform of the columns of the region `width × rows` (stride `stride`) in place,
/// a strip of columns at a time.
fn forward_columns(
    kernel: Kernel,
    plane: &mut [i32],
    stride: usize,
    width: usize,
    rows: usize,
    tmp: &mut Vec<i32>,
) {
    if rows < 2 {
        return;
    }
    let nl = rows.div_ceil(2);
    for x0 in (0..width).step_by(STRIP) {
        let sw = STRIP.min(width - x0);
        tmp.clear();
        for y in (0..rows).step_by(2).chain((1..rows).step_by(2)) {
            tmp.extend_from_slice(&plane[y * stride + x0..y * stride + x0 + sw]);
        }
        let small = small(tmp);
        let (s, d) = tmp.split_at_mut(nl * sw);
        for &(update, step) in steps(kernel) {
            lift_rows(update, step, s, d, sw, 1, small);
        }
        for (y, row) in tmp.chunks_exact(sw).enumerate() {
            plane[y * stride + x0..y * stride + x0 + sw].copy_from_slice(row);
        }
    }
}

/// Inverse of [`forward_columns`].
fn inverse_columns(
    kernel: Kernel,
    plane: &mut [i32],
    stride: usize,
    width: usize,
    rows: usize,
    tmp: &mut Vec<i32>,
) {
    if rows < 2 {
        return;
    }
    let nl = rows.div_ceil(2);
    for x0 in (0..width).step_by(STRIP) {
        let sw = STRIP.min(width - x0);
        tmp.clear();
        for y in 0..rows {
            tmp.extend_from_slice(&plane[y * stride + x0..y * stride + x0 + sw]);
        }
        let (s, d) = tmp.split_at_mut(nl * sw);
        inverse_columns_window(kernel, s, d, sw);
        for (k, row) in tmp.chunks_exact(sw).enumerate() {
            let y = if k < nl { 2 * k } else { 2 * (k - nl) + 1 };
            plane[y * stride + x0..y * stride + x0 + sw].copy_from_slice(row);
        }
    }
}

/// Rows of each half that a window of one column split's inverse gets wrong next to an edge
/// that is not the plane's (the steps read the other half's neighbours, clamped there):
/// the 9/7's four steps spoil two, the 5/3's two one.
pub(crate) const WINDOW_MARGIN: usize = 2;

/// The inverse of one level's column split over a window of rows: `s` the low half's rows
/// `lo..`, `d` the high half's rows `lo..` (`width` values each). Where the window ends with
/// the plane's rows the result is exact; within [`WINDOW_MARGIN`] rows of another edge it is
/// not. The values are those of the whole plane's inverse (each step is the same per value).
pub(crate) fn inverse_columns_window(kernel: Kernel, s: &mut [i32], d: &mut [i32], width: usize) {
    if d.is_empty() {
        return;
    }
    let small = small(s) && small(d);
    for &(update, step) in steps(kernel).iter().rev() {
        lift_rows(update, step, s, d, width, -1, small);
    }
}

/// The one-dimensional splits `levels` levels make of a `w × h` plane: a side of 1 is left
/// as it is (a line shorter than 2 has no high half), so it adds no gain.
pub(crate) fn splits(w: usize, h: usize, levels: u32) -> u32 {
    (0..levels)
        .map(|l| {
            let (cw, ch) = low_size(w, h, l);
            (cw >= 2) as u32 + (ch >= 2) as u32
        })
        .sum()
}

/// The size of the low-low region after `levels` levels of a `w × h` region.
pub(crate) fn low_size(w: usize, h: usize, levels: u32) -> (usize, usize) {
    let mut s = (w, h);
    for _ in 0..levels {
        s = (s.0.div_ceil(2), s.1.div_ceil(2));
    }
    s
}

/// Forward transform, `levels` levels, of a `w × h` plane (row stride `w`) in place.
pub(crate) fn forward(kernel: Kernel, plane: &mut [i32], w: usize, h: usize, levels: u32) {
    let mut tmp = Vec::new();
    for l in 0..levels {
        let (cw, ch) = low_size(w, h, l);
        for y in 0..ch {
            forward_row(kernel, &mut plane[y * w..y * w + cw], &mut tmp);
        }
        forward_columns(kernel, plane, w, cw, ch, &mut tmp);
    }
}

/// Inverse transform of levels `levels − 1` down to `stop` (0 for the whole picture): the
/// top-left `low_size(w, h, stop)` region then holds the low-low band of level `stop`.
pub(crate) fn inverse(
    kernel: Kernel,
    plane: &mut [i32],
    w: usize,
    h: usize,
    levels: u32,
    stop: u32,
) {
    let mut tmp = Vec::new();
    for l in (stop..levels).rev() {
        let (cw, ch) = low_size(w, h, l);
        inverse_columns(kernel, plane, w, cw, ch, &mut tmp);
        for y in 0..ch {
            inverse_row(kernel, &mut plane[y * w..y * w + cw], &mut tmp);
        }
    }
}

/// [`inverse`] of every level but the rows of level 0, which are left to
/// [`inverse_row_into`] (a caller that reads each row once makes it there).
pub(crate) fn inverse_but_rows(kernel: Kernel, plane: &mut [i32], w: usize, h: usize, levels: u32) {
    if levels > 0 {
        inverse(kernel, plane, w, h, levels, 1);
        inverse_columns(kernel, plane, w, w, h, &mut Vec::new());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn lcg(s: &mut u64) -> i32 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*s >> 33) % 1021) as i32 - 510
    }

    #[test]
    fn inverse_undoes_forward_for_every_small_size() {
        let mut seed = 1;
        for kernel in [Kernel::Reversible53, Kernel::Integer97] {
            for w in 1..=13 {
                for h in 1..=9 {
                    for levels in 0..=4 {
                        let orig: Vec<i32> = (0..w * h).map(|_| lcg(&mut seed)).collect();
                        let mut p = orig.clone();
                        forward(kernel, &mut p, w, h, levels);
                        let mut rows = p.clone();
                        inverse(kernel, &mut p, w, h, levels, 0);
                        assert_eq!(p, orig, "{kernel:?} {w}x{h} levels {levels}");
                        // The same with the last rows made one by one elsewhere.
                        inverse_but_rows(kernel, &mut rows, w, h, levels);
                        if levels > 0 {
                            let mut tmp = Vec::new();
                            let mut out = vec![0; w * h];
                            for (row, o) in rows.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
                                inverse_row_into(kernel, row, &mut tmp, o);
                            }
                            rows = out;
                        }
                        assert_eq!(rows, orig, "{kernel:?} {w}x{h} levels {levels}, by rows");
                    }
                }
            }
        }
    }

    /// Signals below 2^12, the extremes alternating in every pattern of signs that makes the
    /// steps grow most: the unchecked 32-bit steps give what the checked ones give, forward
    /// and inverse.
    #[test]
    fn small_signals_need_no_check() {
        let mut seed = 7;
        for n in [2usize, 3, 8, 33] {
            for pattern in 0..64u32 {
                let v: Vec<i32> = (0..n)
                    .map(|k| match (pattern >> (k % 6)) & 1 {
                        _ if pattern == 63 => lcg(&mut seed) * 8,
                        0 => 4095,
                        _ => -4095,
                    })
                    .collect();
                assert!(small(&v));
                for sign in [1, -1] {
                    let run = |small: bool| {
                        let mut t = v.clone();
                        let (s, d) = t.split_at_mut(n.div_ceil(2));
                        let order = steps(Kernel::Integer97);
                        let order: Vec<_> = if sign == 1 {
                            order.to_vec()
                        } else {
                            order.iter().rev().copied().collect()
                        };
                        for (update, step) in order {
                            lift_1d(update, step, s, d, sign, small);
                        }
                        t
                    };
                    assert_eq!(
                        run(true),
                        run(false),
                        "n {n} pattern {pattern:06b} sign {sign}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_constant_lands_in_the_low_band_only() {
        // 5/3 keeps a constant's value in the low band (DC gain 1) and leaves zero details;
        // the 9/7 steps without their final scaling multiply it by about 1.23 per dimension.
        let (w, h) = (37, 22);
        for (kernel, gain) in [(Kernel::Reversible53, 1.0), (Kernel::Integer97, 1.2302f64)] {
            let mut p = vec![400; w * h];
            forward(kernel, &mut p, w, h, 2);
            let (lw, lh) = low_size(w, h, 2);
            for y in 0..h {
                for x in 0..w {
                    let v = p[y * w + x];
                    if x < lw && y < lh {
                        let want = 400.0 * gain.powi(4);
                        assert!((v as f64 - want).abs() <= 3.0, "{kernel:?} {v} vs {want}");
                    } else {
                        assert!(v.abs() <= 1, "{kernel:?} detail {v} at ({x}, {y})");
                    }
                }
            }
        }
    }

    #[test]
    fn a_partial_inverse_leaves_the_coarser_picture() {
        // Stopping the inverse at level 1 leaves exactly the level-1 low band of the forward
        // transform: what a thumbnail decoder draws from.
        let (w, h) = (29, 17);
        let mut seed = 5;
        let orig: Vec<i32> = (0..w * h).map(|_| lcg(&mut seed)).collect();
        for kernel in [Kernel::Reversible53, Kernel::Integer97] {
            let mut one = orig.clone();
            forward(kernel, &mut one, w, h, 1);
            let mut three = orig.clone();
            forward(kernel, &mut three, w, h, 3);
            inverse(kernel, &mut three, w, h, 3, 1);
            let (lw, lh) = low_size(w, h, 1);
            for y in 0..lh {
                assert_eq!(one[y * w..y * w + lw], three[y * w..y * w + lw]);
            }
        }
    }

    proptest! {
        #[test]
        fn round_trip_of_arbitrary_planes(
            w in 1usize..40, h in 1usize..40, levels in 0u32..6, seed in any::<u64>(), big in any::<bool>()
        ) {
            let mut s = seed;
            let scale = if big { 64 } else { 1 };
            let orig: Vec<i32> = (0..w * h).map(|_| lcg(&mut s) * scale).collect();
            for kernel in [Kernel::Reversible53, Kernel::Integer97] {
                let mut p = orig.clone();
                forward(kernel, &mut p, w, h, levels);
                inverse(kernel, &mut p, w, h, levels, 0);
                prop_assert_eq!(&p, &orig);
            }
        }
    }
}
