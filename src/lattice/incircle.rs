//! Exact orientation and incircle predicates for points of Z\[ζ\].
//!
//! A point `x ∈ Z[ζ]` has `Re x = U/2` and `Im x = s·V` with `U = 2·Re x`, `V = Im x / s`
//! in Z\[τ\] (`s = sin 72°`), and `|x|² ∈ Z[τ]`. So
//!
//! * the orientation determinant of three points is `(s/2)·D`, `D ∈ Z[τ]`, and
//! * the incircle determinant of four points is `(s/2)·E`, `E ∈ Z[τ]`,
//!
//! (every term of the expansion takes one factor from each column: `½Z[τ]`, `s·Z[τ]`, `Z[τ]`).
//! Their signs are the exact signs of `D` and `E`; a zero is two integers being zero.
//!
//! The predicates are invariant under any map `x ↦ c + ℓ·x` with `ℓ > 0` (a pixel frame),
//! so they decide the geometry of the sites' pixel positions without looking at them.
//!
//! **Range**: exact for points with `|n_k| < 2^20` ([`EXACT_LIMIT`], the bound of
//! `spec/sites.md` §4); every intermediate value then stays below 2^100 in `i128`.

use super::cyclotomic::ZZeta;
use super::golden::ZTau;

/// Coordinates `n_k` of points given to [`orient`] and [`incircle`] must satisfy
/// `|n_k| < EXACT_LIMIT` (2^20).
pub const EXACT_LIMIT: i64 = 1 << 20;

/// Whether every coordinate of `x` is below [`EXACT_LIMIT`] in absolute value.
pub fn within_exact_limit(x: ZZeta) -> bool {
    x.0.iter().all(|&n| n > -EXACT_LIMIT && n < EXACT_LIMIT)
}

/// `D ∈ Z[τ]` with `orient2d(a, b, c) = (sin72°/2)·D`, where
/// `orient2d = (b − a) × (c − a)` (positive for a counter-clockwise turn in the
/// (Re, Im) plane).
pub fn orient_value(a: ZZeta, b: ZZeta, c: ZZeta) -> ZTau {
    let (p, q) = (b - a, c - a);
    let (up, vp) = (p.re2(), p.im_s());
    let (uq, vq) = (q.re2(), q.im_s());
    up * vq - vp * uq
}

/// Exact orientation of `a, b, c`: `1` counter-clockwise (in the (Re, Im) plane, i.e. also
/// for pixel coordinates read as plain Cartesian numbers), `−1` clockwise, `0` collinear.
///
/// ```
/// use qcs::lattice::{orient, ZZeta};
/// let z = |k: usize| { let mut n = [0; 4]; n[k] = 1; ZZeta::new(n) };
/// assert_eq!(orient(z(0), z(1), z(2)), 1);
/// assert_eq!(orient(z(0), z(2), z(1)), -1);
/// // τ = −ζ² − ζ³ is real: 0, 1, τ are collinear.
/// assert_eq!(orient(ZZeta::new([0; 4]), z(0), ZZeta::new([0, 0, -1, -1])), 0);
/// ```
pub fn orient(a: ZZeta, b: ZZeta, c: ZZeta) -> i32 {
    // Floating-point filter on exact integer differences: `to_f64` of a point with
    // `m = Σ|n_k|` is within 2.5ε·m of its value, so the determinant below is within
    // `32ε·m_p·m_q` of the true one; decide exactly only inside that band.
    let (p, q) = (b - a, c - a);
    let ((px, py), (qx, qy)) = (p.to_f64(), q.to_f64());
    let det = px * qy - py * qx;
    let bound = 32.0 * f64::EPSILON * l1(p) * l1(q);
    if det > bound {
        return 1;
    }
    if det < -bound {
        return -1;
    }
    orient_value(a, b, c).signum()
}

/// `Σ|n_k|` as `f64` (a bound on the coordinates and on `to_f64`'s error, in units of ε).
#[inline]
fn l1(x: ZZeta) -> f64 {
    x.0.iter().map(|&n| n.unsigned_abs() as f64).sum()
}

/// `E ∈ Z[τ]` with `incircle(a, b, c, d) = (sin72°/2)·E`, where `incircle` is the usual
/// determinant of the rows `(dx, dy, dx² + dy²)` of `a − d`, `b − d`, `c − d`.
///
/// ```
/// use qcs::lattice::{incircle_value, ZTau, ZZeta};
/// // The regular pentagon 1, ζ, ζ², ζ³ is cocircular.
/// let z = |k: usize| { let mut n = [0; 4]; n[k] = 1; ZZeta::new(n) };
/// assert_eq!(incircle_value(z(0), z(1), z(2), z(3)), ZTau::ZERO);
/// ```
pub fn incircle_value(a: ZZeta, b: ZZeta, c: ZZeta, d: ZZeta) -> ZTau {
    let rows = [(a - d), (b - d), (c - d)].map(|p| (p.re2(), p.im_s(), p.norm2()));
    let [(ua, va, na), (ub, vb, nb), (uc, vc, nc)] = rows;
    // Expand along the |p|² column.
    na * (ub * vc - uc * vb) - nb * (ua * vc - uc * va) + nc * (ua * vb - ub * va)
}

/// Exact incircle test: for `a, b, c` counter-clockwise, `1` if `d` lies strictly inside
/// their circumcircle, `0` on it, `−1` outside (signs flip for clockwise `a, b, c`).
///
/// ```
/// use qcs::lattice::{incircle, ZZeta};
/// let z = |k: usize| { let mut n = [0; 4]; n[k] = 1; ZZeta::new(n) };
/// let origin = ZZeta::new([0; 4]);
/// assert_eq!(incircle(z(0), z(1), z(2), z(3)), 0); // regular pentagon
/// assert_eq!(incircle(z(0), z(1), z(2), origin), 1); // its centre
/// assert_eq!(incircle(z(0), z(1), z(2), ZZeta::new([2, 0, 0, 0])), -1);
/// ```
pub fn incircle(a: ZZeta, b: ZZeta, c: ZZeta, d: ZZeta) -> i32 {
    // Floating-point filter (see `orient`): with `m = max Σ|n_k|` over the three
    // differences, each entry errs by at most 2.5εm (coordinates) or 8εm² (lifts), so the
    // determinant errs by less than `256ε·m⁴`.
    let (p, q, r) = (a - d, b - d, c - d);
    let m = l1(p).max(l1(q)).max(l1(r));
    let lift = |x: ZZeta| {
        let (u, v) = x.to_f64();
        (u, v, u * u + v * v)
    };
    let ((ua, va, na), (ub, vb, nb), (uc, vc, nc)) = (lift(p), lift(q), lift(r));
    let det = na * (ub * vc - uc * vb) - nb * (ua * vc - uc * va) + nc * (ua * vb - ub * va);
    let bound = 256.0 * f64::EPSILON * (m * m) * (m * m);
    if det > bound {
        return 1;
    }
    if det < -bound {
        return -1;
    }
    incircle_exact(a, b, c, d)
}

/// [`incircle`] without its floating-point filter, for callers whose own filter already
/// failed: the zero test in `i64` when the differences are small, else the exact value.
pub(crate) fn incircle_exact(a: ZZeta, b: ZZeta, c: ZZeta, d: ZZeta) -> i32 {
    let (p, q, r) = (a - d, b - d, c - d);
    if l1(p).max(l1(q)).max(l1(r)) < 2048.0 && small_incircle_is_zero(p, q, r) {
        return 0;
    }
    incircle_value(a, b, c, d).signum()
}

/// Whether the incircle value of the differences `p, q, r` (with `Σ|n_k| < 2^11`) is zero,
/// in `i64`: `2·Re` and `Im/s` coefficients stay below 2^13, their 2×2 minors below 2^29,
/// `|x|²` below 2^23, so every term stays below 2^56.
fn small_incircle_is_zero(p: ZZeta, q: ZZeta, r: ZZeta) -> bool {
    type T = (i64, i64);
    fn mul(x: T, y: T) -> T {
        let bd = x.1 * y.1;
        (x.0 * y.0 + bd, x.0 * y.1 + x.1 * y.0 + bd)
    }
    fn sub(x: T, y: T) -> T {
        (x.0 - y.0, x.1 - y.1)
    }
    let row = |x: ZZeta| {
        let [n0, n1, n2, n3] = x.0;
        let n2sq = x.norm2();
        (
            (2 * n0 - n1, n1 - n2 - n3),
            (n1 - n2 + n3, n2 - n3),
            (n2sq.a as i64, n2sq.b as i64),
        )
    };
    let ((ua, va, na), (ub, vb, nb), (uc, vc, nc)) = (row(p), row(q), row(r));
    let t1 = mul(na, sub(mul(ub, vc), mul(uc, vb)));
    let t2 = mul(nb, sub(mul(ua, vc), mul(uc, va)));
    let t3 = mul(nc, sub(mul(ua, vb), mul(ub, va)));
    let e = (t1.0 - t2.0 + t3.0, t1.1 - t2.1 + t3.1);
    e == (0, 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(x: ZZeta) -> (f64, f64) {
        x.to_f64()
    }

    #[test]
    fn values_match_floating_point() {
        let mut s = crate::testing::xorshift(7);
        let mut next = || (s() % 41) as i64 - 20;
        for _ in 0..2000 {
            let p: Vec<ZZeta> = (0..4)
                .map(|_| ZZeta::new([next(), next(), next(), next()]))
                .collect();
            let (a, b, c, d) = (f(p[0]), f(p[1]), f(p[2]), f(p[3]));
            let o = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
            let k = crate::lattice::SIN72 / 2.0;
            let ov = orient_value(p[0], p[1], p[2]).to_f64() * k;
            assert!((o - ov).abs() < 1e-9 * (1.0 + o.abs()), "{o} {ov}");
            let r = |q: (f64, f64)| {
                let (x, y) = (q.0 - d.0, q.1 - d.1);
                (x, y, x * x + y * y)
            };
            let (ra, rb, rc) = (r(a), r(b), r(c));
            let det = ra.2 * (rb.0 * rc.1 - rc.0 * rb.1) - rb.2 * (ra.0 * rc.1 - rc.0 * ra.1)
                + rc.2 * (ra.0 * rb.1 - rb.0 * ra.1);
            let ev = incircle_value(p[0], p[1], p[2], p[3]).to_f64() * k;
            assert!((det - ev).abs() < 1e-7 * (1.0 + det.abs()), "{det} {ev}");
        }
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn exact_limit_bounds_coordinates() {
        use crate::lattice::{within_exact_limit, ZZeta, EXACT_LIMIT};
        assert!(within_exact_limit(ZZeta::new([EXACT_LIMIT - 1, 0, 0, 0])));
        assert!(!within_exact_limit(ZZeta::new([0, 0, -EXACT_LIMIT, 0])));
    }

    #[test]
    fn orient_value_of_one_and_zeta() {
        use crate::lattice::{orient_value, ZTau, ZZeta};
        let o = ZZeta::new([0, 0, 0, 0]);
        let one = ZZeta::new([1, 0, 0, 0]);
        let zeta = ZZeta::new([0, 1, 0, 0]);
        // 1 × ζ = sin 72° = (sin72°/2)·2
        assert_eq!(orient_value(o, one, zeta), ZTau::int(2));
    }
}
