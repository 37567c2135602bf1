//! Camera-size speed through the public API, for a 12-megapixel photo (4000 × 3000)
//! and a 0.3-megapixel one (672 × 448), both `assets/rocket.png` (480 × 320) resized with
//! `image`'s CatmullRom filter (the 12 MP one cropped at the centre to 4:3 after resizing to
//! 4500 × 3000, `resize_to_fill`). Both are upscaled, so smoother than a camera's pictures of
//! that size: the figures show how the codec scales, not what a real photo costs.
//!
//! * `encode`: `qcs::encode` with the default options;
//! * `decode`: `qcs::decode` of the whole file at the image's size;
//! * `thumbnail`: a 1/8-size thumbnail of the whole file (`DecodeOptions::thumbnail`);
//! * `first_preview` (12 MP only): the first 1024 bytes decoded at 1000 × 750, what a viewer
//!   shows first of a cut download (the aim: ≤ 50 ms): the plain render
//!   (`DecodeOptions::size`) and `first_preview_thumbnail` (`DecodeOptions::thumbnail`, what
//!   `qcs decode --size` does unless given `--no-thumbnail`).
//!
//! Each file is encoded once, outside the timing. Throughput is the photo's pixels (Mpx/s),
//! except for the first previews: their 1000 × 750 output pixels. 10 flat samples; the 12 MP group
//! measures for 5 s (longer when 10 calls take longer), whatever the command line says. Work
//! runs on the default rayon pool (every core).
//!
//! Run: `cargo bench --bench photo -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use image::{imageops::FilterType, DynamicImage};
use qcs::DecodeOptions;

/// `assets/rocket.png` resized (CatmullRom) to fill `w × h`, cropped at the centre.
fn photo(w: u32, h: u32) -> DynamicImage {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/rocket.png");
    let img = image::open(path).expect("assets/rocket.png");
    img.resize_to_fill(w, h, FilterType::CatmullRom)
}

/// The cases for `img`; `big`: the 12 MP settings and the first preview.
fn cases(c: &mut Criterion, name: &str, img: &DynamicImage, big: bool) {
    let (w, h) = (img.width(), img.height());
    let bytes = qcs::encode(img, &Default::default()).expect("encode");
    eprintln!("{name}: {w}×{h}, {} bytes", bytes.len());

    let mut g = c.benchmark_group(name);
    g.sample_size(10).sampling_mode(SamplingMode::Flat);
    if big {
        g.measurement_time(Duration::from_secs(5));
    }
    g.throughput(Throughput::Elements(w as u64 * h as u64));
    g.bench_function("encode", |b| {
        b.iter(|| black_box(qcs::encode(img, &Default::default()).expect("encode")))
    });
    let whole = DecodeOptions::default();
    g.bench_function("decode", |b| {
        b.iter(|| black_box(qcs::decode(&bytes, &whole).expect("decode")))
    });
    let thumb = DecodeOptions::thumbnail(w / 8, h / 8);
    g.bench_function(format!("thumbnail_{}x{}", w / 8, h / 8), |b| {
        b.iter(|| black_box(qcs::decode(&bytes, &thumb).expect("thumbnail")))
    });
    if big {
        let first = DecodeOptions {
            size: Some((1000, 750)),
            max_bytes: Some(1024),
            ..Default::default()
        };
        let d = qcs::decode(&bytes, &first).expect("preview");
        eprintln!("{name}: first 1024 bytes: {} samples", d.samples_used);
        g.throughput(Throughput::Elements(1000 * 750));
        let small = DecodeOptions {
            max_bytes: Some(1024),
            ..DecodeOptions::thumbnail(1000, 750)
        };
        for (id, opts) in [
            ("first_preview", &first),
            ("first_preview_thumbnail", &small),
        ] {
            g.bench_function(format!("{id}_1KiB_1000x750"), |b| {
                b.iter(|| black_box(qcs::decode(&bytes, opts).expect("preview")))
            });
        }
    }
    g.finish();
}

fn bench(c: &mut Criterion) {
    cases(c, "photo_12mpx", &photo(4000, 3000), true);
    cases(c, "photo_0.3mpx", &photo(672, 448), false);
}

criterion_group!(benches, bench);
criterion_main!(benches);
