//! The qcs lab: what the paper measures and draws with the codec, kept apart from it.
//!
//! - [`samplers`]: the paper's five other progressive sampling strategies (periodic,
//!   farthest point, jittered, Halton, random) and the [`Sampler`](samplers::Sampler) trait
//!   they share with the format's quasicrystal;
//! - [`styles`]: stylized renderings of a sample set (mosaic, strokes, Voronoi and Delaunay
//!   diagrams, site order, Fourier spectra, the quasicrystal's phase function);
//! - [`eval`]: the six-sampler evaluation, its PSNR tables, plots and report, which
//!   `qcs eval` runs.
//!
//! The lab builds on the codec's internals (the `internals` feature of `qcs`), which carry no
//! stability promise; nothing in the codec depends on the lab.

pub mod eval;
pub mod samplers;
pub mod styles;

pub use qcs::{Error, Result};

/// An [`Error::InvalidArgument`].
pub(crate) fn invalid(
    name: &'static str,
    value: impl std::fmt::Display,
    expected: impl Into<String>,
) -> Error {
    Error::InvalidArgument {
        name,
        value: value.to_string(),
        expected: expected.into(),
    }
}
