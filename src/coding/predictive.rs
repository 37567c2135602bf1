//! Coding 1, predictive: every sample is predicted from the samples before it (closed loop, exact
//! integer arithmetic) and only the quantised residual is coded, with an adaptive binary range
//! coder and contexts (spec/format.md §Coding 1 is normative; this is its implementation).
//!
//! * Colours are transformed reversibly: RGB → YCoCg-R, grey as is, alpha its own channel.
//! * Site positions are fixed point, 1/256 px, computed exactly from the lattice coordinates
//!   ([`fixed_position`]).
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
use crate::lattice::ZZeta;
use crate::sites::Frame;
use crate::Error;

/// How many earlier samples a prediction uses.
pub const NEIGHBOURS: usize = 4;

/// Fixed-point unit of positions: 1/256 px.
pub const POS_ONE: i64 = 256;

/// The parameters of the predictive coding (its header parameter byte).
///
/// The luma quantisation step `s` (1..=255). Luma, grey and alpha use `s`; the chroma
/// channels Co and Cg use `2s − 1`. `s = 1` is lossless.
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

    /// The header's coding for these parameters.
    ///
    /// ```
    /// use qcs::coding::predictive::Params;
    /// use qcs::container::Coding;
    /// assert_eq!(Params::from_quality(80).coding(), Coding::Predictive { step: 5 });
    /// ```
    pub fn coding(&self) -> crate::container::Coding {
        crate::container::Coding::Predictive { step: self.step }
    }
}

const TAU_32: i128 = 6_949_403_065; // round(τ · 2^32)
const SIN72_32: i128 = 4_084_756_634; // round(sin 72° · 2^32)

/// The exact fixed-point position (1/256 px) of a lattice point in a frame, in integers:
///
/// ```text
/// 2·Re x = a + bτ,  Im x / sin72° = u + vτ          (ZZeta::re2, ZZeta::im_s)
/// X = floor((2^33·Cx + L·(2^32·a + T·b) + 2^40) / 2^41)
/// Y = floor((2^64·Cy + L·S·(2^32·u + T·v) + 2^71) / 2^72)
/// T = round(τ·2^32) = 6949403065,  S = round(sin72°·2^32) = 4084756634
/// ```
///
/// ```
/// use qcs::sites::Quasicrystal;
/// let q = Quasicrystal::new(64, 48).unwrap();
/// for s in q.first(50) {
///     let p = qcs::coding::predictive::fixed_position(&q.frame(), s.lattice);
///     assert!((p[0] as f64 / 256.0 - s.pos[0]).abs() <= 0.5 / 256.0 + 1e-9);
///     assert!((p[1] as f64 / 256.0 - s.pos[1]).abs() <= 0.5 / 256.0 + 1e-9);
/// }
/// ```
pub fn fixed_position(frame: &Frame, x: ZZeta) -> [i64; 2] {
    let l = frame.root_len as i128;
    let re = x.re2();
    let im = x.im_s();
    let nx = ((frame.origin[0] as i128) << 33) + l * ((re.a << 32) + TAU_32 * re.b);
    let ny = ((frame.origin[1] as i128) << 64) + l * SIN72_32 * ((im.a << 32) + TAU_32 * im.b);
    [
        ((nx + (1i128 << 40)) >> 41) as i64,
        ((ny + (1i128 << 71)) >> 72) as i64,
    ]
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
    /// Per cell, its samples' positions and indices (inline: no second lookup per candidate).
    grid: Vec<Vec<([i64; 2], u32)>>,
}

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
            grid: Vec::new(),
        }
    }

    /// Rebuilds the grid for a level that will end with `end` samples (≈ 2 per cell then).
    fn begin_level(&mut self, end: usize) {
        let area = self.width as i128 * self.height as i128;
        let c = ((2 * area / end.max(1) as i128) as f64).sqrt() as i64;
        self.cell = c.max(POS_ONE);
        self.gw = (self.width + self.cell - 1) / self.cell + 1;
        self.gh = (self.height + self.cell - 1) / self.cell + 1;
        self.grid = vec![Vec::new(); (self.gw * self.gh) as usize];
        for i in 0..self.pos.len() {
            let k = self.cell_of(self.pos[i]);
            self.grid[k].push((self.pos[i], i as u32));
        }
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

    fn push(&mut self, p: [i64; 2], v: &[i32], mag: u8) {
        self.mags.push(mag);
        let k = self.cell_of(p);
        self.grid[k].push((p, self.pos.len() as u32));
        self.pos.push(p);
        self.values.extend_from_slice(v);
    }

    /// The up to `NEIGHBOURS` nearest earlier samples as (squared distance, index), sorted.
    fn nearest(&self, p: [i64; 2], best: &mut Vec<(i64, u32)>) {
        best.clear();
        if self.pos.is_empty() {
            return;
        }
        // The nearest so far, sorted by (squared distance, index), and how many were taken.
        let mut top = [(i64::MAX, u32::MAX); NEIGHBOURS];
        let mut found = 0usize;
        let mut consider = |cell: &[([i64; 2], u32)]| {
            for &(q, i) in cell {
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                let e = (dx * dx + dy * dy, i);
                if e < top[NEIGHBOURS - 1] {
                    let mut k = NEIGHBOURS - 1;
                    while k > 0 && e < top[k - 1] {
                        top[k] = top[k - 1];
                        k -= 1;
                    }
                    top[k] = e;
                    found += 1;
                }
            }
            (found, top[NEIGHBOURS - 1].0)
        };
        let mut state = (0, i64::MAX);
        let (cx, cy) = self.cell_xy(p);
        let rmax = self.gw.max(self.gh);
        for r in 0..=rmax {
            for y in (cy - r).max(0)..=(cy + r).min(self.gh - 1) {
                let row = (y * self.gw) as usize;
                if y == cy - r || y == cy + r {
                    for x in (cx - r).max(0)..=(cx + r).min(self.gw - 1) {
                        state = consider(&self.grid[row + x as usize]);
                    }
                } else {
                    for x in [cx - r, cx + r] {
                        if (0..self.gw).contains(&x) {
                            state = consider(&self.grid[row + x as usize]);
                        }
                    }
                }
            }
            let reach = r * self.cell;
            if state.0 >= NEIGHBOURS && state.1 < reach * reach {
                break;
            }
        }
        let taken = state.0.min(NEIGHBOURS);
        best.extend(top.into_iter().take(taken));
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
    /// Codes (encoder) or decodes (decoder) one bit with probability `model.probs[i]`.
    fn bit(&mut self, model: &mut Model, i: usize, bit: bool) -> Option<bool>;
}

struct Enc<'a>(&'a mut RangeEncoder);
impl BitIo for Enc<'_> {
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
    fn bit(&mut self, model: &mut Model, i: usize, _bit: bool) -> Option<bool> {
        if model.logging {
            model.log.push((i as u32, model.probs[i]));
        }
        self.rc.decode(&mut model.probs[i], self.bytes, self.len)
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
            return Err(Error::Parameter(format!("{channels} channels")));
        }
        if params.step == 0 {
            return Err(Error::Parameter("predictive step 0".into()));
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

    /// Codes one sample at `p`: `target` holds the coded-domain values to encode (ignored when
    /// decoding); returns the reconstructed coded-domain values in `recon`.
    fn code_sample<B: BitIo>(
        &mut self,
        io: &mut B,
        p: [i64; 2],
        target: &[i32],
        recon: &mut [i32],
    ) -> Option<()> {
        let c = self.layout_channels;
        self.pred.nearest(p, &mut self.nbrs);
        // Inverse squared distance weights, 2^62 / (d² + 2^12).
        let mut w = [0i128; NEIGHBOURS];
        let mut wsum = 0i128;
        for (k, &(d2, _)) in self.nbrs.iter().enumerate() {
            w[k] = (1i128 << 62) / (d2 as i128 + (1 << 12));
            wsum += w[k];
        }
        let per_channel = ACT * LUMA_CLASSES * PER_CTX + ACT * MANT_PER_ACT;
        let mut luma_class = 0;
        for ch in 0..c {
            let (lo, hi, step) = channel_info(c, ch, &self.params);
            let (pred, spread) = if self.nbrs.is_empty() {
                ((lo + hi + 1) / 2, 0)
            } else {
                let mut acc = 0i128;
                let (mut mn, mut mx) = (i32::MAX, i32::MIN);
                for (k, &(_, i)) in self.nbrs.iter().enumerate() {
                    let v = self.pred.values[i as usize * c + ch];
                    acc += w[k] * v as i128;
                    mn = mn.min(v);
                    mx = mx.max(v);
                }
                let pr = (acc + wsum / 2).div_euclid(wsum) as i32;
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
            let r = target[ch] - pred;
            let q = if r >= 0 {
                (r + step / 2) / step
            } else {
                -((-r + step / 2) / step)
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

    /// Encodes the next level: its sites' fixed-point positions ([`fixed_position`]) and their
    /// 8-bit colours in layout order. Returns the level's payload.
    pub fn encode_level(
        &mut self,
        positions: &[[i64; 2]],
        colours: &[u8],
    ) -> Result<Vec<u8>, Error> {
        let c = self.state.layout_channels;
        if colours.len() != positions.len() * c {
            return Err(Error::Parameter(format!(
                "{} colour values for {} samples of {c} channels",
                colours.len(),
                positions.len()
            )));
        }
        let end = self.state.pred.pos.len() + positions.len();
        self.state.pred.begin_level(end);
        let mut rc = RangeEncoder::new();
        let mut target = [0i32; 4];
        let mut recon = [0i32; 4];
        for (p, px) in positions.iter().zip(colours.chunks_exact(c)) {
            forward(c, px, &mut target);
            self.state
                .code_sample(&mut Enc(&mut rc), *p, &target[..c], &mut recon[..c]);
            self.state.pred.push(*p, &recon[..c], self.state.last_mag);
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
    positions: Vec<[i64; 2]>,
    next: usize,
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
        let end = self.state.pred.pos.len() + positions.len();
        self.state.pred.begin_level(end);
        self.level = Some(Level {
            positions: positions.to_vec(),
            next: 0,
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
            return Err(Error::Parameter(
                "payload bytes before a level start".into(),
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
        while level.next < level.positions.len() {
            let p = level.positions[level.next];
            let saved = level.rc;
            self.state.model.log.clear();
            let mut io = Dec {
                rc: &mut level.rc,
                bytes: &level.payload,
                len: level.payload_len,
            };
            if self
                .state
                .code_sample(&mut io, p, &[0; 4][..c], &mut recon[..c])
                .is_none()
            {
                level.rc = saved;
                self.state.model.undo();
                break;
            }
            self.state.pred.push(p, &recon[..c], self.state.last_mag);
            inverse(c, &recon[..c], out);
            level.next += 1;
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

    #[test]
    fn nearest_matches_brute_force() {
        let mut pr = Predictor::new(100, 60);
        let mut s = 12345u64;
        let mut rnd = |m: i64| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((s >> 33) as i64).rem_euclid(m)
        };
        let mut got = Vec::new();
        for level_end in [1usize, 2, 4, 8, 16, 64, 256, 1024] {
            pr.begin_level(level_end);
            while pr.pos.len() < level_end {
                let p = [rnd(100 * 256), rnd(60 * 256)];
                pr.nearest(p, &mut got);
                let mut all: Vec<(i64, u32)> = pr
                    .pos
                    .iter()
                    .enumerate()
                    .map(|(i, q)| ((q[0] - p[0]).pow(2) + (q[1] - p[1]).pow(2), i as u32))
                    .collect();
                all.sort_unstable();
                all.truncate(NEIGHBOURS);
                assert_eq!(got, all);
                pr.push(p, &[0], 0);
            }
        }
    }
}
