//! The header (spec/format.md §Header) and the level schedule (§Levels).

use super::varint::{self, VarintReader};
use super::FormatError;
use std::ops::Range;

/// The magic bytes every `.qcs` file starts with.
pub const MAGIC: [u8; 2] = *b"qc";
/// The newest format version (bits 7–5 of the format byte): version 3, levels followed by a
/// refinement. Version 2 files (levels only) are read and written too.
pub const VERSION: u8 = 3;
/// The version of files with levels only.
pub const LEVELS_ONLY_VERSION: u8 = 2;
/// The longest possible header in bytes (every varint at full length, explicit N, lattice).
pub const MAX_HEADER_LEN: usize = 2 + 1 + 5 + 5 + 1 + 10 + 10 + 1 + 5 + 5 + 5 + 1;

/// The header's check byte: CRC-8/SMBUS (polynomial 0x07, initial value 0, no reflection, no
/// final XOR) of every header byte before it. It detects every single-bit error.
///
/// ```
/// assert_eq!(qcs::container::header_check(b"123456789"), 0xF4);
/// ```
pub fn header_check(bytes: &[u8]) -> u8 {
    CRC_8_SMBUS.checksum(bytes)
}

/// The CRC-8/SMBUS table, built at compile time.
const CRC_8_SMBUS: crc::Crc<u8> = crc::Crc::<u8>::new(&crc::CRC_8_SMBUS);

/// The format byte's bits: lattice fields present, default density and first level (the
/// two fields left out), and the coding's and layout's positions.
const LATTICE_BIT: u8 = 0x10;
const DEFAULTS_BIT: u8 = 0x08;
const CODING_SHIFT: u8 = 2;

/// The density byte and first level size that the format byte's defaults bit stands for in a
/// version-2 file: one sample per 4 pixels, 127 samples in level 0.
pub(crate) const DEFAULT_DENSITY_BYTE: u8 = 64;
/// The first level size that the format byte's defaults bit stands for in a version-2 file:
/// 127 samples in level 0 (the density byte's default is one sample per 4 pixels).
pub const DEFAULT_FIRST_LEVEL: u64 = 127;
/// What the defaults bit stands for in a version-3 file: one level of `min(64, W·H)` samples.
pub(crate) const REFINED_DEFAULT_SAMPLES: u64 = 64;

/// Channels per sample and their order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// 1 channel: grey, 8 bits.
    Grey = 1,
    /// 2 channels: grey then alpha, 8 bits each.
    GreyAlpha = 2,
    /// 3 channels: red, green, blue, 8 bits each.
    Rgb = 3,
    /// 4 channels: red, green, blue, alpha, 8 bits each.
    Rgba = 4,
}

impl Layout {
    /// Number of channels per sample (the layout byte).
    ///
    /// ```
    /// assert_eq!(qcs::format::Layout::Rgb.channels(), 3);
    /// ```
    pub fn channels(self) -> u8 {
        self as u8
    }

    /// The layout with this many channels, if any.
    ///
    /// ```
    /// use qcs::format::Layout;
    /// assert_eq!(Layout::from_channels(4), Some(Layout::Rgba));
    /// assert_eq!(Layout::from_channels(5), None);
    /// ```
    pub fn from_channels(c: u8) -> Option<Layout> {
        match c {
            1 => Some(Layout::Grey),
            2 => Some(Layout::GreyAlpha),
            3 => Some(Layout::Rgb),
            4 => Some(Layout::Rgba),
            _ => None,
        }
    }
}

/// How level payloads code colours.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Coding {
    /// Coding 0: every channel value quantised to `bits` (1..=8) bits, packed MSB-first
    /// (spec/format.md, *Codings*).
    Raw {
        /// Bits per channel value, 1..=8.
        bits: u8,
    },
    /// Coding 1, predictive (spec/format.md, *Codings*): its parameter byte (the
    /// quantisation step, ≥ 1) is passed through; level payload lengths are free.
    Predictive {
        /// The quantisation step, 1..=255 (1 is lossless).
        step: u8,
    },
}

impl Coding {
    /// The coding byte.
    ///
    /// ```
    /// assert_eq!(qcs::format::Coding::Raw { bits: 4 }.id(), 0);
    /// ```
    pub fn id(&self) -> u8 {
        match self {
            Coding::Raw { .. } => 0,
            Coding::Predictive { .. } => 1,
        }
    }
}

// `Params::coding` is defined here, beside `Coding`, rather than in `coding::predictive`: the
// coding layer turns colours into bits and does not know the container's types.
impl crate::coding::predictive::Params {
    /// The header's coding for these parameters.
    ///
    /// ```
    /// use qcs::coding::predictive::Params;
    /// use qcs::format::Coding;
    /// assert_eq!(Params::from_quality(80).coding(), Coding::Predictive { step: 5 });
    /// ```
    pub fn coding(&self) -> Coding {
        Coding::Predictive { step: self.step }
    }
}

/// How `qcs info` names a coding.
///
/// ```
/// use qcs::format::Coding;
/// assert_eq!(Coding::Raw { bits: 8 }.to_string(), "raw, 8 bits per channel");
/// assert_eq!(Coding::Predictive { step: 7 }.to_string(), "predictive, step 7");
/// assert_eq!(Coding::Predictive { step: 1 }.to_string(), "predictive, lossless (step 1)");
/// ```
impl std::fmt::Display for Coding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Coding::Raw { bits } => write!(f, "raw, {bits} bits per channel"),
            Coding::Predictive { step: 1 } => write!(f, "predictive, lossless (step 1)"),
            Coding::Predictive { step } => write!(f, "predictive, step {step}"),
        }
    }
}

/// Explicit lattice fields (present when flags bit 0 is set), in 16.16 fixed point pixels.
///
/// Without them the decoder uses the default lattice of spec/sites.md.
///
/// ```
/// use qcs::format::{Header, LatticeFields, Layout, Coding};
/// let mut h = Header::new(64, 48, Layout::Rgb, 500, 8, Coding::Raw { bits: 8 });
/// h.lattice = Some(LatticeFields { root_length: 0x1_8000, origin_x: -32 << 16, origin_y: -16 << 16 });
/// assert_eq!(Header::parse(&h.encode()?)?.0, h); // 1.5 px root, origin (−32, −16)
/// # Ok::<(), qcs::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LatticeFields {
    /// Root length, 16.16 fixed point pixels, ≥ 1 (i.e. ≥ 2^-16 px). `0x1_0000` is 1 px.
    pub root_length: u32,
    /// Origin x, 16.16 fixed point pixels.
    pub origin_x: i32,
    /// Origin y, 16.16 fixed point pixels.
    pub origin_y: i32,
}

/// A parsed and validated `.qcs` header.
///
/// The fields are public; [`Header::validate`] (called by [`Header::encode`] and by the parsers)
/// checks the rules of the spec.
///
/// ```
/// use qcs::format::{Header, Layout, Coding};
/// let h = Header::new(640, 480, Layout::Rgb, 10_000, 64, Coding::Raw { bits: 6 });
/// let bytes = h.encode()?;
/// let (parsed, len) = Header::parse(&bytes)?;
/// assert_eq!(parsed, h);
/// assert_eq!(len, bytes.len());
/// # Ok::<(), qcs::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Header {
    /// Image width in pixels, ≥ 1.
    pub width: u32,
    /// Image height in pixels, ≥ 1.
    pub height: u32,
    /// Channels per sample.
    pub layout: Layout,
    /// Total number of samples N, ≥ 1.
    pub total_samples: u64,
    /// Size of the first level L0, ≥ 1 (may exceed N: then there is one level of N samples).
    pub first_level: u64,
    /// The colour coding and its parameters.
    pub coding: Coding,
    /// Explicit lattice fields, or `None` for the default lattice.
    pub lattice: Option<LatticeFields>,
    /// Whether a refinement follows the levels (format version 3; version 2 without).
    pub refinement: bool,
}

/// Where a parsed header's fields are, in bytes from the start of the file (0 for a field the
/// header leaves out): what the header's errors name, and the decoder's when the site
/// construction rejects the frame (spec/format.md §Header).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct FieldOffsets {
    pub(crate) width: u64,
    pub(crate) height: u64,
    pub(crate) total_samples: u64,
    pub(crate) first_level: u64,
    pub(crate) parameter: u64,
    pub(crate) root_length: u64,
}

/// Internal: why parsing a prefix stopped.
pub(crate) enum Stop {
    /// The bytes end before the header does.
    More,
    /// The header is malformed.
    Err(FormatError),
}

impl From<FormatError> for Stop {
    fn from(e: FormatError) -> Self {
        Stop::Err(e)
    }
}

struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl Cursor<'_> {
    fn u8(&mut self) -> Result<u8, Stop> {
        let b = *self.bytes.get(self.pos).ok_or(Stop::More)?;
        self.pos += 1;
        Ok(b)
    }

    fn varint(&mut self, field: &'static str, bits: u32) -> Result<(u64, u64), Stop> {
        let offset = self.pos as u64;
        let mut r = VarintReader::new(bits);
        loop {
            let b = self.u8()?;
            match r.push(b) {
                Ok(Some(v)) => return Ok((v, offset)),
                Ok(None) => {}
                Err(error) => {
                    return Err(Stop::Err(FormatError::HeaderVarint {
                        field,
                        offset,
                        error,
                    }))
                }
            }
        }
    }
}

fn invalid(field: &'static str, offset: u64, value: u64, expected: &'static str) -> FormatError {
    FormatError::InvalidField {
        field,
        offset,
        value,
        expected,
    }
}

impl Header {
    /// A header with the default lattice.
    pub fn new(
        width: u32,
        height: u32,
        layout: Layout,
        total_samples: u64,
        first_level: u64,
        coding: Coding,
    ) -> Header {
        Header {
            width,
            height,
            layout,
            total_samples,
            first_level,
            coding,
            lattice: None,
            refinement: false,
        }
    }

    /// The format version of this header: 3 with a refinement, 2 without.
    pub fn version(&self) -> u8 {
        if self.refinement {
            VERSION
        } else {
            LEVELS_ONLY_VERSION
        }
    }

    /// The sample count and first level size the defaults bit stands for.
    fn defaults(&self) -> (u64, u64) {
        defaults_for(self.refinement, self.width, self.height)
    }

    /// The samples of the levels that start before sample `k`: what a decoder that stops at
    /// `k` decodes (all N when `k` is in the last level).
    pub(crate) fn samples_of_levels_before(&self, k: u64) -> u64 {
        (0..self.level_count())
            .map_while(|l| self.level_range(l))
            .take_while(|r| r.start < k)
            .last()
            .map_or(0, |r| r.end)
    }

    /// The refinement's coefficients (width × height × channels) a decoder that decodes
    /// `decoded` samples of the levels goes on to decode: all of them if the file has a
    /// refinement and every level is decoded, else none.
    pub(crate) fn coefficients_decoded(&self, decoded: u64) -> u64 {
        if self.refinement && decoded >= self.total_samples {
            (self.width as u64 * self.height as u64) * self.layout.channels() as u64
        } else {
            0
        }
    }

    /// Number of levels: ⌈log2(N/L0)⌉ + 1 (1 when L0 ≥ N). Never more than 64.
    ///
    /// ```
    /// use qcs::format::{Header, Layout, Coding};
    /// let h = Header::new(8, 8, Layout::Grey, 100, 10, Coding::Raw { bits: 8 });
    /// assert_eq!(h.level_count(), 5); // 10, 20, 40, 80, 100
    /// ```
    pub fn level_count(&self) -> u32 {
        let n = self.total_samples;
        let mut e = self.first_level.min(n);
        let mut k = 1;
        while e < n && k < 128 {
            e = e.saturating_mul(2).min(n);
            k += 1;
        }
        k
    }

    /// The sample range `[s_k, e_k)` of level `k`, or `None` if there is no level `k`.
    ///
    /// ```
    /// use qcs::format::{Header, Layout, Coding};
    /// let h = Header::new(8, 8, Layout::Grey, 100, 10, Coding::Raw { bits: 8 });
    /// assert_eq!(h.level_range(0), Some(0..10));
    /// assert_eq!(h.level_range(3), Some(40..80));
    /// assert_eq!(h.level_range(4), Some(80..100));
    /// assert_eq!(h.level_range(5), None);
    /// ```
    pub fn level_range(&self, k: u32) -> Option<Range<u64>> {
        let n = self.total_samples;
        let mut s = 0u64;
        let mut e = self.first_level.min(n);
        for _ in 0..k {
            if e >= n {
                return None;
            }
            s = e;
            e = e.saturating_mul(2).min(n);
        }
        if s >= e {
            return None;
        }
        Some(s..e)
    }

    /// The payload length of level `k` in bytes if the coding fixes it (raw coding:
    /// ⌈count·channels·B/8⌉), `None` for the predictive coding or if there is no level `k`.
    ///
    /// ```
    /// use qcs::format::{Header, Layout, Coding};
    /// let h = Header::new(8, 8, Layout::Rgb, 100, 10, Coding::Raw { bits: 5 });
    /// assert_eq!(h.level_payload_len(0), Some(19)); // 10 samples · 3 · 5 bits = 150 bits
    /// ```
    pub fn level_payload_len(&self, k: u32) -> Option<u64> {
        let range = self.level_range(k)?;
        match self.coding {
            Coding::Raw { bits } => crate::coding::raw::payload_len(
                range.end - range.start,
                self.layout.channels(),
                bits,
            ),
            Coding::Predictive { .. } => None,
        }
    }

    /// Checks the rules of the spec that the types do not already enforce.
    ///
    /// ```
    /// use qcs::format::{Header, Layout, Coding};
    /// assert!(Header::new(0, 1, Layout::Grey, 1, 1, Coding::Raw { bits: 8 }).validate().is_err());
    /// assert!(Header::new(1, 1, Layout::Grey, 1, 1, Coding::Raw { bits: 9 }).validate().is_err());
    /// assert!(Header::new(1, 1, Layout::Grey, 1, 1, Coding::Predictive { step: 0 }).validate().is_err());
    /// assert!(Header::new(1, 1, Layout::Grey, 1, 1, Coding::Raw { bits: 1 }).validate().is_ok());
    /// ```
    pub fn validate(&self) -> Result<(), FormatError> {
        // Offsets are unknown here (0); the parser reports real offsets.
        self.validate_at(&FieldOffsets::default())
    }

    /// The rules, with errors at the fields' `offsets`.
    fn validate_at(&self, offsets: &FieldOffsets) -> Result<(), FormatError> {
        if self.width == 0 {
            return Err(invalid("width", offsets.width, 0, "≥ 1"));
        }
        if self.height == 0 {
            return Err(invalid("height", offsets.height, 0, "≥ 1"));
        }
        if self.total_samples == 0 {
            return Err(invalid("total samples", offsets.total_samples, 0, "≥ 1"));
        }
        if self.first_level == 0 {
            return Err(invalid("first level size", offsets.first_level, 0, "≥ 1"));
        }
        match self.coding {
            Coding::Raw { bits } => {
                if !(1..=8).contains(&bits) {
                    return Err(invalid(
                        "raw bits per channel",
                        offsets.parameter,
                        bits as u64,
                        "1..=8",
                    ));
                }
                // Every level's payload must fit a chunk (u32 length); the last level is the largest
                // or equal to the largest but one, so check them all (≤ 64).
                for k in 0..self.level_count() {
                    let fits = self
                        .level_payload_len(k)
                        .is_some_and(|len| len <= u32::MAX as u64);
                    if !fits {
                        return Err(invalid(
                            "total samples",
                            offsets.total_samples,
                            self.total_samples,
                            "levels whose payload fits in 2^32 − 1 bytes",
                        ));
                    }
                }
            }
            Coding::Predictive { step } => {
                if step == 0 {
                    return Err(invalid("predictive step", offsets.parameter, 0, "1..=255"));
                }
            }
        }
        if let Some(l) = &self.lattice {
            if l.root_length == 0 {
                return Err(invalid(
                    "lattice root length",
                    offsets.root_length,
                    0,
                    "≥ 1",
                ));
            }
        }
        Ok(())
    }

    /// The density byte that gives this header's N, or 0 if N must be written out:
    /// a byte `d` in 1..=255 stands for `N = max(1, ⌊W·H·d / 256⌋)`.
    ///
    /// ```
    /// use qcs::format::{Header, Layout, Coding};
    /// let h = Header::new(512, 512, Layout::Rgb, 32768, 64, Coding::Predictive { step: 17 });
    /// assert_eq!(h.density_byte(), 32); // one sample per 8 pixels
    /// assert_eq!(Header { total_samples: 32769, ..h }.density_byte(), 0);
    /// ```
    pub fn density_byte(&self) -> u8 {
        (1..=255u8)
            .find(|&d| samples_for_density(self.width, self.height, d) == self.total_samples)
            .unwrap_or(0)
    }

    /// The header's bytes, its check byte (`header_check`) last. (Level 0's CRC covers the
    /// header too.) At the encoder's density and first level size (one sample per 4 pixels,
    /// 127) the format byte's defaults bit stands for both fields, and they are left out.
    ///
    /// ```
    /// use qcs::format::{Header, Layout, Coding};
    /// let bytes = Header::new(1, 1, Layout::Grey, 1, 1, Coding::Raw { bits: 8 }).encode()?;
    /// // "qc", version 2 with raw grey, 1 × 1, density byte 1 (N = 1), L0 = 1, B = 8, check.
    /// assert_eq!(bytes[..8], [b'q', b'c', 0x40, 1, 1, 1, 1, 8]);
    /// assert_eq!(bytes.len(), 9); // the check byte: CRC-8/SMBUS of the eight before it
    /// # Ok::<(), qcs::Error>(())
    /// ```
    pub fn encode(&self) -> Result<Vec<u8>, crate::Error> {
        // A header to write is the caller's: a field the format forbids is a bad argument.
        self.validate().map_err(|e| match e {
            FormatError::InvalidField {
                field,
                value,
                expected,
                ..
            } => crate::Error::invalid("header", format_args!("{field} = {value}"), expected),
            other => crate::Error::invalid("header", other, "a header the format allows"),
        })?;
        let mut out = Vec::with_capacity(16);
        out.extend_from_slice(&MAGIC);
        let lattice = if self.lattice.is_some() {
            LATTICE_BIT
        } else {
            0
        };
        // Several density bytes may give N; the defaults bit is taken whenever they agree.
        let defaults = (self.total_samples, self.first_level) == self.defaults();
        out.push(
            (self.version() << 5)
                | lattice
                | if defaults { DEFAULTS_BIT } else { 0 }
                | (self.coding.id() << CODING_SHIFT)
                | (self.layout.channels() - 1),
        );
        varint::write_u32(&mut out, self.width);
        varint::write_u32(&mut out, self.height);
        if !defaults {
            let d = self.density_byte();
            out.push(d);
            if d == 0 {
                varint::write_u64(&mut out, self.total_samples);
            }
            varint::write_u64(&mut out, self.first_level);
        }
        out.push(match self.coding {
            Coding::Raw { bits } => bits,
            Coding::Predictive { step } => step,
        });
        if let Some(l) = &self.lattice {
            varint::write_u32(&mut out, l.root_length);
            varint::write_u32(&mut out, varint::zigzag(l.origin_x));
            varint::write_u32(&mut out, varint::zigzag(l.origin_y));
        }
        out.push(header_check(&out));
        Ok(out)
    }

    /// Parses a header from the start of `bytes`, returning it and its length in bytes.
    ///
    /// `bytes` may go on past the header. Limits are not checked here (the push parser
    /// checks them); a buffer that ends inside the header is [`FormatError::TruncatedHeader`].
    pub fn parse(bytes: &[u8]) -> Result<(Header, usize), FormatError> {
        match Self::parse_prefix(bytes) {
            Ok((header, len, _)) => Ok((header, len)),
            Err(Stop::Err(e)) => Err(e),
            Err(Stop::More) => Err(FormatError::TruncatedHeader {
                offset: bytes.len() as u64,
            }),
        }
    }

    /// Parses a header from a prefix: `Stop::More` if the bytes end inside it. Errors in the
    /// magic and the version, and malformed varints, are reported as soon as their
    /// byte arrives; then the check byte; then the value rules. With the header, its length
    /// and where its fields are.
    pub(crate) fn parse_prefix(bytes: &[u8]) -> Result<(Header, usize, FieldOffsets), Stop> {
        let mut c = Cursor { bytes, pos: 0 };
        for (i, &m) in MAGIC.iter().enumerate() {
            let b = c.u8()?;
            if b != m {
                return Err(FormatError::BadMagic {
                    offset: i as u64,
                    found: b,
                }
                .into());
            }
        }
        let format = c.u8()?;
        let version = format >> 5;
        if version != VERSION && version != LEVELS_ONLY_VERSION {
            return Err(FormatError::UnsupportedVersion { version }.into());
        }
        let refinement = version == VERSION;
        let coding_id = (format >> CODING_SHIFT) & 1;
        let layout = Layout::from_channels((format & 3) + 1).unwrap_or(Layout::Grey);
        let (width, o_w) = c.varint("width", 32)?;
        let (height, o_h) = c.varint("height", 32)?;
        let defaults = format & DEFAULTS_BIT != 0;
        let mut o_n = c.pos as u64;
        let (total, first, o_l0) = if defaults {
            let (n, l0) = defaults_for(refinement, width as u32, height as u32);
            (n, l0, o_n)
        } else {
            let d = c.u8()?;
            let total = if d == 0 {
                let (n, o) = c.varint("total samples", 64)?;
                o_n = o;
                n
            } else {
                samples_for_density(width as u32, height as u32, d)
            };
            let (first, o_l0) = c.varint("first level size", 64)?;
            (total, first, o_l0)
        };
        let o_param = c.pos as u64;
        let param = c.u8()?;
        let coding = match coding_id {
            0 => Coding::Raw { bits: param },
            _ => Coding::Predictive { step: param },
        };
        let mut o_root = 0;
        let lattice = if format & LATTICE_BIT != 0 {
            let (root, o) = c.varint("lattice root length", 32)?;
            o_root = o;
            let (ox, _) = c.varint("lattice origin x", 32)?;
            let (oy, _) = c.varint("lattice origin y", 32)?;
            Some(LatticeFields {
                root_length: root as u32,
                origin_x: varint::unzigzag(ox as u32),
                origin_y: varint::unzigzag(oy as u32),
            })
        } else {
            None
        };
        let o_check = c.pos;
        let stored = c.u8()?;
        let computed = header_check(&bytes[..o_check]);
        if stored != computed && !cfg!(fuzzing) {
            return Err(FormatError::HeaderCheck {
                offset: o_check as u64,
                stored,
                computed,
            }
            .into());
        }
        let header = Header {
            width: width as u32,
            height: height as u32,
            layout,
            total_samples: total,
            first_level: first,
            coding,
            lattice,
            refinement,
        };
        let offsets = FieldOffsets {
            width: o_w,
            height: o_h,
            total_samples: o_n,
            first_level: o_l0,
            parameter: o_param,
            root_length: o_root,
        };
        header.validate_at(&offsets)?;
        Ok((header, c.pos, offsets))
    }
}

/// The sample count and first level size the defaults bit stands for: in version 2, one
/// sample per 4 pixels in levels from 127; in version 3, one level of `min(64, W·H)`.
fn defaults_for(refinement: bool, width: u32, height: u32) -> (u64, u64) {
    if refinement {
        let n = REFINED_DEFAULT_SAMPLES
            .min(width as u64 * height as u64)
            .max(1);
        (n, REFINED_DEFAULT_SAMPLES)
    } else {
        (
            samples_for_density(width, height, DEFAULT_DENSITY_BYTE),
            DEFAULT_FIRST_LEVEL,
        )
    }
}

/// N for a density byte `d` ≥ 1: `max(1, ⌊W·H·d / 256⌋)`.
fn samples_for_density(width: u32, height: u32, d: u8) -> u64 {
    ((width as u128 * height as u128 * d as u128) >> 8).max(1) as u64
}
