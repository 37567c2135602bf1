//! Output-sensitive cut-and-project enumeration: a 2D quasicrystal as a 2D array of 1D
//! quasicrystals (the paper's Fig. 3 and 4).
//!
//! Floating point only *finds candidates*: every interval is widened by a margin, so the
//! result is a superset of the exact set, and callers decide membership exactly.

use super::cyclotomic::{ZZeta, SIN72};
use super::golden::{ZTau, TAU};

const SQRT5: f64 = 2.236_067_977_499_79;
const SIN36: f64 = 0.587_785_252_292_473_1;
const COS72: f64 = 0.309_016_994_374_947_45;

fn widen(lo: f64, hi: f64) -> (f64, f64) {
    let e = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
    (lo - e, hi + e)
}

/// Calls `f(v)` for every `v = m + kτ ∈ Z[τ]` with `v ∈ [l1, u1]` and conjugate
/// `v' ∈ [l2, u2]` (a superset: bounds are widened by a relative 1e-9).
///
/// Both windows are first rescaled by `τ^j` (and the conjugate by `(−1/τ)^j`) so that
/// they have similar lengths; the work is then `O(1 + √(len1·len2) + output)`.
///
/// ```
/// use qcs::lattice::{one_d, ZTau};
/// // The Fibonacci chain: v ∈ [0, 10], v' ∈ [−1, τ − 1).
/// let mut n = 0;
/// one_d(0.0, 10.0, -1.0, 0.6, &mut |v: ZTau| n += 1);
/// assert!(n >= 7 && n <= 8);
/// ```
pub fn one_d(l1: f64, u1: f64, l2: f64, u2: f64, f: &mut impl FnMut(ZTau)) {
    let (l1, u1) = widen(l1, u1);
    let (l2, u2) = widen(l2, u2);
    if !(u1 >= l1 && u2 >= l2) {
        return;
    }
    let (len1, len2) = ((u1 - l1).max(1e-300), (u2 - l2).max(1e-300));
    let j = ((len2 / len1).ln() / (2.0 * TAU.ln()))
        .round()
        .clamp(-60.0, 60.0) as i32;
    let s1 = TAU.powi(j);
    let s2 = (-1.0 / TAU).powi(j);
    let (a1, b1) = (l1 * s1, u1 * s1);
    let (a2, b2) = if s2 > 0.0 {
        (l2 * s2, u2 * s2)
    } else {
        (u2 * s2, l2 * s2)
    };
    let (a1, b1) = widen(a1, b1);
    let (a2, b2) = widen(a2, b2);
    let back = ZTau::tau_pow(-j);
    // w = m + kτ, w' = m + k − kτ, w − w' = k√5.
    let k_lo = ((a1 - b2) / SQRT5).ceil() as i64;
    let k_hi = ((b1 - a2) / SQRT5).floor() as i64;
    let conj_tau = 1.0 - TAU;
    for k in k_lo..=k_hi {
        let kf = k as f64;
        let m_lo = (a1 - kf * TAU).max(a2 - kf * conj_tau).ceil() as i64;
        let m_hi = (b1 - kf * TAU).min(b2 - kf * conj_tau).floor() as i64;
        for m in m_lo..=m_hi {
            let w = ZTau::new(m as i128, k as i128);
            f(if j == 0 { w } else { w * back });
        }
    }
}

/// Calls `f(x)` for every `x ∈ Z[ζ]` whose physical point lies in the closed box
/// `[x0, x1] × [y0, y1]` and whose star image lies in the closed disk `|x*| ≤ r`
/// (a superset, as for [`one_d`]).
///
/// Rows: `x = a + bζ`, `a, b ∈ Z[τ]`, so `Im x = b·sin72°` and `Im x* = b'·sin36°`:
/// `b` runs over a 1D cut-and-project set, then for each row `a` runs over another with
/// `a ∈ [x0 − b·cos72°, x1 − b·cos72°]` and `a' ∈ [b'τ/2 − w, b'τ/2 + w]`,
/// `w = √(r² − (b'·sin36°)²)`.
///
/// ```
/// use qcs::lattice::disk_candidates;
/// let mut n = 0;
/// disk_candidates([-1.0, 1.0, -1.0, 1.0], 15.33, &mut |_| n += 1);
/// assert!(n >= 1039);
/// ```
pub fn disk_candidates(bounds: [f64; 4], r: f64, f: &mut impl FnMut(ZZeta)) {
    let [x0, x1, y0, y1] = bounds;
    let rb = r / SIN36;
    one_d(y0 / SIN72, y1 / SIN72, -rb, rb, &mut |b: ZTau| {
        let bf = b.to_f64();
        let bc = b.conj().to_f64();
        let h = bc * SIN36;
        let w = (r * r - h * h).max(0.0).sqrt();
        let c = bc * TAU / 2.0;
        one_d(
            x0 - bf * COS72,
            x1 - bf * COS72,
            c - w,
            c + w,
            &mut |a: ZTau| f(ZZeta::from_ab(a, b)),
        );
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over a box of n ∈ Z⁴ for small windows.
    fn brute(bounds: [f64; 4], r: f64) -> Vec<ZZeta> {
        let mut out = Vec::new();
        let lim = 40;
        for n0 in -lim..=lim {
            for n1 in -lim..=lim {
                for n2 in -lim..=lim {
                    for n3 in -lim..=lim {
                        let x = ZZeta::new([n0, n1, n2, n3]);
                        let (re, im) = x.to_f64();
                        if re < bounds[0] || re > bounds[1] || im < bounds[2] || im > bounds[3] {
                            continue;
                        }
                        let (sr, si) = x.star().to_f64();
                        if sr * sr + si * si <= r * r {
                            out.push(x);
                        }
                    }
                }
            }
        }
        out.sort();
        out
    }

    #[test]
    fn matches_brute_force_on_small_windows() {
        for (bounds, r) in [
            ([-3.0, 4.0, -2.5, 3.5], 1.9),
            ([2.2, 7.1, 1.3, 5.0], 2.7),
            ([-6.0, -1.0, -4.0, 0.5], 1.2),
        ] {
            let mut got = Vec::new();
            disk_candidates(bounds, r, &mut |x| got.push(x));
            // keep exactly the ones the float test keeps, as the brute force does
            got.retain(|x| {
                let (re, im) = x.to_f64();
                let (sr, si) = x.star().to_f64();
                re >= bounds[0]
                    && re <= bounds[1]
                    && im >= bounds[2]
                    && im <= bounds[3]
                    && sr * sr + si * si <= r * r
            });
            got.sort();
            let n = got.len();
            got.dedup();
            assert_eq!(n, got.len(), "duplicates");
            let want = brute(bounds, r);
            assert!(!want.is_empty());
            assert_eq!(got, want);
        }
    }
}
