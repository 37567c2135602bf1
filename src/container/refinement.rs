//! The refinement's header and layer framing (spec/format.md §Refinement chunks).
//!
//! A version-3 file has, after its last level, one or more `R` chunks, each holding one
//! *layer*. The first one starts with the refinement header; every layer then holds a
//! segment table (a count n, then n lengths) and the n segments: segment s is the next bytes
//! of stream s (stream 0 codes the low-low band, stream s ≥ 1 the details of transform level
//! L − s + 1).

use super::varint::{self, VarintError, VarintReader};

/// The wavelet of a refinement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wavelet {
    /// The reversible 5/3 (LeGall) lifting: exactly invertible, for lossless files.
    Reversible53,
    /// The CDF 9/7 lifting steps with 12-bit weights, each rounded (lossy files).
    Integer97,
}

/// Which passes of each stream the file codes.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum PassLimit {
    /// Every pass whose priority key is at least this (spec/format.md, pass order).
    Key(i32),
    /// The first `n` passes of stream s, for each stream s.
    Counts(Vec<u32>),
}

/// The refinement header: what a decoder needs before the first pass.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct RefinementHeader {
    /// The wavelet.
    pub wavelet: Wavelet,
    /// Bits below the integer grid the transform works at (F, 0..=3): values are × 2^F.
    pub fraction_bits: u8,
    /// Transform levels (L, 0..=15); there are L + 1 streams.
    pub levels: u8,
    /// Bit-planes of each coded channel (0..=30).
    pub bitplanes: Vec<u8>,
    /// Number of layers (`R` chunks), at least 1.
    pub layers: u32,
    /// Which passes are coded.
    pub limit: PassLimit,
}

/// The most bit-planes a channel may have.
pub(crate) const MAX_BITPLANES: u8 = 30;
/// The most transform levels.
pub(crate) const MAX_LEVELS: u8 = 15;
/// The most fraction bits.
pub(crate) const MAX_FRACTION_BITS: u8 = 3;

/// Why a refinement header or segment table could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Bad {
    /// A field's value is out of its range: field name, value, what is allowed.
    Field(&'static str, u64, &'static str),
    /// A varint is malformed.
    Varint(&'static str, VarintError),
}

impl RefinementHeader {
    /// The number of streams, L + 1.
    pub fn streams(&self) -> usize {
        self.levels as usize + 1
    }

    /// The number of passes stream `s` has (three per bit-plane of each of its bands in each
    /// channel; stream 0 has one band, the others three).
    pub fn passes_in_stream(&self, s: usize) -> u64 {
        let per_band: u64 = self.bitplanes.iter().map(|&b| 3 * b as u64).sum();
        if s == 0 {
            per_band
        } else {
            3 * per_band
        }
    }

    /// The bytes of the header.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let kernel = match self.wavelet {
            Wavelet::Reversible53 => 0,
            Wavelet::Integer97 => 1,
        };
        let counts = matches!(self.limit, PassLimit::Counts(_)) as u8;
        out.push((counts << 7) | (self.fraction_bits << 5) | (kernel << 4) | self.levels);
        out.extend_from_slice(&self.bitplanes);
        varint::write_u32(&mut out, self.layers);
        match &self.limit {
            PassLimit::Key(k) => varint::write_u32(&mut out, varint::zigzag(*k)),
            PassLimit::Counts(c) => {
                for &n in c {
                    varint::write_u32(&mut out, n);
                }
            }
        }
        out
    }

    /// Checks the rules of the format (the ranges of the fields) for a file with `channels`
    /// channels.
    pub(crate) fn validate(&self, channels: usize) -> Result<(), Bad> {
        if self.fraction_bits > MAX_FRACTION_BITS {
            return Err(Bad::Field(
                "fraction bits",
                self.fraction_bits as u64,
                "0..=3",
            ));
        }
        if self.levels > MAX_LEVELS {
            return Err(Bad::Field("levels", self.levels as u64, "0..=15"));
        }
        if self.bitplanes.len() != channels {
            return Err(Bad::Field(
                "bit-planes",
                self.bitplanes.len() as u64,
                "one per channel",
            ));
        }
        if let Some(&b) = self.bitplanes.iter().find(|&&b| b > MAX_BITPLANES) {
            return Err(Bad::Field("bit-planes", b as u64, "0..=30"));
        }
        if self.layers == 0 {
            return Err(Bad::Field("layers", 0, "at least 1"));
        }
        if let PassLimit::Counts(c) = &self.limit {
            if c.len() != self.streams() {
                return Err(Bad::Field("pass counts", c.len() as u64, "one per stream"));
            }
            for (s, &n) in c.iter().enumerate() {
                if n as u64 > self.passes_in_stream(s) {
                    return Err(Bad::Field(
                        "pass count",
                        n as u64,
                        "at most the stream's passes",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Reads a refinement header and then a segment table byte by byte (they may arrive in
/// pieces).
#[derive(Clone, Debug)]
pub(crate) struct TableReader {
    channels: usize,
    /// Still to come: the header (first layer only), then the table.
    header: Option<HeaderFields>,
    streams: usize,
    reader: VarintReader,
    /// The segment count, once read, and the lengths read so far.
    count: Option<usize>,
    lengths: Vec<u32>,
    /// Bytes read (header and table).
    pub read: u32,
}

#[derive(Clone, Debug, Default)]
struct HeaderFields {
    first: Option<u8>,
    bitplanes: Vec<u8>,
    layers: Option<u32>,
    values: Vec<u32>,
}

/// What a [`TableReader`] gives back after a byte.
pub(crate) enum Read {
    /// Needs more bytes.
    More,
    /// The refinement header is complete (first layer only); the table follows.
    Header(RefinementHeader),
    /// The segment table is complete: each segment's length.
    Table(Vec<u32>),
}

impl TableReader {
    /// A reader for the first layer (`header` unknown: read it first) or a later one.
    pub(crate) fn new(channels: usize, header: Option<&RefinementHeader>) -> Self {
        TableReader {
            channels,
            header: header.is_none().then(HeaderFields::default),
            streams: header.map_or(0, |h| h.streams()),
            reader: VarintReader::new(32),
            count: None,
            lengths: Vec::new(),
            read: 0,
        }
    }

    pub(crate) fn push(&mut self, b: u8) -> Result<Read, Bad> {
        self.read += 1;
        if let Some(h) = &mut self.header {
            let Some(first) = h.first else {
                h.first = Some(b);
                return Ok(Read::More);
            };
            if h.bitplanes.len() < self.channels {
                h.bitplanes.push(b);
                return Ok(Read::More);
            }
            let Some(v) = self
                .reader
                .push(b)
                .map_err(|e| Bad::Varint("refinement header", e))?
            else {
                return Ok(Read::More);
            };
            self.reader = VarintReader::new(32);
            let v = v as u32;
            let counts = first & 0x80 != 0;
            let levels = first & 0x0F;
            let streams = levels as usize + 1;
            if h.layers.is_none() {
                h.layers = Some(v);
                return Ok(Read::More);
            }
            h.values.push(v);
            let want = if counts { streams } else { 1 };
            if h.values.len() < want {
                return Ok(Read::More);
            }
            let header = RefinementHeader {
                wavelet: if first & 0x10 != 0 {
                    Wavelet::Integer97
                } else {
                    Wavelet::Reversible53
                },
                fraction_bits: (first >> 5) & 3,
                levels,
                bitplanes: std::mem::take(&mut h.bitplanes),
                layers: h.layers.unwrap_or(0),
                limit: if counts {
                    PassLimit::Counts(std::mem::take(&mut h.values))
                } else {
                    PassLimit::Key(varint::unzigzag(h.values[0]))
                },
            };
            header.validate(self.channels)?;
            self.header = None;
            self.streams = streams;
            return Ok(Read::Header(header));
        }
        let Some(v) = self
            .reader
            .push(b)
            .map_err(|e| Bad::Varint("segment table", e))?
        else {
            return Ok(Read::More);
        };
        self.reader = VarintReader::new(32);
        match self.count {
            None => {
                if v as usize > self.streams {
                    return Err(Bad::Field(
                        "segment count",
                        v,
                        "at most the number of streams",
                    ));
                }
                self.count = Some(v as usize);
            }
            Some(_) => self.lengths.push(v as u32),
        }
        if self.lengths.len() == self.count.unwrap_or(usize::MAX) {
            return Ok(Read::Table(std::mem::take(&mut self.lengths)));
        }
        Ok(Read::More)
    }
}

/// The bytes of a layer: the refinement header (first layer only), the segment table and the
/// segments (trailing empty segments left out).
pub fn encode_layer(header: Option<&RefinementHeader>, segments: &[&[u8]]) -> Vec<u8> {
    let mut out = header.map_or_else(Vec::new, RefinementHeader::encode);
    let n = segments
        .iter()
        .rposition(|s| !s.is_empty())
        .map_or(0, |k| k + 1);
    varint::write_u32(&mut out, n as u32);
    for s in &segments[..n] {
        varint::write_u32(&mut out, s.len() as u32);
    }
    for s in &segments[..n] {
        out.extend_from_slice(s);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_all(
        channels: usize,
        header: Option<&RefinementHeader>,
        bytes: &[u8],
    ) -> (Option<RefinementHeader>, Vec<u32>, u32) {
        let mut r = TableReader::new(channels, header);
        let mut got = None;
        for &b in bytes {
            match r.push(b).unwrap() {
                Read::More => {}
                Read::Header(h) => got = Some(h),
                Read::Table(t) => return (got, t, r.read),
            }
        }
        panic!("table not complete");
    }

    #[test]
    fn header_and_table_round_trip() {
        for limit in [
            PassLimit::Key(-37),
            PassLimit::Key(500),
            PassLimit::Counts(vec![0, 90, 3, 270]),
        ] {
            let h = RefinementHeader {
                wavelet: Wavelet::Integer97,
                fraction_bits: 2,
                levels: 3,
                bitplanes: vec![12, 10, 11],
                layers: 9,
                limit,
            };
            let seg: [&[u8]; 4] = [b"abc", b"", b"de", b""];
            let bytes = encode_layer(Some(&h), &seg);
            let (got, table, read) = read_all(3, None, &bytes);
            assert_eq!(got.as_ref(), Some(&h));
            assert_eq!(table, vec![3, 0, 2]);
            assert_eq!(&bytes[read as usize..], b"abcde");
            // A later layer has no header.
            let later = encode_layer(None, &seg);
            let (none, table, _) = read_all(3, Some(&h), &later);
            assert!(none.is_none());
            assert_eq!(table, vec![3, 0, 2]);
        }
    }

    #[test]
    fn bad_fields_are_refused() {
        let ok = RefinementHeader {
            wavelet: Wavelet::Reversible53,
            fraction_bits: 0,
            levels: 2,
            bitplanes: vec![9],
            layers: 1,
            limit: PassLimit::Counts(vec![27, 81, 81]),
        };
        assert!(ok.validate(1).is_ok());
        let mut h = ok.clone();
        h.bitplanes = vec![31];
        assert!(h.validate(1).is_err());
        let mut h = ok.clone();
        h.layers = 0;
        assert!(h.validate(1).is_err());
        let mut h = ok.clone();
        h.limit = PassLimit::Counts(vec![27, 82, 81]);
        assert!(h.validate(1).is_err());
        assert!(ok.validate(3).is_err());
        // More segments than streams.
        let mut r = TableReader::new(1, Some(&ok));
        assert!(r.push(4).is_err());
    }
}
