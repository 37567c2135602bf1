//! Canonical Delaunay cells: cell statistics, Gouraud PSNR of the centroid rule
//! against `spade`'s own split, monotone sharpening, and a census of the local configurations
//! (the premise of a triangulation that would look them up rather than compute them, #4).
//!
//! Run: `cargo run --release -p qcs-lab --example cells_table -- [stats] [psnr] [monotone] [atlas] [DIR]`
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
use qcs::sites::{site_order, Quasicrystal};

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

/// The vertex stars of the canonical cells of the first `n` sites of a `w × h` picture, for
/// every site at least 8 spacings from the picture's edges: the cells around the site as
/// lattice vectors from it (each cell's cycle starting at the site), sorted.
struct Census {
    set: SampleSet,
    /// (point, its lattice point, its star).
    stars: Vec<(usize, ZZeta, Star)>,
    cells_time: f64,
}

fn census(w: u32, h: u32, n: usize) -> Census {
    let mut set = SampleSet::new(w, h, 1);
    for s in Quasicrystal::new(w, h).expect("frame").first(n) {
        set.push_exact(s.pos, s.lattice, &[0]);
    }
    let t0 = Instant::now();
    let cells = set.cells().expect("exact").clone();
    let cells_time = t0.elapsed().as_secs_f64() * 1e3;
    let (pos, lat) = (set.points(), set.point_lattice());
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
                let mut c: Vec<_> = (cells[k].iter())
                    .map(|&v| (lat[v as usize].expect("exact") - x).0)
                    .collect();
                let at = (c.iter().position(|v| *v == [0; 4])).expect("the site is a vertex");
                c.rotate_left(at);
                c
            })
            .collect();
        star.sort();
        stars.push((p, x, star));
    }
    Census {
        set,
        stars,
        cells_time,
    }
}

/// Radius of the circle through three points.
fn circumradius(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let d = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let (ab, bc, ca) = (d(a, b), d(b, c), d(c, a));
    let area2 = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
    ab * bc * ca / (2.0 * area2)
}

impl Census {
    /// D, twice the largest circumradius of a cell around an interior site; how many lattice
    /// vectors lead from an interior site to a point within D; how many distinct sets of them
    /// there are around interior sites; and how many such sets have two stars.
    fn within(&self) -> (f64, usize, usize, usize) {
        let px = |v: &[i64; 4]| {
            let (x, y) = ZZeta(*v).to_f64();
            [x, y]
        };
        let rho = (self.stars.iter().flat_map(|s| s.2.iter()))
            .map(|c| circumradius(px(&c[0]), px(&c[1]), px(&c[2])))
            .fold(0.0, f64::max);
        let d = 2.0 * rho * (1.0 + 1e-9);
        let (pos, lat) = (self.set.points(), self.set.point_lattice());
        let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        let cell = |p: [f64; 2]| ((p[0] / d).floor() as i64, (p[1] / d).floor() as i64);
        for (k, p) in pos.iter().enumerate() {
            if lat[k].is_some() {
                grid.entry(cell(*p)).or_default().push(k);
            }
        }
        let mut vectors = BTreeSet::new();
        let mut by_set: HashMap<Vec<[i64; 4]>, HashSet<&Star>> = HashMap::new();
        for (p, x, star) in &self.stars {
            let (q, (cx, cy)) = (pos[*p], cell(pos[*p]));
            let mut near = Vec::new();
            for (gx, gy) in
                (cx - 1..=cx + 1).flat_map(|gx| (cy - 1..=cy + 1).map(move |gy| (gx, gy)))
            {
                for &k in grid.get(&(gx, gy)).into_iter().flatten() {
                    let r = pos[k];
                    if k != *p && (r[0] - q[0]).hypot(r[1] - q[1]) <= d {
                        near.push((lat[k].expect("kept") - *x).0);
                    }
                }
            }
            near.sort();
            vectors.extend(near.iter().copied());
            by_set.entry(near).or_default().insert(star);
        }
        let ambiguous = by_set.values().filter(|s| s.len() > 1).count();
        (d, vectors.len(), by_set.len(), ambiguous)
    }

    /// Every vector of a star.
    fn vectors(&self) -> Vec<[i64; 4]> {
        let all: BTreeSet<[i64; 4]> = (self.stars.iter().flat_map(|s| s.2.iter().flatten()))
            .filter(|v| **v != [0; 4])
            .copied()
            .collect();
        all.into_iter().collect()
    }
}

/// The points of a picture by pixel (inside the picture only), to find a lattice point by
/// its position.
struct ByPixel {
    w: usize,
    start: Vec<u32>,
    /// Point indices, their positions and lattice points, pixel by pixel.
    ids: Vec<u32>,
    ps: Vec<[f64; 2]>,
    zs: Vec<[i64; 4]>,
}

impl ByPixel {
    fn new(pos: &[[f64; 2]], lat: &[Option<ZZeta>], w: u32, h: u32) -> Self {
        let (w, h) = (w as usize, h as usize);
        let pixel = |p: [f64; 2]| {
            let inside = p[0] >= 0.0 && p[1] >= 0.0 && p[0] < w as f64 && p[1] < h as f64;
            inside.then(|| p[1] as usize * w + p[0] as usize)
        };
        let mut start = vec![0u32; w * h + 1];
        for &p in pos {
            if let Some(c) = pixel(p) {
                start[c + 1] += 1;
            }
        }
        for c in 0..w * h {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut ids = vec![0u32; start[w * h] as usize];
        let mut ps = vec![[0.0; 2]; ids.len()];
        let mut zs = vec![[0i64; 4]; ids.len()];
        for (k, &p) in pos.iter().enumerate() {
            if let (Some(c), Some(z)) = (pixel(p), lat[k]) {
                let o = fill[c] as usize;
                (ids[o], ps[o], zs[o]) = (k as u32, p, z.0);
                fill[c] += 1;
            }
        }
        ByPixel {
            w,
            start,
            ids,
            ps,
            zs,
        }
    }

    /// The point at lattice point `z`, looked for in the pixel of position `p` (inside the
    /// picture): a point within rounding of a pixel's side could be missed, which the
    /// caller's count of neighbours found would show.
    fn find(&self, p: [f64; 2], z: [i64; 4]) -> Option<u32> {
        let c = p[1] as usize * self.w + p[0] as usize;
        let (a, b) = (self.start[c] as usize, self.start[c + 1] as usize);
        (a..b).find(|&k| self.zs[k] == z).map(|k| self.ids[k])
    }
}

/// Census of vertex stars (see [`census`]): counts the distinct stars, the distinct vectors in
/// them, and the distinct existence patterns of those vectors around a site (which of `x + v`
/// are sites), and checks that the pattern decides the star: then a table from pattern to
/// star would triangulate the interior by look-up, exactly. Then such a table, taken from one
/// picture, is applied to another of the same density, and the look-up timed.
fn atlas() {
    println!("## Vertex stars of the canonical cells, default frame\n");
    println!("| picture | sites | interior sites | stars | vectors | patterns | ambiguous | cells time |");
    println!("|---|---|---|---|---|---|---|---|");
    let sizes = [
        (768u32, 480u32, 23040usize),
        (768, 480, 50000),
        (768, 480, 92160),
        (1024, 1024, 16384),
        (1024, 1024, 65536),
        (1024, 1024, 262144),
    ];
    let mut within = Vec::new();
    for (w, h, n) in sizes {
        let c = census(w, h, n);
        let vectors = c.vectors();
        let lat = c.set.point_lattice();
        let sites: HashSet<[i64; 4]> = lat.iter().flatten().map(|z| z.0).collect();
        let mut by_pattern: HashMap<Vec<bool>, HashSet<&Star>> = HashMap::new();
        for (_, x, star) in &c.stars {
            let pattern = (vectors.iter())
                .map(|v| sites.contains(&std::array::from_fn(|k| x.0[k] + v[k])))
                .collect();
            by_pattern.entry(pattern).or_default().insert(star);
        }
        let distinct: HashSet<_> = c.stars.iter().map(|s| &s.2).collect();
        let ambiguous = by_pattern.values().filter(|s| s.len() > 1).count();
        println!(
            "| {w}×{h} | {n} | {} | {} | {} | {} | {ambiguous} | {:.1} ms |",
            c.stars.len(),
            distinct.len(),
            vectors.len(),
            by_pattern.len(),
            c.cells_time
        );
        within.push(c.within());
    }
    println!();
    println!("The same stars keyed by every site within D = twice the largest circumradius of an");
    println!(
        "interior cell, which decides a star by construction (each cell's circle lies within D"
    );
    println!("of the site):\n");
    println!(
        "| picture | sites | D (px) | D / spacing | vectors within D | patterns | ambiguous |"
    );
    println!("|---|---|---|---|---|---|---|");
    for ((w, h, n), (d, vectors, patterns, ambiguous)) in sizes.iter().zip(within) {
        let spacing = ((w * h) as f64 / *n as f64).sqrt();
        println!(
            "| {w}×{h} | {n} | {d:.2} | {:.2} | {vectors} | {patterns} | {ambiguous} |",
            d / spacing
        );
    }
    println!();
    // A table from 768×480 at 1 site per 4 px², applied to 1024×1024 at the same density.
    let from = census(768, 480, 92160);
    let vectors = from.vectors();
    assert!(vectors.len() <= 64, "a pattern fits a u64");
    let (pos, lat) = (from.set.points(), from.set.point_lattice());
    let index = ByPixel::new(pos, lat, 768, 480);
    let pattern = |x: [i64; 4], p: [f64; 2], pos_v: &[[f64; 2]], index: &ByPixel| {
        let mut bits = 0u64;
        for (k, (v, d)) in vectors.iter().zip(pos_v).enumerate() {
            let z = std::array::from_fn(|i| x[i] + v[i]);
            bits |= u64::from(index.find([p[0] + d[0], p[1] + d[1]], z).is_some()) << k;
        }
        bits
    };
    let pos_v: Vec<[f64; 2]> = (vectors.iter())
        .map(|v| {
            let (x, y) = ZZeta(*v).to_f64();
            [x, y]
        })
        .collect();
    // Each star with the vectors (indices into `vectors`) to its neighbours.
    let table: HashMap<u64, (&Star, Vec<usize>)> = (from.stars.iter())
        .map(|(p, x, star)| {
            let around: BTreeSet<&[i64; 4]> = star.iter().flatten().collect();
            let verts = (vectors.iter().enumerate())
                .filter(|(_, v)| around.contains(v))
                .map(|(k, _)| k)
                .collect();
            (pattern(x.0, pos[*p], &pos_v, &index), (star, verts))
        })
        .collect();
    let to = census(1024, 1024, 262144);
    let (pos, lat) = (to.set.points(), to.set.point_lattice());
    let mut star_of = vec![None; pos.len()];
    for (p, _, star) in &to.stars {
        star_of[*p] = Some(star);
    }
    // Timed: what a look-up triangulation would do for the interior, site by site in pixel
    // order (neighbouring sites read neighbouring memory): which of x + v are sites, from
    // the star map (x + v is a site when it is not after the last site in the site order:
    // decided by |(x + v)*|² in f64, exactly near the last site's), the star from the table,
    // and the star's neighbours' point indices.
    let qc = Quasicrystal::new(1024, 1024).expect("frame");
    let last = qc.first(262144).last().expect("sites").lattice;
    let norm = |(a, b): (f64, f64)| a * a + b * b;
    let r2 = norm(last.star().to_f64());
    let (below, above) = (r2 * (1.0 - 1e-9), r2 * (1.0 + 1e-9));
    let star_v: Vec<(f64, f64)> = vectors.iter().map(|v| ZZeta(*v).star().to_f64()).collect();
    let t0 = Instant::now();
    let index = ByPixel::new(pos, lat, 1024, 1024);
    // The census's interior: 8 spacings (2 px) from the edges.
    let m = 16.0;
    let mut found = Vec::with_capacity(to.stars.len());
    let mut neighbours = 0usize;
    for ((&p, &q), &x) in index.ids.iter().zip(&index.ps).zip(&index.zs) {
        if q[0] < m || q[1] < m || q[0] > 1024.0 - m || q[1] > 1024.0 - m {
            continue;
        }
        let (sx, sy) = ZZeta(x).star().to_f64();
        let mut bits = 0u64;
        for (k, (vx, vy)) in star_v.iter().enumerate() {
            let d = norm((sx + vx, sy + vy));
            let site = d < below
                || (d <= above && {
                    let z = ZZeta(std::array::from_fn(|i| x[i] + vectors[k][i]));
                    site_order(z, last).is_le()
                });
            bits |= u64::from(site) << k;
        }
        let entry = table.get(&bits);
        if let Some((_, verts)) = entry {
            for &k in verts {
                let z = std::array::from_fn(|i| x[i] + vectors[k][i]);
                let at = [q[0] + pos_v[k][0], q[1] + pos_v[k][1]];
                neighbours += usize::from(index.find(at, z).is_some());
            }
        }
        found.push((p, entry.map(|e| e.0)));
    }
    let dt = t0.elapsed().as_secs_f64() * 1e3;
    let same = (found.iter())
        .filter(|(p, f)| f.is_some_and(|f| Some(f) == star_of[*p as usize]))
        .count();
    let missing = found.iter().filter(|f| f.1.is_none()).count();
    let expected: usize = (found.iter().flat_map(|f| f.1))
        .map(|s| s.iter().flatten().collect::<BTreeSet<_>>().len() - 1)
        .sum();
    assert_eq!(neighbours, expected, "every neighbour found by position");
    println!(
        "A table of {} patterns from 768×480 (92160 sites) looks up the stars of the {} interior \
         sites of 1024×1024 (262144 sites) in {dt:.1} ms (cells: {:.1} ms): {same} the same, \
         {missing} not in the table, {} different.\n",
        table.len(),
        to.stars.len(),
        to.cells_time,
        to.stars.len() - same - missing
    );
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
