//! Quasirandom sampling: the Halton sequence in bases 2 and 3.

use crate::samplers::Sampler;
use qcs::sites::Point;

/// The Halton sequence, bases 2 (x) and 3 (y), indices `1…N`, scaled to `W × H`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Halton;

/// The radical inverse of `n` in `base` (digits of `n` mirrored after the point).
pub fn radical_inverse(mut n: u64, base: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let mut f = inv;
    let mut r = 0.0;
    while n > 0 {
        r += f * (n % base) as f64;
        n /= base;
        f *= inv;
    }
    r
}

impl Sampler for Halton {
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point> {
        if width == 0 || height == 0 {
            return Vec::new();
        }
        (1..=count as u64)
            .map(|i| {
                [
                    super::clamp_open(radical_inverse(i, 2) * width as f64, width as f64),
                    super::clamp_open(radical_inverse(i, 3) * height as f64, height as f64),
                ]
            })
            .collect()
    }
    fn name(&self) -> &'static str {
        "halton"
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn halton_sites_are_the_base_2_and_3_radical_inverses() {
        use crate::samplers::{Halton, Sampler};
        let s = Halton.sites(100, 90, 3);
        assert_eq!(s, vec![[50.0, 30.0], [25.0, 60.0], [75.0, 10.0]]);
    }
}
