//! The quasicrystal phase function of the paper's Fig. 2.

use std::collections::{HashSet, VecDeque};

use image::{Rgb, RgbImage};

use crate::Result;

const TAU: f64 = 1.618_033_988_749_895;

/// A window of the complex plane in lattice units (root length 1), `x` right and `y` up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseWindow {
    /// Left edge.
    pub x0: f64,
    /// Bottom edge.
    pub y0: f64,
    /// Right edge.
    pub x1: f64,
    /// Top edge.
    pub y1: f64,
}

impl PhaseWindow {
    /// The square `[−r, r]²` centred on the origin.
    pub fn centred(r: f64) -> Self {
        PhaseWindow {
            x0: -r,
            y0: -r,
            x1: r,
            y1: r,
        }
    }
    fn check(&self) -> Result<()> {
        let ok = [self.x0, self.y0, self.x1, self.y1]
            .iter()
            .all(|v| v.is_finite())
            && self.x1 > self.x0
            && self.y1 > self.y0;
        if ok {
            Ok(())
        } else {
            Err(crate::invalid(
                "phase window",
                format_args!("{self:?}"),
                "finite bounds with x1 > x0 and y1 > y0",
            ))
        }
    }
    fn contains(&self, z: [f64; 2]) -> bool {
        z[0] >= self.x0 && z[0] <= self.x1 && z[1] >= self.y0 && z[1] <= self.y1
    }
    /// Centre of output pixel `(i, j)` of a `w × h` picture (row 0 at the top).
    fn point(&self, i: u32, j: u32, w: u32, h: u32) -> [f64; 2] {
        [
            self.x0 + (i as f64 + 0.5) / w as f64 * (self.x1 - self.x0),
            self.y1 - (j as f64 + 0.5) / h as f64 * (self.y1 - self.y0),
        ]
    }
    fn pixel(&self, z: [f64; 2], w: u32, h: u32) -> [f64; 2] {
        [
            (z[0] - self.x0) / (self.x1 - self.x0) * w as f64,
            (self.y1 - z[1]) / (self.y1 - self.y0) * h as f64,
        ]
    }
}

/// `f(z) = Σ_{j=0}^{9} exp(2πi ζʲ·(2τ⁴z))`, `ζ = e^{2πi/10}`, `u·v = Re(u v̄)`.
///
/// The terms `j` and `j+5` are complex conjugates (`ζ^{j+5} = −ζʲ`), so `f` is
/// real: this returns `Σ cos(2π·2τ⁴ (x cos(πj/5) + y sin(πj/5)))`. Its maximum is
/// `f(0) = 10`; it is invariant under rotation by `ζ` and under `z ↦ −z`.
pub fn phase_value(z: [f64; 2]) -> f64 {
    let k = 2.0 * TAU.powi(4);
    (0..10)
        .map(|j| {
            let a = std::f64::consts::PI * j as f64 / 5.0;
            (2.0 * std::f64::consts::PI * k * (z[0] * a.cos() + z[1] * a.sin())).cos()
        })
        .sum()
}

fn check_size(size: (u32, u32)) -> Result<()> {
    if size.0 == 0 || size.1 == 0 {
        return Err(crate::invalid(
            "output size",
            format_args!("{}×{}", size.0, size.1),
            "at least 1×1",
        ));
    }
    qcs::Limits::default().check_output(size.0 as u64, size.1 as u64)?;
    Ok(())
}

/// Contour map of the phase function over `window` at `size`: a blue (−10) –
/// white (0) – red (+10) colour ramp with dark contour lines at the levels
/// −6, −2, 2, 6. `f` oscillates with wavelength down to `1/(2τ⁴) ≈ 0.073` lattice
/// units, so give at least ~100 pixels per unit (windows of a few units).
pub fn phase_contour(window: PhaseWindow, size: (u32, u32)) -> Result<RgbImage> {
    window.check()?;
    check_size(size)?;
    let (w, h) = size;
    let values: Vec<f64> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| phase_value(window.point(i, j, w, h)))
        .collect();
    let band = |v: f64| ((v + 2.0) / 4.0).floor() as i64;
    Ok(RgbImage::from_fn(w, h, |i, j| {
        let k = (j * w + i) as usize;
        let v = values[k];
        let right = if i + 1 < w { values[k + 1] } else { v };
        let down = if j + 1 < h { values[k + w as usize] } else { v };
        if band(right) != band(v) || band(down) != band(v) {
            return Rgb([40, 40, 40]);
        }
        let t = (v / 10.0).clamp(-1.0, 1.0);
        let c = if t >= 0.0 {
            [255.0, 255.0 * (1.0 - t), 255.0 * (1.0 - t)]
        } else {
            [255.0 * (1.0 + t), 255.0 * (1.0 + t), 255.0]
        };
        Rgb(c.map(|x| x.round() as u8))
    }))
}

/// The unit roots `ζʲ` as points.
fn roots() -> [[f64; 2]; 10] {
    let mut r = [[0.0; 2]; 10];
    for (j, z) in r.iter_mut().enumerate() {
        let a = std::f64::consts::PI * j as f64 / 5.0;
        *z = [a.cos(), a.sin()];
    }
    r
}

/// The point set of Fig. 2's construction: start at the origin; for every
/// accepted point `x`, accept the candidates `x + ζʲ` (`j = 0…9`) with
/// `f(x + ζʲ) ≥ threshold` that lie in `window`. At most `max_sites` points are
/// returned, in breadth-first order (the origin first if it is in the window).
/// Thresholds in `[1, 3]` give a quasicrystal with nearest-neighbour distance
/// `1/τ` (measured: 583 sites in `[−10, 10]²` at `T = 2`); above about 3.2 no
/// unit step leaves the origin.
/// Points are keyed by their exact integer coordinates in the basis `1, ζ, ζ², ζ³`
/// of `Z[ζ]`, so no point is found twice.
pub fn phase_sites(window: PhaseWindow, threshold: f64, max_sites: usize) -> Result<Vec<[f64; 2]>> {
    window.check()?;
    if !threshold.is_finite() {
        return Err(crate::invalid("threshold", threshold, "a finite number"));
    }
    // ζ^j in the basis 1, ζ, ζ², ζ³ of Z[ζ] with ζ = e^{2πi/5}; the tenth roots are ±ζ^k
    // (e^{iπ/5·j}: j even → ζ^{j/2}, j odd → −ζ^{(j+5)/2 mod 5}).
    let fifth: [[i64; 4]; 5] = [
        [1, 0, 0, 0],
        [0, 1, 0, 0],
        [0, 0, 1, 0],
        [0, 0, 0, 1],
        [-1, -1, -1, -1],
    ];
    let steps: Vec<[i64; 4]> = (0..10)
        .map(|j| {
            if j % 2 == 0 {
                fifth[j / 2]
            } else {
                fifth[((j + 5) / 2) % 5].map(|v| -v)
            }
        })
        .collect();
    let r = roots();
    let z5 = [r[0], r[2], r[4], r[6], r[8]];
    let pos = |n: &[i64; 4]| {
        let mut p = [0.0, 0.0];
        for k in 0..4 {
            p[0] += n[k] as f64 * z5[k][0];
            p[1] += n[k] as f64 * z5[k][1];
        }
        p
    };
    let mut out = Vec::new();
    let origin = [0i64; 4];
    if max_sites == 0 || !window.contains([0.0, 0.0]) || phase_value([0.0, 0.0]) < threshold {
        return Ok(out);
    }
    let mut seen = HashSet::new();
    let mut queue = VecDeque::new();
    seen.insert(origin);
    queue.push_back(origin);
    while let Some(x) = queue.pop_front() {
        out.push(pos(&x));
        if out.len() == max_sites {
            break;
        }
        for s in &steps {
            let z = [x[0] + s[0], x[1] + s[1], x[2] + s[2], x[3] + s[3]];
            if seen.contains(&z) {
                continue;
            }
            let p = pos(&z);
            if window.contains(p) && phase_value(p) >= threshold {
                seen.insert(z);
                queue.push_back(z);
            }
        }
    }
    Ok(out)
}

/// The level set `f(z) ≥ threshold` (grey) over `window`, with the points of
/// [`phase_sites`] drawn as dark red dots: the sites lie inside the level set.
pub fn phase_level_set(window: PhaseWindow, size: (u32, u32), threshold: f64) -> Result<RgbImage> {
    window.check()?;
    check_size(size)?;
    let (w, h) = size;
    let mut img = RgbImage::from_fn(w, h, |i, j| {
        if phase_value(window.point(i, j, w, h)) >= threshold {
            Rgb([170, 170, 170])
        } else {
            Rgb([255, 255, 255])
        }
    });
    let sites = phase_sites(window, threshold, 1 << 20)?;
    let r = (w as f64 / (window.x1 - window.x0) * 0.12).max(1.5);
    for z in sites {
        let q = window.pixel(z, w, h);
        let i0 = (q[0] - r).floor().max(0.0) as i64;
        let i1 = (q[0] + r).ceil().min(w as f64 - 1.0) as i64;
        let j0 = (q[1] - r).floor().max(0.0) as i64;
        let j1 = (q[1] + r).ceil().min(h as f64 - 1.0) as i64;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let (dx, dy) = (i as f64 + 0.5 - q[0], j as f64 + 0.5 - q[1]);
                if dx * dx + dy * dy <= r * r {
                    img.put_pixel(i as u32, j as u32, Rgb([160, 0, 0]));
                }
            }
        }
    }
    Ok(img)
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn centred_window() {
        let w = crate::styles::PhaseWindow::centred(2.0);
        assert_eq!((w.x0, w.x1), (-2.0, 2.0));
    }

    #[test]
    fn phase_value_at_the_origin() {
        assert!((crate::styles::phase_value([0.0, 0.0]) - 10.0).abs() < 1e-12);
    }

    #[test]
    fn phase_contour_has_the_asked_size() {
        use crate::styles::{phase_contour, PhaseWindow};
        let img = phase_contour(PhaseWindow::centred(1.0), (64, 64)).unwrap();
        assert_eq!(img.dimensions(), (64, 64));
    }

    #[test]
    fn phase_sites_start_at_the_origin_above_the_level() {
        use crate::styles::{phase_sites, PhaseWindow};
        let s = phase_sites(PhaseWindow::centred(3.0), 2.0, 10_000).unwrap();
        assert_eq!(s[0], [0.0, 0.0]);
        assert!(s.len() > 10);
        assert!(s.iter().all(|&z| crate::styles::phase_value(z) >= 2.0));
    }

    #[test]
    fn phase_level_set_marks_the_origin() {
        use crate::styles::{phase_level_set, PhaseWindow};
        let img = phase_level_set(PhaseWindow::centred(2.0), (80, 80), 2.0).unwrap();
        assert_eq!(img.get_pixel(40, 40).0, [160, 0, 0]); // the origin is a site
    }
}
