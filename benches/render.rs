//! Rendering cost at 1 Mpixel (1024 × 1024), single-threaded, against JPEG decoding.
//!
//! `decode_1mpx` times the whole one-shot `qcs::decode` of a `.qcs` file of the photograph
//! (default coding, 16k / 65k / 262k samples) on a one-thread pool (and on two threads, where
//! the cells are built while the colours decode and the bands render in parallel), and `image` decoding a
//! baseline and a progressive JPEG of the same photograph with the quality whose file size is
//! nearest to the `.qcs` file's (sizes printed).
//!
//! Sites: a jittered grid (the quasicrystal sampler is developed in parallel), colour = the
//! pixel of `assets/rocket.png` (resized to 1024 × 1024) containing the site.
//!
//! Run: `cargo bench --bench render -- --warm-up-time 1 --measurement-time 3`
//!
//! `render_1mpx_single/raster_only` is `rasterise` on spade's triangles (prepared once, with
//! the painted mask it returns); `gouraud` is the whole render from the sample set: point
//! and triangle set-up, binning, rasterising, the outside-the-hull rule (nothing to do here:
//! the hull of the samples and mirror points holds the picture, so no mask is kept); `cubic`
//! the same with the cubic patches (gradients estimated, then a patch per triangle).
//! `render_thumbnail_single` renders a 128 × 128 thumbnail by Shepard from the same sets.
//!
//! Instruction counts (stable on a loaded machine): `QCS_ONCE=<workload>` runs one workload a
//! fixed number of times instead of criterion, e.g.
//! `QCS_ONCE=gouraud:65536 valgrind --tool=callgrind --toggle-collect='*render_with*' target/release/deps/render-*`
//! (workloads: `gouraud:N`, `cubic:N`, `shepard:N`, `natural:N`, `raster:N`; `shepard:N:128`
//! renders at 128 × 128).

mod common;
use common::{photo, pool, SIDE};

use std::hint::black_box;
use std::io::Cursor;

use criterion::{criterion_group, BenchmarkId, Criterion, Throughput};
use image::codecs::jpeg::JpegEncoder;
use image::{ImageEncoder, RgbImage};
use qcs::reconstruction::{
    rasterise, triangles, Method, RenderOptions, SampleGrid, SampleMesh, SampleSet, Vertex,
};
use spade::{Point2, Triangulation as _};

const COUNTS: [usize; 3] = [16_384, 65_536, 262_144];
/// Side of the thumbnail renders.
const THUMB: u32 = 128;

/// A jittered `k × k` grid over the picture (k² = n), deterministic.
fn jittered(n: usize) -> Vec<[f64; 2]> {
    let k = (n as f64).sqrt().round() as usize;
    let cell = SIDE as f64 / k as f64;
    let mut s = 0x1234_5678_9ABC_DEF0u64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out = Vec::with_capacity(k * k);
    for j in 0..k {
        for i in 0..k {
            out.push([(i as f64 + rnd()) * cell, (j as f64 + rnd()) * cell]);
        }
    }
    out
}

fn sample_set(img: &RgbImage, sites: &[[f64; 2]]) -> SampleSet {
    let mut set = SampleSet::new(SIDE, SIDE, 3);
    for p in sites {
        let (x, y) = ((p[0] as u32).min(SIDE - 1), (p[1] as u32).min(SIDE - 1));
        set.push(*p, &img.get_pixel(x, y).0);
    }
    set
}

/// Baseline JPEG (image's encoder) with the quality whose size is closest to `target` bytes.
fn jpeg_near(img: &RgbImage, target: usize, progressive: bool) -> (Vec<u8>, u8) {
    let encode = |q: u8| {
        let mut buf = Vec::new();
        if progressive {
            let mut enc = jpeg_encoder::Encoder::new(&mut buf, q);
            enc.set_progressive(true);
            enc.encode(
                img.as_raw(),
                SIDE as u16,
                SIDE as u16,
                jpeg_encoder::ColorType::Rgb,
            )
            .expect("progressive jpeg");
        } else {
            JpegEncoder::new_with_quality(Cursor::new(&mut buf), q)
                .write_image(img.as_raw(), SIDE, SIDE, image::ExtendedColorType::Rgb8)
                .expect("jpeg");
        }
        buf
    };
    (1..=100u8)
        .map(|q| (encode(q), q))
        .min_by_key(|(b, _)| b.len().abs_diff(target))
        .expect("a quality")
}

fn bench(c: &mut Criterion) {
    let img = photo();
    let single = RenderOptions::single_threaded();
    let pixels = (SIDE * SIDE) as u64;

    let mut tri = c.benchmark_group("triangulate");
    tri.sample_size(10);
    for &n in &COUNTS {
        let sites = jittered(n);
        tri.throughput(Throughput::Elements(n as u64));
        tri.bench_with_input(BenchmarkId::new("spade_bulk_load", n), &sites, |b, s| {
            b.iter(|| {
                let v: Vec<Vertex> = s
                    .iter()
                    .enumerate()
                    .map(|(k, p)| Vertex {
                        position: Point2::new(p[0], p[1]),
                        index: k as u32,
                    })
                    .collect();
                black_box(SampleMesh::bulk_load(v).map(|t| t.num_inner_faces()))
            })
        });
        tri.bench_with_input(BenchmarkId::new("sample_set_stable", n), &sites, |b, s| {
            b.iter(|| {
                let mut set = sample_set(&img, s);
                black_box(set.triangulation().num_inner_faces())
            })
        });
        tri.bench_with_input(BenchmarkId::new("shepard_grid", n), &sites, |b, s| {
            b.iter(|| black_box(SampleGrid::new(s).len()))
        });
    }
    tri.finish();

    let mut ras = c.benchmark_group("render_1mpx_single");
    ras.sample_size(10);
    ras.throughput(Throughput::Elements(pixels));
    for &n in &COUNTS {
        let sites = jittered(n);
        let mut set = sample_set(&img, &sites);
        let _ = set.triangulation();
        let _ = set.render_with(Method::Shepard, 8, 8, single); // builds the grid
        let tris = {
            let cols = set.colours().to_vec();
            triangles(set.triangulation(), &cols, 3, [1.0, 1.0])
        };
        ras.bench_function(BenchmarkId::new("raster_only", n), |b| {
            b.iter(|| black_box(rasterise(&tris, SIDE, SIDE, 3)))
        });
        ras.bench_function(BenchmarkId::new("gouraud", n), |b| {
            b.iter(|| black_box(set.render_with(Method::Gouraud, SIDE, SIDE, single)))
        });
        ras.bench_function(BenchmarkId::new("cubic", n), |b| {
            b.iter(|| black_box(set.render_with(Method::Cubic, SIDE, SIDE, single)))
        });
        ras.bench_function(BenchmarkId::new("shepard", n), |b| {
            b.iter(|| black_box(set.render_with(Method::Shepard, SIDE, SIDE, single)))
        });
    }
    ras.finish();

    // A 128 × 128 thumbnail (many samples per output pixel).
    let mut thumb = c.benchmark_group("render_thumbnail_single");
    thumb.sample_size(10);
    thumb.throughput(Throughput::Elements(THUMB as u64 * THUMB as u64));
    for &n in &COUNTS {
        let mut set = sample_set(&img, &jittered(n));
        let _ = set.render_with(Method::Shepard, 8, 8, single); // builds the grid
        thumb.bench_function(BenchmarkId::new("shepard", n), |b| {
            b.iter(|| black_box(set.render_with(Method::Shepard, THUMB, THUMB, single)))
        });
    }
    thumb.finish();

    // The whole one-shot decode of a real .qcs file (default coding, N samples) on one core,
    // beside `image` decoding a JPEG of the same photograph and the same file size.
    let one_core = pool(1);
    let two_cores = pool(2);
    let mut dec = c.benchmark_group("decode_1mpx");
    dec.sample_size(10);
    dec.throughput(Throughput::Elements(pixels));
    let photo = image::DynamicImage::ImageRgb8(img.clone());
    for &n in &COUNTS {
        let opts = qcs::EncodeOptions {
            samples: Some(n as u64),
            ..Default::default()
        };
        let file = qcs::encode(&photo, &opts).expect("qcs encode");
        eprintln!("qcs file for {n} samples: {} bytes", file.len());
        for (name, pool) in [("qcs_one_core", &one_core), ("qcs_two_cores", &two_cores)] {
            dec.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| {
                    pool.install(|| {
                        black_box(qcs::decode(&file, &Default::default()).map(|d| d.image.width()))
                    })
                })
            });
        }
        for progressive in [false, true] {
            let (jpeg, q) = jpeg_near(&img, file.len(), progressive);
            let name = if progressive {
                "jpeg_progressive"
            } else {
                "jpeg_baseline"
            };
            eprintln!("{name} for {n} samples: quality {q}, {} bytes", jpeg.len());
            dec.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| black_box(image::load_from_memory(&jpeg).map(|i| i.width())))
            });
        }
    }
    dec.finish();
}

/// `QCS_ONCE=method:count[:side]`: render that workload 5 times (for instruction counting),
/// at `side × side` pixels (default 1024).
fn once(spec: &str) {
    let mut parts = spec.split(':');
    let name = parts.next().expect("QCS_ONCE=method:count[:side]");
    let n: usize = parts.next().and_then(|n| n.parse().ok()).expect("count");
    let side: u32 = parts.next().map_or(SIDE, |s| s.parse().expect("side"));
    let img = photo();
    let sites = jittered(n);
    let mut set = sample_set(&img, &sites);
    let _ = set.triangulation();
    let single = RenderOptions::single_threaded();
    let method = match name {
        "gouraud" => Method::Gouraud,
        "shepard" => Method::Shepard,
        "natural" => Method::Natural,
        "cubic" => Method::Cubic,
        "raster" => {
            let tris = {
                let cols = set.colours().to_vec();
                triangles(set.triangulation(), &cols, 3, [1.0, 1.0])
            };
            for _ in 0..5 {
                black_box(rasterise(&tris, SIDE, SIDE, 3));
            }
            return;
        }
        other => panic!("unknown workload {other}"),
    };
    let _ = set.render_with(method, 8, 8, single); // builds the grid outside the count
    for _ in 0..5 {
        black_box(set.render_with(method, side, side, single));
    }
}

criterion_group!(benches, bench);

fn main() {
    if let Ok(spec) = std::env::var("QCS_ONCE") {
        once(&spec);
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
