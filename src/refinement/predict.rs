//! The low-low band's prediction from the levels' samples (spec/refinement.md §4).
//!
//! Each coefficient of the low-low band is about the mean of the picture over a square of
//! 2^L × 2^L pixels. The levels already say much of it: coefficient (i, j) is predicted as the
//! predictive coding would predict a sample at the centre of pixel (i·2^L, j·2^L) from all the
//! samples of the levels (its [`NEIGHBOURS`] nearest, inverse squared distance weights, in
//! exact integer arithmetic, on the samples' coded values with F fraction bits), times the band's
//! gain on a constant.

use crate::coding::predictive::{weighted_mean, weights, NEIGHBOURS, POS_ONE};

use super::picture::coded_channels;
use super::wavelet::{low_size, splits, Kernel};

/// The gain on a constant of n one-dimensional splits of the integer 9/7, 16.16 fixed point,
/// for n = 0..=30: round(2^16 · g^n), g = 1.2298828545 (see
/// [`super::picture::LOW_GAIN_97_INVERSE`]).
const GAIN_97: [i64; 31] = [
    65536, 80602, 99131, 121919, 149946, 184416, 226810, 278950, 343076, 421943, 518940, 638236,
    784955, 965403, 1187333, 1460280, 1795973, 2208837, 2716611, 3341113, 4109177, 5053807,
    6215590, 7644448, 9401775, 11563082, 14221236, 17490455, 21511211, 26456269, 32538112,
];

fn low_gain(kernel: Kernel, w: usize, h: usize, levels: u32) -> i64 {
    match kernel {
        Kernel::Reversible53 => 1 << 16,
        Kernel::Integer97 => GAIN_97[splits(w, h, levels) as usize],
    }
}

/// Points in a uniform grid, for exact nearest-neighbour queries.
struct NearestGrid {
    cell: i64,
    gw: i64,
    gh: i64,
    start: Vec<u32>,
    entries: Vec<([i64; 2], u32)>,
}

impl NearestGrid {
    fn new(points: &[[i64; 2]], width: i64, height: i64) -> NearestGrid {
        let area = (width as i128 * height as i128).max(1);
        let cell = (((2 * area) / points.len().max(1) as i128) as f64).sqrt() as i64;
        let cell = cell.max(POS_ONE);
        let gw = width / cell + 1;
        let gh = height / cell + 1;
        let key = |p: [i64; 2]| {
            let x = (p[0] / cell).clamp(0, gw - 1);
            let y = (p[1] / cell).clamp(0, gh - 1);
            (y * gw + x) as usize
        };
        let cells = (gw * gh) as usize;
        let mut start = vec![0u32; cells + 1];
        for &p in points {
            start[key(p) + 1] += 1;
        }
        for k in 0..cells {
            start[k + 1] += start[k];
        }
        let mut fill = start[..cells].to_vec();
        let mut entries = vec![([0, 0], 0); points.len()];
        for (i, &p) in points.iter().enumerate() {
            let k = key(p);
            entries[fill[k] as usize] = (p, i as u32);
            fill[k] += 1;
        }
        NearestGrid {
            cell,
            gw,
            gh,
            start,
            entries,
        }
    }

    /// The up to [`NEIGHBOURS`] points nearest to `q`, as (squared distance, index), sorted
    /// (ties by the smaller index).
    fn nearest(&self, q: [i64; 2]) -> Vec<(i64, u32)> {
        let mut top: Vec<(i64, u32)> = Vec::with_capacity(NEIGHBOURS + 1);
        let cx = (q[0] / self.cell).clamp(0, self.gw - 1);
        let cy = (q[1] / self.cell).clamp(0, self.gh - 1);
        let gap = |v: i64, c: i64| (c * self.cell - v).max(v - (c + 1) * self.cell).max(0);
        for r in 0.. {
            // A point outside the rings visited is at least this far (the border cells hold
            // the points clamped into them, so only rings still inside the grid bound them).
            let mut any = false;
            for y in (cy - r).max(0)..=(cy + r).min(self.gh - 1) {
                for x in (cx - r).max(0)..=(cx + r).min(self.gw - 1) {
                    if (x - cx).abs() != r && (y - cy).abs() != r {
                        continue;
                    }
                    any = true;
                    let c = (y * self.gw + x) as usize;
                    for &(p, i) in &self.entries[self.start[c] as usize..self.start[c + 1] as usize]
                    {
                        let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
                        let e = (dx * dx + dy * dy, i);
                        if top.len() < NEIGHBOURS || e < top[NEIGHBOURS - 1] {
                            let k = top.partition_point(|&t| t < e);
                            top.insert(k, e);
                            top.truncate(NEIGHBOURS);
                        }
                    }
                }
            }
            if !any {
                break;
            }
            // Ring r + 1 and beyond lie at least `reach` away from q.
            let reach = {
                let gx = gap(q[0], cx - r - 1).min(gap(q[0], cx + r + 1));
                let gy = gap(q[1], cy - r - 1).min(gap(q[1], cy + r + 1));
                let clamp_x = cx - r - 1 < 0 && cx + r + 1 >= self.gw;
                let clamp_y = cy - r - 1 < 0 && cy + r + 1 >= self.gh;
                match (clamp_x, clamp_y) {
                    (true, true) => i64::MAX,
                    (true, false) => gy,
                    (false, true) => gx,
                    (false, false) => gx.min(gy),
                }
            };
            if top.len() == NEIGHBOURS && reach != i64::MAX && reach * reach > top[NEIGHBOURS - 1].0
            {
                break;
            }
            if reach == i64::MAX {
                break;
            }
        }
        top
    }
}

/// The predicted low-low band of each coded channel (row-major, `low_size` wide), from the
/// levels' samples: their fixed positions (1/256 px, spec/format.md *Positions*) and decoded
/// colours (layout order, `channels` bytes each).
#[allow(clippy::too_many_arguments)]
pub(crate) fn low_band(
    positions: &[[i64; 2]],
    colours: &[u8],
    channels: usize,
    width: usize,
    height: usize,
    kernel: Kernel,
    levels: u32,
    frac: u32,
) -> Vec<Vec<i32>> {
    let (lw, lh) = low_size(width, height, levels);
    let mut out = vec![Vec::with_capacity(lw * lh); channels];
    let values: Vec<[i32; 4]> = colours
        .chunks_exact(channels)
        .map(|c| coded_channels(c, frac))
        .collect();
    let grid = NearestGrid::new(positions, width as i64 * POS_ONE, height as i64 * POS_ONE);
    let gain = low_gain(kernel, width, height, levels);
    let step = (1i64 << levels) * POS_ONE;
    for j in 0..lh as i64 {
        for i in 0..lw as i64 {
            let q = [i * step + POS_ONE / 2, j * step + POS_ONE / 2];
            let near = grid.nearest(q);
            let (w, wsum) = weights(&near);
            for (c, plane) in out.iter_mut().enumerate() {
                let p = if near.is_empty() {
                    0
                } else {
                    let acc: i64 = near
                        .iter()
                        .zip(&w)
                        .map(|(&(_, k), &wk)| wk * values[k as usize][c] as i64)
                        .sum();
                    weighted_mean(acc, wsum)
                };
                plane.push((p as i64 * gain + (1 << 15)).div_euclid(1 << 16) as i32);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(points: &[[i64; 2]], q: [i64; 2]) -> Vec<(i64, u32)> {
        let mut all: Vec<(i64, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| ((p[0] - q[0]).pow(2) + (p[1] - q[1]).pow(2), i as u32))
            .collect();
        all.sort();
        all.truncate(NEIGHBOURS);
        all
    }

    #[test]
    fn the_grid_finds_the_nearest_points() {
        let mut s = 17u64;
        let mut next = |m: i64| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as i64) % m
        };
        for n in [1usize, 2, 3, 4, 5, 20, 300] {
            let (w, h) = (97 * 256, 41 * 256);
            // Some points outside the image and some repeated, as mirror-free samples can't
            // be, to test the clamped border cells and the ties.
            let mut pts: Vec<[i64; 2]> = (0..n).map(|_| [next(w + 2000) - 1000, next(h)]).collect();
            if n > 3 {
                pts[2] = pts[1];
            }
            let grid = NearestGrid::new(&pts, w, h);
            for _ in 0..200 {
                let q = [next(w), next(h)];
                assert_eq!(grid.nearest(q), brute(&pts, q), "n {n} q {q:?}");
            }
        }
    }

    #[test]
    fn a_flat_image_is_predicted() {
        // Every sample the same colour: every coefficient of a transformed flat picture, up to
        // the rounding of the lifting steps (a few per mille for the 9/7).
        let (w, h, levels) = (50usize, 30usize, 3u32);
        let positions: Vec<[i64; 2]> = (0..40)
            .map(|k| [(k * 311 % 50) * 256 + 77, (k * 7 % 30) * 256 + 3])
            .collect();
        let colours: Vec<u8> = (0..40).flat_map(|_| [200u8, 40, 90]).collect();
        for kernel in [Kernel::Reversible53, Kernel::Integer97] {
            let pred = low_band(&positions, &colours, 3, w, h, kernel, levels, 2);
            let mut planes =
                super::super::picture::to_planes(&vec![[200u8, 40, 90]; w * h].concat(), 3, 2);
            for p in &mut planes {
                super::super::wavelet::forward(kernel, p, w, h, levels);
            }
            let (lw, lh) = low_size(w, h, levels);
            for c in 0..3 {
                for y in 0..lh {
                    for x in 0..lw {
                        let got = pred[c][y * lw + x];
                        let want = planes[c][y * w + x];
                        let tolerance = 2 + want.abs() / 200;
                        assert!(
                            (got - want).abs() <= tolerance,
                            "{kernel:?} c{c} ({x},{y}): {got} vs {want}"
                        );
                    }
                }
            }
        }
    }
}
