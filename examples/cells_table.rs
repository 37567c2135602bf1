//! Canonical Delaunay cells (issue #11): cell statistics, Gouraud PSNR of the centroid rule
//! against `spade`'s own split, monotone sharpening, and a census of the local configurations
//! (the premise of a triangulation that would look them up rather than compute them, #4).
//!
//! Run: `cargo run --release --example cells_table -- [stats] [psnr] [monotone] [atlas] [DIR]`
//! (default: all four parts on `../shared/corpus/dev`, or `/work/shared/corpus/dev`).
//!
//! Sites: the quasicrystal sequence in the default frame; sample colour: area mean
//! (`SampleColour::Area`) for a file of exactly N samples; picture rendered at source size.
//! "spade" pushes the same samples without exact lattice points, so the triangulation's own
//! split of cocircular cells is drawn.

use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::PathBuf;
use std::time::Instant;

use qcs::lattice::ZZeta;
use qcs::reconstruction::{Method, SampleSet};
use qcs::sampling::{SampleColour, SourceImage};
use qcs::sites::Quasicrystal;

fn psnr(a: &[u8], b: &[u8]) -> f64 {
    let se: f64 = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| {
            let d = x as f64 - y as f64;
            d * d
        })
        .sum();
    let mse = se / a.len() as f64;
    10.0 * (255.0 * 255.0 / mse.max(1e-12)).log10()
}

struct Photo {
    name: String,
    w: u32,
    h: u32,
    rgb: Vec<u8>,
}

fn photos(dir: &PathBuf) -> Vec<Photo> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect())
        .unwrap_or_default();
    files.retain(|p| p.extension().is_some_and(|e| e == "png"));
    files.sort();
    files
        .into_iter()
        .filter_map(|p| {
            let img = image::open(&p).ok()?.to_rgb8();
            Some(Photo {
                name: p.file_stem()?.to_string_lossy().into_owned(),
                w: img.width(),
                h: img.height(),
                rgb: img.into_raw(),
            })
        })
        .collect()
}

/// Gouraud PSNR with the canonical rule and with spade's split, for the first `n` sites,
/// coloured by `rule` for a file of `total` samples (`None`: a file of exactly `n`).
fn both(
    photo: &Photo,
    src: &SourceImage<'_>,
    qc: &Quasicrystal,
    n: usize,
    rule: SampleColour,
    total: Option<usize>,
) -> (f64, f64) {
    let sites = qc.first(n);
    let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
    let col = src.colours(&pos, rule, total.unwrap_or(n));
    let mut exact = SampleSet::new(photo.w, photo.h, 3);
    let mut plain = SampleSet::new(photo.w, photo.h, 3);
    for (k, s) in sites.iter().enumerate() {
        exact.push_exact(s.pos, s.lattice, &col[3 * k..3 * k + 3]);
        plain.push(s.pos, &col[3 * k..3 * k + 3]);
    }
    let a = exact.render(Method::Gouraud, photo.w, photo.h);
    let b = plain.render(Method::Gouraud, photo.w, photo.h);
    (psnr(&a, &photo.rgb), psnr(&b, &photo.rgb))
}

fn polygon_area(pts: &[[f64; 2]]) -> f64 {
    let k = pts.len();
    (0..k)
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % k]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        .abs()
        / 2.0
}

fn stats() {
    println!("## Cell statistics, 512×512, default frame\n");
    println!("| sites | 3-cells | 4-cells | 5-cells | ≥6 | area in k≥4 | flips | cells time |");
    println!("|---|---|---|---|---|---|---|---|");
    let qc = Quasicrystal::new(512, 512).expect("frame");
    for n in [1089usize, 4225, 16641, 65536] {
        let mut set = SampleSet::new(512, 512, 1);
        for s in qc.first(n) {
            set.push_exact(s.pos, s.lattice, &[0]);
        }
        let _ = set.triangulation();
        let positions = set.points().to_vec();
        let t0 = Instant::now();
        let cells = set.cells().expect("exact").clone();
        let dt = t0.elapsed();
        // Cells of the image: those whose vertex centroid is inside (not mirror-point cells).
        let mut h = [0usize; 16];
        let (mut big, mut all) = (0.0, 0.0);
        for c in cells.iter() {
            let pts: Vec<_> = c.iter().map(|&i| positions[i as usize]).collect();
            let k = pts.len() as f64;
            let cx = pts.iter().map(|p| p[0]).sum::<f64>() / k;
            let cy = pts.iter().map(|p| p[1]).sum::<f64>() / k;
            if !(0.0..512.0).contains(&cx) || !(0.0..512.0).contains(&cy) {
                continue;
            }
            h[c.len().min(15)] += 1;
            let a = polygon_area(&pts);
            all += a;
            if c.len() >= 4 {
                big += a;
            }
        }
        let g = |k: usize| h[k];
        let more: usize = h.iter().skip(6).sum();
        println!(
            "| {n} | {} | {} | {} | {more} | {:.1}% | {} | {:.1} ms |",
            g(3),
            g(4),
            g(5),
            100.0 * big / all,
            cells.flips(),
            dt.as_secs_f64() * 1e3
        );
    }
    println!();
}

/// A vertex star: the cells around a site, each as lattice vectors from it.
type Star = Vec<Vec<[i64; 4]>>;

/// The lattice vector from `a` to `b`.
fn diff(a: ZZeta, b: ZZeta) -> [i64; 4] {
    std::array::from_fn(|k| b.0[k] - a.0[k])
}

/// Census of vertex stars: for every site at least 8 spacings from the picture's edges, the
/// cells around it as lattice vectors from it (each cell's cycle starting at the site). Counts
/// the distinct stars, the distinct vectors in them, and the distinct existence patterns of
/// those vectors around a site (which of `x + v` are sites), and checks that the pattern
/// decides the star: then a table from pattern to star would triangulate the interior by
/// look-up, exactly.
fn atlas() {
    println!("## Vertex stars of the canonical cells, default frame\n");
    println!("| picture | sites | interior sites | stars | vectors | patterns | ambiguous | cells time |");
    println!("|---|---|---|---|---|---|---|---|");
    for (w, h, n) in [
        (768u32, 480u32, 23040usize),
        (768, 480, 50000),
        (768, 480, 92160),
        (1024, 1024, 16384),
        (1024, 1024, 65536),
        (1024, 1024, 262144),
    ] {
        let mut set = SampleSet::new(w, h, 1);
        for s in Quasicrystal::new(w, h).expect("frame").first(n) {
            set.push_exact(s.pos, s.lattice, &[0]);
        }
        let t0 = Instant::now();
        let cells = set.cells().expect("exact").clone();
        let dt = t0.elapsed();
        let (pos, lat) = (set.points(), set.point_lattice());
        let sites: HashSet<[i64; 4]> = lat.iter().flatten().map(|z| z.0).collect();
        let mut around = vec![Vec::new(); pos.len()];
        for (k, c) in cells.iter().enumerate() {
            for &v in c {
                around[v as usize].push(k);
            }
        }
        let cells: Vec<&[u32]> = cells.iter().collect();
        let m = 8.0 * ((w * h) as f64 / n as f64).sqrt();
        let mut stars = Vec::new();
        for (p, q) in pos.iter().enumerate() {
            let inner = q[0] >= m && q[1] >= m && q[0] <= w as f64 - m && q[1] <= h as f64 - m;
            let (true, Some(x)) = (inner, lat[p]) else {
                continue;
            };
            let mut star: Star = (around[p].iter())
                .map(|&k| {
                    let mut c: Vec<_> = cells[k]
                        .iter()
                        .map(|&v| diff(x, lat[v as usize].expect("exact")))
                        .collect();
                    let at = c
                        .iter()
                        .position(|v| *v == [0; 4])
                        .expect("the site is a vertex");
                    c.rotate_left(at);
                    c
                })
                .collect();
            star.sort();
            stars.push((x, star));
        }
        let vectors: BTreeSet<[i64; 4]> = (stars.iter().flat_map(|s| s.1.iter().flatten()))
            .filter(|v| **v != [0; 4])
            .copied()
            .collect();
        let mut by_pattern: HashMap<Vec<bool>, HashSet<&Star>> = HashMap::new();
        for (x, star) in &stars {
            let pattern = (vectors.iter())
                .map(|v| sites.contains(&std::array::from_fn(|k| x.0[k] + v[k])))
                .collect();
            by_pattern.entry(pattern).or_default().insert(star);
        }
        let distinct: HashSet<_> = stars.iter().map(|s| &s.1).collect();
        let ambiguous = by_pattern.values().filter(|s| s.len() > 1).count();
        println!(
            "| {w}×{h} | {n} | {} | {} | {} | {} | {ambiguous} | {:.1} ms |",
            stars.len(),
            distinct.len(),
            vectors.len(),
            by_pattern.len(),
            dt.as_secs_f64() * 1e3
        );
    }
    println!();
}

fn table(list: &[Photo]) {
    println!("## Gouraud PSNR (dB): canonical cells / spade split / gain\n");
    println!("| photo | 1089 | 4225 | 16641 |");
    println!("|---|---|---|---|");
    for p in list {
        let src = SourceImage::new(&p.rgb, p.w, p.h, 3).expect("rgb buffer");
        let qc = Quasicrystal::new(p.w, p.h).expect("frame");
        let cols: Vec<String> = [1089usize, 4225, 16641]
            .iter()
            .map(|&n| {
                let (a, b) = both(p, &src, &qc, n, SampleColour::Area, None);
                format!("{a:.2} / {b:.2} / {:+.2}", a - b)
            })
            .collect();
        println!("| {} | {} |", p.name, cols.join(" | "));
    }
    println!();
}

fn monotone(list: &[Photo]) {
    println!("## Monotone sharpening, N = 1000..=6000 step 50 (100 steps)\n");
    println!("| photo | colours | rule | falling steps | worst step | sum of losses |");
    println!("|---|---|---|---|---|---|");
    for p in list
        .iter()
        .filter(|p| ["astronaut", "coffee"].contains(&p.name.as_str()))
    {
        let src = SourceImage::new(&p.rgb, p.w, p.h, 3).expect("rgb buffer");
        let qc = Quasicrystal::new(p.w, p.h).expect("frame");
        // Prefixes of one file of the default size (sample colours fixed as N grows), with
        // the default and the point-sampled colour; and, for comparison, a new file of exactly
        // N samples at each step (area boxes shrink with N).
        let file = (p.w as usize * p.h as usize) / 8;
        for (colours, rule, total) in [
            ("prefix, progressive", SampleColour::Progressive, Some(file)),
            ("prefix, point", SampleColour::Nearest, Some(file)),
            ("file of N, area", SampleColour::Area, None),
        ] {
            let series: Vec<(f64, f64)> = (1000..=6000)
                .step_by(50)
                .map(|n| both(p, &src, &qc, n, rule, total))
                .collect();
            for (rule, pick) in [("canonical", 0), ("spade", 1)] {
                let v: Vec<f64> = series
                    .iter()
                    .map(|s| if pick == 0 { s.0 } else { s.1 })
                    .collect();
                let d: Vec<f64> = v.windows(2).map(|w| w[1] - w[0]).collect();
                if std::env::var_os("CELLS_VERBOSE").is_some() {
                    for (k, x) in d.iter().enumerate() {
                        if *x < 0.0 {
                            eprintln!(
                                "{} {colours} {rule}: N = {} → {}: {x:+.3} dB",
                                p.name,
                                1000 + 50 * k,
                                1050 + 50 * k
                            );
                        }
                    }
                }
                let falls = d.iter().filter(|&&x| x < 0.0).count();
                let worst = d.iter().copied().fold(0.0f64, f64::min);
                let sum: f64 = d.iter().filter(|&&x| x < 0.0).sum();
                println!(
                "| {} | {colours} | {rule} | {falls}/{} ({:.0}%) | {worst:.3} dB | {sum:.3} dB |",
                p.name,
                d.len(),
                100.0 * falls as f64 / d.len() as f64
            );
            }
        }
    }
    println!();
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = args
        .iter()
        .find(|a| a.contains('/'))
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            let rel = PathBuf::from("../shared/corpus/dev");
            if rel.is_dir() {
                rel
            } else {
                PathBuf::from("/work/shared/corpus/dev")
            }
        });
    let want = |s: &str| args.iter().all(|a| a.contains('/')) || args.iter().any(|a| a == s);
    if want("stats") {
        stats();
    }
    if want("atlas") {
        atlas();
    }
    if want("psnr") || want("monotone") {
        let list = photos(&dir);
        if list.is_empty() {
            eprintln!("no PNG in {}", dir.display());
            return;
        }
        if want("psnr") {
            table(&list);
        }
        if want("monotone") {
            monotone(&list);
        }
    }
}
