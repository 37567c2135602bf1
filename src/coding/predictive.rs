//! Coding 1, predictive: every sample is predicted from the samples before it (closed loop, exact
//! integer arithmetic) and only the quantised residual is coded, with an adaptive binary range
//! coder and contexts (spec/format.md §Coding 1 is normative; this is its implementation).
//!
//! * Colours are transformed reversibly: RGB → YCoCg-R, grey as is, alpha its own channel.
//! * Site positions are fixed point, 1/256 px, computed exactly from the lattice coordinates
//!   ([`crate::sites::fixed_position`]).
//! * The prediction of a channel is the inverse-squared-distance mean of the [`NEIGHBOURS`]
//!   nearest earlier samples (ties: lower index first), in integers.
//! * The residual is quantised with a step from the parameters ([`Params`]): step 1 is lossless.
//! * The residual is binarised (zero?, sign, exponent in unary, mantissa bits) and each bit coded
//!   with an adaptive probability chosen by channel, local activity (the spread of the
//!   neighbours' values) and, for chroma and alpha, the size of the luma residual.
//! * Each level's payload is a fresh range-coder stream; the probabilities carry over from the
//!   earlier levels.
//!
//! ```
//! use qcs::coding::predictive::{Params, PredictiveDecoder, PredictiveEncoder};
//! // Four RGB samples at fixed-point positions (1/256 px) in a 4×4 image, two levels.
//! let pos = [[128, 128], [896, 896], [896, 128], [128, 896]];
//! let rgb = [200u8, 10, 10, 10, 200, 10, 10, 10, 200, 90, 90, 90];
//! let params = Params::lossless();
//! let mut enc = PredictiveEncoder::new(params, 3, 4, 4)?;
//! let l0 = enc.encode_level(&pos[..2], &rgb[..6])?;
//! let l1 = enc.encode_level(&pos[2..], &rgb[6..])?;
//!
//! let mut dec = PredictiveDecoder::new(params, 3, 4, 4)?;
//! let mut out = Vec::new();
//! dec.start_level(&pos[..2], l0.len())?;
//! dec.push(&l0, &mut out)?;
//! dec.start_level(&pos[2..], l1.len())?;
//! dec.push(&l1, &mut out)?;
//! assert_eq!(out, rgb);
//! # Ok::<(), qcs::Error>(())
//! ```

use super::range::{Prob, RangeDecoder, RangeEncoder};
use crate::Error;

/// How many earlier samples a prediction uses.
pub const NEIGHBOURS: usize = 4;

/// Fixed-point unit of positions: 1/256 px.
pub const POS_ONE: i64 = 256;

/// The parameters of the predictive coding (its header parameter byte).
///
/// The luma quantisation step `s` (1..=255). Luma, grey and alpha use `s`; the chroma
/// channels Co and Cg use `2s − 1`. `s = 1` is lossless. [`Params::coding`] is the header's
/// coding for them (defined in `container`, which owns the header's types).
///
/// ```
/// use qcs::coding::predictive::Params;
/// assert_eq!(Params::from_quality(100), Params::lossless());
/// assert_eq!(Params::from_quality(75).step, 7);
/// assert_eq!(Params::from_quality(0).step, 101);
/// assert_eq!(Params { step: 5 }.chroma_step(), 9);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Params {
    /// Luma quantisation step, 1..=255.
    pub step: u8,
}

impl Default for Params {
    /// Quality [`DEFAULT_QUALITY`].
    fn default() -> Self {
        Params::from_quality(DEFAULT_QUALITY)
    }
}

/// The quality of [`Params::default`], [`crate::EncodeOptions::default`] and `qcs encode`.
pub const DEFAULT_QUALITY: u8 = 75;

impl Params {
    /// Lossless samples: step 1.
    pub fn lossless() -> Self {
        Params { step: 1 }
    }

    /// The step for a quality `q` in 0..=100 (above 100 counts as 100):
    /// `s = round(1 + (100 − q)² / 100)`, i.e. `1 + ((100 − q)² + 50) / 100` in integers.
    /// 100 → 1 (lossless), 90 → 2, 80 → 5, 75 → 7, 50 → 26, 0 → 101.
    pub fn from_quality(q: u8) -> Self {
        let d = 100 - q.min(100) as u32;
        Params {
            step: (1 + (d * d + 50) / 100) as u8,
        }
    }

    /// Quantisation step of luma, grey and alpha.
    pub fn luma_step(&self) -> i32 {
        self.step.max(1) as i32
    }

    /// Quantisation step of Co and Cg: `2s − 1`.
    pub fn chroma_step(&self) -> i32 {
        2 * self.luma_step() - 1
    }
}

/// Channel values in the coded domain, per layout: YCoCg-R for RGB(A).
fn forward(layout_channels: usize, px: &[u8], out: &mut [i32]) {
    match layout_channels {
        3 | 4 => {
            let (r, g, b) = (px[0] as i32, px[1] as i32, px[2] as i32);
            let co = r - b;
            let t = b + (co >> 1);
            let cg = g - t;
            let y = t + (cg >> 1);
            out[0] = y;
            out[1] = co;
            out[2] = cg;
            if layout_channels == 4 {
                out[3] = px[3] as i32;
            }
        }
        _ => {
            for (o, &v) in out.iter_mut().zip(px) {
                *o = v as i32;
            }
        }
    }
}

/// Back to 8-bit layout values (clamped).
fn inverse(layout_channels: usize, v: &[i32], out: &mut Vec<u8>) {
    match layout_channels {
        3 | 4 => {
            let (y, co, cg) = (v[0], v[1], v[2]);
            let t = y - (cg >> 1);
            let g = cg + t;
            let b = t - (co >> 1);
            let r = b + co;
            for c in [r, g, b] {
                out.push(c.clamp(0, 255) as u8);
            }
            if layout_channels == 4 {
                out.push(v[3].clamp(0, 255) as u8);
            }
        }
        _ => out.extend(v.iter().map(|&c| c.clamp(0, 255) as u8)),
    }
}

/// Range and step of coded channel `c`.
fn channel_info(layout_channels: usize, c: usize, params: &Params) -> (i32, i32, i32) {
    let chroma = layout_channels >= 3 && (c == 1 || c == 2);
    if chroma {
        (-255, 255, params.chroma_step())
    } else {
        (0, 255, params.luma_step())
    }
}

/// Earlier samples, in a uniform grid for exact k-nearest search.
#[derive(Clone, Debug)]
struct Predictor {
    width: i64,
    height: i64,
    pos: Vec<[i64; 2]>,
    values: Vec<i32>,
    /// |quantised luma residual| of each sample, capped at 255.
    mags: Vec<u8>,
    cell: i64,
    gw: i64,
    gh: i64,
    /// Cell `c` holds `entries[start[c]..start[c + 1]]`: the positions and indices of the
    /// samples laid out so far (those coded and those of the level being coded), in index
    /// order, so the coded ones come first.
    start: Vec<u32>,
    entries: Vec<([i64; 2], u32)>,
    /// The level being coded: its positions, their numbers within the level batch by batch
    /// (`order[b·BATCH..]` holds batch `b`'s, in grid order), and the nearest earlier samples
    /// of its samples `batch..batch + near.len()` (found a batch at a time, in grid order, for
    /// locality).
    level: Vec<[i64; 2]>,
    order: Vec<u32>,
    near: Vec<[(i64, u32); NEIGHBOURS]>,
    batch: usize,
}

/// Samples of a level whose nearest earlier samples are found at once (few in unit tests, so
/// that their levels span several batches).
const BATCH: usize = if cfg!(test) { 100 } else { 1 << 14 };

impl Predictor {
    fn new(width: u32, height: u32) -> Self {
        Predictor {
            width: width as i64 * POS_ONE,
            height: height as i64 * POS_ONE,
            pos: Vec::new(),
            values: Vec::new(),
            mags: Vec::new(),
            cell: 1,
            gw: 0,
            gh: 0,
            start: Vec::new(),
            entries: Vec::new(),
            level: Vec::new(),
            order: Vec::new(),
            near: Vec::new(),
            batch: 0,
        }
    }

    /// Lays out the samples coded so far and the positions of the next level, in a grid of
    /// about 2 per cell at the level's end. The level's samples are then pushed in order.
    fn begin_level(&mut self, level: &[[i64; 2]]) {
        let end = self.pos.len() + level.len();
        let area = self.width as i128 * self.height as i128;
        let c = ((2 * area / end.max(1) as i128) as f64).sqrt() as i64;
        self.cell = c.max(POS_ONE);
        self.gw = (self.width + self.cell - 1) / self.cell + 1;
        self.gh = (self.height + self.cell - 1) / self.cell + 1;
        let cells = (self.gw * self.gh) as usize;
        self.start.clear();
        self.start.resize(cells + 1, 0);
        for &p in self.pos.iter().chain(level) {
            let k = self.cell_of(p);
            self.start[k + 1] += 1;
        }
        for k in 0..cells {
            self.start[k + 1] += self.start[k];
        }
        let mut fill = self.start[..cells].to_vec();
        self.entries.clear();
        self.entries.resize(end, ([0, 0], 0));
        for (i, &p) in self.pos.iter().chain(level).enumerate() {
            let k = self.cell_of(p);
            self.entries[fill[k] as usize] = (p, i as u32);
            fill[k] += 1;
        }
        // Every batch but the last holds BATCH samples: batch b starts at b·BATCH.
        let base = self.pos.len() as u32;
        self.order.clear();
        self.order.resize(level.len(), 0);
        let mut slot: Vec<usize> = (0..level.len().div_ceil(BATCH))
            .map(|b| b * BATCH)
            .collect();
        for &(_, i) in self.entries.iter().filter(|e| e.1 >= base) {
            let k = i - base;
            let b = k as usize / BATCH;
            self.order[slot[b]] = k;
            slot[b] += 1;
        }
        self.level.clear();
        self.level.extend_from_slice(level);
        self.near.clear();
        self.batch = 0;
    }

    /// The number within its level of the next sample to code.
    fn next(&self) -> usize {
        self.pos.len() + self.level.len() - self.entries.len()
    }

    /// The up to `NEIGHBOURS` samples nearest to the next sample of the level (which must
    /// exist), among those before it, as (squared distance, index), sorted.
    fn nearest_to_next(&mut self, best: &mut Vec<(i64, u32)>) {
        let base = self.entries.len() - self.level.len();
        let j = self.next();
        if j >= self.batch + self.near.len() {
            // The next batch, in grid order: neighbouring queries read neighbouring cells.
            debug_assert_eq!(j % BATCH, 0, "batches start at multiples of BATCH");
            self.batch = j;
            let end = (j + BATCH).min(self.level.len());
            self.near.clear();
            self.near
                .resize(end - j, [(i64::MAX, u32::MAX); NEIGHBOURS]);
            for n in j..end {
                let k = self.order[n] as usize;
                self.near[k - j] = self.nearest(self.level[k], (base + k) as u32);
            }
        }
        best.clear();
        let near = &self.near[j - self.batch];
        best.extend(near.iter().copied().take_while(|e| e.1 != u32::MAX));
    }

    fn cell_xy(&self, p: [i64; 2]) -> (i64, i64) {
        (
            (p[0] / self.cell).clamp(0, self.gw - 1),
            (p[1] / self.cell).clamp(0, self.gh - 1),
        )
    }

    fn cell_of(&self, p: [i64; 2]) -> usize {
        let (x, y) = self.cell_xy(p);
        (y * self.gw + x) as usize
    }

    /// Appends the next sample of the level laid out by [`Predictor::begin_level`] (which must
    /// exist): its coded values and luma residual magnitude.
    fn push(&mut self, v: &[i32], mag: u8) {
        self.mags.push(mag);
        self.pos.push(self.level[self.next()]);
        self.values.extend_from_slice(v);
    }

    /// The up to `NEIGHBOURS` nearest earlier samples as (squared distance, index), sorted.
    ///
    /// Cells are visited in square rings around `p`'s cell (the 3 × 3 cells of the first two
    /// at once); a cell of a later ring is skipped when even its nearest point is farther than
    /// the current `NEIGHBOURS`-th, and the search ends when no point outside the rings
    /// visited can be as near.
    fn nearest(&self, p: [i64; 2], coded: u32) -> [(i64, u32); NEIGHBOURS] {
        // The nearest so far, sorted by (squared distance, index); (i64::MAX, u32::MAX) fills.
        let mut top = [(i64::MAX, u32::MAX); NEIGHBOURS];
        if coded == 0 {
            return top;
        }
        // How many were taken.
        let mut found = 0usize;
        let cell = self.cell;
        let (cx, cy) = self.cell_xy(p);
        // Distance from p to the cells from `lo` to `hi` along one axis (0 inside): a lower
        // bound for any point in them, also those clamped into a border cell.
        let gap = |v: i64, lo: i64, hi: i64| (lo * cell - v).max(v - (hi + 1) * cell).max(0);
        let offer = |q: [i64; 2], i: u32, top: &mut [(i64, u32); NEIGHBOURS], found: &mut usize| {
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            let e = (dx * dx + dy * dy, i);
            if e < top[NEIGHBOURS - 1] {
                let mut k = NEIGHBOURS - 1;
                while k > 0 && e < top[k - 1] {
                    top[k] = top[k - 1];
                    k -= 1;
                }
                top[k] = e;
                *found += 1;
            }
        };
        let visit = |x: i64, y: i64, top: &mut [(i64, u32); NEIGHBOURS], found: &mut usize| {
            let (gx, gy) = (gap(p[0], x, x), gap(p[1], y, y));
            if gx * gx + gy * gy > top[NEIGHBOURS - 1].0 {
                return;
            }
            let c = (y * self.gw + x) as usize;
            let run = &self.entries[self.start[c] as usize..self.start[c + 1] as usize];
            for &(q, i) in run {
                if i >= coded {
                    break;
                }
                offer(q, i, top, found);
            }
        };
        // The first two rings, 3 × 3 cells, are visited whole: each of their rows of cells is
        // one run of `entries`, read straight through (skipping samples not coded yet).
        let (x0, x1) = ((cx - 1).max(0), (cx + 1).min(self.gw - 1));
        for y in (cy - 1).max(0)..=(cy + 1).min(self.gh - 1) {
            let row = y * self.gw;
            let (a, b) = (
                self.start[(row + x0) as usize],
                self.start[(row + x1 + 1) as usize],
            );
            for &(q, i) in &self.entries[a as usize..b as usize] {
                if i < coded {
                    offer(q, i, &mut top, &mut found);
                }
            }
        }
        for r in 1.. {
            if r > 1 {
                let (x0, x1) = ((cx - r).max(0), (cx + r).min(self.gw - 1));
                let (y0, y1) = ((cy - r).max(0), (cy + r).min(self.gh - 1));
                for y in y0..=y1 {
                    if y == cy - r || y == cy + r {
                        for x in x0..=x1 {
                            visit(x, y, &mut top, &mut found);
                        }
                    } else {
                        for x in [cx - r, cx + r] {
                            if (0..self.gw).contains(&x) {
                                visit(x, y, &mut top, &mut found);
                            }
                        }
                    }
                }
            }
            // Every cell not visited lies beyond a side of the rings that is not the grid's
            // border; its points are at least that side's distance from p.
            let mut beyond = i64::MAX;
            if cx - r > 0 {
                beyond = beyond.min(p[0] - (cx - r) * cell);
            }
            if cx + r < self.gw - 1 {
                beyond = beyond.min((cx + r + 1) * cell - p[0]);
            }
            if cy - r > 0 {
                beyond = beyond.min(p[1] - (cy - r) * cell);
            }
            if cy + r < self.gh - 1 {
                beyond = beyond.min((cy + r + 1) * cell - p[1]);
            }
            if beyond == i64::MAX
                || (found >= NEIGHBOURS && beyond > 0 && top[NEIGHBOURS - 1].0 < beyond * beyond)
            {
                break;
            }
        }
        top
    }
}

/// Context layout of the model.
const ACT: usize = 8;
const LUMA_CLASSES: usize = 3;
const EXP: usize = 10;
const PER_CTX: usize = 2 + EXP;
const MANT_PER_ACT: usize = EXP * EXP;

fn bitlen(v: u32) -> usize {
    (32 - v.leading_zeros()) as usize
}

/// The adaptive probabilities, with an undo log for decodes that run out of bytes.
#[derive(Clone, Debug)]
struct Model {
    probs: Vec<Prob>,
    log: Vec<(u32, Prob)>,
    logging: bool,
}

impl Model {
    fn new(channels: usize) -> Self {
        let per_channel = ACT * LUMA_CLASSES * PER_CTX + ACT * MANT_PER_ACT;
        Model {
            probs: vec![Prob::default(); channels * per_channel],
            log: Vec::new(),
            logging: false,
        }
    }
    fn undo(&mut self) {
        while let Some((i, p)) = self.log.pop() {
            self.probs[i as usize] = p;
        }
    }
}

/// Where a channel's bits go: encoder or decoder.
trait BitIo {
    /// Whether this is the encoder (which picks what the decoder reads).
    const ENCODES: bool;
    /// Codes (encoder) or decodes (decoder) one bit with probability `model.probs[i]`.
    fn bit(&mut self, model: &mut Model, i: usize, bit: bool) -> Option<bool>;
}

struct Enc<'a>(&'a mut RangeEncoder);
impl BitIo for Enc<'_> {
    const ENCODES: bool = true;
    fn bit(&mut self, model: &mut Model, i: usize, bit: bool) -> Option<bool> {
        self.0.encode(&mut model.probs[i], bit);
        Some(bit)
    }
}

struct Dec<'a> {
    rc: &'a mut RangeDecoder,
    bytes: &'a [u8],
    len: usize,
}
impl BitIo for Dec<'_> {
    const ENCODES: bool = false;
    fn bit(&mut self, model: &mut Model, i: usize, _bit: bool) -> Option<bool> {
        if model.logging {
            model.log.push((i as u32, model.probs[i]));
        }
        self.rc.decode(&mut model.probs[i], self.bytes, self.len)
    }
}

/// The quantised residual the encoder codes for value `v` predicted as `p`, in a channel of
/// range `lo..=hi` and step `step`: the nearest step, or one further when `v` is at an end of
/// the range (opaque, transparent, white, black) that the nearest falls short of, which the
/// decoder's clamp then makes exact (the nearest step short of 255 would leave an opaque
/// picture 254 everywhere: each sample predicts the next, so the shortfall never closes).
fn quantise(v: i32, p: i32, step: i32, lo: i32, hi: i32) -> i32 {
    let r = v - p;
    let q = if r >= 0 {
        (r + step / 2) / step
    } else {
        -((-r + step / 2) / step)
    };
    if v == hi && p + q * step < hi {
        q + 1
    } else if v == lo && p + q * step > lo {
        q - 1
    } else {
        q
    }
}

/// Codes the quantised residual `q` of one channel in context (`base` = the context's first
/// probability, `mant` = the first mantissa probability of its activity class).
fn code_residual<B: BitIo>(
    io: &mut B,
    m: &mut Model,
    base: usize,
    mant: usize,
    q: i32,
) -> Option<i32> {
    if !io.bit(m, base, q != 0)? {
        return Some(0);
    }
    let neg = io.bit(m, base + 1, q < 0)?;
    let mag = q.unsigned_abs();
    // When decoding, `q` is a placeholder: only its bits up to the first read matter.
    let e = bitlen(mag).saturating_sub(1); // 0..
    let mut got = 0;
    while got < EXP - 1 && io.bit(m, base + 2 + got, got < e)? {
        got += 1;
    }
    let mut v: u32 = 1;
    for b in (0..got).rev() {
        let bit = io.bit(m, mant + got * EXP + b, (mag >> b) & 1 == 1)?;
        v = (v << 1) | bit as u32;
    }
    let v = v as i32;
    Some(if neg { -v } else { v })
}

/// Inverse squared distance weights of neighbours given as (squared distance, index):
/// 2^62 / (d² + 2^12), each at most 2^50, so with values within ±255 a weighted sum stays
/// under 2^61 in i64. Also their sum.
pub(crate) fn weights(nbrs: &[(i64, u32)]) -> ([i64; NEIGHBOURS], i64) {
    let mut w = [0i64; NEIGHBOURS];
    let mut wsum = 0i64;
    for (k, &(d2, _)) in nbrs.iter().enumerate() {
        w[k] = (1i64 << 62) / d2.saturating_add(1 << 12);
        wsum += w[k];
    }
    (w, wsum)
}

/// The prediction from a weighted sum `acc` of values and the sum of the weights:
/// `floor((acc + floor(W/2)) / W)`.
pub(crate) fn weighted_mean(acc: i64, wsum: i64) -> i32 {
    (acc + wsum / 2).div_euclid(wsum) as i32
}

/// The shared closed-loop state of encoder and decoder.
#[derive(Clone, Debug)]
struct State {
    params: Params,
    layout_channels: usize,
    pred: Predictor,
    model: Model,
    nbrs: Vec<(i64, u32)>,
    /// |quantised luma residual| of the last coded sample.
    last_mag: u8,
}

impl State {
    fn new(params: Params, channels: u8, width: u32, height: u32) -> Result<Self, Error> {
        if !(1..=4).contains(&channels) {
            return Err(Error::invalid("channels", channels, "1..=4"));
        }
        if params.step == 0 {
            return Err(Error::invalid("predictive step", 0, "1..=255"));
        }
        let c = channels as usize;
        Ok(State {
            params,
            layout_channels: c,
            pred: Predictor::new(width, height),
            model: Model::new(c),
            nbrs: Vec::with_capacity(NEIGHBOURS),
            last_mag: 0,
        })
    }

    /// Codes the next sample of the level: `target` holds the coded-domain values to encode
    /// (ignored when decoding); returns the reconstructed coded-domain values in `recon`.
    fn code_sample<B: BitIo>(
        &mut self,
        io: &mut B,
        target: &[i32],
        recon: &mut [i32],
    ) -> Option<()> {
        let c = self.layout_channels;
        self.pred.nearest_to_next(&mut self.nbrs);
        let (w, wsum) = weights(&self.nbrs);
        let per_channel = ACT * LUMA_CLASSES * PER_CTX + ACT * MANT_PER_ACT;
        let mut luma_class = 0;
        for ch in 0..c {
            let (lo, hi, step) = channel_info(c, ch, &self.params);
            let (pred, spread) = if self.nbrs.is_empty() {
                ((lo + hi + 1) / 2, 0)
            } else {
                let mut acc = 0i64;
                let (mut mn, mut mx) = (i32::MAX, i32::MIN);
                for (k, &(_, i)) in self.nbrs.iter().enumerate() {
                    let v = self.pred.values[i as usize * c + ch];
                    acc += w[k] * v as i64;
                    mn = mn.min(v);
                    mx = mx.max(v);
                }
                let pr = weighted_mean(acc, wsum);
                (pr, mx - mn)
            };
            let act = bitlen((spread / step) as u32).min(ACT - 1);
            let lc = if ch == 0 {
                let e: u32 = self
                    .nbrs
                    .iter()
                    .map(|&(_, i)| self.pred.mags[i as usize] as u32)
                    .sum();
                bitlen(e).min(LUMA_CLASSES - 1)
            } else {
                luma_class
            };
            let base = ch * per_channel + (act * LUMA_CLASSES + lc) * PER_CTX;
            let mant = ch * per_channel + ACT * LUMA_CLASSES * PER_CTX + act * MANT_PER_ACT;
            // The decoder reads q: only the encoder picks it.
            let q = match B::ENCODES {
                true => quantise(target[ch], pred, step, lo, hi),
                false => 0,
            };
            let q = code_residual(io, &mut self.model, base, mant, q)?;
            let v = (pred as i64 + q as i64 * step as i64).clamp(lo as i64, hi as i64) as i32;
            recon[ch] = v;
            if ch == 0 {
                luma_class = bitlen(q.unsigned_abs()).min(LUMA_CLASSES - 1);
                self.last_mag = q.unsigned_abs().min(255) as u8;
            }
        }
        Some(())
    }
}

/// Encoder of the predictive coding: one call per level, in order.
#[derive(Clone, Debug)]
pub struct PredictiveEncoder {
    state: State,
}

impl PredictiveEncoder {
    /// An encoder for `channels` (layout order: 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA) of a
    /// `width × height` image.
    pub fn new(params: Params, channels: u8, width: u32, height: u32) -> Result<Self, Error> {
        Ok(PredictiveEncoder {
            state: State::new(params, channels, width, height)?,
        })
    }

    /// Encodes the next level: its sites' fixed-point positions
    /// ([`crate::sites::fixed_position`]) and their 8-bit colours in layout order. Returns the level's payload.
    pub fn encode_level(
        &mut self,
        positions: &[[i64; 2]],
        colours: &[u8],
    ) -> Result<Vec<u8>, Error> {
        let c = self.state.layout_channels;
        if colours.len() != positions.len() * c {
            return Err(Error::invalid(
                "colours",
                format_args!("{} values", colours.len()),
                format!(
                    "{} for {} samples of {c} channels",
                    positions.len() * c,
                    positions.len()
                ),
            ));
        }
        self.state.pred.begin_level(positions);
        let mut rc = RangeEncoder::new();
        let mut target = [0i32; 4];
        let mut recon = [0i32; 4];
        for px in colours.chunks_exact(c) {
            forward(c, px, &mut target);
            self.state
                .code_sample(&mut Enc(&mut rc), &target[..c], &mut recon[..c]);
            self.state.pred.push(&recon[..c], self.state.last_mag);
        }
        Ok(rc.finish())
    }

    /// The decoded colours (8-bit, layout order) of every sample encoded so far: what a decoder
    /// of the whole file reconstructs.
    pub fn reconstructed(&self) -> Vec<u8> {
        let c = self.state.layout_channels;
        let mut out = Vec::with_capacity(self.state.pred.values.len());
        for v in self.state.pred.values.chunks_exact(c) {
            inverse(c, v, &mut out);
        }
        out
    }
}

/// A level being decoded.
#[derive(Clone, Debug)]
struct Level {
    payload: Vec<u8>,
    payload_len: usize,
    rc: RangeDecoder,
}

/// Streaming decoder of the predictive coding: levels in order, payload bytes in any chunking.
/// Each sample is emitted as soon as decoding it needs no byte beyond those received.
#[derive(Clone, Debug)]
pub struct PredictiveDecoder {
    state: State,
    level: Option<Level>,
}

impl PredictiveDecoder {
    /// A decoder for `channels` of a `width × height` image (as [`PredictiveEncoder::new`]).
    pub fn new(params: Params, channels: u8, width: u32, height: u32) -> Result<Self, Error> {
        Ok(PredictiveDecoder {
            state: State::new(params, channels, width, height)?,
            level: None,
        })
    }

    /// Starts the next level: the fixed-point positions of its sites and its payload length.
    /// A level left unfinished is abandoned (its decoded samples stay).
    pub fn start_level(&mut self, positions: &[[i64; 2]], payload_len: usize) -> Result<(), Error> {
        self.state.pred.begin_level(positions);
        self.level = Some(Level {
            payload: Vec::new(),
            payload_len,
            rc: RangeDecoder::new(),
        });
        Ok(())
    }

    /// Samples decoded so far, over all levels.
    pub fn samples_done(&self) -> u64 {
        self.state.pred.pos.len() as u64
    }

    /// Feeds the next payload bytes of the current level; appends the 8-bit colours (layout
    /// order) of every sample completed to `out` and returns how many were.
    pub fn push(&mut self, bytes: &[u8], out: &mut Vec<u8>) -> Result<u64, Error> {
        let Some(level) = &mut self.level else {
            return Err(Error::misuse(
                "PredictiveDecoder::push",
                "payload bytes before a level begins",
            ));
        };
        let room = level.payload_len.saturating_sub(level.payload.len());
        level
            .payload
            .extend_from_slice(&bytes[..bytes.len().min(room)]);
        let c = self.state.layout_channels;
        let mut recon = [0i32; 4];
        let mut done = 0;
        self.state.model.logging = level.payload.len() < level.payload_len;
        while self.state.pred.next() < self.state.pred.level.len() {
            let saved = level.rc;
            self.state.model.log.clear();
            let mut io = Dec {
                rc: &mut level.rc,
                bytes: &level.payload,
                len: level.payload_len,
            };
            if self
                .state
                .code_sample(&mut io, &[0; 4][..c], &mut recon[..c])
                .is_none()
            {
                level.rc = saved;
                self.state.model.undo();
                break;
            }
            self.state.pred.push(&recon[..c], self.state.last_mag);
            inverse(c, &recon[..c], out);
            done += 1;
        }
        self.state.model.log.clear();
        Ok(done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ycocg_r_is_reversible() {
        let mut v = [0i32; 3];
        let mut out = Vec::new();
        for r in (0..=255u8).step_by(5) {
            for g in (0..=255u8).step_by(3) {
                for b in [0u8, 1, 77, 254, 255] {
                    forward(3, &[r, g, b], &mut v);
                    out.clear();
                    inverse(3, &v, &mut out);
                    assert_eq!(out, [r, g, b]);
                    assert!((-255..=255).contains(&v[1]) && (-255..=255).contains(&v[2]));
                }
            }
        }
    }

    /// Exact 4 nearest against brute force: random positions, positions on a coarse lattice
    /// (many equal distances, duplicates), positions on the image border and the last level
    /// abandoned half-way (its laid-out samples must not be found).
    #[test]
    fn nearest_matches_brute_force() {
        let mut s = 12345u64;
        let mut rnd = |m: i64| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((s >> 33) as i64).rem_euclid(m)
        };
        // The 4 nearest of p among the samples coded, by sorting them all.
        let brute = |pr: &Predictor, p: [i64; 2]| {
            let d2 = |q: &[i64; 2]| (q[0] - p[0]).pow(2) + (q[1] - p[1]).pow(2);
            let mut all: Vec<(i64, u32)> = (pr.pos.iter().enumerate())
                .map(|(i, q)| (d2(q), i as u32))
                .collect();
            all.sort_unstable();
            all.truncate(NEIGHBOURS);
            all
        };
        // 0, -4: positions on multiples of the grid's cell side, of a quarter of it (distances
        // equal to the bound of a cell, or of the cells not visited).
        for coarse in [1i64, 5 * 256, 19 * 256, 0, -4] {
            let mut pr = Predictor::new(100, 60);
            let mut unit = coarse;
            let mut got = Vec::new();
            for level_end in [1usize, 2, 4, 8, 16, 64, 256, 1024, 2000] {
                let n = level_end - pr.pos.len();
                // The grid depends on the count only.
                pr.begin_level(&vec![[0, 0]; n]);
                if coarse <= 0 {
                    unit = pr.cell / coarse.abs().max(1);
                }
                let level: Vec<[i64; 2]> = (0..n)
                    .map(|_| match rnd(8) {
                        0 => [0, rnd(60 * 256)],
                        1 => [100 * 256 - 1, rnd(60 * 256)],
                        _ => [rnd(100 * 256) / unit * unit, rnd(60 * 256) / unit * unit],
                    })
                    .collect();
                pr.begin_level(&level);
                // The last level is abandoned at half.
                let take = if level_end == 2000 { n / 2 } else { n };
                for &p in &level[..take] {
                    pr.nearest_to_next(&mut got);
                    assert_eq!(
                        got,
                        brute(&pr, p),
                        "coarse {coarse}, sample {}",
                        pr.pos.len()
                    );
                    pr.push(&[0], 0);
                }
            }
            // Queries anywhere, also outside the image, after the abandoned level.
            for _ in 0..500 {
                let p = [rnd(140 * 256) - 20 * 256, rnd(100 * 256) - 20 * 256];
                let p = p.map(|v| v / unit * unit);
                let got: Vec<_> = (pr.nearest(p, pr.pos.len() as u32).into_iter())
                    .take_while(|e| e.1 != u32::MAX)
                    .collect();
                assert_eq!(got, brute(&pr, p), "coarse {coarse}, query {p:?}");
            }
        }
    }

    /// A sample tied with the 4th nearest, with a smaller index, exactly at the distance
    /// beyond which the search stops: it must be found.
    #[test]
    fn nearest_finds_a_tie_at_the_search_bound() {
        let mut pr = Predictor::new(100, 60);
        let n = 200;
        pr.begin_level(&vec![[0, 0]; n]);
        let c = pr.cell;
        assert!(pr.gw > 6 && pr.gh > 7, "grid {}x{}", pr.gw, pr.gh);
        // p in cell (3, 2); after the first ring the nearest side not visited is at x = 5c.
        let p = [3 * c + c - c / 4, 2 * c + c / 2];
        let d = 5 * c - p[0];
        let mut level = vec![
            [p[0] + d, p[1]], // index 0, in cell (5, 2)
            [p[0] + 1, p[1]],
            [p[0] - 1, p[1]],
            [p[0], p[1] + 1],
            [p[0] - d, p[1]], // index 4, as far, in a cell of the first ring
        ];
        while level.len() < n {
            let k = level.len() as i64;
            level.push([(k % 90) * 256, 59 * 256 - (k % 7) * 256]);
        }
        pr.begin_level(&level);
        for _ in &level {
            pr.push(&[0], 0);
        }
        assert_eq!(
            pr.nearest(p, n as u32),
            [(1, 1), (1, 2), (1, 3), (d * d, 0)]
        );
    }
}
