//! A levels-only decoder of raw-coded files over the container's push [`Parser`]: the fuzz
//! harnesses (`fuzz/harness/`) cross-check [`crate::StreamDecoder`] against it, and
//! `tests/container.rs` uses it to read raw levels back.

use crate::coding::raw::RawUnpacker;
use crate::container::{
    Coding, EndState, Event, FormatError, Header, Metadata, Parser, ParserOptions,
};

/// Streaming decoder of raw-coded files: bytes in any chunking → the dequantised colours of every
/// sample available so far, split into verified and not-yet-verified samples.
///
/// It wraps a `Parser` and a `RawUnpacker` per level. `colours()` holds
/// `samples_available() × channels` values in sample order; the first `samples_verified()` samples
/// are CRC-verified, the rest come from a partial level chunk. In recovery mode a damaged chunk
/// drops the unverified samples and stops. Memory grows with the bytes given, never with header
/// claims.
///
/// ```
/// use qcs::container::{ContainerWriter, Header, Layout, Coding};
/// use qcs::coding::raw::pack;
/// use qcs::RawDecoder;
/// let header = Header::new(2, 2, Layout::Grey, 4, 2, Coding::Raw { bits: 8 });
/// let mut w = ContainerWriter::new(Vec::new(), &header)?;
/// w.write_level(&pack(&[10, 20], 8)?)?;
/// w.write_level(&pack(&[30, 40], 8)?)?;
/// let file = w.finish()?;
///
/// let mut d = RawDecoder::new(Default::default());
/// d.push(&file[..file.len() - 5])?; // level 1 has 1 of its 2 payload bytes
/// assert_eq!(d.colours(), [10, 20, 30]);
/// assert_eq!((d.samples_verified(), d.samples_available()), (2, 3));
/// d.push(&file[file.len() - 5..])?;
/// assert_eq!(d.colours(), [10, 20, 30, 40]);
/// assert_eq!(d.samples_verified(), 4);
/// # Ok::<(), qcs::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct RawDecoder {
    parser: Parser,
    events: Vec<Event>,
    unpacker: Option<RawUnpacker>,
    colours: Vec<u8>,
    channels: usize,
    verified: u64,
    metadata: Vec<Metadata>,
    unsupported: bool,
}

impl RawDecoder {
    /// A decoder at the start of a file.
    pub fn new(opts: ParserOptions) -> Self {
        RawDecoder {
            parser: Parser::new(opts),
            events: Vec::new(),
            unpacker: None,
            colours: Vec::new(),
            channels: 1,
            verified: 0,
            metadata: Vec::new(),
            unsupported: false,
        }
    }

    /// Feeds bytes (any length, including 0). Errors as `Parser::push`; a file whose coding is
    /// not raw fails with [`FormatError::UnsupportedCoding`].
    pub fn push(&mut self, bytes: &[u8]) -> Result<(), crate::Error> {
        if self.unsupported {
            return Err(crate::Error::Poisoned {
                object: "RawDecoder",
            });
        }
        let result = self.parser.push(bytes, &mut self.events);
        for ev in std::mem::take(&mut self.events) {
            match ev {
                Event::Header(h) => {
                    if let Coding::Raw { .. } = h.coding {
                        self.channels = h.layout.channels() as usize;
                    } else {
                        self.unsupported = true;
                        return Err(FormatError::UnsupportedCoding {
                            coding: h.coding.id(),
                        }
                        .into());
                    }
                }
                Event::LevelStart { samples, .. } => {
                    let bits = match self.parser.header().map(|h| &h.coding) {
                        Some(Coding::Raw { bits }) => *bits,
                        _ => 8,
                    };
                    self.unpacker = Some(RawUnpacker::new(
                        self.channels as u8,
                        bits,
                        samples.end - samples.start,
                    )?);
                }
                Event::LevelData { bytes, .. } => {
                    if let Some(u) = &mut self.unpacker {
                        u.push(&bytes, &mut self.colours);
                    }
                }
                Event::LevelVerified { .. } => {
                    self.unpacker = None;
                    self.verified = self.parser.progress().samples_verified;
                }
                Event::Metadata { metadata, .. } => self.metadata.push(metadata),
                Event::Stopped { .. } => {
                    self.unpacker = None;
                    self.colours
                        .truncate(self.verified as usize * self.channels);
                }
                // The raw coding's decoder reads the levels only.
                Event::LevelsComplete
                | Event::Skipped { .. }
                | Event::LayerStart { .. }
                | Event::RefinementHeader(_)
                | Event::RefinementData { .. }
                | Event::LayerVerified { .. } => {}
            }
        }
        result
    }

    /// The header, once parsed.
    pub fn header(&self) -> Option<&Header> {
        self.parser.header()
    }

    /// Dequantised colours of the available samples, `channels` values per sample.
    pub fn colours(&self) -> &[u8] {
        &self.colours
    }

    /// Number of samples in [`RawDecoder::colours`].
    pub fn samples_available(&self) -> u64 {
        (self.colours.len() / self.channels) as u64
    }

    /// Number of leading samples whose level CRC has been verified.
    pub fn samples_verified(&self) -> u64 {
        self.verified
    }

    /// Verified metadata chunks so far.
    pub fn metadata(&self) -> &[Metadata] {
        &self.metadata
    }

    /// Where the bytes given so far end.
    pub fn end_state(&self) -> EndState {
        self.parser.end_state()
    }

    /// The underlying parser (progress, current chunk).
    pub fn parser(&self) -> &Parser {
        &self.parser
    }
}
