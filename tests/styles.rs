//! Samplers (determinism, bounds, prefix property, farthest-point optimality) and
//! stylized renderers (mosaic congruence, constant images, spectrum peaks, phase).

use qcs::sites::strategies::{self, FarthestPoint, Halton, Jittered, Periodic, Random};
use qcs::sites::{Point, Sampler};

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
        for s in strategies::all(11) {
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
    for s in strategies::all(0) {
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
