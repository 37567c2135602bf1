//! # qcs — any prefix is a picture
//!
//! qcs is a progressive image codec. A `.qcs` file starts with colours sampled at the sites of
//! a 2D cut-and-project quasicrystal (golden ratio, roots of H2), which the decoder computes
//! from the image size by exact integer arithmetic; then comes a wavelet **refinement**, coded
//! bit-plane by bit-plane over the whole frame. Every prefix of a file, from its first 32
//! bytes, decodes to a whole picture at any size, and the whole file is as faithful as the
//! encoder was asked, up to lossless. The format is specified byte by byte and pixel by pixel
//! in the repository's `spec/`.
//!
//! ## Encode
//!
//! [`encode`] takes an [`image::DynamicImage`] (grey, grey + alpha, RGB or RGBA, 8 bits) and
//! [`EncodeOptions`]; [`Target`] says what the file aims at: a quality from 0 to 100 as for
//! cjpeg (the default is [`DEFAULT_QUALITY`]), lossless, a byte size, or the quasicrystal
//! levels alone.
//!
//! ```
//! use qcs::{EncodeOptions, Target};
//! let img = image::open("tests/data/coffee-150x100.png")?;
//! let photo = qcs::encode(&img, &EncodeOptions::default())?;
//! let exact = qcs::encode(&img, &EncodeOptions { target: Target::Lossless, ..Default::default() })?;
//! let small = qcs::encode(&img, &EncodeOptions { target: Target::Size(600), ..Default::default() })?;
//! assert!(small.len() <= 600 && photo.len() < exact.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Decode a file, or any prefix of it
//!
//! [`decode`] draws what the bytes given hold, at the image's size or any other
//! ([`DecodeOptions`]). A cut file is not an error: it is a less detailed picture, and
//! [`DecodedImage::is_final`] says which one you have.
//!
//! ```
//! # let img = image::open("tests/data/coffee-150x100.png")?;
//! # let file = qcs::encode(&img, &Default::default())?;
//! let whole = qcs::decode(&file, &Default::default())?;
//! assert!(whole.is_final);
//! let first_kib = qcs::decode(&file[..1024], &qcs::DecodeOptions {
//!     size: Some((300, 200)),
//!     ..Default::default()
//! })?;
//! assert!(!first_kib.is_final);
//! assert_eq!(first_kib.image.width(), 300);
//! // A thumbnail reads only the coarse part of the refinement.
//! let thumb = qcs::decode(&file, &qcs::DecodeOptions::thumbnail(38, 25))?;
//! assert_eq!((thumb.image.width(), thumb.image.height()), (38, 25));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Stream
//!
//! A [`StreamDecoder`] takes bytes as they arrive, in any chunking, and renders whenever asked;
//! [`Picture`] tells a preview from the final picture. [`Previews`] drives one from any
//! [`std::io::Read`], yielding a picture per level or every so many bytes.
//!
//! ```
//! # let img = image::open("tests/data/coffee-150x100.png")?;
//! # let file = qcs::encode(&img, &Default::default())?;
//! let mut decoder = qcs::StreamDecoder::new(qcs::Limits::default());
//! for packet in file.chunks(512) {
//!     decoder.push(packet)?;
//!     if decoder.header().is_some() {
//!         match decoder.render(qcs::Method::Gouraud, 75, 50)? {
//!             qcs::Picture::Preview(p) => assert!(!p.is_final),
//!             qcs::Picture::Final(p) => assert!(p.is_final),
//!         }
//!     }
//! }
//! assert!(decoder.is_complete());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Hostile input, errors, and the `image` crate
//!
//! [`Limits`] bound what a file may cost (pixels, samples, output size, metadata, and the
//! decoder's account of a decode's memory) before anything it sizes is allocated:
//!
//! ```
//! # let img = image::open("tests/data/coffee-150x100.png")?;
//! # let file = qcs::encode(&img, &Default::default())?;
//! let tight = qcs::DecodeOptions {
//!     limits: qcs::Limits { max_alloc: 64 << 10, ..Default::default() },
//!     ..Default::default()
//! };
//! // 150 × 100 × 3 coefficients of a refinement are more than 64 KiB by the account.
//! assert!(matches!(qcs::decode(&file, &tight), Err(qcs::Error::Limits(_))));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A damaged file gives an [`Error::Format`] naming the chunk
//! and byte offset, or, with [`DecodeOptions::recover`], the longest verified prefix.
//! [`Error`]'s variants say who is to blame. [`register_image_hooks`] makes `image::open`
//! read `.qcs` files, and [`QcsImageDecoder`] is an [`image::ImageDecoder`].
//! [`format`](mod@format) names what a decoder reports of a file: its [`Header`](format::Header),
//! metadata, the format's errors and the sites.
//!
//! ## Inside
//!
//! The pipeline, one module per stage: `lattice` (exact arithmetic in Z\[τ\] and Z\[ζ\]) →
//! `sites` (the progressive site sequence) → `sampling` (a colour per site) → `coding`
//! (colours ↔ bits) → `container` (bytes on disk) → `reconstruction` (samples → picture at
//! any size), with `refinement` (the wavelet part of a file) beside it. The stages are public
//! modules only with the `internals` feature, for the lab (`qcs-lab`), the command line, the
//! benches and the measuring tools, with no stability promise.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// What is `pub` is reachable: with the stages public (`internals`), every `pub` item must be
// (the rest is `pub(crate)` or narrower). Without the feature the stages are private and their
// `pub` items unreachable by design, so the lint applies to the build that exposes them.
#![cfg_attr(feature = "internals", deny(unreachable_pub))]

/// The codec's stages: public modules with the `internals` feature, private without it (where
/// what only the lab and the tools use is not dead code to warn about).
macro_rules! stages {
    ($($(#[$meta:meta])* mod $name:ident;)*) => {$(
        $(#[$meta])*
        #[cfg(feature = "internals")]
        pub mod $name;
        $(#[$meta])*
        #[cfg(not(feature = "internals"))]
        #[allow(dead_code, unused_imports)]
        mod $name;
    )*};
}

stages! {
    mod coding;
    mod container;
    mod lattice;
    mod reconstruction;
    mod sampling;
    mod sites;
}

mod decoder;
mod encoder;
pub mod error;
mod integration;
pub mod limits;
mod pull;
mod refinement;
#[cfg(test)]
mod testing;

#[cfg(feature = "internals")]
#[doc(hidden)]
pub use decoder::RawDecoder;
pub use decoder::{decode, thumbnail_samples, DecodeOptions, DecodedImage, Picture, StreamDecoder};
pub use encoder::{encode, encode_to, EncodeOptions, Target, DEFAULT_QUALITY};
pub use error::{Error, Result};
pub use integration::{register_image_hooks, QcsImageDecoder};
pub use limits::Limits;
pub use pull::{Cadence, Previews};
pub use reconstruction::Method;

/// The file as the decoder reports it and the encoder's choices (`spec/format.md`): the
/// header, its layout, coding and refinement, metadata, the parser's options, the format's
/// errors, and the sites the samples sit on with their exact lattice points.
pub mod format {
    pub use crate::container::{
        ChunkRef, Coding, FormatError, Header, LatticeFields, Layout, Metadata, ParserOptions,
        PassLimit, RefinementHeader, VarintError, Wavelet,
    };
    pub use crate::lattice::{ZTau, ZZeta};
    pub use crate::sampling::SampleColour;
    pub use crate::sites::{Frame, FrameError, Site};
}

/// The README's code examples, run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
