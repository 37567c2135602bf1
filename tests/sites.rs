//! The site construction against independent expectations (paper, notes, brute force).

use qcs::lattice::{decagon_forms, disk_candidates, sign_plus_sin72, ZTau, ZZeta};

fn in_closed_square(x: ZZeta) -> bool {
    let re2 = x.re2();
    let im = x.im_s();
    (re2 - ZTau::int(2)).signum() <= 0
        && (re2 + ZTau::int(2)).signum() >= 0
        && sign_plus_sin72(ZTau::int(-1), im) <= 0
        && sign_plus_sin72(ZTau::int(1), im) >= 0
}

fn fig1(closed: bool) -> usize {
    let r = ZTau::new(4, 7); // τ⁵ + τ³
    let mut n = 0;
    disk_candidates([-1.0, 1.0, -1.0, 1.0], r.to_f64(), &mut |x| {
        let forms = decagon_forms(x.star());
        let two_r = r.scale(2);
        let ok_dec = forms.iter().all(|f| {
            let a = (*f - two_r).signum();
            let b = (-*f - two_r).signum();
            if closed {
                a <= 0 && b <= 0
            } else {
                a < 0 && b < 0
            }
        });
        let ok_sq = if closed {
            in_closed_square(x)
        } else {
            let re2 = x.re2();
            let im = x.im_s();
            (re2 - ZTau::int(2)).signum() < 0
                && (re2 + ZTau::int(2)).signum() > 0
                && sign_plus_sin72(ZTau::int(-1), im) < 0
                && sign_plus_sin72(ZTau::int(1), im) > 0
        };
        if ok_dec && ok_sq {
            n += 1;
        }
    });
    n
}

#[test]
fn paper_figure_1_has_1035_points() {
    assert_eq!(fig1(true), 1035);
    assert_eq!(fig1(false), 919);
}

#[test]
fn disk_of_fig1_radius_has_1039_points() {
    let r = ZTau::new(4, 7);
    let r2 = r * r;
    let mut n = 0;
    disk_candidates([-1.0, 1.0, -1.0, 1.0], r.to_f64(), &mut |x| {
        if in_closed_square(x) && (x.star().norm2() - r2).signum() <= 0 {
            n += 1;
        }
    });
    assert_eq!(n, 1039);
}

use qcs::sites::{site_order, Frame, Quasicrystal, DENSITY};

/// All lattice points of the image with |x*|² ≤ r2, by a plain filter over the candidates
/// of a much larger disk, sorted with the exact comparator.
fn brute_sorted(q: &Quasicrystal, w: u32, h: u32, r: f64) -> Vec<ZZeta> {
    let f = q.frame();
    let l = f.root_len as f64 / 65536.0;
    let o = [f.origin[0] as f64 / 65536.0, f.origin[1] as f64 / 65536.0];
    let mut v = Vec::new();
    disk_candidates(
        [
            -o[0] / l - 1.0,
            (w as f64 - o[0]) / l + 1.0,
            -o[1] / l - 1.0,
            (h as f64 - o[1]) / l + 1.0,
        ],
        r,
        &mut |x| {
            if f.contains(x, w, h) {
                v.push(x)
            }
        },
    );
    v.sort_by(|a, b| site_order(*a, *b));
    v
}

#[test]
fn first_n_equals_brute_force_sort() {
    for (w, h, frame) in [
        (64, 64, None),
        (97, 41, None),
        (
            50,
            80,
            Some(Frame {
                root_len: 3 << 15,
                origin: [25 << 16, 40 << 16],
            }),
        ),
    ] {
        let q = match frame {
            Some(f) => Quasicrystal::with_frame(w, h, f).unwrap(),
            None => Quasicrystal::new(w, h).unwrap(),
        };
        let n = 1500;
        let all = brute_sorted(&q, w, h, q.radius_for(4.0 * n as f64));
        assert!(all.len() > 2 * n);
        let got: Vec<ZZeta> = q.first(n).iter().map(|s| s.lattice).collect();
        assert_eq!(got, all[..n].to_vec());
        // Positions lie in the image, in raster order within ties.
        for s in q.first(n) {
            assert!(
                s.pos[0] >= 0.0 && s.pos[0] < w as f64 && s.pos[1] >= 0.0 && s.pos[1] < h as f64
            );
        }
    }
}

#[test]
fn prefixes_are_consistent_and_deterministic() {
    let q = Quasicrystal::new(300, 200).unwrap();
    let long = q.first(5000);
    for k in [1, 2, 3, 17, 100, 999, 4321] {
        assert_eq!(q.first(k)[..], long[..k]);
    }
}

fn nn_and_cover(pts: &[[f64; 2]], w: f64, h: f64) -> (f64, f64) {
    let mut min_nn = f64::INFINITY;
    for (i, a) in pts.iter().enumerate() {
        for b in &pts[i + 1..] {
            min_nn = min_nn.min(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
        }
    }
    // Largest empty circle centred on a fine grid of pixel centres inside the image.
    let mut cover: f64 = 0.0;
    let step = (w.max(h) / 64.0).max(1.0);
    let mut y = 0.5;
    while y < h {
        let mut x = 0.5;
        while x < w {
            let d = pts
                .iter()
                .map(|p| (p[0] - x).powi(2) + (p[1] - y).powi(2))
                .fold(f64::INFINITY, f64::min);
            cover = cover.max(d.sqrt());
            x += step;
        }
        y += step;
    }
    (min_nn, cover)
}

/// The Delone constants written in spec/sites.md.
const DELONE_A: f64 = 0.50;
const DELONE_B: f64 = 2.0;

#[test]
fn every_prefix_is_delone() {
    let (w, h) = (256u32, 192u32);
    let q = Quasicrystal::new(w, h).unwrap();
    let all: Vec<[f64; 2]> = q.first(2000).iter().map(|s| s.pos).collect();
    let mut worst = (f64::INFINITY, 0.0f64);
    for n in (16..=2000).step_by(37) {
        let (nn, cov) = nn_and_cover(&all[..n], w as f64, h as f64);
        let unit = ((w * h) as f64 / n as f64).sqrt();
        worst = (worst.0.min(nn / unit), worst.1.max(cov / unit));
    }
    assert!(worst.0 >= DELONE_A, "nearest neighbour ratio {}", worst.0);
    assert!(worst.1 <= DELONE_B, "covering ratio {}", worst.1);
}

#[test]
fn count_follows_the_density_formula() {
    let (w, h) = (400u32, 300u32);
    let q = Quasicrystal::new(w, h).unwrap();
    let f = q.frame();
    for target in [1000.0, 20000.0] {
        let r = q.radius_for(target);
        let r2 = r * r;
        let mut n = 0usize;
        let l = f.root_len as f64 / 65536.0;
        let o = [f.origin[0] as f64 / 65536.0, f.origin[1] as f64 / 65536.0];
        disk_candidates(
            [
                -o[0] / l,
                (w as f64 - o[0]) / l,
                -o[1] / l,
                (h as f64 - o[1]) / l,
            ],
            r,
            &mut |x| {
                let (sr, si) = x.star().to_f64();
                if f.contains(x, w, h) && sr * sr + si * si <= r2 {
                    n += 1;
                }
            },
        );
        let expected = DENSITY * (w * h) as f64 * std::f64::consts::PI * r2;
        let rel = n as f64 / expected - 1.0;
        assert!(
            rel.abs() < 0.02,
            "target {target}: {n} vs {expected:.1} ({rel:+.4})"
        );
    }
}

/// The committed first-64 vectors of spec/vectors/ (regenerate with QCS_REGENERATE=1).
#[test]
fn committed_site_vectors() {
    for (w, h) in [(64u32, 64u32), (480, 320), (1000, 17)] {
        let q = Quasicrystal::new(w, h).unwrap();
        let mut text = String::from("index,x,y,n0,n1,n2,n3,p,q\n");
        for (i, s) in q.first(64).iter().enumerate() {
            let [n0, n1, n2, n3] = s.lattice.0;
            let r2 = s.lattice.star().norm2();
            text += &format!(
                "{i},{:.9},{:.9},{n0},{n1},{n2},{n3},{},{}\n",
                s.pos[0], s.pos[1], r2.a, r2.b
            );
        }
        let path = format!(
            "{}/spec/vectors/sites-{w}x{h}.csv",
            env!("CARGO_MANIFEST_DIR")
        );
        if std::env::var("QCS_REGENERATE").is_ok_and(|v| v == "1") {
            std::fs::write(&path, &text).unwrap();
        }
        let want =
            std::fs::read_to_string(&path).expect("vector file (QCS_REGENERATE=1 writes it)");
        assert_eq!(text, want, "{path}");
    }
}

/// The integer bounds of spec/sites.md §4 hold at the extremes the frame allows
/// (tests run with overflow checks on).
#[test]
fn integer_bounds_hold_at_the_extremes() {
    let frames = [
        (65535u32, 65535u32, Frame::default_for(65535, 65535)),
        (
            65535,
            1,
            Frame {
                root_len: 1 << 16,
                origin: [i32::MIN, i32::MAX],
            },
        ),
        (
            1,
            65535,
            Frame {
                root_len: 1 << 16,
                origin: [i32::MAX, i32::MIN],
            },
        ),
        (
            300,
            200,
            Frame {
                root_len: 1 << 24,
                origin: [0, 0],
            },
        ),
    ];
    for (w, h, f) in frames {
        let q = Quasicrystal::with_frame(w, h, f).unwrap();
        for s in q.first(2000) {
            let n = s.lattice.0;
            assert!(n.iter().all(|v| v.abs() < 1 << 20), "{n:?}");
            let r2 = s.lattice.star().norm2();
            assert!(r2.a.abs() < 1 << 37 && r2.b.abs() < 1 << 37, "{r2:?}");
            assert!(
                s.pos[0] >= 0.0 && s.pos[0] < w as f64 && s.pos[1] >= 0.0 && s.pos[1] < h as f64
            );
        }
    }
    // Sizes and root lengths outside the bounds are refused.
    assert!(Quasicrystal::new(0, 5).is_err() && Quasicrystal::new(65536, 5).is_err());
    assert!(Quasicrystal::with_frame(
        9,
        9,
        Frame {
            root_len: (1 << 16) - 1,
            origin: [0, 0]
        }
    )
    .is_err());
}
