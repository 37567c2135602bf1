//! Sample sites in progressive order: the quasicrystal sequence of the format,
//! and the paper's five other sampling strategies for evaluation.
//!
//! All sites are in source-image pixel coordinates: pixel `(i, j)` covers
//! `[i, i+1) × [j, j+1)`, so its centre is `(i + 0.5, j + 0.5)`, and every site
//! of a `W × H` image lies in `[0, W) × [0, H)`.

pub mod strategies;

/// A site position in pixel coordinates (`x` right, `y` down).
pub type Point = [f64; 2];

/// A progressive sampling strategy: the first `count` sites of its sequence.
///
/// Every prefix of the returned sequence is the sequence for a smaller count.
pub trait Sampler {
    /// The first `count` sites for a `width × height` image, in progressive order.
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point>;
    /// A short lower-case name (`quasicrystal`, `periodic`, …).
    fn name(&self) -> &'static str;
}

mod quasicrystal;

pub use quasicrystal::{
    fixed_position, site_order, Frame, FrameError, Quasicrystal, Site, DENSITY, FX_ONE,
};
