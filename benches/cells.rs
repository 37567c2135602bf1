//! Canonical Delaunay cells against spade's plain triangles: 1 Mpixel Gouraud render,
//! single-threaded, same quasicrystal sites and colours.
//!
//! * `gouraud_plain`: samples pushed without exact points (spade's own split);
//! * `gouraud_cells`: samples pushed with exact points, cells already computed (one-shot
//!   decode renders once, so add `incremental` below for its cost);
//! * `cells_build`: the canonical cells from spade's kept triangulation (`Cells::build`).
//!
//! Group `exact_cells` (16k, 65k, 262k sites on 1024², samples and mirror points) times how
//! the canonical cells are made, from the points alone: `spade_bulk_load` (spade's
//! triangulation only, not yet the cells), `spade_then_exact` (that, then exact flips and
//! merges: `Cells::build`), `incremental` (exact insertion: `Cells::incremental`, what a
//! growing `SampleSet` does) and `atlas` (look-up of local configurations: `Cells::atlas`).
//!
//! Run: `cargo bench --bench cells -- --warm-up-time 1 --measurement-time 3`

mod common;
use common::{photo, SIDE};

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use qcs::lattice::ZZeta;
use qcs::reconstruction::{Cells, Method, RenderOptions, SampleMesh, SampleSet, Vertex};
use qcs::sites::Quasicrystal;
use spade::{Point2, Triangulation as _};

const COUNTS: [usize; 2] = [16_384, 65_536];

fn bench(c: &mut Criterion) {
    let img = photo();
    let single = RenderOptions::single_threaded();
    let qc = Quasicrystal::new(SIDE, SIDE).expect("frame");
    let mut g = c.benchmark_group("cells_1mpx_single");
    g.sample_size(10);
    for &n in &COUNTS {
        let sites = qc.first(n);
        let mut exact = SampleSet::new(SIDE, SIDE, 3);
        let mut plain = SampleSet::new(SIDE, SIDE, 3);
        for s in &sites {
            let (x, y) = (
                (s.pos[0] as u32).min(SIDE - 1),
                (s.pos[1] as u32).min(SIDE - 1),
            );
            let col = img.get_pixel(x, y).0;
            exact.push_exact(s.pos, s.lattice, &col);
            plain.push(s.pos, &col);
        }
        let _ = plain.render_with(Method::Gouraud, 8, 8, single);
        let _ = exact.render_with(Method::Gouraud, 8, 8, single); // computes the cells
        g.bench_function(BenchmarkId::new("gouraud_plain", n), |b| {
            b.iter(|| black_box(plain.render_with(Method::Gouraud, SIDE, SIDE, single)))
        });
        g.bench_function(BenchmarkId::new("gouraud_cells", n), |b| {
            b.iter(|| black_box(exact.render_with(Method::Gouraud, SIDE, SIDE, single)))
        });
        // The mesh's vertices are the samples and their mirror points.
        let lattice: Vec<Option<ZZeta>> = exact.point_lattice().to_vec();
        let mesh = exact.triangulation().clone();
        assert!(Cells::build(&mesh, &lattice).is_some(), "exact cells");
        g.bench_function(BenchmarkId::new("cells_build", n), |b| {
            b.iter(|| black_box(Cells::build(&mesh, &lattice).map(|c| c.len())))
        });
    }
    g.finish();
}

fn exact_cells(c: &mut Criterion) {
    let mut g = c.benchmark_group("exact_cells");
    g.sample_size(10);
    for n in [16_384, 65_536, 262_144] {
        let mut set = SampleSet::new(SIDE, SIDE, 1);
        for s in Quasicrystal::new(SIDE, SIDE).expect("frame").first(n) {
            set.push_exact(s.pos, s.lattice, &[0]);
        }
        let lattice = set.point_lattice().to_vec();
        let vertices: Vec<Vertex> = set
            .points()
            .iter()
            .enumerate()
            .map(|(k, p)| Vertex {
                position: Point2::new(p[0], p[1]),
                index: k as u32,
            })
            .collect();
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function(BenchmarkId::new("spade_bulk_load", n), |b| {
            b.iter(|| {
                let t = SampleMesh::bulk_load_stable(vertices.clone()).expect("spade");
                black_box(t.num_inner_faces())
            })
        });
        g.bench_function(BenchmarkId::new("spade_then_exact", n), |b| {
            b.iter(|| {
                let t = SampleMesh::bulk_load_stable(vertices.clone()).expect("spade");
                black_box(Cells::build(&t, &lattice).map(|c| c.len()))
            })
        });
        g.bench_function(BenchmarkId::new("incremental", n), |b| {
            b.iter(|| black_box(Cells::incremental(set.points(), &lattice).map(|c| c.len())))
        });
        g.bench_function(BenchmarkId::new("atlas", n), |b| {
            b.iter(|| black_box(Cells::atlas(set.points(), &lattice).map(|c| c.len())))
        });
    }
    g.finish();
}

criterion_group!(benches, bench, exact_cells);
criterion_main!(benches);
