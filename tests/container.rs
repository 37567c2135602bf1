//! The `.qcs` container: header, level schedule, push parser, writer, inspector, raw coding.
//!
//! Expected values are computed independently of the code under test (literal bytes, float
//! formulas, offsets summed by hand) wherever possible.

use proptest::prelude::*;
use qcs::coding::raw;
use qcs::container::{
    chunk, inspect, varint, ChunkRef, ChunkStatus, Coding, ContainerWriter, EndState, Event,
    FormatError, Header, LatticeFields, Layout, Metadata, Parser, ParserOptions,
};
use qcs::limits::LimitError;
use qcs::{Error, Limits, RawDecoder};

// ---------------------------------------------------------------------------------------------
// A small hand-built file: 5×4 RGB, N = 7, L0 = 2 → levels [0,2) [2,4) [4,7), raw B = 5.
// Chunks: level 0 (no tag), t, L1, x (unknown ancillary), L2, i.
// ---------------------------------------------------------------------------------------------

const B: u8 = 5;
const CH: usize = 3;

fn sample_values() -> Vec<u8> {
    (0..7 * CH).map(|i| (i * 37 % 256) as u8).collect()
}

fn level_payload(k: usize) -> Vec<u8> {
    let ranges = [0..2, 2..4, 4..7];
    let v = sample_values();
    let r = &ranges[k];
    raw::pack(&v[r.start * CH..r.end * CH], B).unwrap()
}

fn test_header() -> Header {
    Header::new(5, 4, Layout::Rgb, 7, 2, Coding::Raw { bits: B })
}

/// Header bytes written out by hand from the spec: format byte 0x42 (version 2, raw, RGB),
/// density byte 90 (⌊20·90/256⌋ = 7, and 89 would give 6), then the check byte.
fn header_bytes_by_hand() -> Vec<u8> {
    with_check(vec![b'q', b'c', 0x42, 5, 4, 90, 2, B])
}

/// Appends the header check byte: CRC-8/SMBUS, computed bit by bit as the spec says.
fn with_check(mut h: Vec<u8>) -> Vec<u8> {
    let mut c = 0u8;
    for &b in &h {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ 0x07
            } else {
                c << 1
            };
        }
    }
    h.push(c);
    h
}

/// Level 0 written out by hand after `header`: length, payload, CRC of everything before it.
fn level0_by_hand(header: &[u8], payload: &[u8]) -> Vec<u8> {
    assert!(payload.len() < 128);
    let mut c = vec![payload.len() as u8];
    c.extend_from_slice(payload);
    let crc = crc32fast::hash(&[header, &c].concat());
    c.extend_from_slice(&crc.to_le_bytes());
    c
}

/// Bytes before the payload of chunk `i` of [`test_file`]: level 0 has no tag.
fn framing(i: usize) -> usize {
    if i == 0 {
        1
    } else {
        2
    }
}

/// A chunk written out by hand from the spec (length < 128 so the varint is one byte).
fn chunk_by_hand(tag: u8, payload: &[u8]) -> Vec<u8> {
    assert!(payload.len() < 128);
    let mut c = vec![tag, payload.len() as u8];
    c.extend_from_slice(payload);
    let crc = crc32fast::hash(&c);
    c.extend_from_slice(&crc.to_le_bytes());
    c
}

/// The file and the (offset, length) of each chunk.
fn test_file() -> (Vec<u8>, Vec<(u8, usize, usize)>) {
    let mut file = header_bytes_by_hand();
    let mut chunks = Vec::new();
    let parts: Vec<(u8, Vec<u8>)> = vec![
        (b'L', level_payload(0)),
        (b't', b"Title\0quasi".to_vec()),
        (b'L', level_payload(1)),
        (b'x', vec![9, 8, 7]),
        (b'L', level_payload(2)),
        (b'i', b"ICCPROFILE".to_vec()),
    ];
    for (i, (tag, payload)) in parts.into_iter().enumerate() {
        let c = if i == 0 {
            level0_by_hand(&file, &payload)
        } else {
            chunk_by_hand(tag, &payload)
        };
        chunks.push((tag, file.len(), c.len()));
        file.extend_from_slice(&c);
    }
    (file, chunks)
}

fn with_limits(limits: Limits) -> ParserOptions {
    ParserOptions {
        limits,
        ..Default::default()
    }
}

fn parse_all(bytes: &[u8], opts: ParserOptions) -> (Parser, Vec<Event>, Result<(), Error>) {
    let mut p = Parser::new(opts);
    let mut ev = Vec::new();
    let r = p.push(bytes, &mut ev);
    (p, ev, r)
}

/// Merges consecutive `LevelData` events of the same level (their split depends on the chunking).
fn normalise(events: Vec<Event>) -> Vec<Event> {
    let mut out: Vec<Event> = Vec::new();
    for e in events {
        if let Event::LevelData { level, bytes } = &e {
            if let Some(Event::LevelData {
                level: l,
                bytes: prev,
            }) = out.last_mut()
            {
                if l == level {
                    prev.extend_from_slice(bytes);
                    continue;
                }
            }
        }
        out.push(e);
    }
    out
}

fn format_err(r: Result<(), Error>) -> FormatError {
    match r {
        Err(Error::Format(e)) => e,
        other => panic!("expected a format error, got {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Header
// ---------------------------------------------------------------------------------------------

#[test]
fn header_encoding_matches_hand_written_bytes() {
    assert_eq!(test_header().encode().unwrap(), header_bytes_by_hand());

    let mut h = Header::new(300, 2, Layout::Rgb, 1000, 16, Coding::Raw { bits: 5 });
    h.lattice = Some(LatticeFields {
        root_length: 0x1_0000,
        origin_x: -5,
        origin_y: 7,
    });
    // Format byte 0x52: version 2, lattice, raw, RGB. N = 1000 > W·H is for the site
    // construction to refuse, not the header: no density byte gives it, so it is written out.
    let expected = with_check(vec![
        b'q', b'c', 0x52, 0xAC, 0x02, 2, 0, 0xE8, 0x07, 16, 5, 0x80, 0x80, 0x04, 9, 14,
    ]);
    assert_eq!(h.encode().unwrap(), expected);
    assert_eq!(Header::parse(&expected).unwrap(), (h, expected.len()));

    // The encoder's defaults (one sample per 4 px, L0 = 127) leave both fields out: format
    // byte 0x4E is version 2, defaults bit, predictive, RGB; then W, H, the step, the check.
    let h = Header::new(
        512,
        512,
        Layout::Rgb,
        65536,
        127,
        Coding::Predictive { step: 7 },
    );
    let short = with_check(vec![b'q', b'c', 0x4E, 0x80, 0x04, 0x80, 0x04, 7]);
    assert_eq!(h.encode().unwrap(), short);
    assert_eq!(short[8], 0x5e, "spec/format.md's worked example");
    assert_eq!(Header::parse(&short).unwrap(), (h.clone(), short.len()));
    // Written out in full (density byte 64, L0 127) it is the same header, two bytes longer.
    let long = with_check(vec![b'q', b'c', 0x46, 0x80, 0x04, 0x80, 0x04, 64, 127, 7]);
    assert_eq!(Header::parse(&long).unwrap(), (h.clone(), long.len()));
    // At 82 × 1 density bytes 63 and 64 both give N = 20: the defaults bit still applies
    // (the fuzzer found the encoder writing the 9-byte form of a 7-byte header).
    let tiny = Header::new(82, 1, Layout::Grey, 20, 127, Coding::Predictive { step: 7 });
    assert_eq!(tiny.encode().unwrap().len(), 7);
    // Either field off its default keeps both in the header.
    for h in [
        Header {
            first_level: 126,
            ..h.clone()
        },
        Header {
            total_samples: 65537,
            ..h
        },
    ] {
        let bytes = h.encode().unwrap();
        assert_eq!(bytes[2] & 0x08, 0, "{h:?}");
        assert_eq!(Header::parse(&bytes).unwrap(), (h, bytes.len()));
    }
}

fn arb_header() -> impl Strategy<Value = Header> {
    let layout = prop_oneof![
        Just(Layout::Grey),
        Just(Layout::GreyAlpha),
        Just(Layout::Rgb),
        Just(Layout::Rgba)
    ];
    let coding = prop_oneof![
        (1u8..=8).prop_map(|bits| Coding::Raw { bits }),
        (1u8..=255).prop_map(|step| Coding::Predictive { step }),
    ];
    let lattice = proptest::option::of((1u32.., any::<i32>(), any::<i32>()).prop_map(
        |(root_length, origin_x, origin_y)| LatticeFields {
            root_length,
            origin_x,
            origin_y,
        },
    ));
    (
        1u32..,
        1u32..,
        layout,
        prop_oneof![1u64..1000, 1u64..(1 << 30), 1u64..],
        prop_oneof![1u64..100, 1u64..],
        coding,
        lattice,
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(
            |(w, h, layout, n, l0, coding, lattice, defaults, refinement)| Header {
                width: w,
                height: h,
                layout,
                // Sometimes the values of the format byte's defaults bit: in version 2 one
                // sample per 4 pixels from 127, in version 3 one level of 64.
                total_samples: match (defaults, refinement) {
                    (true, false) => (u64::from(w) * u64::from(h) / 4).max(1),
                    (true, true) => (u64::from(w) * u64::from(h)).min(64),
                    _ => n,
                },
                first_level: match (defaults, refinement) {
                    (true, false) => 127,
                    (true, true) => 64,
                    _ => l0,
                },
                coding,
                lattice,
                refinement,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn header_round_trip(h in arb_header()) {
        // A raw header whose last level would not fit a chunk is refused; everything else round-trips.
        let fits = match h.coding {
            Coding::Raw { bits } => {
                let last = h.level_range(h.level_count() - 1).unwrap();
                (last.end - last.start) as u128 * h.layout.channels() as u128 * bits as u128
                    <= 8 * u32::MAX as u128
            }
            Coding::Predictive { .. } => true,
        };
        match h.encode() {
            Ok(bytes) => {
                prop_assert!(fits);
                prop_assert!(bytes.len() <= qcs::container::MAX_HEADER_LEN);
                let mut with_tail = bytes.clone();
                with_tail.extend_from_slice(b"Ltail");
                prop_assert_eq!(Header::parse(&with_tail).unwrap(), (h.clone(), bytes.len()));
                // Every strict prefix is "need more data" to the push parser, never an error.
                for cut in 0..bytes.len() {
                    let (p, ev, r) = parse_all(&bytes[..cut], with_limits(Limits::none()));
                    prop_assert!(r.is_ok());
                    prop_assert!(ev.is_empty());
                    prop_assert_eq!(p.end_state(), EndState::InHeader);
                }
            }
            Err(_) => prop_assert!(!fits),
        }
    }

    #[test]
    fn level_schedule(n in 1u64.., l0 in 1u64..) {
        let h = Header::new(1, 1, Layout::Grey, n, l0, Coding::Predictive { step: 1 });
        let count = h.level_count();
        // Independent: ⌈log2(N/L0)⌉ + 1 = 1 + the least j ≥ 0 with L0·2^j ≥ N.
        let mut j = 0u32;
        while (l0 as u128) << j < n as u128 {
            j += 1;
        }
        prop_assert_eq!(count, j + 1);
        prop_assert!(count <= 65);
        let mut next = 0u64;
        for k in 0..count {
            let r = h.level_range(k).unwrap();
            prop_assert_eq!(r.start, next);
            let want_end = ((l0 as u128) << k).min(n as u128) as u64;
            prop_assert_eq!(r.end, want_end);
            next = r.end;
        }
        prop_assert_eq!(next, n);
        prop_assert_eq!(h.level_range(count), None);
    }
}

#[test]
fn schedule_small_cases() {
    let h = |n, l0| Header::new(1, 1, Layout::Grey, n, l0, Coding::Raw { bits: 8 });
    assert_eq!(h(1, 1).level_count(), 1);
    assert_eq!(h(5, 100).level_count(), 1);
    assert_eq!(h(5, 100).level_range(0), Some(0..5));
    assert_eq!(h(8, 1).level_count(), 4); // 1, 2, 4, 8
    assert_eq!(h(9, 1).level_count(), 5); // 1, 2, 4, 8, 9
    assert_eq!(h(9, 1).level_range(4), Some(8..9));
    assert_eq!(h(u64::MAX, 1).level_count(), 65);
}

#[test]
fn header_rules() {
    let good = header_bytes_by_hand();
    // The header with byte i changed and a correct check byte (so the value rule is what fails).
    let with = |i: usize, b: u8| {
        let mut h = good[..good.len() - 1].to_vec();
        h[i] = b;
        with_check(h)
    };
    // Another version: rejected as soon as the format byte arrives (2 and 3 are read).
    for version in [0u8, 1, 4, 7] {
        let e = format_err(parse_all(&with(2, version << 5 | 2)[..3], Default::default()).2);
        assert_eq!(e, FormatError::UnsupportedVersion { version });
    }
    // "qcs" 0x01 (a pre-release layout) starts a version-3 header like any other.
    assert!(parse_all(b"qcs\x01", Default::default()).2.is_ok());
    // Bad magic after one byte.
    let e = format_err(parse_all(b"Q", Default::default()).2);
    assert_eq!(
        e,
        FormatError::BadMagic {
            offset: 0,
            found: b'Q'
        }
    );
    // The check byte.
    let mut bad = good.clone();
    *bad.last_mut().unwrap() ^= 1;
    assert!(matches!(
        format_err(parse_all(&bad, Default::default()).2),
        FormatError::HeaderCheck { offset: 8, .. }
    ));
    // Field rules.
    let explicit_n0 = with_check(vec![b'q', b'c', 0x42, 5, 4, 0, 0, 2, B]);
    let cases: [(Vec<u8>, &str, u64); 5] = [
        (with(3, 0), "width", 3),
        (with(4, 0), "height", 4),
        (explicit_n0, "total samples", 6),
        (with(6, 0), "first level size", 6),
        (with(7, 9), "raw bits per channel", 7),
    ];
    for (bytes, field, offset) in cases {
        let e = format_err(parse_all(&bytes, Default::default()).2);
        match e {
            FormatError::InvalidField {
                field: f,
                offset: o,
                ..
            } => assert_eq!((f, o), (field, offset)),
            other => panic!("{field}: {other:?}"),
        }
    }
    let mut zero_step = with(2, 0x46);
    zero_step.truncate(7);
    zero_step.push(0);
    let e = format_err(parse_all(&with_check(zero_step), Default::default()).2);
    assert!(matches!(
        e,
        FormatError::InvalidField {
            field: "predictive step",
            offset: 7,
            ..
        }
    ));
    // Non-minimal varint in the width.
    let mut nm = good[..3].to_vec();
    nm.extend_from_slice(&[0x85, 0x00]);
    let e = format_err(parse_all(&nm, Default::default()).2);
    assert_eq!(
        e,
        FormatError::HeaderVarint {
            field: "width",
            offset: 3,
            error: varint::VarintError::NonMinimal
        }
    );
    // A density byte: N = max(1, ⌊W·H·d/256⌋), so 1 × 1 with d = 1 is one sample.
    let (h, len) = Header::parse(&with_check(vec![b'q', b'c', 0x40, 1, 1, 1, 1, 8])).unwrap();
    assert_eq!((h.total_samples, len), (1, 9));
    let square = with_check(vec![b'q', b'c', 0x40, 0x80, 0x04, 0x80, 0x04, 0x40, 1, 8]);
    let (h, _) = Header::parse(&square).unwrap();
    assert_eq!(h.total_samples, 512 * 512 / 4);
}

#[test]
fn huge_claims_rejected_by_default_limits() {
    // 2^32−1 × 2^32−1 pixels (the largest a u32 field holds).
    let h = Header::new(
        u32::MAX,
        u32::MAX,
        Layout::Rgb,
        100,
        1,
        Coding::Raw { bits: 8 },
    );
    let bytes = h.encode().unwrap();
    let (p, ev, r) = parse_all(&bytes, Default::default());
    assert!(
        matches!(r, Err(Error::Limits(LimitError::Dimension { .. }))),
        "{r:?}"
    );
    assert!(ev.is_empty());
    assert_eq!(p.end_state(), EndState::Failed);

    // 2^40 samples (predictive coding, since raw levels that large cannot be written).
    let h = Header::new(
        100,
        100,
        Layout::Rgb,
        1 << 40,
        1,
        Coding::Predictive { step: 1 },
    );
    let r = parse_all(&h.encode().unwrap(), Default::default()).2;
    assert!(
        matches!(r, Err(Error::Limits(LimitError::Samples { .. }))),
        "{r:?}"
    );

    // A raw header claiming 2^40 samples is malformed (its levels cannot fit a chunk).
    let mut hand = vec![b'q', b'c', 0x42, 100, 100, 0];
    varint::write_u64(&mut hand, 1 << 40);
    hand.extend_from_slice(&[1, 8]);
    let hand = with_check(hand);
    let e = format_err(parse_all(&hand, with_limits(Limits::none())).2);
    assert!(matches!(
        e,
        FormatError::InvalidField {
            field: "total samples",
            ..
        }
    ));

    // Under Limits::none (dimensions up to 2^16 − 1) a huge header is accepted, and nothing is
    // allocated for it.
    let h = Header::new(
        65535,
        65535,
        Layout::Rgb,
        1 << 40,
        1,
        Coding::Predictive { step: 1 },
    );
    let (p, ev, r) = parse_all(&h.encode().unwrap(), with_limits(Limits::none()));
    assert!(r.is_ok());
    assert_eq!(ev, vec![Event::Header(h)]);
    assert!(matches!(p.end_state(), EndState::InChunk(c) if c.index == 0));
}

// ---------------------------------------------------------------------------------------------
// Parser: whole file, prefixes, chunkings
// ---------------------------------------------------------------------------------------------

#[test]
fn whole_file_events() {
    let (file, chunks) = test_file();
    let (p, ev, r) = parse_all(&file, Default::default());
    r.unwrap();
    assert!(p.is_complete());
    let cref = |i: usize| ChunkRef {
        index: i as u32,
        tag: chunks[i].0,
        offset: chunks[i].1 as u64,
    };
    let expected = vec![
        Event::Header(test_header()),
        Event::LevelStart {
            level: 0,
            chunk: cref(0),
            samples: 0..2,
            payload_len: 4, // 2·3·5 = 30 bits
        },
        Event::LevelData {
            level: 0,
            bytes: level_payload(0),
        },
        Event::LevelVerified {
            level: 0,
            chunk: cref(0),
        },
        Event::Metadata {
            chunk: cref(1),
            metadata: Metadata::Text {
                key: "Title".into(),
                value: "quasi".into(),
            },
        },
        Event::LevelStart {
            level: 1,
            chunk: cref(2),
            samples: 2..4,
            payload_len: 4,
        },
        Event::LevelData {
            level: 1,
            bytes: level_payload(1),
        },
        Event::LevelVerified {
            level: 1,
            chunk: cref(2),
        },
        Event::Skipped {
            chunk: cref(3),
            payload_len: 3,
        },
        Event::LevelStart {
            level: 2,
            chunk: cref(4),
            samples: 4..7,
            payload_len: 6, // 45 bits
        },
        Event::LevelData {
            level: 2,
            bytes: level_payload(2),
        },
        Event::LevelVerified {
            level: 2,
            chunk: cref(4),
        },
        Event::LevelsComplete,
        Event::Metadata {
            chunk: cref(5),
            metadata: Metadata::Icc(b"ICCPROFILE".to_vec()),
        },
    ];
    assert_eq!(ev, expected);
    let pr = p.progress();
    assert_eq!(pr.samples_verified, 7);
    assert_eq!(pr.samples_available, 7);
    assert_eq!(pr.levels_verified, 3);
    assert_eq!(pr.bytes_consumed, file.len() as u64);
}

#[test]
fn every_prefix_monotone() {
    let (file, chunks) = test_file();
    let hlen = header_bytes_by_hand().len();
    let level_chunks: Vec<(usize, usize, usize)> = chunks
        .iter()
        .enumerate()
        .filter(|(_, c)| c.0 == b'L')
        .map(|(i, c)| (c.1, c.2, framing(i)))
        .collect();
    let starts = [0u64, 2, 4];
    let ends = [2u64, 4, 7];
    let (mut last_v, mut last_a) = (0, 0);
    for cut in 0..=file.len() {
        let (p, _, r) = parse_all(&file[..cut], Default::default());
        r.unwrap();
        let pr = p.progress();
        assert!(pr.samples_verified <= pr.samples_available, "cut {cut}");
        assert!(
            pr.samples_verified >= last_v && pr.samples_available >= last_a,
            "cut {cut}"
        );
        (last_v, last_a) = (pr.samples_verified, pr.samples_available);
        // Independent expectation from the chunk offsets.
        let mut verified = 0;
        let mut available = 0;
        for (k, &(off, len, pre)) in level_chunks.iter().enumerate() {
            if cut >= off + len {
                verified = ends[k];
                available = ends[k];
            } else if cut > off + pre {
                let got = (cut - off - pre).min(len - pre - 4) as u64; // payload bytes present
                available = starts[k] + (got * 8 / (CH as u64 * B as u64)).min(ends[k] - starts[k]);
            }
        }
        assert_eq!(
            (pr.samples_verified, pr.samples_available),
            (verified, available),
            "cut {cut}"
        );
        let expected_end = if cut < hlen {
            EndState::InHeader
        } else if cut == file.len() || cut == chunks[5].1 {
            EndState::Complete // every level verified, ending between chunks
        } else if chunks[1..].iter().any(|c| c.1 == cut) {
            EndState::BetweenChunks
        } else {
            // Right after the header, level 0 has begun (its length comes next).
            let i = chunks.iter().rposition(|c| c.1 <= cut).unwrap();
            EndState::InChunk(ChunkRef {
                index: i as u32,
                tag: chunks[i].0,
                offset: chunks[i].1 as u64,
            })
        };
        assert_eq!(p.end_state(), expected_end, "cut {cut}");
        // The partial level payload's complete samples decode to the right colours.
        let info = inspect(&file[..cut]);
        assert_eq!(info.samples_available, available);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn chunking_invariance(sizes in proptest::collection::vec(0usize..9, 1..200)) {
        let (file, _) = test_file();
        let (_, whole, r) = parse_all(&file, Default::default());
        r.unwrap();
        let mut p = Parser::new(Default::default());
        let mut ev = Vec::new();
        let mut pos = 0;
        // Zero-length pushes are part of the test, but a list of only zeros would never end.
        let all_zero = sizes.iter().all(|&s| s == 0);
        let mut sizes = sizes.into_iter().cycle();
        while pos < file.len() {
            let n = if all_zero { 1 } else { sizes.next().unwrap().min(file.len() - pos) };
            p.push(&file[pos..pos + n], &mut ev).unwrap();
            pos += n;
        }
        prop_assert!(p.is_complete());
        prop_assert_eq!(normalise(ev), whole);
    }
}

#[test]
fn byte_at_a_time_with_empty_pushes() {
    let (file, _) = test_file();
    let (_, whole, _) = parse_all(&file, Default::default());
    let mut p = Parser::new(Default::default());
    let mut ev = Vec::new();
    for b in &file {
        p.push(&[], &mut ev).unwrap();
        p.push(std::slice::from_ref(b), &mut ev).unwrap();
    }
    assert_eq!(normalise(ev), whole);
}

// ---------------------------------------------------------------------------------------------
// Damage
// ---------------------------------------------------------------------------------------------

#[test]
fn every_bit_flip_detected() {
    let (file, chunks) = test_file();
    let hlen = header_bytes_by_hand().len();
    for byte in 0..file.len() {
        for bit in 0..8 {
            let mut bad = file.clone();
            bad[byte] ^= 1 << bit;
            let (p, _, r) = parse_all(&bad, Default::default());
            let what = format!("byte {byte} bit {bit}");
            if byte < hlen {
                // The check byte (or an earlier rule) catches every header flip.
                let e = format_err(r);
                assert_eq!(e.chunk(), None, "{what}: {e:?}");
                continue;
            }
            let i = chunks.iter().rposition(|c| c.1 <= byte).unwrap();
            let (tag, off, _) = chunks[i];
            let in_length = byte == off + framing(i) - 1;
            match r {
                Err(Error::Format(e)) => {
                    if !in_length {
                        let c = e.chunk().unwrap_or_else(|| panic!("{what}: {e:?}"));
                        assert_eq!((c.index, c.offset), (i as u32, off as u64), "{what}: {e}");
                    } else if tag == b'L' {
                        // A level's length is fixed by the header.
                        assert_eq!(e.chunk().map(|c| c.offset), Some(off as u64), "{what}: {e}");
                    }
                }
                Err(Error::Limits(_)) => assert!(in_length, "{what}"),
                Err(e) => panic!("{what}: {e}"),
                // Only a changed ancillary length can make the file look like a longer file's prefix.
                Ok(()) => {
                    assert!(in_length && tag != b'L', "{what}");
                    assert!(!p.is_complete(), "{what}");
                }
            }
        }
    }
}

#[test]
fn recovery_keeps_longest_verified_prefix() {
    let (file, chunks) = test_file();
    let (_, off, len) = chunks[4]; // level 2
    let mut bad = file.clone();
    bad[off + 3] ^= 0x10;
    // Without recovery: an error naming chunk #4, then poisoned.
    let mut p = Parser::new(Default::default());
    let mut ev = Vec::new();
    let e = format_err(p.push(&bad, &mut ev));
    assert!(
        matches!(e, FormatError::ChunkCrc { chunk, .. } if chunk.index == 4 && chunk.offset == off as u64)
    );
    assert!(
        e.to_string()
            .contains(&format!("chunk #4 'L' at byte {off}")),
        "{e}"
    );
    // Poisoned: the first error is the one to report.
    assert!(matches!(
        p.push(&[], &mut ev),
        Err(Error::Poisoned { object: "Parser" })
    ));
    assert_eq!(p.end_state(), EndState::Failed);
    // Events before the error were still delivered.
    assert!(ev.contains(&Event::LevelVerified {
        level: 1,
        chunk: ChunkRef {
            index: 2,
            tag: b'L',
            offset: chunks[2].1 as u64
        }
    }));

    // With recovery: a Stopped event, verified samples only, the rest ignored.
    let mut p = Parser::new(ParserOptions {
        recover: true,
        ..Default::default()
    });
    let mut ev = Vec::new();
    p.push(&bad[..off + len], &mut ev).unwrap();
    p.push(&bad[off + len..], &mut ev).unwrap();
    assert!(matches!(
        ev.last(),
        Some(Event::Stopped {
            error: FormatError::ChunkCrc { .. }
        })
    ));
    assert_eq!(p.end_state(), EndState::Stopped);
    let pr = p.progress();
    assert_eq!((pr.samples_verified, pr.samples_available), (4, 4));
    assert!(!ev.iter().any(|e| matches!(
        e,
        Event::Metadata {
            metadata: Metadata::Icc(_),
            ..
        }
    )));

    // The inspector reports the damaged chunk.
    let info = inspect(&bad);
    assert_eq!(
        info.levels[2]
            .status
            .as_ref()
            .map(|s| matches!(s, ChunkStatus::Bad(_))),
        Some(true)
    );
    assert_eq!(info.levels[1].status, Some(ChunkStatus::Verified));
    assert_eq!(info.samples_verified, 4);
    assert!(info.error.is_some());
}

#[test]
fn chunk_order_rules() {
    let header = header_bytes_by_hand();
    let l = |k| {
        if k == 0 {
            level0_by_hand(&header, &level_payload(0))
        } else {
            chunk_by_hand(b'L', &level_payload(k))
        }
    };
    let cat = |parts: &[Vec<u8>]| parts.concat();

    // Unknown ancillary: skipped.
    let f = cat(&[header.clone(), l(0), chunk_by_hand(b'q', b"zz"), l(1), l(2)]);
    let (p, ev, r) = parse_all(&f, Default::default());
    r.unwrap();
    assert!(p.is_complete());
    assert!(ev
        .iter()
        .any(|e| matches!(e, Event::Skipped { payload_len: 2, .. })));

    // Unknown critical: rejected at its tag.
    let off = header.len() + l(0).len();
    let f = cat(&[header.clone(), l(0), chunk_by_hand(b'Q', b"zz"), l(1), l(2)]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert_eq!(
        e,
        FormatError::UnknownCritical {
            chunk: ChunkRef {
                index: 1,
                tag: b'Q',
                offset: off as u64
            }
        }
    );

    // Nothing can come before level 0: a chunk there is read as level 0's length (a 't' is
    // 116 bytes of payload, where the raw coding fixes 4).
    let f = cat(&[header.clone(), chunk_by_hand(b't', b"a\0b"), l(0)]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert!(matches!(
        e,
        FormatError::LevelLength { chunk, level: 0, found: 116, .. } if chunk.index == 0
    ));

    // A level too many.
    let f = cat(&[header.clone(), l(0), l(1), l(2), l(2)]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert!(matches!(e, FormatError::ExtraLevel { chunk } if chunk.index == 3));

    // A stray byte after a complete file.
    let f = cat(&[header.clone(), l(0), l(1), l(2), vec![0]]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert!(matches!(e, FormatError::UnknownCritical { chunk } if chunk.tag == 0));

    // Level payload of the wrong length (level 2 needs 6 bytes).
    let f = cat(&[header.clone(), l(0), l(1), chunk_by_hand(b'L', &[0; 5])]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert!(matches!(
        e,
        FormatError::LevelLength {
            level: 2,
            expected: 6,
            found: 5,
            ..
        }
    ));

    // Bad text, two ICC profiles.
    let f = cat(&[header.clone(), l(0), chunk_by_hand(b't', b"nokey")]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert!(matches!(e, FormatError::BadText { .. }));
    let icc = chunk_by_hand(b'i', b"p");
    let f = cat(&[header.clone(), l(0), icc.clone(), icc]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert!(matches!(e, FormatError::DuplicateIcc { chunk } if chunk.index == 2));
    // Two Exif chunks, apart: the second is the error, at its tag byte.
    let exif = chunk_by_hand(b'e', b"MM\0*\0\0\0\x08\0\0");
    let f = cat(&[header.clone(), l(0), exif.clone(), l(1), exif.clone()]);
    let (_, ev, r) = parse_all(&f, Default::default());
    let e = format_err(r);
    assert!(matches!(e, FormatError::DuplicateExif { chunk } if chunk.index == 3));
    assert!(ev.iter().any(|e| matches!(
        e,
        Event::Metadata { metadata: Metadata::Exif(x), .. } if x == b"MM\0*\0\0\0\x08\0\0"
    )));

    // Non-minimal chunk length.
    let mut f = cat(&[header.clone(), l(0)]);
    f.extend_from_slice(&[b't', 0x83, 0x00]);
    let e = format_err(parse_all(&f, Default::default()).2);
    assert!(matches!(e, FormatError::ChunkLength { chunk, .. } if chunk.index == 1));
}

#[test]
fn metadata_limit() {
    let (file, _) = test_file();
    let limits = Limits {
        max_metadata_bytes: 10, // the text chunk has 11 bytes
        ..Default::default()
    };
    let (_, ev, r) = parse_all(&file, with_limits(limits));
    assert!(
        matches!(
            r,
            Err(Error::Limits(LimitError::Metadata {
                value: 11,
                limit: 10
            }))
        ),
        "{r:?}"
    );
    assert!(ev
        .iter()
        .any(|e| matches!(e, Event::LevelVerified { level: 0, .. })));
    let limits = Limits {
        max_metadata_bytes: 21, // 11 + 10
        ..Default::default()
    };
    assert!(parse_all(&file, with_limits(limits)).2.is_ok());
}

// ---------------------------------------------------------------------------------------------
// Writer and inspector
// ---------------------------------------------------------------------------------------------

#[test]
fn writer_matches_hand_built_file() {
    let mut w = ContainerWriter::new(Vec::new(), &test_header()).unwrap();
    w.write_text("Title", "quasi").unwrap(); // queued until level 0 is written
    w.write_level(&level_payload(0)).unwrap();
    w.write_level(&level_payload(1)).unwrap();
    w.write_ancillary(b'x', &[9, 8, 7]).unwrap();
    assert_eq!(w.next_level(), 2);
    w.write_level(&level_payload(2)).unwrap();
    w.write_icc(b"ICCPROFILE").unwrap();
    assert!(w.write_icc(b"again").is_err());
    let mut twice = ContainerWriter::new(Vec::new(), &test_header()).unwrap();
    twice.write_exif(b"II*\0\x08\0\0\0").unwrap();
    assert!(twice.write_exif(b"II*\0\x08\0\0\0").is_err());
    assert!(w.write_level(&[0]).is_err());
    assert!(w.write_ancillary(b'X', b"").is_err());
    let bytes = w.finish().unwrap();
    assert_eq!(bytes, test_file().0);

    let mut w = ContainerWriter::new(Vec::new(), &test_header()).unwrap();
    assert!(w.write_level(&[0; 3]).is_err()); // level 0 needs 4 bytes
    w.write_level(&level_payload(0)).unwrap();
    assert!(w.finish().is_err()); // levels missing
}

#[test]
fn inspection_lists_chunks_and_levels() {
    let (file, chunks) = test_file();
    let info = inspect(&file);
    assert_eq!(info.header, Some(test_header()));
    assert_eq!(info.header_len, Some(header_bytes_by_hand().len() as u64));
    assert_eq!(info.end, EndState::Complete);
    assert!(info.error.is_none());
    let listed: Vec<(u8, u64, Option<u32>)> = info
        .chunks
        .iter()
        .map(|c| (c.chunk.tag, c.chunk.offset, c.payload_len))
        .collect();
    let expected: Vec<(u8, u64, Option<u32>)> = chunks
        .iter()
        .enumerate()
        .map(|(i, &(t, o, l))| (t, o as u64, Some((l - framing(i) - 4) as u32)))
        .collect();
    assert_eq!(listed, expected);
    assert_eq!(info.levels.len(), 3);
    assert_eq!(info.levels[2].samples, 4..7);
    assert_eq!(
        info.levels[2].chunk.map(|c| c.offset),
        Some(chunks[4].1 as u64)
    );
    assert_eq!(info.levels[2].expected_payload_len, Some(6));
    assert_eq!(info.metadata.len(), 2);

    // A file cut between level 0 and the text chunk.
    let info = inspect(&file[..chunks[1].1]);
    assert_eq!(info.end, EndState::BetweenChunks);
    assert_eq!(info.levels[1].status, None);
    assert_eq!(info.samples_verified, 2);
    // Garbage.
    let info = inspect(b"PNG");
    assert!(info.header.is_none());
    assert!(matches!(
        info.error,
        Some(Error::Format(FormatError::BadMagic { .. }))
    ));
}

// ---------------------------------------------------------------------------------------------
// Raw coding
// ---------------------------------------------------------------------------------------------

#[test]
fn raw_pack_unpack_every_bit_depth() {
    let values: Vec<u8> = vec![0, 255, 128, 1, 254, 77, 200, 13, 64];
    for bits in 1..=8u8 {
        let m = ((1u32 << bits) - 1) as f64;
        // Independent expectation: float rounding and a string of '0'/'1'.
        let q: Vec<u32> = values
            .iter()
            .map(|&v| (v as f64 * m / 255.0).round() as u32)
            .collect();
        let mut s = String::new();
        for &x in &q {
            s.push_str(&format!("{:0width$b}", x, width = bits as usize));
        }
        while !s.len().is_multiple_of(8) {
            s.push('0');
        }
        let expected: Vec<u8> = s
            .as_bytes()
            .chunks(8)
            .map(|c| u8::from_str_radix(std::str::from_utf8(c).unwrap(), 2).unwrap())
            .collect();
        let packed = raw::pack(&values, bits).unwrap();
        assert_eq!(packed, expected, "B={bits}");
        assert_eq!(raw::payload_len(3, 3, bits), Some(expected.len() as u64));
        let decoded: Vec<u8> = q
            .iter()
            .map(|&x| (x as f64 * 255.0 / m).round() as u8)
            .collect();
        assert_eq!(
            raw::unpack(&packed, 3, bits, 3).unwrap(),
            decoded,
            "B={bits}"
        );
        if bits == 8 {
            assert_eq!(decoded, values);
        }
        // Partial payloads: only complete samples (3 values each).
        for cut in 0..=packed.len() {
            let n = (cut * 8 / (3 * bits as usize)).min(3);
            assert_eq!(
                raw::unpack(&packed[..cut], 3, bits, 3).unwrap(),
                decoded[..n * 3].to_vec(),
                "B={bits} cut={cut}"
            );
        }
        // Streaming, byte by byte.
        let mut u = raw::RawUnpacker::new(3, bits, 3).unwrap();
        let mut out = Vec::new();
        for b in &packed {
            u.push(std::slice::from_ref(b), &mut out);
        }
        assert_eq!(out, decoded);
    }
    assert!(raw::pack(&values, 0).is_err());
    assert!(raw::pack(&values, 9).is_err());
}

#[test]
fn parsed_level_data_decodes_to_quantised_colours() {
    let (file, _) = test_file();
    let (_, ev, _) = parse_all(&file, Default::default());
    let mut colours = Vec::new();
    let h = test_header();
    for e in ev {
        if let Event::LevelData { level, bytes } = e {
            let r = h.level_range(level).unwrap();
            colours.extend(raw::unpack(&bytes, 3, B, r.end - r.start).unwrap());
        }
    }
    let m = 31.0;
    let expected: Vec<u8> = sample_values()
        .iter()
        .map(|&v| (((v as f64 * m / 255.0).round()) * 255.0 / m).round() as u8)
        .collect();
    assert_eq!(colours, expected);
    // Raw chunk encoding agrees with the hand-built one.
    assert_eq!(
        chunk::encode(b'L', &level_payload(0)).unwrap(),
        chunk_by_hand(b'L', &level_payload(0))
    );
}

#[test]
fn spec_worked_example() {
    // The example file of spec/format.md §Worked example, byte for byte.
    let file: Vec<u8> = [
        "71 63 40 02 02 c0 02 08 15",
        "02 80 40 cf 0c dc 67",
        "74 03 6b 00 76 34 ee 21 25",
        "4c 01 c0 47 5e be 04",
    ]
    .join(" ")
    .split(' ')
    .map(|h| u8::from_str_radix(h, 16).unwrap())
    .collect();
    let header = Header::new(2, 2, Layout::Grey, 3, 2, Coding::Raw { bits: 8 });
    let mut w = ContainerWriter::new(Vec::new(), &header).unwrap();
    w.write_level(&[128, 64]).unwrap();
    w.write_text("k", "v").unwrap();
    w.write_level(&[192]).unwrap();
    assert_eq!(w.finish().unwrap(), file);
    let (p, _, r) = parse_all(&file, Default::default());
    r.unwrap();
    assert!(p.is_complete());
    let pr = parse_all(&file[..11], Default::default()).0.progress();
    assert_eq!((pr.samples_verified, pr.samples_available), (0, 1));
    let pr = parse_all(&file[..16], Default::default()).0.progress();
    assert_eq!((pr.samples_verified, pr.samples_available), (2, 2));
    // §Codings raw example: B = 5, RGB (10, 128, 255) → 0C 3E.
    assert_eq!(raw::pack(&[10, 128, 255], 5).unwrap(), [0x0C, 0x3E]);
    // §Conventions CRC check value and varint examples.
    assert_eq!(crc32fast::hash(b"123456789"), 0xCBF4_3926);
    for (v, bytes) in [
        (0u64, &[0u8][..]),
        (127, &[0x7F]),
        (128, &[0x80, 0x01]),
        (300, &[0xAC, 0x02]),
        (65536, &[0x80, 0x80, 0x04]),
    ] {
        let mut out = Vec::new();
        varint::write_u64(&mut out, v);
        assert_eq!(out, bytes);
    }
}

// ---------------------------------------------------------------------------------------------
// RawDecoder: bytes → colours
// ---------------------------------------------------------------------------------------------

fn expected_colours() -> Vec<u8> {
    sample_values()
        .iter()
        .map(|&v| raw::dequantise(raw::quantise(v, B), B))
        .collect()
}

#[test]
fn raw_decoder_every_prefix_and_byte_at_a_time() {
    let (file, _) = test_file();
    let all = expected_colours();
    let mut streaming = RawDecoder::new(Default::default());
    for cut in 0..=file.len() {
        let mut d = RawDecoder::new(Default::default());
        d.push(&file[..cut]).unwrap();
        let p = d.parser().progress();
        assert_eq!(d.samples_available(), p.samples_available, "cut {cut}");
        assert_eq!(d.samples_verified(), p.samples_verified, "cut {cut}");
        assert_eq!(d.colours(), &all[..d.colours().len()], "cut {cut}");
        if cut > 0 {
            streaming.push(&file[cut - 1..cut]).unwrap();
        }
        assert_eq!(streaming.colours(), d.colours(), "cut {cut}");
    }
    assert_eq!(streaming.colours(), all);
    assert_eq!(streaming.metadata().len(), 2);
    assert_eq!(streaming.end_state(), EndState::Complete);

    let h = Header::new(2, 2, Layout::Grey, 4, 2, Coding::Predictive { step: 7 });
    let mut d = RawDecoder::new(Default::default());
    let r = d.push(&h.encode().unwrap());
    assert!(matches!(
        r,
        Err(Error::Format(FormatError::UnsupportedCoding { coding: 1 }))
    ));
    assert!(d.push(&[]).is_err());
}

#[test]
fn recovery_after_any_bit_flip_keeps_only_true_samples() {
    // With recovery on, whatever bit is flipped after the header, the verified samples are
    // exactly the original ones, and whole levels.
    let (file, chunks) = test_file();
    let all = expected_colours();
    let hlen = header_bytes_by_hand().len();
    let level_ends = [0u64, 2, 4, 7];
    for byte in hlen..file.len() {
        for bit in 0..8 {
            let mut bad = file.clone();
            bad[byte] ^= 1 << bit;
            let mut d = RawDecoder::new(ParserOptions {
                recover: true,
                ..Default::default()
            });
            let r = d.push(&bad);
            let what = format!("byte {byte} bit {bit}");
            match r {
                Ok(()) => {}
                Err(Error::Limits(_)) => {}
                Err(e) => panic!("{what}: {e}"),
            }
            let v = d.samples_verified();
            assert!(level_ends.contains(&v), "{what}: {v}");
            assert_eq!(
                &d.colours()[..v as usize * CH],
                &all[..v as usize * CH],
                "{what}"
            );
            // A flip inside a level chunk loses that level and everything after it.
            let i = chunks.iter().rposition(|c| c.1 <= byte).unwrap();
            let levels_before = chunks[..i].iter().filter(|c| c.0 == b'L').count();
            if chunks[i].0 == b'L' {
                assert_eq!(v, level_ends[levels_before], "{what}");
                assert_eq!(d.end_state(), EndState::Stopped, "{what}");
                assert_eq!(d.samples_available(), v, "{what}");
            } else {
                assert!(v >= level_ends[levels_before], "{what}");
            }
        }
    }
}

#[test]
fn inspection_display() {
    let (file, chunks) = test_file();
    let text = inspect(&file).to_string();
    assert!(
        text.contains("header: 9 bytes, 5×4, Rgb (3 channels), 7 samples, first level 2, 3 levels"),
        "{text}"
    );
    assert!(
        text.contains(&format!(
            "level 2: samples 4..7, chunk #4 at byte {}, 6 payload bytes, CRC ok",
            chunks[4].1
        )),
        "{text}"
    );
    assert!(text.contains("text: Title = quasi"), "{text}");
    assert!(
        text.contains("samples: 7 verified, 7 available; end: Complete"),
        "{text}"
    );
    let text = inspect(&file[..chunks[2].1 + 4]).to_string();
    assert!(text.contains("truncated (unverified)"), "{text}");
    assert!(text.contains("level 2: samples 4..7, missing"), "{text}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Arbitrary damage (byte changes, insertions, deletions) never panics, and the outcome does not
    /// depend on how the bytes are split.
    #[test]
    fn damaged_files_never_panic(
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 1..6),
        split in any::<prop::sample::Index>(),
    ) {
        let (mut file, _) = test_file();
        for (at, b, op) in edits {
            let i = at.index(file.len());
            match op {
                0 => file[i] = b,
                1 => file.insert(i, b),
                _ => { file.remove(i); }
            }
        }
        for recover in [false, true] {
            let opts = ParserOptions {
                recover,
                ..Default::default()
            };
            let (p1, ev1, r1) = parse_all(&file, opts.clone());
            let cut = split.index(file.len() + 1);
            let mut p2 = Parser::new(opts);
            let mut ev2 = Vec::new();
            let r2 = p2.push(&file[..cut], &mut ev2).and_then(|_| p2.push(&file[cut..], &mut ev2));
            prop_assert_eq!(r1.is_ok(), r2.is_ok());
            prop_assert_eq!(normalise(ev1), normalise(ev2));
            // After an error the byte count is unspecified; everything else must agree.
            let (mut a, mut b) = (p1.progress(), p2.progress());
            if r1.is_err() {
                a.bytes_consumed = 0;
                b.bytes_consumed = 0;
            }
            prop_assert_eq!(a, b);
            prop_assert_eq!(p1.end_state(), p2.end_state());
            let _ = inspect(&file).to_string();
        }
    }
}

/// Throughput figures for the report: `cargo test --release --test suite container:: -- --ignored --nocapture`.
#[test]
#[ignore]
fn throughput() {
    let n = 1u64 << 20;
    let header = Header::new(1024, 1024, Layout::Rgb, n, 256, Coding::Raw { bits: 6 });
    let values: Vec<u8> = (0..n * 3).map(|i| (i * 7 % 251) as u8).collect();
    let t = std::time::Instant::now();
    let mut w = ContainerWriter::new(Vec::new(), &header).unwrap();
    for k in 0..header.level_count() {
        let r = header.level_range(k).unwrap();
        w.write_level(&raw::pack(&values[r.start as usize * 3..r.end as usize * 3], 6).unwrap())
            .unwrap();
    }
    let file = w.finish().unwrap();
    let enc = t.elapsed();
    let t = std::time::Instant::now();
    let mut d = RawDecoder::new(Default::default());
    d.push(&file).unwrap();
    let dec = t.elapsed();
    assert_eq!(d.samples_verified(), n);
    let t = std::time::Instant::now();
    let mut d = RawDecoder::new(Default::default());
    for c in file.chunks(1500) {
        d.push(c).unwrap();
    }
    let dec_chunked = t.elapsed();
    let mb = file.len() as f64 / 1e6;
    println!(
        "{} samples, {:.2} MB: pack+write {:.1} MB/s, decode whole {:.1} MB/s, decode in 1500-byte pushes {:.1} MB/s",
        n,
        mb,
        mb / enc.as_secs_f64(),
        mb / dec.as_secs_f64(),
        mb / dec_chunked.as_secs_f64()
    );
}

#[test]
fn predictive_coding_passes_through() {
    // Coding 1: the step passed through, level lengths free, availability = verified.
    let h = Header::new(4, 4, Layout::Rgba, 3, 2, Coding::Predictive { step: 3 });
    let mut w = ContainerWriter::new(Vec::new(), &h).unwrap();
    w.write_level(&[0xAA; 17]).unwrap();
    w.write_level(&[]).unwrap();
    let file = w.finish().unwrap();
    let (p, ev, r) = parse_all(&file, Default::default());
    r.unwrap();
    assert!(p.is_complete());
    assert_eq!(ev[0], Event::Header(h));
    assert!(ev.iter().any(|e| matches!(
        e,
        Event::LevelStart {
            level: 1,
            payload_len: 0,
            ..
        }
    )));
    let (p, _, _) = parse_all(&file[..file.len() - 12], Default::default());
    let pr = p.progress();
    assert_eq!((pr.samples_verified, pr.samples_available), (0, 0));
}
