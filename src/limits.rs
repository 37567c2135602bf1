//! Resource limits, checked before anything sized by input is allocated.

use thiserror::Error as ThisError;

/// Upper bounds a decoder (or encoder) enforces before allocating.
///
/// The image and sample limits are checked on the header, before anything sized by it is
/// allocated; the output limit before a render allocates its picture; the metadata limit
/// before each metadata chunk is buffered. Within them, a decoder's memory and time are bounded
/// by the limits themselves, not by the bytes given: the predictive coding decodes a level whose
/// residuals are all zero from an empty payload, so a file of a few dozen bytes can hold
/// [`Limits::max_samples`] samples, and a level's sites are laid out when its chunk begins.
///
/// The defaults are meant for untrusted input (see [`Limits::max_samples`] for the memory they
/// allow); [`Limits::none`] lifts them to the format's own bounds. As every options type of the
/// crate, a struct of public fields: set those you need and take the rest from a default.
///
/// ```
/// let limits = qcs::Limits { max_samples: 1 << 20, ..Default::default() };
/// assert!(limits.check_samples(1000).is_ok());
/// assert!(limits.check_samples(1 << 21).is_err());
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Largest image width or height accepted from a header.
    pub max_dimension: u32,
    /// Largest width × height accepted from a header.
    pub max_image_pixels: u64,
    /// Largest output picture (width × height) a render may produce.
    pub max_output_pixels: u64,
    /// Largest number of samples that will be decoded and triangulated: the header's N, or
    /// for a one-shot decode capped at fewer ([`crate::DecodeOptions::max_samples`], a
    /// thumbnail), the samples of the levels it decodes.
    ///
    /// This is also the bound on the decoder's memory for sites, colours and the triangulation,
    /// which grows with the samples of the levels begun (never with N itself). A one-shot
    /// decode of all of them peaks at about 380 bytes per sample on two threads (the cells are
    /// built while the colours decode) and 260 on one (measured: 1.59 GB and 1.10 GB for
    /// 2^22 samples of a 4096 × 4096 image; a 32768 × 128 strip, whose mirror points
    /// (`spec/reconstruction.md` §2) are more, 410 and 294 bytes per sample). The default 2^22
    /// (a 16-megapixel photo at the encoder's default 1 sample per 4 pixels) bounds that to
    /// about 1.6 GB, reached by a file whose levels hold 2^22 samples (which, for a flat
    /// picture in the predictive coding, can be a file of a few dozen bytes); raise it for
    /// larger images, lower it on small machines or for untrusted input.
    pub max_samples: u64,
    /// Largest total size of metadata (ICC, Exif, text) kept by a decoder.
    pub max_metadata_bytes: u64,
    /// The most memory, in bytes, a decode may hold at once by the decoder's account, which
    /// it checks before allocating: when the header arrives (for the levels it will decode and
    /// the refinement) and before each picture (adding the picture). The account is an upper
    /// bound of what the decoder allocates, not counting the file's own bytes: 512 bytes per
    /// sample of the levels decoded, 8 per coefficient of a refinement decoded (width × height
    /// × channels), and twice the picture drawn (measured peaks are below it: 380–410 bytes per
    /// sample, 1.4 per coefficient at the default quality and 5.2 for a lossless file, 1.0–1.6
    /// times the picture; MEASUREMENTS.md). A thumbnail holds much less than the account of its
    /// refinement. The default 4 GiB refuses no file of levels within the other defaults, and a
    /// refinement beyond about 140 megapixels of RGB (30 bytes a pixel: 24 for its coefficients,
    /// 6 for its picture) or 110 of RGBA.
    pub max_alloc: u64,
}

/// The decoder's account of its memory ([`Limits::max_alloc`]): for each sample of the levels
/// it decodes…
const SAMPLE_BYTES: u64 = 512;
/// … for each coefficient of the refinement it decodes…
const COEFFICIENT_BYTES: u64 = 8;
/// … and for each byte of the picture it draws.
const PICTURE_BYTES: u64 = 2;

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_dimension: 1 << 15,
            max_image_pixels: 1 << 28,
            max_output_pixels: 1 << 28,
            max_samples: 1 << 22,
            max_metadata_bytes: 1 << 24,
            max_alloc: 1 << 32,
        }
    }
}

/// Which limit was exceeded, with the value that exceeded it.
#[derive(Clone, Debug, PartialEq, Eq, ThisError)]
#[non_exhaustive]
pub enum LimitError {
    /// Width or height above `max_dimension`.
    #[error("image dimension {value} exceeds the limit {limit}")]
    Dimension {
        /// The larger of width and height.
        value: u64,
        /// `max_dimension`.
        limit: u64,
    },
    /// Width × height above `max_image_pixels`.
    #[error("image of {value} pixels exceeds the limit {limit}")]
    ImagePixels {
        /// Width × height (saturated at `u64::MAX`).
        value: u64,
        /// `max_image_pixels`.
        limit: u64,
    },
    /// Output size above `max_output_pixels`.
    #[error("output of {value} pixels exceeds the limit {limit}")]
    OutputPixels {
        /// Width × height of the output (saturated at `u64::MAX`).
        value: u64,
        /// `max_output_pixels`.
        limit: u64,
    },
    /// Sample count above `max_samples`.
    #[error("{value} samples exceed the limit {limit}")]
    Samples {
        /// The samples asked for.
        value: u64,
        /// `max_samples`.
        limit: u64,
    },
    /// The decoder's account of a decode's memory above `max_alloc`.
    #[error("a decode of {value} bytes exceeds the limit {limit}")]
    Alloc {
        /// The decoder's account, in bytes (saturated at `u64::MAX`).
        value: u64,
        /// `max_alloc`.
        limit: u64,
    },
    /// Metadata above `max_metadata_bytes`.
    #[error("{value} metadata bytes exceed the limit {limit}")]
    Metadata {
        /// The metadata bytes, with the chunk that went over.
        value: u64,
        /// `max_metadata_bytes`.
        limit: u64,
    },
}

impl Limits {
    /// No limits beyond the format's own (dimensions below 2^16 for the site construction).
    pub fn none() -> Self {
        Limits {
            max_dimension: u16::MAX as u32,
            max_image_pixels: u64::MAX,
            max_output_pixels: u64::MAX,
            max_samples: u64::MAX,
            max_metadata_bytes: u64::MAX,
            max_alloc: u64::MAX,
        }
    }

    /// Checks an image size against `max_dimension` and `max_image_pixels`.
    pub fn check_image(&self, width: u64, height: u64) -> Result<(), LimitError> {
        let d = width.max(height);
        if d > self.max_dimension as u64 {
            return Err(LimitError::Dimension {
                value: d,
                limit: self.max_dimension as u64,
            });
        }
        let p = width.saturating_mul(height);
        if p > self.max_image_pixels {
            return Err(LimitError::ImagePixels {
                value: p,
                limit: self.max_image_pixels,
            });
        }
        Ok(())
    }

    /// Checks a requested output size against `max_output_pixels`.
    pub fn check_output(&self, width: u64, height: u64) -> Result<(), LimitError> {
        let p = width.saturating_mul(height);
        if p > self.max_output_pixels {
            return Err(LimitError::OutputPixels {
                value: p,
                limit: self.max_output_pixels,
            });
        }
        Ok(())
    }

    /// Checks a sample count against `max_samples`.
    pub fn check_samples(&self, n: u64) -> Result<(), LimitError> {
        if n > self.max_samples {
            return Err(LimitError::Samples {
                value: n,
                limit: self.max_samples,
            });
        }
        Ok(())
    }

    /// Checks the decoder's account of a decode ([`Limits::max_alloc`]) against `max_alloc`:
    /// `samples` of the levels decoded, `coefficients` of the refinement decoded (0 if none)
    /// and `picture` bytes drawn.
    pub(crate) fn check_alloc(
        &self,
        samples: u64,
        coefficients: u64,
        picture: u64,
    ) -> Result<(), LimitError> {
        let value = samples
            .saturating_mul(SAMPLE_BYTES)
            .saturating_add(coefficients.saturating_mul(COEFFICIENT_BYTES))
            .saturating_add(picture.saturating_mul(PICTURE_BYTES));
        if value > self.max_alloc {
            return Err(LimitError::Alloc {
                value,
                limit: self.max_alloc,
            });
        }
        Ok(())
    }

    /// Checks a metadata size against `max_metadata_bytes`.
    pub fn check_metadata(&self, n: u64) -> Result<(), LimitError> {
        if n > self.max_metadata_bytes {
            return Err(LimitError::Metadata {
                value: n,
                limit: self.max_metadata_bytes,
            });
        }
        Ok(())
    }
}
