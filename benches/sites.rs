//! Ordered quasicrystal site sequences of 10^4, 10^5 and 10^6 sites (issue target:
//! 10^6 in under 100 ms on one core).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use qcs::sites::Quasicrystal;

fn sites(c: &mut Criterion) {
    let mut g = c.benchmark_group("sites");
    g.sample_size(10);
    for n in [10_000usize, 100_000, 1_000_000] {
        // About one site per pixel at 10^6: a 1024×1024 image.
        let q = Quasicrystal::new(1024, 1024).expect("valid size");
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::new("quasicrystal_1024", n), &n, |b, &n| {
            b.iter(|| q.first(n))
        });
    }
    g.finish();
}

criterion_group!(benches, sites);
criterion_main!(benches);
