//! Chunk tags and the chunk framing `tag | length varint | payload | CRC-32 LE` (spec/format.md
//! §Chunks); level 0 comes first, without its tag, its CRC covering the header too.

use super::varint;
use byteorder::{ByteOrder, LittleEndian};

/// `L`: the next level's colour data (critical).
pub const LEVEL: u8 = b'L';
/// `R`: a layer of the refinement (critical; version 3).
pub const REFINEMENT: u8 = b'R';
/// `i`: an ICC profile, raw bytes (ancillary).
pub const ICC: u8 = b'i';
/// `e`: Exif metadata, the TIFF-structured block (as PNG's `eXIf`), raw bytes (ancillary).
pub const EXIF: u8 = b'e';
/// `t`: a text comment, UTF-8 `key`, 0x00, UTF-8 `value` (ancillary).
pub const TEXT: u8 = b't';

/// The bit of a tag byte that marks an ancillary chunk (lower-case ASCII letters have it).
pub const ANCILLARY_BIT: u8 = 0x20;

/// Whether a chunk with this tag may be skipped by a decoder that does not know it.
///
/// ```
/// use qcs::container::chunk::{is_ancillary, LEVEL, TEXT};
/// assert!(!is_ancillary(LEVEL));
/// assert!(is_ancillary(TEXT));
/// ```
pub fn is_ancillary(tag: u8) -> bool {
    tag & ANCILLARY_BIT != 0
}

/// A printable form of a tag: the ASCII character if it is graphic, else `0xNN`.
///
/// ```
/// use qcs::container::chunk::tag_name;
/// assert_eq!(tag_name(b'L'), "'L'");
/// assert_eq!(tag_name(0), "0x00");
/// ```
pub fn tag_name(tag: u8) -> String {
    if tag.is_ascii_graphic() {
        format!("'{}'", tag as char)
    } else {
        format!("0x{tag:02X}")
    }
}

/// The bytes of level 0 after the header `header`: the varint payload length, the payload and
/// the CRC-32 (IEEE, little-endian) over the header, the length bytes and the payload.
///
/// Returns `None` if the payload is longer than `u32::MAX` bytes.
///
/// ```
/// let bytes = qcs::container::chunk::encode_first(b"head", b"hi").unwrap();
/// assert_eq!(&bytes[..3], &[2, b'h', b'i']);
/// assert_eq!(bytes[3..], crc32fast::hash(b"head\x02hi").to_le_bytes());
/// ```
pub fn encode_first(header: &[u8], payload: &[u8]) -> Option<Vec<u8>> {
    let len = u32::try_from(payload.len()).ok()?;
    let mut out = Vec::with_capacity(payload.len() + 9);
    varint::write_u32(&mut out, len);
    out.extend_from_slice(payload);
    let mut crc = crc32fast::Hasher::new();
    crc.update(header);
    crc.update(&out);
    let at = out.len();
    out.resize(at + 4, 0);
    LittleEndian::write_u32(&mut out[at..], crc.finalize());
    Some(out)
}

/// The complete bytes of one chunk: tag, varint length, payload and CRC-32 (IEEE, little-endian)
/// over the tag, the length bytes and the payload.
///
/// Returns `None` if the payload is longer than `u32::MAX` bytes.
///
/// ```
/// let bytes = qcs::container::chunk::encode(b'x', b"hi").unwrap();
/// assert_eq!(&bytes[..4], &[b'x', 2, b'h', b'i']);
/// assert_eq!(bytes.len(), 8);
/// ```
pub fn encode(tag: u8, payload: &[u8]) -> Option<Vec<u8>> {
    // The same framing as level 0's, with the tag in front in place of the header.
    let mut out = vec![tag];
    out.extend(encode_first(&[tag], payload)?);
    Some(out)
}
