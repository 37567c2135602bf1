//! Encoding a refinement: transform, prediction, streams, and where the bytes go — which
//! passes to code (a quality, lossless, or a size) and how to split them into layers.

use super::decode::pass_limits;
use super::picture::to_planes;
use super::schedule::band_weight;
use super::wavelet::{forward, low_size, Kernel};
use super::{bitplanes, channel_classes, encode_stream, predict, CodedStream, Layout};
use crate::container::{PassLimit, RefinementHeader};
use rayon::prelude::*;

/// What the refinement should reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Goal {
    /// Every pass whose priority key is at least this.
    Key(i32),
    /// Every pass (with the reversible 5/3 and no fraction bits: exactly the input).
    Lossless,
    /// As good a picture as fits in this many bytes of refinement (layer framing included).
    Bytes(usize),
}

/// The transform levels for a `width × height` image: until the low-low band's longer side
/// is at most 16 coefficients (at most 15 levels).
pub(crate) fn default_levels(width: u32, height: u32) -> u32 {
    let mut levels = 0;
    let (mut w, mut h) = (width as usize, height as usize);
    while w.max(h) > 16 && levels < 15 {
        w = w.div_ceil(2);
        h = h.div_ceil(2);
        levels += 1;
    }
    levels
}

/// A refinement, coded: its header and its layers (each a segment per stream).
#[derive(Clone, Debug)]
pub(crate) struct Encoded {
    pub header: RefinementHeader,
    pub layers: Vec<Vec<Vec<u8>>>,
}

/// Framing a layer costs besides its segments: the chunk's tag, length and CRC, the table's
/// count and a length per segment (estimates, for the byte goal).
fn framing(layers: usize, streams: usize) -> usize {
    layers * (1 + 2 + 4 + 1 + 2 * streams)
}

/// The weight of each pass of a stream (the squared error in the picture per unit squared
/// error of a coefficient of its band and channel, over 4^F).
pub(super) fn pass_weights(
    layout: &Layout,
    frac: u32,
    passes: &[super::schedule::Pass],
) -> Vec<f64> {
    let (_, cw) = channel_classes(layout.channels);
    let bands = layout.bands();
    let scale = (1u64 << (2 * frac)) as f64;
    passes
        .iter()
        .map(|p| {
            let w = band_weight(layout.kernel, &bands[p.band as usize]) + cw[p.channel as usize];
            2f64.powf(w as f64 / 8.0) / scale
        })
        .collect()
}

/// Passes of `stream` to keep at slope `lambda`: the point of its (bytes, gain) curve that
/// maximises gain − λ·bytes.
pub(super) fn cut_at(stream: &CodedStream, lambda: f64) -> usize {
    let mut best = (0.0f64, 0usize);
    let mut g = 0.0;
    for (k, (&e, &dg)) in stream.pass_end.iter().zip(&stream.gain).enumerate() {
        g += dg;
        let v = g - lambda * e as f64;
        if v > best.0 {
            best = (v, k + 1);
        }
    }
    best.1
}

/// Bytes of `stream` that decode its first `k` passes.
fn end_of(stream: &CodedStream, k: usize) -> usize {
    if k == 0 {
        0
    } else {
        stream.pass_end[k - 1].min(stream.bytes.len())
    }
}

/// The slope whose cuts fill at most `budget` bytes (as large a total as possible).
fn slope_for(streams: &[CodedStream], budget: usize) -> f64 {
    let total = |l: f64| -> usize { streams.iter().map(|s| end_of(s, cut_at(s, l))).sum() };
    let (mut lo, mut hi) = (1e-12f64, 1e15f64);
    if total(lo) <= budget {
        return lo;
    }
    for _ in 0..100 {
        let mid = (lo * hi).sqrt();
        if total(mid) > budget {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The transformed channels of a picture, before the prediction.
#[derive(Clone, Debug)]
pub(crate) struct Transformed {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub kernel: Kernel,
    pub frac: u32,
    pub levels: u32,
    planes: Vec<Vec<i32>>,
}

/// Transforms `pixels` (`channels` interleaved, `width × height`).
pub(crate) fn transform(
    pixels: &[u8],
    width: u32,
    height: u32,
    channels: usize,
    kernel: Kernel,
    frac: u32,
    levels: u32,
) -> Transformed {
    let (w, h) = (width as usize, height as usize);
    let mut planes = to_planes(pixels, channels, frac);
    // Grey + alpha and RGBA (the even channel counts) have alpha last.
    if frac > 0 && channels.is_multiple_of(2) {
        overshoot_alpha(&mut planes[channels - 1], frac);
    }
    (planes.par_iter_mut()).for_each(|plane| forward(kernel, plane, w, h, levels));
    Transformed {
        width: w,
        height: h,
        channels,
        kernel,
        frac,
        levels,
        planes,
    }
}

/// Levels beyond 0..=255 that a lossy file's alpha aims at where the image is wholly
/// transparent or opaque. On a dev photograph with a soft-edged mask at quality 85
/// (MEASUREMENTS.md, *Alpha that stays opaque*): 22% of its opaque pixels decoded below 255
/// without it, none with 8, the file 0.02% smaller; with a hard-edged mask 0.6% of them
/// still do (next to its edges).
const ALPHA_MARGIN: i32 = 8;

/// Moves a lossy file's alpha plane (centred, `frac` fraction bits) past 0 and 255 by
/// [`ALPHA_MARGIN`] levels where it is 0 or 255: the decoder clamps to 0..=255, so the
/// small errors of a lossy transform leave those pixels exactly transparent or opaque
/// instead of 1 or 254 (a picture's opaque parts are otherwise faintly see-through).
fn overshoot_alpha(plane: &mut [i32], frac: u32) {
    let (lo, hi) = (-128 << frac, 127 << frac);
    let m = ALPHA_MARGIN << frac;
    for v in plane {
        if *v == lo {
            *v -= m;
        } else if *v == hi {
            *v += m;
        }
    }
}

impl Transformed {
    /// The low-low band's prediction from levels whose samples have fixed positions
    /// `positions` and decoded colours `colours`.
    pub(crate) fn prediction(&self, positions: &[[i64; 2]], colours: &[u8]) -> Vec<Vec<i32>> {
        predict::low_band(
            positions,
            colours,
            self.channels,
            self.width,
            self.height,
            self.kernel,
            self.levels,
            self.frac,
        )
    }

    /// The planes less the prediction, and their layout.
    fn residual(&self, prediction: &[Vec<i32>]) -> (Vec<Vec<i32>>, Layout) {
        self.clone().into_residual(prediction)
    }

    /// [`Transformed::residual`], in place.
    fn into_residual(self, prediction: &[Vec<i32>]) -> (Vec<Vec<i32>>, Layout) {
        let (w, h) = (self.width, self.height);
        let (lw, lh) = low_size(w, h, self.levels);
        let mut planes = self.planes;
        for (plane, pred) in planes.iter_mut().zip(prediction) {
            for y in 0..lh {
                for (v, p) in plane[y * w..y * w + lw].iter_mut().zip(&pred[y * lw..]) {
                    *v -= p;
                }
            }
        }
        let layout = Layout {
            width: w,
            height: h,
            channels: self.channels,
            kernel: self.kernel,
            levels: self.levels,
            top: planes.iter().map(|p| bitplanes(p)).collect(),
        };
        (planes, layout)
    }
}

/// A refinement's streams coded for a look at its first bytes: see [`Early::picture`].
pub(crate) struct Early<'a> {
    t: &'a Transformed,
    prediction: Vec<Vec<i32>>,
    layout: Layout,
    streams: Vec<CodedStream>,
}

impl Transformed {
    /// The refinement over levels with decoded `colours` at `positions`, its passes with key
    /// at least `key` coded.
    pub(crate) fn early(&self, positions: &[[i64; 2]], colours: &[u8], key: i32) -> Early<'_> {
        let prediction = self.prediction(positions, colours);
        let (planes, layout) = self.residual(&prediction);
        let limits = pass_limits(&layout, &PassLimit::Key(key));
        let streams = layout
            .stream_states(Some(&planes))
            .into_iter()
            .zip(&limits)
            .map(|(mut st, &n)| {
                let weights = pass_weights(&layout, self.frac, &st.passes);
                encode_stream(&mut st, n, &weights)
            })
            .collect();
        Early {
            t: self,
            prediction,
            layout,
            streams,
        }
    }
}

impl Early<'_> {
    /// The picture a decoder draws from `budget` bytes of this refinement (its passes cut at
    /// one slope, at pass ends).
    pub(crate) fn picture(&self, budget: usize) -> Vec<u8> {
        let lambda = slope_for(&self.streams, budget);
        let decoders: Vec<super::StreamDecoder> = self
            .layout
            .stream_states(None)
            .into_iter()
            .zip(&self.streams)
            .map(|(st, c)| {
                let k = cut_at(c, lambda);
                let mut d = super::StreamDecoder::new(st, k);
                d.advance(&c.bytes[..end_of(c, k)]);
                d
            })
            .collect();
        let states: Vec<Option<&super::bitplane::StreamState>> =
            decoders.iter().map(|d| Some(&d.state)).collect();
        let src = super::picture::Source {
            width: self.t.width,
            height: self.t.height,
            channels: self.t.channels,
            kernel: self.t.kernel,
            levels: self.t.levels,
            frac: self.t.frac,
            prediction: &self.prediction,
        };
        super::picture::picture(&src, &states, 0)
    }
}

/// Codes the refinement of a picture over levels whose samples have fixed positions
/// `positions` and decoded colours `colours`.
pub(crate) fn encode(
    t: Transformed,
    positions: &[[i64; 2]],
    colours: &[u8],
    goal: Goal,
    first_layer: usize,
) -> Encoded {
    let prediction = t.prediction(positions, colours);
    let (kernel, frac, levels) = (t.kernel, t.frac, t.levels);
    let (planes, layout) = t.into_residual(&prediction);
    let all: Vec<usize> = layout.passes().iter().map(Vec::len).collect();
    let (limits, limit) = match goal {
        Goal::Key(k) => (pass_limits(&layout, &PassLimit::Key(k)), PassLimit::Key(k)),
        Goal::Lossless | Goal::Bytes(_) => (all.clone(), PassLimit::Counts(vec![])),
    };
    // The states copy their bands' coefficients, each plane going once copied. The streams
    // are coded in parallel, each state going once its stream is coded, the largest (the
    // finest level's) first.
    let states = layout.stream_states_taking(planes);
    let mut streams: Vec<CodedStream> = (states.into_par_iter().zip(&limits).rev())
        .map(|(mut st, &n)| {
            let weights = pass_weights(&layout, frac, &st.passes);
            encode_stream(&mut st, n, &weights)
        })
        .collect();
    streams.reverse();
    let mut header = RefinementHeader {
        wavelet: kernel,
        fraction_bits: frac as u8,
        levels: levels as u8,
        bitplanes: layout.top.clone(),
        layers: 1,
        limit,
    };
    match goal {
        Goal::Key(_) => {}
        Goal::Lossless => {
            header.limit = PassLimit::Counts(all.iter().map(|&n| n as u32).collect());
        }
        Goal::Bytes(budget) => {
            let (cut, lengths) = fill(&streams, &mut header, budget, first_layer);
            header.limit = PassLimit::Counts(cut.iter().map(|&n| n as u32).collect());
            for (s, len) in streams.iter_mut().zip(lengths) {
                s.truncate(len);
            }
        }
    }
    let layers = split_layers(&streams, first_layer);
    header.layers = layers.len() as u32;
    Encoded { header, layers }
}

/// Bytes a refinement takes in the file: its `R` chunks (tag, length, payload, CRC).
fn size_in_file(header: &RefinementHeader, layers: &[Vec<Vec<u8>>]) -> usize {
    layers
        .iter()
        .enumerate()
        .map(|(k, segs)| {
            let segs: Vec<&[u8]> = segs.iter().map(Vec::as_slice).collect();
            let n = crate::container::encode_layer((k == 0).then_some(header), &segs).len();
            1 + crate::container::varint::encoded_len(n as u64) + n + 4
        })
        .sum()
}

/// For a refinement of at most `budget` bytes in the file: the passes of each stream it
/// keeps (the last of them perhaps in part) and the bytes of each stream, the streams' full
/// codes cut there. Whole passes first, at one slope; the bytes left then go, a pass at a time
/// in the order of their slopes, to the passes next in line, the last one cut where the budget
/// ends (a stream's bytes decode as far as they go).
fn fill(
    streams: &[CodedStream],
    header: &mut RefinementHeader,
    budget: usize,
    first_layer: usize,
) -> (Vec<usize>, Vec<usize>) {
    let n = streams.len();
    let measure = |cut: &[usize], lengths: &[usize], header: &mut RefinementHeader| -> usize {
        header.limit = PassLimit::Counts(cut.iter().map(|&c| c as u32).collect());
        let kept: Vec<CodedStream> = streams
            .iter()
            .zip(lengths)
            .map(|(s, &len)| {
                let mut s = s.clone();
                s.truncate(len);
                s
            })
            .collect();
        let layers = split_layers(&kept, first_layer);
        header.layers = layers.len() as u32;
        size_in_file(header, &layers)
    };
    // Whole passes at one slope, the framing first estimated, then measured.
    let mut room = budget.saturating_sub(framing(layer_count(budget, first_layer), n) + 16);
    let (mut cut, mut lengths);
    loop {
        let lambda = slope_for(streams, room);
        cut = streams
            .iter()
            .map(|s| cut_at(s, lambda))
            .collect::<Vec<_>>();
        lengths = streams
            .iter()
            .zip(&cut)
            .map(|(s, &k)| end_of(s, k))
            .collect::<Vec<_>>();
        let size = measure(&cut, &lengths, header);
        if size <= budget || room == 0 {
            break;
        }
        room = room.saturating_sub(size - budget);
    }
    // Then the passes next in line, best slope first, as far as the budget goes; the
    // framing (layer tables, chunks) is taken as it is now, then measured again.
    let framing_now = measure(&cut, &lengths, header) - lengths.iter().sum::<usize>();
    let mut left = budget.saturating_sub(framing_now + lengths.iter().sum::<usize>());
    let mut partial = None;
    while left > 0 {
        let next = (0..n)
            .filter(|&s| cut[s] < streams[s].pass_end.len())
            .max_by(|&a, &b| {
                let slope = |s: usize| {
                    let bytes = (streams[s].pass_end[cut[s]] - lengths[s]).max(1);
                    streams[s].gain[cut[s]] / bytes as f64
                };
                slope(a).total_cmp(&slope(b))
            });
        let Some(s) = next else { break };
        let end = streams[s].pass_end[cut[s]].min(streams[s].bytes.len());
        let take = (end - lengths[s]).min(left);
        lengths[s] += take;
        left -= take;
        cut[s] += 1;
        if lengths[s] < end {
            partial = Some(s);
        }
    }
    // The tables' lengths may have grown by a byte or two: take them back from the last pass
    // (or, failing that, from any stream's tail).
    loop {
        let size = measure(&cut, &lengths, header);
        if size <= budget {
            break;
        }
        let over = size - budget;
        let s = partial
            .filter(|&s| lengths[s] > 0)
            .or_else(|| (0..n).rev().find(|&s| lengths[s] > 0));
        let Some(s) = s else { break };
        lengths[s] -= over.min(lengths[s]);
    }
    measure(&cut, &lengths, header);
    (cut, lengths)
}

/// Layers for a refinement of about `total` bytes whose first layer holds `first`.
fn layer_count(total: usize, first: usize) -> usize {
    let mut n = 1;
    let mut size = first.max(1);
    while size < total {
        size *= 2;
        n += 1;
    }
    n
}

/// Splits the coded streams into layers of about `first`, 2·`first`, 4·`first`… bytes, each
/// holding the passes of every stream whose rate–distortion slope is above the layer's.
fn split_layers(streams: &[CodedStream], first: usize) -> Vec<Vec<Vec<u8>>> {
    let total: usize = streams.iter().map(|s| s.bytes.len()).sum();
    let n = layer_count(total, first);
    let mut ends: Vec<Vec<usize>> = Vec::with_capacity(n);
    let mut budget = first.max(1);
    for layer in 0..n {
        let cut: Vec<usize> = if layer + 1 == n {
            streams.iter().map(|s| s.bytes.len()).collect()
        } else {
            let lambda = slope_for(streams, budget);
            streams
                .iter()
                .map(|s| end_of(s, cut_at(s, lambda)))
                .collect()
        };
        // Never go back: a stream's bytes only grow from layer to layer.
        let cut = match ends.last() {
            Some(prev) => cut.iter().zip(prev).map(|(&c, &p)| c.max(p)).collect(),
            None => cut,
        };
        ends.push(cut);
        budget *= 2;
    }
    let mut layers = Vec::with_capacity(n);
    let mut start = vec![0usize; streams.len()];
    for e in ends {
        let segs: Vec<Vec<u8>> = streams
            .iter()
            .zip(&start)
            .zip(&e)
            .map(|((s, &a), &b)| s.bytes[a..b].to_vec())
            .collect();
        // Layers that would be empty are merged into the next.
        if segs.iter().all(Vec::is_empty) {
            continue;
        }
        layers.push(segs);
        start = e;
    }
    if layers.is_empty() {
        layers.push(vec![Vec::new(); streams.len()]);
    }
    layers
}
