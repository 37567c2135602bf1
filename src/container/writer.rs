//! Writing a `.qcs` file to any [`std::io::Write`].

use super::chunk::{self, EXIF, ICC, LEVEL, REFINEMENT, TEXT};
use super::refinement::Bad;
use super::{encode_layer, Header, RefinementHeader};
use std::io::Write;

/// Writes a header, then level 0 (no tag; its CRC covers the header), then the other level
/// chunks in order, with metadata chunks placed after level 0.
///
/// Metadata given before level 0 is held back and written right after it (the format forbids
/// metadata before level 0). The caller supplies each level's payload bytes (e.g. from
/// [`crate::coding::raw::pack`]); for the raw coding their length is checked against the header.
///
/// ```
/// use qcs::container::{ContainerWriter, Header, Layout, Coding};
/// let header = Header::new(2, 1, Layout::Grey, 2, 1, Coding::Raw { bits: 8 });
/// let mut w = ContainerWriter::new(Vec::new(), &header)?;
/// w.write_icc(b"fake profile")?;        // held until level 0 is written
/// w.write_level(&[200])?;
/// w.write_level(&[100])?;
/// let file = w.finish()?;
/// assert_eq!(&file[..2], b"qc");
/// # Ok::<(), qcs::Error>(())
/// ```
#[derive(Debug)]
pub struct ContainerWriter<W: Write> {
    inner: W,
    header: Header,
    level_count: u32,
    next_level: u32,
    pending: Vec<Vec<u8>>,
    written: u64,
    icc_written: bool,
    exif_written: bool,
    /// The header's bytes, until level 0 (whose CRC covers them) is written.
    header_bytes: Vec<u8>,
    /// The refinement header once its first layer is written, and the layers written.
    refinement: Option<RefinementHeader>,
    layers_written: u32,
}

impl<W: Write> ContainerWriter<W> {
    /// Validates and writes the header.
    pub fn new(mut inner: W, header: &Header) -> Result<Self, crate::Error> {
        let bytes = header.encode()?;
        inner.write_all(&bytes)?;
        Ok(ContainerWriter {
            inner,
            header: header.clone(),
            level_count: header.level_count(),
            next_level: 0,
            pending: Vec::new(),
            written: bytes.len() as u64,
            icc_written: false,
            exif_written: false,
            header_bytes: bytes,
            refinement: None,
            layers_written: 0,
        })
    }

    /// The header being written.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The index of the next level to write (= levels written so far).
    pub fn next_level(&self) -> u32 {
        self.next_level
    }

    /// Bytes written so far.
    pub fn bytes_written(&self) -> u64 {
        self.written
    }

    /// Writes a chunk's bytes (`None`: its payload was too long for the length field).
    fn put(&mut self, bytes: Option<Vec<u8>>, payload_len: usize) -> Result<(), crate::Error> {
        let bytes = bytes.ok_or_else(|| too_long(payload_len))?;
        self.inner.write_all(&bytes)?;
        self.written += bytes.len() as u64;
        Ok(())
    }

    /// Writes the next level with `payload` as its colour data: level 0 right after the header,
    /// the others as `L` chunks.
    pub fn write_level(&mut self, payload: &[u8]) -> Result<(), crate::Error> {
        let k = self.next_level;
        if k >= self.level_count {
            return Err(crate::Error::misuse(
                "ContainerWriter::write_level",
                format!("all {} levels are written already", self.level_count),
            ));
        }
        if let Some(expected) = self.header.level_payload_len(k) {
            if expected != payload.len() as u64 {
                return Err(crate::Error::invalid(
                    "level payload",
                    format_args!("{} bytes", payload.len()),
                    format!("the {expected} bytes the header implies for level {k}"),
                ));
            }
        }
        let bytes = if k == 0 {
            // Level 0 has no tag, and its CRC covers the header.
            chunk::encode_first(&std::mem::take(&mut self.header_bytes), payload)
        } else {
            chunk::encode(LEVEL, payload)
        };
        self.put(bytes, payload.len())?;
        self.next_level += 1;
        for chunk in std::mem::take(&mut self.pending) {
            self.inner.write_all(&chunk)?;
            self.written += chunk.len() as u64;
        }
        Ok(())
    }

    /// Writes the next refinement layer (an `R` chunk, version 3, after the last level): its
    /// segments, one per stream (trailing empty ones are left out). The first layer carries
    /// the refinement header `header`, which later calls must repeat.
    pub fn write_layer(
        &mut self,
        header: &RefinementHeader,
        segments: &[&[u8]],
    ) -> Result<(), crate::Error> {
        if !self.header.refinement {
            return Err(crate::Error::misuse(
                "ContainerWriter::write_layer",
                "the header has no refinement (version 2)",
            ));
        }
        if self.next_level < self.level_count {
            return Err(crate::Error::misuse(
                "ContainerWriter::write_layer",
                format!(
                    "a layer before the last level ({} of {} levels written)",
                    self.next_level, self.level_count
                ),
            ));
        }
        if segments.len() > header.streams() {
            return Err(crate::Error::invalid(
                "segments",
                segments.len(),
                format!("at most one per stream: {}", header.streams()),
            ));
        }
        let first = match &self.refinement {
            None => {
                header
                    .validate(self.header.layout.channels() as usize)
                    .map_err(|e| match e {
                        Bad::Field(field, value, expected) => crate::Error::invalid(
                            "refinement header",
                            format_args!("{field} = {value}"),
                            expected,
                        ),
                        Bad::Varint(field, e) => crate::Error::invalid(
                            "refinement header",
                            format_args!("{field}: {e}"),
                            "a header the format allows",
                        ),
                    })?;
                self.refinement = Some(header.clone());
                true
            }
            Some(h) if h == header => false,
            Some(_) => {
                return Err(crate::Error::invalid(
                    "refinement header",
                    "another than the first layer's",
                    "the first layer's: a file has one",
                ))
            }
        };
        if self.layers_written >= header.layers {
            return Err(crate::Error::misuse(
                "ContainerWriter::write_layer",
                format!("all {} layers are written already", header.layers),
            ));
        }
        let payload = encode_layer(first.then_some(header), segments);
        self.put(chunk::encode(REFINEMENT, &payload), payload.len())?;
        self.layers_written += 1;
        Ok(())
    }

    /// Writes (or, before level 0, queues) an ancillary chunk. `tag` must have the ancillary bit
    /// (0x20) set; the payload is written as given. At most one ICC (`i`) and one Exif (`e`)
    /// chunk.
    pub fn write_ancillary(&mut self, tag: u8, payload: &[u8]) -> Result<(), crate::Error> {
        if !chunk::is_ancillary(tag) {
            return Err(crate::Error::invalid(
                "chunk tag",
                chunk::tag_name(tag),
                "an ancillary tag (bit 0x20 set)",
            ));
        }
        let once = match tag {
            ICC => Some((&mut self.icc_written, "ContainerWriter::write_icc", "an ICC profile")),
            EXIF => Some((&mut self.exif_written, "ContainerWriter::write_exif", "an Exif chunk")),
            _ => None,
        };
        if let Some((written, call, what)) = once {
            if *written {
                return Err(crate::Error::misuse(
                    call,
                    format!("{what} is written already: a file holds at most one"),
                ));
            }
            *written = true;
        }
        if self.next_level == 0 {
            let bytes = chunk::encode(tag, payload).ok_or_else(|| too_long(payload.len()))?;
            self.pending.push(bytes);
            Ok(())
        } else {
            self.put(chunk::encode(tag, payload), payload.len())
        }
    }

    /// Writes an ICC profile chunk (`i`). At most one per file.
    pub fn write_icc(&mut self, profile: &[u8]) -> Result<(), crate::Error> {
        self.write_ancillary(ICC, profile)
    }

    /// Writes an Exif chunk (`e`): the TIFF-structured Exif block (byte-order mark, IFDs), as
    /// PNG's `eXIf`. At most one per file.
    pub fn write_exif(&mut self, exif: &[u8]) -> Result<(), crate::Error> {
        self.write_ancillary(EXIF, exif)
    }

    /// Writes a text chunk (`t`): `key` (non-empty, no 0x00), 0x00, `value`.
    pub fn write_text(&mut self, key: &str, value: &str) -> Result<(), crate::Error> {
        if key.is_empty() || key.contains('\0') {
            return Err(crate::Error::invalid(
                "text key",
                format_args!("{key:?}"),
                "a non-empty key without NUL",
            ));
        }
        let mut payload = Vec::with_capacity(key.len() + 1 + value.len());
        payload.extend_from_slice(key.as_bytes());
        payload.push(0);
        payload.extend_from_slice(value.as_bytes());
        self.write_ancillary(TEXT, &payload)
    }

    /// Checks that every level was written, flushes and returns the inner writer.
    ///
    /// To stop early on purpose (a deliberately truncated file is still valid), use
    /// [`ContainerWriter::into_inner`].
    pub fn finish(mut self) -> Result<W, crate::Error> {
        if self.next_level < self.level_count {
            return Err(crate::Error::misuse(
                "ContainerWriter::finish",
                format!(
                    "only {} of {} levels written (into_inner stops early on purpose)",
                    self.next_level, self.level_count
                ),
            ));
        }
        if self.header.refinement {
            let want = self.refinement.as_ref().map_or(1, |r| r.layers);
            if self.layers_written < want {
                return Err(crate::Error::misuse(
                    "ContainerWriter::finish",
                    format!(
                        "only {} of {want} refinement layers written (into_inner stops early \
                         on purpose)",
                        self.layers_written
                    ),
                ));
            }
        }
        self.inner.flush()?;
        Ok(self.inner)
    }

    /// Returns the inner writer without checks (queued metadata not yet written is dropped).
    pub fn into_inner(self) -> W {
        self.inner
    }
}

/// A chunk payload longer than the length field holds: the caller's data is too long.
fn too_long(payload_len: usize) -> crate::Error {
    crate::Error::invalid(
        "chunk payload",
        format_args!("{payload_len} bytes"),
        "at most 2^32 − 1 bytes",
    )
}
