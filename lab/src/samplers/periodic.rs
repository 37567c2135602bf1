//! Periodic sampling: square lattices refined level by level in scan-line order.

use crate::samplers::Sampler;
use qcs::sites::Point;

/// Square grids of `(2^k+1)²` points on pixel centres, refined level by level.
///
/// Level `k` is the lattice `x_i = 0.5 + i·(W−1)/2^k`, `y_j = 0.5 + j·(H−1)/2^k`,
/// `i, j ∈ 0..=2^k` (a square lattice stretched to `W × H` for non-square images):
/// its corners are the centres of the corner pixels. Level 0 is the 4 corners;
/// level `k ≥ 1` adds the points of its lattice that are not in level `k−1`
/// (`i` or `j` odd), in scan-line order (row `j` ascending, then `i`). So the
/// counts 4, 9, 25, …, 1089, 4225, 16641 are exactly the full 2², 3², …, 33², 65², 129²
/// grids, and any other count is a full grid plus the first rows of the next level
/// (the top of the image is refined first — the paper's "refined in scan-line order").
/// On a 1-pixel-wide or -high image the lattice collapses and sites repeat.
#[derive(Clone, Copy, Debug, Default)]
pub struct Periodic;

/// Visits the first `count` points of the periodic sequence as
/// `(level, i, j)` with lattice indices in `0..=2^level`.
pub(crate) fn for_each_index(count: usize, mut f: impl FnMut(u32, u64, u64)) {
    let mut emitted = 0usize;
    // Level 0.
    for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        if emitted == count {
            return;
        }
        f(0, i, j);
        emitted += 1;
    }
    let mut level = 1u32;
    while emitted < count && level < 62 {
        let n = 1u64 << level;
        for j in 0..=n {
            let row_odd = j % 2 == 1;
            let mut i = if row_odd { 0 } else { 1 };
            let step = if row_odd { 1 } else { 2 };
            while i <= n {
                if emitted == count {
                    return;
                }
                f(level, i, j);
                emitted += 1;
                i += step;
            }
        }
        level += 1;
    }
}

/// The position of lattice point `(i, j)` of `level` in a `w × h` image.
pub(crate) fn position(w: u32, h: u32, level: u32, i: u64, j: u64) -> Point {
    let n = (1u64 << level) as f64;
    [
        0.5 + i as f64 * (w as f64 - 1.0) / n,
        0.5 + j as f64 * (h as f64 - 1.0) / n,
    ]
}

impl Sampler for Periodic {
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point> {
        if width == 0 || height == 0 {
            return Vec::new();
        }
        let mut out = Vec::with_capacity(count.min(1 << 26));
        for_each_index(count, |level, i, j| {
            out.push(position(width, height, level, i, j))
        });
        out
    }
    fn name(&self) -> &'static str {
        "periodic"
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn periodic_sites_are_pixel_centres_on_a_square_grid() {
        use crate::samplers::{Periodic, Sampler};
        let s = Periodic.sites(33, 33, 1089);
        assert_eq!(s[0], [0.5, 0.5]);
        assert!(s.iter().all(|p| p[0].fract() == 0.5 && p[1].fract() == 0.5));
    }
}
