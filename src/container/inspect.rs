//! A listing of what a (possibly truncated or damaged) file holds, for `qcs info`.

use super::parser::{EndState, Event, Metadata, Parser, ParserOptions};
use super::{varint, ChunkRef, FormatError, Header, RefinementHeader};
use crate::Limits;
use std::ops::Range;

/// The CRC status of a chunk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ChunkStatus {
    /// Complete, CRC matched.
    Verified,
    /// The file ends inside it.
    Truncated,
    /// It breaks the format (CRC mismatch, bad length, …); nothing after it was read.
    Bad(FormatError),
}

/// One chunk of an [`Inspection`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InspectedChunk {
    /// Index, tag and offset.
    pub chunk: ChunkRef,
    /// The payload length from the chunk's length field, if it was readable.
    pub payload_len: Option<u32>,
    /// The level it holds, for `L` chunks.
    pub level: Option<u32>,
    /// The refinement layer it holds, for `R` chunks.
    pub layer: Option<u32>,
    /// CRC status.
    pub status: ChunkStatus,
}

/// One level of an [`Inspection`] (every level the header implies, present or not).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InspectedLevel {
    /// The level index.
    pub level: u32,
    /// Its sample range.
    pub samples: Range<u64>,
    /// The payload length the header implies (raw coding).
    pub expected_payload_len: Option<u64>,
    /// Its chunk, if it was reached.
    pub chunk: Option<ChunkRef>,
    /// Payload bytes present in the file.
    pub payload_present: u64,
    /// `Some(Verified)`, `Some(Truncated)`, `Some(Bad(..))`, or `None` if its chunk is absent.
    pub status: Option<ChunkStatus>,
}

/// What [`inspect`] found.
#[derive(Debug)]
pub struct Inspection {
    /// File length in bytes.
    pub file_len: u64,
    /// The header, if complete and valid.
    pub header: Option<Header>,
    /// Header length in bytes, if complete.
    pub header_len: Option<u64>,
    /// Every chunk reached, in order.
    pub chunks: Vec<InspectedChunk>,
    /// Every level the header implies.
    pub levels: Vec<InspectedLevel>,
    /// Verified metadata.
    pub metadata: Vec<Metadata>,
    /// Samples in verified levels.
    pub samples_verified: u64,
    /// Samples whose bytes are present (verified or not).
    pub samples_available: u64,
    /// The refinement header (version 3), if its layer was reached.
    pub refinement: Option<RefinementHeader>,
    /// Where the levels end and the refinement begins: the offset of the first `R` chunk.
    pub refinement_offset: Option<u64>,
    /// Refinement layers verified.
    pub layers_verified: u32,
    /// Bytes present of each refinement stream (verified or not).
    pub stream_bytes: Vec<u64>,
    /// Where the file ends.
    pub end: EndState,
    /// The error that stopped reading, if any (a header error, a limit, or a chunk error).
    pub error: Option<crate::Error>,
}

/// Lists the header, chunks (offsets, lengths, CRC status), levels (sample ranges, bytes present)
/// and metadata of a `.qcs` file or prefix. Never fails: problems are reported in the result.
/// Uses [`Limits::none`]: memory stays bounded by `bytes.len()`.
///
/// ```
/// use qcs::container::{inspect, ContainerWriter, Header, Layout, Coding, ChunkStatus};
/// let header = Header::new(3, 3, Layout::Grey, 4, 2, Coding::Raw { bits: 8 });
/// let mut w = ContainerWriter::new(Vec::new(), &header)?;
/// w.write_level(&[1, 2])?;
/// w.write_level(&[3, 4])?;
/// let mut file = w.finish()?;
/// file.truncate(file.len() - 5); // cut inside level 1
/// let info = inspect(&file);
/// assert_eq!(info.levels.len(), 2);
/// assert_eq!(info.levels[0].status, Some(ChunkStatus::Verified));
/// assert_eq!(info.levels[1].status, Some(ChunkStatus::Truncated));
/// assert_eq!(info.levels[1].payload_present, 1);
/// assert_eq!(info.samples_available, 3);
/// # Ok::<(), qcs::Error>(())
/// ```
pub fn inspect(bytes: &[u8]) -> Inspection {
    let mut parser = Parser::new(ParserOptions {
        limits: Limits::none(),
        recover: true,
        max_samples: None,
    });
    let mut events = Vec::new();
    let result = parser.push(bytes, &mut events);
    let header = parser.header().cloned();
    let header_len = header
        .as_ref()
        .and_then(|_| Header::parse(bytes).ok())
        .map(|(_, len)| len as u64);
    let read_len = |c: &ChunkRef| -> Option<u32> {
        // Level 0 has no tag: its length is at its offset.
        let tag_len = (c.index > 0) as usize;
        let start = usize::try_from(c.offset).ok()?.checked_add(tag_len)?;
        match varint::read(bytes.get(start..)?, 32) {
            Ok(Some((v, _))) => u32::try_from(v).ok(),
            _ => None,
        }
    };
    let mut chunks = Vec::new();
    let mut metadata = Vec::new();
    let mut level_data: Vec<u64> = Vec::new();
    let mut refinement = None;
    let mut refinement_offset = None;
    let mut stream_bytes: Vec<u64> = Vec::new();
    let mut error = result.err();
    let levels_verified = parser.progress().levels_verified;
    let layers_verified = parser.progress().layers_verified;
    for ev in events {
        match ev {
            Event::LevelStart { .. } => level_data.push(0),
            Event::LevelData { bytes, .. } => {
                if let Some(n) = level_data.last_mut() {
                    *n += bytes.len() as u64;
                }
            }
            Event::LevelVerified { level, chunk } => {
                chunks.push(InspectedChunk {
                    chunk,
                    payload_len: read_len(&chunk),
                    level: Some(level),
                    layer: None,
                    status: ChunkStatus::Verified,
                });
            }
            Event::LayerStart { chunk, .. } => {
                refinement_offset.get_or_insert(chunk.offset);
            }
            Event::RefinementHeader(h) => {
                stream_bytes = vec![0; h.streams()];
                refinement = Some(h);
            }
            Event::RefinementData { stream, bytes, .. } => {
                if let Some(n) = stream_bytes.get_mut(stream as usize) {
                    *n += bytes.len() as u64;
                }
            }
            Event::LayerVerified { layer, chunk } => chunks.push(InspectedChunk {
                chunk,
                payload_len: read_len(&chunk),
                level: None,
                layer: Some(layer),
                status: ChunkStatus::Verified,
            }),
            Event::Metadata { chunk, metadata: m } => {
                metadata.push(m);
                chunks.push(InspectedChunk {
                    chunk,
                    payload_len: read_len(&chunk),
                    level: None,
                    layer: None,
                    status: ChunkStatus::Verified,
                });
            }
            Event::Skipped { chunk, payload_len } => chunks.push(InspectedChunk {
                chunk,
                payload_len: Some(payload_len),
                level: None,
                layer: None,
                status: ChunkStatus::Verified,
            }),
            Event::Stopped { error: e } => {
                if let Some(chunk) = e.chunk() {
                    chunks.push(InspectedChunk {
                        chunk,
                        payload_len: read_len(&chunk),
                        level: (chunk.tag == super::chunk::LEVEL).then_some(levels_verified),
                        layer: (chunk.tag == super::chunk::REFINEMENT).then_some(layers_verified),
                        status: ChunkStatus::Bad(e.clone()),
                    });
                }
                error = Some(e.into());
            }
            Event::Header(_) | Event::LevelsComplete => {}
        }
    }
    if let EndState::InChunk(chunk) = parser.end_state() {
        chunks.push(InspectedChunk {
            chunk,
            payload_len: read_len(&chunk),
            level: (chunk.tag == super::chunk::LEVEL).then_some(levels_verified),
            layer: (chunk.tag == super::chunk::REFINEMENT).then_some(layers_verified),
            status: ChunkStatus::Truncated,
        });
    }
    let mut levels = Vec::new();
    if let Some(h) = &header {
        for k in 0..h.level_count() {
            let Some(samples) = h.level_range(k) else {
                break;
            };
            let c = chunks.iter().find(|c| c.level == Some(k));
            levels.push(InspectedLevel {
                level: k,
                samples,
                expected_payload_len: h.level_payload_len(k),
                chunk: c.map(|c| c.chunk),
                payload_present: level_data.get(k as usize).copied().unwrap_or(0),
                status: c.map(|c| c.status.clone()),
            });
        }
    }
    let p = parser.progress();
    Inspection {
        file_len: bytes.len() as u64,
        header,
        header_len,
        chunks,
        levels,
        metadata,
        samples_verified: p.samples_verified,
        samples_available: if parser.end_state() == EndState::Stopped {
            p.samples_verified
        } else {
            p.samples_available
        },
        refinement,
        refinement_offset,
        layers_verified: p.layers_verified,
        stream_bytes,
        end: parser.end_state(),
        error,
    }
}

impl std::fmt::Display for ChunkStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ChunkStatus::Verified => f.write_str("CRC ok"),
            ChunkStatus::Truncated => f.write_str("truncated (unverified)"),
            ChunkStatus::Bad(e) => write!(f, "BAD: {e}"),
        }
    }
}

impl Inspection {
    /// The bytes of the refinement present in the file: from where the levels end to where
    /// the chunk after its last layer present begins (metadata may follow it, as the Exif
    /// does), or to the file's end. `None` for a file without a refinement.
    ///
    /// ```
    /// let img = image::DynamicImage::ImageRgb8(image::RgbImage::new(40, 30));
    /// let opts = qcs::EncodeOptions { exif: Some(b"II*\0\x08\0\0\0\0\0".to_vec()), ..Default::default() };
    /// let bytes = qcs::encode(&img, &opts)?;
    /// let ins = qcs::container::inspect(&bytes);
    /// let r = ins.refinement_bytes().expect("a refinement");
    /// assert_eq!(r.start, ins.refinement_offset.unwrap());
    /// assert_eq!(r.end as usize, bytes.len() - (1 + 1 + 10 + 4)); // the Exif chunk follows
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn refinement_bytes(&self) -> Option<std::ops::Range<u64>> {
        let start = self.refinement_offset?;
        let last = self.chunks.iter().rposition(|c| c.layer.is_some());
        let after = last.and_then(|i| self.chunks.get(i + 1));
        Some(start..after.map_or(self.file_len, |c| c.chunk.offset))
    }
}

/// The listing `qcs info` prints: header fields, then one line per level and per chunk.
///
/// ```
/// use qcs::container::{inspect, ContainerWriter, Header, Layout, Coding};
/// let header = Header::new(3, 3, Layout::Grey, 2, 1, Coding::Raw { bits: 8 });
/// let mut w = ContainerWriter::new(Vec::new(), &header)?;
/// w.write_level(&[1])?;
/// w.write_level(&[2])?;
/// let text = inspect(&w.finish()?).to_string();
/// assert!(text.contains("level 1: samples 1..2"));
/// # Ok::<(), qcs::Error>(())
/// ```
impl std::fmt::Display for Inspection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "file: {} bytes", self.file_len)?;
        match &self.header {
            None => writeln!(f, "header: incomplete or invalid")?,
            Some(h) => {
                writeln!(
                    f,
                    "header: {} bytes, {}×{}, {:?} ({} channels), {} samples, first level {}, {} levels",
                    self.header_len.unwrap_or(0),
                    h.width,
                    h.height,
                    h.layout,
                    h.layout.channels(),
                    h.total_samples,
                    h.first_level,
                    h.level_count()
                )?;
                writeln!(f, "coding: {}", h.coding)?;
                match &h.lattice {
                    None => writeln!(f, "lattice: default")?,
                    Some(l) => writeln!(
                        f,
                        "lattice: root {} px, origin ({}, {}) px",
                        l.root_length as f64 / 65536.0,
                        l.origin_x as f64 / 65536.0,
                        l.origin_y as f64 / 65536.0
                    )?,
                }
            }
        }
        for l in &self.levels {
            write!(
                f,
                "level {}: samples {}..{}",
                l.level, l.samples.start, l.samples.end
            )?;
            match (&l.chunk, &l.status) {
                (Some(c), Some(s)) => writeln!(
                    f,
                    ", chunk #{} at byte {}, {} payload bytes, {s}",
                    c.index, c.offset, l.payload_present
                )?,
                _ => writeln!(f, ", missing")?,
            }
        }
        for c in &self.chunks {
            write!(f, "{}", c.chunk)?;
            if let Some(len) = c.payload_len {
                write!(f, ", {len} payload bytes")?;
            }
            writeln!(f, ", {}", c.status)?;
        }
        for m in &self.metadata {
            match m {
                Metadata::Icc(p) => writeln!(f, "ICC profile: {} bytes", p.len())?,
                Metadata::Exif(p) => writeln!(f, "Exif: {} bytes", p.len())?,
                Metadata::Text { key, value } => writeln!(f, "text: {key} = {value}")?,
            }
        }
        writeln!(
            f,
            "samples: {} verified, {} available; end: {:?}",
            self.samples_verified, self.samples_available, self.end
        )?;
        if let Some(e) = &self.error {
            // The error and its causes ("malformed file: chunk #2 …"): `Error` prints only
            // its own part.
            write!(f, "error: {e}")?;
            let mut cause = std::error::Error::source(e);
            while let Some(c) = cause {
                write!(f, ": {c}")?;
                cause = c.source();
            }
            writeln!(f)?;
        }
        Ok(())
    }
}
