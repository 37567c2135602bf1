//! Robustness: hostile header claims, every single-bit flip and every truncation of the
//! conformance set (`spec/vectors/*.qcs`), recovery, and a replay of the fuzz regressions.
//!
//! The expectations here come from an independent walk of the chunk structure
//! (spec/format.md §Chunks), not from the library's parser.

use qcs::container::{chunk, ChunkRef, Coding, FormatError, Header, Layout, Parser, ParserOptions};
use qcs::{DecodeOptions, Error, Limits, Method, StreamDecoder};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn vectors() -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<_> = std::fs::read_dir(root().join("spec/vectors"))
        .expect("spec/vectors")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "qcs"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).expect("read vector"))
        })
        .collect();
    out.sort();
    assert!(out.len() >= 5, "the conformance set is missing");
    out
}

// ---------------------------------------------------------------------------------------------
// An independent reading of the chunk structure.

/// One chunk as laid out in the bytes: where its tag, payload and CRC are.
#[derive(Clone, Debug)]
struct Span {
    chunk: ChunkRef,
    payload: std::ops::Range<usize>,
    /// One past its CRC.
    end: usize,
}

fn leb128(bytes: &[u8], mut at: usize) -> (u64, usize) {
    let (mut v, mut shift) = (0u64, 0);
    loop {
        let b = bytes[at];
        v |= ((b & 0x7F) as u64) << shift;
        at += 1;
        shift += 7;
        if b & 0x80 == 0 {
            return (v, at);
        }
    }
}

fn chunks(file: &[u8], header_len: usize) -> Vec<Span> {
    let mut out = Vec::new();
    let mut at = header_len;
    while at < file.len() {
        // Level 0 comes first, without a tag.
        let first = out.is_empty();
        let (len, p) = leb128(file, at + !first as usize);
        let end = p + len as usize + 4;
        out.push(Span {
            chunk: ChunkRef {
                index: out.len() as u32,
                tag: if first { b'L' } else { file[at] },
                offset: at as u64,
            },
            payload: p..p + len as usize,
            end,
        });
        at = end;
    }
    assert_eq!(at, file.len(), "chunks tile the file");
    out
}

/// Samples (verified, available) in a prefix of `cut` bytes, by spec/format.md §Truncation.
/// For the predictive coding the complete samples of a partial level depend on the range
/// coder, so only their range is known: `available` is then an upper bound (≥ verified).
fn expected_counts(h: &Header, spans: &[Span], cut: usize) -> (u64, u64) {
    let sample_bits = match h.coding {
        Coding::Raw { bits } => h.layout.channels() as u64 * bits as u64,
        _ => 0,
    };
    let (mut verified, mut level) = (0, 0);
    for s in spans.iter().filter(|s| s.chunk.tag == b'L') {
        let range = h.level_range(level).expect("level");
        level += 1;
        if cut >= s.end {
            verified = range.end;
            continue;
        }
        let got = cut.saturating_sub(s.payload.start).min(s.payload.len()) as u64;
        let complete = match sample_bits {
            0 => range.end - range.start,
            b => (got * 8 / b).min(range.end - range.start),
        };
        return (verified, verified + complete);
    }
    (verified, verified)
}

fn small(limits: Limits) -> DecodeOptions {
    DecodeOptions {
        size: Some((12, 10)),
        method: Method::Shepard,
        limits,
        ..Default::default()
    }
}

// ---------------------------------------------------------------------------------------------
// Truncation and corruption of the conformance set.

#[test]
fn truncation_at_every_byte() {
    for (name, file) in vectors() {
        let (h, header_len) = Header::parse(&file).expect("vector header");
        let spans = chunks(&file, header_len);
        // The picture is final at the end of the last level or layer (spec/format.md, rule 2):
        // ancillary chunks may follow (an Exif chunk does).
        let last = spans.iter().filter(|s| !chunk::is_ancillary(s.chunk.tag));
        let complete = last.map(|s| s.end).max().expect("level 0");
        let mut stream = StreamDecoder::new(Limits::default());
        for cut in 0..=file.len() {
            let r = qcs::decode(&file[..cut], &small(Limits::default()));
            if cut < header_len {
                assert!(
                    matches!(r, Err(Error::NeedMoreData)),
                    "{name} @{cut}: {r:?}"
                );
            } else {
                let d = r.unwrap_or_else(|e| panic!("{name} @{cut}: {e}"));
                assert_eq!((d.image.width(), d.image.height()), (12, 10));
                let (verified, available) = expected_counts(&h, &spans, cut);
                let exact = matches!(h.coding, Coding::Raw { .. });
                assert_eq!(d.samples_verified, verified, "{name} @{cut}");
                if exact {
                    assert_eq!(d.samples_used, available, "{name} @{cut}");
                } else {
                    assert!(
                        d.samples_used >= verified && d.samples_used <= available,
                        "{name} @{cut}"
                    );
                }
                assert_eq!(d.is_final, cut >= complete, "{name} @{cut}");
            }
            // The push decoder, fed byte by byte, agrees with the one-shot decode.
            if cut > 0 {
                stream.push(&file[cut - 1..cut]).expect("push");
            }
            if cut >= header_len {
                let (verified, available) = expected_counts(&h, &spans, cut);
                assert_eq!(stream.samples_verified(), verified, "{name} stream @{cut}");
                if matches!(h.coding, Coding::Raw { .. }) {
                    assert_eq!(
                        stream.samples_available(),
                        available,
                        "{name} stream @{cut}"
                    );
                } else {
                    assert!(
                        stream.samples_available() <= available,
                        "{name} stream @{cut}"
                    );
                }
            } else {
                assert!(stream.header().is_none());
                assert!(matches!(
                    stream.render(Method::Gouraud, 4, 4),
                    Err(Error::NeedMoreData)
                ));
            }
        }
        assert!(stream.is_complete());
        assert!(stream
            .render(Method::Gouraud, 5, 3)
            .expect("render")
            .is_final());
    }
}

/// What a strict decode of a file with bit `bit` of byte `at` flipped may give.
fn check_flip(name: &str, file: &[u8], header_len: usize, spans: &[Span], at: usize, bit: u8) {
    let mut bad = file.to_vec();
    bad[at] ^= 1 << bit;
    let h = Header::parse(file).expect("header").0;
    let ctx = format!("{name}: bit {bit} of byte {at}");
    match qcs::decode(&bad, &small(Limits::default())) {
        Ok(d) => {
            // Undetected: only possible where the flip turns the file into a valid prefix of
            // another file (e.g. a longer last metadata chunk); the picture is still whole.
            assert_eq!((d.image.width(), d.image.height()), (12, 10), "{ctx}");
            if at < header_len {
                // A flip that moves where the header ends escapes the check byte once in 256
                // times; then level 0's CRC, over the header as read, is never matched, so
                // nothing is verified and the picture is not final.
                let old = Header::parse(file).map(|(_, l)| l).ok();
                let new = Header::parse(&bad).map(|(_, l)| l).ok();
                assert_ne!(old, new, "{ctx}: header flip undetected");
                assert!(!d.is_final && d.samples_verified == 0, "{ctx}");
            }
        }
        Err(Error::NeedMoreData) => {
            // A flip that lengthens the header (a varint continuation, an explicit N):
            // the file now ends inside a longer header.
            assert!(at < header_len, "{ctx}");
        }
        Err(Error::Format(e)) if at < header_len => {
            assert_eq!(e.chunk(), None, "{ctx}: {e}");
        }
        Err(Error::Format(e)) => {
            let span = spans
                .iter()
                .find(|s| (s.chunk.offset as usize..s.end).contains(&at))
                .expect("flip inside a chunk");
            let chunk = e
                .chunk()
                .unwrap_or_else(|| panic!("{ctx}: {e} names no chunk"));
            assert_eq!(chunk.offset, span.chunk.offset, "{ctx}: {e}");
            assert_eq!(chunk.index, span.chunk.index, "{ctx}: {e}");
            if at >= span.payload.start {
                // Payload and CRC bytes are covered by the CRC only, but for a refinement
                // layer's header and segment table, whose fields are checked as they arrive.
                match e {
                    FormatError::ChunkCrc { chunk, .. } | FormatError::BadText { chunk, .. } => {
                        assert_eq!(chunk, span.chunk, "{ctx}")
                    }
                    FormatError::BadRefinement { chunk, .. }
                    | FormatError::RefinementVarint { chunk, .. }
                    | FormatError::SegmentLengths { chunk, .. }
                        if span.chunk.tag == b'R' =>
                    {
                        assert_eq!(chunk, span.chunk, "{ctx}")
                    }
                    other => panic!("{ctx}: {other}"),
                }
            }
            // Recovery keeps exactly the levels before the damaged chunk.
            let mut opts = small(Limits::default());
            opts.recover = true;
            let d = qcs::decode(&bad, &opts).unwrap_or_else(|e| panic!("{ctx}: recover: {e}"));
            let (verified, _) = expected_counts(&h, spans, span.chunk.offset as usize);
            assert_eq!(d.samples_verified, verified, "{ctx}");
            assert_eq!(d.samples_used, verified, "{ctx}: unverified samples kept");
            assert!(!d.is_final || span.chunk.tag != b'L', "{ctx}");
        }
        Err(other) => panic!("{ctx}: {other}"),
    }
}

#[test]
fn every_single_bit_flip_is_caught_or_harmless() {
    for (name, file) in vectors() {
        let (_, header_len) = Header::parse(&file).expect("vector header");
        let spans = chunks(&file, header_len);
        for at in 0..file.len() {
            for bit in 0..8 {
                check_flip(&name, &file, header_len, &spans, at, bit);
            }
        }
    }
}

#[test]
fn payload_flip_names_chunk_and_offset() {
    let (_, file) = vectors().into_iter().next().expect("a vector");
    let (h, header_len) = Header::parse(&file).expect("header");
    let spans = chunks(&file, header_len);
    let level1 = spans
        .iter()
        .filter(|s| s.chunk.tag == b'L')
        .nth(1)
        .expect("level 1");
    let mut bad = file.clone();
    bad[level1.payload.start] ^= 0x10;
    let e = qcs::decode(&bad, &Default::default()).expect_err("CRC catches it");
    // The error says what kind it is; its source, the format error, says what and where.
    assert_eq!(e.to_string(), "malformed file");
    let msg = std::error::Error::source(&e)
        .expect("the format error")
        .to_string();
    assert!(
        msg.contains(&format!(
            "chunk #{} 'L' at byte {}",
            level1.chunk.index, level1.chunk.offset
        )) && msg.contains("CRC mismatch"),
        "{msg}"
    );
    // Recovery: the longest verified prefix is level 0.
    let d = qcs::decode(
        &bad,
        &DecodeOptions {
            recover: true,
            ..Default::default()
        },
    )
    .expect("recovered");
    assert_eq!(d.samples_verified, h.level_range(0).unwrap().end);
    assert_eq!(d.samples_used, d.samples_verified);
    assert_eq!(d.levels_complete, 1);
    let mut s = StreamDecoder::with_options(ParserOptions {
        recover: true,
        ..Default::default()
    });
    s.push(&bad).expect("recovering push");
    assert!(
        matches!(s.stopped(), Some(FormatError::ChunkCrc { chunk, .. }) if chunk == &level1.chunk)
    );
}

// ---------------------------------------------------------------------------------------------
// Hostile header claims: errors at once, or cost that follows the bytes given.

/// A header's bytes with its check byte, from fields the type cannot hold (hand-written
/// varints): `qc`, format byte 0x40 (version 2, raw, grey), `fields`, CRC-8.
fn raw_header(fields: &[u8]) -> Vec<u8> {
    let mut h = b"qc\x40".to_vec();
    h.extend_from_slice(fields);
    h.push(qcs::container::header_check(&h));
    h
}

#[test]
fn header_claiming_2_pow_32_pixels_a_side_is_a_format_error() {
    // W = H = 2^32: the varint u32 overflows (5th byte 0x10).
    let w = [0x80, 0x80, 0x80, 0x80, 0x10];
    let mut f = w.to_vec();
    f.extend_from_slice(&w);
    f.extend_from_slice(&[0x20, 1, 8]);
    let bytes = raw_header(&f);
    let e = qcs::decode(&bytes, &Default::default()).expect_err("rejected");
    assert!(
        matches!(
            e,
            Error::Format(FormatError::HeaderVarint {
                field: "width",
                offset: 3,
                ..
            })
        ),
        "{e}"
    );
}

#[test]
fn header_claiming_huge_images_or_sample_counts_fails_at_once() {
    // 2^32 − 1 square, 2^40 samples, raw: the last level's payload cannot fit a chunk.
    let h = Header::new(
        u32::MAX,
        u32::MAX,
        Layout::Grey,
        1 << 40,
        1,
        Coding::Raw { bits: 1 },
    );
    assert!(h.validate().is_err());
    // The same with the predictive coding is format-valid; the limits reject it.
    let h = Header::new(
        u32::MAX,
        u32::MAX,
        Layout::Rgb,
        1 << 40,
        1,
        Coding::Predictive { step: 1 },
    );
    let bytes = h.encode().expect("format-valid");
    for limits in [Limits::default(), Limits::none()] {
        let e = qcs::decode(&bytes, &small(limits)).expect_err("rejected");
        assert!(matches!(e, Error::Limits(_)), "{e}");
    }
    // Within the default dimension limit but over the sample limit.
    let h = Header::new(
        30000,
        30000,
        Layout::Rgb,
        1 << 28,
        8,
        Coding::Raw { bits: 8 },
    );
    let e = qcs::decode(&h.encode().unwrap(), &Default::default()).expect_err("rejected");
    assert!(
        matches!(
            e,
            Error::Limits(qcs::limits::LimitError::ImagePixels { .. })
        ),
        "{e}"
    );
    // More samples than pixels.
    let h = Header::new(10, 10, Layout::Grey, 101, 8, Coding::Raw { bits: 8 });
    let e = qcs::decode(&h.encode().unwrap(), &Default::default()).expect_err("rejected");
    assert!(
        matches!(e, Error::Format(FormatError::TooManySamples { .. })),
        "{e}"
    );
    // A frame the site construction cannot use (root length 0.5 px) is a format error too.
    let mut h = Header::new(10, 10, Layout::Grey, 50, 8, Coding::Raw { bits: 8 });
    h.lattice = Some(qcs::container::LatticeFields {
        root_length: 0x8000,
        origin_x: 0,
        origin_y: 0,
    });
    let bytes = h.encode().unwrap();
    let e = qcs::decode(&bytes, &Default::default()).expect_err("rejected");
    match e {
        Error::Format(FormatError::InvalidField {
            field,
            offset,
            value,
            ..
        }) => {
            assert_eq!((field, value), ("lattice root length", 0x8000));
            assert_eq!(
                offset as usize,
                bytes.len() - 1 - 1 - 1 - 3,
                "root at its byte"
            );
        }
        other => panic!("{other}"),
    }
}

#[test]
fn a_frame_error_is_at_the_field_the_file_has_it() {
    // The header of the test above (10×10 grey, N = 50, L0 = 8, raw B = 8, root 0.5 px) in
    // another valid form: N written out after a density byte 0, where the density byte 128
    // would give it. The root length is at byte 9, one later than in the encoder's form.
    let mut bytes = b"qc\x50".to_vec(); // version 2, lattice fields, raw, grey
    bytes.extend_from_slice(&[10, 10, 0, 50, 8, 8]); // W, H, d = 0, N, L0, B
    bytes.extend_from_slice(&[0x80, 0x80, 0x02, 0, 0]); // root 0x8000, origin (0, 0)
    bytes.push(qcs::container::header_check(&bytes));
    assert_eq!(Header::parse(&bytes).map(|(h, _)| h.total_samples), Ok(50));
    let e = qcs::decode(&bytes, &Default::default()).expect_err("rejected");
    assert!(
        matches!(
            e,
            Error::Format(FormatError::InvalidField {
                field: "lattice root length",
                offset: 9,
                value: 0x8000,
                ..
            })
        ),
        "{e}"
    );
}

/// The largest file the format and raised limits allow: 65535², as many samples as pixels
/// (≈ 2^32) at 1 bit. Only
/// level 0 (8 samples) is given; decoding must cost what those bytes cost.
fn giant_claim() -> Vec<u8> {
    let h = Header::new(
        65535,
        65535,
        Layout::Grey,
        65535 * 65535,
        8,
        Coding::Raw { bits: 1 },
    );
    let mut file = h.encode().expect("valid header");
    file.extend(qcs::container::chunk::encode_first(&file, &[0b1010_1010]).expect("level 0"));
    file
}

fn raised() -> Limits {
    let mut l = Limits::none();
    l.max_output_pixels = 64 * 64;
    l
}

#[test]
fn giant_claims_cost_what_the_bytes_cost() {
    let file = giant_claim();
    let t = std::time::Instant::now();
    let d = qcs::decode(&file, &small(raised())).expect("a picture from level 0");
    assert_eq!(
        (d.samples_used, d.samples_verified, d.levels_complete),
        (8, 8, 1)
    );
    assert!(!d.is_final);
    let mut s = StreamDecoder::new(raised());
    for b in &file {
        s.push(std::slice::from_ref(b)).expect("push");
    }
    let p = s.render(Method::Gouraud, 64, 64).expect("render");
    assert_eq!(p.decoded().samples_used, 8);
    // Output size is checked before allocating: over the limit, and beyond memory with none.
    assert!(matches!(
        s.render(Method::Gouraud, 65, 64),
        Err(Error::Limits(_))
    ));
    let mut s = StreamDecoder::new(Limits::none());
    s.push(&file).expect("push");
    assert!(matches!(
        s.render(Method::Gouraud, u32::MAX, u32::MAX),
        Err(Error::OutOfMemory { bytes }) if bytes > isize::MAX as u64
    ));
    assert!(t.elapsed().as_secs_f64() < 5.0, "took {:?}", t.elapsed());
    // The default limits reject the claim at the header.
    assert!(matches!(
        qcs::decode(&file, &Default::default()),
        Err(Error::Limits(_))
    ));
    // The parser alone: the header event, then level 0, nothing sized by N.
    let mut p = Parser::new(ParserOptions {
        limits: Limits::none(),
        ..Default::default()
    });
    let mut ev = Vec::new();
    p.push(&file, &mut ev).expect("parse");
    assert_eq!(p.progress().samples_verified, 8);
}

const CHILD: &str = "QCS_ROBUSTNESS_MEMORY_CHILD";

/// Peak resident memory of this process, in KiB (Linux).
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Run in a child process (so that other tests do not count): decodes the giant claims.
#[test]
#[ignore = "run by giant_claims_use_bounded_memory in a child process"]
fn memory_child() {
    if std::env::var_os(CHILD).is_none() {
        return;
    }
    let before = peak_rss_kib().unwrap_or(0);
    let file = giant_claim();
    for _ in 0..3 {
        let d = qcs::decode(&file, &small(raised())).expect("picture");
        assert_eq!(d.samples_used, 8);
        let mut s = StreamDecoder::new(raised());
        s.push(&file[..file.len() / 2]).expect("push");
        s.push(&file[file.len() / 2..]).expect("push");
        s.render(Method::Natural, 64, 64).expect("render");
    }
    println!("PEAK_RSS_KIB {before} {}", peak_rss_kib().unwrap_or(0));
}

/// Runs test `name` of this binary in a child process with `env` set, and returns the
/// `PEAK_RSS_KIB before after` it prints.
fn child_peak_kib(name: &str, env: (&str, &str)) -> (u64, u64) {
    // Its name in this binary: `name`, or `MODULE::name` in tests/suite.rs.
    let name = match module_path!().split_once("::") {
        Some((_, module)) => format!("{module}::{name}"),
        None => name.to_string(),
    };
    let out = std::process::Command::new(std::env::current_exe().expect("test binary"))
        .args([
            "--exact",
            &name,
            "--include-ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(env.0, env.1)
        .output()
        .expect("run child");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "child failed: {text}");
    let line = text
        .lines()
        .find_map(|l| l.split("PEAK_RSS_KIB").nth(1))
        .expect("child report");
    let v: Vec<u64> = line
        .split_whitespace()
        .map(|x| x.parse().expect("KiB"))
        .collect();
    (v[0], v[1])
}

#[test]
fn giant_claims_use_bounded_memory() {
    if peak_rss_kib().is_none() {
        eprintln!("no /proc/self/status: skipped");
        return;
    }
    let (before, after) = child_peak_kib("memory_child", (CHILD, "1"));
    let grown = after.saturating_sub(before);
    eprintln!("peak RSS {before} KiB before, {after} KiB after (+{grown} KiB)");
    // A claim-sized allocation would be ≥ 2^32 samples: gigabytes. Allow 64 MiB.
    assert!(
        grown < 64 * 1024,
        "decoding a giant claim grew the peak RSS by {grown} KiB"
    );
}

/// The decoder's memory account (`Limits::max_alloc`) of a whole decode of `file` at its own
/// size, as the limit's documentation states it.
fn account(file: &[u8]) -> u64 {
    let (h, _) = Header::parse(file).expect("header");
    let c = h.layout.channels() as u64;
    let pixels = h.width as u64 * h.height as u64;
    let coefficients = if h.refinement { pixels * c } else { 0 };
    h.total_samples * 512 + coefficients * 8 + pixels * c * 2
}

/// Three photograph-like files of 640 × 480: the default encode, lossless, levels only.
fn account_files() -> Vec<Vec<u8>> {
    let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(640, 480, |x, y| {
        let v = (x * 7 + y * 13) ^ (x * y / 5);
        image::Rgb([v as u8, (v >> 3) as u8 ^ x as u8, (x + y) as u8])
    }));
    [
        qcs::EncodeOptions::default(),
        qcs::EncodeOptions {
            target: qcs::Target::Lossless,
            ..Default::default()
        },
        qcs::EncodeOptions {
            target: qcs::Target::LevelsOnly,
            ..Default::default()
        },
    ]
    .iter()
    .map(|o| qcs::encode(&img, o).expect("encode"))
    .collect()
}

const ACCOUNT_CHILD: &str = "QCS_ROBUSTNESS_ACCOUNT_CHILD";

/// Run in a child process: decodes file `i` of [`account_files`] (made before measuring).
#[test]
#[ignore = "run by decodes_stay_within_their_memory_account in a child process"]
fn account_child() {
    let Some(i) = std::env::var(ACCOUNT_CHILD).ok() else {
        return;
    };
    let file = account_files().swap_remove(i.parse().expect("index"));
    // The encoder's peak is past: measure the decode alone from a fresh high-water mark.
    std::fs::write("/proc/self/clear_refs", "5").expect("reset the peak");
    let fresh = peak_rss_kib().unwrap_or(0);
    let d = qcs::decode(&file, &DecodeOptions::default()).expect("decode");
    assert!(d.is_final);
    println!("PEAK_RSS_KIB {fresh} {}", peak_rss_kib().unwrap_or(0));
}

/// A whole decode holds less than the decoder's account of it, and a limit below the account
/// refuses the file before allocating.
#[test]
fn decodes_stay_within_their_memory_account() {
    let files = account_files();
    for (i, file) in files.iter().enumerate() {
        let account = account(file);
        let within = |max_alloc| DecodeOptions {
            limits: Limits {
                max_alloc,
                ..Default::default()
            },
            ..Default::default()
        };
        assert!(qcs::decode(file, &within(account)).is_ok(), "file {i}");
        assert!(
            matches!(
                qcs::decode(file, &within(account - 1)),
                Err(Error::Limits(qcs::limits::LimitError::Alloc { value, .. })) if value == account
            ),
            "file {i}"
        );
        if peak_rss_kib().is_none() || std::fs::metadata("/proc/self/clear_refs").is_err() {
            continue;
        }
        let (fresh, after) = child_peak_kib("account_child", (ACCOUNT_CHILD, &i.to_string()));
        let grown = after.saturating_sub(fresh) * 1024;
        eprintln!("file {i}: decode grew the peak RSS by {grown} bytes; account {account}");
        assert!(
            grown <= account,
            "file {i}: {grown} bytes > account {account}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Fuzz corpus replay: every committed regression through the same harness as the fuzzer.

fn harness(target: &str) -> Option<fn(&[u8])> {
    Some(match target {
        "decode" => |d| {
            qcs_fuzz_harness::decode(d);
        },
        "push" => qcs_fuzz_harness::push,
        "header" => qcs_fuzz_harness::header,
        "roundtrip" => qcs_fuzz_harness::roundtrip,
        _ => return None,
    })
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect()
        })
        .unwrap_or_default();
    v.retain(|p| {
        !p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'))
    });
    v.sort();
    v
}

#[test]
fn replay_fuzz_regressions() {
    let fuzz = root().join("fuzz");
    let mut n = 0;
    for target in ["decode", "push", "header", "roundtrip"] {
        let run = harness(target).expect("known target");
        // The committed regressions only: what the fuzzer leaves in fuzz/artifacts/ is local,
        // unchecked and not yet fixed (fuzz/README.md says how an input becomes a regression).
        for path in files_in(&fuzz.join("corpus").join(target).join("regressions")) {
            let data = std::fs::read(&path).expect("read");
            let r = std::panic::catch_unwind(|| run(&data));
            assert!(r.is_ok(), "{target}: {} fails", path.display());
            n += 1;
        }
    }
    eprintln!("replayed {n} regression inputs");
}

#[test]
fn vectors_through_every_harness() {
    for (_, file) in vectors() {
        // The harnesses take control bytes first (see qcs_fuzz_harness): the last two also decode
        // with recovery (0x40 in the second byte) and on two threads (0x20 in the third).
        for ctl in [
            &[16u8, 12, 0][..],
            &[63, 1, 0x81],
            &[5, 40, 2],
            &[16, 0x4C, 0x20],
            &[9, 0x47, 0x61],
        ] {
            let mut d = ctl.to_vec();
            d.extend_from_slice(&file);
            let pic = qcs_fuzz_harness::decode(&d).expect("vector decodes");
            assert!(pic.is_final || ctl[2] & 0x80 != 0);
        }
        for seed in [
            *b"abcd",
            *b"\0\0\0\0",
            *b"zzzz",
            *b"pull",
            *b"thmb",
            *b"1234",
        ] {
            let mut d = seed.to_vec();
            d.extend_from_slice(&file);
            qcs_fuzz_harness::push(&d);
            // Damaged: the push and pull decoders must agree on it.
            for at in [file.len() / 3, file.len() - 3] {
                d[4 + at] ^= 0x24;
                qcs_fuzz_harness::push(&d);
                d[4 + at] ^= 0x24;
            }
        }
        qcs_fuzz_harness::header(&file);
    }
    for ctl in [
        [0u8; 8],
        [7, 5, 2, 4, 48, 3, 3, 0],
        [23, 23, 3, 0, 255, 15, 1, 9],
        [23, 19, 2, 8, 0, 0x80, 3, 0], // the encoder's N and L0: the header's defaults bit
        // With a refinement: lossless, quality 75 and 20, a size of 400 bytes.
        [23, 19, 3, 0x47, 20, 3, 4, 0],
        [9, 13, 0, 0x85, 75, 1, 0, 0],
        [16, 16, 2, 0x81, 20, 0x80, 1, 0],
        [23, 23, 3, 0xC6, 100, 2, 2, 0],
    ] {
        let mut d = ctl.to_vec();
        d.extend_from_slice(b"some pixels \x00\xff\x80");
        qcs_fuzz_harness::roundtrip(&d);
        qcs_fuzz_harness::roundtrip(&ctl); // constant (zero) pixels
    }
}
