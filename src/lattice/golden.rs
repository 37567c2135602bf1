//! Z\[τ\]: numbers `a + bτ` with integer `a`, `b` and τ = (1 + √5)/2, compared exactly.

use std::cmp::Ordering;
use std::ops::{Add, Mul, Neg, Sub};

/// The golden ratio τ = (1 + √5)/2, for rendering only.
pub const TAU: f64 = 1.618_033_988_749_895;

/// An element `a + bτ` of Z\[τ\], with `τ² = τ + 1`.
///
/// Coefficients are `i128`; every operation the site construction performs stays far
/// below the range (see `spec/sites.md`, "Integer bounds"), and comparisons are exact.
///
/// ```
/// use qcs::format::ZTau;
/// let tau = ZTau::new(0, 1);
/// assert_eq!(tau * tau, ZTau::new(1, 1)); // τ² = 1 + τ
/// // F51 − F50·τ ≈ 4.4e−9 is positive, though f64 evaluates it to 0.
/// assert!(ZTau::new(20_365_011_074, -12_586_269_025).signum() > 0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct ZTau {
    /// Rational part.
    pub a: i128,
    /// Coefficient of τ.
    pub b: i128,
}

impl ZTau {
    /// Zero.
    pub const ZERO: ZTau = ZTau { a: 0, b: 0 };
    /// One.
    pub const ONE: ZTau = ZTau { a: 1, b: 0 };
    /// τ.
    pub const TAU: ZTau = ZTau { a: 0, b: 1 };

    /// `a + bτ`.
    pub const fn new(a: i128, b: i128) -> Self {
        ZTau { a, b }
    }

    /// The integer `n`.
    pub const fn int(n: i128) -> Self {
        ZTau { a: n, b: 0 }
    }

    /// Galois conjugate `a + b(1 − τ)` (τ ↦ −1/τ).
    pub const fn conj(self) -> Self {
        ZTau {
            a: self.a + self.b,
            b: -self.b,
        }
    }

    /// Multiplies by an integer.
    pub const fn scale(self, k: i128) -> Self {
        ZTau {
            a: self.a * k,
            b: self.b * k,
        }
    }

    /// `τ^j` for any integer `j` (τ⁻¹ = τ − 1).
    pub fn tau_pow(j: i32) -> Self {
        let base = if j >= 0 { ZTau::TAU } else { ZTau::new(-1, 1) };
        let mut r = ZTau::ONE;
        for _ in 0..j.unsigned_abs() {
            r = r * base;
        }
        r
    }

    /// The value as `f64` (rendering and candidate search only).
    pub fn to_f64(self) -> f64 {
        self.a as f64 + self.b as f64 * TAU
    }

    /// Exact sign: −1, 0 or 1.
    pub fn signum(self) -> i32 {
        // 2(a + bτ) = u + v√5 with u = 2a + b, v = b.
        let u = 2 * self.a + self.b;
        sign_plus_sqrt5(u, self.b)
    }
}

/// Exact sign of `u + v·√5` for `|u|, |v| < 2^125`.
pub(crate) fn sign_plus_sqrt5(u: i128, v: i128) -> i32 {
    let (su, sv) = (u.signum() as i32, v.signum() as i32);
    if su == sv || sv == 0 {
        return su;
    }
    if su == 0 {
        return sv;
    }
    // Opposite signs: compare u² with 5v² (256-bit products).
    let u2 = mul_wide(u.unsigned_abs(), u.unsigned_abs());
    let v2 = mul_wide(v.unsigned_abs(), v.unsigned_abs());
    let v25 = mul_small(v2, 5);
    match u2.cmp(&v25) {
        Ordering::Greater => su,
        Ordering::Less => sv,
        Ordering::Equal => 0, // impossible for (u, v) ≠ 0 since √5 is irrational
    }
}

/// 128 × 128 → 256-bit product as (high, low).
fn mul_wide(a: u128, b: u128) -> (u128, u128) {
    let (a1, a0) = (a >> 64, a & u64::MAX as u128);
    let (b1, b0) = (b >> 64, b & u64::MAX as u128);
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 64) + (p01 & u64::MAX as u128) + (p10 & u64::MAX as u128);
    let lo = (p00 & u64::MAX as u128) | (mid << 64);
    let hi = p11 + (p01 >> 64) + (p10 >> 64) + (mid >> 64);
    (hi, lo)
}

fn mul_small((hi, lo): (u128, u128), k: u128) -> (u128, u128) {
    let (l1, l0) = (lo >> 64, lo & u64::MAX as u128);
    let p0 = l0 * k;
    let p1 = l1 * k + (p0 >> 64);
    let lo2 = (p0 & u64::MAX as u128) | (p1 << 64);
    (hi * k + (p1 >> 64), lo2)
}

impl Ord for ZTau {
    fn cmp(&self, other: &Self) -> Ordering {
        (*self - *other).signum().cmp(&0)
    }
}

impl PartialOrd for ZTau {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Add for ZTau {
    type Output = ZTau;
    fn add(self, o: ZTau) -> ZTau {
        ZTau::new(self.a + o.a, self.b + o.b)
    }
}

impl Sub for ZTau {
    type Output = ZTau;
    fn sub(self, o: ZTau) -> ZTau {
        ZTau::new(self.a - o.a, self.b - o.b)
    }
}

impl Neg for ZTau {
    type Output = ZTau;
    fn neg(self) -> ZTau {
        ZTau::new(-self.a, -self.b)
    }
}

impl Mul for ZTau {
    type Output = ZTau;
    fn mul(self, o: ZTau) -> ZTau {
        // (a + bτ)(c + dτ) = ac + bd + (ad + bc + bd)τ
        let bd = self.b * o.b;
        ZTau::new(self.a * o.a + bd, self.a * o.b + self.b * o.a + bd)
    }
}

/// ⌊√5 · 2^80⌋, for [`order_key`].
const SQRT5_2_80: i128 = 2_703_240_312_412_959_446_656_825;

/// A single integer that orders the elements of Z\[τ\] whose value and conjugate are
/// bounded: `K(α) = (2a + b)·2^80 + ⌊b·⌊√5·2^80⌋⌋`, strictly increasing in α for
/// `|α|, |α'| ≤ 2^36` (the bound the site construction guarantees; proof in `spec/sites.md`).
pub fn order_key(x: ZTau) -> i128 {
    ((2 * x.a + x.b) << 80) + x.b * SQRT5_2_80
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fibonacci_near_zero() {
        // F(n+1) − F(n)·τ alternates in sign and shrinks like τ^-n.
        let (mut f0, mut f1) = (0i128, 1i128);
        for n in 1..150 {
            let x = ZTau::new(f1, -f0);
            let expected = if n % 2 == 1 { 1 } else { -1 };
            assert_eq!(x.signum(), expected, "n = {n}");
            let f2 = f0 + f1;
            f0 = f1;
            f1 = f2;
            if f1 > 1 << 100 {
                break;
            }
        }
    }

    #[test]
    fn wide_products() {
        let a = u128::MAX;
        assert_eq!(mul_wide(a, a), (u128::MAX - 1, 1));
        assert_eq!(mul_small((0, u128::MAX), 5), (4, u128::MAX - 4));
    }

    #[test]
    fn tau_powers() {
        assert_eq!(ZTau::tau_pow(5) + ZTau::tau_pow(3), ZTau::new(4, 7));
        assert_eq!(ZTau::tau_pow(7) * ZTau::tau_pow(-7), ZTau::ONE);
        assert!((ZTau::tau_pow(-9).to_f64() - TAU.powi(-9)).abs() < 1e-12);
    }

    #[test]
    fn key_is_monotone_on_near_ties() {
        // Pairs of |x*|²-like values: small value, large conjugate.
        let mut next = crate::testing::xorshift(0x1234_5678_9abc_def0);
        for _ in 0..20000 {
            let q = (next() % (1 << 34)) as i128 - (1 << 33);
            // p ≈ −qτ so that the value is small
            let p = (-(q as f64) * TAU).round() as i128 + (next() % 7) as i128 - 3;
            let x = ZTau::new(p, q);
            let d = ZTau::new((next() % 5) as i128 - 2, (next() % 5) as i128 - 2);
            let y = x + d;
            assert_eq!(x.cmp(&y), order_key(x).cmp(&order_key(y)), "{x:?} {y:?}");
        }
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn order_key_orders_like_the_values() {
        use crate::lattice::{order_key, ZTau};
        let (x, y) = (ZTau::new(165_580_141, -102_334_155), ZTau::ZERO);
        assert!(x > y && order_key(x) > order_key(y));
    }
}
