//! A pull decoder over `std::io::Read`: previews as the bytes of a file or socket arrive.

use crate::container::ParserOptions;
use crate::decoder::{thumbnail_samples, DecodeOptions, Picture, StreamDecoder};
use crate::reconstruction::Method;
use crate::{Error, Result};
use std::io::Read;

/// When [`Previews`] yields a picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cadence {
    /// After every completed level and refinement layer (and at the end of the stream).
    PerLevel,
    /// After every `K` bytes read (and at the end of the stream), however the reader splits
    /// them.
    EveryBytes(usize),
}

/// An iterator of pictures read from a stream: previews, then the final picture.
///
/// Bytes after the last level (metadata chunks) are still read and checked after the final
/// picture: damage there ends the iteration with an error, as [`crate::decode`] reports it. A
/// stream that ends before its header is complete yields [`crate::Error::NeedMoreData`]. An
/// error is always the last item. For a `size` much smaller than the image,
/// [`DecodeOptions::thumbnail`] draws better pictures for less work.
///
/// ```
/// use qcs::{Cadence, Previews};
/// let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(96, 64, |x, y| image::Rgb([x as u8 * 2, y as u8 * 3, (x * y) as u8])));
/// let bytes = qcs::encode(&img, &qcs::EncodeOptions::default())?;
/// let pics: Vec<_> = Previews::new(&bytes[..], Cadence::PerLevel, &Default::default())
///     .collect::<Result<_, _>>()?;
/// // A picture for the level of samples and one per layer of the refinement.
/// assert!(pics.len() > 3);
/// assert!(pics.last().unwrap().is_final());
/// assert!(pics[..pics.len() - 1].iter().all(|p| !p.is_final()));
/// # Ok::<(), qcs::Error>(())
/// ```
pub struct Previews<R> {
    reader: R,
    decoder: StreamDecoder,
    cadence: Cadence,
    method: Method,
    size: Option<(u32, u32)>,
    /// Pictures are thumbnails ([`DecodeOptions::thumbnail`]).
    thumbnail: bool,
    /// Pictures draw on at most this many samples ([`DecodeOptions::max_samples`]).
    max_samples: u64,
    /// Bytes still to read ([`DecodeOptions::max_bytes`]).
    left: usize,
    levels_seen: u32,
    buf: Vec<u8>,
    pos: usize,
    len: usize,
    /// Bytes pushed since the last [`Cadence::EveryBytes`] picture.
    since: usize,
    /// Whether the last picture was yielded (the rest of the stream is only checked).
    last_sent: bool,
    finished: bool,
}

impl<R: Read> Previews<R> {
    /// Reads `reader` and yields a picture at each `cadence` step, drawn as [`crate::decode`]
    /// draws one with `opts` from the bytes read so far: with its method, at its size (default:
    /// the image's own), from at most its `max_samples`, reading at most its `max_bytes`, and
    /// with its limits and recovery. Only the levels those pictures draw on are decoded (the
    /// rest are read and checked).
    ///
    /// As thumbnails (`opts.thumbnail`), each picture draws on at most the first 16 samples per
    /// output pixel, each pixel the mean of a square rendered at its subpixel centres, and
    /// the last picture is the first one drawn on all of them: it is [`Picture::Final`] only if
    /// that is every sample of the file. (At the image's own size a thumbnail is the plain
    /// picture.)
    ///
    /// ```
    /// use qcs::{Cadence, DecodeOptions, Previews};
    /// let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(96, 96, |x, y| image::Luma([(x ^ y) as u8])));
    /// let levels = qcs::EncodeOptions { target: qcs::Target::LevelsOnly, ..Default::default() };
    /// let bytes = qcs::encode(&img, &levels)?; // 2304 samples
    /// let opts = DecodeOptions { size: Some((6, 6)), thumbnail: true, ..Default::default() };
    /// let pics: Vec<_> = Previews::new(&bytes[..], Cadence::PerLevel, &opts)
    ///     .collect::<Result<_, _>>()?;
    /// let last = pics.last().unwrap().decoded();
    /// assert_eq!((last.image.width(), last.samples_used), (6, 16 * 6 * 6));
    /// // The last picture is the one-shot decode's.
    /// assert_eq!(last.image, qcs::decode(&bytes, &opts)?.image);
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn new(reader: R, cadence: Cadence, opts: &DecodeOptions) -> Self {
        // A read size only: pictures follow the bytes pushed, not the reads.
        let chunk = match cadence {
            Cadence::EveryBytes(k) => k.clamp(1 << 12, 1 << 20),
            Cadence::PerLevel => 1 << 12,
        };
        let max_samples = opts.max_samples.unwrap_or(u64::MAX);
        // As `decode`: decode only the levels the pictures draw on.
        let thumbnail_size = opts.size.filter(|_| opts.thumbnail);
        let decoded = thumbnail_size.map_or(max_samples, |(w, h)| {
            max_samples.min(thumbnail_samples(w, h))
        });
        let mut decoder = StreamDecoder::with_options(ParserOptions {
            limits: opts.limits.clone(),
            recover: opts.recover,
            max_samples: (decoded < u64::MAX).then_some(decoded),
        });
        if let Some((w, h)) = thumbnail_size {
            decoder = decoder.with_thumbnail_size(w, h);
        }
        Previews {
            reader,
            decoder,
            cadence,
            method: opts.method,
            size: opts.size,
            thumbnail: opts.thumbnail,
            max_samples,
            left: opts.max_bytes.unwrap_or(usize::MAX),
            levels_seen: 0,
            buf: vec![0; chunk],
            pos: 0,
            len: 0,
            since: 0,
            last_sent: false,
            finished: false,
        }
    }

    /// The decoder, e.g. for its header and sample counts.
    pub fn decoder(&self) -> &StreamDecoder {
        &self.decoder
    }

    /// `(width, height)` of the pictures, once the header is in.
    fn size(&self) -> Option<(u32, u32)> {
        let h = self.decoder.header()?;
        Some(self.size.unwrap_or((h.width, h.height)))
    }

    /// The picture now; an error (e.g. an output size beyond the limits, which every later
    /// picture would repeat) ends the iteration.
    fn picture(&mut self) -> Option<Result<Picture>> {
        let (w, h) = self.size()?;
        let k = self.max_samples;
        let r = match self.thumbnail {
            true => self.decoder.render_thumbnail_first(k, self.method, w, h),
            false => self.decoder.render_first(k, self.method, w, h),
        };
        if r.is_err() {
            (self.finished, self.pos) = (true, self.len);
        }
        Some(r)
    }

    /// Levels and refinement layers complete.
    fn parts(&self) -> u32 {
        self.decoder.levels_complete() + self.decoder.layers_complete()
    }

    /// Whether every sample the pictures draw on has arrived and is verified: no later byte
    /// can change the picture.
    fn done(&self) -> bool {
        let verified = self.decoder.samples_verified();
        match (self.thumbnail, self.size(), self.decoder.header()) {
            (true, Some((w, h)), Some(head)) if !head.refinement => {
                verified >= (head.total_samples.min(thumbnail_samples(w, h))).min(self.max_samples)
            }
            (_, _, Some(head)) if self.max_samples < head.total_samples => {
                verified >= self.max_samples
            }
            _ => self.decoder.is_complete(),
        }
    }
}

impl<R: Read> Iterator for Previews<R> {
    type Item = Result<Picture>;

    fn next(&mut self) -> Option<Result<Picture>> {
        loop {
            if self.pos == self.len {
                if self.finished {
                    return None;
                }
                let room = self.buf.len().min(self.left);
                match self.reader.read(&mut self.buf[..room]) {
                    Ok(0) => {
                        self.finished = true;
                        if self.last_sent {
                            return None;
                        }
                        return Some(self.picture().unwrap_or(Err(Error::NeedMoreData)));
                    }
                    Ok(n) => {
                        (self.pos, self.len) = (0, n);
                        self.left -= n;
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(e) => {
                        self.finished = true;
                        return Some(Err(e.into()));
                    }
                }
            }
            // Per level: feed small pieces so that a level boundary inside a read is seen;
            // every K bytes: feed up to the next multiple of K.
            let left = self.len - self.pos;
            let step = match self.cadence {
                Cadence::EveryBytes(k) => left.min(k.max(1) - self.since),
                Cadence::PerLevel => left.min(32),
            };
            let piece = self.pos..self.pos + step;
            self.pos += step;
            if let Err(e) = self.decoder.push(&self.buf[piece]) {
                self.finished = true;
                self.pos = self.len;
                return Some(Err(e));
            }
            if self.last_sent {
                continue;
            }
            if self.done() {
                self.last_sent = true;
                return self.picture();
            }
            let due = match self.cadence {
                Cadence::EveryBytes(k) => {
                    self.since += step;
                    let due = self.since >= k.max(1);
                    if due {
                        self.since = 0;
                    }
                    due
                }
                Cadence::PerLevel => self.parts() > self.levels_seen,
            };
            if due {
                self.levels_seen = self.parts();
                if let Some(p) = self.picture() {
                    return Some(p);
                }
            }
        }
    }
}
