//! The push decoder (`StreamDecoder`) and the pull decoder (`Previews`) against the one-shot
//! `decode` on the same bytes, in the cases a library audit found them to disagree.

use qcs::container::ParserOptions;
use qcs::{decode, encode, Cadence, DecodeOptions, EncodeOptions, Error, Limits, Method};
use qcs::{Previews, StreamDecoder};

/// A file of quasicrystal levels only (format version 2), at the levels' own quality 75:
/// what these tests of the levels' pictures are about.
fn levels_only() -> EncodeOptions {
    EncodeOptions {
        target: qcs::Target::LevelsOnly,
        coding: qcs::coding::predictive::Params::default().coding(),
        ..Default::default()
    }
}

fn gradient() -> image::DynamicImage {
    image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(48, 32, |x, y| {
        image::Rgb([x as u8 * 5, y as u8 * 7, (x * y) as u8])
    }))
}

fn file() -> Vec<u8> {
    let opts = EncodeOptions {
        first_level: 8,
        ..levels_only()
    };
    encode(&gradient(), &opts).expect("encode")
}

/// The file's sample count N.
fn samples(bytes: &[u8]) -> u64 {
    let header = qcs::container::inspect(bytes).header;
    header.expect("header").total_samples
}

/// A reader that returns at most 10 bytes per call, as sockets and pipes may.
struct Trickle<'a>(&'a [u8]);

impl std::io::Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(10).min(self.0.len());
        buf[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        Ok(n)
    }
}

fn previews<R: std::io::Read>(r: R, cadence: Cadence) -> Vec<Result<qcs::Picture, Error>> {
    Previews::new(r, cadence, &DecodeOptions::default()).collect()
}

/// In recovery mode a damaged last level is dropped: a render after that shows the verified
/// samples only, although an earlier preview had drawn some of the dropped ones.
#[test]
fn recovery_drops_damaged_samples_from_later_renders() {
    let mut bad = file();
    let n = bad.len();
    bad[n - 2] ^= 0x55; // the last level's CRC
    for method in [
        Method::Gouraud,
        Method::Shepard,
        Method::Natural,
        Method::Cubic,
    ] {
        let opts = ParserOptions {
            recover: true,
            ..Default::default()
        };
        let mut d = StreamDecoder::with_options(opts);
        d.push(&bad[..n - 30]).expect("push");
        let early = d.render(method, 48, 32).expect("render");
        assert!(early.decoded().samples_used > early.decoded().samples_verified);
        d.push(&bad[n - 30..]).expect("push");
        assert!(d.stopped().is_some());
        let late = d.render(method, 48, 32).expect("render");
        let one = decode(
            &bad,
            &DecodeOptions {
                recover: true,
                method,
                ..Default::default()
            },
        )
        .expect("decode");
        assert_eq!(late.decoded().samples_used, one.samples_used, "{method:?}");
        assert!(late.decoded().image == one.image, "{method:?}");
    }
}

/// `Cadence::EveryBytes(K)` gives a picture per K bytes, however the reader splits them.
#[test]
fn every_k_bytes_does_not_depend_on_the_reads() {
    let bytes = file();
    for k in [1, 100, 333] {
        let whole = previews(&bytes[..], Cadence::EveryBytes(k));
        let trickled = previews(Trickle(&bytes), Cadence::EveryBytes(k));
        assert_eq!(whole.len(), trickled.len(), "K = {k}");
        // One per K bytes once the header is in (11 bytes here), and the final picture.
        let (most, least) = (bytes.len().div_ceil(k) + 1, (bytes.len() - 11) / k);
        assert!((least..=most).contains(&whole.len()), "K = {k}");
        for (a, b) in whole.iter().zip(&trickled) {
            let (a, b) = (a.as_ref().expect("picture"), b.as_ref().expect("picture"));
            assert!(a.decoded().image == b.decoded().image);
        }
        assert!(whole
            .last()
            .expect("pictures")
            .as_ref()
            .expect("final")
            .is_final());
    }
}

/// Bytes after the last level are still read: metadata there is seen, damage there is an
/// error after the final picture, as `decode` reports it. A stream that ends inside the
/// header is `NeedMoreData`, as for `decode`.
#[test]
fn the_stream_is_read_to_its_end() {
    let levels = file();
    let mut damaged = levels.clone();
    damaged.extend_from_slice(&[0xFF, 0, 0, 0, 0, 0]);
    let want = decode(&damaged, &DecodeOptions::default()).expect_err("damaged");
    for pics in [
        previews(&damaged[..], Cadence::PerLevel),
        previews(Trickle(&damaged), Cadence::EveryBytes(50)),
    ] {
        let (last, rest) = pics.split_last().expect("pictures");
        let got = last.as_ref().expect_err("damage after the last level");
        assert_eq!(got.to_string(), want.to_string());
        assert!(rest.iter().all(|p| p.is_ok()));
    }

    // A text chunk after the levels, written by the container writer.
    let header = qcs::container::Header::new(
        2,
        1,
        qcs::container::Layout::Grey,
        2,
        1,
        qcs::container::Coding::Raw { bits: 8 },
    );
    let mut w = qcs::container::ContainerWriter::new(Vec::new(), &header).expect("writer");
    w.write_level(&[200]).expect("level");
    w.write_level(&[100]).expect("level");
    w.write_text("Author", "me").expect("text");
    let with_text = w.finish().expect("file");
    let mut p = Previews::new(&with_text[..], Cadence::PerLevel, &DecodeOptions::default());
    assert!(p.by_ref().all(|r| r.is_ok()));
    let mut d = StreamDecoder::new(Limits::default());
    d.push(&with_text).expect("push");
    assert_eq!(p.decoder().metadata(), d.metadata());
    assert_eq!(d.metadata().len(), 1);

    for cut in [0, 3] {
        let pics = previews(&levels[..cut], Cadence::PerLevel);
        assert!(
            matches!(pics[..], [Err(Error::NeedMoreData)]),
            "{cut} bytes"
        );
    }
}

/// `levels_complete` counts the levels within the samples the picture used.
#[test]
fn levels_complete_follows_the_samples_used() {
    let bytes = file();
    // Levels of 8, 8, 16, 32 … samples.
    for (cap, levels) in [(0, 0), (7, 0), (8, 1), (15, 1), (16, 2), (31, 2), (32, 3)] {
        let d = decode(
            &bytes,
            &DecodeOptions {
                max_samples: Some(cap),
                ..Default::default()
            },
        )
        .expect("decode");
        assert_eq!(d.levels_complete, levels, "{cap} samples");
    }
}

/// A level payload no encoder writes (all 0xFF), framed with a valid check byte and CRC: the
/// colours decoded from any part of it are those decoded from all of it (found by the push
/// fuzzer; the range decoder had decided bits from codes a valid stream cannot reach).
#[test]
fn invalid_payloads_decode_alike_in_pieces() {
    use qcs::container::{Coding, ContainerWriter, Header, Layout};
    for (step, len) in [(101, 8), (7, 20), (1, 40)] {
        let header = Header::new(128, 48, Layout::Rgb, 960, 115, Coding::Predictive { step });
        let mut w = ContainerWriter::new(Vec::new(), &header).expect("writer");
        w.write_level(&vec![0xFF; len]).expect("level");
        let file = w.into_inner();
        let mut whole = StreamDecoder::new(Limits::default());
        whole.push(&file).expect("push");
        let n = whole.samples_available();
        let want = whole.samples(n).1.to_vec();
        for cut in 0..file.len() {
            let mut d = StreamDecoder::new(Limits::default());
            d.push(&file[..cut]).expect("push");
            let early = d.samples(n).1.to_vec();
            d.push(&file[cut..]).expect("push");
            assert_eq!(d.samples(n).1, &want[..], "step {step}, cut at {cut}");
            assert_eq!(early, want[..early.len()], "step {step}, cut at {cut}");
        }
    }
}

/// `render_first(k, …)` on the bytes received so far is the one-shot decode of those bytes
/// capped at `k` samples, whichever `k` came before (the kept set shrinks and grows).
#[test]
fn render_first_equals_a_capped_decode() {
    let bytes = file();
    let total = samples(&bytes);
    let mut dec = StreamDecoder::new(Limits::default());
    let mut fed = 0;
    for cut in [40, bytes.len() / 3, bytes.len()] {
        dec.push(&bytes[fed..cut]).expect("push");
        fed = cut;
        for k in [total, 20, 8, 300, 9, u64::MAX] {
            for method in [Method::Gouraud, Method::Shepard] {
                let pic = dec.render_first(k, method, 20, 13).expect("render");
                let opts = DecodeOptions {
                    method,
                    size: Some((20, 13)),
                    max_bytes: Some(cut),
                    max_samples: Some(k),
                    ..Default::default()
                };
                let one = decode(&bytes, &opts).expect("decode");
                let d = pic.decoded();
                let what = format!("cut {cut}, {k} samples, {method:?}");
                assert_eq!(d.samples_used, one.samples_used, "{what}");
                assert_eq!(d.samples_verified, one.samples_verified, "{what}");
                assert_eq!(d.levels_complete, one.levels_complete, "{what}");
                assert_eq!(pic.is_final(), one.is_final, "{what}");
                assert!(d.image == one.image, "{what}");
            }
        }
    }
    assert!(dec.is_complete());
}

/// `render_thumbnail` on the bytes received so far is the one-shot thumbnail of those bytes.
#[test]
fn render_thumbnail_equals_a_one_shot_thumbnail() {
    let bytes = file();
    let mut dec = StreamDecoder::new(Limits::default());
    let mut fed = 0;
    for cut in [40, bytes.len() / 2, bytes.len()] {
        dec.push(&bytes[fed..cut]).expect("push");
        fed = cut;
        for (w, h) in [(6, 4), (12, 8), (48, 32)] {
            for method in [Method::Gouraud, Method::Shepard] {
                let pic = dec.render_thumbnail(method, w, h).expect("render");
                let opts = DecodeOptions {
                    method,
                    max_bytes: Some(cut),
                    ..DecodeOptions::thumbnail(w, h)
                };
                let one = decode(&bytes, &opts).expect("decode");
                let what = format!("cut {cut}, {w}×{h}, {method:?}");
                assert_eq!(pic.decoded().samples_used, one.samples_used, "{what}");
                assert_eq!(pic.is_final(), one.is_final, "{what}");
                assert!(pic.decoded().image == one.image, "{what}");
            }
        }
    }
}

/// A push decoder that decodes only the levels before a thumbnail's samples
/// (`ParserOptions::max_samples`) draws the same thumbnails as one that decodes them all, at
/// every cut, while decoding no level past them; it takes a file with more samples than its
/// limit, and is complete once every level is verified.
#[test]
fn a_decoder_capped_at_a_thumbnails_samples_draws_the_same_thumbnails() {
    let bytes = file();
    let n = samples(&bytes);
    let (w, h) = (2, 2);
    let cap = qcs::thumbnail_samples(w, h);
    assert!(cap < n / 4);
    let limits = Limits {
        max_samples: cap, // the levels before `cap` end at it: 8, 16, 32, 64
        ..Default::default()
    };
    let opts = ParserOptions {
        limits: limits.clone(),
        ..Default::default()
    };
    assert!(StreamDecoder::with_options(opts.clone())
        .push(&bytes)
        .is_err());
    let mut capped = StreamDecoder::with_options(ParserOptions {
        max_samples: Some(cap),
        ..opts
    });
    let mut whole = StreamDecoder::new(Limits::default());
    for piece in bytes.chunks(7) {
        capped.push(piece).expect("push");
        whole.push(piece).expect("push");
        assert!(capped.samples_available() <= cap);
        assert_eq!(capped.is_complete(), whole.is_complete());
        if capped.header().is_none() {
            continue;
        }
        for method in [Method::Gouraud, Method::Shepard] {
            let a = capped.render_thumbnail(method, w, h).expect("render");
            let b = whole.render_thumbnail(method, w, h).expect("render");
            assert_eq!(a.decoded().samples_used, b.decoded().samples_used);
            assert!(a.decoded().image == b.decoded().image);
        }
    }
    assert!(capped.is_complete());
    assert_eq!(capped.samples_available(), cap);
    assert_eq!(capped.levels_complete(), whole.levels_complete());
}

/// `Previews::thumbnails`: the pictures `decode` draws as a thumbnail, from only the levels a
/// thumbnail uses; the rest of the stream is still read and checked.
#[test]
fn previews_draw_thumbnails() {
    let img = image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(96, 80, |x, y| {
        image::Rgb([(x * 3) as u8, (x ^ y) as u8 * 2, (y * 3) as u8])
    }));
    let bytes = encode(&img, &levels_only()).expect("encode");
    let n = samples(&bytes);
    let size = (6, 5);
    let uses = qcs::thumbnail_samples(size.0, size.1);
    assert!(uses < n / 2, "{uses} of {n} samples");
    let thumbs = |b: &[u8]| -> Vec<_> { per_level(Trickle(b), Some(size), true).collect() };
    let pics: Vec<_> = thumbs(&bytes)
        .into_iter()
        .map(|p| p.expect("picture"))
        .collect();
    let plain = per_level(&bytes[..], Some(size), false);
    assert!(
        pics.len() >= 2 && pics.len() < plain.count(),
        "{} pictures",
        pics.len()
    );
    let used: Vec<u64> = pics.iter().map(|p| p.decoded().samples_used).collect();
    assert!(used.windows(2).all(|w| w[0] < w[1]), "{used:?}");
    // The last picture is the first drawn on every sample the thumbnail uses: `decode`'s
    // thumbnail of the whole file, which is not its final picture.
    let last = pics.last().expect("pictures");
    assert!(!last.is_final());
    let one = decode(
        &bytes,
        &DecodeOptions {
            size: Some(size),
            thumbnail: true,
            ..Default::default()
        },
    )
    .expect("decode");
    assert_eq!(
        (last.decoded().samples_used, one.samples_used),
        (uses, uses)
    );
    assert!(last.decoded().image == one.image);
    // Each preview is the thumbnail of its samples.
    for p in &pics[..pics.len() - 1] {
        let d = p.decoded();
        let opts = DecodeOptions {
            size: Some(size),
            thumbnail: true,
            max_samples: Some(d.samples_used),
            ..Default::default()
        };
        assert!(d.image == decode(&bytes, &opts).expect("decode").image);
    }
    // Damage in the last level, which no thumbnail draws on, is still reported, after them.
    let mut bad = bytes.clone();
    let end = bad.len();
    bad[end - 2] ^= 0x55;
    let got = thumbs(&bad);
    assert_eq!(got.len(), pics.len() + 1);
    assert!(matches!(got.last(), Some(Err(Error::Format(_)))));
    assert!(got[pics.len() - 1]
        .as_ref()
        .is_ok_and(|p| p.decoded().image == one.image));

    // At the image's own size a thumbnail is the plain picture.
    let own = |thumb: bool| -> Vec<image::DynamicImage> {
        let p = per_level(&bytes[..], None, thumb);
        p.map(|p| p.expect("picture").into_image()).collect()
    };
    assert!(own(true) == own(false));
}

/// A picture per level, Gouraud, at `size`, thumbnails or not.
fn per_level<R: std::io::Read>(r: R, size: Option<(u32, u32)>, thumbnails: bool) -> Previews<R> {
    let opts = DecodeOptions {
        size,
        thumbnail: thumbnails,
        ..Default::default()
    };
    Previews::new(r, Cadence::PerLevel, &opts)
}

/// A picture that cannot be drawn (here: larger than the limits allow) ends the iteration:
/// every later one would fail the same way.
#[test]
fn previews_end_at_a_render_error() {
    let bytes = file();
    let limits = Limits {
        max_output_pixels: 100,
        ..Default::default()
    };
    for thumbnails in [false, true] {
        for cadence in [Cadence::PerLevel, Cadence::EveryBytes(16)] {
            let opts = DecodeOptions {
                thumbnail: thumbnails,
                limits: limits.clone(),
                ..Default::default()
            };
            let p = Previews::new(Trickle(&bytes), cadence, &opts);
            let items: Vec<_> = p.collect();
            assert!(
                matches!(items[..], [Err(Error::Limits(_))]),
                "{cadence:?}: {} items",
                items.len()
            );
        }
    }
}

/// A decoder that returned an error is poisoned: feeding it again is `Error::Poisoned`, not
/// the damage a second time (the first error is the one to report), nor a success.
#[test]
fn a_failed_decoder_is_poisoned() {
    let mut bytes = file();
    bytes[0] = b'Q';
    let mut dec = StreamDecoder::new(Limits::default());
    assert!(matches!(dec.push(&bytes), Err(Error::Format(_))));
    for more in [&[][..], &bytes[..]] {
        let e = dec.push(more).unwrap_err();
        assert!(
            matches!(
                e,
                Error::Poisoned {
                    object: "StreamDecoder"
                }
            ),
            "{e:?}"
        );
        assert_eq!(
            e.to_string(),
            "StreamDecoder used again after it returned an error"
        );
    }
}

/// `Previews` draws what `decode` draws with the same options: its last picture is the
/// one-shot decode's, whatever the options (a sample cap, a byte cut, thumbnails, the method),
/// for a file of levels only and for one with a refinement.
#[test]
fn previews_draw_what_decode_draws_with_the_same_options() {
    let refined = encode(&gradient(), &EncodeOptions::default()).expect("encode");
    for bytes in [file(), refined] {
        let n = bytes.len();
        let all = [
            DecodeOptions::default(),
            DecodeOptions {
                max_bytes: Some(n / 2),
                ..Default::default()
            },
            DecodeOptions {
                max_samples: Some(40),
                size: Some((20, 12)),
                method: Method::Shepard,
                ..Default::default()
            },
            DecodeOptions {
                size: Some((6, 4)),
                thumbnail: true,
                ..Default::default()
            },
            DecodeOptions {
                size: Some((6, 4)),
                thumbnail: true,
                max_samples: Some(20),
                max_bytes: Some(n - 3),
                ..Default::default()
            },
        ];
        for opts in all {
            for cadence in [Cadence::PerLevel, Cadence::EveryBytes(16)] {
                let pics: Vec<_> = Previews::new(Trickle(&bytes), cadence, &opts)
                    .collect::<Result<_, _>>()
                    .expect("pictures");
                let last = pics.last().expect("a picture").decoded();
                let once = decode(&bytes, &opts).expect("decode");
                assert!(
                    last.image == once.image && last.samples_used == once.samples_used,
                    "{opts:?}, {cadence:?}: {} against {} samples",
                    last.samples_used,
                    once.samples_used
                );
                assert_eq!(last.is_final, once.is_final, "{opts:?}");
            }
        }
    }
}
