//! Encoder + decoder end to end: round trips on photographs, prefixes, streaming equality.

use qcs::{decode, encode, DecodeOptions, EncodeOptions, Error, Method, StreamDecoder};

/// A file of quasicrystal levels only (format version 2), at the levels' own quality 75:
/// what these tests of the levels' pictures are about.
fn levels_only() -> EncodeOptions {
    EncodeOptions {
        target: qcs::Target::LevelsOnly,
        coding: qcs::coding::predictive::Params::default().coding(),
        ..Default::default()
    }
}

fn photo(name: &str) -> image::DynamicImage {
    image::open(format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"))).expect("test image")
}

fn psnr(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    qcs_lab::eval::psnr(a, b).unwrap()
}

#[test]
fn round_trip_psnr_on_photographs() {
    // One sample per 4 pixels, raw 8-bit: the full decode must be a faithful picture.
    for (name, floor) in [
        ("coffee-150x100.png", 22.0),
        ("astronaut-128x128.png", 19.0),
        ("seashore-100x100.png", 22.5),
    ] {
        let img = photo(name);
        let bytes = encode(
            &img,
            &EncodeOptions {
                density: 0.25,
                ..Default::default()
            },
        )
        .unwrap();
        let d = decode(&bytes, &DecodeOptions::default()).unwrap();
        assert!(d.is_final);
        assert_eq!(d.samples_used, d.samples_verified);
        let p = psnr(&img.to_rgb8(), &d.image.to_rgb8());
        eprintln!("{name}: full {p:.2} dB");
        assert!(p > floor, "{name}: {p:.2} dB");
        // Fewer samples, lower but still sensible PSNR; more bytes never hurt much.
        let half = decode(
            &bytes,
            &DecodeOptions {
                max_bytes: Some(bytes.len() / 4),
                ..Default::default()
            },
        )
        .unwrap();
        let ph = psnr(&img.to_rgb8(), &half.image.to_rgb8());
        assert!(
            ph < p && ph > floor - 6.0,
            "{name}: quarter file {ph:.2} dB vs {p:.2}"
        );
    }
}

#[test]
fn every_prefix_decodes() {
    let img = photo("seashore-100x100.png");
    let img = image::DynamicImage::ImageRgb8(image::imageops::thumbnail(&img.to_rgb8(), 24, 24));
    let bytes = encode(
        &img,
        &EncodeOptions {
            samples: Some(120),
            ..Default::default()
        },
    )
    .unwrap();
    let header_len = qcs::container::Header::parse(&bytes).unwrap().1;
    let mut last = 0;
    for cut in 0..=bytes.len() {
        let r = decode(
            &bytes,
            &DecodeOptions {
                max_bytes: Some(cut),
                size: Some((13, 7)),
                ..Default::default()
            },
        );
        if cut < header_len {
            assert!(matches!(r, Err(Error::NeedMoreData)), "cut {cut}");
            continue;
        }
        let d = r.unwrap_or_else(|e| panic!("cut {cut}: {e}"));
        assert_eq!((d.image.width(), d.image.height()), (13, 7));
        assert!(d.samples_used >= last, "samples never decrease");
        assert!(d.samples_verified <= d.samples_used);
        assert_eq!(d.is_final, cut == bytes.len());
        last = d.samples_used;
    }
    assert_eq!(last, 120);
}

#[test]
fn layouts_round_trip() {
    let rgb = photo("coffee-150x100.png");
    for img in [
        image::DynamicImage::ImageLuma8(rgb.to_luma8()),
        image::DynamicImage::ImageLumaA8(rgb.to_luma_alpha8()),
        rgb.clone(),
        image::DynamicImage::ImageRgba8(rgb.to_rgba8()),
    ] {
        let bytes = encode(&img, &EncodeOptions::default()).unwrap();
        let d = decode(
            &bytes,
            &DecodeOptions {
                size: Some((75, 50)),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(d.image.color(), img.color());
        assert_eq!((d.image.width(), d.image.height()), (75, 50));
    }
}

#[test]
fn low_bit_depths_cost_fewer_bytes() {
    let img = photo("coffee-150x100.png");
    let mut sizes = Vec::new();
    for bits in [1u8, 4, 8] {
        let opts = EncodeOptions {
            coding: qcs::container::Coding::Raw { bits },
            ..Default::default()
        };
        let bytes = encode(&img, &opts).unwrap();
        sizes.push(bytes.len());
        let d = decode(&bytes, &DecodeOptions::default()).unwrap();
        assert!(d.is_final);
    }
    assert!(sizes[0] < sizes[1] && sizes[1] < sizes[2], "{sizes:?}");
}

/// A reproducible xorshift for chunk sizes.
fn chunks(seed: u64, len: usize) -> Vec<usize> {
    let mut s = seed | 1;
    let mut cuts = Vec::new();
    let mut at = 0;
    while at < len {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let step = match s % 4 {
            0 => 1,
            1 => (s >> 8) as usize % 16,
            _ => (s >> 8) as usize % 700,
        };
        at = (at + step).min(len);
        cuts.push(at);
    }
    cuts
}

#[test]
fn streaming_renders_equal_one_shot_decodes_of_the_same_prefix() {
    for name in ["coffee-150x100.png", "seashore-100x100.png"] {
        let img = photo(name);
        let bytes = encode(
            &img,
            &EncodeOptions {
                density: 0.2,
                ..Default::default()
            },
        )
        .unwrap();
        for seed in 1..4u64 {
            let mut dec = StreamDecoder::new(qcs::Limits::default());
            let mut fed = 0;
            for (i, cut) in chunks(seed, bytes.len()).into_iter().enumerate() {
                dec.push(&bytes[fed..cut]).unwrap();
                fed = cut;
                if i % 5 != 0 && cut != bytes.len() {
                    continue;
                }
                if dec.header().is_none() {
                    continue;
                }
                for method in [Method::Gouraud, Method::Shepard] {
                    let pic = dec.render(method, 61, 47).unwrap();
                    let one = decode(
                        &bytes,
                        &DecodeOptions {
                            method,
                            max_bytes: Some(cut),
                            size: Some((61, 47)),
                            ..Default::default()
                        },
                    )
                    .unwrap();
                    assert_eq!(pic.decoded().samples_used, one.samples_used);
                    assert_eq!(pic.is_final(), one.is_final);
                    assert!(
                        pic.decoded().image.as_bytes() == one.image.as_bytes(),
                        "{name} seed {seed} cut {cut} {method:?}: streaming and one-shot pictures differ"
                    );
                }
            }
            assert!(dec.is_complete());
        }
    }
}

/// A decode capped at `max_samples` reads the levels beyond the one holding that sample
/// only to verify them: its picture is that of the file cut after that level, and a damaged
/// level beyond it is still an error.
#[test]
fn capped_decodes_equal_decodes_of_the_levels_they_need() {
    let bytes = encode(&photo("coffee-150x100.png"), &levels_only()).unwrap();
    let levels = qcs::container::inspect(&bytes).levels;
    // The byte where each level's chunk ends: the next one's start, or the end of the file.
    let ends: Vec<usize> = (levels.iter().skip(1))
        .map(|l| l.chunk.as_ref().unwrap().offset as usize)
        .chain([bytes.len()])
        .collect();
    for (l, level) in levels.iter().enumerate() {
        let r = &level.samples;
        for cap in [r.start + 1, (r.start + r.end) / 2, r.end] {
            for method in [Method::Gouraud, Method::Shepard] {
                let opts = |max_bytes, max_samples| DecodeOptions {
                    method,
                    size: Some((75, 50)),
                    max_bytes,
                    max_samples,
                    ..Default::default()
                };
                let capped = decode(&bytes, &opts(None, Some(cap))).unwrap();
                let cut = decode(&bytes, &opts(Some(ends[l]), Some(cap))).unwrap();
                assert_eq!(capped.samples_used, cap.min(r.end));
                assert_eq!(capped.samples_verified, cut.samples_verified);
                assert_eq!(capped.levels_complete, cut.levels_complete);
                assert!(capped.image == cut.image, "level {l}, {cap} samples");
            }
        }
    }
    // A flipped byte in the last level: an error even for a decode of the first level.
    let mut bad = bytes.clone();
    let last = ends[ends.len() - 2] + 4;
    bad[last] ^= 0x10;
    let first = DecodeOptions {
        max_samples: Some(levels[0].samples.end),
        ..Default::default()
    };
    assert!(decode(&bytes, &first).is_ok());
    assert!(matches!(decode(&bad, &first), Err(Error::Format(_))));
}

/// `Limits::max_samples` bounds the samples a decode decodes, not the header's N: a capped
/// decode or a thumbnail of a file with more samples than the limit works when the levels it
/// decodes fit, and is the picture a decode without the limit gives.
#[test]
fn capped_decodes_need_only_their_levels_within_the_limits() {
    let bytes = encode(&photo("coffee-150x100.png"), &levels_only()).unwrap();
    let levels = qcs::container::inspect(&bytes).levels;
    let n = levels.last().unwrap().samples.end;
    let limit = levels[levels.len() - 2].samples.end; // all but the last level
    let limits = qcs::Limits {
        max_samples: limit,
        ..Default::default()
    };
    let whole = DecodeOptions {
        limits: limits.clone(),
        ..Default::default()
    };
    assert!(matches!(
        decode(&bytes, &whole),
        Err(Error::Limits(qcs::limits::LimitError::Samples { value, limit: l })) if value == n && l == limit
    ));
    // Caps within the levels that fit, and one sample more (the last level).
    for (cap, fits) in [
        (1, true),
        (limit / 2, true),
        (limit, true),
        (limit + 1, false),
    ] {
        for thumbnail in [false, true] {
            let opts = |limits: qcs::Limits| DecodeOptions {
                max_samples: Some(cap),
                size: Some((15, 10)),
                thumbnail,
                limits,
                ..Default::default()
            };
            let got = decode(&bytes, &opts(limits.clone()));
            if !fits {
                assert!(matches!(got, Err(Error::Limits(_))), "{cap} samples");
                continue;
            }
            let want = decode(&bytes, &opts(qcs::Limits::default())).unwrap();
            let got = got.unwrap();
            assert_eq!(got.samples_used, want.samples_used);
            assert!(got.samples_used <= limit && !got.is_final);
            assert!(
                got.image == want.image,
                "{cap} samples, thumbnail {thumbnail}"
            );
        }
    }
    // A thumbnail whose 16 samples per pixel fit (3 × 2 pixels: 96 samples).
    let thumb = DecodeOptions {
        limits,
        ..DecodeOptions::thumbnail(3, 2)
    };
    assert_eq!(decode(&bytes, &thumb).unwrap().samples_used, 96);
}

/// A thumbnail (`DecodeOptions::thumbnail`) is the plain render of its first samples at f × f
/// times the size, each f × f square averaged (to within rounding, and not shifted); and it
/// is far closer to an area-averaged downscale of the photograph than the plain render of
/// every sample at the thumbnail's pixel centres, which aliases.
#[test]
fn thumbnails_average_a_finer_render_of_a_prefix() {
    for name in ["coffee-150x100.png", "astronaut-128x128.png"] {
        let img = photo(name);
        let bytes = encode(&img, &levels_only()).unwrap();
        let total = qcs::container::inspect(&bytes)
            .header
            .unwrap()
            .total_samples;
        for (f, want_factor) in [(4, 2), (8, 4)] {
            let (w, h) = (img.width() / f, img.height() / f);
            let reference = img.thumbnail_exact(w, h).to_rgb8();
            for method in [Method::Gouraud, Method::Shepard] {
                let what = format!("{name} 1/{f} {method:?}");
                let thumb = DecodeOptions {
                    method,
                    ..DecodeOptions::thumbnail(w, h)
                };
                let t = decode(&bytes, &thumb).unwrap();
                let k = total.min(16 * (w * h) as u64);
                assert_eq!(t.samples_used, k, "{what}");
                // The same samples rendered plainly at `want_factor` times the size, averaged.
                let s = want_factor;
                let fine = DecodeOptions {
                    method,
                    size: Some((w * s, h * s)),
                    max_samples: Some(k),
                    ..Default::default()
                };
                let fine = decode(&bytes, &fine).unwrap().image.to_rgb8();
                let t = t.image.to_rgb8();
                for (x, y, p) in t.enumerate_pixels() {
                    for c in 0..3 {
                        let sum: u32 = (0..s * s)
                            .map(|i| fine.get_pixel(x * s + i % s, y * s + i / s)[c] as u32)
                            .sum();
                        let mean = sum as f64 / (s * s) as f64;
                        assert!((p[c] as f64 - mean).abs() <= 1.0, "{what} at ({x}, {y})");
                    }
                }
                let plain = DecodeOptions {
                    thumbnail: false,
                    ..thumb.clone()
                };
                let a = decode(&bytes, &plain).unwrap();
                assert!(a.is_final);
                let (pt, pa) = (psnr(&t, &reference), psnr(&a.image.to_rgb8(), &reference));
                eprintln!("{what}: thumbnail {pt:.2} dB, plain {pa:.2} dB");
                assert!(pt > pa + 2.0, "{what}: {pt:.2} vs {pa:.2} dB");
            }
        }
    }
}

/// The README's photo at the default settings: the figures its caption states (the file's
/// size to the byte, its picture's PSNR to 0.01 dB).
#[test]
fn bundled_photo_is_what_the_readme_says() {
    let img = image::open(format!("{}/assets/rocket.png", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let bytes = encode(&img, &EncodeOptions::default()).unwrap();
    let d = decode(&bytes, &DecodeOptions::default()).unwrap();
    let p = psnr(&img.to_rgb8(), &d.image.to_rgb8());
    assert_eq!(bytes.len(), 15_249, "rocket.qcs");
    assert!((p - 36.31).abs() < 0.005, "rocket: {p:.3} dB");
}

/// A one-shot Gouraud decode on a pool with threads to spare builds the cells of the verified
/// samples while the colours decode, then extends them: the picture must be the one the
/// single-threaded decode gives, for whole files and prefixes (in the raw coding a prefix
/// also has unverified samples beyond the verified ones), with and without a sample cap.
#[test]
fn parallel_one_shot_decode_equals_the_single_threaded_one() {
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("a pool")
    };
    let (one, two) = (pool(1), pool(2));
    let img = photo("coffee-150x100.png");
    for coding in [
        qcs::container::Coding::Raw { bits: 8 },
        EncodeOptions::default().coding,
    ] {
        let opts = EncodeOptions {
            coding: coding.clone(),
            ..Default::default()
        };
        let bytes = encode(&img, &opts).unwrap();
        for cut in [0, 20, 150, 700, 1999, bytes.len() / 2, bytes.len()] {
            for max_samples in [None, Some(400)] {
                let opts = DecodeOptions {
                    max_bytes: Some(cut),
                    max_samples,
                    ..Default::default()
                };
                let a = one.install(|| decode(&bytes, &opts));
                let b = two.install(|| decode(&bytes, &opts));
                match (a, b) {
                    (Ok(a), Ok(b)) => {
                        assert_eq!(a.samples_used, b.samples_used, "{coding} cut {cut}");
                        assert!(a.image == b.image, "{coding} cut {cut} {max_samples:?}");
                    }
                    (a, b) => assert_eq!(
                        a.err().map(|e| e.to_string()),
                        b.err().map(|e| e.to_string())
                    ),
                }
            }
        }
    }
}

/// With the hooks registered, `image` knows a .qcs file by its first bytes whatever its name,
/// in both versions, and reads the picture `qcs::decode` draws.
#[test]
fn image_knows_qcs_files_by_content() {
    qcs::register_image_hooks();
    let img = image::open(format!("{}/assets/rocket.png", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let img = img.thumbnail_exact(96, 64);
    for opts in [EncodeOptions::default(), levels_only()] {
        let bytes = encode(&img, &opts).unwrap();
        let reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
            .with_guessed_format()
            .unwrap();
        let back = reader
            .decode()
            .unwrap_or_else(|e| panic!("version {}: {e}", bytes[2] >> 5));
        let d = decode(&bytes, &DecodeOptions::default()).unwrap();
        assert_eq!(
            back.to_rgb8(),
            d.image.to_rgb8(),
            "version {}",
            bytes[2] >> 5
        );
    }
}

/// A lossy file keeps what is wholly opaque or transparent so: the encoder aims its alpha past
/// 0 and 255 there, and the decoder's clamp lands on them (without it, a fifth of an opaque
/// photograph's pixels decoded to 254, and every one of a file of levels only). Pixels near
/// a soft edge may move; those away from it may not.
#[test]
fn lossy_alpha_stays_opaque_and_transparent() {
    let rgb = image::open(format!("{}/assets/rocket.png", env!("CARGO_MANIFEST_DIR")))
        .unwrap()
        .to_rgb8();
    // Transparent on the left, a ramp over 32 columns, opaque on the right; the whole of it
    // opaque.
    let alpha = |x: u32| (x.saturating_sub(200) * 8).min(255) as u8;
    // Levels only too, opaque: their samples' colours reach 255 by overshooting it.
    for (ramp, opts) in [
        (true, EncodeOptions::default()),
        (false, EncodeOptions::default()),
        (false, levels_only()),
    ] {
        let img = image::RgbaImage::from_fn(rgb.width(), rgb.height(), |x, y| {
            let [r, g, b] = rgb.get_pixel(x, y).0;
            image::Rgba([r, g, b, if ramp { alpha(x) } else { 255 }])
        });
        let bytes = encode(&image::DynamicImage::ImageRgba8(img.clone()), &opts).unwrap();
        let d = decode(&bytes, &DecodeOptions::default())
            .unwrap()
            .image
            .to_rgba8();
        for (x, y, p) in d.enumerate_pixels() {
            let want = img.get_pixel(x, y).0[3];
            let far = !(196..240).contains(&x);
            if (want == 0 || want == 255) && far {
                assert_eq!(p.0[3], want, "ramp {ramp}: alpha at ({x}, {y})");
            }
        }
    }
}
