//! The bit-plane coder: the passes of a stream over its bands, shared by the encoder and the
//! decoder (spec/refinement.md §6).
//!
//! A stream is a sequence of [`Pass`]es over bands (one band of one channel each). A pass codes
//! one bit-plane of a band, block by block in [`block_order`], each block in stripes of four
//! rows, column by column (JPEG 2000's scan). Its *units* are what a decoder commits at once:
//! a band's or a block's activation flag, or one stripe column (up to four coefficients). A
//! decoder near the end of the bytes it has codes unit by unit, journalling each so that one
//! the bytes do not decide is rolled back (it resumes there when more bytes arrive); with
//! bytes to spare, it codes a whole block at a time with no journal.
//!
//! Per coefficient the state is 4 bytes, made a block at a time when a pass first codes the
//! block (most blocks of a lossy file's fine bands never are): its magnitude bits below 2^16,
//! a byte of flags and a byte of its neighbours' significance (the bits from 2^16 up, which
//! no file an encoder writes for 8-bit pictures has, go to a band-wide array made when first
//! needed). The lowest bit-plane known of a significant coefficient is its band's current
//! bit-plane or the one above, told apart by a parity flag (every significant coefficient is
//! refined at every bit-plane).

use super::schedule::{block_order, Band, Orient, Pass, PassKind, BLOCK};
use super::written_zeros;
use crate::coding::range::{Prob, RangeDecoder, RangeEncoder};

/// A coefficient's flags: its state (SIG, VISITED, REFINED, NEG, ODD) in the low byte, the
/// significance of its 8 neighbours (a pattern of N_LEFT, N_RIGHT, … bits) in the high byte,
/// kept up to date as coefficients become significant.
type Flags = u16;
const SIG: Flags = 1;
const VISITED: Flags = 2;
const REFINED: Flags = 4;
const NEG: Flags = 8;
/// The parity of the bit-plane the coefficient was last coded at.
const ODD: Flags = 16;
/// Where the neighbour pattern starts.
const NEIGHBOURS: u32 = 8;

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

/// Neighbour bits of a coefficient's pattern: left, right, up, down, and the diagonals.
const N_LEFT: u8 = 1;
const N_RIGHT: u8 = 2;
const N_UP: u8 = 4;
const N_DOWN: u8 = 8;

/// The sign context and whether the sign is coded flipped, for the horizontal and vertical
/// contributions (each −1, 0 or 1) of a coefficient's neighbours, at 3 (h + 1) + v + 1
/// (JPEG 2000's Table D.3).
const SIGN_CONTEXT: [(usize, bool); 9] = [
    (4, true),  // h −1, v −1
    (3, true),  // h −1, v 0
    (2, true),  // h −1, v 1
    (1, true),  // h 0, v −1
    (0, false), // h 0, v 0
    (1, false), // h 0, v 1
    (2, false), // h 1, v −1
    (3, false), // h 1, v 0
    (4, false), // h 1, v 1
];

/// The significance context of every neighbour pattern, per orientation.
static SIG_CONTEXT: [[u8; 256]; 4] = sig_context_table();

const fn sig_context_table() -> [[u8; 256]; 4] {
    let mut t = [[0u8; 256]; 4];
    let mut o = 0;
    while o < 4 {
        let mut n = 0;
        while n < 256 {
            let n32 = n as u32;
            let h = (n32 & 1) + ((n32 >> 1) & 1);
            let v = ((n32 >> 2) & 1) + ((n32 >> 3) & 1);
            let d = ((n32 >> 4) & 1) + ((n32 >> 5) & 1) + ((n32 >> 6) & 1) + ((n32 >> 7) & 1);
            let orient = match o {
                0 => Orient::LowLow,
                1 => Orient::HighLow,
                2 => Orient::LowHigh,
                _ => Orient::HighHigh,
            };
            t[o][n] = sig_context(orient, h, v, d) as u8;
            n += 1;
        }
        o += 1;
    }
    t
}

/// JPEG 2000's significance contexts (ISO/IEC 15444-1 Table D.1): from the numbers of
/// significant horizontal, vertical and diagonal neighbours.
const fn sig_context(orient: Orient, h: u32, v: u32, d: u32) -> usize {
    if let Orient::HighHigh = orient {
        let hv = h + v;
        return match d {
            3.. => 8,
            2 => 6 + (hv >= 1) as usize,
            1 => 3 + if hv > 2 { 2 } else { hv as usize },
            _ => {
                if hv > 2 {
                    2
                } else {
                    hv as usize
                }
            }
        };
    }
    // Vertical edges (high horizontally) look along columns: swap.
    let (h, v) = if let Orient::HighLow = orient {
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
            _ => {
                if d > 2 {
                    2
                } else {
                    d as usize
                }
            }
        },
    }
}

/// No block state (see [`BandState::slot`]).
const UNOPENED: u32 = u32::MAX;

/// The 8 neighbours of a coefficient, as (dx, dy) and the bit of the neighbour pattern that
/// this coefficient is for that neighbour: for the one on the right, it is on the left…
const TELLS: [(isize, isize, u8); 8] = [
    (1, 0, N_LEFT),
    (-1, 0, N_RIGHT),
    (0, 1, N_UP),
    (0, -1, N_DOWN),
    (1, 1, 0x10),
    (-1, 1, 0x20),
    (1, -1, 0x40),
    (-1, -1, 0x80),
];

/// One band of one channel, with what is known of its coefficients.
///
/// A block's state is made when a pass first codes its coefficients (its flag in a cleanup
/// pass is 1): until then they are all zero and insignificant, and most blocks of the fine
/// bands of a lossy file stay so. So a band holds 4 bytes per coefficient of its opened
/// blocks only.
#[derive(Clone, Debug)]
pub(crate) struct BandState {
    pub band: Band,
    pub class: ChannelClass,
    /// Blocks across.
    bw: usize,
    /// Per block (row-major), the index `s` of its state, or [`UNOPENED`]: its coefficients'
    /// flags are `flags[s · area..]`, and their magnitude bits below 2^16 `low[s · area..]`,
    /// row-major with rows of `stride` (see [`BandState::at`]).
    slot: Vec<u32>,
    /// A block's row length and size in its state: [`BLOCK`], or less for a band narrower
    /// or lower than a block (a block at the band's right or bottom edge uses the top-left
    /// part of its state; the rest is never coded).
    stride: usize,
    area: usize,
    /// The block's interior in its state, `stride − 2` by `area / stride − 2` (0 if none):
    /// the coefficients whose 8 neighbours are all in it ([`BandState::within`]).
    inner: (usize, usize),
    flags: Vec<Flags>,
    low: Vec<u16>,
    /// The magnitude bits from 2^16 up, row-major over the band (empty until the first).
    high: Vec<u16>,
    /// The bit-plane of the band's latest pass.
    current: u8,
    /// Whether each block holds a significant coefficient.
    block_active: Vec<bool>,
    /// Whether any block does.
    band_active: bool,
    order: Vec<(u32, u32)>,
    /// Encoder only: the coefficients being coded.
    pub truth: Vec<i32>,
    /// Encoder only: per block (row-major), the OR of its coefficients' magnitudes (the
    /// bit-planes where any of them has a 1), and the same over the band.
    truth_bits: (Vec<u32>, u32),
}

impl BandState {
    pub(crate) fn new(band: Band, class: ChannelClass, truth: Vec<i32>) -> BandState {
        let (bw, bh) = band.blocks();
        BandState {
            band,
            class,
            bw,
            slot: vec![UNOPENED; bw * bh],
            stride: BLOCK.min(band.w),
            area: BLOCK.min(band.w) * BLOCK.min(band.h),
            inner: (
                BLOCK.min(band.w).saturating_sub(2),
                BLOCK.min(band.h).saturating_sub(2),
            ),
            flags: Vec::new(),
            low: Vec::new(),
            high: Vec::new(),
            current: 0,
            block_active: vec![false; bw * bh],
            band_active: false,
            order: block_order(&band),
            truth_bits: truth_bits(&band, &truth),
            truth,
        }
    }

    /// Where coefficient (x, y), of a block with state `s`, is in `flags` and `low`.
    #[inline(always)]
    fn at(&self, s: usize, x: usize, y: usize) -> usize {
        s * self.area + (y % BLOCK) * self.stride + x % BLOCK
    }

    /// The block of coefficient (x, y).
    #[inline(always)]
    fn block_of(&self, x: usize, y: usize) -> usize {
        (y / BLOCK) * self.bw + x / BLOCK
    }

    /// The state of block `blk` (row-major index), made now if it has none: its coefficients
    /// insignificant, those on its edges told of their significant neighbours in other
    /// blocks. Returns the index `s` of its state.
    fn open(&mut self, blk: usize) -> usize {
        if self.slot[blk] != UNOPENED {
            return self.slot[blk] as usize;
        }
        let s = self.flags.len() / self.area;
        if s == 0 {
            // Room for every block at once: growing would copy the states made so far into
            // fresh pages each time (pages never written cost nothing).
            let all = self.slot.len() * self.area;
            self.flags.reserve_exact(all);
            self.low.reserve_exact(all);
        }
        self.flags.resize((s + 1) * self.area, 0);
        self.low.resize((s + 1) * self.area, 0);
        self.slot[blk] = s as u32;
        // Inside the block no coefficient is significant yet: only those on its edges can
        // have significant neighbours, just outside it in the opened blocks around it.
        let (bx, by) = (blk % self.bw, blk / self.bw);
        let (bw, bh) = self.band.blocks();
        let opened =
            |xx: usize, yy: usize| (xx, yy) != (bx, by) && self.slot[yy * bw + xx] != UNOPENED;
        let ys = by.saturating_sub(1)..(by + 2).min(bh);
        if !ys
            .into_iter()
            .any(|yy| (bx.saturating_sub(1)..(bx + 2).min(bw)).any(|xx| opened(xx, yy)))
        {
            return s;
        }
        let (x0, y0) = ((bx * BLOCK) as isize, (by * BLOCK) as isize);
        let x1 = (x0 + BLOCK as isize).min(self.band.w as isize);
        let y1 = (y0 + BLOCK as isize).min(self.band.h as isize);
        let inside = |x: isize, y: isize| (x0..x1).contains(&x) && (y0..y1).contains(&y);
        // The ring around the block: its rows above and below, and its columns to the left
        // and right.
        let across = (x0 - 1..=x1).flat_map(|x| [(x, y0 - 1), (x, y1)]);
        let down = (y0..y1).flat_map(|y| [(x0 - 1, y), (x1, y)]);
        for (nx, ny) in across.chain(down) {
            if self.flags_near(0, 0, nx, ny) & SIG == 0 {
                continue;
            }
            for &(dx, dy, bit) in &TELLS {
                let (x, y) = (nx + dx, ny + dy);
                if inside(x, y) {
                    let i = self.at(s, x as usize, y as usize);
                    self.flags[i] |= (bit as Flags) << NEIGHBOURS;
                }
            }
        }
        s
    }

    /// The flags of coefficient (x + dx, y + dy): 0 outside the band or in a block with no
    /// state.
    #[inline(always)]
    fn flags_near(&self, x: usize, y: usize, dx: isize, dy: isize) -> Flags {
        let (nx, ny) = (x.wrapping_add_signed(dx), y.wrapping_add_signed(dy));
        if nx >= self.band.w || ny >= self.band.h {
            return 0;
        }
        match self.slot[self.block_of(nx, ny)] {
            UNOPENED => 0,
            s => self.flags[self.at(s as usize, nx, ny)],
        }
    }

    /// Whether the 8 neighbours of the coefficient at (lx, ly) in its block are in the
    /// block's state too (those past the band's edge are never coded, nor significant).
    #[inline(always)]
    fn within(&self, lx: usize, ly: usize) -> bool {
        lx.wrapping_sub(1) < self.inner.0 && ly.wrapping_sub(1) < self.inner.1
    }

    /// The flags of coefficient (x, y), whose block has state `s`.
    #[inline(always)]
    fn flags(&self, s: usize, x: usize, y: usize) -> Flags {
        self.flags[self.at(s, x, y)]
    }

    #[inline(always)]
    fn flags_mut(&mut self, s: usize, x: usize, y: usize) -> &mut Flags {
        let i = self.at(s, x, y);
        &mut self.flags[i]
    }

    /// The reconstruction of a coefficient from its flags and magnitude bits, the band's
    /// current bit-plane being `current` (spec/refinement.md §7).
    #[inline(always)]
    fn value_of(f: Flags, m: u32, current: u8) -> i32 {
        // Without branches, so that a row's values vectorise: all ones if significant, and
        // the sign as a mask (two's complement negation is `(m ^ neg) - neg`).
        let sig = ((f & SIG) as i32).wrapping_neg();
        let neg = (((f & NEG) != 0) as i32).wrapping_neg();
        let k = current as u32 + ((f & ODD != 0) != (current & 1 == 1)) as u32;
        let m = (m + ((3u32 << k) >> 3)) as i32;
        ((m ^ neg).wrapping_sub(neg)) & sig
    }

    /// The lowest bit-plane known of coefficient (x, y), if it is significant.
    #[cfg(test)]
    pub(crate) fn known(&self, x: usize, y: usize) -> Option<u32> {
        let f = self.flags_near(x, y, 0, 0);
        (f & SIG != 0)
            .then(|| self.current as u32 + ((f & ODD != 0) != (self.current & 1 == 1)) as u32)
    }

    /// The magnitude bits of coefficient `i` (band-local, row-major index).
    #[cfg(test)]
    pub(crate) fn mag(&self, i: usize) -> u32 {
        let (x, y) = (i % self.band.w, i / self.band.w);
        match self.slot[self.block_of(x, y)] {
            UNOPENED => 0,
            s => self.mag_in(s as usize, x, y),
        }
    }

    /// The magnitude bits of coefficient (x, y), whose block has state `s`.
    #[inline(always)]
    fn mag_in(&self, s: usize, x: usize, y: usize) -> u32 {
        self.mag_at(self.at(s, x, y), x, y)
    }

    /// The magnitude bits of coefficient (x, y), at `at` in `low` ([`BandState::at`]).
    #[inline(always)]
    fn mag_at(&self, at: usize, x: usize, y: usize) -> u32 {
        let high = if self.high.is_empty() {
            0
        } else {
            self.high[y * self.band.w + x]
        };
        self.low[at] as u32 | (high as u32) << 16
    }

    #[inline(always)]
    fn set_mag(&mut self, s: usize, x: usize, y: usize, m: u32) {
        self.set_mag_at(self.at(s, x, y), x, y, m)
    }

    /// [`BandState::set_mag`] of the coefficient at `at` ([`BandState::at`]).
    #[inline(always)]
    fn set_mag_at(&mut self, i: usize, x: usize, y: usize, m: u32) {
        self.low[i] = m as u16;
        if m >> 16 != 0 || !self.high.is_empty() {
            if self.high.is_empty() {
                self.high = written_zeros(self.band.len());
            }
            self.high[y * self.band.w + x] = (m >> 16) as u16;
        }
    }

    /// The value a decoder reconstructs for coefficient (x, y).
    #[cfg(test)]
    pub(crate) fn value(&self, x: usize, y: usize) -> i32 {
        match self.slot[self.block_of(x, y)] {
            UNOPENED => 0,
            s => Self::value_of(
                self.flags(s as usize, x, y),
                self.mag_in(s as usize, x, y),
                self.current,
            ),
        }
    }

    /// Row `y`'s reconstructed values into `out` (the band's width): added to it (wrapping)
    /// if `add`, else written over it.
    pub(crate) fn row_values(&self, y: usize, out: &mut [i32], add: bool) {
        if add {
            self.row_values_with::<true>(y, out)
        } else {
            self.row_values_with::<false>(y, out)
        }
    }

    fn row_values_with<const ADD: bool>(&self, y: usize, out: &mut [i32]) {
        let put = |o: &mut i32, v: i32| *o = if ADD { o.wrapping_add(v) } else { v };
        let w = self.band.w;
        for (bx, out) in out[..w].chunks_mut(BLOCK).enumerate() {
            let s = self.slot[(y / BLOCK) * self.bw + bx];
            if s == UNOPENED {
                if !ADD {
                    out.fill(0);
                }
                continue;
            }
            let at = self.at(s as usize, 0, y);
            let flags = &self.flags[at..at + out.len()];
            let low = &self.low[at..at + out.len()];
            if self.high.is_empty() {
                for ((o, &f), &m) in out.iter_mut().zip(flags).zip(low) {
                    put(o, Self::value_of(f, m as u32, self.current));
                }
            } else {
                let x0 = y * w + bx * BLOCK;
                let high = &self.high[x0..x0 + out.len()];
                for (((o, &f), &m), &h) in out.iter_mut().zip(flags).zip(low).zip(high) {
                    put(
                        o,
                        Self::value_of(f, m as u32 | (h as u32) << 16, self.current),
                    );
                }
            }
        }
    }

    /// The significance of the 8 neighbours of (x, y), as N_LEFT, N_RIGHT, N_UP, N_DOWN and
    /// four diagonal bits, from their flags.
    fn pattern_at(&self, x: usize, y: usize) -> u8 {
        TELLS.iter().fold(0, |n, &(dx, dy, bit)| {
            // The neighbour at (x − dx, y − dy), if significant, tells (x, y) `bit`.
            let sig = self.flags_near(x, y, -dx, -dy) & SIG != 0;
            n | if sig { bit } else { 0 }
        })
    }

    /// Marks coefficient (x, y), at `at` in its block's state, just made significant, in its
    /// neighbours' patterns (those in blocks with no state learn it when they get one).
    #[inline(always)]
    fn tell_neighbours(&mut self, at: usize, x: usize, y: usize) {
        let (lx, ly) = (x % BLOCK, y % BLOCK);
        if self.within(lx, ly) {
            let (i, stride) = (at as isize, self.stride as isize);
            for &(dx, dy, bit) in &TELLS {
                self.flags[(i + dy * stride + dx) as usize] |= (bit as Flags) << NEIGHBOURS;
            }
            return;
        }
        for &(dx, dy, bit) in &TELLS {
            let (nx, ny) = (x.wrapping_add_signed(dx), y.wrapping_add_signed(dy));
            if nx < self.band.w && ny < self.band.h {
                let n = self.slot[self.block_of(nx, ny)];
                if n != UNOPENED {
                    let i = self.at(n as usize, nx, ny);
                    self.flags[i] |= (bit as Flags) << NEIGHBOURS;
                }
            }
        }
    }

    /// Makes the neighbour patterns of the band's coefficients within one of `(x, y)` agree
    /// with their neighbours' flags again (after a unit was rolled back).
    fn recount_neighbours(&mut self, x: usize, y: usize) {
        for yy in y.saturating_sub(1)..(y + 2).min(self.band.h) {
            for xx in x.saturating_sub(1)..(x + 2).min(self.band.w) {
                let s = self.slot[self.block_of(xx, yy)];
                if s != UNOPENED {
                    let n = self.pattern_at(xx, yy) as Flags;
                    let f = self.flags_mut(s as usize, xx, yy);
                    *f = (*f & 0xff) | n << NEIGHBOURS;
                }
            }
        }
    }

    /// The sign context of coefficient (x, y) from its horizontal and vertical neighbours,
    /// and whether the sign is coded flipped.
    #[inline(always)]
    fn sign_context(&self, at: usize, x: usize, y: usize) -> (usize, bool) {
        let (lx, ly) = (x % BLOCK, y % BLOCK);
        let within = self.within(lx, ly);
        // Left, right, up, down.
        let [l, r, u, d] = if within {
            let (i, stride) = (at, self.stride);
            let f = &self.flags;
            [f[i - 1], f[i + 1], f[i - stride], f[i + stride]]
        } else {
            [(-1, 0), (1, 0), (0, -1), (0, 1)].map(|(dx, dy)| self.flags_near(x, y, dx, dy))
        };
        // 0 if insignificant, else −1 if negative and 1 if not (without branches).
        let c = |v: Flags| -> i32 {
            let sig = (v & SIG) as i32;
            sig - 2 * (sig & ((v & NEG) != 0) as i32)
        };
        let hc = (c(l) + c(r)).clamp(-1, 1);
        let vc = (c(u) + c(d)).clamp(-1, 1);
        SIGN_CONTEXT[(3 * (hc + 1) + vc + 1) as usize]
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

/// A coder of binary decisions: the range encoder, or a decoder that may run out of bytes.
pub(crate) trait Symbols {
    /// Whether this codes the truth (the encoder) rather than reading bits.
    const ENCODES: bool;
    /// Codes `bit` (encoder) or decodes one (decoder; `None` when the bytes so far do not
    /// decide it) with the probability `probs[ctx]`, which then adapts.
    fn code(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> Option<bool>;
    /// [`Symbols::code`] where the bytes are known to decide the bit (a unit coded
    /// unjournalled: [`Mode::Block`] or [`Mode::Unit`]).
    fn code_sure(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> bool;
    /// Called before each unit (or block): how it is coded.
    fn begin_unit(&mut self) -> Mode {
        Mode::Block
    }
    /// Called when the units allowed so far were coded alone and unjournalled: how many more
    /// units of the block can be coded the same way without returning to the pass runner.
    fn more_units(&mut self) -> usize {
        0
    }
    /// Called when a unit ran out of bytes: puts back the coder and the probabilities it
    /// changed as they were at the unit's start.
    fn rollback(&mut self, _probs: &mut [Prob]) {}
}

/// How the next unit is coded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Mode {
    /// With the rest of its block, unjournalled: the block cannot run out of bytes.
    Block,
    /// Alone, unjournalled: the unit cannot run out of bytes.
    Unit,
    /// Alone, journalled: it may run out of bytes, and then is rolled back.
    Journal,
}

/// The encoder side: every bit is coded as given.
pub(crate) struct Encoding {
    pub enc: RangeEncoder,
}

impl Symbols for Encoding {
    const ENCODES: bool = true;
    #[inline(always)]
    fn code(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> Option<bool> {
        Some(self.code_sure(probs, ctx, bit))
    }
    #[inline(always)]
    fn code_sure(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> bool {
        self.enc.encode(&mut probs[ctx], bit);
        bit
    }
}

/// A coder in a unit coded unjournalled ([`Mode::Block`], [`Mode::Unit`]): every decision is
/// decided, so the passes' checks for running out of bytes fold away.
struct Sure<'s, S>(&'s mut S);

impl<S: Symbols> Symbols for Sure<'_, S> {
    const ENCODES: bool = S::ENCODES;
    #[inline(always)]
    fn code(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> Option<bool> {
        Some(self.0.code_sure(probs, ctx, bit))
    }
    #[inline(always)]
    fn code_sure(&mut self, probs: &mut [Prob], ctx: usize, bit: bool) -> bool {
        self.0.code_sure(probs, ctx, bit)
    }
    #[inline(always)]
    fn more_units(&mut self) -> usize {
        self.0.more_units()
    }
}

/// The decoder side over the bytes of a stream received so far (what follows them is
/// unknown). Near their end, every probability a unit changes is journalled so that the unit
/// can be rolled back if the bytes do not decide it; with bytes to spare, bits are decoded on
/// the fast path.
pub(crate) struct Decoding<'a> {
    pub dec: RangeDecoder,
    pub bytes: &'a [u8],
    saved: RangeDecoder,
    journal: Vec<(usize, Prob)>,
    careful: bool,
    /// Units that can still be coded alone and unjournalled without asking the decoder.
    spare: usize,
}

/// Bytes a block's pass can read at most (1024 coefficients, each at most a significance,
/// a sign and a run or block decision of at most 12 bits; and the 4-byte code window), with
/// room to spare: with more than this left, it cannot run out.
const BLOCK_BYTES: usize = 8 * 1024;

/// The same for one unit: at most 10 decisions (a stripe column's cleanup: a run, two for
/// the position, a sign, then a significance and a sign for each of the other three), each
/// shifting in at most 2 bytes (its probability is at least 1/4096).
const UNIT_BYTES: usize = 64;

impl<'a> Decoding<'a> {
    pub(crate) fn new(dec: RangeDecoder, bytes: &'a [u8]) -> Self {
        Decoding {
            dec,
            bytes,
            saved: dec,
            journal: Vec::new(),
            careful: true,
            spare: 0,
        }
    }
}

impl Symbols for Decoding<'_> {
    const ENCODES: bool = false;
    #[inline(always)]
    fn code(&mut self, probs: &mut [Prob], ctx: usize, _bit: bool) -> Option<bool> {
        self.journal.push((ctx, probs[ctx]));
        self.dec.decode(&mut probs[ctx], self.bytes, usize::MAX)
    }

    #[inline(always)]
    fn code_sure(&mut self, probs: &mut [Prob], ctx: usize, _bit: bool) -> bool {
        self.dec.decode_fast(&mut probs[ctx], self.bytes)
    }

    #[inline(always)]
    fn begin_unit(&mut self) -> Mode {
        // One look at the bytes left decides the mode (a block needs BLOCK_BYTES of them).
        let runs = self.dec.fast_runs(self.bytes, UNIT_BYTES);
        self.spare = runs.saturating_sub(1);
        let mode = if runs >= BLOCK_BYTES / UNIT_BYTES {
            Mode::Block
        } else if runs > 0 {
            Mode::Unit
        } else {
            self.saved = self.dec;
            self.journal.clear();
            Mode::Journal
        };
        self.careful = mode == Mode::Journal;
        mode
    }

    #[inline(always)]
    fn more_units(&mut self) -> usize {
        if self.careful {
            return 0;
        }
        if self.spare == 0 {
            self.spare = self.dec.fast_runs(self.bytes, UNIT_BYTES);
        }
        std::mem::take(&mut self.spare)
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
    /// (x, y, flags, magnitude) of each coefficient of the unit, as they were.
    coefficients: Vec<(usize, usize, Flags, u32)>,
    block: Option<(usize, bool)>,
    band_active: bool,
    current: u8,
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

/// What a step of the pass runner did.
enum Step {
    /// Coded a unit (or a block); the pass goes on.
    More,
    /// The pass is complete.
    PassDone,
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

    /// Codes until `limit` passes are done, or (decoder) the bytes run out. `tally` hears of
    /// every change to a coefficient's reconstruction; `pass_done(k)` of every completed pass.
    pub(crate) fn run<S: Symbols, T: Tally>(
        &mut self,
        sym: &mut S,
        limit: usize,
        tally: &mut T,
        pass_done: &mut dyn FnMut(&mut S, &mut T, usize),
    ) {
        let mut undo = Undo::default();
        while self.cursor.pass < limit.min(self.passes.len()) {
            let mode = sym.begin_unit();
            // Only a journalled unit can run out of bytes and be rolled back.
            let saved_cursor = (mode == Mode::Journal).then_some(self.cursor);
            let done = if mode == Mode::Journal {
                let b = &self.bands[self.targets[self.cursor.pass]];
                undo.coefficients.clear();
                undo.block = None;
                undo.band_active = b.band_active;
                undo.current = b.current;
                self.step(sym, tally, true, Some(&mut undo))
            } else {
                self.step(&mut Sure(sym), tally, mode == Mode::Unit, None)
            };
            match done {
                Some(Step::More) => {}
                Some(Step::PassDone) => {
                    let k = self.cursor.pass;
                    self.cursor = Cursor {
                        pass: k + 1,
                        ..Cursor::default()
                    };
                    pass_done(sym, tally, k);
                }
                None => {
                    // Out of bytes: undo the unit and stop.
                    let saved_cursor = saved_cursor.expect("only a journalled unit runs out");
                    sym.rollback(&mut self.probs);
                    let b = &mut self.bands[self.targets[saved_cursor.pass]];
                    for &(x, y, f, m) in undo.coefficients.iter().rev() {
                        let s = b.slot[b.block_of(x, y)] as usize;
                        *b.flags_mut(s, x, y) = f;
                        b.set_mag(s, x, y, m);
                    }
                    for &(x, y, _, _) in &undo.coefficients {
                        b.recount_neighbours(x, y);
                    }
                    if let Some((blk, a)) = undo.block {
                        b.block_active[blk] = a;
                    }
                    b.band_active = undo.band_active;
                    b.current = undo.current;
                    self.cursor = saved_cursor;
                    return;
                }
            }
        }
    }

    /// Codes the next unit of the current pass if `one` (and the units after it in its block
    /// while [`Symbols::more_units`] allows), else the rest of the current block;
    /// journalled in `undo` if given.
    fn step<S: Symbols, T: Tally>(
        &mut self,
        sym: &mut S,
        tally: &mut T,
        one: bool,
        undo: Option<&mut Undo>,
    ) -> Option<Step> {
        let pass = self.passes[self.cursor.pass];
        let ti = self.targets[self.cursor.pass];
        let band = &mut self.bands[ti];
        let set = (band.class as usize * 4 + band.band.orient as usize) * CTX_SET;
        let probs = &mut self.probs[..];
        let cur = &mut self.cursor;
        let p = pass.bitplane as u32;
        if band.order.is_empty() {
            return Some(Step::PassDone);
        }
        band.current = pass.bitplane;
        // A cleanup of a band without active blocks starts with the band's flag.
        if pass.kind == PassKind::Cleanup && !band.band_active && !cur.band_open && cur.block == 0 {
            let truth = S::ENCODES && band_has_new(band, p);
            if !sym.code(probs, set + CTX_BAND, truth)? {
                return Some(Step::PassDone);
            }
            cur.band_open = true;
            return Some(Step::More);
        }
        let (bx, by) = band.order[cur.block];
        let (bw, _) = band.band.blocks();
        let blk = by as usize * bw + bx as usize;
        if !band.block_active[blk] && !cur.block_open {
            match pass.kind {
                PassKind::Propagation | PassKind::Refinement => {
                    return Some(next_block(band, cur));
                }
                PassKind::Cleanup => {
                    let truth = S::ENCODES && block_has_new(band, bx, by, p);
                    let ctx = set + CTX_BLOCK + band.block_context(bx as usize, by as usize);
                    if !sym.code(probs, ctx, truth)? {
                        return Some(next_block(band, cur));
                    }
                    cur.block_open = true;
                    if one {
                        return Some(Step::More);
                    }
                }
            }
        }
        // Stripe columns of the block: one (journalled), or all that are left.
        let x0 = bx as usize * BLOCK;
        let y0 = by as usize * BLOCK;
        let cols = BLOCK.min(band.band.w - x0);
        let rows = BLOCK.min(band.band.h - y0);
        let s = band.open(blk);
        let block = BlockAt {
            s,
            x0,
            y0,
            cols,
            rows,
        };
        if let Some(u) = undo {
            // One unit (the decoder grants no more while journalling), journalled first.
            journal(band, blk, block, cur.column, u);
        }
        let left = if one { 1 } else { usize::MAX };
        // One loop per pass kind, each with its column coder inlined.
        macro_rules! scan_with {
            ($code:ident) => {
                scan(
                    band,
                    sym,
                    probs,
                    tally,
                    cur,
                    block,
                    left,
                    |b, sym, pr, t, col| $code(b, sym, pr, t, set, col, p),
                )
            };
        }
        match pass.kind {
            PassKind::Propagation => scan_with!(propagate),
            PassKind::Refinement => scan_with!(refine),
            PassKind::Cleanup => scan_with!(clean),
        }
    }
}

/// Journals in `u` what coding stripe column `column` of `block` (block `blk`) may change.
#[cold]
#[inline(never)]
fn journal(band: &BandState, blk: usize, block: BlockAt, column: usize, u: &mut Undo) {
    let BlockAt {
        s,
        x0,
        y0,
        cols,
        rows,
    } = block;
    u.block = Some((blk, band.block_active[blk]));
    let (stripe, x) = (column / cols, x0 + column % cols);
    let ys = y0 + 4 * stripe;
    for y in ys..(ys + 4).min(y0 + rows) {
        (u.coefficients).push((x, y, band.flags(s, x, y), band.mag_in(s, x, y)));
    }
}

/// The block being coded: its state `s`, its first coefficient (x0, y0), its size.
#[derive(Clone, Copy)]
struct BlockAt {
    s: usize,
    x0: usize,
    y0: usize,
    cols: usize,
    rows: usize,
}

/// Codes the stripe columns of a block with `code`, from the cursor's column on: `left` of
/// them, then as many more as [`Symbols::more_units`] allows each time (all, if `left` is
/// `usize::MAX`). Moves the cursor past the columns coded.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scan<S: Symbols, T: Tally>(
    band: &mut BandState,
    sym: &mut S,
    probs: &mut [Prob],
    tally: &mut T,
    cur: &mut Cursor,
    BlockAt {
        s,
        x0,
        y0,
        cols,
        rows,
    }: BlockAt,
    mut left: usize,
    mut code: impl FnMut(&mut BandState, &mut S, &mut [Prob], &mut T, Column) -> Option<()>,
) -> Option<Step> {
    let (first_stripe, first_x) = (cur.column / cols, cur.column % cols);
    for stripe in first_stripe..rows.div_ceil(4) {
        let ys = y0 + 4 * stripe;
        let ye = (ys + 4).min(y0 + rows);
        let start = if stripe == first_stripe { first_x } else { 0 };
        let row = band.at(s, x0, ys);
        for dx in start..cols {
            if left == 0 {
                left = sym.more_units();
                if left == 0 {
                    cur.column = stripe * cols + dx;
                    return Some(Step::More);
                }
            }
            left -= 1;
            let col = Column {
                x: x0 + dx,
                ys,
                ye,
                at: row + dx,
            };
            code(band, sym, probs, tally, col)?;
        }
    }
    Some(next_block(band, cur))
}

/// Moves the cursor to the next block; the pass is done after its last block.
fn next_block(band: &BandState, cur: &mut Cursor) -> Step {
    cur.block += 1;
    cur.column = 0;
    cur.block_open = false;
    if cur.block == band.order.len() {
        Step::PassDone
    } else {
        Step::More
    }
}

/// The parity flag of bit-plane `p`.
#[inline(always)]
fn parity(p: u32) -> Flags {
    if p & 1 == 1 {
        ODD
    } else {
        0
    }
}

/// A stripe column being coded: column `x`, rows `ys..ye`; its first coefficient is at `at`
/// in the band's state ([`BandState::at`]).
#[derive(Clone, Copy)]
struct Column {
    x: usize,
    ys: usize,
    ye: usize,
    at: usize,
}

/// The flags of a whole stripe column starting at `at`, OR-ed: what none of its
/// coefficients has.
#[inline(always)]
fn column_flags(band: &BandState, at: usize) -> Flags {
    let stride = band.stride;
    let f = &band.flags[at..=at + 3 * stride];
    f[0] | f[stride] | f[2 * stride] | f[3 * stride]
}

/// A propagation pass over a stripe column.
#[inline(always)]
fn propagate<S: Symbols, T: Tally>(
    band: &mut BandState,
    sym: &mut S,
    probs: &mut [Prob],
    tally: &mut T,
    set: usize,
    Column { x, ys, ye, at: l0 }: Column,
    p: u32,
) -> Option<()> {
    // No coefficient with a significant neighbour: nothing to code.
    if ye - ys == 4 && column_flags(band, l0) >> NEIGHBOURS == 0 {
        return Some(());
    }
    let orient = band.band.orient as usize;
    let stride = band.stride;
    for y in ys..ye {
        let at = l0 + (y - ys) * stride;
        let f = band.flags[at];
        if f & SIG == 0 {
            let n = (f >> NEIGHBOURS) as u8;
            if n != 0 {
                let ctx = set + CTX_SIG + SIG_CONTEXT[orient][n as usize] as usize;
                code_significance(band, sym, probs, tally, (at, x, y), p, ctx, set)?;
                band.flags[at] |= VISITED;
            }
        }
    }
    Some(())
}

/// A refinement pass over a stripe column.
#[inline(always)]
fn refine<S: Symbols, T: Tally>(
    band: &mut BandState,
    sym: &mut S,
    probs: &mut [Prob],
    tally: &mut T,
    set: usize,
    Column { x, ys, ye, at: l0 }: Column,
    p: u32,
) -> Option<()> {
    // No significant coefficient: nothing to code.
    if ye - ys == 4 && column_flags(band, l0) & SIG == 0 {
        return Some(());
    }
    let stride = band.stride;
    for y in ys..ye {
        let at = l0 + (y - ys) * stride;
        let f = band.flags[at];
        if f & (SIG | VISITED) == SIG {
            let ctx = if f & REFINED != 0 {
                2
            } else {
                (f >> NEIGHBOURS != 0) as usize
            };
            let i = y * band.band.w + x;
            let truth = S::ENCODES && (band.truth[i].unsigned_abs() >> p) & 1 != 0;
            let value =
                |band: &BandState, f| BandState::value_of(f, band.mag_at(at, x, y), band.current);
            let before = if T::COUNTS { value(band, f) } else { 0 };
            let bit = sym.code(probs, set + CTX_REF + ctx, truth)?;
            if p < 16 {
                band.low[at] |= (bit as u16) << p;
            } else {
                band.set_mag_at(at, x, y, band.mag_at(at, x, y) | (bit as u32) << p);
            }
            let g = (f & !ODD) | REFINED | parity(p);
            band.flags[at] = g;
            if T::COUNTS {
                let t = band.truth[i] as i64;
                tally.gain(t - before as i64, t - value(band, g) as i64);
            }
        }
    }
    Some(())
}

/// A cleanup pass over a stripe column (then its coefficients are no longer visited).
#[inline(always)]
fn clean<S: Symbols, T: Tally>(
    band: &mut BandState,
    sym: &mut S,
    probs: &mut [Prob],
    tally: &mut T,
    set: usize,
    Column { x, ys, ye, at: l0 }: Column,
    p: u32,
) -> Option<()> {
    let orient = band.band.orient as usize;
    let stride = band.stride;
    let mut y = ys;
    // What the column's coefficients have (a partial stripe: taken as visited).
    let all = if ye - ys == 4 {
        column_flags(band, l0)
    } else {
        VISITED
    };
    if ye - ys == 4 {
        // No coefficient significant, visited or with a significant neighbour.
        const BUSY: Flags = SIG | VISITED | 0xff << NEIGHBOURS;
        if all & BUSY == 0 {
            let first = if S::ENCODES {
                (ys..ye).position(|yy| {
                    let i = yy * band.band.w + x;
                    (band.truth[i].unsigned_abs() >> p) & 1 != 0
                })
            } else {
                None
            };
            if sym.code(probs, set + CTX_RUN, first.is_some())? {
                let k = first.unwrap_or(0);
                let hi = sym.code(probs, set + CTX_UNI, k & 2 != 0)?;
                let lo = sym.code(probs, set + CTX_UNI + 1, k & 1 != 0)?;
                let yy = ys + 2 * hi as usize + lo as usize;
                let at = l0 + (yy - ys) * stride;
                let (sc, flip) = band.sign_context(at, x, yy);
                let i = yy * band.band.w + x;
                let neg_truth = S::ENCODES && band.truth[i] < 0;
                let neg = sym.code(probs, set + CTX_SIGN + sc, neg_truth ^ flip)? ^ flip;
                make_significant(band, tally, (at, x, yy), p, neg);
                y = yy + 1;
            } else {
                y = ye;
            }
        }
    }
    while y < ye {
        let at = l0 + (y - ys) * stride;
        let f = band.flags[at];
        if f & (SIG | VISITED) == 0 {
            let n = (f >> NEIGHBOURS) as usize;
            let ctx = set + CTX_SIG + SIG_CONTEXT[orient][n] as usize;
            code_significance(band, sym, probs, tally, (at, x, y), p, ctx, set)?;
        }
        y += 1;
    }
    if all & VISITED != 0 {
        for k in 0..ye - ys {
            band.flags[l0 + k * stride] &= !VISITED;
        }
    }
    Some(())
}

/// Codes whether coefficient (x, y) of block state `s`, insignificant so far, is
/// significant at bit-plane `p`, and if so its sign.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn code_significance<S: Symbols, T: Tally>(
    band: &mut BandState,
    sym: &mut S,
    probs: &mut [Prob],
    tally: &mut T,
    (at, x, y): (usize, usize, usize),
    p: u32,
    ctx: usize,
    set: usize,
) -> Option<()> {
    let i = y * band.band.w + x;
    let truth = S::ENCODES && (band.truth[i].unsigned_abs() >> p) & 1 != 0;
    if sym.code(probs, ctx, truth)? {
        let (sc, flip) = band.sign_context(at, x, y);
        let neg_truth = S::ENCODES && band.truth[i] < 0;
        let neg = sym.code(probs, set + CTX_SIGN + sc, neg_truth ^ flip)? ^ flip;
        make_significant(band, tally, (at, x, y), p, neg);
    }
    Some(())
}

#[inline(always)]
fn make_significant<T: Tally>(
    band: &mut BandState,
    tally: &mut T,
    (at, x, y): (usize, usize, usize),
    p: u32,
    neg: bool,
) {
    let f = &mut band.flags[at];
    *f = (*f & !ODD) | SIG | if neg { NEG } else { 0 } | parity(p);
    band.tell_neighbours(at, x, y);
    band.set_mag_at(at, x, y, 1 << p);
    let blk = band.block_of(x, y);
    band.block_active[blk] = true;
    band.band_active = true;
    if T::COUNTS {
        let t = band.truth[y * band.band.w + x] as i64;
        tally.gain(
            t,
            t - BandState::value_of(band.flags[at], band.mag_at(at, x, y), band.current) as i64,
        );
    }
}

/// Encoder: whether a coefficient of a block that has no significant one (it is not active)
/// becomes significant at `p`.
fn block_has_new(band: &BandState, bx: u32, by: u32, p: u32) -> bool {
    (band.truth_bits.0[by as usize * band.bw + bx as usize] >> p) & 1 != 0
}

/// Encoder: whether any coefficient of a band without significant ones becomes significant.
fn band_has_new(band: &BandState, p: u32) -> bool {
    (band.truth_bits.1 >> p) & 1 != 0
}

/// [`BandState::truth_bits`] of `truth` (empty: the decoder's, none).
fn truth_bits(band: &Band, truth: &[i32]) -> (Vec<u32>, u32) {
    if truth.is_empty() {
        return (Vec::new(), 0);
    }
    let (bw, bh) = band.blocks();
    let mut blocks = vec![0u32; bw * bh];
    for (y, row) in truth.chunks_exact(band.w).enumerate() {
        let ors = &mut blocks[(y / BLOCK) * bw..][..bw];
        for (o, run) in ors.iter_mut().zip(row.chunks(BLOCK)) {
            *o |= run.iter().fold(0, |b, t| b | t.unsigned_abs());
        }
    }
    let all = blocks.iter().fold(0, |b, &o| b | o);
    (blocks, all)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Opened blocks hold at most twice a band's coefficients along each side, and exactly
    /// them when the band is narrower or lower than a block: a thin band of a hostile file
    /// costs what its coefficients do.
    #[test]
    fn block_states_follow_the_band_s_size() {
        for (w, h) in [
            (1, 1000),
            (1000, 1),
            (31, 31),
            (32, 32),
            (33, 33),
            (40, 70),
            (100, 7),
        ] {
            let band = Band::sized(w, h);
            let mut b = BandState::new(band, 0, Vec::new());
            let (bw, bh) = band.blocks();
            for blk in 0..bw * bh {
                b.open(blk);
            }
            let (sw, sh) = (if w > BLOCK { 2 } else { 1 }, if h > BLOCK { 2 } else { 1 });
            assert!(
                b.flags.len() <= sw * sh * band.len(),
                "{w}x{h}: {}",
                b.flags.len()
            );
            assert_eq!(b.low.len(), b.flags.len());
            if w <= BLOCK && h <= BLOCK {
                assert_eq!(b.flags.len(), band.len());
            }
        }
    }

    /// The encoder's block and band flags from the kept ORs: what a scan of the coefficients
    /// says, for every block and bit-plane of bands with partial blocks.
    #[test]
    fn new_significance_is_read_from_the_ors() {
        let mut next = crate::testing::xorshift(7);
        for (w, h) in [(1, 1), (33, 70), (64, 64), (100, 7)] {
            let band = Band::sized(w, h);
            let truth: Vec<i32> = (0..w * h)
                .map(|_| ((next() % 2000) as i32 - 1000) >> (next() % 9))
                .collect();
            let b = BandState::new(band, 0, truth.clone());
            let (bw, bh) = band.blocks();
            for p in 0..12 {
                let bit = |t: &i32| (t.unsigned_abs() >> p) & 1 != 0;
                assert_eq!(band_has_new(&b, p), truth.iter().any(bit));
                for (bx, by) in (0..bh).flat_map(|y| (0..bw).map(move |x| (x, y))) {
                    let scan = (0..h).filter(|y| y / BLOCK == by).any(|y| {
                        (0..w)
                            .filter(|x| x / BLOCK == bx)
                            .any(|x| bit(&truth[y * w + x]))
                    });
                    assert_eq!(block_has_new(&b, bx as u32, by as u32, p), scan);
                }
            }
        }
    }

    #[test]
    fn the_context_table_is_jpeg_2000_s() {
        // Spot checks of ISO/IEC 15444-1 Table D.1.
        assert_eq!(SIG_CONTEXT[0][0], 0);
        assert_eq!(SIG_CONTEXT[0][(N_LEFT | N_RIGHT) as usize], 8);
        assert_eq!(SIG_CONTEXT[0][(N_UP | N_DOWN) as usize], 4);
        assert_eq!(SIG_CONTEXT[1][(N_UP | N_DOWN) as usize], 8); // HL swaps
        assert_eq!(SIG_CONTEXT[3][0b1111_0000], 8); // HH: four diagonals
        assert_eq!(SIG_CONTEXT[3][(0b0001_0000 | N_LEFT) as usize], 4);
    }
}
