//! The predictive colour coding alone (no container, no rendering), one core: encoding and
//! decoding every level of 16k, 65k and 262k samples of `assets/rocket.png` resized to
//! 1024 × 1024, at the encoder's default quality (75). Levels as in a file (the header's
//! schedule, first level 127); colours are the pixels at the sites.
//!
//! Run: `cargo bench --bench coding -- --warm-up-time 1 --measurement-time 3`

mod common;
use common::{photo, SIDE};

use std::hint::black_box;

use criterion::{criterion_group, BenchmarkId, Criterion, Throughput};
use qcs::coding::predictive::{Params, PredictiveDecoder, PredictiveEncoder};
use qcs::container::{Header, Layout};
use qcs::sites::{fixed_position, Quasicrystal};

const COUNTS: [usize; 3] = [16_384, 65_536, 262_144];

fn bench(c: &mut Criterion) {
    let img = photo();
    let q = Quasicrystal::new(SIDE, SIDE).expect("frame");
    let params = Params::from_quality(75);
    let mut g = c.benchmark_group("predictive_1mpx");
    g.sample_size(10);
    for n in COUNTS {
        let sites = q.first(n);
        let pos: Vec<[i64; 2]> = sites
            .iter()
            .map(|s| fixed_position(&q.frame(), s.lattice))
            .collect();
        let rgb: Vec<u8> = sites
            .iter()
            .flat_map(|s| {
                let x = (s.pos[0] as u32).min(SIDE - 1);
                let y = (s.pos[1] as u32).min(SIDE - 1);
                img.get_pixel(x, y).0
            })
            .collect();
        let header = Header::new(SIDE, SIDE, Layout::Rgb, n as u64, 127, params.coding());
        let levels: Vec<(usize, usize)> = (0..header.level_count())
            .filter_map(|k| header.level_range(k))
            .map(|r| (r.start as usize, r.end as usize))
            .collect();
        let encode = || {
            let mut enc = PredictiveEncoder::new(params, 3, SIDE, SIDE).expect("encoder");
            let mut payloads = Vec::new();
            for &(s, e) in &levels {
                let level = enc.encode_level(&pos[s..e], &rgb[s * 3..e * 3]);
                payloads.push(level.expect("level"));
            }
            payloads
        };
        let payloads = encode();
        let bytes: usize = payloads.iter().map(Vec::len).sum();
        eprintln!("{n} samples: {bytes} payload bytes");
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function(BenchmarkId::new("encode", n), |b| {
            b.iter(|| black_box(encode()))
        });
        g.bench_function(BenchmarkId::new("decode", n), |b| {
            b.iter(|| {
                let mut dec = PredictiveDecoder::new(params, 3, SIDE, SIDE).expect("decoder");
                let mut out = Vec::with_capacity(n * 3);
                for (&(s, e), payload) in levels.iter().zip(&payloads) {
                    dec.start_level(&pos[s..e], payload.len()).expect("level");
                    dec.push(payload, &mut out).expect("payload");
                }
                assert_eq!(out.len(), n * 3);
                black_box(out)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
}
