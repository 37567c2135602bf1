//! Exact resampling of a picture to another size (spec/reconstruction.md, *The refined
//! picture at other sizes*): along each axis, a smaller output averages the source over each
//! output pixel's footprint (a box filter with exact overlaps), a larger one interpolates
//! linearly between source pixel centres. Weights are integers, the result is rounded once.

/// Per output pixel along one axis: the source indices and integer weights, and their sum.
struct Axis {
    taps: Vec<Vec<(usize, u64)>>,
    total: u64,
}

impl Axis {
    fn new(src: usize, dst: usize) -> Axis {
        if dst <= src {
            // Output pixel i covers [i·src, (i+1)·src) and source pixel x covers
            // [x·dst, (x+1)·dst), in units of 1/(src·dst) of the image side: weights are
            // overlaps, `src` in all.
            let taps = (0..dst)
                .map(|i| {
                    let (a, b) = (i * src, (i + 1) * src);
                    (a / dst..b.div_ceil(dst))
                        .map(|x| {
                            let lo = a.max(x * dst);
                            let hi = b.min((x + 1) * dst);
                            (x, (hi - lo) as u64)
                        })
                        .filter(|&(_, w)| w > 0)
                        .collect()
                })
                .collect();
            Axis {
                taps,
                total: src as u64,
            }
        } else {
            // Output centre i maps to source coordinate u = ((2i + 1)·src − dst) / (2·dst)
            // (in pixels from the first source centre), clamped to the source centres;
            // weights are in units of 1/(2·dst).
            let d = 2 * dst as i64;
            let taps = (0..dst as i64)
                .map(|i| {
                    let num =
                        ((2 * i + 1) * src as i64 - dst as i64).clamp(0, (src as i64 - 1) * d);
                    let x = (num / d) as usize;
                    let frac = (num % d) as u64;
                    let mut t = vec![(x, d as u64 - frac)];
                    if frac > 0 {
                        t.push((x + 1, frac));
                    }
                    t
                })
                .collect();
            Axis {
                taps,
                total: d as u64,
            }
        }
    }
}

/// `pixels` (`sw × sh`, `channels` interleaved) resampled to `dw × dh`.
pub(crate) fn resample(
    pixels: &[u8],
    sw: usize,
    sh: usize,
    channels: usize,
    dw: usize,
    dh: usize,
) -> Vec<u8> {
    if (sw, sh) == (dw, dh) {
        return pixels.to_vec();
    }
    let ax = Axis::new(sw, dw);
    let ay = Axis::new(sh, dh);
    let total = ax.total * ay.total;
    let mut out = vec![0u8; dw * dh * channels];
    let mut acc = vec![0u64; channels];
    for (j, ty) in ay.taps.iter().enumerate() {
        for (i, tx) in ax.taps.iter().enumerate() {
            acc.iter_mut().for_each(|a| *a = 0);
            for &(y, wy) in ty {
                for &(x, wx) in tx {
                    let w = wx * wy;
                    let p = &pixels[(y * sw + x) * channels..(y * sw + x + 1) * channels];
                    for (a, &v) in acc.iter_mut().zip(p) {
                        *a += w * v as u64;
                    }
                }
            }
            let o = (j * dw + i) * channels;
            for (c, a) in acc.iter().enumerate() {
                out[o + c] = ((2 * a + total) / (2 * total)) as u8;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halving_averages_pairs() {
        // 10 20 30 41 over 50 60 70 80: (10 + 20 + 50 + 60) / 4 = 35, (30 + 41 + 70 + 80) / 4
        // = 55.25.
        let src = [10u8, 20, 30, 41, 50, 60, 70, 80];
        assert_eq!(resample(&src, 4, 2, 1, 2, 1), vec![35, 55]);
    }

    #[test]
    fn a_constant_stays_constant_at_any_size() {
        let src = vec![77u8; 13 * 7 * 3];
        for (dw, dh) in [(1, 1), (5, 3), (13, 7), (20, 11), (40, 2)] {
            assert!(
                resample(&src, 13, 7, 3, dw, dh).iter().all(|&v| v == 77),
                "{dw}x{dh}"
            );
        }
    }

    #[test]
    fn enlarging_interpolates_between_centres() {
        // 2 pixels to 4: centres at 0.25 and 0.75 of the way → clamped ends, then 1/4, 3/4.
        let out = resample(&[0u8, 100], 2, 1, 1, 4, 1);
        assert_eq!(out, vec![0, 25, 75, 100]);
    }

    #[test]
    fn thirds_weigh_overlaps() {
        // 3 pixels to 2: output 0 covers source 0 and half of 1.
        let out = resample(&[0u8, 90, 180], 3, 1, 1, 2, 1);
        assert_eq!(out, vec![30, 150]);
    }
}
