//! # qcs — progressive images on quasicrystal sample sites
//!
//! An image is stored as colours sampled at the sites of a 2D cut-and-project
//! quasicrystal (golden ratio, roots of H2). The sites are never stored: they
//! follow from the image size and a few header numbers by exact integer
//! arithmetic, in a progressive order, so every prefix of a `.qcs` file is a
//! uniformly spread subset of the samples and decodes to a whole picture.
//!
//! The pipeline, one module per stage:
//! [`lattice`] (exact arithmetic in Z\[τ\] and Z\[ζ\]) →
//! [`sites`] (the progressive site sequence and the other samplers) →
//! [`coding`] (colours ↔ bits) → [`container`] (bytes on disk) →
//! [`reconstruction`] (samples → picture at any size) and [`styles`].
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod coding;
pub mod container;
mod decoder;
mod encoder;
pub mod error;
pub mod eval;
#[cfg(any(fuzzing, feature = "fuzzing"))]
#[doc(hidden)]
pub mod fuzzing;
mod integration;
pub mod lattice;
pub mod limits;
mod pull;
pub mod reconstruction;
mod refinement;
pub mod sampling;
pub mod sites;
pub mod styles;
#[cfg(test)]
mod testing;

pub use decoder::{
    decode, thumbnail_samples, DecodeOptions, DecodedImage, Picture, RawDecoder, StreamDecoder,
};
pub use encoder::{encode, encode_to, EncodeOptions, Target, DEFAULT_QUALITY};
pub use error::{Error, Result};
pub use integration::{register_image_hooks, QcsImageDecoder};
pub use limits::Limits;
pub use pull::{Cadence, Previews};
pub use reconstruction::Method;

/// The README's code examples, run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
