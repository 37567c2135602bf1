//! Streaming decode costs on `assets/rocket.png` (480 × 320, default encode options):
//! cost per push (1 B, 64 B, 4 KiB chunks), the whole file byte by byte against one-shot
//! `qcs::decode` (the target is ≤ 2×; the ratio is printed), and preview renders at 256 × 256
//! and at 1 Mpixel from 1 %, 10 % and 100 % of the file.
//!
//! Run: `cargo bench --bench stream -- --warm-up-time 1 --measurement-time 3`
//!
//! Instruction counts: `QCS_ONCE=gouraud:100:256 valgrind --tool=callgrind target/release/deps/stream-*`
//! renders one preview (method, percent of the file, side) 5 times instead of running criterion.

use std::hint::black_box;
use std::time::Instant;

use criterion::{criterion_group, BenchmarkId, Criterion, Throughput};
use qcs::{DecodeOptions, Limits, Method, StreamDecoder};

fn file() -> Vec<u8> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/rocket.png");
    let img = image::open(path).expect("assets/rocket.png");
    qcs::encode(&img, &Default::default()).expect("encode")
}

/// Pushes all of `bytes` in `chunk`-byte pieces, then renders the final picture at `size`.
fn stream(bytes: &[u8], chunk: usize, size: (u32, u32)) -> usize {
    let mut dec = StreamDecoder::new(Limits::default());
    for c in bytes.chunks(chunk) {
        dec.push(c).expect("push");
    }
    let pic = dec.render(Method::Gouraud, size.0, size.1).expect("render");
    pic.decoded().samples_used as usize
}

fn one_shot(bytes: &[u8]) -> usize {
    let img = qcs::decode(bytes, &DecodeOptions::default()).expect("decode");
    img.samples_used as usize
}

/// Mean seconds per call of `f` over at least `min` seconds.
fn mean_secs(min: f64, mut f: impl FnMut()) -> f64 {
    let t = Instant::now();
    let mut n = 0u32;
    while n == 0 || t.elapsed().as_secs_f64() < min {
        f();
        n += 1;
    }
    t.elapsed().as_secs_f64() / n as f64
}

fn bench(c: &mut Criterion) {
    let bytes = file();
    let len = bytes.len();
    let (w, h) = (480, 320);
    eprintln!("rocket.qcs: {len} bytes");

    // Ratio byte-by-byte / one-shot, both ending in a full-size Gouraud render.
    let one = mean_secs(2.0, || {
        black_box(one_shot(&bytes));
    });
    let byte = mean_secs(2.0, || {
        black_box(stream(&bytes, 1, (w, h)));
    });
    eprintln!(
        "byte-by-byte push + final render: {:.2} ms, one-shot decode: {:.2} ms, ratio {:.2}",
        byte * 1e3,
        one * 1e3,
        byte / one
    );

    let mut push = c.benchmark_group("push");
    push.sample_size(10);
    push.throughput(Throughput::Bytes(len as u64));
    for chunk in [1usize, 64, 4096] {
        push.bench_with_input(BenchmarkId::new("whole_file", chunk), &chunk, |b, &k| {
            b.iter(|| {
                let mut dec = StreamDecoder::new(Limits::default());
                for piece in bytes.chunks(k) {
                    dec.push(piece).expect("push");
                }
                black_box(dec.samples_available())
            })
        });
    }
    push.finish();

    let mut whole = c.benchmark_group("decode_whole");
    whole.sample_size(10);
    whole.throughput(Throughput::Bytes(len as u64));
    whole.bench_function("one_shot", |b| b.iter(|| black_box(one_shot(&bytes))));
    whole.bench_function("byte_by_byte_then_render", |b| {
        b.iter(|| black_box(stream(&bytes, 1, (w, h))))
    });
    whole.finish();

    let mut prev = c.benchmark_group("preview");
    prev.sample_size(10);
    for pct in [1usize, 10, 100] {
        let cut = (len * pct / 100).max(1);
        let mut dec = StreamDecoder::new(Limits::default());
        dec.push(&bytes[..cut]).expect("push");
        let _ = dec.render(Method::Gouraud, 8, 8); // triangulate outside the timing
        eprintln!("{pct}% = {cut} bytes: {} samples", dec.samples_available());
        for (name, size) in [("256x256", (256u32, 256u32)), ("1mpx", (1024, 1024))] {
            prev.throughput(Throughput::Elements(size.0 as u64 * size.1 as u64));
            for method in [Method::Gouraud, Method::Shepard] {
                let id = BenchmarkId::new(format!("{method:?}_{name}"), format!("{pct}pct"));
                prev.bench_function(id, |b| {
                    b.iter(|| black_box(dec.render(method, size.0, size.1).map(|p| p.is_final())))
                });
            }
        }
    }
    prev.finish();
}

criterion_group!(benches, bench);

/// `QCS_ONCE=gouraud|shepard:pct:side`: 5 preview renders (for instruction counting).
fn once(spec: &str) {
    let v: Vec<&str> = spec.split(':').collect();
    let method = if v[0] == "shepard" {
        Method::Shepard
    } else {
        Method::Gouraud
    };
    let pct: usize = v[1].parse().expect("pct");
    let side: u32 = v[2].parse().expect("side");
    let bytes = file();
    let mut dec = StreamDecoder::new(Limits::default());
    dec.push(&bytes[..(bytes.len() * pct / 100).max(1)])
        .expect("push");
    let _ = dec.render(method, 8, 8);
    for _ in 0..5 {
        black_box(dec.render(method, side, side).map(|p| p.is_final()).ok());
    }
}

fn main() {
    if let Ok(spec) = std::env::var("QCS_ONCE") {
        once(&spec);
        return;
    }
    benches();
    criterion::Criterion::default()
        .configure_from_args()
        .final_summary();
}
