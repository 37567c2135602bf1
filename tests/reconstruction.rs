//! Reconstruction: exactness on ramps and constants, fill rule, incremental = one-shot.

use qcs::reconstruction::{
    raster_coverage, render, render_with, triangles, Method, RenderOptions, SampleSet,
};

/// splitmix64: a small deterministic generator, so the tests need no dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn f(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn points(&mut self, n: usize, w: f64, h: f64) -> Vec<[f64; 2]> {
        (0..n).map(|_| [self.f() * w, self.f() * h]).collect()
    }
}

fn single() -> RenderOptions {
    RenderOptions::single_threaded()
}

/// Convex hull (counter-clockwise in y-up terms, by Andrew's monotone chain).
fn hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.partial_cmp(b).unwrap());
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut h: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

/// Signed distance of `q` inside the convex polygon `h` (negative outside).
fn inside_depth(h: &[[f64; 2]], q: [f64; 2]) -> f64 {
    let mut d = f64::INFINITY;
    for k in 0..h.len() {
        let (a, b) = (h[k], h[(k + 1) % h.len()]);
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let len = (ex * ex + ey * ey).sqrt();
        d = d.min((ex * (q[1] - a[1]) - ey * (q[0] - a[0])) / len);
    }
    d
}

/// An affine colour ramp over a W × H source, within 0..=255.
fn ramp(p: [f64; 2], w: f64, h: f64) -> [f64; 3] {
    let (u, v) = (p[0] / w, p[1] / h);
    [
        10.0 + 200.0 * u + 40.0 * v,
        240.0 - 120.0 * u - 100.0 * v,
        30.0 + 90.0 * v + 50.0 * u,
    ]
}

fn ramp_colours(points: &[[f64; 2]], w: f64, h: f64) -> Vec<u8> {
    points
        .iter()
        .flat_map(|&p| ramp(p, w, h).map(|c| c.round() as u8))
        .collect()
}

/// The output pixels of a `w × h` render where `method` depends on samples only, not on
/// mirror points (which carry a sample's colour to its mirror image, so a ramp continues flat
/// across the image edges): inside a triangle with three sample vertices (Gouraud), and where
/// every triangle whose circumcircle holds the pixel centre has sample vertices only (natural
/// neighbour: those are its neighbours).
fn sample_region(
    method: Method,
    points: &[[f64; 2]],
    src: (u32, u32),
    w: u32,
    h: u32,
) -> Vec<bool> {
    use qcs::reconstruction::RasterVertex;
    use spade::Triangulation as _;
    let mut set = SampleSet::new(src.0, src.1, 1);
    for p in points {
        set.push(*p, &[0]);
    }
    let samples: std::collections::HashSet<[u64; 2]> =
        points.iter().map(|p| p.map(f64::to_bits)).collect();
    let all = set.points().to_vec();
    let faces: Vec<([[f64; 2]; 3], bool)> = set
        .triangulation()
        .inner_faces()
        .map(|f| {
            let v = f.vertices().map(|v| all[v.data().index as usize]);
            (v, v.iter().all(|p| samples.contains(&p.map(f64::to_bits))))
        })
        .collect();
    let (sx, sy) = (w as f64 / src.0 as f64, h as f64 / src.1 as f64);
    // Cubic: the gradient of a point comes from its neighbours, so every vertex of the
    // triangle must have samples only as neighbours.
    let faces: Vec<([[f64; 2]; 3], bool)> = if method == Method::Cubic {
        let mut clean = vec![true; all.len()];
        for f in set.triangulation().inner_faces() {
            let v = f.vertices().map(|v| v.data().index as usize);
            if !v
                .iter()
                .all(|&i| samples.contains(&all[i].map(f64::to_bits)))
            {
                for i in v {
                    clean[i] = false;
                }
            }
        }
        let tri = set.triangulation();
        tri.inner_faces()
            .map(|f| {
                let v = f.vertices().map(|v| v.data().index as usize);
                (v.map(|i| all[i]), v.iter().all(|&i| clean[i]))
            })
            .collect()
    } else {
        faces
    };
    if matches!(method, Method::Gouraud | Method::Cubic) {
        let tris: Vec<_> = faces
            .iter()
            .filter(|f| f.1)
            .map(|(t, _)| {
                t.map(|p| RasterVertex {
                    pos: [p[0] * sx, p[1] * sy],
                    colour: [0.0; 4],
                })
            })
            .collect();
        return raster_coverage(&tris, w, h)
            .iter()
            .map(|&n| n == 1)
            .collect();
    }
    let mut out = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let q = [(i as f64 + 0.5) / sx, (j as f64 + 0.5) / sy];
            let mut any = false;
            let mut ok = true;
            for (t, only_samples) in &faces {
                let d = |p: [f64; 2]| [p[0] - q[0], p[1] - q[1]];
                let (a, b, c) = (d(t[0]), d(t[1]), d(t[2]));
                let l = |p: [f64; 2]| p[0] * p[0] + p[1] * p[1];
                let det = l(a) * (b[0] * c[1] - c[0] * b[1]) - l(b) * (a[0] * c[1] - c[0] * a[1])
                    + l(c) * (a[0] * b[1] - b[0] * a[1]);
                let orient = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                if det * orient.signum() > -1e-6 {
                    ok &= only_samples;
                    any = true;
                }
            }
            out.push(any && ok);
        }
    }
    out
}

fn check_ramp(method: Method, points: &[[f64; 2]], src: (u32, u32), sizes: &[(u32, u32)]) {
    let (sw, sh) = (src.0 as f64, src.1 as f64);
    let colours = ramp_colours(points, sw, sh);
    let hl = hull(points);
    // The vertex colours are the ramp rounded to bytes: ±½ each. Gouraud interpolates them
    // (±½), then rounds (±½). The cubic patches also carry the gradients' error (estimated
    // from the rounded colours) into their edge and centre control values.
    let tolerance = if method == Method::Cubic { 1.5 } else { 1.0 };
    for &(w, h) in sizes {
        let exact = sample_region(method, points, src, w, h);
        let img = render(src, 3, points, &colours, method, w, h);
        assert_eq!(img.len(), (w * h * 3) as usize);
        let mut checked = 0;
        for j in 0..h {
            for i in 0..w {
                let q = [
                    (i as f64 + 0.5) * sw / w as f64,
                    (j as f64 + 0.5) * sh / h as f64,
                ];
                if hl.len() < 3 || inside_depth(&hl, q) < 1e-9 || !exact[(j * w + i) as usize] {
                    continue;
                }
                checked += 1;
                let want = ramp(q, sw, sh);
                let o = ((j * w + i) * 3) as usize;
                for k in 0..3 {
                    let got = img[o + k] as f64;
                    assert!(
                        (got - want[k]).abs() <= tolerance + 1e-9,
                        "{method:?} {} samples at {w}x{h}: pixel ({i},{j}) channel {k}: {got} vs {}",
                        points.len(),
                        want[k]
                    );
                }
            }
        }
        if points.len() > 100 {
            assert!(
                checked as f64 > 0.4 * (w * h) as f64,
                "hull covers too little"
            );
        }
    }
}

const SIZES: &[(u32, u32)] = &[(200, 150), (97, 61), (311, 233), (13, 7)];

const METHODS: [Method; 4] = [
    Method::Gouraud,
    Method::Shepard,
    Method::Natural,
    Method::Cubic,
];

/// Points `step` apart from (0.5, 0.5) over a 200 × 150 source.
fn grid(step: f64) -> Vec<[f64; 2]> {
    let mut grid = Vec::new();
    let mut y = 0.5;
    while y < 150.0 {
        let mut x = 0.5;
        while x < 200.0 {
            grid.push([x, y]);
            x += step;
        }
        y += step;
    }
    grid
}

#[test]
fn gouraud_reproduces_ramp_random_and_grid() {
    let mut rng = Rng(1);
    let all = rng.points(4000, 200.0, 150.0);
    for n in [3, 40, 700, 4000] {
        check_ramp(Method::Gouraud, &all[..n], (200, 150), SIZES);
    }
    // Grid points (cocircular everywhere: ties in the triangulation and pixel centres on edges).
    for step in [7.0, 2.0, 1.0] {
        check_ramp(Method::Gouraud, &grid(step), (200, 150), SIZES);
    }
}

#[test]
fn cubic_reproduces_ramp_random_and_grid() {
    let mut rng = Rng(4);
    let all = rng.points(4000, 200.0, 150.0);
    for n in [40, 700, 4000] {
        check_ramp(Method::Cubic, &all[..n], (200, 150), SIZES);
    }
    for step in [7.0, 2.0] {
        check_ramp(Method::Cubic, &grid(step), (200, 150), SIZES);
    }
}

#[test]
fn cubic_is_closer_than_gouraud_on_a_smooth_picture() {
    // A smooth picture sampled at random points: the cubic patches follow its curvature,
    // Gouraud's planes cannot (compared inside the samples' hull, away from the edges).
    let f = |p: [f64; 2]| 128.0 + 100.0 * (p[0] / 9.0).sin() * (p[1] / 13.0).cos();
    let mut rng = Rng(5);
    let pts = rng.points(1500, 200.0, 150.0);
    let colours: Vec<u8> = pts.iter().map(|&p| f(p).round() as u8).collect();
    let mse = |method| {
        let img = render((200, 150), 1, &pts, &colours, method, 200, 150);
        let mut se = 0.0;
        for j in 10..140 {
            for i in 10..190 {
                let d = img[j * 200 + i] as f64 - f([i as f64 + 0.5, j as f64 + 0.5]);
                se += d * d;
            }
        }
        se / (130.0 * 180.0)
    };
    let (gouraud, cubic) = (mse(Method::Gouraud), mse(Method::Cubic));
    assert!(
        cubic < 0.6 * gouraud,
        "MSE cubic {cubic:.2}, Gouraud {gouraud:.2}"
    );
}

#[test]
fn natural_reproduces_ramp() {
    // Sibson coordinates have linear precision.
    let mut rng = Rng(2);
    let pts = rng.points(300, 200.0, 150.0);
    check_ramp(Method::Natural, &pts, (200, 150), &[(97, 61), (60, 45)]);
}

#[test]
fn constant_stays_constant_everywhere() {
    let mut rng = Rng(3);
    let colour = [17u8, 200, 99, 255];
    let mut sets: Vec<Vec<[f64; 2]>> = vec![
        vec![[40.0, 30.0]],
        vec![[10.0, 10.0], [90.0, 60.0]],
        vec![[10.0, 10.0], [30.0, 23.0], [50.0, 36.0], [90.0, 62.0]], // collinear
        vec![[5.0, 5.0], [95.0, 8.0], [50.0, 70.0]],
    ];
    sets.push(rng.points(50, 100.0, 75.0));
    sets.push(rng.points(1500, 100.0, 75.0));
    for pts in &sets {
        for channels in [1, 3, 4] {
            let colours: Vec<u8> = pts
                .iter()
                .flat_map(|_| colour[..channels].to_vec())
                .collect();
            for method in METHODS {
                for (w, h) in [(100, 75), (97, 61), (7, 5), (203, 151), (1, 1)] {
                    let img = render((100, 75), channels, pts, &colours, method, w, h);
                    assert_eq!(img.len(), (w * h) as usize * channels);
                    for (k, px) in img.chunks_exact(channels).enumerate() {
                        assert_eq!(
                            px,
                            &colour[..channels],
                            "{method:?} {} samples, {w}x{h}, pixel {k}",
                            pts.len()
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn empty_set_is_mid_grey_and_zero_size_is_empty() {
    for method in METHODS {
        assert_eq!(render((10, 10), 3, &[], &[], method, 4, 3), vec![128; 36]);
        assert!(render((10, 10), 3, &[[1.0, 1.0]], &[1, 2, 3], method, 0, 3).is_empty());
    }
}

#[test]
fn two_samples_paint_a_linear_ramp_between_them() {
    // With their mirror points the two samples are a grid of rectangles; the colour depends
    // on x only: flat beyond the samples (mirrored), linear between them.
    let pts = [[10.0, 50.0], [90.0, 50.0]];
    for method in [Method::Gouraud, Method::Natural, Method::Cubic] {
        let img = render((100, 100), 1, &pts, &[0, 200], method, 100, 100);
        for j in [0usize, 37, 99] {
            let row = &img[j * 100..j * 100 + 100];
            if method == Method::Gouraud {
                assert_eq!(row[3], 0);
                assert_eq!(row[95], 200);
                // x = 50.5: 200 · 40.5 / 80 = 101.25.
                assert_eq!(row[50], 101);
            }
            assert!(row.windows(2).all(|p| p[0] <= p[1]), "{method:?}");
        }
    }
}

/// Brute-force Shepard: 4 nearest by sorting, weights 1/d².
fn shepard_brute(pts: &[[f64; 2]], cols: &[u8], q: [f64; 2]) -> f64 {
    let mut d: Vec<(f64, usize)> = pts
        .iter()
        .enumerate()
        .map(|(k, p)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2), k))
        .collect();
    d.sort_by(|a, b| a.partial_cmp(b).unwrap());
    if d[0].0 == 0.0 {
        return cols[d[0].1] as f64;
    }
    let (mut s, mut ws) = (0.0, 0.0);
    for &(dd, k) in d.iter().take(4) {
        s += cols[k] as f64 / dd;
        ws += 1.0 / dd;
    }
    s / ws
}

#[test]
fn shepard_matches_brute_force_4nn() {
    let mut rng = Rng(4);
    for n in [2usize, 4, 5, 60, 900] {
        let pts = rng.points(n, 80.0, 60.0);
        let cols: Vec<u8> = (0..n).map(|_| (rng.next() % 256) as u8).collect();
        for (w, h) in [(80, 60), (37, 29)] {
            let img = render_with((80, 60), 1, &pts, &cols, Method::Shepard, w, h, single());
            for j in 0..h {
                for i in 0..w {
                    let q = [
                        (i as f64 + 0.5) * 80.0 / w as f64,
                        (j as f64 + 0.5) * 60.0 / h as f64,
                    ];
                    let want = shepard_brute(&pts, &cols, q);
                    let got = img[(j * w + i) as usize] as f64;
                    assert!(
                        (got - want).abs() <= 0.5 + 1e-6,
                        "n={n} {w}x{h} ({i},{j}): {got} vs {want}"
                    );
                }
            }
        }
    }
}

#[test]
fn shepard_returns_sample_colour_at_coincident_centre() {
    let mut rng = Rng(5);
    let (sw, sh) = (64u32, 48u32);
    // Upscaled ×2: output pixel centres are at source (i + 0.5) / 2.
    let mut pts = Vec::new();
    let mut cols = Vec::new();
    let mut expect = Vec::new();
    for j in 0..(2 * sh) {
        for i in 0..(2 * sw) {
            if rng.next().is_multiple_of(7) {
                pts.push([(i as f64 + 0.5) / 2.0, (j as f64 + 0.5) / 2.0]);
                let c = [
                    (rng.next() % 256) as u8,
                    (rng.next() % 256) as u8,
                    (rng.next() % 256) as u8,
                ];
                cols.extend_from_slice(&c);
                expect.push((i, j, c));
            }
        }
    }
    let img = render((sw, sh), 3, &pts, &cols, Method::Shepard, 2 * sw, 2 * sh);
    for (i, j, c) in expect {
        let o = ((j * 2 * sw + i) * 3) as usize;
        assert_eq!(&img[o..o + 3], &c, "pixel ({i},{j})");
    }
}

#[test]
fn rasteriser_paints_each_pixel_once() {
    let mut rng = Rng(6);
    type Case = (Vec<[f64; 2]>, (u32, u32));
    let mut cases: Vec<Case> = Vec::new();
    for n in [3usize, 10, 200, 3000] {
        cases.push((rng.points(n, 50.0, 40.0), (97, 61)));
        cases.push((rng.points(n, 50.0, 40.0), (31, 83)));
    }
    // Sites on pixel centres and corners: centres exactly on edges and vertices.
    let mut lattice = Vec::new();
    for j in 0..=40 {
        for i in 0..=50 {
            lattice.push([i as f64, j as f64]);
            if (i + j) % 3 == 0 {
                lattice.push([i as f64 + 0.5, j as f64 + 0.5]);
            }
        }
    }
    cases.push((lattice.clone(), (50, 40)));
    cases.push((lattice.clone(), (100, 80)));
    cases.push((lattice, (25, 20)));
    for (pts, (w, h)) in cases {
        let mut set = SampleSet::new(50, 40, 1);
        for p in &pts {
            set.push(*p, &[0]);
        }
        let colours = set.colours().to_vec();
        let scale = [w as f64 / 50.0, h as f64 / 40.0];
        let tris = triangles(set.triangulation(), &colours, 1, scale);
        let cover = raster_coverage(&tris, w, h);
        let hl: Vec<[f64; 2]> = hull(set.points())
            .iter()
            .map(|p| [p[0] * scale[0], p[1] * scale[1]])
            .collect();
        for j in 0..h {
            for i in 0..w {
                let n = cover[(j * w + i) as usize];
                assert!(
                    n <= 1,
                    "{} sites {w}x{h}: pixel ({i},{j}) painted {n} times",
                    pts.len()
                );
                let depth = inside_depth(&hl, [i as f64 + 0.5, j as f64 + 0.5]);
                if depth > 1e-9 {
                    assert_eq!(n, 1, "{} sites {w}x{h}: pixel ({i},{j}) skipped", pts.len());
                } else if depth < -1e-9 {
                    assert_eq!(
                        n,
                        0,
                        "{} sites {w}x{h}: pixel ({i},{j}) outside hull painted",
                        pts.len()
                    );
                }
            }
        }
    }
}

/// Fans of triangles around a centre, spokes reaching `far` away (some along rows, columns
/// and diagonals through pixel centres): every centre of a small picture is painted exactly
/// once, however far the vertices (the crossings are then decided by the exact predicate).
#[test]
fn rasteriser_is_exact_with_far_vertices() {
    use qcs::reconstruction::RasterVertex;
    let v = |p: [f64; 2]| RasterVertex {
        pos: p,
        colour: [0.0; 4],
    };
    let dirs = [
        [1.0, 0.0],
        [1.0, 1.0],
        [0.3, 1.0],
        [0.0, 1.0],
        [-1.0, 1.0],
        [-1.0, 0.0],
        [-1.0, -0.7],
        [0.0, -1.0],
        [1.0, -1.0],
    ];
    for far in [20.0, 1e9, 1e30, 1e60, 1e150] {
        for centre in [[5.5, 5.5], [5.0, 6.0], [5.25, 5.5], [0.5, 10.5]] {
            let tips: Vec<[f64; 2]> = dirs
                .iter()
                .map(|d| [centre[0] + far * d[0], centre[1] + far * d[1]])
                .collect();
            let tris: Vec<_> = (0..tips.len())
                .map(|k| [v(centre), v(tips[k]), v(tips[(k + 1) % tips.len()])])
                .collect();
            for (w, h) in [(11, 11), (7, 13)] {
                let cover = raster_coverage(&tris, w, h);
                assert!(
                    cover.iter().all(|&n| n == 1),
                    "far {far}, centre {centre:?}, {w}x{h}: {cover:?}"
                );
            }
        }
    }
}

/// `rasterise`'s painted mask is exactly the set of pixels some triangle claims, for spans of
/// every length (the mask is set with fixed-size stores for short spans).
#[test]
fn rasterise_marks_exactly_the_claimed_pixels() {
    use qcs::reconstruction::{rasterise, RasterVertex};
    let mut rng = Rng(17);
    let (w, h) = (53u32, 31u32);
    for case in 0..60 {
        let size = [1.5, 4.0, 9.0, 20.0, 60.0][case % 5];
        let tris: Vec<_> = (0..1 + case % 4)
            .map(|_| {
                let c = [rng.f() * 60.0 - 4.0, rng.f() * 38.0 - 4.0];
                [(); 3].map(|_| RasterVertex {
                    pos: [c[0] + rng.f() * size, c[1] + rng.f() * size],
                    colour: [rng.f() as f32 * 255.0; 4],
                })
            })
            .collect();
        let (_, painted) = rasterise(&tris, w, h, 3);
        let cover = raster_coverage(&tris, w, h);
        for (k, (&p, &n)) in painted.iter().zip(&cover).enumerate() {
            assert_eq!(
                p,
                n > 0,
                "case {case}, pixel {k}: painted {p}, claimed {n} times"
            );
        }
    }
}

/// Every painted pixel is the triangle's plane at its centre, rounded and clamped, also for
/// planes too steep or colours too far out of range for the fixed-point span loop.
#[test]
fn rasterise_matches_the_plane() {
    use qcs::reconstruction::{rasterise, RasterVertex};
    let mut rng = Rng(9);
    let (w, h) = (37u32, 29u32);
    for case in 0..400 {
        let scale = [2.0, 40.0, 0.7][case % 3];
        let mut tri = [RasterVertex::default(); 3];
        for v in &mut tri {
            v.pos = [rng.f() * 50.0 - 6.0, rng.f() * 40.0 - 6.0];
            for c in &mut v.colour {
                *c = ((rng.f() - 0.5) * 255.0 * scale + 128.0) as f32;
            }
        }
        if case % 7 == 0 {
            // A sliver: steep across it.
            tri[2].pos = [
                (tri[0].pos[0] + tri[1].pos[0]) / 2.0 + 0.01,
                (tri[0].pos[1] + tri[1].pos[1]) / 2.0,
            ];
        }
        let (img, painted) = rasterise(&[tri], w, h, 3);
        let [a, b, c] = tri.map(|v| v.pos);
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        for j in 0..h as usize {
            for i in 0..w as usize {
                if !painted[j * w as usize + i] {
                    continue;
                }
                let q = [i as f64 + 0.5, j as f64 + 0.5];
                let l1 = ((q[0] - a[0]) * (c[1] - a[1]) - (q[1] - a[1]) * (c[0] - a[0])) / det;
                let l2 = ((b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])) / det;
                for k in 0..3 {
                    let col = |v: usize| tri[v].colour[k] as f64;
                    let want = (col(0) + l1 * (col(1) - col(0)) + l2 * (col(2) - col(0)))
                        .clamp(0.0, 255.0);
                    let got = img[(j * w as usize + i) * 3 + k] as f64;
                    assert!(
                        (got - want).abs() <= 0.501 + 1e-6 / det.abs(),
                        "case {case} pixel ({i},{j}) channel {k}: {got} vs {want}"
                    );
                }
            }
        }
    }
}

/// Samples far outside the picture (up to the ±2^200 the API accepts) still draw it: here a
/// constant colour.
#[test]
fn far_samples_render() {
    for far in [1e6, 1e60, 2f64.powi(199)] {
        let pts = [[-far, -far], [far, -far * 0.5], [3.0, far], [20.0, 7.0]];
        let colours = [40u8, 90, 200].repeat(4);
        let img = render_with(
            (30, 20),
            3,
            &pts,
            &colours,
            Method::Gouraud,
            23,
            17,
            single(),
        );
        assert!(img.chunks_exact(3).all(|p| p == [40, 90, 200]), "far {far}");
    }
    // Samples right of the picture: their hull misses it, the outside rule paints it all.
    let pts = [[150.0, 10.0], [190.0, 12.0], [170.0, 60.0], [160.0, 30.0]];
    let colours = [7u8, 250, 31].repeat(4);
    let img = render_with(
        (100, 80),
        3,
        &pts,
        &colours,
        Method::Gouraud,
        41,
        33,
        single(),
    );
    assert!(img.chunks_exact(3).all(|p| p == [7, 250, 31]));
}

#[test]
fn incremental_equals_one_shot() {
    let mut rng = Rng(7);
    let pts = rng.points(2500, 120.0, 90.0);
    let cols: Vec<u8> = (0..pts.len() * 3)
        .map(|_| (rng.next() % 256) as u8)
        .collect();
    // (Not Method::Cubic: without lattice points the triangles are spade's, and the cubic
    // gradients depend on which diagonal it picks in cocircular quadrilaterals, e.g. of a
    // sample's mirror points; tests/cells.rs checks the cubic picture from exact samples.)
    for method in [Method::Gouraud, Method::Natural, Method::Shepard] {
        let mut set = SampleSet::new(120, 90, 3);
        let mut k = 0;
        for (b, batch) in [1usize, 2, 5, 40, 300, 1000, 1152].iter().enumerate() {
            for _ in 0..*batch {
                set.push(pts[k], &cols[k * 3..k * 3 + 3]);
                k += 1;
            }
            let _ = set.render(method, 31 + b as u32, 17 + 2 * b as u32);
        }
        assert_eq!(k, pts.len());
        for (w, h) in [(120, 90), (97, 61)] {
            let inc = set.render(method, w, h);
            let one = render((120, 90), 3, &pts, &cols, method, w, h);
            assert!(
                inc == one,
                "{method:?} {w}x{h}: incremental differs from one-shot"
            );
        }
    }
}

#[test]
fn parallel_equals_single_threaded() {
    let mut rng = Rng(8);
    let pts = rng.points(3000, 100.0, 100.0);
    let cols: Vec<u8> = (0..pts.len()).map(|_| (rng.next() % 256) as u8).collect();
    for method in METHODS {
        let a = render_with((100, 100), 1, &pts, &cols, method, 173, 211, single());
        let b = render((100, 100), 1, &pts, &cols, method, 173, 211);
        assert!(a == b, "{method:?}");
    }
}

#[test]
fn bad_input_does_not_panic() {
    let pts = [
        [f64::NAN, 1.0],
        [f64::INFINITY, 2.0],
        [1e300, 1.0],
        [3.0, 3.0],
        [5.0, 1.0],
    ];
    for method in METHODS {
        // Short colour buffer, zero-sized source, odd channel count.
        let img = render((0, 0), 7, &pts, &[9, 9, 9], method, 5, 4);
        assert_eq!(img.len(), 5 * 4 * 4);
    }
}
