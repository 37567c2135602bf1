//! The refinement: after the quasicrystal levels, a wavelet transform of what their picture
//! misses, coded bit-plane by bit-plane (spec/refinement.md; its chunks: spec/format.md).
//!
//! The levels give the first picture; the refinement sharpens it on the pixel grid up to
//! lossless. Its pieces, in the order the decoder uses them:
//!
//! * [`schedule`]: bands, blocks, streams (one per resolution) and the order of passes;
//! * [`bitplane`]: the coding of a stream's passes, shared by encoder and decoder;
//! * [`wavelet`]: the integer lifting transforms;
//! * [`predict`]: the low-low band's prediction from the levels' samples;
//! * [`decode`] and [`encode`]: a refinement's decoder as bytes arrive, and its encoder;
//! * `picture` and `resample`: coefficients → pixels, at the image size or any other.

pub(crate) mod bitplane;
pub(crate) mod decode;
pub(crate) mod encode;
#[cfg(test)]
mod lab;
pub(crate) mod picture;
pub(crate) mod predict;
pub(crate) mod resample;
pub(crate) mod schedule;
pub(crate) mod wavelet;

use bitplane::{BandState, ChannelClass, Decoding, Encoding, ErrorDrop, StreamState};
use schedule::{bands, passes, Band, Pass};
pub(crate) use wavelet::Kernel;

use crate::coding::range::{RangeDecoder, RangeEncoder};

/// How the channels of a layout are coded: their context class and weight (sixteenths of a
/// bit-plane: 8·log2 of the weight of an error in the channel in the squared error over the
/// layout's own channels, R, G, B for colour).
pub(crate) fn channel_classes(channels: usize) -> (&'static [ChannelClass], &'static [i32]) {
    match channels {
        1 => (&[0], &[0]),
        2 => (&[0, 2], &[0, 0]),
        3 => (&[0, 1, 1], &[13, -8, -3]),
        _ => (&[0, 1, 1, 2], &[13, -8, -3, 0]),
    }
}

/// What a decoder needs to know of the transform and the passes before the first pass.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub kernel: Kernel,
    pub levels: u32,
    /// Bit-planes of each channel.
    pub top: Vec<u8>,
}

impl Layout {
    pub(crate) fn bands(&self) -> Vec<Band> {
        bands(self.width, self.height, self.levels)
    }

    pub(crate) fn streams(&self) -> usize {
        self.levels as usize + 1
    }

    /// The passes of each stream, in order.
    pub(crate) fn passes(&self) -> Vec<Vec<Pass>> {
        let (_, weights) = channel_classes(self.channels);
        passes(self.kernel, &self.bands(), &self.top, weights)
    }

    /// The state of each stream, its bands' coefficients taken from `planes` (the encoder's
    /// transformed channels, Mallat layout) or zero (a decoder's).
    pub(crate) fn stream_states(&self, planes: Option<&[Vec<i32>]>) -> Vec<StreamState> {
        self.states_with(|_, band, c| planes.map_or_else(Vec::new, |p| self.band_of(&p[c], band)))
    }

    /// [`Layout::stream_states`] from `planes`, each freed once its bands are copied (the
    /// planes and the copies are never all held at once).
    pub(crate) fn stream_states_taking(&self, planes: Vec<Vec<i32>>) -> Vec<StreamState> {
        let all = self.bands();
        let mut truths: Vec<Vec<Vec<i32>>> = vec![Vec::new(); all.len()];
        for plane in planes {
            for (t, band) in truths.iter_mut().zip(&all) {
                t.push(self.band_of(&plane, band));
            }
        }
        self.states_with(|bi, _, c| std::mem::take(&mut truths[bi][c]))
    }

    /// The coefficients of `band` in `plane`, row by row.
    fn band_of(&self, plane: &[i32], band: &Band) -> Vec<i32> {
        let mut t = Vec::with_capacity(band.len());
        for y in band.y0..band.y0 + band.h {
            let row = y * self.width;
            t.extend_from_slice(&plane[row + band.x0..row + band.x0 + band.w]);
        }
        t
    }

    /// The state of each stream, the coefficients of band `bi` (`band`) of channel `c` from
    /// `truth(bi, band, c)`.
    fn states_with(
        &self,
        mut truth: impl FnMut(usize, &Band, usize) -> Vec<i32>,
    ) -> Vec<StreamState> {
        let (classes, _) = channel_classes(self.channels);
        let all = self.bands();
        self.passes()
            .into_iter()
            .enumerate()
            .map(|(s, ps)| {
                let mut members = Vec::new();
                let mut index = Vec::new();
                for (bi, band) in all.iter().enumerate().filter(|(_, b)| b.stream == s as u32) {
                    for (c, &class) in classes.iter().enumerate().take(self.channels) {
                        members.push((c as u8, BandState::new(*band, class, truth(bi, band, c))));
                        index.push(bi as u16);
                    }
                }
                StreamState::new(members, &index, ps)
            })
            .collect()
    }
}

/// `n` zeros, written now. The pages of a zeroed allocation map to the shared zero page
/// when first read and are copied when first written: two faults per page, and from the
/// second thread on, each copy flushes the TLB of every core. Buffers that are read before
/// they are written (coefficient states, planes that bands are added to) start here.
pub(crate) fn written_zeros<T: Copy + Default>(n: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    // Not a constant zero, so not made a zeroed allocation again.
    v.resize(n, std::hint::black_box(T::default()));
    v
}

/// The number of bit-planes that hold every value of `plane`.
pub(crate) fn bitplanes(plane: &[i32]) -> u8 {
    let max = plane.iter().map(|v| v.unsigned_abs()).max().unwrap_or(0);
    (32 - max.leading_zeros()) as u8
}

/// One stream, coded: its bytes and, for each pass, where its bytes end and how much it
/// lowers the squared error.
#[derive(Clone, Debug, Default)]
pub(crate) struct CodedStream {
    pub bytes: Vec<u8>,
    /// Bytes needed to decode each pass completely (an upper bound), cumulative.
    pub pass_end: Vec<usize>,
    /// The squared error each pass removes, in picture units (its band's and channel's
    /// weight applied).
    pub gain: Vec<f64>,
}

impl CodedStream {
    /// Keeps the first `len` bytes (a stream decodes as far as its bytes go).
    pub(crate) fn truncate(&mut self, len: usize) {
        self.bytes.truncate(len);
        for e in &mut self.pass_end {
            *e = (*e).min(len);
        }
    }
}

/// Codes the first `limit` passes of a stream.
pub(crate) fn encode_stream(state: &mut StreamState, limit: usize, weights: &[f64]) -> CodedStream {
    let mut sym = Encoding {
        enc: RangeEncoder::new(),
    };
    let mut tally = ErrorDrop::default();
    let mut pass_end = Vec::new();
    let mut gain = Vec::new();
    let mut done = |s: &mut Encoding, t: &mut ErrorDrop, k: usize| {
        pass_end.push(s.enc.len_estimate());
        gain.push(t.0 * weights[k]);
        t.0 = 0.0;
    };
    state.run(&mut sym, limit, &mut tally, &mut done);
    let bytes = sym.enc.finish_open();
    let n = bytes.len();
    for e in &mut pass_end {
        *e = (*e).min(n);
    }
    CodedStream {
        bytes,
        pass_end,
        gain,
    }
}

/// A stream being decoded: its state and the range decoder where it stopped.
#[derive(Clone, Debug)]
pub(crate) struct StreamDecoder {
    pub state: StreamState,
    dec: RangeDecoder,
    /// The passes the file codes.
    pub limit: usize,
}

impl StreamDecoder {
    pub(crate) fn new(state: StreamState, limit: usize) -> Self {
        StreamDecoder {
            state,
            dec: RangeDecoder::new(),
            limit,
        }
    }

    /// Decodes as far as `bytes` (every byte of the stream received so far) decide.
    pub(crate) fn advance(&mut self, bytes: &[u8]) {
        let mut sym = Decoding::new(self.dec, bytes);
        self.state
            .run(&mut sym, self.limit, &mut (), &mut |_, _, _| {});
        self.dec = sym.dec;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn lcg(s: &mut u64) -> u64 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *s >> 33
    }

    /// Planes whose coefficients look like a transform's: sparse, heavy-tailed, larger in
    /// the coarse bands.
    fn planes(layout: &Layout, seed: u64) -> Vec<Vec<i32>> {
        let mut s = seed;
        let bands = layout.bands();
        (0..layout.channels)
            .map(|_| {
                let mut p = vec![0i32; layout.width * layout.height];
                for b in &bands {
                    let scale = 1u64 << (b.level.min(6) + 1);
                    for y in b.y0..b.y0 + b.h {
                        for x in b.x0..b.x0 + b.w {
                            let r = lcg(&mut s);
                            let mag = if r.is_multiple_of(3) {
                                0
                            } else {
                                ((r >> 8) % (scale * 8)) >> (r % 5)
                            };
                            p[y * layout.width + x] = if r & 1 == 0 {
                                mag as i32
                            } else {
                                -(mag as i32)
                            };
                        }
                    }
                }
                p
            })
            .collect()
    }

    fn layout_for(w: usize, h: usize, channels: usize, levels: u32, planes: &[Vec<i32>]) -> Layout {
        Layout {
            width: w,
            height: h,
            channels,
            kernel: Kernel::Integer97,
            levels,
            top: planes.iter().map(|p| bitplanes(p)).collect(),
        }
    }

    fn values(state: &StreamState) -> Vec<i32> {
        state
            .bands
            .iter()
            .flat_map(|b| {
                (0..b.band.h).flat_map(move |y| (0..b.band.w).map(move |x| b.value(x, y)))
            })
            .collect()
    }

    fn encode_all(layout: &Layout, planes: &[Vec<i32>]) -> Vec<(Vec<u8>, usize)> {
        layout
            .stream_states(Some(planes))
            .into_iter()
            .map(|mut st| {
                let n = st.passes.len();
                let weights = vec![1.0; n];
                (encode_stream(&mut st, n, &weights).bytes, n)
            })
            .collect()
    }

    #[test]
    fn every_pass_decodes_to_the_coefficients() {
        let probe = Layout {
            width: 70,
            height: 45,
            channels: 3,
            kernel: Kernel::Integer97,
            levels: 3,
            top: vec![0; 3],
        };
        let p = planes(&probe, 9);
        let layout = layout_for(70, 45, 3, 3, &p);
        let coded = encode_all(&layout, &p);
        let mut decoders: Vec<StreamDecoder> = layout
            .stream_states(None)
            .into_iter()
            .zip(&coded)
            .map(|(st, (_, n))| StreamDecoder::new(st, *n))
            .collect();
        let truth = layout.stream_states(Some(&p));
        for ((d, (bytes, _)), t) in decoders.iter_mut().zip(&coded).zip(&truth) {
            d.advance(bytes);
            assert_eq!(d.state.cursor.pass, d.limit);
            let got = values(&d.state);
            let want: Vec<i32> = t
                .bands
                .iter()
                .flat_map(|b| b.truth.iter().copied())
                .collect();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn prefixes_and_pieces_decode_the_same_units() {
        let probe = Layout {
            width: 33,
            height: 20,
            channels: 1,
            kernel: Kernel::Integer97,
            levels: 2,
            top: vec![0],
        };
        let p = planes(&probe, 4);
        let layout = layout_for(33, 20, 1, 2, &p);
        let coded = encode_all(&layout, &p);
        let truth = layout.stream_states(Some(&p));
        for (s, (bytes, n)) in coded.iter().enumerate() {
            let want: Vec<i32> = truth[s]
                .bands
                .iter()
                .flat_map(|b| b.truth.iter().copied())
                .collect();
            let mut last = (0usize, 0usize);
            for cut in 0..=bytes.len() {
                let mut one = StreamDecoder::new(layout.stream_states(None).swap_remove(s), *n);
                one.advance(&bytes[..cut]);
                // Everything a prefix decodes is true: each significant coefficient has the
                // sign and the top bits of the coefficient.
                for (got, &t) in values(&one.state).iter().zip(&want) {
                    if *got != 0 {
                        assert_eq!(got.signum(), t.signum());
                    }
                }
                for (b, tb) in one.state.bands.iter().zip(&truth[s].bands) {
                    for i in 0..b.band.len() {
                        let m = b.mag(i);
                        if let Some(k) = b.known(i % b.band.w, i / b.band.w) {
                            let t = tb.truth[i].unsigned_abs();
                            assert_eq!(m, (t >> k) << k);
                        }
                    }
                }
                let progress = (one.state.cursor.pass, one.state.cursor.block);
                assert!(progress >= last, "cut {cut}: {progress:?} < {last:?}");
                last = progress;
                // Fed in pieces, the decoder reaches the same state.
                let mut pieces = StreamDecoder::new(layout.stream_states(None).swap_remove(s), *n);
                for k in (0..=cut).step_by(3).chain([cut]) {
                    pieces.advance(&bytes[..k]);
                }
                assert_eq!(values(&pieces.state), values(&one.state), "cut {cut}");
                assert_eq!(pieces.state.cursor, one.state.cursor);
            }
            assert_eq!(
                last.0, *n,
                "stream {s}: the whole stream decodes every pass"
            );
        }
    }

    /// The picture drawn a strip at a time equals the one drawn from whole planes, at every
    /// small size, for both kernels, with some streams missing, and on pictures tall enough
    /// for many strips.
    #[test]
    fn strips_draw_the_planes_picture() {
        use picture::{draw_planes, picture, Source};
        let mut seed = 3u64;
        let sizes = (1..=12).flat_map(|w| [1, 2, 3, 5, 8, 13].map(|h| (w, h)));
        let tall = [(7, 131), (40, 97), (3, 200), (65, 66)];
        for (k, (w, h)) in sizes.chain(tall).enumerate() {
            let kernel = [Kernel::Integer97, Kernel::Reversible53][k % 2];
            let (channels, levels) = (1 + k % 4, 1 + (k % 3) as u32);
            let probe = Layout {
                width: w,
                height: h,
                channels,
                kernel,
                levels,
                top: vec![],
            };
            let p = planes(&probe, k as u64);
            let layout = Layout {
                kernel,
                ..layout_for(w, h, channels, levels, &p)
            };
            let coded = encode_all(&layout, &p);
            let decoders: Vec<StreamDecoder> = (layout.stream_states(None).into_iter().zip(&coded))
                .map(|(st, (bytes, n))| {
                    let mut d = StreamDecoder::new(st, *n);
                    d.advance(bytes);
                    d
                })
                .collect();
            let (lw, lh) = wavelet::low_size(w, h, levels);
            let prediction: Vec<Vec<i32>> = (0..channels)
                .map(|_| {
                    (0..lw * lh)
                        .map(|_| (lcg(&mut seed) % 4000) as i32 - 2000)
                        .collect()
                })
                .collect();
            let src = Source {
                width: w,
                height: h,
                channels,
                kernel,
                levels,
                frac: 3,
                prediction: &prediction,
            };
            for skip in [None, Some(layout.streams() - 1), Some(0)] {
                let states: Vec<Option<&StreamState>> = (decoders.iter().enumerate())
                    .map(|(s, d)| (Some(s) != skip).then_some(&d.state))
                    .collect();
                let mut bands = vec![Vec::new(); channels];
                for st in states.iter().flatten() {
                    for (b, band) in st.bands.iter().enumerate() {
                        bands[st.channel_of(b)].push(band);
                    }
                }
                assert_eq!(
                    picture(&src, &states, 0),
                    draw_planes(&src, 0, bands),
                    "{w}x{h}, {channels} channels, {levels} levels, {kernel:?}, skipping {skip:?}"
                );
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn arbitrary_planes_round_trip(w in 1usize..50, h in 1usize..50, channels in 1usize..5, levels in 0u32..4, seed in any::<u64>()) {
            let probe = Layout { width: w, height: h, channels, kernel: Kernel::Reversible53, levels, top: vec![] };
            let p = planes(&probe, seed);
            let layout = layout_for(w, h, channels, levels, &p);
            let coded = encode_all(&layout, &p);
            let truth = layout.stream_states(Some(&p));
            for ((st, (bytes, n)), t) in layout.stream_states(None).into_iter().zip(&coded).zip(&truth) {
                let mut d = StreamDecoder::new(st, *n);
                d.advance(bytes);
                let want: Vec<i32> = t.bands.iter().flat_map(|b| b.truth.iter().copied()).collect();
                prop_assert_eq!(values(&d.state), want);
            }
        }
    }
}
