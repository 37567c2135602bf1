//! Profiling aid: canonical cells of 65536 sites against spade bulk loading and rendering.
use qcs::reconstruction::{Method, RenderOptions, SampleSet};
use qcs::sites::Quasicrystal;
use std::time::Instant;
fn main() {
    let qc = Quasicrystal::new(1024, 1024).expect("frame");
    let sites = qc.first(65536);
    for _ in 0..3 {
        let mut set = SampleSet::new(1024, 1024, 1);
        let mut plain = SampleSet::new(1024, 1024, 1);
        for s in &sites {
            set.push_exact(s.pos, s.lattice, &[0]);
            plain.push(s.pos, &[0]);
        }
        let t = Instant::now();
        let _ = set.triangulation();
        let tb = t.elapsed();
        let t = Instant::now();
        let n = set.cells().map_or(0, |c| c.len());
        let tc = t.elapsed();
        let _ = plain.triangulation();
        let t = Instant::now();
        let _ = plain.render_with(
            Method::Gouraud,
            1024,
            1024,
            RenderOptions::single_threaded(),
        );
        let tr = t.elapsed();
        let t = Instant::now();
        let _ = set.render_with(
            Method::Gouraud,
            1024,
            1024,
            RenderOptions::single_threaded(),
        );
        let tx = t.elapsed();
        println!(
            "{n} cells: bulk load {tb:?}, cells {tc:?}, plain render {tr:?}, cells render {tx:?}"
        );
    }
}
