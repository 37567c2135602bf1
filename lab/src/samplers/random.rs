//! Random sampling: independent uniform sites.

use super::{clamp_open, unit_pair};
use crate::samplers::Sampler;
use qcs::sites::Point;

/// Independent uniform sites in `[0, W) × [0, H)`, seeded ([`super::SplitMix64`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Random {
    /// Seed of the sequence.
    pub seed: u64,
}

impl Sampler for Random {
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point> {
        if width == 0 || height == 0 {
            return Vec::new();
        }
        let (w, h) = (width as f64, height as f64);
        (0..count as u64)
            .map(|n| {
                let (u, v) = unit_pair(self.seed, 1, n);
                [clamp_open(u * w, w), clamp_open(v * h, h)]
            })
            .collect()
    }
    fn name(&self) -> &'static str {
        "random"
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn random_sites_are_progressive() {
        use crate::samplers::{Random, Sampler};
        let long = Random { seed: 9 }.sites(10, 10, 50);
        assert_eq!(&long[..20], &Random { seed: 9 }.sites(10, 10, 20)[..]);
    }
}
