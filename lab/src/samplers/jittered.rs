//! Jittered sampling: the periodic sequence, each site displaced within its cell.

use super::{clamp_open, periodic, unit_pair};
use crate::samplers::Sampler;
use qcs::sites::Point;

/// The [`Periodic`](super::Periodic) sequence with each site moved to a uniformly
/// random point of its own level's cell ("full random displacement").
///
/// A site of level `k` owns the cell of size `(W−1)/2^k × (H−1)/2^k` centred on its
/// lattice point; the cell is clipped to the image `[0, W) × [0, H)` and the site
/// is drawn uniformly in what remains (so the corner sites of level 0 move within
/// the quarter of their cell that lies inside the image). The displacement of
/// site `n` depends only on `seed` and `n`, so the prefix property holds.
#[derive(Clone, Copy, Debug, Default)]
pub struct Jittered {
    /// Seed of the displacements.
    pub seed: u64,
}

impl Sampler for Jittered {
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point> {
        if width == 0 || height == 0 {
            return Vec::new();
        }
        let (w, h) = (width as f64, height as f64);
        let mut out = Vec::with_capacity(count.min(1 << 26));
        let mut index = 0u64;
        periodic::for_each_index(count, |level, i, j| {
            let c = periodic::position(width, height, level, i, j);
            let n = (1u64 << level) as f64;
            let (cw, ch) = ((w - 1.0) / n, (h - 1.0) / n);
            let x0 = (c[0] - cw / 2.0).max(0.0);
            let x1 = (c[0] + cw / 2.0).min(w);
            let y0 = (c[1] - ch / 2.0).max(0.0);
            let y1 = (c[1] + ch / 2.0).min(h);
            let (u, v) = unit_pair(self.seed, 2, index);
            index += 1;
            out.push([
                clamp_open(x0 + u * (x1 - x0), w),
                clamp_open(y0 + v * (y1 - y0), h),
            ]);
        });
        out
    }
    fn name(&self) -> &'static str {
        "jittered"
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn jittered_sites_follow_the_seed() {
        use crate::samplers::{Jittered, Sampler};
        let a = Jittered { seed: 3 }.sites(64, 48, 300);
        assert_eq!(a, Jittered { seed: 3 }.sites(64, 48, 300));
        assert_ne!(a, Jittered { seed: 4 }.sites(64, 48, 300));
    }
}
