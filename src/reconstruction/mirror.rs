//! Mirror points: samples near an image edge, reflected across it.
//!
//! A prefix of the site sequence covers the image only up to a ragged band along its edges,
//! and the sites that arrive there later are sparse at first: triangles between them are long
//! slivers along the edge, which smear colours over hundreds of pixels and make the picture
//! worse when samples are added. So every sample close enough to an edge is also triangulated
//! as its mirror image across that edge (and, near a corner, across both), carrying the
//! sample's colour. The triangulation of samples and mirror points covers the image, its cells
//! at the edges are as well shaped as inside, and the outside-the-hull rule is only a fallback
//! for the first few samples.
//!
//! **Which samples** (`spec/reconstruction.md`): sample `k` (0-based, in file order) at
//! `(x, y)` in a `W × H` source is mirrored across the left edge if `0 ≤ x` and
//! `x²·(k+1) < 4·W·H`, across the right edge if `0 ≤ W − x` and `(W − x)²·(k+1) < 4·W·H`, and
//! likewise for the top and bottom edges (`f64`, evaluated as written): a sample is near an
//! edge when it is within twice the sample spacing `√(W·H/(k+1))` of its own arrival. The
//! decision is made once, when the sample arrives, so mirror points only ever accumulate.
//!
//! **Where**: samples with exact lattice points are reflected across *lattice* mirror lines,
//! so that their images are lattice points too and the exact predicates keep deciding the
//! cells: the vertical lines `Re x = a/2` and the horizontal lines `Im x = b·sin 72°`
//! (`a, b ∈ Z`), taking on each side the nearest such line on or outside the image edge.
//! Reflections are `x ↦ a − x̄` and `x ↦ x̄ + b·(ζ − ζ⁴)`. Other samples are reflected across
//! the edges themselves (`x ↦ −x`, `2W − x`, …).

use crate::lattice::{sign_plus_sin72, within_exact_limit, ZTau, ZZeta};
use crate::sites::{Frame, Point, FX_ONE};

/// The lattice mirror lines of a frame: `[left a, right a, top b, bottom b]` with vertical
/// lines `Re x = a/2` and horizontal lines `Im x = b·sin 72°`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Lines {
    frame: Frame,
    line: [i64; 4],
}

/// `⌊p / q⌋` for `q > 0`.
fn floor_div(p: i64, q: i64) -> i64 {
    p.div_euclid(q)
}

impl Lines {
    /// The mirror lines of `frame` for a `width × height` image.
    pub(crate) fn new(frame: Frame, width: u32, height: u32) -> Lines {
        let l = frame.root_len.max(1) as i64;
        let [ox, oy] = frame.origin.map(|v| v as i64);
        // Vertical: pixel x of Re x = a/2 is (2·ox + L·a) / 2^17.
        let left = floor_div(-2 * ox, l); // largest a with 2·ox + L·a ≤ 0
        let right = -floor_div(2 * ox - 2 * width as i64 * FX_ONE, l); // smallest a, ≥ 2W
                                                                       // Horizontal: pixel y of Im x = b·s is (oy + L·s·b) / 2^16; decided with exact signs.
        let y_sign = |b: i64, target: i64| {
            sign_plus_sin72(
                ZTau::int((oy - target) as i128),
                ZTau::int(l as i128 * b as i128),
            )
        };
        let guess = |target: i64| {
            ((target - oy) as f64 / (l as f64 * crate::lattice::SIN72)).floor() as i64
        };
        // Largest b with y(b) ≤ 0.
        let mut top = guess(0);
        while y_sign(top + 1, 0) <= 0 {
            top += 1;
        }
        while y_sign(top, 0) > 0 {
            top -= 1;
        }
        // Smallest b with y(b) ≥ H.
        let target = height as i64 * FX_ONE;
        let mut bottom = guess(target) + 1;
        while y_sign(bottom - 1, target) >= 0 {
            bottom -= 1;
        }
        while y_sign(bottom, target) < 0 {
            bottom += 1;
        }
        Lines {
            frame,
            line: [left, right, top, bottom],
        }
    }

    /// The lattice frame the lines are in.
    pub(crate) fn frame(&self) -> &Frame {
        &self.frame
    }

    /// `x` reflected across line `side` (0 left, 1 right, 2 top, 3 bottom).
    fn reflect(&self, x: ZZeta, side: usize) -> ZZeta {
        let [n0, n1, n2, n3] = x.0;
        // Complex conjugate: ζ^k ↦ ζ^{5−k}, with ζ⁴ = −1 − ζ − ζ² − ζ³.
        let conj = [n0 - n1, -n1, n3 - n1, n2 - n1];
        let m = self.line[side];
        if side < 2 {
            // a − x̄
            ZZeta([m - conj[0], -conj[1], -conj[2], -conj[3]])
        } else {
            // x̄ + b·(ζ − ζ⁴), ζ − ζ⁴ = 2i·sin 72° = 1 + 2ζ + ζ² + ζ³.
            ZZeta([conj[0] + m, conj[1] + 2 * m, conj[2] + m, conj[3] + m])
        }
    }
}

/// The mirror points of sample `k` at `pos` in a `width × height` source: positions and, with
/// `exact = Some((lines, x))`, their lattice points. Mirror images whose lattice point would
/// be beyond [`crate::lattice::EXACT_LIMIT`] are left out.
pub(crate) fn mirror_points(
    k: usize,
    pos: Point,
    width: u32,
    height: u32,
    exact: Option<(&Lines, ZZeta)>,
    mut out: impl FnMut(Point, Option<ZZeta>),
) {
    let (w, h) = (width as f64, height as f64);
    let limit = 4.0 * w * h;
    let near = |d: f64| d >= 0.0 && d * d * (k as f64 + 1.0) < limit;
    let sx = [near(pos[0]), near(w - pos[0])];
    let sy = [near(pos[1]), near(h - pos[1])];
    if !(sx[0] || sx[1] || sy[0] || sy[1]) {
        return; // Far from every edge: most samples of a large set.
    }
    let float_x = [-pos[0], 2.0 * w - pos[0]];
    let float_y = [-pos[1], 2.0 * h - pos[1]];
    // Across a vertical edge, a horizontal one, and both (near a corner).
    for i in 0..3usize {
        for j in 0..3usize {
            let (vx, vy) = (i.checked_sub(1), j.checked_sub(1));
            if (vx.is_none() && vy.is_none())
                || vx.is_some_and(|a| !sx[a])
                || vy.is_some_and(|b| !sy[b])
            {
                continue;
            }
            match exact {
                Some((lines, x)) => {
                    let mut z = x;
                    if let Some(a) = vx {
                        z = lines.reflect(z, a);
                    }
                    if let Some(b) = vy {
                        z = lines.reflect(z, 2 + b);
                    }
                    if within_exact_limit(z) {
                        out(lines.frame.position(z), Some(z));
                    }
                }
                None => {
                    let x = vx.map_or(pos[0], |a| float_x[a]);
                    let y = vy.map_or(pos[1], |b| float_y[b]);
                    out([x, y], None);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sites::Quasicrystal;

    #[test]
    fn lattice_lines_are_just_outside_the_edges() {
        for (w, h) in [(512u32, 512u32), (150, 100), (7, 300), (1000, 3)] {
            let frame = Frame::default_for(w, h);
            let lines = Lines::new(frame, w, h);
            let l = frame.root_len as f64 / FX_ONE as f64;
            let s = crate::lattice::SIN72;
            let ox = frame.origin[0] as f64 / FX_ONE as f64;
            let oy = frame.origin[1] as f64 / FX_ONE as f64;
            let x = |a: i64| ox + l * a as f64 / 2.0;
            let y = |b: i64| oy + l * s * b as f64;
            let [left, right, top, bottom] = lines.line;
            assert!(x(left) <= 1e-9 && x(left + 1) > 0.0, "{w}×{h} left");
            assert!(
                x(right) >= w as f64 - 1e-9 && x(right - 1) < w as f64,
                "right"
            );
            assert!(y(top) <= 1e-9 && y(top + 1) > 0.0, "top");
            assert!(
                y(bottom) >= h as f64 - 1e-9 && y(bottom - 1) < h as f64,
                "bottom"
            );
        }
    }

    #[test]
    fn reflections_are_mirror_images() {
        let (w, h) = (96u32, 64u32);
        let frame = Frame::default_for(w, h);
        let lines = Lines::new(frame, w, h);
        for s in Quasicrystal::new(w, h).unwrap().first(300) {
            for side in 0..4 {
                let z = lines.reflect(s.lattice, side);
                let (p, q) = (s.pos, frame.position(z));
                // The mirror line lies halfway; the other coordinate is kept.
                let (keep, mid) = if side < 2 { (1, 0) } else { (0, 1) };
                assert!((p[keep] - q[keep]).abs() < 1e-9);
                let m = (p[mid] + q[mid]) / 2.0;
                let edge = [0.0, w as f64, 0.0, h as f64][side];
                assert!(
                    (m - edge).abs() < 1.0,
                    "side {side}: line {m} vs edge {edge}"
                );
                assert_eq!(lines.reflect(z, side), s.lattice, "an involution");
            }
        }
    }

    #[test]
    fn mirrors_near_edges_only() {
        let (w, h) = (100u32, 100u32);
        let mut got = Vec::new();
        // Sample 99: spacing 10 px, mirrored within 20 px of an edge.
        mirror_points(99, [5.0, 50.0], w, h, None, |p, _| got.push(p));
        assert_eq!(got, vec![[-5.0, 50.0]]);
        got.clear();
        mirror_points(99, [95.0, 90.0], w, h, None, |p, _| got.push(p));
        assert_eq!(got, vec![[95.0, 110.0], [105.0, 90.0], [105.0, 110.0]]);
        got.clear();
        mirror_points(99, [50.0, 50.0], w, h, None, |p, _| got.push(p));
        assert!(got.is_empty());
        // Sample 0 is mirrored everywhere (spacing 100 px).
        mirror_points(0, [50.0, 50.0], w, h, None, |p, _| got.push(p));
        assert_eq!(got.len(), 8);
    }
}
