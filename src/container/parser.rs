//! The push parser: bytes in any chunking → [`Event`]s (spec/format.md §Decoding and truncation).

use super::chunk::{self, EXIF, ICC, LEVEL, REFINEMENT, TEXT};
use super::header::{FieldOffsets, Header, Stop, MAX_HEADER_LEN};
use super::refinement::{Bad, Read, RefinementHeader, TableReader};
use super::varint::VarintReader;
use super::{ChunkRef, Coding, FormatError};
use crate::Limits;
use byteorder::{ByteOrder, LittleEndian};
use std::ops::Range;

/// How a `Parser` treats limits and damage. Like every options type of the crate, a struct of
/// public fields with a [`Default`] (the default limits, no recovery, every level decoded):
/// set the fields you need and take the rest from the default.
///
/// ```
/// use qcs::format::{Coding, Header, Layout, ParserOptions};
/// // 10 000 samples in levels of 100, 100, 200, 400, …; a sample limit of 1000.
/// let h = Header::new(100, 100, Layout::Grey, 10_000, 100, Coding::Raw { bits: 1 });
/// let bytes = h.encode()?; // the header alone
/// let limits = qcs::Limits { max_samples: 1000, ..Default::default() };
/// let push = |opts: ParserOptions| qcs::StreamDecoder::with_options(opts).push(&bytes);
/// assert!(push(ParserOptions { limits: limits.clone(), ..Default::default() }).is_err());
/// // Samples 0..800 are in the levels that start before sample 500.
/// let capped = |k| ParserOptions { limits: limits.clone(), max_samples: Some(k), ..Default::default() };
/// assert!(push(capped(500)).is_ok());
/// assert!(push(capped(801)).is_err());
/// # Ok::<(), qcs::Error>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ParserOptions {
    /// Limits checked on the header (image size, samples) and on metadata, before allocating.
    pub limits: Limits,
    /// On a format error after the header (CRC mismatch, bad chunk), stop with
    /// `Event::Stopped` and keep the longest verified prefix instead of failing.
    pub recover: bool,
    /// The caller draws on at most this many samples (`None`: all), as
    /// [`crate::DecodeOptions::max_samples`]: only the levels that start before it are decoded
    /// (the later ones are parsed and verified), and the sample limit is checked against the
    /// samples of those levels, not the header's count.
    pub max_samples: Option<u64>,
}

/// A metadata chunk's content.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Metadata {
    /// `i`: an ICC profile.
    Icc(Vec<u8>),
    /// `e`: Exif metadata (a TIFF header and its IFDs, as PNG's `eXIf`).
    Exif(Vec<u8>),
    /// `t`: a text comment.
    Text {
        /// The key (non-empty, UTF-8, no 0x00).
        key: String,
        /// The value (UTF-8).
        value: String,
    },
}

/// What the parser found, in file order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Event {
    /// The header is complete, valid and within the limits (its bytes are verified with level
    /// 0's CRC).
    Header(Header),
    /// A level chunk starts; its payload bytes follow as [`Event::LevelData`].
    LevelStart {
        /// The level.
        level: u32,
        /// Where its chunk is.
        chunk: ChunkRef,
        /// The samples it holds.
        samples: Range<u64>,
        /// Its payload length in bytes.
        payload_len: u32,
    },
    /// Payload bytes of the current level, as they arrive: **not yet verified** by the CRC.
    /// Concatenated, a level's `LevelData` bytes are its payload.
    LevelData {
        /// The level.
        level: u32,
        /// The next bytes of its payload.
        bytes: Vec<u8>,
    },
    /// The level's chunk CRC matched: its samples are verified.
    LevelVerified {
        /// The level.
        level: u32,
        /// Where its chunk is.
        chunk: ChunkRef,
    },
    /// The last level was verified: in a version-2 file only ancillary chunks may follow; in a
    /// version-3 file the refinement's layers come next.
    LevelsComplete,
    /// A refinement layer (`R` chunk) starts.
    LayerStart {
        /// The layer, from 0.
        layer: u32,
        /// Where its chunk is.
        chunk: ChunkRef,
    },
    /// The refinement header, read from the first layer: **not yet verified** by its CRC
    /// (the layer's [`Event::LayerVerified`] verifies it).
    RefinementHeader(RefinementHeader),
    /// Bytes of a refinement stream, as they arrive: **not yet verified**. Concatenated, a
    /// stream's bytes over the layers are the stream.
    RefinementData {
        /// The layer they are in.
        layer: u32,
        /// The stream (0 = low-low band, then the details from the coarsest level).
        stream: u32,
        /// The next bytes of the stream.
        bytes: Vec<u8>,
    },
    /// The layer's chunk CRC matched: its bytes (and, for layer 0, the refinement header)
    /// are verified.
    LayerVerified {
        /// The layer.
        layer: u32,
        /// Where its chunk is.
        chunk: ChunkRef,
    },
    /// A metadata chunk, CRC verified.
    Metadata {
        /// Where it is.
        chunk: ChunkRef,
        /// Its content.
        metadata: Metadata,
    },
    /// An unknown ancillary chunk, CRC verified and skipped.
    Skipped {
        /// Where it is.
        chunk: ChunkRef,
        /// Its payload length.
        payload_len: u32,
    },
    /// Recovery mode only: a format error; the unverified data of the current chunk must be dropped,
    /// and the parser ignores all further input. Everything verified before stays valid.
    Stopped {
        /// The error that stopped the parser.
        error: FormatError,
    },
}

/// How far the parser has got.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Progress {
    /// Bytes consumed from the start of the file (unspecified after a fatal error).
    pub bytes_consumed: u64,
    /// Whether the header has been parsed (it is verified with level 0).
    pub header_complete: bool,
    /// Number of levels whose CRC has been verified.
    pub levels_verified: u32,
    /// Samples in verified levels (`[0, samples_verified)`).
    pub samples_verified: u64,
    /// Refinement layers whose CRC has been verified.
    pub layers_verified: u32,
    /// Samples whose bytes have all arrived (`≥ samples_verified`): the verified ones plus, in the
    /// raw coding, the complete samples of a partial level chunk, which are **unverified**. With the
    /// predictive coding the container cannot tell, and this equals `samples_verified`.
    pub samples_available: u64,
}

/// Where the bytes given so far end (spec/format.md §Truncation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndState {
    /// The header has not been fully received: nothing to show (a decoder may render grey).
    InHeader,
    /// Between chunks, with levels or refinement layers missing: every one so far is complete
    /// and verified.
    BetweenChunks,
    /// Inside a chunk: the complete samples of a partial level payload are usable but unverified.
    InChunk(ChunkRef),
    /// Every level (and every refinement layer) is verified and the bytes end between
    /// chunks: a complete file.
    Complete,
    /// Recovery mode stopped on an error: only verified samples are valid.
    Stopped,
    /// A fatal error was returned; the parser is poisoned.
    Failed,
}

impl std::fmt::Display for EndState {
    /// What the state means to someone reading `qcs info`.
    ///
    /// ```
    /// use qcs::container::EndState;
    /// assert_eq!(EndState::Complete.to_string(), "a complete file");
    /// ```
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EndState::InHeader => write!(f, "inside the header"),
            EndState::BetweenChunks => write!(f, "between chunks, with levels or layers missing"),
            EndState::InChunk(c) => write!(f, "inside {c}"),
            EndState::Complete => write!(f, "a complete file"),
            EndState::Stopped => write!(f, "stopped at a damaged chunk (recovery)"),
            EndState::Failed => write!(f, "failed"),
        }
    }
}

#[derive(Clone, Debug)]
enum Kind {
    Level { level: u32, samples: Range<u64> },
    Layer(LayerRead),
    Icc(Vec<u8>),
    Exif(Vec<u8>),
    Text(Vec<u8>),
    Skip,
}

/// A layer being read: its header and segment table, then its segments.
#[derive(Clone, Debug)]
struct LayerRead {
    layer: u32,
    table: TableReader,
    /// Once the table is read: the lengths of the segments still to come, the stream of the
    /// first of them and the bytes left in it.
    segments: Option<(Vec<u32>, usize)>,
}

#[derive(Clone, Debug)]
enum State {
    Header,
    Tag,
    Length {
        chunk: ChunkRef,
        reader: VarintReader,
        hasher: crc32fast::Hasher,
    },
    Payload {
        chunk: ChunkRef,
        len: u32,
        received: u32,
        hasher: crc32fast::Hasher,
        kind: Kind,
    },
    Crc {
        chunk: ChunkRef,
        len: u32,
        computed: u32,
        bytes: [u8; 4],
        n: usize,
        kind: Kind,
    },
    Stopped,
    Poisoned,
}

impl State {
    /// Inside a payload after `received` of its `len` bytes: still reading it, or on to the CRC.
    fn payload_or_crc(
        chunk: ChunkRef,
        len: u32,
        received: u32,
        hasher: crc32fast::Hasher,
        kind: Kind,
    ) -> State {
        if received == len {
            State::Crc {
                chunk,
                len,
                computed: hasher.finalize(),
                bytes: [0; 4],
                n: 0,
                kind,
            }
        } else {
            State::Payload {
                chunk,
                len,
                received,
                hasher,
                kind,
            }
        }
    }
}

/// A push parser for `.qcs` bytes: feed it any chunking of the file (one byte at a time, empty
/// slices, or all at once) and it emits the same events, as early as they can be known.
///
/// Memory is bounded by the bytes given and by [`Limits`]: level payloads are passed through as
/// they arrive, never buffered; metadata is buffered up to `max_metadata_bytes` in total; the
/// header (at most [`MAX_HEADER_LEN`] bytes) is buffered until complete.
///
/// After a fatal error the parser is poisoned and every further `push` fails.
///
/// ```
/// use qcs::container::{ContainerWriter, Header, Layout, Coding, Parser, Event, EndState};
/// // Levels [0, 2) and [2, 4) of RGB samples, 8 bits per value.
/// let header = Header::new(2, 2, Layout::Rgb, 4, 2, Coding::Raw { bits: 8 });
/// let mut w = ContainerWriter::new(Vec::new(), &header)?;
/// w.write_level(&[1, 2, 3, 4, 5, 6])?;
/// w.write_level(&[7, 8, 9, 10, 11, 12])?;
/// let file = w.finish()?;
///
/// // A prefix that ends inside level 1, after its first sample.
/// let cut = file.len() - 4 /* crc */ - 3;
/// let mut p = Parser::new(Default::default());
/// let mut events = Vec::new();
/// p.push(&file[..cut], &mut events)?;
/// assert_eq!(p.progress().samples_verified, 2);
/// assert_eq!(p.progress().samples_available, 3);
/// assert!(matches!(p.end_state(), EndState::InChunk(_)));
/// p.push(&file[cut..], &mut events)?;
/// assert_eq!(p.end_state(), EndState::Complete);
/// # Ok::<(), qcs::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Parser {
    opts: ParserOptions,
    offset: u64,
    state: State,
    header: Option<Header>,
    /// Where the header's fields are, once it has been parsed.
    header_offsets: FieldOffsets,
    level_count: u32,
    header_buf: Vec<u8>,
    chunk_index: u32,
    next_level: u32,
    samples_verified: u64,
    metadata_bytes: u64,
    seen_icc: bool,
    seen_exif: bool,
    /// The refinement header, once read (version 3).
    refinement: Option<RefinementHeader>,
    /// Layers started and verified.
    layers_started: u32,
    layers_verified: u32,
}

impl Parser {
    /// A parser at the start of a file.
    pub fn new(opts: ParserOptions) -> Self {
        Parser {
            opts,
            offset: 0,
            state: State::Header,
            header: None,
            header_offsets: FieldOffsets::default(),
            level_count: 0,
            header_buf: Vec::new(),
            chunk_index: 0,
            next_level: 0,
            samples_verified: 0,
            metadata_bytes: 0,
            seen_icc: false,
            seen_exif: false,
            refinement: None,
            layers_started: 0,
            layers_verified: 0,
        }
    }

    /// The refinement header, once read from the first layer (version 3).
    pub fn refinement(&self) -> Option<&RefinementHeader> {
        self.refinement.as_ref()
    }

    /// Whether every level and (version 3) every refinement layer is verified.
    fn all_verified(&self) -> bool {
        if self.next_level < self.level_count {
            return false;
        }
        match &self.header {
            Some(h) if h.refinement => self
                .refinement
                .as_ref()
                .is_some_and(|r| self.layers_verified == r.layers),
            _ => true,
        }
    }

    /// The header, once it has been parsed.
    pub fn header(&self) -> Option<&Header> {
        self.header.as_ref()
    }

    /// Where the header's fields are in the file, once it has been parsed (all 0 before).
    pub(crate) fn header_offsets(&self) -> FieldOffsets {
        self.header_offsets
    }

    /// Whether every level is verified and the input ends between chunks.
    pub fn is_complete(&self) -> bool {
        self.end_state() == EndState::Complete
    }

    /// Where the bytes given so far end.
    pub fn end_state(&self) -> EndState {
        match &self.state {
            State::Header => EndState::InHeader,
            State::Tag if self.all_verified() => EndState::Complete,
            State::Tag => EndState::BetweenChunks,
            State::Length { chunk, .. }
            | State::Payload { chunk, .. }
            | State::Crc { chunk, .. } => EndState::InChunk(*chunk),
            State::Stopped => EndState::Stopped,
            State::Poisoned => EndState::Failed,
        }
    }

    /// The current counts (see [`Progress`]).
    pub fn progress(&self) -> Progress {
        let mut available = self.samples_verified;
        if let (
            State::Payload {
                kind: Kind::Level { samples, .. },
                received,
                ..
            }
            | State::Crc {
                kind: Kind::Level { samples, .. },
                len: received,
                ..
            },
            Some(h),
        ) = (&self.state, &self.header)
        {
            if let Coding::Raw { bits } = h.coding {
                let sample_bits = h.layout.channels() as u64 * bits as u64;
                let complete = (*received as u64 * 8) / sample_bits;
                available = samples.start + complete.min(samples.end - samples.start);
            }
        }
        Progress {
            bytes_consumed: self.offset,
            header_complete: self.header.is_some(),
            levels_verified: self.next_level,
            layers_verified: self.layers_verified,
            samples_verified: self.samples_verified,
            samples_available: available,
        }
    }

    /// The chunk being read and how many of its payload bytes have arrived, if inside a chunk.
    pub fn current_chunk(&self) -> Option<(ChunkRef, u32)> {
        match &self.state {
            State::Length { chunk, .. } => Some((*chunk, 0)),
            State::Payload {
                chunk, received, ..
            } => Some((*chunk, *received)),
            State::Crc { chunk, len, .. } => Some((*chunk, *len)),
            _ => None,
        }
    }

    /// Consumes `input` (any length, including 0) and appends the events it completes to `events`.
    ///
    /// "Not enough bytes yet" is never an error. Events found before an error are still appended.
    /// A format error fails (and poisons the parser: every later push is
    /// [`crate::Error::Poisoned`]) unless recovery is on and the header is complete, in which
    /// case [`Event::Stopped`] is appended and `Ok` returned; a limit error always fails.
    pub fn push(&mut self, input: &[u8], events: &mut Vec<Event>) -> Result<(), crate::Error> {
        match self.state {
            State::Poisoned => return Err(crate::Error::Poisoned { object: "Parser" }),
            State::Stopped => return Ok(()),
            _ => {}
        }
        let mut i = 0;
        while i < input.len() {
            match self.step(&input[i..], events) {
                Ok(n) => {
                    i += n;
                    self.offset += n as u64;
                }
                Err(Fail::Format(e)) => {
                    if self.opts.recover && self.header.is_some() {
                        self.state = State::Stopped;
                        events.push(Event::Stopped { error: e });
                        return Ok(());
                    }
                    self.state = State::Poisoned;
                    return Err(e.into());
                }
                Err(Fail::Limits(e)) => {
                    self.state = State::Poisoned;
                    return Err(e.into());
                }
            }
            if matches!(self.state, State::Stopped) {
                return Ok(());
            }
        }
        Ok(())
    }

    /// One step on a non-empty input: returns how many bytes it consumed (≥ 1).
    fn step(&mut self, input: &[u8], events: &mut Vec<Event>) -> Result<usize, Fail> {
        let state = std::mem::replace(&mut self.state, State::Poisoned);
        match state {
            State::Header => self.step_header(input, events),
            State::Tag => {
                self.step_tag(input[0])?;
                Ok(1)
            }
            State::Length {
                chunk,
                mut reader,
                mut hasher,
            } => {
                let b = input[0];
                hasher.update(&[b]);
                match reader.push(b) {
                    Err(error) => Err(Fail::Format(FormatError::ChunkLength { chunk, error })),
                    Ok(None) => {
                        self.state = State::Length {
                            chunk,
                            reader,
                            hasher,
                        };
                        Ok(1)
                    }
                    Ok(Some(len)) => {
                        // A u32 reader never yields more than u32::MAX.
                        let len = u32::try_from(len).unwrap_or(u32::MAX);
                        let kind = self.start_payload(chunk, len, events)?;
                        self.state = State::payload_or_crc(chunk, len, 0, hasher, kind);
                        Ok(1)
                    }
                }
            }
            State::Payload {
                chunk,
                len,
                mut received,
                mut hasher,
                mut kind,
            } => {
                let want = (len - received) as usize;
                let mut take = want.min(input.len());
                if let Kind::Layer(read) = &mut kind {
                    take = self.step_layer(read, chunk, len, received, &input[..take], events)?;
                }
                let bytes = &input[..take];
                hasher.update(bytes);
                match &mut kind {
                    Kind::Layer(_) => {}
                    Kind::Level { level, .. } => events.push(Event::LevelData {
                        level: *level,
                        bytes: bytes.to_vec(),
                    }),
                    Kind::Icc(buf) | Kind::Exif(buf) | Kind::Text(buf) => {
                        buf.extend_from_slice(bytes)
                    }
                    Kind::Skip => {}
                }
                received += take as u32;
                self.state = State::payload_or_crc(chunk, len, received, hasher, kind);
                Ok(take)
            }
            State::Crc {
                chunk,
                len,
                computed,
                mut bytes,
                mut n,
                kind,
            } => {
                bytes[n] = input[0];
                n += 1;
                if n < 4 {
                    self.state = State::Crc {
                        chunk,
                        len,
                        computed,
                        bytes,
                        n,
                        kind,
                    };
                    return Ok(1);
                }
                let stored = LittleEndian::read_u32(&bytes);
                if stored != computed && !cfg!(fuzzing) {
                    return Err(Fail::Format(FormatError::ChunkCrc {
                        chunk,
                        stored,
                        computed,
                    }));
                }
                self.finish_chunk(chunk, len, kind, events)?;
                self.chunk_index = self.chunk_index.saturating_add(1);
                self.state = State::Tag;
                Ok(1)
            }
            State::Stopped | State::Poisoned => {
                // push() never steps in these states.
                self.state = state;
                Ok(input.len())
            }
        }
    }

    fn step_header(&mut self, input: &[u8], events: &mut Vec<Event>) -> Result<usize, Fail> {
        let before = self.header_buf.len();
        let room = MAX_HEADER_LEN - before;
        let take = room.min(input.len());
        self.header_buf.extend_from_slice(&input[..take]);
        match Header::parse_prefix(&self.header_buf) {
            Err(Stop::More) => {
                if self.header_buf.len() >= MAX_HEADER_LEN {
                    // Cannot happen: a header of MAX_HEADER_LEN bytes always parses or fails.
                    return Err(Fail::Format(FormatError::TruncatedHeader {
                        offset: MAX_HEADER_LEN as u64,
                    }));
                }
                self.state = State::Header;
                Ok(take)
            }
            Err(Stop::Err(e)) => Err(Fail::Format(e)),
            Ok((header, len, offsets)) => {
                let limits = &self.opts.limits;
                limits
                    .check_image(header.width as u64, header.height as u64)
                    .map_err(Fail::Limits)?;
                let decoded = match self.opts.max_samples {
                    Some(k) => header.samples_of_levels_before(k),
                    None => header.total_samples,
                };
                limits.check_samples(decoded).map_err(Fail::Limits)?;
                limits
                    .check_alloc(decoded, header.coefficients_decoded(decoded), 0)
                    .map_err(Fail::Limits)?;
                self.level_count = header.level_count();
                self.header = Some(header.clone());
                self.header_offsets = offsets;
                events.push(Event::Header(header));
                // Level 0 follows without a tag; its CRC covers the header too.
                let mut hasher = crc32fast::Hasher::new();
                hasher.update(&self.header_buf[..len]);
                self.header_buf = Vec::new();
                self.state = State::Length {
                    chunk: ChunkRef {
                        index: 0,
                        tag: LEVEL,
                        offset: len as u64,
                    },
                    reader: VarintReader::new(32),
                    hasher,
                };
                Ok(len - before)
            }
        }
    }

    /// Reads layer bytes (at most `input`): the header and table a byte at a time, then
    /// segment bytes up to the end of the current segment. Returns how many were taken.
    fn step_layer(
        &mut self,
        read: &mut LayerRead,
        chunk: ChunkRef,
        len: u32,
        received: u32,
        input: &[u8],
        events: &mut Vec<Event>,
    ) -> Result<usize, Fail> {
        let bad = |e: Bad| {
            Fail::Format(match e {
                Bad::Field(field, value, expected) => FormatError::BadRefinement {
                    chunk,
                    field,
                    value,
                    expected,
                },
                Bad::Varint(field, error) => FormatError::RefinementVarint {
                    chunk,
                    field,
                    error,
                },
            })
        };
        let Some((lengths, stream)) = &mut read.segments else {
            match read.table.push(input[0]).map_err(bad)? {
                Read::More => {}
                Read::Header(h) => {
                    self.refinement = Some(h.clone());
                    events.push(Event::RefinementHeader(h));
                }
                Read::Table(t) => {
                    let declared: u64 = t.iter().map(|&l| l as u64).sum();
                    let available = (len - received - 1) as u64;
                    if declared != available {
                        return Err(Fail::Format(FormatError::SegmentLengths {
                            chunk,
                            declared,
                            available,
                        }));
                    }
                    read.segments = Some((t, 0));
                    Self::skip_empty(read);
                }
            }
            return Ok(1);
        };
        let left = lengths[*stream] as usize;
        let take = left.min(input.len());
        events.push(Event::RefinementData {
            layer: read.layer,
            stream: *stream as u32,
            bytes: input[..take].to_vec(),
        });
        lengths[*stream] -= take as u32;
        Self::skip_empty(read);
        Ok(take)
    }

    /// Moves a layer's current segment past those with no bytes left.
    fn skip_empty(read: &mut LayerRead) {
        if let Some((lengths, stream)) = &mut read.segments {
            while *stream < lengths.len() && lengths[*stream] == 0 {
                *stream += 1;
            }
        }
    }

    fn step_tag(&mut self, tag: u8) -> Result<(), Fail> {
        let chunk = ChunkRef {
            index: self.chunk_index,
            tag,
            offset: self.offset,
        };
        if tag == REFINEMENT {
            let misplaced =
                |reason| Err(Fail::Format(FormatError::MisplacedLayer { chunk, reason }));
            if !self.header.as_ref().is_some_and(|h| h.refinement) {
                return misplaced("a refinement layer in a version-2 file (levels only)");
            }
            if self.next_level < self.level_count {
                return misplaced("a refinement layer before the last level");
            }
            if self
                .refinement
                .as_ref()
                .is_some_and(|r| self.layers_started >= r.layers)
            {
                return misplaced("a refinement layer after the last one its header declares");
            }
        } else if tag == LEVEL {
            if self.next_level >= self.level_count {
                return Err(Fail::Format(FormatError::ExtraLevel { chunk }));
            }
        } else if !chunk::is_ancillary(tag) {
            return Err(Fail::Format(FormatError::UnknownCritical { chunk }));
        } else if tag == ICC && self.seen_icc {
            return Err(Fail::Format(FormatError::DuplicateIcc { chunk }));
        } else if tag == EXIF && self.seen_exif {
            return Err(Fail::Format(FormatError::DuplicateExif { chunk }));
        }
        let mut hasher = crc32fast::Hasher::new();
        hasher.update(&[tag]);
        self.state = State::Length {
            chunk,
            reader: VarintReader::new(32),
            hasher,
        };
        Ok(())
    }

    fn start_payload(
        &mut self,
        chunk: ChunkRef,
        len: u32,
        events: &mut Vec<Event>,
    ) -> Result<Kind, Fail> {
        let header = match &self.header {
            Some(h) => h,
            None => return Ok(Kind::Skip), // unreachable: chunks follow the header
        };
        match chunk.tag {
            LEVEL => {
                let level = self.next_level;
                let samples = header.level_range(level).unwrap_or(0..0);
                if let Some(expected) = header.level_payload_len(level) {
                    if expected != len as u64 {
                        return Err(Fail::Format(FormatError::LevelLength {
                            chunk,
                            level,
                            expected,
                            found: len as u64,
                        }));
                    }
                }
                events.push(Event::LevelStart {
                    level,
                    chunk,
                    samples: samples.clone(),
                    payload_len: len,
                });
                Ok(Kind::Level { level, samples })
            }
            REFINEMENT => {
                let layer = self.layers_started;
                self.layers_started += 1;
                events.push(Event::LayerStart { layer, chunk });
                Ok(Kind::Layer(LayerRead {
                    layer,
                    table: TableReader::new(
                        header.layout.channels() as usize,
                        self.refinement.as_ref(),
                    ),
                    segments: None,
                }))
            }
            ICC | EXIF | TEXT => {
                let total = self.metadata_bytes.saturating_add(len as u64);
                self.opts
                    .limits
                    .check_metadata(total)
                    .map_err(Fail::Limits)?;
                self.metadata_bytes = total;
                Ok(match chunk.tag {
                    ICC => {
                        self.seen_icc = true;
                        Kind::Icc(Vec::new())
                    }
                    EXIF => {
                        self.seen_exif = true;
                        Kind::Exif(Vec::new())
                    }
                    _ => Kind::Text(Vec::new()),
                })
            }
            _ => Ok(Kind::Skip),
        }
    }

    fn finish_chunk(
        &mut self,
        chunk: ChunkRef,
        len: u32,
        kind: Kind,
        events: &mut Vec<Event>,
    ) -> Result<(), Fail> {
        match kind {
            Kind::Level { level, samples } => {
                self.samples_verified = samples.end;
                self.next_level += 1;
                events.push(Event::LevelVerified { level, chunk });
                if self.next_level == self.level_count {
                    events.push(Event::LevelsComplete);
                }
            }
            Kind::Layer(read) => {
                if read.segments.is_none() {
                    // The payload ended inside the header or the segment table.
                    return Err(Fail::Format(FormatError::BadRefinement {
                        chunk,
                        field: "layer payload",
                        value: len as u64,
                        expected: "a refinement header (first layer) and a segment table",
                    }));
                }
                self.layers_verified += 1;
                events.push(Event::LayerVerified {
                    layer: read.layer,
                    chunk,
                });
            }
            Kind::Icc(data) => events.push(Event::Metadata {
                chunk,
                metadata: Metadata::Icc(data),
            }),
            Kind::Exif(data) => events.push(Event::Metadata {
                chunk,
                metadata: Metadata::Exif(data),
            }),
            Kind::Text(data) => {
                let bad = |reason| Fail::Format(FormatError::BadText { chunk, reason });
                let nul = data
                    .iter()
                    .position(|&b| b == 0)
                    .ok_or_else(|| bad("no 0x00 after the key"))?;
                if nul == 0 {
                    return Err(bad("empty key"));
                }
                let key = std::str::from_utf8(&data[..nul]).map_err(|_| bad("key is not UTF-8"))?;
                let value =
                    std::str::from_utf8(&data[nul + 1..]).map_err(|_| bad("value is not UTF-8"))?;
                events.push(Event::Metadata {
                    chunk,
                    metadata: Metadata::Text {
                        key: key.to_owned(),
                        value: value.to_owned(),
                    },
                });
            }
            Kind::Skip => events.push(Event::Skipped {
                chunk,
                payload_len: len,
            }),
        }
        Ok(())
    }
}

enum Fail {
    Format(FormatError),
    Limits(crate::limits::LimitError),
}
