//! Samplers (determinism, bounds, prefix property, farthest-point optimality) and
//! stylized renderers (mosaic congruence, constant images, spectrum peaks, phase).

use qcs::sites::Point;
use qcs_lab::samplers::Sampler;
use qcs_lab::samplers::{self, FarthestPoint, Halton, Jittered, Periodic, Random};

fn min_dist(s: &[Point]) -> f64 {
    let mut m = f64::INFINITY;
    for i in 0..s.len() {
        for j in 0..i {
            let d = ((s[i][0] - s[j][0]).powi(2) + (s[i][1] - s[j][1]).powi(2)).sqrt();
            m = m.min(d);
        }
    }
    m
}

fn nearest(s: &[Point], p: [f64; 2]) -> f64 {
    s.iter()
        .map(|q| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt())
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn samplers_deterministic_inside_and_progressive() {
    for (w, h) in [(64u32, 48u32), (37, 91), (1, 5), (200, 3)] {
        for s in samplers::all(11) {
            let long = s.sites(w, h, 700);
            assert_eq!(long.len(), 700, "{}", s.name());
            assert_eq!(long, s.sites(w, h, 700), "{} not deterministic", s.name());
            for p in &long {
                assert!(
                    p[0] >= 0.0 && p[0] < w as f64 && p[1] >= 0.0 && p[1] < h as f64,
                    "{} site {p:?} outside {w}x{h}",
                    s.name()
                );
            }
            for n in [0, 1, 2, 5, 99, 256, 699] {
                assert_eq!(&long[..n], &s.sites(w, h, n)[..], "{} prefix {n}", s.name());
            }
        }
    }
    for s in samplers::all(0) {
        assert!(s.sites(0, 10, 5).is_empty());
    }
}

#[test]
fn seeds_change_stochastic_samplers() {
    let (a, b) = (
        Random { seed: 1 }.sites(50, 50, 10),
        Random { seed: 2 }.sites(50, 50, 10),
    );
    assert_ne!(a, b);
    let (a, b) = (
        Jittered { seed: 1 }.sites(50, 50, 10),
        Jittered { seed: 2 }.sites(50, 50, 10),
    );
    assert_ne!(a, b);
    let (a, b) = (
        FarthestPoint { seed: 1 }.sites(50, 50, 10),
        FarthestPoint { seed: 2 }.sites(50, 50, 10),
    );
    assert_ne!(a, b);
}

#[test]
fn periodic_full_grids_at_square_counts() {
    let (w, h) = (129u32, 65u32);
    for k in 0..=5u32 {
        let n = (1usize << k) + 1;
        let s = Periodic.sites(w, h, n * n);
        let mut got: Vec<(i64, i64)> = s
            .iter()
            .map(|p| {
                (
                    ((p[0] - 0.5) * 1e6).round() as i64,
                    ((p[1] - 0.5) * 1e6).round() as i64,
                )
            })
            .collect();
        got.sort_unstable();
        let mut want = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let x = i as f64 * (w - 1) as f64 / (n - 1) as f64;
                let y = j as f64 * (h - 1) as f64 / (n - 1) as f64;
                want.push(((x * 1e6).round() as i64, (y * 1e6).round() as i64));
            }
        }
        want.sort_unstable();
        assert_eq!(got, want, "level {k}");
    }
    // New points of a level come in scan-line order.
    let s = Periodic.sites(33, 33, 25);
    let level2 = &s[9..25];
    for pair in level2.windows(2) {
        assert!((pair[0][1], pair[0][0]) < (pair[1][1], pair[1][0]));
    }
}

#[test]
fn jittered_stays_in_its_cell() {
    let (w, h) = (65u32, 65u32);
    let p = Periodic.sites(w, h, 1089);
    let j = Jittered { seed: 5 }.sites(w, h, 1089);
    // Sites 289..1089 are level 5: cell 2 × 2 px around the lattice point.
    for k in 289..1089 {
        assert!((p[k][0] - j[k][0]).abs() <= 1.0 + 1e-9 && (p[k][1] - j[k][1]).abs() <= 1.0 + 1e-9);
    }
    // Full displacement: the jitter is spread over the whole cell, not concentrated.
    let far = (289..1089)
        .filter(|&k| (p[k][0] - j[k][0]).abs() > 0.5)
        .count();
    assert!(
        (300..500).contains(&far),
        "{far} of 800 displaced by more than a quarter cell"
    );
}

#[test]
fn halton_matches_radical_inverse_by_hand() {
    let s = Halton.sites(8, 9, 6);
    let want = [
        [4.0, 3.0],
        [2.0, 6.0],
        [6.0, 1.0],
        [1.0, 4.0],
        [5.0, 7.0],
        [3.0, 2.0],
    ];
    for (a, b) in s.iter().zip(want) {
        assert!(
            (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12,
            "{a:?} vs {b:?}"
        );
    }
}

#[test]
fn farthest_point_is_the_farthest_on_a_fine_grid() {
    let (w, h) = (40u32, 30u32);
    let s = FarthestPoint { seed: 3 }.sites(w, h, 120);
    // Each new site's distance to the previous ones must be (up to the grid step)
    // the largest over the domain [0.5, W-0.5] × [0.5, H-0.5].
    let step = 0.25;
    for n in [1usize, 2, 3, 4, 5, 10, 31, 64, 119] {
        let prev = &s[..n];
        let chosen = nearest(prev, s[n]);
        let mut best: f64 = 0.0;
        let mut y = 0.5;
        while y <= h as f64 - 0.5 {
            let mut x = 0.5;
            while x <= w as f64 - 0.5 {
                best = best.max(nearest(prev, [x, y]));
                x += step;
            }
            y += step;
        }
        assert!(
            chosen >= best - 1e-9,
            "n={n}: chose {chosen}, grid has {best}"
        );
        assert!(
            chosen <= best + step,
            "n={n}: chose {chosen} > grid max {best} + step"
        );
    }
    // Distances at insertion never increase (farthest-point property).
    let d: Vec<f64> = (1..s.len()).map(|n| nearest(&s[..n], s[n])).collect();
    for pair in d.windows(2) {
        assert!(pair[1] <= pair[0] + 1e-9);
    }
}

#[test]
fn farthest_point_min_distance_bound() {
    let (w, h) = (128u32, 96u32);
    let s = FarthestPoint { seed: 0 }.sites(w, h, 1500);
    let area = (w * h) as f64;
    for n in [100usize, 500, 1500] {
        let ratio = min_dist(&s[..n]) / (area / n as f64).sqrt();
        // Measured 0.70–0.90 in the reference; random sampling gives < 0.2.
        assert!(ratio > 0.65, "n={n}: min distance ratio {ratio}");
    }
    let r = Random { seed: 0 }.sites(w, h, 500);
    assert!(min_dist(&r) / (area / 500.0).sqrt() < 0.3);
}

// ---------------------------------------------------------------- styles

use qcs_lab::styles::{self, PhaseWindow, INK};
use std::collections::HashMap;

fn constant_colours(n: usize, c: [u8; 3]) -> Vec<u8> {
    (0..n).flat_map(|_| c).collect()
}

#[test]
fn mosaic_tiles_of_a_periodic_grid_are_congruent() {
    // 9×9 grid on a 129×129 image: spacing 16 px. Give every site its own colour
    // and count the pixels of each colour: interior tiles must all be equal.
    let (w, h) = (129u32, 129u32);
    let sites = Periodic.sites(w, h, 81);
    let colours: Vec<u8> = (0..sites.len())
        .flat_map(|k| [k as u8, 255 - k as u8, 7])
        .collect();
    let img = styles::mosaic(&sites, &colours, (w, h), (w, h)).unwrap();
    let mut count: HashMap<[u8; 3], usize> = HashMap::new();
    for p in img.pixels() {
        *count.entry(p.0).or_default() += 1;
    }
    let mut interior = Vec::new();
    for (k, p) in sites.iter().enumerate() {
        let inner = p[0] > 1.0 && p[0] < 128.0 && p[1] > 1.0 && p[1] < 128.0;
        if inner {
            interior.push(count[&[k as u8, 255 - k as u8, 7]]);
        }
    }
    assert_eq!(interior.len(), 49);
    let (lo, hi) = (
        *interior.iter().min().unwrap(),
        *interior.iter().max().unwrap(),
    );
    // Canonical cells are the 16×16 squares; a site's tile is its 4 corner
    // pieces, right triangles with legs 8: 4 × 32 = 128 px.
    assert!(hi - lo <= 4, "tile sizes {lo}..{hi}");
    assert!(
        (lo as i64 - 128).abs() <= 4,
        "tile size {lo}, expected ≈ 128"
    );
    // Grout: the central diamond, half of each square of the hull.
    let black = count.get(&INK).copied().unwrap_or(0);
    assert!(
        (black as f64 - 128.0 * 128.0 / 2.0).abs() < 300.0,
        "grout {black}"
    );
}

#[test]
fn renderers_on_a_constant_image_give_the_constant() {
    let (w, h) = (60u32, 45u32);
    let c = [90u8, 140, 200];
    let background = image::RgbImage::from_pixel(120, 90, image::Rgb(c));
    for s in samplers::all(4) {
        let sites = s.sites(w, h, 150);
        let colours = constant_colours(sites.len(), c);
        let out = (120, 90);
        let imgs = [
            (
                "mosaic",
                styles::mosaic(&sites, &colours, (w, h), out).unwrap(),
            ),
            (
                "strokes",
                styles::strokes(&sites, &colours, (w, h), out).unwrap(),
            ),
            (
                "voronoi",
                styles::voronoi(&sites, &colours, (w, h), out).unwrap(),
            ),
            (
                "delaunay",
                styles::delaunay_over(&sites, (w, h), &background).unwrap(),
            ),
        ];
        for (name, img) in imgs {
            assert_eq!(img.dimensions(), out);
            let mut other = 0;
            let mut ink = 0;
            for p in img.pixels() {
                if p.0 == INK {
                    ink += 1;
                } else if p.0 != c {
                    other += 1;
                }
            }
            assert_eq!(
                other,
                0,
                "{name}/{}: {other} pixels neither constant nor ink",
                s.name()
            );
            if name == "strokes" {
                assert_eq!(ink, 0, "strokes have no ink");
            }
            let constant = img.pixels().filter(|p| p.0 == c).count();
            assert!(constant > img.pixels().count() / 2, "{name}/{}", s.name());
        }
    }
}

#[test]
fn strokes_sharpen_transitions_relative_to_gouraud() {
    // Two sites black, two white on a square: along the middle row the sharp
    // version is closer to pure black/white than plain linear shading.
    let sites = [[0.5, 0.5], [63.5, 0.5], [0.5, 63.5], [63.5, 63.5]];
    let colours = [0, 0, 0, 0, 0, 0, 255, 255, 255, 255, 255, 255];
    let lin = styles::strokes_with(&sites, &colours, (64, 64), (64, 64), 1.0).unwrap();
    let sharp = styles::strokes(&sites, &colours, (64, 64), (64, 64)).unwrap();
    let extreme =
        |img: &image::RgbImage| img.pixels().filter(|p| p.0[0] < 20 || p.0[0] > 235).count();
    assert!(
        extreme(&sharp) > 2 * extreme(&lin),
        "{} vs {}",
        extreme(&sharp),
        extreme(&lin)
    );
    // Linear shading at the vertical centre is mid grey.
    let mid = lin.get_pixel(32, 31).0[0];
    assert!((110..=145).contains(&mid), "{mid}");
}

#[test]
fn renderers_reject_bad_input() {
    let sites = [[1.0, 1.0], [2.0, 2.0]];
    assert!(styles::mosaic(&sites, &[0; 5], (4, 4), (4, 4)).is_err());
    assert!(styles::voronoi(&sites, &[0; 6], (0, 4), (4, 4)).is_err());
    assert!(styles::strokes(&sites, &[0; 6], (4, 4), (4, 0)).is_err());
    assert!(styles::order(&[[f64::NAN, 1.0]], (4, 4), (4, 4)).is_err());
    assert!(styles::delaunay_graph(&[[1e300, 1.0], [0.0, 0.0]], (4, 4), (4, 4)).is_err());
    assert!(styles::spectrum(&sites, (4, 4), 1).is_err());
    assert!(styles::mosaic(&sites, &[0; 6], (4, 4), (1 << 20, 1 << 20)).is_err());
    // Empty and tiny site sets are fine.
    assert!(styles::mosaic(&[], &[], (4, 4), (4, 4)).is_ok());
    assert!(styles::strokes(&sites, &[9; 6], (4, 4), (4, 4)).is_ok());
}

#[test]
fn order_colours_run_from_dark_blue_to_light_green() {
    let sites = Halton.sites(100, 100, 50);
    let img = styles::order(&sites, (100, 100), (200, 200)).unwrap();
    let first = img
        .get_pixel((sites[0][0] * 2.0) as u32, (sites[0][1] * 2.0) as u32)
        .0;
    let last = img
        .get_pixel((sites[49][0] * 2.0) as u32, (sites[49][1] * 2.0) as u32)
        .0;
    assert!(
        first[2] > first[1] && first[1] < 60,
        "{first:?} is dark blue"
    );
    assert!(
        last[1] > 200 && last[1] > last[2],
        "{last:?} is light green"
    );
}

#[test]
fn delaunay_graph_edge_count() {
    let t = styles::Triangulation::new(&Halton.sites(50, 50, 200)).unwrap();
    // Euler: E = 3V − 3 − hull, T = 2V − 2 − hull for a triangulation.
    let (e, f) = (t.edges().len(), t.cells().len());
    assert_eq!(e + 1, 200 + f, "V − E + F = 2 with the outer face");
}

#[test]
fn spectrum_of_a_periodic_grid_peaks_at_lattice_frequencies() {
    // 33×33 grid on 256×256: lattice spacing 255/32 px, so the reciprocal lattice
    // is the multiples of 32·256/255 ≈ 32.13 cycles per image on each axis.
    let n = 256usize;
    let sites = Periodic.sites(256, 256, 1089);
    let p = styles::power_spectrum(&sites, (256, 256), n).unwrap();
    let half = (n / 2) as i64;
    let mut bins: Vec<(f64, i64, i64)> = Vec::new();
    for v in 0..n as i64 {
        for u in 0..n as i64 {
            let (fu, fv) = (u - half, v - half);
            if (fu, fv) != (0, 0) {
                bins.push((p[(v as usize) * n + u as usize], fu, fv));
            }
        }
    }
    bins.sort_by(|a, b| b.0.total_cmp(&a.0));
    let near_lattice = |f: i64| {
        let k = (f as f64 / (32.0 * 256.0 / 255.0)).round();
        (f as f64 - k * 32.0 * 256.0 / 255.0).abs() <= 1.0
    };
    for &(power, fu, fv) in &bins[..12] {
        assert!(
            near_lattice(fu) && near_lattice(fv),
            "peak at ({fu}, {fv}) power {power}"
        );
    }
    let strongest_axis = bins.iter().find(|b| b.2 == 0 && b.1 != 0).unwrap();
    assert!(
        strongest_axis.1.abs() == 32,
        "first axis peak at {}",
        strongest_axis.1
    );
    let mut sorted: Vec<f64> = bins.iter().map(|b| b.0).collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    assert!(
        bins[0].0 > 100.0 * median.max(1e-9),
        "peak {} vs median {median}",
        bins[0].0
    );
    // The picture puts DC at the centre, saturated.
    let img = styles::spectrum(&sites, (256, 256), n).unwrap();
    assert_eq!(img.get_pixel(128, 128).0, [255]);
}

#[test]
fn random_spectrum_is_flat() {
    let n = 64usize;
    let sites = Random { seed: 2 }.sites(64, 64, 2000);
    let p = styles::power_spectrum(&sites, (64, 64), n).unwrap();
    let dc = (n / 2) * n + n / 2;
    let mean: f64 = p
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != dc)
        .map(|(_, v)| v)
        .sum::<f64>()
        / (n * n - 1) as f64;
    // White noise: mean power per site ≈ 1 − N/cells-ish (cells are shared); within 40%.
    assert!((0.4..1.4).contains(&mean), "{mean}");
    assert!((p[dc] - 2000.0).abs() < 1e-6);
}

#[test]
fn phase_function_is_real_symmetric_and_contains_the_sites() {
    // Rotation by ζ = e^{2πi/10} and z ↦ −z leave f unchanged.
    for z in [[0.3, 0.7], [1.1, -0.4], [2.5, 2.5]] {
        let f = styles::phase_value(z);
        let a = std::f64::consts::PI / 5.0;
        let r = [
            z[0] * a.cos() - z[1] * a.sin(),
            z[0] * a.sin() + z[1] * a.cos(),
        ];
        assert!((styles::phase_value(r) - f).abs() < 1e-9);
        assert!((styles::phase_value([-z[0], -z[1]]) - f).abs() < 1e-9);
        assert!(f.abs() <= 10.0 + 1e-9);
    }
    let window = PhaseWindow::centred(6.0);
    let sites = styles::phase_sites(window, 2.0, 100_000).unwrap();
    assert!(sites.len() > 100, "{} sites", sites.len());
    assert!(sites.iter().all(|&z| styles::phase_value(z) >= 2.0));
    // A Delone set: no two sites closer than 1/τ (the quasicrystal's short distance).
    let md = min_dist(&sites);
    assert!((md - 0.618_034).abs() < 1e-6, "min distance {md}");
    // The level set picture shows every site inside the grey region.
    let img = styles::phase_level_set(window, (300, 300), 2.0).unwrap();
    assert_eq!(img.get_pixel(150, 150).0, [160, 0, 0]);
    let contour = styles::phase_contour(PhaseWindow::centred(0.5), (200, 200)).unwrap();
    // Around the centre (f ≈ 10) the ramp is deep red; a band away it is not.
    let red = |p: [u8; 3]| p[0] == 255 && p[1] < 40 && p[2] < 40;
    assert!((98..103).any(|i| (98..103).any(|j| red(contour.get_pixel(i, j).0))));
    assert!(contour.pixels().filter(|p| red(p.0)).count() < 200 * 200 / 10);
    assert!(styles::phase_contour(
        PhaseWindow {
            x0: 1.0,
            y0: 0.0,
            x1: 0.0,
            y1: 1.0
        },
        (4, 4)
    )
    .is_err());
}

#[test]
fn canonical_cells_merge_cocircular_triangles_only() {
    // A regular pentagon (5 cocircular sites) is one cell of 5 vertices.
    let pent: Vec<Point> = (0..5)
        .map(|k| {
            let a = 2.0 * std::f64::consts::PI * k as f64 / 5.0;
            [50.0 + 20.0 * a.cos(), 50.0 + 20.0 * a.sin()]
        })
        .collect();
    let t = styles::Triangulation::new(&pent).unwrap();
    let cells = t.cells();
    assert_eq!(cells.len(), 1);
    let mut c = cells[0].clone();
    c.sort_unstable();
    assert_eq!(c, vec![0, 1, 2, 3, 4]);
    assert_eq!(t.triangles().len(), 3);
    // The 9×9 periodic grid: 64 square cells.
    let grid = Periodic.sites(129, 129, 81);
    let cells = styles::Triangulation::new(&grid).unwrap().cells();
    assert_eq!(cells.len(), 64);
    assert!(cells.iter().all(|c| c.len() == 4));
    // Random sites: no cocircular quadruples, so cells are the Delaunay triangles.
    let r = Random { seed: 8 }.sites(100, 100, 300);
    let t = styles::Triangulation::new(&r).unwrap();
    assert!(t.cells().iter().all(|c| c.len() == 3));
    // Duplicated sites are merged, not a failure.
    let dup = [[1.0, 1.0], [1.0, 1.0], [5.0, 1.0], [1.0, 5.0]];
    assert_eq!(styles::Triangulation::new(&dup).unwrap().cells().len(), 1);
}

#[test]
fn quasicrystal_cells_are_exact_and_match_the_tolerant_merge() {
    use qcs_lab::styles::{Sites, Triangulation};
    // Cells as sorted vertex lists, without the zero-area slivers of collinear hull sites
    // that the tolerant merge keeps (the exact cells drop them).
    let norm = |cells: Vec<Vec<usize>>, pos: &[[f64; 2]]| {
        let area = |c: &[usize]| {
            let k = c.len();
            (0..k)
                .map(|i| {
                    let (a, b) = (pos[c[i]], pos[c[(i + 1) % k]]);
                    a[0] * b[1] - a[1] * b[0]
                })
                .sum::<f64>()
                .abs()
        };
        let mut v: Vec<Vec<usize>> = cells
            .into_iter()
            .filter(|c| area(c) > 1e-6)
            .map(|mut c| {
                c.sort_unstable();
                c
            })
            .collect();
        v.sort();
        v
    };
    for (w, h, n) in [(64, 64, 300), (120, 80, 1500), (200, 30, 900)] {
        let sites = qcs::sites::Quasicrystal::new(w, h).unwrap().first(n);
        let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
        let lat: Vec<_> = sites.iter().map(|s| s.lattice).collect();
        let exact = Triangulation::of(Sites::exact(&pos, &lat)).unwrap();
        let tolerant = Triangulation::of(&pos).unwrap();
        assert!(exact.is_exact() && !tolerant.is_exact());
        let cells = exact.cells();
        assert!(cells.iter().any(|c| c.len() == 4) && cells.iter().any(|c| c.len() == 5));
        assert_eq!(
            norm(cells, &pos),
            norm(tolerant.cells(), &pos),
            "{w}×{h}, {n}"
        );
        // The wireframe: every cell edge once, no diagonal inside a cell.
        let edges = exact.edges();
        let sides: usize = exact.cells().iter().map(|c| c.len()).sum();
        assert!(edges.len() < sides && edges.windows(2).all(|e| e[0] < e[1]));
        for c in exact.cells().iter().filter(|c| c.len() >= 4) {
            assert!(edges
                .binary_search(&[c[0].min(c[2]), c[0].max(c[2])])
                .is_err());
        }
    }
}
