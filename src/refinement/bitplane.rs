//! The bit-plane coder: the passes of a stream over its bands, shared by the encoder and the
//! decoder (spec/format.md, *Refinement: coding a pass*).
//!
//! A stream is a sequence of [`Pass`]es over bands (one band of one channel each). A pass codes
//! one bit-plane of a band, block by block in [`block_order`], each block in stripes of four
//! rows, column by column (JPEG 2000's scan). Its *units* are what a decoder commits at once:
//! a block's activation flag, or one stripe column (up to four coefficients). A decoder that
//! runs out of bytes inside a unit rolls it back and resumes there when more bytes arrive, so
//! the state after any number of bytes is that of the last complete unit.

use super::schedule::{block_order, Band, Orient, Pass, PassKind, BLOCK};
use crate::coding::range::{Prob, RangeDecoder, RangeEncoder};

const SIG: u8 = 1;
const VISITED: u8 = 2;
const REFINED: u8 = 4;
const NEG: u8 = 8;

// Context layout within one (channel class, orientation) set.
const CTX_SIG: usize = 0; // 9
const CTX_SIGN: usize = 9; // 5
const CTX_REF: usize = 14; // 3
const CTX_RUN: usize = 17;
const CTX_UNI: usize = 18; // 2
const CTX_BLOCK: usize = 20; // 3
const CTX_BAND: usize = 23;
const CTX_SET: usize = 24;
/// Probabilities of one stream: 3 channel classes × 4 orientations.
pub(crate) const STREAM_CONTEXTS: usize = 3 * 4 * CTX_SET;

/// Which context set a channel uses: 0 luma (or grey), 1 chroma, 2 alpha.
pub(crate) type ChannelClass = u8;

/// One band of one channel, with what is known of its coefficients.
#[derive(Clone, Debug)]
pub(crate) struct BandState {
    pub band: Band,
    pub class: ChannelClass,
    /// Row stride of `flags`: the band's width plus a border column on each side.
    pw: usize,
    /// Per coefficient, with a one-coefficient border of zeros: SIG, VISITED, REFINED, NEG.
    flags: Vec<u8>,
    /// The magnitude bits known so far.
    pub mag: Vec<u32>,
    /// For a significant coefficient, the lowest bit-plane known.
    pub known: Vec<u8>,
    /// Whether each block holds a significant coefficient.
    block_active: Vec<bool>,
    /// Whether any block does.
    band_active: bool,
    order: Vec<(u32, u32)>,
    /// Encoder only: the coefficients being coded.
    pub truth: Vec<i32>,
}

impl BandState {
    pub(crate) fn new(band: Band, class: ChannelClass, truth: Vec<i32>) -> BandState {
        let pw = band.w + 2;
        let (bw, bh) = band.blocks();
        BandState {
            band,
            class,
            pw,
            flags: vec![0; pw * (band.h + 2)],
            mag: vec![0; band.len()],
            known: vec![0; band.len()],
            block_active: vec![false; bw * bh],
            band_active: false,
            order: block_order(&band),
            truth,
        }
    }

    #[inline(always)]
    fn fi(&self, x: usize, y: usize) -> usize {
        (y + 1) * self.pw + x + 1
    }

    /// The value a decoder reconstructs for coefficient `i` (band-local index): zero unless
    /// significant; else the known bits plus 3/8 of the unknown interval below them.
    #[inline]
    pub(crate) fn value(&self, x: usize, y: usize) -> i32 {
        let f = self.flags[self.fi(x, y)];
        if f & SIG == 0 {
            return 0;
        }
        let i = y * self.band.w + x;
        let k = self.known[i] as u32;
        let m = self.mag[i] + ((3u32 << k) >> 3);
        if f & NEG != 0 {
            -(m as i32)
        } else {
            m as i32
        }
    }

    /// Significant horizontal, vertical and diagonal neighbours.
    #[inline(always)]
    fn neighbours(&self, fi: usize) -> (u32, u32, u32) {
        let f = &self.flags;
        let pw = self.pw;
        let s = |i: usize| (f[i] & SIG) as u32;
        let h = s(fi - 1) + s(fi + 1);
        let v = s(fi - pw) + s(fi + pw);
        let d = s(fi - pw - 1) + s(fi - pw + 1) + s(fi + pw - 1) + s(fi + pw + 1);
        (h, v, d)
    }

    #[inline(always)]
    fn sig_context(&self, fi: usize) -> usize {
        let (h, v, d) = self.neighbours(fi);
        sig_context(self.band.orient, h, v, d)
    }

    #[inline(always)]
    fn sign_context(&self, fi: usize) -> (usize, bool) {
        let f = &self.flags;
        let c = |i: usize| -> i32 {
            let v = f[i];
            if v & SIG == 0 {
                0
            } else if v & NEG != 0 {
                -1
            } else {
                1
            }
        };
        let hc = (c(fi - 1) + c(fi + 1)).clamp(-1, 1);
        let vc = (c(fi - self.pw) + c(fi + self.pw)).clamp(-1, 1);
        match (hc, vc) {
            (1, 1) => (4, false),
            (1, 0) => (3, false),
            (1, -1) => (2, false),
            (0, 1) => (1, false),
            (0, 0) => (0, false),
            (0, -1) => (1, true),
            (-1, 1) => (2, true),
            (-1, 0) => (3, true),
            _ => (4, true),
        }
    }

    fn block_context(&self, bx: usize, by: usize) -> usize {
        let (bw, bh) = self.band.blocks();
        let a = |x: usize, y: usize| self.block_active[y * bw + x] as usize;
        let mut n = 0;
        if bx > 0 {
            n += a(bx - 1, by);
        }
        if bx + 1 < bw {
            n += a(bx + 1, by);
        }
        if by > 0 {
            n += a(bx, by - 1);
        }
        if by + 1 < bh {
            n += a(bx, by + 1);
        }
        n.min(2)
    }
}

/// JPEG 2000's significance contexts (ISO/IEC 15444-1 Table D.1): from the numbers of
/// significant horizontal, vertical and diagonal neighbours.
#[inline(always)]
fn sig_context(orient: Orient, h: u32, v: u32, d: u32) -> usize {
    match orient {
        Orient::HighHigh => {
            let hv = h + v;
            match d {
                3.. => 8,
                2 => 6 + (hv >= 1) as usize,
                1 => 3 + (hv.min(2)) as usize,
                _ => hv.min(2) as usize,
            }
        }
        _ => {
            // Vertical edges (high horizontally) look along columns: swap.
            let (h, v) = if orient == Orient::HighLow {
                (v, h)
            } else {
                (h, v)
            };
            match h {
                2 => 8,
                1 => {
                    if v >= 1 {
                        7
                    } else if d >= 1 {
                        6
                    } else {
                        5
                    }
                }
                _ => match v {
                    2 => 4,
                    1 => 3,
                    _ => d.min(2) as usize,
                },
            }
        }
    }
}

/// A coder of binary decisions: the range encoder, or a decoder that may run out of bytes.
pub(crate) trait Symbols {
    /// Whether this codes the truth (the encoder) rather than reading bits.
    const ENCODES: bool;
    /// Codes `bit` (encoder) or decodes one (decoder; `None` when the bytes so far do not
    /// decide it) with the probability `probs[ctx]`, which then adapts.
    fn code(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> Option<bool>;
    /// Called before each unit.
    fn begin_unit(&mut self) {}
    /// Called when a unit ran out of bytes: puts back the coder and the probabilities it
    /// changed as they were at the unit's start.
    fn rollback(&mut self, _probs: &mut [Prob]) {}
}

/// The encoder side: every bit is coded as given.
pub(crate) struct Encoding {
    pub enc: RangeEncoder,
}

impl Symbols for Encoding {
    const ENCODES: bool = true;
    #[inline(always)]
    fn code(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> Option<bool> {
        self.enc.encode(&mut probs[ctx], bit);
        Some(bit)
    }
}

/// The decoder side over the bytes of a stream received so far (what follows them is
/// unknown). Near their end, every probability a unit changes is journalled so that the unit
/// can be rolled back if the bytes do not decide it.
pub(crate) struct Decoding<'a> {
    pub dec: RangeDecoder,
    pub bytes: &'a [u8],
    saved: RangeDecoder,
    journal: Vec<(usize, Prob)>,
    careful: bool,
}

/// Bytes a unit can read at most (11 decisions of at most 12 bits each, and the 4-byte code
/// window), with room to spare: with more than this left, a unit cannot run out.
const UNIT_BYTES: usize = 64;

impl<'a> Decoding<'a> {
    pub(crate) fn new(dec: RangeDecoder, bytes: &'a [u8]) -> Self {
        Decoding {
            dec,
            bytes,
            saved: dec,
            journal: Vec::new(),
            careful: true,
        }
    }
}

impl Symbols for Decoding<'_> {
    const ENCODES: bool = false;
    #[inline(always)]
    fn code(&mut self, probs: &mut [Prob], ctx: usize, _bit: bool) -> Option<bool> {
        if self.careful {
            self.journal.push((ctx, probs[ctx]));
        }
        self.dec.decode(&mut probs[ctx], self.bytes, usize::MAX)
    }

    #[inline(always)]
    fn begin_unit(&mut self) {
        self.careful = self.bytes.len() < self.dec.position() + UNIT_BYTES;
        if self.careful {
            self.saved = self.dec;
            self.journal.clear();
        }
    }

    fn rollback(&mut self, probs: &mut [Prob]) {
        assert!(
            self.careful,
            "a unit ran out of bytes with {UNIT_BYTES} to spare"
        );
        for &(ctx, p) in self.journal.iter().rev() {
            probs[ctx] = p;
        }
        self.dec = self.saved;
    }
}

/// Where a stream's coding stands: the next unit to code.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Cursor {
    /// Index of the pass in the stream's pass list.
    pub pass: usize,
    /// The cleanup of a band with no active block has decided its band flag (and it is 1).
    band_open: bool,
    /// Index into the band's block order.
    pub(crate) block: usize,
    /// The block being coded was decided (its flag, if it needed one, was 1).
    block_open: bool,
    /// Stripe column within the block: stripe index × block width + column.
    column: usize,
}

/// The state of one stream: its bands, its probabilities, its passes and where it stands.
#[derive(Clone, Debug)]
pub(crate) struct StreamState {
    pub bands: Vec<BandState>,
    /// The channel of each band.
    channels: Vec<u8>,
    /// For each pass, the index in `bands` of the band it codes.
    targets: Vec<usize>,
    pub passes: Vec<Pass>,
    pub probs: Vec<Prob>,
    pub cursor: Cursor,
}

/// What a unit changed, to undo it.
#[derive(Default)]
struct Undo {
    coefficients: Vec<(usize, usize, u8, u32, u8)>,
    block: Option<(usize, bool)>,
    band_active: bool,
}

/// The encoder's account of a unit: how much it lowered the squared error of its band's
/// coefficients (in coefficient units).
pub(crate) trait Tally {
    /// Whether it counts at all (the decoder's `()` does not, and costs nothing).
    const COUNTS: bool;
    fn gain(&mut self, before: i64, after: i64);
}

impl Tally for () {
    const COUNTS: bool = false;
    #[inline(always)]
    fn gain(&mut self, _: i64, _: i64) {}
}

/// Sum of the decrease of squared error.
#[derive(Default)]
pub(crate) struct ErrorDrop(pub f64);

impl Tally for ErrorDrop {
    const COUNTS: bool = true;
    #[inline(always)]
    fn gain(&mut self, before: i64, after: i64) {
        self.0 += (before * before - after * after) as f64;
    }
}

impl StreamState {
    /// A stream over `bands` (each with its channel), coding `passes`, whose pass `k`
    /// codes `bands[target(passes[k])]`.
    pub(crate) fn new(bands: Vec<(u8, BandState)>, band_index: &[u16], passes: Vec<Pass>) -> Self {
        let targets = passes
            .iter()
            .map(|p| {
                band_index
                    .iter()
                    .zip(&bands)
                    .position(|(&b, (c, _))| b == p.band && *c == p.channel)
                    .expect("every pass codes a band of its stream")
            })
            .collect();
        StreamState {
            channels: bands.iter().map(|(c, _)| *c).collect(),
            bands: bands.into_iter().map(|(_, b)| b).collect(),
            targets,
            passes,
            probs: vec![Prob::default(); STREAM_CONTEXTS],
            cursor: Cursor::default(),
        }
    }

    /// The channel of band `k`.
    pub(crate) fn channel_of(&self, k: usize) -> usize {
        self.channels[k] as usize
    }

    /// Which band pass `k` codes.
    pub(crate) fn target(&self, k: usize) -> usize {
        self.targets[k]
    }

    /// Codes units until `limit` passes are done, or (decoder) the bytes run out. `tally`
    /// hears of every change to a coefficient's reconstruction; `pass_done(k)` of every
    /// completed pass.
    pub(crate) fn run<S: Symbols, T: Tally>(
        &mut self,
        sym: &mut S,
        limit: usize,
        tally: &mut T,
        pass_done: &mut dyn FnMut(&mut S, &mut T, usize),
    ) {
        let mut undo = Undo::default();
        while self.cursor.pass < limit.min(self.passes.len()) {
            sym.begin_unit();
            let saved_cursor = self.cursor;
            undo.coefficients.clear();
            undo.block = None;
            undo.band_active = self.bands[self.targets[self.cursor.pass]].band_active;
            let journal = !S::ENCODES;
            let done = self.unit(sym, tally, journal.then_some(&mut undo));
            match done {
                Some(pass_finished) => {
                    if pass_finished {
                        let k = self.cursor.pass;
                        self.cursor = Cursor {
                            pass: k + 1,
                            ..Cursor::default()
                        };
                        pass_done(sym, tally, k);
                    }
                }
                None => {
                    // Out of bytes: undo the unit and stop.
                    sym.rollback(&mut self.probs);
                    let b = &mut self.bands[self.targets[saved_cursor.pass]];
                    for &(fi, i, f, m, k) in undo.coefficients.iter().rev() {
                        b.flags[fi] = f;
                        b.mag[i] = m;
                        b.known[i] = k;
                    }
                    if let Some((blk, a)) = undo.block {
                        b.block_active[blk] = a;
                    }
                    b.band_active = undo.band_active;
                    self.cursor = saved_cursor;
                    return;
                }
            }
        }
    }

    /// Codes the next unit of the current pass; `Some(true)` when the pass is then complete.
    fn unit<S: Symbols, T: Tally>(
        &mut self,
        sym: &mut S,
        tally: &mut T,
        undo: Option<&mut Undo>,
    ) -> Option<bool> {
        let pass = self.passes[self.cursor.pass];
        let ti = self.targets[self.cursor.pass];
        let band = &mut self.bands[ti];
        let set = (band.class as usize * 4 + band.band.orient as usize) * CTX_SET;
        let probs = &mut self.probs[..];
        let cur = &mut self.cursor;
        let p = pass.bitplane as u32;
        if band.order.is_empty() {
            return Some(true);
        }
        // A cleanup of a band without active blocks starts with the band's flag.
        if pass.kind == PassKind::Cleanup && !band.band_active && !cur.band_open && cur.block == 0 {
            let truth = S::ENCODES && band_has_new(band, p);
            let bit = sym.code(probs, set + CTX_BAND, truth)?;
            if !bit {
                return Some(true);
            }
            cur.band_open = true;
            return Some(false);
        }
        let (bx, by) = band.order[cur.block];
        let (bw, _) = band.band.blocks();
        let blk = by as usize * bw + bx as usize;
        let active = band.block_active[blk];
        if !active && !cur.block_open {
            match pass.kind {
                PassKind::Propagation | PassKind::Refinement => return Some(next_block(band, cur)),
                PassKind::Cleanup => {
                    let truth = S::ENCODES && block_has_new(band, bx, by, p);
                    let ctx = set + CTX_BLOCK + band.block_context(bx as usize, by as usize);
                    let bit = sym.code(probs, ctx, truth)?;
                    if !bit {
                        return Some(next_block(band, cur));
                    }
                    cur.block_open = true;
                    return Some(false);
                }
            }
        }
        // One stripe column of the block.
        let x0 = bx as usize * BLOCK;
        let y0 = by as usize * BLOCK;
        let cols = BLOCK.min(band.band.w - x0);
        let rows = BLOCK.min(band.band.h - y0);
        let stripe = cur.column / cols;
        let x = x0 + cur.column % cols;
        let ys = y0 + 4 * stripe;
        let ye = (ys + 4).min(y0 + rows);
        if let Some(u) = undo {
            for y in ys..ye {
                let fi = band.fi(x, y);
                let i = y * band.band.w + x;
                u.coefficients
                    .push((fi, i, band.flags[fi], band.mag[i], band.known[i]));
            }
            u.block = Some((blk, band.block_active[blk]));
        }
        match pass.kind {
            PassKind::Propagation => {
                for y in ys..ye {
                    let fi = band.fi(x, y);
                    if band.flags[fi] & SIG == 0 {
                        let (h, v, d) = band.neighbours(fi);
                        if h + v + d > 0 {
                            let ctx = set + CTX_SIG + sig_context(band.band.orient, h, v, d);
                            code_significance(band, sym, probs, tally, x, y, p, ctx, set)?;
                            band.flags[fi] |= VISITED;
                        }
                    }
                }
            }
            PassKind::Refinement => {
                for y in ys..ye {
                    let fi = band.fi(x, y);
                    let f = band.flags[fi];
                    if f & SIG != 0 && f & VISITED == 0 {
                        let ctx = if f & REFINED != 0 {
                            2
                        } else {
                            let (h, v, d) = band.neighbours(fi);
                            (h + v + d > 0) as usize
                        };
                        let i = y * band.band.w + x;
                        let truth = S::ENCODES && (band.truth[i].unsigned_abs() >> p) & 1 != 0;
                        let before = if T::COUNTS { band.value(x, y) } else { 0 };
                        let bit = sym.code(probs, set + CTX_REF + ctx, truth)?;
                        band.mag[i] |= (bit as u32) << p;
                        band.known[i] = p as u8;
                        band.flags[fi] |= REFINED;
                        if T::COUNTS {
                            let t = band.truth[i] as i64;
                            tally.gain(t - before as i64, t - band.value(x, y) as i64);
                        }
                    }
                }
            }
            PassKind::Cleanup => {
                let mut y = ys;
                if ye - ys == 4 {
                    let quiet = (ys..ye).all(|yy| {
                        let fi = band.fi(x, yy);
                        band.flags[fi] & (SIG | VISITED) == 0 && {
                            let (h, v, d) = band.neighbours(fi);
                            h + v + d == 0
                        }
                    });
                    if quiet {
                        let first = if S::ENCODES {
                            (ys..ye).position(|yy| {
                                let i = yy * band.band.w + x;
                                (band.truth[i].unsigned_abs() >> p) & 1 != 0
                            })
                        } else {
                            None
                        };
                        let any = sym.code(probs, set + CTX_RUN, first.is_some())?;
                        if any {
                            let k = first.unwrap_or(0);
                            let hi = sym.code(probs, set + CTX_UNI, k & 2 != 0)?;
                            let lo = sym.code(probs, set + CTX_UNI + 1, k & 1 != 0)?;
                            let k = 2 * hi as usize + lo as usize;
                            let yy = ys + k;
                            let fi = band.fi(x, yy);
                            let (sc, flip) = band.sign_context(fi);
                            let i = yy * band.band.w + x;
                            let neg_truth = S::ENCODES && band.truth[i] < 0;
                            let neg =
                                sym.code(probs, set + CTX_SIGN + sc, neg_truth ^ flip)? ^ flip;
                            make_significant(band, tally, x, yy, p, neg);
                            y = yy + 1;
                        } else {
                            y = ye;
                        }
                    }
                }
                while y < ye {
                    let fi = band.fi(x, y);
                    if band.flags[fi] & (SIG | VISITED) == 0 {
                        let ctx = set + CTX_SIG + band.sig_context(fi);
                        code_significance(band, sym, probs, tally, x, y, p, ctx, set)?;
                    }
                    y += 1;
                }
                for yy in ys..ye {
                    let fi = band.fi(x, yy);
                    band.flags[fi] &= !VISITED;
                }
            }
        }
        // Next stripe column, or the next block.
        cur.column += 1;
        if cur.column == cols * rows.div_ceil(4) {
            return Some(next_block(band, cur));
        }
        Some(false)
    }
}

/// Moves the cursor to the next block; `true` when the band's blocks are all done.
fn next_block(band: &BandState, cur: &mut Cursor) -> bool {
    cur.block += 1;
    cur.column = 0;
    cur.block_open = false;
    cur.block == band.order.len()
}

/// Codes whether coefficient (x, y), insignificant so far, is significant at bit-plane `p`,
/// and if so its sign.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn code_significance<S: Symbols, T: Tally>(
    band: &mut BandState,
    sym: &mut S,
    probs: &mut [Prob],
    tally: &mut T,
    x: usize,
    y: usize,
    p: u32,
    ctx: usize,
    set: usize,
) -> Option<()> {
    let i = y * band.band.w + x;
    let truth = S::ENCODES && (band.truth[i].unsigned_abs() >> p) & 1 != 0;
    if sym.code(probs, ctx, truth)? {
        let fi = band.fi(x, y);
        let (sc, flip) = band.sign_context(fi);
        let neg_truth = S::ENCODES && band.truth[i] < 0;
        let neg = sym.code(probs, set + CTX_SIGN + sc, neg_truth ^ flip)? ^ flip;
        make_significant(band, tally, x, y, p, neg);
    }
    Some(())
}

#[inline(always)]
fn make_significant<T: Tally>(
    band: &mut BandState,
    tally: &mut T,
    x: usize,
    y: usize,
    p: u32,
    neg: bool,
) {
    let fi = band.fi(x, y);
    let i = y * band.band.w + x;
    band.flags[fi] |= SIG | if neg { NEG } else { 0 };
    band.mag[i] = 1 << p;
    band.known[i] = p as u8;
    let (bw, _) = band.band.blocks();
    band.block_active[(y / BLOCK) * bw + x / BLOCK] = true;
    band.band_active = true;
    if T::COUNTS {
        let t = band.truth[i] as i64;
        tally.gain(t, t - band.value(x, y) as i64);
    }
}

/// Encoder: whether an insignificant coefficient of the block becomes significant at `p`.
fn block_has_new(band: &BandState, bx: u32, by: u32, p: u32) -> bool {
    let x0 = bx as usize * BLOCK;
    let y0 = by as usize * BLOCK;
    (y0..(y0 + BLOCK).min(band.band.h)).any(|y| {
        (x0..(x0 + BLOCK).min(band.band.w)).any(|x| {
            let i = y * band.band.w + x;
            band.flags[band.fi(x, y)] & SIG == 0 && (band.truth[i].unsigned_abs() >> p) & 1 != 0
        })
    })
}

/// Encoder: whether any coefficient of a band without significant ones becomes significant.
fn band_has_new(band: &BandState, p: u32) -> bool {
    band.truth.iter().any(|&t| (t.unsigned_abs() >> p) & 1 != 0)
}
