//! The encoder's sample colours, one core: the progressive area mean and the fitted colours
//! (`SampleColour::Fitted`: a Gouraud render of every complete level after the first, at the
//! source size) of 16k, 65k and 262k sites of `assets/rocket.png` resized to 1024 × 1024,
//! first level 127 as in a default file.
//!
//! Run: `cargo bench --bench sampling -- --warm-up-time 1 --measurement-time 5`

mod common;
use common::{photo, pool, SIDE};

use std::hint::black_box;

use criterion::{criterion_group, BenchmarkId, Criterion, Throughput};
use qcs::sampling::{SampleColour, SourceImage};
use qcs::sites::Quasicrystal;

const COUNTS: [usize; 3] = [16_384, 65_536, 262_144];

fn bench(c: &mut Criterion) {
    let img = photo();
    let src = SourceImage::new(img.as_raw(), SIDE, SIDE, 3).expect("source");
    let q = Quasicrystal::new(SIDE, SIDE).expect("frame");
    let one_core = pool(1);
    let mut g = c.benchmark_group("sample_colours_1mpx");
    g.sample_size(10);
    for n in COUNTS {
        let sites = q.first(n);
        let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function(BenchmarkId::new("progressive", n), |b| {
            b.iter(|| black_box(src.colours(&pos, SampleColour::Progressive, n)))
        });
        g.bench_function(BenchmarkId::new("fitted", n), |b| {
            b.iter(|| one_core.install(|| black_box(src.fitted(&sites, q.frame(), 127, n))))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
}
