//! `.qcs` bytes → pictures: a push decoder for streams, and one-shot decoding.

// A second, levels-only decoder that cross-checks this one: for the fuzz harness
// (fuzz/harness) and the tests.
#[cfg(feature = "internals")]
mod raw;

#[cfg(feature = "internals")]
pub use raw::RawDecoder;

use std::sync::Arc;

use crate::coding::predictive::{Params, PredictiveDecoder};
use crate::coding::raw::RawUnpacker;
use crate::container::{
    Coding, Event, FormatError, Header, Layout, Metadata, Parser, ParserOptions,
};
use crate::reconstruction::{Method, SampleSet};
use crate::refinement::decode::RefinementDecoder;
use crate::sites::{fixed_position, Frame, FrameError, Quasicrystal, Site};
use crate::{Error, Limits, Result};
use image::DynamicImage;

/// A decoded picture and how much of the file it rests on.
#[derive(Clone, Debug)]
pub struct DecodedImage {
    /// The picture, in the file's layout (grey, grey+alpha, RGB or RGBA, 8 bits).
    pub image: DynamicImage,
    /// Samples the picture was rendered from.
    pub samples_used: u64,
    /// How many of those are verified by their chunk's CRC (the rest come from a partial chunk).
    pub samples_verified: u64,
    /// Levels received completely and verified, among those the picture was rendered from.
    pub levels_complete: u32,
    /// Whether this is the final picture: every sample and refinement layer of the file, all
    /// verified.
    pub is_final: bool,
    /// Whether the picture is the refinement's (version 3, once its first layer has begun):
    /// drawn on the pixel grid from the wavelet coefficients received, the levels' samples
    /// predicting the coarsest band.
    pub refined: bool,
    /// The file's ICC colour profile, if it has one and its chunk (after the first level) was
    /// received and verified: the colour space the pixels are in. `None` means sRGB.
    pub icc: Option<Vec<u8>>,
    /// The file's Exif metadata, if it has one and its chunk was received and verified
    /// ([`StreamDecoder::exif`]).
    pub exif: Option<Vec<u8>>,
}

/// A render of a [`StreamDecoder`]: a preview while samples are missing, or the final picture.
#[derive(Clone, Debug)]
pub enum Picture {
    /// Rendered from a prefix of the samples: more bytes will sharpen it.
    Preview(DecodedImage),
    /// Rendered from every sample of the file, all verified.
    Final(DecodedImage),
}

impl Picture {
    /// `d` as the final picture if it draws on the whole file, else as a preview.
    fn of(d: DecodedImage) -> Picture {
        if d.is_final {
            Picture::Final(d)
        } else {
            Picture::Preview(d)
        }
    }

    /// Whether this is the final picture.
    pub fn is_final(&self) -> bool {
        matches!(self, Picture::Final(_))
    }
    /// The decoded picture, preview or final.
    pub fn decoded(&self) -> &DecodedImage {
        match self {
            Picture::Preview(d) | Picture::Final(d) => d,
        }
    }
    /// The picture itself.
    pub fn into_image(self) -> DynamicImage {
        match self {
            Picture::Preview(d) | Picture::Final(d) => d.image,
        }
    }
}

/// A push decoder: feed bytes as they arrive, render at any moment.
///
/// ```
/// use qcs::{Method, StreamDecoder};
/// let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(32, 24, |x, y| image::Rgb([x as u8 * 8, y as u8 * 10, 90])));
/// let bytes = qcs::encode(&img, &Default::default())?;
/// let mut dec = StreamDecoder::new(qcs::Limits::default());
/// for byte in &bytes[..bytes.len() / 2] {
///     dec.push(std::slice::from_ref(byte))?; // one byte at a time
/// }
/// let preview = dec.render(Method::Gouraud, 64, 48)?; // any size, any moment
/// assert!(!preview.is_final());
/// dec.push(&bytes[bytes.len() / 2..])?;
/// assert!(dec.render(Method::Shepard, 32, 24)?.is_final());
/// # Ok::<(), qcs::Error>(())
/// ```
pub struct StreamDecoder {
    parser: Parser,
    events: Vec<Event>,
    limits: Limits,
    header: Option<Header>,
    seq: Option<Quasicrystal>,
    /// The first sites with their exact lattice points (Gouraud draws the canonical Delaunay
    /// cells), as many as were needed so far or more; shared with the thread that builds the
    /// cells of a one-shot decode.
    sites: Arc<Vec<Site>>,
    /// Decoded colours of the available samples, `channels` bytes each.
    colours: Vec<u8>,
    verified: u64,
    levels_complete: u32,
    unpacker: Option<RawUnpacker>,
    /// The predictive coding's decoder (coding 1), kept across levels.
    predictive: Option<PredictiveDecoder>,
    set: Option<SampleSet>,
    stopped: Option<FormatError>,
    metadata: Vec<Metadata>,
    /// Levels starting at or after this sample are parsed and verified but not decoded
    /// ([`ParserOptions::max_samples`]): a decode capped at fewer samples does not pay for
    /// the rest.
    max_samples: u64,
    /// Whether the level being parsed is past `max_samples`.
    skipping: bool,
    /// Set when `push` returned an error: the events after it were not applied, so the state
    /// no longer follows the parser and every further `push` must fail.
    failed: bool,
    /// The refinement (version 3), once its header has arrived and if every level is decoded.
    refinement: Option<RefinementDecoder>,
    /// Refinement layers received and verified.
    layers_complete: u32,
    /// Decode only the refinement streams a picture of this size needs (`None`: all).
    size_hint: Option<(u32, u32)>,
}

impl StreamDecoder {
    /// A decoder enforcing `limits`; a format error after the header fails the push.
    pub fn new(limits: Limits) -> Self {
        Self::with_options(ParserOptions {
            limits,
            ..Default::default()
        })
    }

    /// A decoder with parser options: `recover` keeps the longest verified prefix of a
    /// damaged file instead of failing (see [`StreamDecoder::stopped`]); `max_samples: Some(k)`
    /// decodes only the levels that start before sample `k` (the later ones are parsed and
    /// verified, not decoded), for a stream shown at a size that needs no more, e.g.
    /// [`thumbnail_samples`] for [`StreamDecoder::render_thumbnail`]. The sample limit then
    /// applies to those levels, not to the file's count.
    ///
    /// ```
    /// use qcs::format::ParserOptions;
    /// use qcs::{Method, StreamDecoder};
    /// let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(96, 96, |x, y| image::Luma([(x * y) as u8])));
    /// // A file of levels only: one sample per 4 pixels.
    /// let levels = qcs::EncodeOptions { target: qcs::Target::LevelsOnly, ..Default::default() };
    /// let bytes = qcs::encode(&img, &levels)?;
    /// let opts = ParserOptions { max_samples: Some(qcs::thumbnail_samples(6, 6)), ..Default::default() };
    /// let mut dec = StreamDecoder::with_options(opts);
    /// dec.push(&bytes)?;
    /// assert!(dec.is_complete() && dec.samples_available() < 96 * 96 / 4);
    /// let thumb = dec.render_thumbnail(Method::Gouraud, 6, 6)?;
    /// assert_eq!(thumb.decoded().samples_used, 16 * 6 * 6);
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn with_options(opts: ParserOptions) -> Self {
        let max_samples = opts.max_samples.unwrap_or(u64::MAX);
        StreamDecoder {
            limits: opts.limits.clone(),
            parser: Parser::new(opts),
            events: Vec::new(),
            header: None,
            seq: None,
            sites: Arc::default(),
            colours: Vec::new(),
            verified: 0,
            levels_complete: 0,
            unpacker: None,
            predictive: None,
            set: None,
            stopped: None,
            metadata: Vec::new(),
            max_samples,
            skipping: false,
            failed: false,
            refinement: None,
            layers_complete: 0,
            size_hint: None,
        }
    }

    /// Feeds the next bytes of the file (any length, including 0).
    ///
    /// Running out of bytes is never an error. A damaged file is an error, unless recovery was
    /// asked for; the decoder is then poisoned: every later push is [`Error::Poisoned`].
    pub fn push(&mut self, bytes: &[u8]) -> Result<()> {
        let (events, parsed) = self.parse(bytes)?;
        let r = self.apply_events(&events, parsed);
        self.events = events;
        r
    }

    /// The parser's events for `bytes`, not yet applied, and how its push ended.
    fn parse(&mut self, bytes: &[u8]) -> Result<(Vec<Event>, Result<()>)> {
        if self.failed {
            return Err(Error::Poisoned {
                object: "StreamDecoder",
            });
        }
        let mut events = std::mem::take(&mut self.events);
        events.clear();
        let parsed = self.parser.push(bytes, &mut events);
        Ok((events, parsed))
    }

    /// Applies `events` from [`Self::parse`], then reports how the parse ended. An error (from
    /// either, e.g. a header the site construction cannot use) leaves the parser ahead of this
    /// decoder: it poisons it, or the next push would see levels without a header.
    fn apply_events(&mut self, events: &[Event], parsed: Result<()>) -> Result<()> {
        let r = events.iter().try_for_each(|e| self.apply(e)).and(parsed);
        if r.is_err() {
            self.failed = true;
        }
        r
    }

    fn apply(&mut self, e: &Event) -> Result<()> {
        match e {
            Event::Header(h) => {
                let frame = match h.lattice {
                    Some(l) => Frame {
                        root_len: l.root_length,
                        origin: [l.origin_x, l.origin_y],
                    },
                    None => Frame::default_for(h.width, h.height),
                };
                // spec/sites.md §2 bounds the frame (1 ≤ W, H ≤ 65535, 1 px ≤ root ≤ 256 px): a
                // header outside them is malformed, not a bad caller parameter, reported at
                // the field where the parser read it.
                let at = self.parser.header_offsets();
                let seq = Quasicrystal::with_frame(h.width, h.height, frame).map_err(|e| {
                    let (field, offset, value, expected) = match (e, h.lattice) {
                        (FrameError::RootLength { root_len }, Some(_)) => (
                            "lattice root length",
                            at.root_length,
                            root_len as u64,
                            "65536..=16777216",
                        ),
                        (FrameError::Size { .. }, _) if h.width > 65535 => {
                            ("width", at.width, h.width as u64, "≤ 65535")
                        }
                        _ => ("height", at.height, h.height as u64, "≤ 65535"),
                    };
                    Error::Format(FormatError::InvalidField {
                        field,
                        offset,
                        value,
                        expected,
                    })
                })?;
                if h.total_samples > h.width as u64 * h.height as u64 {
                    return Err(Error::Format(FormatError::TooManySamples {
                        samples: h.total_samples,
                        pixels: h.width as u64 * h.height as u64,
                    }));
                }
                if let Coding::Predictive { step } = h.coding {
                    let params = Params { step };
                    self.predictive = Some(PredictiveDecoder::new(
                        params,
                        h.layout.channels(),
                        h.width,
                        h.height,
                    )?);
                }
                self.seq = Some(seq);
                self.header = Some(h.clone());
            }
            Event::LevelStart {
                samples,
                payload_len,
                ..
            } => {
                let h = self.header.as_ref().expect("header precedes levels");
                self.skipping = samples.start >= self.max_samples;
                if self.skipping {
                    self.unpacker = None;
                    return Ok(());
                }
                self.unpacker = match h.coding {
                    Coding::Raw { bits } => Some(RawUnpacker::new(
                        h.layout.channels(),
                        bits,
                        samples.end - samples.start,
                    )?),
                    Coding::Predictive { .. } => {
                        let frame = self.seq.expect("header precedes levels").frame();
                        let fixed: Vec<_> = self.sites_to(samples.end as usize)
                            [samples.start as usize..]
                            .iter()
                            .map(|s| fixed_position(&frame, s.lattice))
                            .collect();
                        if let Some(p) = &mut self.predictive {
                            p.start_level(&fixed, *payload_len as usize)?;
                            // An empty payload (every residual zero) sends no data event, and
                            // decodes from no bytes at all.
                            p.push(&[], &mut self.colours)?;
                        }
                        None
                    }
                };
            }
            Event::LevelData { .. } if self.skipping => {}
            Event::LevelData { bytes, .. } => {
                if let Some(u) = &mut self.unpacker {
                    u.push(bytes, &mut self.colours);
                } else if let Some(p) = &mut self.predictive {
                    p.push(bytes, &mut self.colours)?;
                }
            }
            Event::LevelVerified { .. } => {
                self.levels_complete += 1;
                self.verified = self.sample_count();
                self.unpacker = None;
            }
            Event::Stopped { error } => {
                let c = self.channels();
                self.colours.truncate(self.verified as usize * c);
                self.unpacker = None;
                self.stopped = Some(error.clone());
                if let Some(r) = &mut self.refinement {
                    r.drop_unverified();
                }
            }
            Event::Metadata { metadata, .. } => self.metadata.push(metadata.clone()),
            Event::RefinementHeader(r) => {
                let h = self.header.clone().expect("header precedes the refinement");
                // The refinement draws on every level; a decoder capped below them (a
                // thumbnail of a level-only preview) leaves it.
                if self.sample_count() == h.total_samples {
                    let n = h.total_samples as usize;
                    let frame = self.seq.expect("sites imply a header").frame();
                    let positions: Vec<[i64; 2]> = self
                        .sites_to(n)
                        .iter()
                        .map(|s| fixed_position(&frame, s.lattice))
                        .collect();
                    let mut dec = RefinementDecoder::new(
                        r,
                        h.width,
                        h.height,
                        self.channels(),
                        &positions,
                        &self.colours,
                        usize::MAX,
                    );
                    if let Some((w, ht)) = self.size_hint {
                        dec.keep_streams_for_thumbnail(w, ht);
                    }
                    self.refinement = Some(dec);
                }
            }
            Event::RefinementData { stream, bytes, .. } => {
                if let Some(r) = &mut self.refinement {
                    r.push(*stream as usize, bytes);
                }
            }
            Event::LayerVerified { .. } => {
                self.layers_complete += 1;
                if let Some(r) = &mut self.refinement {
                    r.verify();
                }
            }
            Event::LevelsComplete | Event::Skipped { .. } | Event::LayerStart { .. } => {}
        }
        Ok(())
    }

    fn channels(&self) -> usize {
        self.header
            .as_ref()
            .map_or(1, |h| h.layout.channels() as usize)
    }

    fn sample_count(&self) -> u64 {
        (self.colours.len() / self.channels()) as u64
    }

    /// The header, once it has arrived complete and verified.
    pub fn header(&self) -> Option<&Header> {
        self.header.as_ref()
    }

    /// Samples whose bytes have all arrived (verified or not).
    pub fn samples_available(&self) -> u64 {
        self.sample_count()
    }

    /// Samples verified by their chunk's CRC.
    pub fn samples_verified(&self) -> u64 {
        self.verified
    }

    /// Levels received completely and verified.
    pub fn levels_complete(&self) -> u32 {
        self.levels_complete
    }

    /// Whether every level (and every refinement layer) of the file has arrived and is
    /// verified (with [`ParserOptions::max_samples`], those past it are verified but not
    /// decoded).
    pub fn is_complete(&self) -> bool {
        self.header.as_ref().is_some_and(|h| {
            self.levels_complete == h.level_count()
                && (!h.refinement
                    || self
                        .parser
                        .refinement()
                        .is_some_and(|r| self.layers_complete == r.layers))
        })
    }

    /// Refinement layers received completely and verified.
    pub fn layers_complete(&self) -> u32 {
        self.layers_complete
    }

    /// Decode only the refinement streams that a thumbnail of `width × height` needs: a
    /// decoder that only ever renders such thumbnails skips the rest of the refinement.
    pub(crate) fn with_thumbnail_size(mut self, width: u32, height: u32) -> Self {
        self.size_hint = Some((width, height));
        self
    }

    /// In recovery mode, the error that stopped decoding (everything verified before it is kept).
    pub fn stopped(&self) -> Option<&FormatError> {
        self.stopped.as_ref()
    }

    /// Metadata chunks (ICC profile, Exif, text) received so far.
    pub fn metadata(&self) -> &[Metadata] {
        &self.metadata
    }

    /// The file's ICC colour profile, once its chunk is received and verified (`None` before,
    /// and for a file without one: sRGB).
    ///
    /// ```
    /// use qcs::{EncodeOptions, StreamDecoder};
    /// let img = image::DynamicImage::ImageRgb8(image::RgbImage::new(8, 8));
    /// let opts = EncodeOptions { icc: Some(b"a profile".to_vec()), ..Default::default() };
    /// let bytes = qcs::encode(&img, &opts)?;
    /// let mut dec = StreamDecoder::new(qcs::Limits::default());
    /// dec.push(&bytes)?;
    /// assert_eq!(dec.icc_profile(), Some(&b"a profile"[..]));
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn icc_profile(&self) -> Option<&[u8]> {
        self.metadata.iter().find_map(|m| match m {
            Metadata::Icc(icc) => Some(&icc[..]),
            _ => None,
        })
    }

    /// The file's Exif metadata (a TIFF header and its IFDs, as PNG's `eXIf`), once its chunk
    /// is received and verified (`None` before, and for a file without one). `qcs encode`
    /// stores a photo's, its orientation reset: the pixels are stored upright.
    ///
    /// ```
    /// use qcs::{EncodeOptions, StreamDecoder};
    /// let img = image::DynamicImage::ImageRgb8(image::RgbImage::new(8, 8));
    /// let opts = EncodeOptions { exif: Some(b"MM\0*\0\0\0\x08\0\0".to_vec()), ..Default::default() };
    /// let bytes = qcs::encode(&img, &opts)?;
    /// let mut dec = StreamDecoder::new(qcs::Limits::default());
    /// dec.push(&bytes)?;
    /// assert_eq!(dec.exif(), Some(&b"MM\0*\0\0\0\x08\0\0"[..]));
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn exif(&self) -> Option<&[u8]> {
        self.metadata.iter().find_map(|m| match m {
            Metadata::Exif(exif) => Some(&exif[..]),
            _ => None,
        })
    }

    /// Copies of the ICC profile and the Exif, for a [`DecodedImage`].
    fn owned_metadata(&self) -> (Option<Vec<u8>>, Option<Vec<u8>>) {
        let icc = self.icc_profile().map(<[u8]>::to_vec);
        (icc, self.exif().map(<[u8]>::to_vec))
    }

    /// Sites (exact lattice point and pixel position) and colours (in the file's layout) of
    /// the first `k` available samples, e.g. for the stylized renderers.
    pub fn samples(&mut self, k: u64) -> (&[Site], &[u8]) {
        let k = k.min(self.sample_count()) as usize;
        self.sites_to(k);
        let c = self.channels();
        (&self.sites[..k], &self.colours[..k * c])
    }

    /// The first `k` sites (`k` at most the header's sample count), computed if not yet known.
    fn sites_to(&mut self, k: usize) -> &[Site] {
        if self.sites.len() < k {
            let seq = self.seq.expect("sites imply a header");
            let total = self.header.as_ref().map_or(0, |h| h.total_samples) as usize;
            // Grow geometrically: total work stays O(n log n) however the bytes arrive. Twice
            // what is asked: levels double, so the next level's sites come with this one's.
            let target = (2 * k).max(2 * self.sites.len()).min(total).max(k);
            self.sites = Arc::new(seq.first(target));
        }
        &self.sites[..k]
    }

    /// Renders the picture from every sample received so far, at `width × height`.
    ///
    /// It is the picture the spec fixes at the image's size, drawn whole and then averaged to
    /// the output: for a preview much smaller than the image (a 1000 × 750 view of a
    /// 12-megapixel photo), [`StreamDecoder::render_thumbnail`] reads only the coarse bands
    /// and costs about half as much.
    ///
    /// Before the header is complete this is [`Error::NeedMoreData`].
    pub fn render(&mut self, method: Method, width: u32, height: u32) -> Result<Picture> {
        self.render_first(u64::MAX, method, width, height)
    }

    /// Renders the picture from the first `k` samples received so far (or all, if fewer), at
    /// `width × height`: a [`Picture::Preview`] unless it draws on every sample of the file.
    /// With `k` at least the file's sample count, a file with a refinement gives the
    /// refinement's picture ([`StreamDecoder::render`]).
    ///
    /// ```
    /// use qcs::{Method, StreamDecoder};
    /// let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(64, 64, |x, y| image::Luma([(x ^ y) as u8])));
    /// let levels = qcs::EncodeOptions { target: qcs::Target::LevelsOnly, ..Default::default() };
    /// let bytes = qcs::encode(&img, &levels)?;
    /// let mut dec = StreamDecoder::new(qcs::Limits::default());
    /// dec.push(&bytes)?;
    /// let first = dec.render_first(100, Method::Gouraud, 16, 16)?;
    /// assert_eq!(first.decoded().samples_used, 100);
    /// assert!(!first.is_final() && dec.is_complete());
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn render_first(
        &mut self,
        k: u64,
        method: Method,
        width: u32,
        height: u32,
    ) -> Result<Picture> {
        let h = self.header.clone().ok_or(Error::NeedMoreData)?;
        self.check_output_size(width, height)?;
        if k >= h.total_samples {
            if let Some(d) = self.render_refined(&h, width, height, false, false) {
                return Ok(Picture::of(d));
            }
        }
        let n = self.sample_count().min(k);
        let c = self.channels();
        // A kept set with more samples than asked for now (a recovery dropped a damaged
        // chunk's, or a smaller `k`) is rebuilt.
        let mut set = match self.set.take() {
            Some(set) if set.len() as u64 <= n => set,
            _ => self.new_set(&h),
        };
        let have = set.len();
        let (sites, col) = self.samples(n);
        for k in have..n as usize {
            set.push_site(&sites[k], &col[k * c..k * c + c]);
        }
        let pixels = set.render(method, width, height);
        self.set = Some(set);
        let (icc, exif) = self.owned_metadata();
        let decoded = DecodedImage {
            image: to_image(h.layout, width, height, pixels),
            samples_used: n,
            samples_verified: self.verified.min(n),
            levels_complete: self.levels_within(&h, n),
            is_final: n == h.total_samples && self.is_complete() && !h.refinement,
            refined: false,
            icc,
            exif,
        };
        Ok(Picture::of(decoded))
    }

    /// A thumbnail of what has arrived (see [`DecodeOptions::thumbnail`]): from the
    /// refinement's coarse bands, or, before the refinement or in a file of levels only, from
    /// at most the first 16 samples per output pixel, each pixel the mean of a square of
    /// pixels rendered at its subpixel centres. A [`Picture::Preview`] unless it draws on
    /// everything the file holds.
    ///
    /// ```
    /// use qcs::{Method, StreamDecoder};
    /// let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(96, 96, |x, y| image::Luma([(x ^ y) as u8])));
    /// let levels = qcs::EncodeOptions { target: qcs::Target::LevelsOnly, ..Default::default() };
    /// let bytes = qcs::encode(&img, &levels)?;
    /// let mut dec = StreamDecoder::new(qcs::Limits::default());
    /// dec.push(&bytes)?;
    /// let thumb = dec.render_thumbnail(Method::Gouraud, 6, 6)?;
    /// assert_eq!(thumb.decoded().samples_used, 16 * 6 * 6);
    /// assert_eq!(thumb.decoded().image.width(), 6);
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn render_thumbnail(&mut self, method: Method, width: u32, height: u32) -> Result<Picture> {
        self.render_thumbnail_first(u64::MAX, method, width, height)
    }

    /// [`StreamDecoder::render_thumbnail`] from at most the first `k` samples (with `k` at
    /// least the file's sample count, a file with a refinement gives the refinement's
    /// thumbnail), as [`StreamDecoder::render_first`] is [`StreamDecoder::render`].
    pub(crate) fn render_thumbnail_first(
        &mut self,
        k: u64,
        method: Method,
        width: u32,
        height: u32,
    ) -> Result<Picture> {
        self.check_output_size(width, height)?;
        if let Some(h) = self.header.clone().filter(|h| k >= h.total_samples) {
            if let Some(d) = self.render_refined(&h, width, height, true, false) {
                return Ok(Picture::of(d));
            }
        }
        let k = self
            .sample_count()
            .min(thumbnail_samples(width, height))
            .min(k);
        let f = thumbnail_factor(k, width, height, &self.limits);
        let pic = self.render_first(k, method, width * f, height * f)?;
        Ok(match pic {
            Picture::Preview(d) => Picture::Preview(shrink(d, f)),
            Picture::Final(d) => Picture::Final(shrink(d, f)),
        })
    }

    /// The refinement's picture (or a thumbnail of it), once its header has arrived; if
    /// `last`, a one-shot decode's, which frees the refinement's state as it draws.
    fn render_refined(
        &mut self,
        h: &Header,
        width: u32,
        height: u32,
        thumbnail: bool,
        last: bool,
    ) -> Option<DecodedImage> {
        let complete = self.is_complete();
        let (icc, exif) = self.owned_metadata();
        let r = self.refinement.as_mut()?;
        let pixels = if thumbnail {
            r.render_thumbnail(width, height, last)
        } else {
            r.render(width, height, last)
        };
        Some(DecodedImage {
            image: to_image(h.layout, width, height, pixels),
            samples_used: h.total_samples,
            samples_verified: self.verified,
            levels_complete: self.levels_complete,
            is_final: complete,
            refined: true,
            icc,
            exif,
        })
    }

    /// Levels complete and verified within the first `used` samples.
    fn levels_within(&self, h: &Header, used: u64) -> u32 {
        (0..self.levels_complete)
            .take_while(|&l| h.level_range(l).is_some_and(|r| r.end <= used))
            .count() as u32
    }

    /// An empty sample set for the file's source size, layout and lattice frame.
    fn new_set(&self, h: &Header) -> SampleSet {
        let set = SampleSet::new(h.width, h.height, self.channels());
        match &self.seq {
            Some(seq) => set.with_frame(seq.frame()),
            None => set,
        }
    }

    /// Checks a requested output size before anything is allocated: the limits, a non-empty
    /// size, and a byte count (`width × height × channels`) that an allocation can hold.
    fn check_output_size(&self, width: u32, height: u32) -> Result<()> {
        self.limits.check_output(width as u64, height as u64)?;
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                "output size",
                format_args!("{width}×{height}"),
                "at least 1×1",
            ));
        }
        let bytes = (width as u64 * height as u64).saturating_mul(self.channels() as u64);
        if bytes > isize::MAX as u64 {
            return Err(Error::OutOfMemory { bytes });
        }
        if let Some(h) = &self.header {
            let decoded = h.samples_of_levels_before(self.max_samples);
            self.limits
                .check_alloc(decoded, h.coefficients_decoded(decoded), bytes)?;
        }
        Ok(())
    }

    /// Renders from the first `k` available samples only. `seed`, if given, is a set of the
    /// first samples (blank colours) whose cells are built: it is coloured and completed
    /// rather than built again. A one-shot decode's last step: the decoder is consumed, so
    /// that what the picture no longer needs (the colour decoder's state, the sites, the
    /// cells' insertion structure) is freed before the picture is allocated.
    #[allow(clippy::too_many_arguments)]
    fn render_prefix(
        mut self,
        k: u64,
        method: Method,
        width: u32,
        height: u32,
        seed: Option<SampleSet>,
        thumbnail: bool,
    ) -> Result<DecodedImage> {
        let h = self.header.clone().ok_or(Error::NeedMoreData)?;
        self.check_output_size(width, height)?;
        if k >= h.total_samples {
            if let Some(d) = self.render_refined(&h, width, height, thumbnail, true) {
                return Ok(d);
            }
        }
        self.predictive = None;
        self.set = None;
        let c = self.channels();
        let fresh = self.new_set(&h);
        let (sites, col) = self.samples(k);
        let used = sites.len() as u64;
        let mut set = match seed {
            Some(set) if set.len() <= sites.len() => set,
            _ => fresh,
        };
        let have = set.len();
        set.reserve(sites.len() - have);
        set.recolour(0, &col[..have * c]);
        for (k, s) in sites.iter().enumerate().skip(have) {
            set.push_site(s, &col[k * c..k * c + c]);
        }
        let (icc, exif) = self.owned_metadata();
        let (verified, levels) = (self.verified, self.levels_within(&h, used));
        drop(self);
        set.settle(method);
        let pixels = set.render(method, width, height);
        Ok(DecodedImage {
            image: to_image(h.layout, width, height, pixels),
            samples_used: used,
            samples_verified: verified.min(used),
            levels_complete: levels,
            is_final: used == h.total_samples && verified == h.total_samples && !h.refinement,
            refined: false,
            icc,
            exif,
        })
    }
}

fn to_image(layout: Layout, w: u32, h: u32, px: Vec<u8>) -> DynamicImage {
    let bad = "render returns w×h×channels bytes";
    match layout {
        Layout::Grey => DynamicImage::ImageLuma8(image::GrayImage::from_raw(w, h, px).expect(bad)),
        Layout::GreyAlpha => {
            DynamicImage::ImageLumaA8(image::GrayAlphaImage::from_raw(w, h, px).expect(bad))
        }
        Layout::Rgb => DynamicImage::ImageRgb8(image::RgbImage::from_raw(w, h, px).expect(bad)),
        Layout::Rgba => DynamicImage::ImageRgba8(image::RgbaImage::from_raw(w, h, px).expect(bad)),
    }
}

/// How to decode a whole buffer.
///
/// ```
/// let opts = qcs::DecodeOptions { size: Some((100, 50)), max_bytes: Some(200), ..Default::default() };
/// assert_eq!(opts.method, qcs::Method::Gouraud);
/// ```
#[derive(Clone, Debug)]
pub struct DecodeOptions {
    /// Reconstruction method (default Gouraud).
    pub method: Method,
    /// Output size; `None` for the image's own size.
    pub size: Option<(u32, u32)>,
    /// Use at most this many samples. The levels after the one that holds the last of them
    /// are read only to check them, not decoded, so the decode costs what those samples cost
    /// (see [`DecodeOptions::thumbnail`]), and [`Limits::max_samples`] applies to the levels
    /// decoded, not to the file's count.
    pub max_samples: Option<u64>,
    /// Use only the first this many bytes, as a cut download would.
    pub max_bytes: Option<usize>,
    /// Render a thumbnail ([`DecodeOptions::thumbnail`]): from the refinement's coarse bands,
    /// or, of levels alone, from at most 16 samples per output pixel. Off by default: the
    /// spec's picture at the output size, from everything the file holds.
    pub thumbnail: bool,
    /// Resource limits.
    pub limits: Limits,
    /// Return the longest verified prefix of a damaged file instead of an error.
    pub recover: bool,
}

impl Default for DecodeOptions {
    fn default() -> Self {
        DecodeOptions {
            method: Method::Gouraud,
            size: None,
            max_samples: None,
            max_bytes: None,
            thumbnail: false,
            limits: Limits::default(),
            recover: false,
        }
    }
}

/// Samples per output pixel a thumbnail draws on at most.
const THUMBNAIL_SAMPLES_PER_PIXEL: u64 = 16;

/// Largest side of the square of rendered pixels a thumbnail pixel averages.
const THUMBNAIL_MAX_FACTOR: u32 = 4;

/// The most samples a `width × height` thumbnail ([`DecodeOptions::thumbnail`],
/// [`StreamDecoder::render_thumbnail`]) draws on: 16 per pixel.
///
/// ```
/// assert_eq!(qcs::thumbnail_samples(120, 90), 172_800);
/// ```
pub fn thumbnail_samples(width: u32, height: u32) -> u64 {
    (width as u64 * height as u64).saturating_mul(THUMBNAIL_SAMPLES_PER_PIXEL)
}

/// The side f of the square of rendered pixels each pixel of a `width × height` thumbnail
/// from `k` samples averages: about one sample per rendered pixel (f² ≈ k / pixels, rounded),
/// from 1 to [`THUMBNAIL_MAX_FACTOR`], and no more than `limits` allow to render.
fn thumbnail_factor(k: u64, width: u32, height: u32, limits: &Limits) -> u32 {
    let pixels = (width as u64 * height as u64).max(1);
    let mut f = ((k as f64 / pixels as f64).sqrt().round() as u32).clamp(1, THUMBNAIL_MAX_FACTOR);
    let fits = |f: u32| {
        let (w, h) = (width as u64 * f as u64, height as u64 * f as u64);
        limits.check_output(w, h).is_ok() && w <= u32::MAX as u64 && h <= u32::MAX as u64
    };
    while f > 1 && !fits(f) {
        f -= 1;
    }
    f
}

/// `d` with each `f × f` square of its pixels averaged into one (`image`'s box filter).
fn shrink(mut d: DecodedImage, f: u32) -> DecodedImage {
    if f > 1 {
        let (w, h) = (d.image.width() / f, d.image.height() / f);
        d.image = d.image.thumbnail_exact(w, h);
    }
    d
}

impl DecodeOptions {
    /// Options for a `width × height` thumbnail: a picture much smaller than the image, as
    /// close to an area-averaged downscale of it as the file allows, at a cost that grows
    /// with the thumbnail, not the file.
    ///
    /// With a refinement (format version 3), it decodes only the coarse bands: those of the
    /// deepest transform level at least twice the thumbnail's size, less a pixel (a 1/8-size
    /// thumbnail decodes 1/16 of the coefficients), draws the image-size picture with the
    /// finer bands taken as zero, and averages it over each thumbnail pixel. The spec's picture at
    /// that size ([`DecodeOptions::size`] alone) is the image-size picture averaged over each
    /// pixel, which decodes every band; the two differ by about 40 dB PSNR (README,
    /// *Thumbnails*).
    ///
    /// From levels only (a version-2 file, or a prefix that ends before the refinement), it
    /// draws on at most the first 16 samples per output pixel (any prefix of a file is
    /// spread evenly over the image, so they are a coarser sampling of the whole picture; the
    /// rest of the file is read only to check it), renders them at f × f times the size, f²
    /// about the samples per output pixel (1 to 4), and averages each f × f square into a
    /// pixel. The plain render at the pixel centres aliases once samples are denser than the
    /// output pixels: each centre picks up the detail at that one point. A file with more
    /// samples than [`Limits::max_samples`] has a thumbnail when the levels it draws on fit in
    /// the limit.
    ///
    /// ```
    /// let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(96, 96, |x, y| image::Luma([(x * y) as u8])));
    /// let bytes = qcs::encode(&img, &Default::default())?;
    /// let thumb = qcs::decode(&bytes, &qcs::DecodeOptions::thumbnail(12, 12))?;
    /// assert!(thumb.refined && thumb.is_final && thumb.image.width() == 12);
    /// // From the levels of a version-2 file: 16 samples per thumbnail pixel.
    /// let levels = qcs::EncodeOptions { target: qcs::Target::LevelsOnly, ..Default::default() };
    /// let bytes = qcs::encode(&img, &levels)?;
    /// let thumb = qcs::decode(&bytes, &qcs::DecodeOptions::thumbnail(6, 6))?;
    /// assert_eq!((thumb.image.width(), thumb.samples_used), (6, 16 * 6 * 6));
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn thumbnail(width: u32, height: u32) -> Self {
        DecodeOptions {
            size: Some((width, height)),
            thumbnail: true,
            ..Default::default()
        }
    }
}

/// Decodes a `.qcs` buffer (or any prefix of one) to a picture.
///
/// A prefix that ends inside the header is [`Error::NeedMoreData`]; any longer prefix is a
/// picture ([`DecodedImage::is_final`] says whether it is the whole file).
///
/// Work is spread over the current `rayon` pool: the rows of the picture, and for
/// [`Method::Gouraud`] the cells, which are built while the colours decode. Run it inside a
/// one-thread pool (`ThreadPool::install`) to keep it on one core; the picture is the same.
///
/// ```
/// let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(30, 20, |x, _| image::Luma([x as u8 * 8])));
/// let bytes = qcs::encode(&img, &Default::default())?;
/// let cut = qcs::decode(&bytes, &qcs::DecodeOptions { max_bytes: Some(bytes.len() - 10), ..Default::default() })?;
/// assert!(!cut.is_final && cut.samples_used > 0);
/// assert!(matches!(qcs::decode(&bytes[..5], &Default::default()), Err(qcs::Error::NeedMoreData)));
/// # Ok::<(), qcs::Error>(())
/// ```
pub fn decode(bytes: &[u8], opts: &DecodeOptions) -> Result<DecodedImage> {
    let bytes = &bytes[..opts.max_bytes.unwrap_or(usize::MAX).min(bytes.len())];
    let mut max_samples = opts.max_samples.unwrap_or(u64::MAX);
    // A thumbnail at the image's own size draws on every sample anyway.
    if let (true, Some((w, h))) = (opts.thumbnail, opts.size) {
        max_samples = max_samples.min(thumbnail_samples(w, h));
    }
    let mut dec = StreamDecoder::with_options(ParserOptions {
        limits: opts.limits.clone(),
        recover: opts.recover,
        max_samples: Some(max_samples),
    });
    if let (true, Some((w, h))) = (opts.thumbnail, opts.size) {
        dec = dec.with_thumbnail_size(w, h);
    }
    let build_cells = opts.method == Method::Gouraud && rayon::current_num_threads() > 1;
    let seed = push_whole(&mut dec, bytes, max_samples, build_cells)?;
    let h = dec.header().cloned().ok_or(Error::NeedMoreData)?;
    let (w, ht) = opts.size.unwrap_or((h.width, h.height));
    let k = max_samples.min(dec.samples_available());
    if !opts.thumbnail || dec.refinement.is_some() {
        return dec.render_prefix(k, opts.method, w, ht, seed, opts.thumbnail);
    }
    dec.check_output_size(w, ht)?;
    let f = thumbnail_factor(k, w, ht, &opts.limits);
    let d = dec.render_prefix(k, opts.method, w * f, ht * f, seed, false)?;
    Ok(shrink(d, f))
}

/// Pushes `bytes` (a whole buffer) into the fresh decoder `dec`, parsing them once: the parser
/// reads the whole buffer (its limits checked at the header, before any work) before its
/// events are applied, so that the sites of the levels present (up to the one holding sample
/// `max_samples`, where `dec` stops decoding) are computed at once. If `build_cells`,
/// meanwhile, on another thread of the pool, the cells of the samples that are surely there
/// (those of the verified levels, at most `max_samples`) are built: the cells depend only on
/// the header, so they need not wait for the colours.
fn push_whole(
    dec: &mut StreamDecoder,
    bytes: &[u8],
    max_samples: u64,
    build_cells: bool,
) -> Result<Option<SampleSet>> {
    let (events, parsed) = dec.parse(bytes)?;
    let heads = events
        .iter()
        .take_while(|e| matches!(e, Event::Header(_)))
        .count();
    let (head, rest) = events.split_at(heads);
    dec.apply_events(head, Ok(()))?;
    let (Some(h), Some(seq)) = (dec.header().cloned(), dec.seq) else {
        return dec.apply_events(rest, parsed).map(|_| None);
    };
    let present = (rest.iter())
        .filter_map(|e| match e {
            Event::LevelStart { samples, .. } => Some(samples.end),
            _ => None,
        })
        .max()
        .unwrap_or(0)
        .min(h.total_samples);
    // The levels that start at or after `max_samples` are only verified (`ParserOptions::max_samples`).
    let present = present.min(h.samples_of_levels_before(max_samples)) as usize;
    // The levels' colours need their sites' positions, the cells the sites.
    dec.sites = Arc::new(seq.first(present));
    if !build_cells {
        return dec.apply_events(rest, parsed).map(|_| None);
    }
    let verified = dec.parser.progress().samples_verified;
    let sure = verified.min(max_samples).min(present as u64) as usize;
    let mut set = dec.new_set(&h);
    let blank = vec![0; dec.channels()];
    let sites = Arc::clone(&dec.sites);
    let (pushed, seed) = rayon::join(
        || dec.apply_events(rest, parsed),
        move || {
            // Room for every sample present: the render adds those beyond `sure`.
            set.reserve(present);
            for s in &sites[..sure] {
                set.push_site(s, &blank);
            }
            // With every sample present verified, the render adds none.
            set.build_cells(sure == present);
            set
        },
    );
    pushed?;
    Ok(Some(seed))
}
