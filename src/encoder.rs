//! Image → `.qcs` bytes: sites, sample colours, colour coding, container.

use crate::coding::predictive::{fixed_position, Params, PredictiveEncoder};
use crate::container::{Coding, ContainerWriter, Header, LatticeFields, Layout};
use crate::sampling::{SampleColour, SourceImage};
use crate::sites::{Frame, Quasicrystal};
use crate::{Error, Result};
use image::DynamicImage;
use std::borrow::Cow;
use std::io::Write;

/// How to encode an image.
///
/// ```
/// let opts = qcs::EncodeOptions { samples: Some(5000), ..Default::default() };
/// assert_eq!(opts.sample_count(512, 512), 5000);
/// assert_eq!(qcs::EncodeOptions::default().sample_count(512, 512), 65536);
/// // A 24-megapixel photo gets what a default decoder takes.
/// assert_eq!(qcs::EncodeOptions::default().sample_count(6000, 4000), 1 << 22);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeOptions {
    /// Total samples N; `None` uses `density`.
    pub samples: Option<u64>,
    /// Samples per pixel when `samples` is `None` (default 1/4): N = ⌊W·H·density⌋, at least 1
    /// and at most 2^22, the default [`Limits::max_samples`](crate::Limits::max_samples), so
    /// that a decoder with the default limits decodes the whole file (above 16.7 megapixels
    /// the default density gives fewer samples per pixel; set `samples` for more). A multiple
    /// of 1/256 is stored in one header byte.
    pub density: f64,
    /// The colour coding (default: predictive at quality
    /// [`DEFAULT_QUALITY`](crate::coding::predictive::DEFAULT_QUALITY)).
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
    /// Text comments to store (after the first level).
    pub text: Vec<(String, String)>,
}

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions {
            samples: None,
            density: 0.25,
            coding: crate::coding::predictive::Params::default().coding(),
            colour: SampleColour::default(),
            first_level: crate::container::DEFAULT_FIRST_LEVEL,
            frame: None,
            icc: None,
            text: Vec::new(),
        }
    }
}

impl EncodeOptions {
    /// The sample count N these options give for a `width × height` image (1 ≤ N ≤ W·H).
    pub fn sample_count(&self, width: u32, height: u32) -> u64 {
        let px = width as u64 * height as u64;
        let n = match self.samples {
            Some(n) => n,
            None => ((self.density * px as f64).floor() as u64)
                .min(crate::Limits::default().max_samples),
        };
        n.clamp(1, px.max(1))
    }
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

/// Encodes an image to `.qcs` bytes.
///
/// ```
/// let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(40, 30, image::Rgb([200, 100, 50])));
/// let bytes = qcs::encode(&img, &qcs::EncodeOptions { samples: Some(300), ..Default::default() })?;
/// let back = qcs::decode(&bytes, &qcs::DecodeOptions::default())?;
/// assert!(back.is_final);
/// // The default predictive coding (quality 75) quantises luma in steps of 7, chroma of 13.
/// let px = back.image.to_rgb8().get_pixel(20, 15).0;
/// assert!(px.iter().zip([200, 100, 50]).all(|(&a, b)| a.abs_diff(b) <= 7), "{px:?}");
/// # Ok::<(), qcs::Error>(())
/// ```
pub fn encode(image: &DynamicImage, opts: &EncodeOptions) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    encode_to(image, opts, &mut out)?;
    Ok(out)
}

/// Encodes an image to any writer.
pub fn encode_to<W: Write>(image: &DynamicImage, opts: &EncodeOptions, writer: W) -> Result<()> {
    let (width, height) = (image.width(), image.height());
    let frame = opts
        .frame
        .unwrap_or_else(|| Frame::default_for(width, height));
    let seq = Quasicrystal::with_frame(width, height, frame)
        .map_err(|e| Error::Parameter(e.to_string()))?;
    if opts.first_level == 0 {
        return Err(Error::Parameter(
            "the first level must hold at least one sample".into(),
        ));
    }
    let n = opts.sample_count(width, height);
    let (layout, pixels) = layout_and_pixels(image);
    let channels = layout.channels() as usize;
    let mut header = Header::new(
        width,
        height,
        layout,
        n,
        opts.first_level,
        opts.coding.clone(),
    );
    if opts.frame.is_some() {
        header.lattice = Some(LatticeFields {
            root_length: frame.root_len,
            origin_x: frame.origin[0],
            origin_y: frame.origin[1],
        });
    }
    let sites = seq.first(n as usize);
    let positions: Vec<_> = sites.iter().map(|s| s.pos).collect();
    let mut predictive = match &opts.coding {
        Coding::Predictive { step } => Some((
            PredictiveEncoder::new(Params { step: *step }, channels as u8, width, height)?,
            sites
                .iter()
                .map(|s| fixed_position(&frame, s.lattice))
                .collect::<Vec<_>>(),
        )),
        Coding::Raw { .. } => None,
    };
    let source = SourceImage::new(&pixels, width, height, channels)?;
    let colours = match opts.colour {
        SampleColour::Fitted => {
            let first = usize::try_from(opts.first_level).unwrap_or(usize::MAX);
            source.fitted(&sites, seq.frame(), first, n as usize)
        }
        rule => source.colours(&positions, rule, n as usize),
    };
    let mut w = ContainerWriter::new(writer, &header)?;
    for k in 0..header.level_count() {
        let range = header.level_range(k).expect("level below level_count");
        let values = &colours[range.start as usize * channels..range.end as usize * channels];
        let payload = match &opts.coding {
            Coding::Raw { bits } => crate::coding::raw::pack(values, *bits)?,
            Coding::Predictive { .. } => match &mut predictive {
                Some((enc, fixed)) => {
                    enc.encode_level(&fixed[range.start as usize..range.end as usize], values)?
                }
                None => unreachable!("predictive state exists for the predictive coding"),
            },
        };
        w.write_level(&payload)?;
        if k == 0 {
            if let Some(icc) = &opts.icc {
                w.write_icc(icc)?;
            }
            for (key, value) in &opts.text {
                w.write_text(key, value)?;
            }
        }
    }
    w.finish()?;
    Ok(())
}
