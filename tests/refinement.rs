//! Format version 3: the refinement after the levels. Lossless round trips of every layout at
//! odd sizes, every prefix a picture that never gets worse, the push decoder against the
//! one-shot decode, targets kept, pictures at other sizes.

use qcs::container::ParserOptions;
use qcs::{decode, encode, DecodeOptions, EncodeOptions, StreamDecoder, Target};

fn photo(name: &str) -> image::DynamicImage {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    image::open(dir.join(name)).expect("test photo")
}

/// A picture with edges, gradients and noise in every channel.
fn synthetic(w: u32, h: u32, channels: u8) -> image::DynamicImage {
    let mut s = 12345u32;
    let mut px = Vec::with_capacity((w * h) as usize * channels as usize);
    for y in 0..h {
        for x in 0..w {
            for c in 0..channels as u32 {
                s = s.wrapping_mul(1664525).wrapping_add(1013904223);
                let edge = if (x + 2 * y + 7 * c) % 23 < 11 { 60 } else { 0 };
                let v = (x * 5 + y * 3 + c * 40 + edge + (s >> 29)) % 256;
                px.push(v as u8);
            }
        }
    }
    match channels {
        1 => image::GrayImage::from_raw(w, h, px).unwrap().into(),
        2 => image::GrayAlphaImage::from_raw(w, h, px).unwrap().into(),
        3 => image::RgbImage::from_raw(w, h, px).unwrap().into(),
        _ => image::RgbaImage::from_raw(w, h, px).unwrap().into(),
    }
}

fn mse(a: &[u8], b: &[u8]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (x as f64 - y as f64).powi(2))
        .sum::<f64>()
        / a.len() as f64
}

fn lossless() -> EncodeOptions {
    EncodeOptions {
        target: Target::Lossless,
        ..Default::default()
    }
}

#[test]
fn lossless_is_exact_for_every_layout_and_odd_sizes() {
    for channels in 1..=4u8 {
        for (w, h) in [(1, 1), (1, 37), (29, 1), (37, 23), (64, 3), (33, 65)] {
            let img = synthetic(w, h, channels);
            let bytes = encode(&img, &lossless()).unwrap();
            let d = decode(&bytes, &DecodeOptions::default()).unwrap();
            assert!(d.is_final && d.refined);
            assert_eq!(d.image.color(), img.color(), "{channels} channels {w}x{h}");
            assert!(
                d.image.as_bytes() == img.as_bytes(),
                "{channels} channels {w}x{h}"
            );
        }
    }
    let img = photo("coffee-150x100.png");
    let bytes = encode(&img, &lossless()).unwrap();
    let d = decode(&bytes, &DecodeOptions::default()).unwrap();
    assert!(d.image.to_rgb8() == img.to_rgb8());
}

/// Lossless files are smaller than the same pixels as a PNG at `image`'s best compression
/// (a bound: `examples/peers.py` compares with an optimised PNG).
#[test]
fn lossless_is_smaller_than_png() {
    for name in [
        "coffee-150x100.png",
        "astronaut-128x128.png",
        "seashore-100x100.png",
    ] {
        let img = photo(name);
        let qcs = encode(&img, &lossless()).unwrap().len();
        let mut png = Vec::new();
        let enc = image::codecs::png::PngEncoder::new_with_quality(
            &mut png,
            image::codecs::png::CompressionType::Best,
            image::codecs::png::FilterType::Adaptive,
        );
        img.write_with_encoder(enc).unwrap();
        assert!(qcs < png.len(), "{name}: {qcs} bytes, PNG {}", png.len());
    }
}

/// Every prefix of a file is a picture, and a longer prefix is never noticeably worse: the
/// squared error goes down with the bytes (by at most 3% up at a step, where a coefficient
/// becomes significant on the wrong side of its interval's middle; over the refinement as a
/// whole it falls many times over).
#[test]
fn every_prefix_is_a_picture_that_improves() {
    let img = photo("astronaut-128x128.png");
    let rgb = img.to_rgb8();
    let bytes = encode(&img, &EncodeOptions::default()).unwrap();
    let info = qcs::container::inspect(&bytes);
    let start = info.refinement_offset.expect("a refinement") as usize;
    let mut prev = f64::MAX;
    let mut first = None;
    for cut in start..=bytes.len() {
        let d = decode(&bytes[..cut], &DecodeOptions::default()).unwrap();
        // The refinement's picture from the end of its header (at most 16 bytes in).
        assert!(d.refined || cut < start + 16, "cut {cut}");
        if !d.refined {
            continue;
        }
        assert_eq!(d.is_final, cut == bytes.len());
        let e = mse(d.image.to_rgb8().as_raw(), rgb.as_raw());
        assert!(e <= prev * 1.03, "cut {cut}: {e} after {prev}");
        prev = prev.min(e);
        first.get_or_insert(e);
    }
    assert!(prev * 20.0 < first.unwrap(), "{prev} from {first:?}");
}

/// The push decoder fed in pieces draws what the one-shot decode of the same prefix draws.
#[test]
fn the_push_decoder_follows_the_bytes() {
    let img = synthetic(70, 45, 4);
    let bytes = encode(&img, &EncodeOptions::default()).unwrap();
    let mut dec = StreamDecoder::new(qcs::Limits::default());
    let mut have = 0;
    for piece in [1usize, 7, 3, 50, 2, 200, 31].iter().cycle() {
        let end = (have + piece).min(bytes.len());
        dec.push(&bytes[have..end]).unwrap();
        have = end;
        if dec.header().is_some() {
            let pic = dec.render(qcs::Method::Gouraud, 70, 45).unwrap();
            let one = decode(&bytes[..have], &DecodeOptions::default()).unwrap();
            assert!(pic.decoded().image == one.image, "at {have} bytes");
            assert_eq!(pic.is_final(), have == bytes.len());
        }
        if have == bytes.len() {
            break;
        }
    }
}

/// Higher quality: more bytes and a closer picture; a size target is kept.
#[test]
fn targets_are_kept() {
    let img = photo("coffee-150x100.png");
    let rgb = img.to_rgb8();
    let mut last = (0usize, f64::MAX);
    for q in [10u8, 40, 70, 85, 95] {
        let bytes = encode(
            &img,
            &EncodeOptions {
                target: Target::Quality(q),
                ..Default::default()
            },
        )
        .unwrap();
        let d = decode(&bytes, &DecodeOptions::default()).unwrap();
        let e = mse(d.image.to_rgb8().as_raw(), rgb.as_raw());
        assert!(
            bytes.len() > last.0 && e < last.1,
            "quality {q}: {} bytes, mse {e}",
            bytes.len()
        );
        last = (bytes.len(), e);
    }
    for size in [200u64, 1000, 4000, 12000] {
        let bytes = encode(
            &img,
            &EncodeOptions {
                target: Target::Size(size),
                ..Default::default()
            },
        )
        .unwrap();
        assert!(
            bytes.len() as u64 <= size,
            "{} bytes for {size}",
            bytes.len()
        );
        assert!(
            bytes.len() as u64 >= size * 3 / 4,
            "{} bytes for {size}",
            bytes.len()
        );
    }
    // A camera's Exif, last in the file, is inside the size too, and every byte before it
    // is the picture's: a cut just before it draws the same picture.
    let exif = [b"MM\0*\0\0\0\x08\0\0\0\0\0\0".as_slice(), &[7; 3000]].concat();
    let opts = EncodeOptions {
        target: Target::Size(4000),
        exif: Some(exif.clone()),
        ..Default::default()
    };
    let bytes = encode(&img, &opts).unwrap();
    assert!(bytes.len() <= 4000, "{} bytes", bytes.len());
    let whole = decode(&bytes, &DecodeOptions::default()).unwrap();
    assert_eq!(whole.exif, Some(exif.clone()));
    let before = bytes.len() - exif.len() - 7; // tag, two length bytes, CRC
    let cut = decode(&bytes[..before], &DecodeOptions::default()).unwrap();
    assert_eq!((cut.exif, cut.image), (None, whole.image));
}

/// The picture at another size is the image-size picture averaged over each output pixel
/// (or interpolated, larger); a thumbnail draws about the same from the coarse streams only,
/// as the push decoder's does.
#[test]
fn pictures_and_thumbnails_at_other_sizes() {
    let img = photo("coffee-150x100.png");
    let bytes = encode(&img, &EncodeOptions::default()).unwrap();
    let full = decode(&bytes, &DecodeOptions::default()).unwrap();
    for (w, h) in [(75, 50), (37, 25), (19, 12), (150, 100), (200, 90)] {
        let opts = DecodeOptions {
            size: Some((w, h)),
            ..Default::default()
        };
        let small = decode(&bytes, &opts).unwrap();
        assert_eq!((small.image.width(), small.image.height()), (w, h));
        if w <= 150 && h <= 100 {
            // The mean of the full picture over each output pixel's area, in floating point.
            let f = full.image.to_rgb8();
            let (sx, sy) = (150.0 / w as f64, 100.0 / h as f64);
            let overlap =
                |a: f64, b: f64, p: u32| (b.min(p as f64 + 1.0) - a.max(p as f64)).max(0.0);
            let s = small.image.to_rgb8();
            for (x, y, px) in s.enumerate_pixels() {
                let (x0, y0) = (x as f64 * sx, y as f64 * sy);
                let (mut acc, mut area) = ([0.0f64; 3], 0.0);
                for v in y0 as u32..((y0 + sy).ceil() as u32).min(100) {
                    for u in x0 as u32..((x0 + sx).ceil() as u32).min(150) {
                        let a = overlap(x0, x0 + sx, u) * overlap(y0, y0 + sy, v);
                        area += a;
                        for (sum, &v) in acc.iter_mut().zip(&f.get_pixel(u, v).0) {
                            *sum += a * v as f64;
                        }
                    }
                }
                for (&got, sum) in px.0.iter().zip(acc) {
                    let want = sum / area;
                    assert!(
                        (got as f64 - want).abs() <= 0.5 + 1e-9,
                        "{w}x{h} at ({x}, {y}): {got} vs {want}"
                    );
                }
            }
        }
        let thumb = decode(&bytes, &DecodeOptions::thumbnail(w, h)).unwrap();
        let e = mse(
            thumb.image.to_rgb8().as_raw(),
            small.image.to_rgb8().as_raw(),
        );
        assert!(e < 20.0, "{w}x{h}: thumbnail mse {e} against the picture");
        let mut dec = StreamDecoder::with_options(ParserOptions::default());
        dec.push(&bytes).unwrap();
        let pushed = dec.render_thumbnail(qcs::Method::Gouraud, w, h).unwrap();
        assert!(pushed.decoded().image == thumb.image, "{w}x{h}");
    }
}
