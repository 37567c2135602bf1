//! An adaptive binary range coder (LZMA style, carry-less decoding), the entropy coder of the
//! predictive coding (spec/format.md §Coding 1).
//!
//! The coder keeps a 32-bit `range`; a bit is coded with a 12-bit probability `p` that it is 0:
//! `bound = (range >> 12) · p`. Probabilities adapt after every bit with a rate that starts fast
//! and slows down ([`Prob`]). The encoder drops the constant leading zero byte of the classic LZMA
//! layout and flushes as few bytes as needed, trimming trailing zeros: the decoder reads 0x00 past
//! the end of a payload.
//!
//! **Why not a crate.** `constriction` (the well-kept Rust entropy-coding library) was the
//! candidate. Its range coder works on multi-symbol models with fixed probabilities per call;
//! qcs needs three things it does not give: adaptive *binary* contexts updated after every bit
//! (which would mean building a model per bit), a decoder that reads a *truncated* payload
//! and reports exactly which symbols the received bytes determine (the any-prefix rule of
//! `spec/format.md`: a sample counts only if no missing byte can change it), and a bitstream
//! simple enough to be normative in a page of the spec and frozen independently of a
//! dependency's versions. This coder is about 150 lines of code, tested by round trips, by every
//! truncation of every conformance file and by the fuzz targets.
//!
//! ```
//! use qcs::coding::range::{Prob, RangeDecoder, RangeEncoder};
//! let bits = [true, false, false, true, true, true, false, true];
//! let mut p = Prob::default();
//! let mut enc = RangeEncoder::new();
//! for &b in &bits {
//!     enc.encode(&mut p, b);
//! }
//! let bytes = enc.finish();
//! let mut p = Prob::default();
//! let mut dec = RangeDecoder::new();
//! for &b in &bits {
//!     assert_eq!(dec.decode(&mut p, &bytes, bytes.len()), Some(b));
//! }
//! ```

/// Probability resolution: probabilities are in `1..4096` (units of 1/4096).
pub const PROB_BITS: u32 = 12;
const PROB_ONE: u16 = 1 << PROB_BITS;
const TOP: u32 = 1 << 24;

/// An adaptive probability that the next bit is 0, with an update count that sets the
/// adaptation rate: shift `min(1 + n/2, 5)` after `n` updates (fast at first, then steady).
///
/// ```
/// let mut p = qcs::coding::range::Prob::default();
/// assert_eq!(p.p0(), 2048);
/// p.update(false);
/// assert_eq!(p.p0(), 3072); // first update: shift 1
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Prob {
    p: u16,
    /// Updates so far, up to 8.
    n: u8,
}

impl Default for Prob {
    fn default() -> Self {
        Prob {
            p: PROB_ONE / 2,
            n: 0,
        }
    }
}

impl Prob {
    /// Probability of a 0 bit, in 1/4096.
    pub fn p0(&self) -> u16 {
        self.p
    }

    /// Adapts to an observed bit. `p` stays within `1..=4095`.
    pub fn update(&mut self, bit: bool) {
        // `n` stops at 8, where the shift reaches 5: no minimum to take.
        let shift = 1 + self.n as u32 / 2;
        let (down, up) = (self.p >> shift, (PROB_ONE - self.p) >> shift);
        // Masks, not a jump on the bit (see `RangeDecoder::decode_fast`).
        let mask = (bit as u16).wrapping_neg();
        self.p = self.p.wrapping_add(up & !mask).wrapping_sub(down & mask);
        self.n += (self.n < 8) as u8;
    }
}

/// The encoder: bits in, bytes out.
#[derive(Clone, Debug)]
pub struct RangeEncoder {
    low: u64,
    range: u32,
    cache: u8,
    cache_size: u64,
    first: bool,
    out: Vec<u8>,
}

impl Default for RangeEncoder {
    fn default() -> Self {
        Self::new()
    }
}

impl RangeEncoder {
    /// An encoder at the start of a payload.
    pub fn new() -> Self {
        RangeEncoder {
            low: 0,
            range: u32::MAX,
            cache: 0,
            cache_size: 1,
            first: true,
            out: Vec::new(),
        }
    }

    fn shift_low(&mut self) {
        if (self.low as u32) < 0xFF00_0000 || (self.low >> 32) != 0 {
            let carry = (self.low >> 32) as u8;
            let mut temp = self.cache;
            loop {
                if self.first {
                    // The classic leading byte is always 0: not stored.
                    self.first = false;
                } else {
                    self.out.push(temp.wrapping_add(carry));
                }
                temp = 0xFF;
                self.cache_size -= 1;
                if self.cache_size == 0 {
                    break;
                }
            }
            self.cache = ((self.low >> 24) & 0xFF) as u8;
        }
        self.cache_size += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    /// Codes `bit` with probability `p` (then adapts `p`).
    pub fn encode(&mut self, p: &mut Prob, bit: bool) {
        let bound = (self.range >> PROB_BITS) * p.p as u32;
        // Masks, not a jump on the bit (see `RangeDecoder::decode_fast`).
        let mask = (bit as u32).wrapping_neg();
        self.low += (bound & mask) as u64;
        self.range = bound.wrapping_add(self.range.wrapping_sub(bound.wrapping_mul(2)) & mask);
        p.update(bit);
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    /// Bytes the payload would have if it ended now (an upper bound, before trimming).
    pub fn len_estimate(&self) -> usize {
        self.out.len() + self.cache_size as usize + 4
    }

    /// Ends the payload: picks the value in the final interval with the most trailing zero
    /// bytes, writes it out and trims trailing zero bytes.
    pub fn finish(mut self) -> Vec<u8> {
        let hi = self.low + self.range as u64 - 1;
        for z in (0..=4u32).rev() {
            let mask = (1u64 << (8 * z)) - 1;
            let v = (self.low + mask) & !mask;
            if v <= hi {
                self.low = v;
                break;
            }
        }
        for _ in 0..5 {
            self.shift_low();
        }
        while self.out.last() == Some(&0) {
            self.out.pop();
        }
        self.out
    }
}

impl RangeEncoder {
    /// Ends a payload whose length the decoder does not know (bytes after the last one are
    /// unknown to it, as in a payload still arriving): writes the fewest bytes such that every
    /// continuation of them lies in the final interval, so every bit coded is decided by the
    /// bytes written, whatever follows them.
    pub(crate) fn finish_open(mut self) -> Vec<u8> {
        let hi = self.low + self.range as u64 - 1;
        let mut keep = 4u32;
        for z in (0..=4u32).rev() {
            let mask = (1u64 << (8 * z)) - 1;
            let v = (self.low + mask) & !mask;
            if v + mask <= hi {
                self.low = v;
                keep = 4 - z;
                break;
            }
        }
        for _ in 0..=keep {
            self.shift_low();
        }
        self.out
    }
}

/// The decoder's state: bits out of a payload that may still be arriving.
///
/// Every call names the bytes received so far and the payload length; a byte at or past the
/// length reads as 0x00. Where bytes are missing the code value is only known to lie in an
/// interval: its low end `lo` reads the missing bytes as 0x00, its high end reads them as 0xFF.
/// A bit is decoded only when both ends give it and the high end is below `range` (as a valid
/// payload's code always is), so no byte still to come can change it, whatever the payload.
/// Missing bytes are always the newest ones in the code window; when they arrive, `lo` takes
/// their values. A decode that cannot be decided returns `None` and leaves the decoder unusable
/// until restored from a copy (it is `Copy`, so callers snapshot it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RangeDecoder {
    range: u32,
    lo: u32,
    /// How many of the newest bytes shifted in were missing (read as 0x00 in `lo`).
    missing: usize,
    pos: usize,
    started: bool,
}

impl Default for RangeDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl RangeDecoder {
    /// A decoder at the start of a payload.
    pub fn new() -> Self {
        RangeDecoder {
            range: u32::MAX,
            lo: 0,
            missing: 0,
            pos: 0,
            started: false,
        }
    }

    /// Bytes of the payload read so far (the 4-byte code window included; missing bytes count).
    pub fn position(&self) -> usize {
        self.pos
    }

    /// The byte at `i`: received, 0x00 past the payload's end, or `None` (missing).
    fn at(i: usize, bytes: &[u8], len: usize) -> Option<u8> {
        if i < bytes.len() {
            Some(bytes[i])
        } else if i >= len {
            Some(0)
        } else {
            None
        }
    }

    /// Puts the bytes that have arrived since they were shifted in as missing into `lo`.
    fn refresh(&mut self, bytes: &[u8], len: usize) {
        while self.missing > 0 {
            let i = self.pos - self.missing;
            let Some(b) = Self::at(i, bytes, len) else {
                break;
            };
            let age = self.missing - 1; // bytes shifted in after it
            if age < 4 {
                self.lo = self.lo.wrapping_add((b as u32) << (8 * age));
            }
            self.missing -= 1;
        }
    }

    fn shift_in(&mut self, bytes: &[u8], len: usize) {
        let b = if self.missing == 0 {
            Self::at(self.pos, bytes, len)
        } else {
            None
        };
        self.lo = (self.lo << 8) | b.unwrap_or(0) as u32;
        self.missing += b.is_none() as usize;
        self.pos += 1;
    }

    /// The high end of the code interval while bytes are missing, if every code in it is
    /// valid (below `range`, as every stream the encoder writes keeps it). Bits are decided
    /// from a partial interval only then: an arbitrary payload can reach codes at or above
    /// `range`, where the interval would no longer bound the code after the next shift, and
    /// the bits decided from a prefix must be those decided from the whole payload.
    fn hi(&self) -> Option<u32> {
        let spread = if self.missing >= 4 {
            u32::MAX as u64
        } else {
            (1u64 << (8 * self.missing)) - 1
        };
        let hi = self.lo as u64 + spread;
        (hi < self.range as u64).then_some(hi as u32)
    }

    /// Whether [`RangeDecoder::decode_fast`] may decode bits that read up to `margin` more
    /// bytes: the decoder has started, every byte it holds has arrived (missing ones are
    /// taken in now), and `margin` more have too.
    fn ready_for_fast(&mut self, bytes: &[u8], margin: usize) -> bool {
        if !self.started || bytes.len() < self.pos + margin {
            return false;
        }
        self.refresh(bytes, usize::MAX);
        self.missing == 0
    }

    /// How many runs of at most `margin` bytes [`RangeDecoder::decode_fast`] can take now, one
    /// after the other ([`RangeDecoder::ready_for_fast`] for each; 0 if not for the first).
    pub(crate) fn fast_runs(&mut self, bytes: &[u8], margin: usize) -> usize {
        if self.ready_for_fast(bytes, margin) {
            (bytes.len() - self.pos) / margin
        } else {
            0
        }
    }

    /// [`RangeDecoder::decode`] when [`RangeDecoder::ready_for_fast`] said so: no byte is
    /// missing, and the bytes it reads are there.
    #[inline(always)]
    pub(crate) fn decode_fast(&mut self, p: &mut Prob, bytes: &[u8]) -> bool {
        let bound = (self.range >> PROB_BITS) * p.p as u32;
        // Masks rather than branches: the bit is as hard to predict as the data (a
        // refinement bit is nearly a coin toss), and the compiler turned selects into a jump.
        let bit = self.lo >= bound;
        let mask = (bit as u32).wrapping_neg();
        self.lo -= bound & mask;
        self.range = bound.wrapping_add(self.range.wrapping_sub(bound.wrapping_mul(2)) & mask);
        while self.range < TOP {
            self.range <<= 8;
            self.lo = (self.lo << 8) | bytes[self.pos] as u32;
            self.pos += 1;
        }
        p.update(bit);
        bit
    }

    /// Decodes one bit with probability `p` (then adapts `p`), from `bytes` (received so far)
    /// of a payload of `len` bytes. `None`: the bytes received do not decide the bit; `p` is
    /// unchanged.
    pub fn decode(&mut self, p: &mut Prob, bytes: &[u8], len: usize) -> Option<bool> {
        if !self.started {
            for _ in 0..4 {
                self.shift_in(bytes, len);
            }
            self.started = true;
        }
        self.refresh(bytes, len);
        let bound = (self.range >> PROB_BITS) * p.p as u32;
        let below = if self.missing == 0 {
            self.lo < bound
        } else {
            match self.hi() {
                Some(hi) if hi < bound => true,
                Some(_) if self.lo >= bound => false,
                _ => return None,
            }
        };
        let bit = if below {
            self.range = bound;
            false
        } else {
            self.lo -= bound;
            self.range -= bound;
            true
        };
        while self.range < TOP {
            self.range <<= 8;
            self.shift_in(bytes, len);
        }
        p.update(bit);
        Some(bit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The update as spec/format.md writes it (`k = min(1 + n/2, 5)`, `n = min(n + 1, 16)`,
    /// a branch on the bit), against [`Prob::update`] (count stopped at 8, masks): every
    /// probability, every count, both bits, and then long runs, give the same probabilities.
    #[test]
    fn update_is_the_spec_s() {
        let spec = |p: u16, n: u8, bit: bool| -> (u16, u8) {
            let k = (1 + n as u32 / 2).min(5);
            let p = if bit { p - (p >> k) } else { p + ((4096 - p) >> k) };
            (p, (n + 1).min(16))
        };
        for p0 in 1..4096u16 {
            for n in 0..=16u8 {
                for bit in [false, true] {
                    let mut q = Prob { p: p0, n: n.min(8) };
                    q.update(bit);
                    assert_eq!(q.p, spec(p0, n, bit).0, "p {p0} n {n} bit {bit}");
                }
            }
        }
        let mut seed = 3u64;
        for _ in 0..200 {
            let (mut q, mut s) = (Prob::default(), (2048u16, 0u8));
            for _ in 0..40 {
                let bit = lcg(&mut seed) & 1 == 1;
                q.update(bit);
                s = spec(s.0, s.1, bit);
                assert_eq!(q.p, s.0);
            }
        }
    }

    fn lcg(s: &mut u64) -> u32 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*s >> 33) as u32
    }

    #[test]
    fn round_trip_skewed_and_random_bits() {
        let mut seed = 7;
        for &(n, skew) in &[
            (0usize, 50u32),
            (1, 50),
            (10, 3),
            (1000, 50),
            (5000, 2),
            (5000, 98),
        ] {
            let bits: Vec<bool> = (0..n).map(|_| lcg(&mut seed) % 100 < skew).collect();
            let mut probs = [Prob::default(); 4];
            let mut enc = RangeEncoder::new();
            for (i, &b) in bits.iter().enumerate() {
                enc.encode(&mut probs[i % 4], b);
            }
            let bytes = enc.finish();
            let mut probs = [Prob::default(); 4];
            let mut dec = RangeDecoder::new();
            for (i, &b) in bits.iter().enumerate() {
                assert_eq!(dec.decode(&mut probs[i % 4], &bytes, bytes.len()), Some(b));
            }
            if skew <= 3 || skew >= 97 {
                assert!(
                    bytes.len() * 8 < n / 3,
                    "{} bytes for {n} skewed bits",
                    bytes.len()
                );
            }
        }
    }

    #[test]
    fn missing_bytes_are_never_guessed() {
        let mut seed = 3;
        let bits: Vec<bool> = (0..400).map(|_| lcg(&mut seed).is_multiple_of(2)).collect();
        let mut p = Prob::default();
        let mut enc = RangeEncoder::new();
        for &b in &bits {
            enc.encode(&mut p, b);
        }
        let bytes = enc.finish();
        for cut in 0..bytes.len() {
            let mut p = Prob::default();
            let mut dec = RangeDecoder::new();
            let mut k = 0;
            while let Some(b) = dec.decode(&mut p, &bytes[..cut], bytes.len()) {
                assert_eq!(b, bits[k]);
                k += 1;
            }
            assert!(k < bits.len());
            // The bytes received decide more bits than a decoder that stops at the first
            // missing byte would find: each byte holds about 8 bits of these fair coins.
            if cut >= 8 {
                assert!(k + 40 >= cut * 8, "{k} bits from {cut} bytes");
            }
        }
    }

    #[test]
    fn decoding_goes_on_as_bytes_arrive() {
        // A decoder fed the payload in pieces, resuming from its last decided bit each time
        // (as the streaming decoder does), decodes exactly the bits of a whole decode.
        let mut seed = 11;
        for skew in [50u32, 90, 99] {
            let bits: Vec<bool> = (0..3000).map(|_| lcg(&mut seed) % 100 >= skew).collect();
            let mut probs = [Prob::default(); 3];
            let mut enc = RangeEncoder::new();
            for (i, &b) in bits.iter().enumerate() {
                enc.encode(&mut probs[i % 3], b);
            }
            let bytes = enc.finish();
            for piece in [1usize, 2, 3, 7] {
                let mut probs = [Prob::default(); 3];
                let mut dec = RangeDecoder::new();
                let mut got = Vec::new();
                let mut have = 0;
                while got.len() < bits.len() {
                    have = (have + piece).min(bytes.len());
                    loop {
                        let saved = dec;
                        let k = got.len() % 3;
                        match dec.decode(&mut probs[k], &bytes[..have], bytes.len()) {
                            Some(b) => got.push(b),
                            None => {
                                dec = saved;
                                break;
                            }
                        }
                        if got.len() == bits.len() {
                            break;
                        }
                    }
                    assert!(have < bytes.len() || got.len() == bits.len());
                }
                assert_eq!(got, bits, "skew {skew}, pieces of {piece}");
            }
        }
    }
}
