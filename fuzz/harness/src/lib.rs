//! The fuzz targets' bodies, shared by the cargo-fuzz targets in `fuzz/` and by the replay
//! test (`tests/robustness.rs`), so that a crash input found by the fuzzer is checked by plain
//! `cargo test` through exactly the same code.
//!
//! Every function takes arbitrary bytes. It returns normally when the library behaved (an
//! error result is fine: it is how a decoder rejects a bad file) and **panics** when an
//! invariant of the library is broken: that panic is what the fuzzer reports. Limits are tight
//! ([`limits`]) so that one input costs milliseconds.
//!
//! It reaches into the codec's stages (the `internals` feature of `qcs`) to cross-check the
//! decoders against each other. Not a stable API: it changes with the fuzz targets.

use qcs::coding::raw;
use qcs::container::{self, Coding, Header, Layout, Parser, ParserOptions};
use qcs::sampling::{SampleColour, SourceImage};
use qcs::sites::{Frame, Quasicrystal};
use qcs::{Cadence, DecodeOptions, EncodeOptions, Error, Limits, Method, Previews, Target};
use qcs::{Picture, RawDecoder, StreamDecoder};

/// The limits every harness decodes with: small images, few samples, little metadata.
///
/// At most 2^10 samples and 2^16 pixels, so that one input costs well under a millisecond and
/// a run reaches 10^7 executions: every code path is reached by files this small (the
/// round trip encodes at most 24×24 pixels, 576 samples), and larger ones only repeat the same
/// loops longer. Under `cfg(fuzzing)` `spade` also checks its bulk-load hull after every
/// vertex, which is quadratic (a 6318-sample file took 9 s in the decode target and 10 ms in
/// a normal build).
pub fn limits() -> Limits {
    Limits {
        max_dimension: 4096,
        max_image_pixels: 1 << 16,
        max_output_pixels: 64 * 64,
        max_samples: 1 << 10,
        max_metadata_bytes: 1 << 12,
        // Never reached within the others (at most about 3 MB).
        max_alloc: 1 << 24,
    }
}

/// The samples of the levels that start before sample `k`: at most what a decoder capped at
/// `k` samples holds (all of them when `k` is in the last level).
fn samples_of_levels_before(h: &Header, k: u64) -> u64 {
    (0..h.level_count())
        .map_while(|l| h.level_range(l))
        .take_while(|r| r.start < k)
        .last()
        .map_or(0, |r| r.end)
}

/// Runs `f` on one thread (`threads == 1`: this one, as the only worker of its own pool, so
/// rayon's parallel loops run inline without a handoff, which costs a small input more than its
/// decode) or on a pool of two.
fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    use rayon::{ThreadPool, ThreadPoolBuilder};
    thread_local! {
        static HERE: Option<ThreadPool> =
            ThreadPoolBuilder::new().num_threads(1).use_current_thread().build().ok();
    }
    static TWO: std::sync::OnceLock<Option<ThreadPool>> = std::sync::OnceLock::new();
    if threads > 1 {
        let two = TWO.get_or_init(|| ThreadPoolBuilder::new().num_threads(2).build().ok());
        return match two {
            Some(pool) => pool.install(f),
            None => f(),
        };
    }
    HERE.with(|here| match here {
        Some(pool) => pool.install(f),
        None => f(),
    })
}

const METHODS: [Method; 4] = [
    Method::Gouraud,
    Method::Shepard,
    Method::Natural,
    Method::Cubic,
];

/// A small deterministic generator (xorshift64*) driven by fuzzer bytes.
struct Rng(u64);

impl Rng {
    fn new(seed: &[u8]) -> Rng {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        for &b in seed {
            s = (s ^ b as u64).wrapping_mul(0x100_0000_01B3);
        }
        Rng(s | 1)
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
}

/// Splits `n` control bytes off the front of `data` (fewer if `data` is shorter).
fn split(data: &[u8], n: usize) -> (&[u8], &[u8]) {
    data.split_at(n.min(data.len()))
}

fn byte(ctl: &[u8], i: usize) -> u8 {
    ctl.get(i).copied().unwrap_or(0)
}

/// Checks a decoded picture against what the header and the request imply.
fn check_decoded(d: &qcs::DecodedImage, header: &Header, w: u32, h: u32) {
    assert_eq!((d.image.width(), d.image.height()), (w, h), "output size");
    let channels = d.image.color().channel_count();
    assert_eq!(channels, header.layout.channels(), "output layout");
    assert!(d.samples_verified <= d.samples_used, "verified ≤ used");
    assert!(d.samples_used <= header.total_samples, "used ≤ N");
    assert!(d.levels_complete <= header.level_count(), "levels ≤ count");
    if d.is_final {
        assert_eq!(
            d.samples_used, header.total_samples,
            "final uses every sample"
        );
        assert_eq!(d.samples_verified, header.total_samples);
    }
}

/// One-shot decode: control bytes `[w, h, flags]`, then the file.
///
/// Decodes at a fuzzer-chosen size (≤ 64×64), method, sample cap (flag 0x80) and as a
/// thumbnail or not (flag 0x40), strictly and, where that fails or `h`'s byte has bit 0x40,
/// with recovery, and checks:
/// the picture has the size asked for and the header's layout; verified ≤ used ≤ N; recovery
/// never fails where the strict decoder succeeds and agrees with it then; the header seen by
/// the decoder is the one [`Header::parse`] reads; the counts match [`RawDecoder`]'s; a
/// two-thread pool gives the same result as one thread (flag 0x20).
pub fn decode(data: &[u8]) -> Option<qcs::DecodedImage> {
    on_threads(1, || decode_on_one_thread(data))
}

fn decode_on_one_thread(data: &[u8]) -> Option<qcs::DecodedImage> {
    let (ctl, file) = split(data, 3);
    let w = 1 + (byte(ctl, 0) % 64) as u32;
    let h = 1 + (byte(ctl, 1) % 64) as u32;
    let flags = byte(ctl, 2);
    let method = METHODS[(flags % 4) as usize];
    let max_samples = (flags & 0x80 != 0).then_some((flags & 0x1F) as u64);
    let thumbnail = flags & 0x40 != 0;
    let opts = |recover| DecodeOptions {
        method,
        size: Some((w, h)),
        max_samples,
        max_bytes: None,
        thumbnail,
        limits: limits(),
        recover,
    };
    let strict = qcs::decode(file, &opts(false));
    // Recovery where the strict decode fails, and on a good decode when flag 0x40 of the
    // second control byte asks (a second decode doubles an input's cost).
    let recovered =
        (strict.is_err() || byte(ctl, 1) & 0x40 != 0).then(|| qcs::decode(file, &opts(true)));
    // On more than one thread, Gouraud builds the cells beside the colour decoding; on one it
    // does not. Same answer either way (flag 0x20: a thread handoff costs more than a small
    // decode, so only some inputs pay for this check).
    if flags & 0x20 != 0 {
        match (&strict, on_threads(2, || qcs::decode(file, &opts(false)))) {
            (Ok(a), Ok(b)) => {
                assert_eq!(
                    a.samples_used, b.samples_used,
                    "threads change the sample count"
                );
                assert_eq!(a.image, b.image, "threads change the picture");
            }
            (Err(a), Err(b)) => {
                assert_eq!(
                    format!("{a:?}"),
                    format!("{b:?}"),
                    "threads change the error"
                )
            }
            (a, b) => panic!(
                "threads change the outcome: {:?} vs {:?}",
                a.is_ok(),
                b.is_ok()
            ),
        }
    }

    // The samples a decode decodes: its limits apply to those levels only.
    let cap = match thumbnail {
        true => max_samples
            .unwrap_or(u64::MAX)
            .min(16 * w as u64 * h as u64),
        false => max_samples.unwrap_or(u64::MAX),
    };
    let mut raw = RawDecoder::new(ParserOptions {
        limits: limits(),
        recover: false,
        max_samples: Some(cap),
    });
    let raw_result = raw.push(file);

    match (&strict, &recovered) {
        (Ok(a), Some(Ok(b))) => {
            assert_eq!(
                a.samples_used, b.samples_used,
                "recovery changes a good decode"
            );
            assert_eq!(a.samples_verified, b.samples_verified);
            assert_eq!(a.image, b.image, "recovery changes a good decode");
        }
        (Ok(_), Some(Err(e))) => {
            panic!("recovery fails where the strict decoder succeeds: {e:?}")
        }
        (Err(Error::NeedMoreData), Some(Ok(_))) => {
            panic!("recovery decodes an incomplete header")
        }
        _ => {}
    }
    if let Ok(d) = &strict {
        let (header, _) = Header::parse(file).expect("a decoded file has a parsable header");
        check_decoded(d, &header, w, h);
        if !matches!(header.coding, qcs::container::Coding::Raw { .. }) {
            return strict.ok();
        }
        assert!(
            raw_result.is_ok(),
            "raw decoder fails where decode succeeds"
        );
        assert_eq!(d.samples_used, raw.samples_available().min(cap));
        assert_eq!(
            d.samples_verified,
            raw.samples_verified().min(d.samples_used)
        );
    }
    if let Some(Ok(d)) = &recovered {
        let (header, _) = Header::parse(file).expect("a decoded file has a parsable header");
        check_decoded(d, &header, w, h);
    }
    strict.ok()
}

/// The push decoder: control bytes `[seed × 4]`, then the file, fed in pseudo-random chunks
/// (0..=64 bytes, sometimes one byte) with renders at random points (about two per file) and
/// sizes (≤ 16×16), some from the first samples only, some thumbnails; some decoders decode
/// only the levels before a sample ([`ParserOptions::max_samples`]).
///
/// Checks: a push error is final (the decoder stays poisoned); the counts never go down (but
/// for a recovery dropping a damaged chunk's unverified samples) and
/// match a one-shot [`qcs::decode`] of the same bytes at the end; renders have the size asked
/// for; the same file split differently gives the same result as one push. Then reads the
/// file with the pull decoder, [`Previews`] (see `pull` in the source).
pub fn push(data: &[u8]) {
    on_threads(1, || push_on_one_thread(data))
}

fn push_on_one_thread(data: &[u8]) {
    let (ctl, file) = split(data, 4);
    let mut rng = Rng::new(ctl);
    let recover = rng.below(4) == 0;
    let mut opts = ParserOptions {
        limits: limits(),
        recover,
        max_samples: None,
    };
    // Sometimes decoding only the levels that start before a sample (below 256), as for
    // thumbnails: the levels after it are verified, not decoded.
    let cap = (rng.below(4) == 0).then(|| rng.below(256));
    if let Some(k) = cap {
        opts.max_samples = Some(k);
    }
    let mut dec = StreamDecoder::with_options(opts.clone());
    let mut pos = 0;
    let mut failed = false;
    let (mut last_avail, mut last_verified) = (0, 0);
    // A render after one chunk in four, but about two per file on long files: a render costs
    // more than a push, and the fuzzer chooses where they fall.
    let render_odds = (file.len() as u64 / 56).max(4);
    while pos < file.len() {
        let n = match rng.below(8) {
            0 => 0,
            1 => 1,
            _ => 1 + rng.below(64) as usize,
        };
        let end = (pos + n).min(file.len());
        let r = dec.push(&file[pos..end]);
        pos = end;
        if failed {
            assert!(
                matches!(r, Err(Error::Poisoned { .. })),
                "push after an error: {r:?}"
            );
            continue;
        }
        if r.is_err() {
            failed = true;
            let again = dec.push(&[]);
            assert!(
                matches!(again, Err(Error::Poisoned { .. })),
                "decoder not poisoned after an error: {again:?}"
            );
            continue;
        }
        // Only a recovery drops samples: the unverified ones of the damaged chunk.
        let dropped = dec.stopped().is_some() && dec.samples_available() == dec.samples_verified();
        assert!(
            dec.samples_available() >= last_avail || dropped,
            "available went down"
        );
        assert!(
            dec.samples_verified() >= last_verified,
            "verified went down"
        );
        assert!(dec.samples_verified() <= dec.samples_available());
        if let (Some(k), Some(h)) = (cap, dec.header()) {
            assert!(dec.samples_available() <= samples_of_levels_before(h, k));
        }
        last_avail = dec.samples_available();
        last_verified = dec.samples_verified();
        if rng.below(render_odds) == 0 {
            let w = 1 + rng.below(16) as u32;
            let h = 1 + rng.below(16) as u32;
            let method = METHODS[rng.below(3) as usize];
            // Sometimes from the first k samples only (k below 64), sometimes a thumbnail
            // (at most 16 samples per pixel).
            let (k, r) = match rng.below(4) {
                0 => {
                    let k = rng.below(64);
                    (k, dec.render_first(k, method, w, h))
                }
                1 => (16 * w as u64 * h as u64, dec.render_thumbnail(method, w, h)),
                _ => (u64::MAX, dec.render(method, w, h)),
            };
            match r {
                Ok(p) => {
                    let header = dec.header().cloned().expect("render implies a header");
                    check_decoded(p.decoded(), &header, w, h);
                    // The refinement's picture draws on every sample (its prediction).
                    let used = match p.decoded().refined {
                        true => header.total_samples,
                        false => dec.samples_available().min(k),
                    };
                    assert_eq!(p.decoded().samples_used, used);
                    let all = used == header.total_samples;
                    assert_eq!(p.is_final(), all && dec.is_complete());
                }
                Err(Error::NeedMoreData) => assert!(dec.header().is_none()),
                Err(e) => panic!("render failed after a good push: {e:?}"),
            }
        }
    }
    // Split invariance: one push of everything gives the same state.
    let mut whole = StreamDecoder::with_options(opts);
    let r = whole.push(file);
    assert_eq!(
        r.is_err(),
        failed,
        "error depends on how the bytes are split"
    );
    if !failed {
        assert_eq!(whole.samples_available(), dec.samples_available());
        assert_eq!(whole.samples_verified(), dec.samples_verified());
        assert_eq!(whole.levels_complete(), dec.levels_complete());
        assert_eq!(whole.header(), dec.header());
        assert_eq!(whole.metadata(), dec.metadata());
        assert_eq!(whole.stopped(), dec.stopped());
        if whole.header().is_some() {
            let a = whole.render(Method::Shepard, 8, 8).map(|p| p.into_image());
            let b = dec.render(Method::Shepard, 8, 8).map(|p| p.into_image());
            match (a, b) {
                (Ok(a), Ok(b)) => assert_eq!(a, b, "split changes the picture"),
                (a, b) => panic!("render after a good push: {:?} / {:?}", a.err(), b.err()),
            }
        }
    }
    pull(
        file,
        &mut rng,
        (!recover && cap.is_none()).then_some(failed),
    );
}

/// Reads pieces of 1 to 64 bytes of a file, sizes chosen by the generator.
struct Pieces<'a>(&'a [u8], Rng);

impl std::io::Read for Pieces<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = (1 + self.1.below(64) as usize)
            .min(buf.len())
            .min(self.0.len());
        buf[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        Ok(n)
    }
}

/// The pull decoder ([`Previews`]) on `file`, read in random pieces, at a random cadence and
/// size, as thumbnails or not: it ends, with at most one picture per cadence step and one more;
/// an error is its last item; pictures have the size asked for and never draw on fewer
/// samples; and, where `strict_failed` says how a strict push of the file ended, it fails on
/// a damaged file exactly when the push did (at a size within the limits, not as thumbnails).
fn pull(file: &[u8], rng: &mut Rng, strict_failed: Option<bool>) {
    // At most about four pictures by bytes: a picture costs more than the bytes between them.
    let step = (1 + rng.below(256) as usize).max(file.len() / 4);
    let cadence = match rng.below(2) {
        0 => Cadence::PerLevel,
        _ => Cadence::EveryBytes(step),
    };
    let size = (rng.below(2) == 0).then(|| (1 + rng.below(16) as u32, 1 + rng.below(16) as u32));
    let method = METHODS[rng.below(3) as usize];
    let thumbnails = rng.below(2) == 0;
    let reader = Pieces(file, Rng(rng.next() | 1));
    let opts = DecodeOptions {
        method,
        size,
        thumbnail: thumbnails,
        limits: limits(),
        ..Default::default()
    };
    let p = Previews::new(reader, cadence, &opts);
    // Per level: at most a picture per level (each takes at least 5 bytes); every K bytes:
    // one per K; plus the last, or an error.
    let bound = match cadence {
        Cadence::PerLevel => file.len() / 5 + 2,
        Cadence::EveryBytes(k) => file.len() / k + 2,
    };
    // (Compared only at a size within the limits: the image's own may be beyond them, which
    // is an error of the picture, not of the file.)
    let strict_failed = strict_failed.filter(|_| !thumbnails && size.is_some());
    let (mut used, mut errored, mut count) = (0, false, 0);
    for item in p {
        count += 1;
        assert!(count <= bound, "more pictures than cadence steps");
        assert!(!errored, "an item after an error");
        match item {
            Ok(pic) => {
                let d = pic.decoded();
                if let Some((w, h)) = size {
                    assert_eq!((d.image.width(), d.image.height()), (w, h), "output size");
                }
                assert!(d.samples_used >= used, "a picture drew on fewer samples");
                assert!(!matches!(pic, Picture::Final(_)) || d.is_final);
                used = d.samples_used;
            }
            Err(e) => {
                errored = true;
                let damaged = !matches!(e, Error::NeedMoreData);
                if let Some(failed) = strict_failed {
                    assert_eq!(
                        damaged, failed,
                        "the pull and push decoders disagree on the damage"
                    );
                }
            }
        }
    }
    if strict_failed == Some(true) {
        assert!(errored, "the pull decoder misses the damage the push found");
    }
}

/// The header parser on arbitrary bytes: a parsed header re-encodes to the same header, its
/// level schedule is consistent, and the push [`Parser`] fed one byte at
/// a time agrees with [`Header::parse`]. Also runs [`container::inspect`].
pub fn header(data: &[u8]) {
    let parsed = Header::parse(data);
    if let Ok((h, len)) = &parsed {
        let len = *len;
        assert!(
            (7..=container::MAX_HEADER_LEN).contains(&len),
            "header length {len}"
        );
        // N may be written out where a density byte would do, or several density bytes may
        // give it: the encoder writes the shortest form, and the same header.
        let bytes = h.encode().expect("a parsed header encodes");
        assert!(bytes.len() <= len, "re-encoded length");
        assert_eq!(Header::parse(&bytes).ok(), Some((h.clone(), bytes.len())));
        let levels = h.level_count();
        assert!((1..=65).contains(&levels), "{levels} levels");
        let mut next = 0;
        for k in 0..levels {
            let r = h.level_range(k).expect("level below level_count");
            assert_eq!(r.start, next, "levels are contiguous");
            assert!(r.end > r.start);
            if k > 0 {
                assert!(
                    r.end - r.start <= r.start,
                    "a level at most doubles the count"
                );
            }
            next = r.end;
            if let Coding::Raw { bits } = h.coding {
                let len = h.level_payload_len(k).expect("raw fixes payload lengths");
                assert!(len <= u32::MAX as u64);
                let c = h.layout.channels() as u64;
                assert_eq!(len, ((r.end - r.start) * c * bits as u64).div_ceil(8));
            }
        }
        assert_eq!(next, h.total_samples, "levels cover N");
        assert!(h.level_range(levels).is_none());
    }
    // The push parser, byte by byte, with no limits, sees the same header.
    let mut p = Parser::new(ParserOptions {
        limits: Limits::none(),
        ..Default::default()
    });
    let mut events = Vec::new();
    let mut result = Ok(());
    for b in data.iter().take(container::MAX_HEADER_LEN + 1) {
        result = p.push(std::slice::from_ref(b), &mut events);
        if result.is_err() || p.header().is_some() {
            break;
        }
    }
    match &parsed {
        // Limits::none() still bounds dimensions to the site construction's 65535.
        Ok(_) if matches!(result, Err(Error::Limits(_))) => assert!(h_too_big(&parsed)),
        Ok((h, _)) => assert_eq!(p.header(), Some(h), "push parser disagrees"),
        Err(container::FormatError::TruncatedHeader { .. }) => {
            assert!(result.is_ok() && p.header().is_none())
        }
        Err(e) => match &result {
            Err(Error::Format(f)) => assert_eq!(f, e, "push parser reports another error"),
            other => panic!("push parser: {other:?}, Header::parse: {e}"),
        },
    }
    let _ = container::inspect(data);
}

fn h_too_big(parsed: &Result<(Header, usize), container::FormatError>) -> bool {
    parsed
        .as_ref()
        .is_ok_and(|(h, _)| h.width.max(h.height) > u16::MAX as u32)
}

/// A round trip: control bytes `[w, h, layout, bits, n, first level, colour rule, frame]`, then
/// pixels (cycled). Encodes the small image, decodes it and checks exactly what must hold: the
/// decode is final with N samples; every sample colour is the encoder's sample colour quantised
/// to B bits and back; a prefix cut anywhere after the header decodes to a picture. The top two
/// bits of `bits` choose the target: levels only (a constant image then decodes to its
/// quantised constant everywhere, by the method byte 6 chooses), lossless (every pixel exact), a quality
/// (byte `n`, a constant image decodes to within 2 of its constant from quality 50 on: 1 for
/// the levels' rounding, 1 for the lossy 9/7's), or a
/// size (the file is no larger than asked, when that leaves room for the levels).
pub fn roundtrip(data: &[u8]) {
    on_threads(1, || roundtrip_on_one_thread(data))
}

fn roundtrip_on_one_thread(data: &[u8]) {
    let (ctl, px) = split(data, 8);
    let w = 1 + (byte(ctl, 0) % 24) as u32;
    let h = 1 + (byte(ctl, 1) % 24) as u32;
    let layout = Layout::from_channels(1 + byte(ctl, 2) % 4).unwrap_or(Layout::Grey);
    let bits = 1 + byte(ctl, 3) % 8;
    let area = w as u64 * h as u64;
    // A first-level byte with its high bit set asks for the encoder's N and L0, which the
    // header writes as the format byte's defaults bit.
    let (n, first) = if byte(ctl, 5) & 0x80 != 0 {
        ((area / 4).max(1), container::DEFAULT_FIRST_LEVEL)
    } else {
        (
            1 + byte(ctl, 4) as u64 % area,
            1 + (byte(ctl, 5) % 16) as u64,
        )
    };
    let colour = [
        SampleColour::Nearest,
        SampleColour::Bilinear,
        SampleColour::Area,
        SampleColour::Progressive,
        SampleColour::Fitted,
    ][(byte(ctl, 6) % 5) as usize];
    let c = layout.channels() as usize;
    let len = (w * h) as usize * c;
    let pixels: Vec<u8> = if px.is_empty() {
        vec![0; len]
    } else {
        px.iter().copied().cycle().take(len).collect()
    };
    let frame_byte = byte(ctl, 7);
    let frame = (frame_byte != 0).then(|| {
        let d = Frame::default_for(w, h);
        Frame {
            root_len: (1 << 16) + ((frame_byte & 0x0F) as u32) * (1 << 13),
            origin: [d.origin[0] - (frame_byte as i32) * 977, d.origin[1]],
        }
    });
    let image = to_image(layout, w, h, pixels.clone());
    let target = match byte(ctl, 3) >> 6 {
        0 => Target::LevelsOnly,
        1 => Target::Lossless,
        2 => Target::Quality(byte(ctl, 4) % 101),
        _ => Target::Size(byte(ctl, 4) as u64 * 4),
    };
    let opts = EncodeOptions {
        target,
        samples: Some(n),
        coding: Coding::Raw { bits },
        colour,
        first_level: first,
        frame,
        ..Default::default()
    };
    let file = qcs::encode(&image, &opts).expect("encoding a small image");
    let levels_only = EncodeOptions {
        target: Target::LevelsOnly,
        ..opts.clone()
    };
    if let Target::Size(size) = target {
        let base = qcs::encode(&image, &levels_only).expect("encoding a small image");
        if size as usize >= base.len() + 64 {
            assert!(
                file.len() as u64 <= size,
                "{} bytes for a target of {size}",
                file.len()
            );
        }
    }

    // Independent expectation of the sample colours: the sampling rule at the sites, quantised.
    let q = Quasicrystal::with_frame(w, h, frame.unwrap_or_else(|| Frame::default_for(w, h)))
        .expect("frame within bounds");
    let sites = q.first(n as usize);
    let positions: Vec<_> = sites.iter().map(|s| s.pos).collect();
    let source = SourceImage::new(&pixels, w, h, c).expect("harness buffers match");
    let colours = match colour {
        SampleColour::Fitted => source.fitted(&sites, q.frame(), first as usize, n as usize),
        rule => source.colours(&positions, rule, n as usize),
    };
    let expected: Vec<u8> = colours
        .iter()
        .map(|&v| raw::dequantise(raw::quantise(v, bits), bits))
        .collect();
    let mut rd = RawDecoder::new(ParserOptions {
        limits: limits(),
        ..Default::default()
    });
    rd.push(&file).expect("decoding what was encoded");
    assert_eq!(rd.samples_verified(), n);
    assert_eq!(rd.colours(), &expected[..], "sample colours");

    let constant = pixels.chunks(c).all(|p| p == &pixels[..c]);
    if target != Target::LevelsOnly {
        let d = qcs::decode(
            &file,
            &DecodeOptions {
                limits: limits(),
                ..Default::default()
            },
        )
        .expect("decoding what was encoded");
        assert!(d.is_final && d.refined && d.samples_used == n);
        assert_eq!((d.image.width(), d.image.height()), (w, h));
        let got = d.image.as_bytes();
        match target {
            Target::Lossless => assert!(got == &pixels[..], "lossless decodes to other pixels"),
            // Levels of 6 bits or fewer are already 2 or more off, and a quality codes only
            // the passes its threshold pays for: the check holds for finer levels. The base is
            // within 1 of the constant; the lossy 9/7 refinement may round one more
            // (regressions `constant-21x3-7bit-quality-55`: 157 from the levels for 156, and
            // the 9/7's fixed-point rounding draws 158 on alternate pixels of the middle row;
            // `constant-16x23-7bit-quality-89`, which was 3 off before the picture undid
            // YCoCg-R before rounding; `constant-16x23-7bit-quality-89-odd-co`, 3 off in blue
            // before the planes and the low band's prediction took YCoCg-R on fixed-point
            // values, as the picture undoes it).
            Target::Quality(q) if constant && q >= 50 && bits >= 7 => assert!(
                got.iter()
                    .zip(pixels.iter())
                    .all(|(&a, &b)| a.abs_diff(b) <= 2),
                "quality {q}: constant image {:?} decodes to other colours",
                &pixels[..c]
            ),
            _ => {}
        }
    }
    // Levels only: one method per input (the colour rule's byte chooses it too).
    if target == Target::LevelsOnly {
        let method = METHODS[(byte(ctl, 6) / 5 % 4) as usize];
        let d = qcs::decode(
            &file,
            &DecodeOptions {
                method,
                limits: limits(),
                ..Default::default()
            },
        )
        .expect("decoding what was encoded");
        assert!(d.is_final && d.samples_used == n && d.samples_verified == n);
        assert_eq!((d.image.width(), d.image.height()), (w, h));
        if constant {
            let want: Vec<u8> = pixels[..c]
                .iter()
                .map(|&v| raw::dequantise(raw::quantise(v, bits), bits))
                .collect();
            let got = d.image.as_bytes();
            assert!(
                got.chunks(c).all(|p| p == &want[..]),
                "{method:?}: constant image {want:?} decodes to other colours"
            );
        }
    }
    // A prefix cut after the header is a picture; inside the header it is NeedMoreData.
    let (_, header_len) = Header::parse(&file).expect("own header");
    let cut = header_len + (byte(ctl, 4) as usize * 7 + px.len()) % (file.len() - header_len + 1);
    let d = qcs::decode(
        &file[..cut],
        &DecodeOptions {
            size: Some((8, 8)),
            limits: limits(),
            ..Default::default()
        },
    )
    .expect("a prefix after the header decodes");
    assert!(d.samples_used <= n);
    assert_eq!(d.is_final, cut == file.len());
    assert!(matches!(
        qcs::decode(&file[..header_len - 1], &Default::default()),
        Err(Error::NeedMoreData)
    ));
}

fn to_image(layout: Layout, w: u32, h: u32, px: Vec<u8>) -> image::DynamicImage {
    use image::DynamicImage as D;
    let bad = "buffer of w×h×channels";
    match layout {
        Layout::Grey => D::ImageLuma8(image::GrayImage::from_raw(w, h, px).expect(bad)),
        Layout::GreyAlpha => D::ImageLumaA8(image::GrayAlphaImage::from_raw(w, h, px).expect(bad)),
        Layout::Rgb => D::ImageRgb8(image::RgbImage::from_raw(w, h, px).expect(bad)),
        Layout::Rgba => D::ImageRgba8(image::RgbaImage::from_raw(w, h, px).expect(bad)),
    }
}
