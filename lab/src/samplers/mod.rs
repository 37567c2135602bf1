//! The paper's five other sampling strategies (periodic, jittered, Halton,
//! random, farthest point), each a progressive [`Sampler`].
//!
//! Every sampler here returns sites in `[0, W) × [0, H)` and has the prefix
//! property: `sites(w, h, n)` is the first `n` entries of `sites(w, h, m)` for
//! every `m ≥ n`. The stochastic ones are seeded and use the crate's own
//! [`SplitMix64`] generator, so a sequence is the same on every platform and with
//! every version of the dependencies.
//!
//! ```
//! use qcs_lab::samplers::{self, Sampler};
//! let samplers = samplers::all(7);
//! assert_eq!(samplers.len(), 5);
//! for s in &samplers {
//!     let sites = s.sites(40, 30, 100);
//!     assert_eq!(sites.len(), 100);
//!     assert!(sites.iter().all(|p| p[0] >= 0.0 && p[0] < 40.0 && p[1] >= 0.0 && p[1] < 30.0));
//! }
//! ```

mod farthest;
mod halton;
mod jittered;
mod periodic;
mod random;

pub use farthest::FarthestPoint;
pub use halton::Halton;
pub use jittered::Jittered;
pub use periodic::Periodic;
pub use random::Random;

use qcs::sites::{Point, Quasicrystal};

/// A progressive sampling strategy: the first `count` sites of its sequence.
///
/// Every prefix of the returned sequence is the sequence for a smaller count.
pub trait Sampler {
    /// The first `count` sites for a `width × height` image, in progressive order.
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point>;
    /// A short lower-case name (`quasicrystal`, `periodic`, …).
    fn name(&self) -> &'static str;
}

/// The format's own sequence: the quasicrystal's sites in their progressive order.
impl Sampler for Quasicrystal {
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point> {
        match Quasicrystal::new(width, height) {
            Ok(q) => q.first(count).into_iter().map(|s| s.pos).collect(),
            Err(_) => Vec::new(),
        }
    }

    fn name(&self) -> &'static str {
        "quasicrystal"
    }
}

/// The five strategies in the paper's order after the quasicrystal:
/// periodic, farthest point, jittered, quasirandom (Halton), random.
///
/// The stochastic ones (farthest point's first site, jittered, random) use `seed`.
pub fn all(seed: u64) -> Vec<Box<dyn Sampler + Send + Sync>> {
    vec![
        Box::new(Periodic),
        Box::new(FarthestPoint { seed }),
        Box::new(Jittered { seed }),
        Box::new(Halton),
        Box::new(Random { seed }),
    ]
}

/// SplitMix64 (Steele, Lea, Flood 2014): a tiny, fast, well-mixed 64-bit generator.
///
/// Used instead of a crate so that seeded sequences never change with a dependency
/// upgrade. [`SplitMix64::at`] gives random access (`seed`, index) → value, which is
/// how the samplers keep the prefix property trivially.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl SplitMix64 {
    /// A generator whose first output is `SplitMix64::at(seed, 0)`.
    pub fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix(self.state)
    }
    /// A uniform value in `[0, 1)` with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        to_unit(self.next_u64())
    }
    /// The `index`-th output of the generator seeded with `seed` (random access).
    pub fn at(seed: u64, index: u64) -> u64 {
        mix(seed.wrapping_add(GOLDEN_GAMMA.wrapping_mul(index.wrapping_add(1))))
    }
}

/// 53 high bits → `[0, 1)`.
pub(crate) fn to_unit(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Two independent uniforms in `[0,1)` for item `index` of stream `stream` under `seed`.
pub(crate) fn unit_pair(seed: u64, stream: u64, index: u64) -> (f64, f64) {
    let base = mix(seed ^ mix(stream.wrapping_add(0x5151)));
    let mut g = SplitMix64::new(base ^ mix(index));
    (g.next_f64(), g.next_f64())
}

/// Clamps `v` into `[0, limit)` (for `limit > 0`).
pub(crate) fn clamp_open(v: f64, limit: f64) -> f64 {
    let top = limit - limit * f64::EPSILON * 4.0;
    v.max(0.0).min(top)
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn all_lists_the_five_strategies() {
        let names: Vec<_> = crate::samplers::all(0).iter().map(|s| s.name()).collect();
        assert_eq!(
            names,
            ["periodic", "farthest", "jittered", "halton", "random"]
        );
    }

    #[test]
    fn splitmix_streams_are_addressable() {
        use crate::samplers::SplitMix64;
        let mut a = SplitMix64::new(1);
        let first = a.next_u64();
        assert_eq!(first, SplitMix64::at(1, 0));
        assert!((0.0..1.0).contains(&a.next_f64()));
    }
}
