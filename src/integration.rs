//! `image` crate integration: an [`image::ImageDecoder`] for `.qcs`, and registration through
//! `image`'s decoding hooks so that `image::open("photo.qcs")` works.

use crate::container::{Event, Header, Layout, Metadata, Parser, ParserOptions};
use crate::{decode, DecodeOptions, Error, Limits, StreamDecoder};
use image::error::{DecodingError, ImageFormatHint, LimitError, LimitErrorKind};
use image::{ColorType, ImageDecoder, ImageError, ImageResult};
use std::io::Read;

/// Largest `.qcs` file [`QcsImageDecoder`] reads into memory (1 GiB).
pub(crate) const MAX_FILE_BYTES: u64 = 1 << 30;

/// `image`'s error for `e`. `image` prints a decoding error as "Format error decoding qcs: "
/// and the error it wraps: a format error is wrapped itself, since [`Error::Format`] would
/// print only "malformed file".
fn to_image_error(e: Error) -> ImageError {
    let hint = || ImageFormatHint::Name("qcs".into());
    match e {
        Error::Io(e) => ImageError::IoError(e),
        Error::Limits(_) | Error::OutOfMemory { .. } => {
            ImageError::Limits(LimitError::from_kind(LimitErrorKind::InsufficientMemory))
        }
        Error::Format(e) => ImageError::Decoding(DecodingError::new(hint(), e)),
        other => ImageError::Decoding(DecodingError::new(hint(), other)),
    }
}

/// Decodes a whole `.qcs` stream for the `image` crate (Gouraud, at the file's own size).
///
/// ```
/// use image::ImageDecoder;
/// let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(16, 8, image::Rgb([9, 99, 199])));
/// let lossless = qcs::EncodeOptions { target: qcs::Target::Lossless, ..Default::default() };
/// let bytes = qcs::encode(&img, &lossless)?;
/// let dec = qcs::QcsImageDecoder::new(std::io::Cursor::new(bytes))?;
/// assert_eq!(dec.dimensions(), (16, 8));
/// let back = image::DynamicImage::from_decoder(dec)?;
/// assert_eq!(back.to_rgb8().get_pixel(3, 3).0, [9, 99, 199]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct QcsImageDecoder {
    bytes: Vec<u8>,
    header: Header,
    limits: Limits,
}

impl QcsImageDecoder {
    /// Reads the stream (at most 1 GiB) and parses its header.
    pub fn new<R: Read>(reader: R) -> ImageResult<Self> {
        let mut bytes = Vec::new();
        reader.take(MAX_FILE_BYTES).read_to_end(&mut bytes)?;
        let limits = Limits::default();
        let mut d = StreamDecoder::new(limits.clone());
        let head = bytes.len().min(crate::container::MAX_HEADER_LEN);
        d.push(&bytes[..head]).map_err(to_image_error)?;
        let header = d
            .header()
            .cloned()
            .ok_or_else(|| to_image_error(Error::NeedMoreData))?;
        Ok(QcsImageDecoder {
            bytes,
            header,
            limits,
        })
    }

    /// The first metadata chunk `pick` takes, once verified: the file is parsed as far as
    /// that chunk (an error before it is the answer).
    fn metadata(&self, pick: impl Fn(Metadata) -> Option<Vec<u8>>) -> ImageResult<Option<Vec<u8>>> {
        let mut parser = Parser::new(ParserOptions {
            limits: self.limits.clone(),
            ..Default::default()
        });
        let mut events = Vec::new();
        let parsed = parser.push(&self.bytes, &mut events);
        let found = events.into_iter().find_map(|e| match e {
            Event::Metadata { metadata, .. } => pick(metadata),
            _ => None,
        });
        match (found, parsed) {
            (Some(m), _) => Ok(Some(m)),
            (None, Ok(())) => Ok(None),
            (None, Err(e)) => Err(to_image_error(e)),
        }
    }
}

impl ImageDecoder for QcsImageDecoder {
    fn dimensions(&self) -> (u32, u32) {
        (self.header.width, self.header.height)
    }

    fn color_type(&self) -> ColorType {
        match self.header.layout {
            Layout::Grey => ColorType::L8,
            Layout::GreyAlpha => ColorType::La8,
            Layout::Rgb => ColorType::Rgb8,
            Layout::Rgba => ColorType::Rgba8,
        }
    }

    /// The file's ICC profile (its chunk follows the first level, and counts once its CRC is
    /// checked), so that colour-managed callers can convert the pixels.
    ///
    /// ```
    /// use image::ImageDecoder;
    /// let img = image::DynamicImage::ImageRgb8(image::RgbImage::new(8, 8));
    /// let opts = qcs::EncodeOptions { icc: Some(b"a profile".to_vec()), ..Default::default() };
    /// let bytes = qcs::encode(&img, &opts)?;
    /// let mut dec = qcs::QcsImageDecoder::new(std::io::Cursor::new(bytes))?;
    /// assert_eq!(dec.icc_profile()?, Some(b"a profile".to_vec()));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    fn icc_profile(&mut self) -> ImageResult<Option<Vec<u8>>> {
        self.metadata(|m| match m {
            Metadata::Icc(icc) => Some(icc),
            _ => None,
        })
    }

    /// The file's Exif metadata (its chunk ends the file), as `image`'s decoders of other
    /// formats give it.
    ///
    /// ```
    /// use image::ImageDecoder;
    /// let img = image::DynamicImage::ImageRgb8(image::RgbImage::new(8, 8));
    /// let exif = b"II*\0\x08\0\0\0\0\0".to_vec();
    /// let opts = qcs::EncodeOptions { exif: Some(exif.clone()), ..Default::default() };
    /// let bytes = qcs::encode(&img, &opts)?;
    /// let mut dec = qcs::QcsImageDecoder::new(std::io::Cursor::new(bytes))?;
    /// assert_eq!(dec.exif_metadata()?, Some(exif));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    fn exif_metadata(&mut self) -> ImageResult<Option<Vec<u8>>> {
        self.metadata(|m| match m {
            Metadata::Exif(exif) => Some(exif),
            _ => None,
        })
    }

    fn set_limits(&mut self, limits: image::Limits) -> ImageResult<()> {
        limits.check_dimensions(self.header.width, self.header.height)?;
        if let Some(w) = limits.max_image_width {
            self.limits.max_dimension = self.limits.max_dimension.min(w);
        }
        if let Some(h) = limits.max_image_height {
            self.limits.max_dimension = self.limits.max_dimension.min(h);
        }
        if let Some(bytes) = limits.max_alloc {
            let px = bytes / self.color_type().bytes_per_pixel() as u64;
            self.limits.max_output_pixels = self.limits.max_output_pixels.min(px);
        }
        Ok(())
    }

    fn read_image(self, buf: &mut [u8]) -> ImageResult<()> {
        let opts = DecodeOptions {
            limits: self.limits.clone(),
            ..Default::default()
        };
        let d = decode(&self.bytes, &opts).map_err(to_image_error)?;
        buf.copy_from_slice(d.image.as_bytes());
        Ok(())
    }

    fn read_image_boxed(self: Box<Self>, buf: &mut [u8]) -> ImageResult<()> {
        (*self).read_image(buf)
    }
}

/// Registers `.qcs` with the `image` crate: by extension and by signature (`qc` and a format
/// byte of version 2 or 3), so that `image::open` and `ImageReader::with_guessed_format` read
/// `.qcs` files whatever their names.
/// Returns `false` if a decoder for the extension was already registered.
///
/// ```
/// qcs::register_image_hooks();
/// let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_pixel(8, 8, image::Luma([77])));
/// let path = std::env::temp_dir().join("qcs-doc-hook.qcs");
/// let lossless = qcs::EncodeOptions { target: qcs::Target::Lossless, ..Default::default() };
/// std::fs::write(&path, qcs::encode(&img, &lossless)?)?;
/// let back = image::open(&path)?;
/// assert_eq!(back.to_luma8().get_pixel(4, 4).0, [77]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn register_image_hooks() -> bool {
    let new = image::hooks::register_decoding_hook(
        "qcs".into(),
        Box::new(|r| Ok(Box::new(QcsImageDecoder::new(r)?))),
    );
    if new {
        // The format byte's top three bits are the version (spec/format.md, the header).
        for signature in [b"qc\x40", b"qc\x60"] {
            image::hooks::register_format_detection_hook(
                "qcs".into(),
                signature,
                Some(b"\xFF\xFF\xE0"),
            );
        }
    }
    new
}
