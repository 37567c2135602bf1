//! The `.qcs` byte format (spec/format.md): header, level schedule, chunks, a push parser,
//! a writer and an inspector.
//!
//! A file is a [`Header`] followed by chunks. Level `k`'s colours are in the `k`-th `L` chunk, whose
//! sample range comes from [`Header::level_range`]. [`Parser`] takes bytes in any chunking and
//! emits [`Event`]s as soon as they can be known; [`ContainerWriter`] writes a file; [`inspect`]
//! lists what a (possibly truncated or damaged) file holds.
//!
//! ```
//! use qcs::container::{ContainerWriter, Header, Layout, Coding, Parser, Event};
//! use qcs::coding::raw;
//!
//! let header = Header::new(4, 3, Layout::Grey, 5, 2, Coding::Raw { bits: 8 });
//! let mut w = ContainerWriter::new(Vec::new(), &header)?;
//! for k in 0..header.level_count() {
//!     let range = header.level_range(k).unwrap();
//!     let values: Vec<u8> = range.map(|i| (i * 50) as u8).collect();
//!     w.write_level(&raw::pack(&values, 8)?)?;
//! }
//! w.write_text("Author", "me")?;
//! let file = w.finish()?;
//!
//! let mut parser = Parser::new(Default::default());
//! let mut events = Vec::new();
//! for byte in &file {
//!     parser.push(std::slice::from_ref(byte), &mut events)?;
//! }
//! assert!(parser.is_complete());
//! assert_eq!(parser.progress().samples_verified, 5);
//! assert!(matches!(events[0], Event::Header(_)));
//! # Ok::<(), qcs::Error>(())
//! ```

pub mod chunk;
mod header;
mod inspect;
mod parser;
mod refinement;
pub mod varint;
mod writer;

pub use header::DEFAULT_FIRST_LEVEL;
pub use header::{
    header_check, Coding, Header, LatticeFields, Layout, LEVELS_ONLY_VERSION, MAGIC,
    MAX_HEADER_LEN, VERSION,
};
pub use inspect::{inspect, ChunkStatus, InspectedChunk, InspectedLevel, Inspection};
pub use parser::{EndState, Event, Metadata, Parser, ParserOptions, Progress};
pub use refinement::{encode_layer, PassLimit, RefinementHeader, Wavelet};
pub use varint::VarintError;
pub use writer::ContainerWriter;

use thiserror::Error as ThisError;

/// Where a chunk is: its index among the chunks (0 = first after the header), its tag, and the
/// byte offset of its tag byte in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChunkRef {
    /// Index among the file's chunks, 0 for the first one after the header.
    pub index: u32,
    /// The tag byte.
    pub tag: u8,
    /// Byte offset of the tag in the file.
    pub offset: u64,
}

impl std::fmt::Display for ChunkRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "chunk #{} {} at byte {}",
            self.index,
            chunk::tag_name(self.tag),
            self.offset
        )
    }
}

/// A violation of the byte format, saying what and where (byte offsets are from the file start).
///
/// ```
/// use qcs::format::FormatError;
/// let err = qcs::decode(b"qc\xE0", &Default::default()).unwrap_err();
/// assert!(matches!(err, qcs::Error::Format(FormatError::UnsupportedVersion { version: 7 })));
/// ```
#[derive(Debug, Clone, PartialEq, Eq, ThisError)]
#[non_exhaustive]
pub enum FormatError {
    /// The file does not start with the qcs magic `qc`.
    #[error("not a qcs file (bad magic byte 0x{found:02X} at byte {offset})")]
    BadMagic {
        /// Offset of the first wrong byte (0..3).
        offset: u64,
        /// The byte found there.
        found: u8,
    },
    /// More samples than pixels (the site construction requires N ≤ W·H, spec/sites.md §4).
    #[error("{samples} samples in an image of {pixels} pixels (at most one sample per pixel)")]
    TooManySamples {
        /// N from the header.
        samples: u64,
        /// W·H.
        pixels: u64,
    },
    /// The format byte's version (its bits 7–5) is not one this decoder reads.
    #[error(
        "unsupported format version {version} (this decoder reads versions 2 and 3) at byte 2"
    )]
    UnsupportedVersion {
        /// The version found.
        version: u8,
    },
    /// A header varint is malformed.
    #[error("header field {field} at byte {offset}: {error}")]
    HeaderVarint {
        /// The field's name as in the spec.
        field: &'static str,
        /// Offset of the field's first byte.
        offset: u64,
        /// What is wrong with it.
        error: VarintError,
    },
    /// A header field has a value the format forbids.
    #[error("header field {field} at byte {offset} is {value}, expected {expected}")]
    InvalidField {
        /// The field's name as in the spec.
        field: &'static str,
        /// Offset of the field's first byte.
        offset: u64,
        /// The value found.
        value: u64,
        /// What the spec allows.
        expected: &'static str,
    },
    /// The header's check byte does not match its bytes.
    #[error("header check byte mismatch at byte {offset}: stored 0x{stored:02X}, computed 0x{computed:02X}")]
    HeaderCheck {
        /// Offset of the check byte.
        offset: u64,
        /// The check byte in the file.
        stored: u8,
        /// The CRC-8 of the header bytes before it.
        computed: u8,
    },
    /// A header ended before all its fields (only from [`Header::parse`] on a complete buffer).
    #[error("header truncated at byte {offset}")]
    TruncatedHeader {
        /// Length of the buffer.
        offset: u64,
    },
    /// A chunk's length varint is malformed.
    #[error("{chunk}: length: {error}")]
    ChunkLength {
        /// The chunk.
        chunk: ChunkRef,
        /// What is wrong with it.
        error: VarintError,
    },
    /// A chunk's CRC does not match.
    #[error("{chunk}: CRC mismatch: stored 0x{stored:08X}, computed 0x{computed:08X}")]
    ChunkCrc {
        /// The chunk.
        chunk: ChunkRef,
        /// The CRC in the file.
        stored: u32,
        /// The CRC of the chunk's tag, length and payload (level 0: of the header, the
        /// length and the payload).
        computed: u32,
    },
    /// A level chunk's payload length differs from what the header implies.
    #[error("{chunk}: level {level} payload is {found} bytes, the header implies {expected}")]
    LevelLength {
        /// The chunk.
        chunk: ChunkRef,
        /// The level.
        level: u32,
        /// The length the header implies.
        expected: u64,
        /// The length in the chunk.
        found: u64,
    },
    /// A critical chunk with a tag this decoder does not know.
    #[error("{chunk}: unknown critical chunk")]
    UnknownCritical {
        /// The chunk.
        chunk: ChunkRef,
    },
    /// A level chunk after the last level.
    #[error("{chunk}: level chunk after the last level")]
    ExtraLevel {
        /// The chunk.
        chunk: ChunkRef,
    },
    /// A refinement layer where the format does not allow one: in a version-2 file, before
    /// the last level, or after the last layer the refinement header declares.
    #[error("{chunk}: {reason}")]
    MisplacedLayer {
        /// The chunk.
        chunk: ChunkRef,
        /// Why it cannot be there.
        reason: &'static str,
    },
    /// A field of the refinement header or of a layer's segment table is out of its range.
    #[error("{chunk}: {field} is {value}, expected {expected}")]
    BadRefinement {
        /// The chunk.
        chunk: ChunkRef,
        /// The field's name as in the spec.
        field: &'static str,
        /// The value found.
        value: u64,
        /// What the spec allows.
        expected: &'static str,
    },
    /// A varint of the refinement header or of a segment table is malformed.
    #[error("{chunk}: {field}: {error}")]
    RefinementVarint {
        /// The chunk.
        chunk: ChunkRef,
        /// The part it is in.
        field: &'static str,
        /// What is wrong with it.
        error: VarintError,
    },
    /// A layer's segments do not fill its payload exactly.
    #[error("{chunk}: the segment table declares {declared} bytes of segments, the payload holds {available}")]
    SegmentLengths {
        /// The chunk.
        chunk: ChunkRef,
        /// The sum of the segment lengths.
        declared: u64,
        /// The payload bytes after the table.
        available: u64,
    },
    /// A second ICC profile chunk.
    #[error("{chunk}: second ICC profile")]
    DuplicateIcc {
        /// The chunk.
        chunk: ChunkRef,
    },
    /// A second Exif chunk.
    #[error("{chunk}: second Exif chunk")]
    DuplicateExif {
        /// The chunk.
        chunk: ChunkRef,
    },
    /// The file uses a coding this decoder does not implement (e.g. the reserved predictive coding).
    #[error("coding {coding} is not supported by this decoder")]
    UnsupportedCoding {
        /// The coding byte.
        coding: u8,
    },
    /// A text chunk that is not `key 0x00 value` in UTF-8 with a non-empty key.
    #[error("{chunk}: malformed text chunk: {reason}")]
    BadText {
        /// The chunk.
        chunk: ChunkRef,
        /// What is wrong.
        reason: &'static str,
    },
}

impl FormatError {
    /// The chunk the error is in, if it is in a chunk (not in the header).
    ///
    /// ```
    /// use qcs::format::{ChunkRef, FormatError};
    /// let chunk = ChunkRef { index: 2, tag: b'L', offset: 40 };
    /// let e = FormatError::UnknownCritical { chunk };
    /// assert_eq!(e.chunk(), Some(chunk));
    /// assert_eq!(e.to_string(), "chunk #2 'L' at byte 40: unknown critical chunk");
    /// ```
    pub fn chunk(&self) -> Option<ChunkRef> {
        match self {
            FormatError::ChunkLength { chunk, .. }
            | FormatError::ChunkCrc { chunk, .. }
            | FormatError::LevelLength { chunk, .. }
            | FormatError::UnknownCritical { chunk }
            | FormatError::ExtraLevel { chunk }
            | FormatError::DuplicateIcc { chunk }
            | FormatError::DuplicateExif { chunk }
            | FormatError::MisplacedLayer { chunk, .. }
            | FormatError::BadRefinement { chunk, .. }
            | FormatError::RefinementVarint { chunk, .. }
            | FormatError::SegmentLengths { chunk, .. }
            | FormatError::BadText { chunk, .. } => Some(*chunk),
            _ => None,
        }
    }
}
