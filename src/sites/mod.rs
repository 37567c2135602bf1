//! Sample sites in progressive order: the quasicrystal sequence of the format.
//!
//! All sites are in source-image pixel coordinates: pixel `(i, j)` covers
//! `[i, i+1) × [j, j+1)`, so its centre is `(i + 0.5, j + 0.5)`, and every site
//! of a `W × H` image lies in `[0, W) × [0, H)`.

/// A site position in pixel coordinates (`x` right, `y` down).
pub type Point = [f64; 2];

mod quasicrystal;

pub use quasicrystal::{
    fixed_position, site_order, Frame, FrameError, Quasicrystal, Site, DENSITY, FX_ONE,
};
