//! Z\[ζ\], ζ = e^{2πi/5}: the H2 root lattice with unit roots, in integer coordinates.

use super::golden::ZTau;

/// sin 72°, for rendering only (exact code uses `s² = (2 + τ)/4`).
pub const SIN72: f64 = 0.951_056_516_295_153_5;

/// A point `x = n0 + n1ζ + n2ζ² + n3ζ³` of Z\[ζ\] (the ten H2 roots are `±ζ^k`).
///
/// ```
/// use qcs::format::{ZTau, ZZeta};
/// let x = ZZeta::new([1, 2, 0, -1]);
/// // |x|² and |x*|² are Galois conjugates in Z[τ].
/// assert_eq!(x.norm2(), x.star().norm2().conj());
/// let (re, im) = x.to_f64();
/// assert!((re * re + im * im - x.norm2().to_f64()).abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ZZeta(pub [i64; 4]);

/// The lattice vector `self − o` (coordinate-wise).
impl std::ops::Sub for ZZeta {
    type Output = ZZeta;
    #[inline]
    fn sub(self, o: ZZeta) -> ZZeta {
        ZZeta(std::array::from_fn(|k| self.0[k] - o.0[k]))
    }
}

impl ZZeta {
    /// The point with coordinates `n`.
    pub const fn new(n: [i64; 4]) -> Self {
        ZZeta(n)
    }

    /// From `x = a + bζ` with `a, b ∈ Z[τ]` (the rows of the enumeration).
    pub fn from_ab(a: ZTau, b: ZTau) -> Self {
        let (a0, a1, b0, b1) = (a.a as i64, a.b as i64, b.a as i64, b.b as i64);
        ZZeta([a0 + b1, b0 + b1, b1 - a1, -a1])
    }

    /// The star map `x* = Σ n_k ζ^{2k}` (Galois automorphism ζ ↦ ζ²).
    pub fn star(self) -> Self {
        let [n0, n1, n2, n3] = self.0;
        ZZeta([n0 - n2, n3 - n2, n1 - n2, -n2])
    }

    /// `2·Re x` exactly: `(2n0 − n1) + (n1 − n2 − n3)τ`.
    pub fn re2(self) -> ZTau {
        let [n0, n1, n2, n3] = self.0.map(|v| v as i128);
        ZTau::new(2 * n0 - n1, n1 - n2 - n3)
    }

    /// `Im x / sin 72°` exactly: `(n1 − n2 + n3) + (n2 − n3)τ`.
    pub fn im_s(self) -> ZTau {
        let [_, n1, n2, n3] = self.0.map(|v| v as i128);
        ZTau::new(n1 - n2 + n3, n2 - n3)
    }

    /// `|x|²` exactly, as `p + qτ`.
    pub fn norm2(self) -> ZTau {
        // |n_k| < 2^20 in the site construction, so i64 products cannot overflow.
        let [m0, m1, m2, m3] = self.0;
        let s0 = m0 * m0 + m1 * m1 + m2 * m2 + m3 * m3;
        let a1 = m0 * m1 + m1 * m2 + m2 * m3;
        let a2 = m0 * m2 + m0 * m3 + m1 * m3;
        ZTau::new((s0 - a1) as i128, (a1 - a2) as i128)
    }

    /// `(Re x, Im x)` in floating point.
    pub fn to_f64(self) -> (f64, f64) {
        // cos/sin of 0°, 72°, 144°, 216° (i64 → f64 is exact below 2^53).
        const C: [f64; 4] = [
            1.0,
            0.309_016_994_374_947_45,
            -0.809_016_994_374_947_5,
            -0.809_016_994_374_947_5,
        ];
        const S: [f64; 4] = [
            0.0,
            SIN72,
            0.587_785_252_292_473_1,
            -0.587_785_252_292_473_1,
        ];
        let n = self.0.map(|v| v as f64);
        (
            n[0] * C[0] + n[1] * C[1] + n[2] * C[2] + n[3] * C[3],
            n[1] * S[1] + n[2] * S[2] + n[3] * S[3],
        )
    }
}

/// Exact sign of `u + sin72°·v` for `u, v ∈ Z[τ]` (uses `sin²72° = (2 + τ)/4`).
pub fn sign_plus_sin72(u: ZTau, v: ZTau) -> i32 {
    let (su, sv) = (u.signum(), v.signum());
    if su == sv || sv == 0 {
        return su;
    }
    if su == 0 {
        return sv;
    }
    // Opposite signs: the sign of the larger magnitude; compare 4u² with (2 + τ)v².
    let d = u * u * ZTau::int(4) - ZTau::new(2, 1) * v * v;
    let ds = d.signum();
    if ds > 0 {
        su
    } else if ds < 0 {
        sv
    } else {
        0
    }
}

/// The five linear forms whose absolute values bound a regular decagon with a vertex on
/// the real axis (edge normals at 18° + 36°k), applied to `x*`: for a point with
/// `Re = U`, `Im = sin72°·V`, each is `2·(distance to the centre along the normal)/sin72°`
/// as an element of Z\[τ\] (times 2). A point lies in the closed decagon of circumradius `R`
/// iff all five are `≤ 2R` in absolute value.
pub fn decagon_forms(x: ZZeta) -> [ZTau; 5] {
    let u2 = x.re2(); // 2U
    let v = x.im_s(); // V
    let t1 = ZTau::new(-1, 1); // τ − 1
                               // f1 = U + V(τ−1)/2, f2 = U(τ−1) + Vτ/2, f3 = V, f4 = −U(τ−1) + Vτ/2, f5 = −U + V(τ−1)/2 (all ×2)
    [
        u2 + v * t1,
        u2 * t1 + v * ZTau::TAU,
        v.scale(2),
        -(u2 * t1) + v * ZTau::TAU,
        -u2 + v * t1,
    ]
}

/// Float approximations of the H2 root directions ζ^k, for rendering.
pub fn zeta_f64(k: i32) -> (f64, f64) {
    let a = 2.0 * std::f64::consts::PI * k as f64 / 5.0;
    (a.cos(), a.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn complex(n: [i64; 4], pow: i32) -> (f64, f64) {
        let mut re = 0.0;
        let mut im = 0.0;
        for (k, &c) in n.iter().enumerate() {
            let (zr, zi) = zeta_f64(pow * k as i32);
            re += c as f64 * zr;
            im += c as f64 * zi;
        }
        (re, im)
    }

    #[test]
    fn star_and_coordinates_match_complex_powers() {
        let mut s = 99u64;
        for _ in 0..5000 {
            let mut n = [0i64; 4];
            for v in &mut n {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                *v = ((s >> 33) % 2001) as i64 - 1000;
            }
            let x = ZZeta::new(n);
            let (re, im) = x.to_f64();
            let (cr, ci) = complex(n, 1);
            assert!((re - cr).abs() < 1e-9 && (im - ci).abs() < 1e-9);
            let (sr, si) = x.star().to_f64();
            let (cr, ci) = complex(n, 2);
            assert!((sr - cr).abs() < 1e-9 && (si - ci).abs() < 1e-9);
            let n2 = x.star().norm2().to_f64();
            assert!((n2 - (cr * cr + ci * ci)).abs() < 1e-6 * (1.0 + n2));
            assert_eq!(x.norm2().conj(), x.star().norm2());
        }
    }

    #[test]
    fn tau_is_minus_zeta2_minus_zeta3() {
        let tau = ZZeta::new([0, 0, -1, -1]);
        assert_eq!(tau.re2(), ZTau::new(0, 2));
        assert_eq!(tau.im_s(), ZTau::ZERO);
    }

    #[test]
    fn from_ab_roundtrip() {
        let a = ZTau::new(3, -2);
        let b = ZTau::new(-1, 4);
        let x = ZZeta::from_ab(a, b);
        // Im x = b·sin72 and Re x = a + b·cos72, cos72 = (τ − 1)/2
        assert_eq!(x.im_s(), b);
        assert_eq!(x.re2(), a.scale(2) + b * ZTau::new(-1, 1));
    }

    #[test]
    fn sin72_sign() {
        // sin72 ≈ 0.9510565: u + s·v with u = −95105, v = 100000 → positive; u = −95106 → negative.
        assert_eq!(sign_plus_sin72(ZTau::int(-95105), ZTau::int(100000)), 1);
        assert_eq!(sign_plus_sin72(ZTau::int(-95106), ZTau::int(100000)), -1);
        assert_eq!(sign_plus_sin72(ZTau::ZERO, ZTau::ZERO), 0);
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn subtraction_is_coordinatewise() {
        use crate::lattice::ZZeta;
        assert_eq!(
            ZZeta::new([3, 1, 0, -2]) - ZZeta::new([1, 1, 2, -2]),
            ZZeta::new([2, 0, -2, 0])
        );
    }

    #[test]
    fn sign_plus_sin72_of_a_positive_sum() {
        use crate::lattice::{sign_plus_sin72, ZTau};
        assert_eq!(sign_plus_sin72(ZTau::int(-1), ZTau::int(2)), 1);
    }
}
