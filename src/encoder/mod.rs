//! Image → `.qcs` bytes: sites, sample colours, colour coding, container.

mod levels;
mod start;

use crate::coding::predictive::Params;
use crate::container::{Coding, ContainerWriter, Header, LatticeFields, Layout, Wavelet};
use crate::refinement::encode::{self as refine, Goal};
use crate::sampling::{SampleColour, SourceImage};
use crate::sites::{Frame, FrameError, Quasicrystal};
use crate::{Error, Result};
use image::DynamicImage;
use std::borrow::Cow;
use std::io::Write;

/// What the file aims at: how faithful its whole is, or how large.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A quality from 0 (the smallest files) to 100 (nearly lossless), as cjpeg's and
    /// cwebp's: the refinement codes every bit-plane worth more than the quality allows.
    Quality(u8),
    /// Exactly the input's pixels (every channel, alpha included), at 8 bits per channel: an
    /// image with deeper channels is reduced to 8 bits first.
    Lossless,
    /// The best picture the file can give in this many bytes (the whole file, at least its
    /// levels).
    Size(u64),
    /// No refinement: the quasicrystal levels only (a format version 2 file), their fidelity
    /// set by [`EncodeOptions::coding`].
    LevelsOnly,
}

/// The quality of [`EncodeOptions::default`] and `qcs encode`.
pub const DEFAULT_QUALITY: u8 = 85;

/// How to encode an image.
///
/// ```
/// use qcs::{EncodeOptions, Target};
/// // The default: a first level of 64 samples, then the refinement, at quality 85.
/// assert_eq!(EncodeOptions::default().sample_count(512, 512), 64);
/// let opts = EncodeOptions { samples: Some(5000), ..Default::default() };
/// assert_eq!(opts.sample_count(512, 512), 5000);
/// // Levels only: one sample per 4 pixels, and a 24-megapixel photo gets what a default
/// // decoder takes.
/// let levels = EncodeOptions { target: Target::LevelsOnly, ..Default::default() };
/// assert_eq!(levels.sample_count(512, 512), 65536);
/// assert_eq!(levels.sample_count(6000, 4000), 1 << 22);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeOptions {
    /// What the file aims at (default: quality [`DEFAULT_QUALITY`]).
    pub target: Target,
    /// Samples in the levels N; `None` uses `density` for [`Target::LevelsOnly`], and with a
    /// refinement lets the encoder choose: a first level of 64 samples, then each doubling
    /// that pays for its bytes (measured on the image: spec/refinement.md §9).
    pub samples: Option<u64>,
    /// Samples per pixel when `samples` is `None` (default 1/4): N = ⌊W·H·density⌋, at least 1
    /// and at most 2^22, the default [`Limits::max_samples`](crate::Limits::max_samples), so
    /// that a decoder with the default limits decodes the whole file (above 16.7 megapixels
    /// the default density gives fewer samples per pixel; set `samples` for more). A multiple
    /// of 1/256 is stored in one header byte.
    pub density: f64,
    /// The levels' colour coding (default: predictive at quality 40, for the smallest
    /// previews; a file with levels only wants more, e.g.
    /// the predictive coder's `DEFAULT_QUALITY`).
    pub coding: Coding,
    /// What a sample's colour is.
    pub colour: SampleColour,
    /// Samples in the first level (each later level doubles the count). Default 127, the
    /// largest whose header field is one byte: the first level is then one stretch of about
    /// a hundred bytes with no chunk framing inside, which the smallest previews need.
    pub first_level: u64,
    /// Lattice placement; `None` for the default frame of spec/sites.md.
    pub frame: Option<Frame>,
    /// ICC profile to store (after the first level).
    pub icc: Option<Vec<u8>>,
    /// Exif metadata to store, at the end of the file (no preview waits for it; a file cut
    /// short has none): the TIFF-structured block, as
    /// `image`'s `ImageDecoder::exif_metadata` gives it. Its orientation should say upright
    /// if the pixels are (`image::metadata::Orientation::remove_from_exif_chunk`).
    pub exif: Option<Vec<u8>>,
    /// Text comments to store (after the first level).
    pub text: Vec<(String, String)>,
}

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions {
            target: Target::Quality(DEFAULT_QUALITY),
            samples: None,
            density: 0.25,
            coding: Params::from_quality(BASE_QUALITY).coding(),
            colour: SampleColour::default(),
            first_level: crate::container::DEFAULT_FIRST_LEVEL,
            frame: None,
            icc: None,
            exif: None,
            text: Vec::new(),
        }
    }
}

impl EncodeOptions {
    /// The sample count N these options give for a `width × height` image (1 ≤ N ≤ W·H); with
    /// a refinement and no `samples`, the first level's (the encoder may add levels).
    pub fn sample_count(&self, width: u32, height: u32) -> u64 {
        let px = width as u64 * height as u64;
        let n = match (self.samples, self.target) {
            (Some(n), _) => n,
            (None, Target::LevelsOnly) => ((self.density * px as f64).floor() as u64)
                .min(crate::Limits::default().max_samples),
            (None, _) => BASE_SAMPLES,
        };
        n.clamp(1, px.max(1))
    }
}

/// Bytes in the refinement's first layer (each later one doubles).
const FIRST_LAYER: usize = 64;

/// Samples in the levels before a refinement, unless told otherwise: one level, whose first
/// bytes are the smallest previews (about 20 samples in 32 bytes).
const BASE_SAMPLES: u64 = 64;

/// The levels' quality before a refinement: coarse colours, so that the first bytes hold
/// many samples.
const BASE_QUALITY: u8 = 40;

/// The fraction bits of a lossy refinement (spec/refinement.md §1): with 3, the 9/7's
/// rounding stays about 1/8 of a level below the integer grid, where its noise no longer
/// caps the best pictures (F = 2 left near-lossless encodes 1.2–1.4 dB lower at equal bytes).
pub(crate) const LOSSY_FRACTION_BITS: u32 = 3;

/// The key (sixteenths of a bit-plane, spec/format.md) below which a refinement at `quality`
/// codes no pass: a quantiser scale like libjpeg's (`5000/Q` below 50, `200 − 2Q` above), each
/// halving of it one half bit-plane finer, fitted so that a photograph at quality Q is a little
/// closer to the original (PSNR) than libjpeg's at Q, in fewer bytes; 100 is nearly lossless.
pub(crate) fn quality_key(quality: u8) -> i32 {
    let q = quality.clamp(1, 100) as f64;
    let scale = if q >= 100.0 {
        0.25
    } else if q >= 50.0 {
        200.0 - 2.0 * q
    } else {
        5000.0 / q
    };
    // A fraction bit more is a bit-plane more (16 in the key) for the same quantiser.
    (17.0 + 16.0 * LOSSY_FRACTION_BITS as f64 + 8.43 * scale.log2()).round() as i32
}

/// The layout qcs stores for an image, and its pixels in that layout (borrowed when the
/// image is already 8-bit: a 24-megapixel photo is 72 MB).
fn layout_and_pixels(image: &DynamicImage) -> (Layout, Cow<'_, [u8]>) {
    match image {
        DynamicImage::ImageLuma8(i) => (Layout::Grey, i.as_raw().into()),
        DynamicImage::ImageLumaA8(i) => (Layout::GreyAlpha, i.as_raw().into()),
        DynamicImage::ImageRgb8(i) => (Layout::Rgb, i.as_raw().into()),
        DynamicImage::ImageRgba8(i) => (Layout::Rgba, i.as_raw().into()),
        other => match (other.color().has_color(), other.color().has_alpha()) {
            (true, true) => (Layout::Rgba, other.to_rgba8().into_raw().into()),
            (true, false) => (Layout::Rgb, other.to_rgb8().into_raw().into()),
            (false, true) => (Layout::GreyAlpha, other.to_luma_alpha8().into_raw().into()),
            (false, false) => (Layout::Grey, other.to_luma8().into_raw().into()),
        },
    }
}

/// Bytes an Exif chunk of `exif` takes (tag, length, payload, CRC).
fn exif_chunk_len(exif: &[u8]) -> u64 {
    let len = exif.len() as u64;
    1 + crate::container::varint::encoded_len(len) as u64 + len + 4
}

/// Encodes an image to `.qcs` bytes.
///
/// ```
/// let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(40, 30, image::Rgb([200, 100, 50])));
/// let bytes = qcs::encode(&img, &qcs::EncodeOptions { samples: Some(300), ..Default::default() })?;
/// let back = qcs::decode(&bytes, &qcs::DecodeOptions::default())?;
/// assert!(back.is_final);
/// // At the default quality (85) a flat colour comes back within a few levels.
/// let px = back.image.to_rgb8().get_pixel(20, 15).0;
/// assert!(px.iter().zip([200, 100, 50]).all(|(&a, b)| a.abs_diff(b) <= 7), "{px:?}");
/// # Ok::<(), qcs::Error>(())
/// ```
pub fn encode(image: &DynamicImage, opts: &EncodeOptions) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    encode_to(image, opts, &mut out)?;
    Ok(out)
}

/// The caller's image size or [`EncodeOptions::frame`] that the site construction cannot use.
fn frame_error(e: FrameError) -> Error {
    match e {
        FrameError::RootLength { root_len } => Error::invalid(
            "EncodeOptions::frame root length",
            format_args!("{root_len}/65536 px"),
            "65536..=16777216 (1 to 256 px)",
        ),
        FrameError::Size { width, height } => Error::invalid(
            "image size",
            format_args!("{width}×{height}"),
            "1..=65535 pixels on each side",
        ),
    }
}

/// Encodes an image to any writer.
pub fn encode_to<W: Write>(image: &DynamicImage, opts: &EncodeOptions, writer: W) -> Result<()> {
    let (width, height) = (image.width(), image.height());
    let frame = opts
        .frame
        .unwrap_or_else(|| Frame::default_for(width, height));
    let seq = Quasicrystal::with_frame(width, height, frame).map_err(frame_error)?;
    if opts.first_level == 0 {
        return Err(Error::invalid(
            "EncodeOptions::first_level",
            0,
            "at least 1 sample",
        ));
    }
    let refined = opts.target != Target::LevelsOnly;
    let (layout, pixels) = layout_and_pixels(image);
    let channels = layout.channels() as usize;
    let (kernel, frac) = match opts.target {
        Target::Lossless => (Wavelet::Reversible53, 0),
        _ => (Wavelet::Integer97, LOSSY_FRACTION_BITS),
    };
    // With a refinement the levels are short: the encoder decides where they stop, unless told.
    let (n, first_level) = if refined && opts.samples.is_none() {
        let n = start::samples_before_refinement(
            &pixels,
            width,
            height,
            layout,
            &opts.coding,
            opts.colour,
            kernel,
            frac,
        )?;
        (n, start::FIRST_LEVEL)
    } else {
        (opts.sample_count(width, height), opts.first_level)
    };
    let mut header = Header::new(width, height, layout, n, first_level, opts.coding.clone());
    header.refinement = refined;
    if opts.frame.is_some() {
        header.lattice = Some(LatticeFields {
            root_length: frame.root_len,
            origin_x: frame.origin[0],
            origin_y: frame.origin[1],
        });
    }
    let source = SourceImage::new(&pixels, width, height, channels)?;
    let levels = levels::code_last(source, &seq, &header, opts.colour)?;
    let mut w = ContainerWriter::new(writer, &header)?;
    for (k, payload) in levels.payloads.iter().enumerate() {
        w.write_level(payload)?;
        if k == 0 {
            if let Some(icc) = &opts.icc {
                w.write_icc(icc)?;
            }
            for (key, value) in &opts.text {
                w.write_text(key, value)?;
            }
        }
    }
    if refined {
        let goal = match opts.target {
            Target::Lossless => Goal::Lossless,
            Target::Quality(q) => Goal::Key(quality_key(q)),
            Target::Size(bytes) => {
                let exif = opts.exif.as_ref().map_or(0, |e| exif_chunk_len(e));
                let used = w.bytes_written() + exif;
                Goal::Bytes(usize::try_from(bytes.saturating_sub(used)).unwrap_or(usize::MAX))
            }
            Target::LevelsOnly => unreachable!("no refinement"),
        };
        let levels_of_transform = refine::default_levels(width, height);
        let t = refine::transform(
            &pixels,
            width,
            height,
            channels,
            kernel,
            frac,
            levels_of_transform,
        );
        let coded = refine::encode(t, &levels.fixed, &levels.decoded, goal, FIRST_LAYER);
        for layer in &coded.layers {
            let segs: Vec<&[u8]> = layer.iter().map(Vec::as_slice).collect();
            w.write_layer(&coded.header, &segs)?;
        }
    }
    // Last: no preview needs it (the pixels are stored upright), and a camera's, often tens
    // of kilobytes with its own thumbnail, would delay every preview after the first.
    if let Some(exif) = &opts.exif {
        w.write_exif(exif)?;
    }
    w.finish()?;
    Ok(())
}
