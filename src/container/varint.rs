//! Unsigned LEB128 varints and zigzag, as used by the header and the chunk lengths (spec/format.md §Integers).
//!
//! A varint stores 7 bits per byte, low group first; bit 7 (0x80) of a byte says another byte follows.
//! A `u32` field takes at most 5 bytes, a `u64` field at most 10. Two encodings are rejected so that
//! every value has exactly one encoding: a non-minimal one (its last byte is 0x00 after at least one
//! earlier byte) and one whose value does not fit the field.

/// Why a varint was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarintError {
    /// The value does not fit the field's width (too many bytes, or high bits set in the last one).
    Overflow,
    /// The encoding ends with a 0x00 continuation group: a shorter encoding of the same value exists.
    NonMinimal,
}

impl std::fmt::Display for VarintError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            VarintError::Overflow => f.write_str("value too large for the field"),
            VarintError::NonMinimal => f.write_str("non-minimal encoding"),
        }
    }
}

/// Appends the unsigned LEB128 encoding of `v` to `out`.
///
/// ```
/// let mut out = Vec::new();
/// qcs::container::varint::write_u64(&mut out, 300);
/// assert_eq!(out, [0xAC, 0x02]);
/// ```
pub fn write_u64(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let group = (v & 0x7F) as u8;
        v >>= 7;
        if v == 0 {
            out.push(group);
            return;
        }
        out.push(group | 0x80);
    }
}

/// The number of bytes of the varint of `v` (1 up to 127, 2 up to 16383, …).
pub fn encoded_len(v: u64) -> usize {
    (64 - v.leading_zeros() as usize).div_ceil(7).max(1)
}

/// Appends the unsigned LEB128 encoding of a `u32` field (at most 5 bytes).
pub fn write_u32(out: &mut Vec<u8>, v: u32) {
    write_u64(out, v as u64);
}

/// Zigzag-maps a signed value to an unsigned one: 0, −1, 1, −2, … → 0, 1, 2, 3, …
///
/// ```
/// use qcs::container::varint::{zigzag, unzigzag};
/// assert_eq!(zigzag(-1), 1);
/// assert_eq!(zigzag(1), 2);
/// assert_eq!(unzigzag(zigzag(i32::MIN)), i32::MIN);
/// ```
pub fn zigzag(v: i32) -> u32 {
    ((v << 1) ^ (v >> 31)) as u32
}

/// The inverse of [`zigzag`].
pub fn unzigzag(u: u32) -> i32 {
    ((u >> 1) as i32) ^ -((u & 1) as i32)
}

/// Incremental decoder of one varint field of `bits` bits (32 or 64), fed one byte at a time.
///
/// ```
/// use qcs::container::varint::VarintReader;
/// let mut r = VarintReader::new(32);
/// assert_eq!(r.push(0xAC), Ok(None));
/// assert_eq!(r.push(0x02), Ok(Some(300)));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VarintReader {
    bits: u32,
    value: u64,
    count: u32,
}

impl VarintReader {
    /// A reader for a field of `bits` bits; anything but 32 is treated as 64.
    pub fn new(bits: u32) -> Self {
        VarintReader {
            bits: if bits == 32 { 32 } else { 64 },
            value: 0,
            count: 0,
        }
    }

    /// How many bytes have been fed so far.
    pub fn len(&self) -> u32 {
        self.count
    }

    /// Whether no byte has been fed yet.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Feeds one byte: `Ok(Some(v))` when the varint is complete, `Ok(None)` when more bytes follow.
    pub fn push(&mut self, byte: u8) -> Result<Option<u64>, VarintError> {
        let shift = 7 * self.count;
        let max_bytes = self.bits.div_ceil(7);
        if self.count >= max_bytes {
            return Err(VarintError::Overflow);
        }
        let group = (byte & 0x7F) as u64;
        // Bits of this group that land at or above the field width must be zero.
        let room = self.bits - shift; // ≥ 1 because count < max_bytes
        if room < 7 && (group >> room) != 0 {
            return Err(VarintError::Overflow);
        }
        self.value |= group << shift;
        self.count += 1;
        if byte & 0x80 != 0 {
            if self.count >= max_bytes {
                return Err(VarintError::Overflow);
            }
            return Ok(None);
        }
        if byte == 0 && self.count > 1 {
            return Err(VarintError::NonMinimal);
        }
        Ok(Some(self.value))
    }
}

/// Decodes one varint from the start of `bytes`: `Ok(Some((value, length)))`, or `Ok(None)` if
/// `bytes` ends before the varint does.
///
/// ```
/// use qcs::container::varint::read;
/// assert_eq!(read(&[0xAC, 0x02, 0xFF], 32), Ok(Some((300, 2))));
/// assert_eq!(read(&[0xAC], 32), Ok(None));
/// assert!(read(&[0x80, 0x00], 32).is_err()); // non-minimal
/// ```
pub fn read(bytes: &[u8], bits: u32) -> Result<Option<(u64, usize)>, VarintError> {
    let mut r = VarintReader::new(bits);
    for (i, &b) in bytes.iter().enumerate() {
        if let Some(v) = r.push(b)? {
            return Ok(Some((v, i + 1)));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boundaries() {
        for &(v, len) in &[
            (0u64, 1usize),
            (127, 1),
            (128, 2),
            (16383, 2),
            (16384, 3),
            (u32::MAX as u64, 5),
        ] {
            let mut out = Vec::new();
            write_u64(&mut out, v);
            assert_eq!(out.len(), len, "{v}");
            assert_eq!(read(&out, 32), Ok(Some((v, len))));
        }
        let mut out = Vec::new();
        write_u64(&mut out, u64::MAX);
        assert_eq!(out.len(), 10);
        assert_eq!(read(&out, 64), Ok(Some((u64::MAX, 10))));
        assert_eq!(read(&out, 32), Err(VarintError::Overflow));
        // 2^32 in a u32 field.
        assert_eq!(
            read(&[0x80, 0x80, 0x80, 0x80, 0x10], 32),
            Err(VarintError::Overflow)
        );
        // Six bytes for a u32 field.
        assert_eq!(
            read(&[0x80, 0x80, 0x80, 0x80, 0x80, 0x00], 32),
            Err(VarintError::Overflow)
        );
        // 11 bytes for a u64 field / high bit in the 10th.
        assert_eq!(read(&[0xFF; 11], 64), Err(VarintError::Overflow));
        let mut big = vec![0x80u8; 9];
        big.push(0x02);
        assert_eq!(read(&big, 64), Err(VarintError::Overflow));
        assert_eq!(read(&[0x81, 0x00], 64), Err(VarintError::NonMinimal));
        assert_eq!(read(&[0x00], 64), Ok(Some((0, 1))));
    }

    #[test]
    fn zigzag_round_trip() {
        for v in [0, 1, -1, 2, -2, i32::MAX, i32::MIN, 65536, -65536] {
            assert_eq!(unzigzag(zigzag(v)), v);
        }
        assert_eq!(zigzag(0), 0);
        assert_eq!(zigzag(-2), 3);
        assert_eq!(zigzag(i32::MIN), u32::MAX);
    }
}
