//! Decoding a refinement as its bytes arrive: the streams' bytes, their decoders, and the
//! picture at any size (spec/refinement.md §8).

use super::bitplane::StreamState;
use super::picture::{picture, picture_releasing, thumbnail, Source};
use super::predict;
use super::resample::resample;
use super::schedule::key;
use super::wavelet::low_size;
use super::{channel_classes, Layout, StreamDecoder};
use crate::container::{PassLimit, RefinementHeader};
use rayon::prelude::*;

/// A refinement being decoded.
#[derive(Clone, Debug)]
pub(crate) struct RefinementDecoder {
    layout: Layout,
    frac: u32,
    /// Per channel, the low-low band's prediction from the levels.
    prediction: Vec<Vec<i32>>,
    /// Each stream's decoder; `None` for a stream this decoder skips (a picture smaller than
    /// the image needs only the first streams).
    streams: Vec<Option<StreamDecoder>>,
    limits: Vec<usize>,
    /// Each stream's bytes received so far, and how many of them are in verified layers.
    bytes: Vec<Vec<u8>>,
    verified: Vec<usize>,
}

impl RefinementDecoder {
    /// A decoder for a `width × height` image with `channels` channels, whose levels' samples
    /// have the fixed positions `positions` and the decoded colours `colours`. It decodes
    /// streams `0..wanted` (at most all of them).
    pub(crate) fn new(
        header: &RefinementHeader,
        width: u32,
        height: u32,
        channels: usize,
        positions: &[[i64; 2]],
        colours: &[u8],
        wanted: usize,
    ) -> RefinementDecoder {
        let layout = Layout {
            width: width as usize,
            height: height as usize,
            channels,
            kernel: header.wavelet,
            levels: header.levels as u32,
            top: header.bitplanes.clone(),
        };
        let frac = header.fraction_bits as u32;
        let prediction = predict::low_band(
            positions,
            colours,
            channels,
            layout.width,
            layout.height,
            layout.kernel,
            layout.levels,
            frac,
        );
        let limits = pass_limits(&layout, &header.limit);
        let streams = layout
            .stream_states(None)
            .into_iter()
            .zip(&limits)
            .enumerate()
            .map(|(s, (st, &n))| (s < wanted).then(|| StreamDecoder::new(st, n)))
            .collect();
        let n = layout.streams();
        RefinementDecoder {
            layout,
            frac,
            prediction,
            streams,
            limits,
            bytes: vec![Vec::new(); n],
            verified: vec![0; n],
        }
    }

    /// The next bytes of stream `s` (not yet verified). A skipped stream's are not kept.
    pub(crate) fn push(&mut self, s: usize, bytes: &[u8]) {
        if self.streams.get(s).is_some_and(Option::is_some) {
            self.bytes[s].extend_from_slice(bytes);
        }
    }

    /// The layer being read is verified: every byte so far is.
    pub(crate) fn verify(&mut self) {
        for (v, b) in self.verified.iter_mut().zip(&self.bytes) {
            *v = b.len();
        }
    }

    /// Recovery: forgets the bytes of the layer that failed (the streams start over from their
    /// verified bytes).
    pub(crate) fn drop_unverified(&mut self) {
        let states = self.layout.stream_states(None);
        for (s, st) in states.into_iter().enumerate() {
            self.bytes[s].truncate(self.verified[s]);
            if let Some(d) = &mut self.streams[s] {
                *d = StreamDecoder::new(st, self.limits[s]);
            }
        }
    }

    /// Keeps only the streams a `width × height` thumbnail needs (the others' bytes are
    /// dropped as they arrive, and never decoded).
    pub(crate) fn keep_streams_for_thumbnail(&mut self, width: u32, height: u32) {
        let decoded = self.thumbnail_level(width, height);
        let keep = self.streams_for(decoded);
        for d in self.streams.iter_mut().skip(keep) {
            *d = None;
        }
    }

    /// The streams a picture of transform level `level` draws on.
    fn streams_for(&self, level: u32) -> usize {
        (self.layout.levels - level.min(self.layout.levels)) as usize + 1
    }

    fn thumbnail_level(&self, width: u32, height: u32) -> u32 {
        thumbnail_level(&self.layout, width as usize, height as usize)
    }

    /// Advances the first `n` streams over the bytes received.
    /// The streams are independent: they are decoded in parallel.
    fn advance(&mut self, n: usize) {
        let n = n.min(self.streams.len());
        (self.streams[..n].par_iter_mut().zip(&self.bytes[..n]))
            .for_each(|(d, bytes)| d.iter_mut().for_each(|d| d.advance(bytes)));
    }

    /// What the picture is drawn from, but the streams.
    fn source(&self) -> Source<'_> {
        source(&self.layout, self.frac, &self.prediction)
    }

    /// The states of the first `n` streams (`None`: skipped).
    fn states(&self, n: usize) -> Vec<Option<&StreamState>> {
        let used = self.streams.iter().take(n);
        used.map(|d| d.as_ref().map(|d| &d.state)).collect()
    }

    /// The picture at `width × height` from the bytes received so far (interleaved, the file's
    /// layout): the image-size picture, averaged over each output pixel (smaller) or
    /// interpolated (larger). This is the spec's picture. If `last`, the decoder is spent:
    /// its states are freed as the picture is made.
    pub(crate) fn render(&mut self, width: u32, height: u32, last: bool) -> Vec<u8> {
        let all = self.layout.streams();
        self.advance(all);
        let pic = if last {
            let src = source(&self.layout, self.frac, &self.prediction);
            let used = self.streams.iter_mut();
            let mut states: Vec<_> = used.map(|d| d.as_mut().map(|d| &mut d.state)).collect();
            picture_releasing(&src, &mut states, 0)
        } else {
            picture(&self.source(), &self.states(all), 0)
        };
        let (w, h) = (self.layout.width, self.layout.height);
        if (width as usize, height as usize) == (w, h) {
            return pic;
        }
        let c = self.layout.channels;
        resample(&pic, w, h, c, 0, (w, h), width as usize, height as usize)
    }

    /// A thumbnail at `width × height`: about the same picture from the coarse streams only
    /// (a 1/8-size thumbnail decodes 1/16 of the coefficients). Near the image's size, the
    /// picture of [`RefinementDecoder::render`].
    pub(crate) fn render_thumbnail(&mut self, width: u32, height: u32, last: bool) -> Vec<u8> {
        let decoded = self.thumbnail_level(width, height);
        if decoded == 0 {
            return self.render(width, height, last);
        }
        // Streams with no bytes yet hold zero bands: the bands from the first of them on are
        // synthesised one axis at a time, like those finer than `decoded` (the first preview
        // of a cut file does not run the whole inverse transform on zeros).
        let n = self.streams_for(decoded);
        let coded = (self.bytes[..n].iter().rposition(|b| !b.is_empty())).map_or(1, |s| s + 1);
        let decoded = decoded.max(self.layout.levels + 1 - coded as u32);
        let n = self.streams_for(decoded);
        self.advance(n);
        let size = (width as usize, height as usize);
        thumbnail(&self.source(), &self.states(n), decoded, size)
    }
}

/// The transform level whose bands a `width × height` thumbnail of `layout` decodes (the finer
/// bands are taken as zero): the deepest whose low-low band is at least twice the thumbnail on
/// each side, less a pixel. The pixel is a rounding's: a 4000 × 3000 photo's 1/16 thumbnail is
/// 250 × 188 (187.5 rounded up), and its level-3 band, 500 × 375, is as good as twice that.
fn thumbnail_level(layout: &Layout, width: usize, height: usize) -> u32 {
    (0..=layout.levels)
        .rev()
        .find(|&k| {
            let (lw, lh) = low_size(layout.width, layout.height, k);
            2 * width <= lw + 1 && 2 * height <= lh + 1
        })
        .unwrap_or(0)
}

/// What a picture of `layout` is drawn from, but the streams.
fn source<'a>(layout: &Layout, frac: u32, prediction: &'a [Vec<i32>]) -> Source<'a> {
    Source {
        width: layout.width,
        height: layout.height,
        channels: layout.channels,
        kernel: layout.kernel,
        levels: layout.levels,
        frac,
        prediction,
    }
}

/// The number of passes the file codes in each stream.
pub(crate) fn pass_limits(layout: &Layout, limit: &PassLimit) -> Vec<usize> {
    match limit {
        PassLimit::Counts(c) => c.iter().map(|&n| n as usize).collect(),
        PassLimit::Key(k) => {
            let (_, weights) = channel_classes(layout.channels);
            let bands = layout.bands();
            layout
                .passes()
                .iter()
                .map(|ps| {
                    ps.iter()
                        .take_while(|p| {
                            key(
                                layout.kernel,
                                &bands[p.band as usize],
                                weights[p.channel as usize],
                                p.bitplane,
                                p.kind,
                            ) >= *k
                        })
                        .count()
                })
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refinement::Kernel;

    #[test]
    fn a_thumbnail_decodes_down_to_twice_its_size_less_a_pixel() {
        let layout = Layout {
            width: 4000,
            height: 3000,
            channels: 3,
            kernel: Kernel::Integer97,
            levels: 5,
            top: vec![12; 3],
        };
        // Low-low bands: 2000 × 1500, 1000 × 750, 500 × 375, 250 × 188, 125 × 94.
        for ((w, h), level) in [
            ((500, 375), 2),
            ((501, 375), 1),
            ((250, 188), 3),
            ((251, 188), 2),
            ((250, 189), 2),
            ((160, 120), 3),
            ((125, 94), 4),
            ((62, 47), 5),
            ((1, 1), 5),
            ((4000, 3000), 0),
            ((8000, 6000), 0),
        ] {
            assert_eq!(thumbnail_level(&layout, w, h), level, "{w}x{h}");
        }
    }
}
