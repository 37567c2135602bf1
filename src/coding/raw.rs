//! Coding 0, raw: each channel value quantised to `B` bits (1..=8), packed MSB-first.
//!
//! A level's payload is its samples in order, each sample's channels in layout order, each value
//! `q = round(v·(2^B−1)/255)` written as `B` bits, most significant first, the whole zero-padded to a
//! byte. The decoded value is `round(q·255/(2^B−1))`. Neither rounding can meet a tie (2^B−1 and
//! 255 are odd), so both are exact integer formulas.
//!
//! ```
//! use qcs::coding::raw;
//! let colours = [255u8, 0, 128, 10, 20, 30]; // two RGB samples
//! let payload = raw::pack(&colours, 4)?;
//! assert_eq!(payload.len(), 3); // 6 values · 4 bits
//! let back = raw::unpack(&payload, 3, 4, 2)?;
//! assert_eq!(back, [255, 0, 136, 17, 17, 34]);
//! # Ok::<(), qcs::Error>(())
//! ```

use bitvec::prelude::*;

fn check(channels: u8, bits: u8) -> Result<(), crate::Error> {
    if !(1..=8).contains(&bits) {
        return Err(crate::Error::invalid("raw bits per channel", bits, "1..=8"));
    }
    if channels == 0 {
        return Err(crate::Error::invalid("channels", 0, "at least 1"));
    }
    Ok(())
}

/// Quantises an 8-bit value to `bits` bits: `round(v·(2^bits−1)/255)`. `bits` is clamped to 1..=8.
///
/// ```
/// use qcs::coding::raw::quantise;
/// assert_eq!(quantise(255, 3), 7);
/// assert_eq!(quantise(128, 1), 1);
/// assert_eq!(quantise(127, 1), 0);
/// ```
pub fn quantise(v: u8, bits: u8) -> u8 {
    let m = (1u32 << bits.clamp(1, 8)) - 1;
    ((v as u32 * m + 127) / 255) as u8
}

/// The 8-bit value of a `bits`-bit code: `round(q·255/(2^bits−1))`. `bits` is clamped to 1..=8 and
/// `q` to its range.
///
/// ```
/// use qcs::coding::raw::dequantise;
/// assert_eq!(dequantise(7, 3), 255);
/// assert_eq!(dequantise(3, 3), 109);
/// ```
pub fn dequantise(q: u8, bits: u8) -> u8 {
    let m = (1u32 << bits.clamp(1, 8)) - 1;
    let q = (q as u32).min(m);
    ((q * 255 + m / 2) / m) as u8
}

/// The payload length in bytes of `samples` samples: ⌈samples·channels·bits/8⌉ (`None` on overflow).
///
/// ```
/// assert_eq!(qcs::coding::raw::payload_len(3, 3, 5), Some(6)); // 45 bits
/// ```
pub fn payload_len(samples: u64, channels: u8, bits: u8) -> Option<u64> {
    let total_bits = samples.checked_mul(channels as u64 * bits as u64)?;
    Some(total_bits.div_ceil(8))
}

/// Packs 8-bit channel values (samples × channels, in order) into a raw payload of `bits` bits per value.
///
/// ```
/// let payload = qcs::coding::raw::pack(&[255, 0, 255], 2)?;
/// assert_eq!(payload, [0b1100_1100]);
/// # Ok::<(), qcs::Error>(())
/// ```
pub fn pack(values: &[u8], bits: u8) -> Result<Vec<u8>, crate::Error> {
    check(1, bits)?;
    let mut bv: BitVec<u8, Msb0> = BitVec::with_capacity(values.len() * bits as usize);
    for &v in values {
        let q = quantise(v, bits);
        bv.extend_from_bitslice(&q.view_bits::<Msb0>()[8 - bits as usize..]);
    }
    bv.set_uninitialized(false);
    Ok(bv.into_vec())
}

/// Unpacks the complete samples (at most `max_samples`) at the start of a raw payload, which may be
/// partial, into dequantised 8-bit values (samples × channels). A trailing incomplete sample is
/// not returned.
///
/// ```
/// // 2 grey samples at 6 bits need 12 bits; one byte holds only the first.
/// let back = qcs::coding::raw::unpack(&[0b1111_1100], 1, 6, 2)?;
/// assert_eq!(back, [255]);
/// # Ok::<(), qcs::Error>(())
/// ```
pub fn unpack(
    payload: &[u8],
    channels: u8,
    bits: u8,
    max_samples: u64,
) -> Result<Vec<u8>, crate::Error> {
    let mut u = RawUnpacker::new(channels, bits, max_samples)?;
    let mut out = Vec::new();
    u.push(payload, &mut out);
    Ok(out)
}

/// Streaming unpacker for one level: takes payload bytes in any chunking and appends the values of
/// every sample that became complete.
///
/// ```
/// use qcs::coding::raw::{pack, RawUnpacker};
/// let payload = pack(&[10, 20, 30, 40, 50, 60], 8)?; // 3 grey+alpha samples
/// let mut u = RawUnpacker::new(2, 8, 3)?;
/// let mut out = Vec::new();
/// u.push(&payload[..3], &mut out);
/// assert_eq!(out, [10, 20]); // one complete sample
/// u.push(&payload[3..], &mut out);
/// assert_eq!(out, [10, 20, 30, 40, 50, 60]);
/// assert_eq!(u.samples_done(), 3);
/// # Ok::<(), qcs::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct RawUnpacker {
    channels: u8,
    bits: u8,
    remaining: u64,
    done: u64,
    pending: Vec<u8>,
    bit_offset: usize,
}

impl RawUnpacker {
    /// An unpacker for a level of `samples` samples of `channels` values at `bits` bits.
    pub fn new(channels: u8, bits: u8, samples: u64) -> Result<Self, crate::Error> {
        check(channels, bits)?;
        Ok(RawUnpacker {
            channels,
            bits,
            remaining: samples,
            done: 0,
            pending: Vec::new(),
            bit_offset: 0,
        })
    }

    /// Number of samples decoded so far.
    pub fn samples_done(&self) -> u64 {
        self.done
    }

    /// Feeds payload bytes; appends `channels` values per newly complete sample to `out` and
    /// returns how many samples were completed. Bytes past the last sample are ignored.
    pub fn push(&mut self, bytes: &[u8], out: &mut Vec<u8>) -> u64 {
        if self.remaining == 0 {
            return 0;
        }
        self.pending.extend_from_slice(bytes);
        let sample_bits = self.channels as usize * self.bits as usize;
        let avail = self.pending.len() * 8 - self.bit_offset;
        let n = ((avail / sample_bits) as u64).min(self.remaining);
        let view = &self.pending.view_bits::<Msb0>()[self.bit_offset..];
        let b = self.bits as usize;
        out.reserve(n as usize * self.channels as usize);
        for chunk in view
            .chunks_exact(b)
            .take(n as usize * self.channels as usize)
        {
            out.push(dequantise(chunk.load_be::<u8>(), self.bits));
        }
        let consumed = self.bit_offset + n as usize * sample_bits;
        self.pending.drain(..consumed / 8);
        self.bit_offset = consumed % 8;
        self.remaining -= n;
        self.done += n;
        if self.remaining == 0 {
            self.pending.clear();
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_matches_float_rounding() {
        for bits in 1..=8u8 {
            let m = ((1u32 << bits) - 1) as f64;
            for v in 0..=255u8 {
                let q = quantise(v, bits);
                assert_eq!(q as f64, (v as f64 * m / 255.0).round(), "v={v} B={bits}");
                let d = dequantise(q, bits);
                assert_eq!(d as f64, (q as f64 * 255.0 / m).round());
            }
        }
        for v in 0..=255u8 {
            assert_eq!(dequantise(quantise(v, 8), 8), v);
        }
    }
}
