//! A pull decoder over `std::io::Read`: previews as the bytes of a file or socket arrive.

use crate::decoder::{Picture, StreamDecoder};
use crate::reconstruction::Method;
use crate::{Limits, Result};
use std::io::Read;

/// When [`Previews`] yields a picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cadence {
    /// After every completed level (and at the end of the stream).
    PerLevel,
    /// After every `K` bytes read (and at the end of the stream).
    EveryBytes(usize),
}

/// An iterator of pictures read from a stream: previews, then the final picture.
///
/// ```
/// use qcs::{Cadence, Method, Previews};
/// let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(48, 32, |x, y| image::Rgb([x as u8 * 5, y as u8 * 7, 128])));
/// let opts = qcs::EncodeOptions { first_level: 8, ..Default::default() };
/// let bytes = qcs::encode(&img, &opts)?;
/// let pics: Vec<_> = Previews::new(&bytes[..], Cadence::PerLevel, Method::Gouraud, None, qcs::Limits::default())
///     .collect::<Result<_, _>>()?;
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
    levels_seen: u32,
    buf: Vec<u8>,
    pos: usize,
    len: usize,
    finished: bool,
}

impl<R: Read> Previews<R> {
    /// Reads `reader` and yields a picture at each `cadence` step, rendered with `method` at
    /// `size` (default: the image's own size).
    pub fn new(
        reader: R,
        cadence: Cadence,
        method: Method,
        size: Option<(u32, u32)>,
        limits: Limits,
    ) -> Self {
        let chunk = match cadence {
            Cadence::EveryBytes(k) => k.clamp(1, 1 << 20),
            Cadence::PerLevel => 1 << 12,
        };
        Previews {
            reader,
            decoder: StreamDecoder::new(limits),
            cadence,
            method,
            size,
            levels_seen: 0,
            buf: vec![0; chunk],
            pos: 0,
            len: 0,
            finished: false,
        }
    }

    /// The decoder, e.g. for its header and sample counts.
    pub fn decoder(&self) -> &StreamDecoder {
        &self.decoder
    }

    fn picture(&mut self) -> Option<Result<Picture>> {
        let h = self.decoder.header()?;
        let (w, ht) = self.size.unwrap_or((h.width, h.height));
        Some(self.decoder.render(self.method, w, ht))
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
                match self.reader.read(&mut self.buf) {
                    Ok(0) => {
                        self.finished = true;
                        return self.picture();
                    }
                    Ok(n) => (self.pos, self.len) = (0, n),
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(e) => {
                        self.finished = true;
                        return Some(Err(e.into()));
                    }
                }
            }
            // Per level: feed small pieces so that a level boundary inside a read is seen.
            let step = match self.cadence {
                Cadence::EveryBytes(_) => self.len - self.pos,
                Cadence::PerLevel => (self.len - self.pos).min(32),
            };
            let piece = self.pos..self.pos + step;
            self.pos += step;
            if let Err(e) = self.decoder.push(&self.buf[piece]) {
                self.finished = true;
                self.pos = self.len;
                return Some(Err(e));
            }
            if self.decoder.is_complete() {
                self.finished = true;
                self.pos = self.len;
                return self.picture();
            }
            let due = match self.cadence {
                Cadence::EveryBytes(_) => true,
                Cadence::PerLevel => self.decoder.levels_complete() > self.levels_seen,
            };
            if due {
                self.levels_seen = self.decoder.levels_complete();
                if let Some(p) = self.picture() {
                    return Some(p);
                }
            }
        }
    }
}
