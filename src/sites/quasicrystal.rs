//! The normative site sequence of the format: a golden-ratio quasicrystal in the image,
//! ordered by the exact star-map radius (spec/sites.md).

use super::Point;
use crate::lattice::{disk_candidates, order_key, sign_plus_sin72, ZTau, ZZeta};

/// One in fixed point 16.16.
pub const FX_ONE: i64 = 1 << 16;

/// Inverse covolume of Z\[ζ\] embedded by `x ↦ (x, x*)`: 4/(5√5). With unit roots, the
/// expected number of sites is `DENSITY · area(viewing window) · area(acceptance window)`.
pub const DENSITY: f64 = 0.357_770_876_399_966_4;

/// How the lattice is placed on the image: pixel position of a lattice point `x` is
/// `origin + root_len · (Re x, Im x)`, all in 16.16 fixed point pixels.
///
/// ```
/// use qcs::format::Frame;
/// let f = Frame::default_for(512, 512);
/// assert_eq!(f.root_len, 1 << 16);          // 1 px per root
/// assert_eq!(f.origin, [-256 << 16, -11184810]); // (−W/2, −H/3)
/// assert!(f.validate(512, 512).is_ok());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Frame {
    /// Root length in pixels, 16.16 fixed point, in `[1, 256]` px.
    pub root_len: u32,
    /// Pixel position of the lattice origin, 16.16 fixed point, each in `[−2^15, 2^15)` px.
    pub origin: [i32; 2],
}

/// Why a frame or image size cannot be used for the site construction.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    /// Width or height is 0 or above 65535.
    #[error("image size {width}×{height} is outside 1..=65535")]
    Size {
        /// The width asked for.
        width: u32,
        /// The height asked for.
        height: u32,
    },
    /// Root length outside 1..=256 px.
    #[error("root length {root_len}/65536 px is outside [1, 256] px")]
    RootLength {
        /// The root length asked for, 16.16 fixed point.
        root_len: u32,
    },
}

impl Frame {
    /// The default frame: 1 px per root, origin at pixel `(−W/2, −H/3)` (outside the image,
    /// so the sites have no global five-fold symmetry): `origin = (−W·2^15, −⌊H·2^16/3⌋)`.
    pub fn default_for(width: u32, height: u32) -> Self {
        let w = width.min(65535) as i64;
        let h = height.min(65535) as i64;
        Frame {
            root_len: FX_ONE as u32,
            origin: [(-w * (FX_ONE / 2)) as i32, (-(h * FX_ONE) / 3) as i32],
        }
    }

    /// Checks the bounds that keep every integer of the construction in range.
    pub fn validate(&self, width: u32, height: u32) -> Result<(), FrameError> {
        if width == 0 || height == 0 || width > 65535 || height > 65535 {
            return Err(FrameError::Size { width, height });
        }
        if (self.root_len as i64) < FX_ONE || self.root_len as i64 > 256 * FX_ONE {
            return Err(FrameError::RootLength {
                root_len: self.root_len,
            });
        }
        Ok(())
    }

    fn root_px(&self) -> f64 {
        self.root_len as f64 / FX_ONE as f64
    }

    /// Pixel position of a lattice point (floating point, for rendering).
    pub fn position(&self, x: ZZeta) -> Point {
        let (re, im) = x.to_f64();
        // (origin + L·re) / 2^16, evaluated in this order (spec/sites.md).
        let l = self.root_len as f64;
        [
            (self.origin[0] as f64 + l * re) / FX_ONE as f64,
            (self.origin[1] as f64 + l * im) / FX_ONE as f64,
        ]
    }

    /// Exact membership of a lattice point in the half-open image `[0, W) × [0, H)`.
    pub fn contains(&self, x: ZZeta, width: u32, height: u32) -> bool {
        let p = self.position(x);
        let (w, h) = (width as f64, height as f64);
        let e = 1e-6;
        let inside_x = if p[0] > e && p[0] < w - e {
            true
        } else if p[0] < -e || p[0] > w + e {
            false
        } else {
            self.exact_x(x, width)
        };
        if !inside_x {
            return false;
        }
        if p[1] > e && p[1] < h - e {
            true
        } else if p[1] < -e || p[1] > h + e {
            false
        } else {
            self.exact_y(x, height)
        }
    }

    fn exact_x(&self, x: ZZeta, width: u32) -> bool {
        // 2·X = 2·origin + L·(2 Re x), in 2^-16 px.
        let l = self.root_len as i128;
        let v = x.re2().scale(l) + ZTau::int(2 * self.origin[0] as i128);
        v.signum() >= 0 && (v - ZTau::int(2 * width as i128 * FX_ONE as i128)).signum() < 0
    }

    fn exact_y(&self, x: ZZeta, height: u32) -> bool {
        // Y = origin + L·sin72°·(Im x / sin72°), in 2^-16 px.
        let v = x.im_s().scale(self.root_len as i128);
        let o = self.origin[1] as i128;
        sign_plus_sin72(ZTau::int(o), v) >= 0
            && sign_plus_sin72(ZTau::int(o - height as i128 * FX_ONE as i128), v) < 0
    }
}

const TAU_32: i128 = 6_949_403_065; // round(τ · 2^32)
const SIN72_32: i128 = 4_084_756_634; // round(sin 72° · 2^32)

/// The exact fixed-point position (1/256 px) of a lattice point in a frame, in integers: the
/// positions of the predictive coding and of the refinement's prediction (spec/format.md,
/// *Coding 1*, *Positions*):
///
/// ```text
/// 2·Re x = a + bτ,  Im x / sin72° = u + vτ          (ZZeta::re2, ZZeta::im_s)
/// X = floor((2^33·Cx + L·(2^32·a + T·b) + 2^40) / 2^41)
/// Y = floor((2^64·Cy + L·S·(2^32·u + T·v) + 2^71) / 2^72)
/// T = round(τ·2^32) = 6949403065,  S = round(sin72°·2^32) = 4084756634
/// ```
///
/// ```
/// use qcs::sites::Quasicrystal;
/// let q = Quasicrystal::new(64, 48).unwrap();
/// for s in q.first(50) {
///     let p = qcs::sites::fixed_position(&q.frame(), s.lattice);
///     assert!((p[0] as f64 / 256.0 - s.pos[0]).abs() <= 0.5 / 256.0 + 1e-9);
///     assert!((p[1] as f64 / 256.0 - s.pos[1]).abs() <= 0.5 / 256.0 + 1e-9);
/// }
/// ```
pub fn fixed_position(frame: &Frame, x: ZZeta) -> [i64; 2] {
    let l = frame.root_len as i128;
    let re = x.re2();
    let im = x.im_s();
    let nx = ((frame.origin[0] as i128) << 33) + l * ((re.a << 32) + TAU_32 * re.b);
    let ny = ((frame.origin[1] as i128) << 64) + l * SIN72_32 * ((im.a << 32) + TAU_32 * im.b);
    [
        ((nx + (1i128 << 40)) >> 41) as i64,
        ((ny + (1i128 << 71)) >> 72) as i64,
    ]
}

/// A site of the sequence: its lattice point and its pixel position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    /// Exact lattice coordinates `n0..n3` (`x = Σ n_k ζ^k`).
    pub lattice: ZZeta,
    /// Pixel position (floating point, rendering only).
    pub pos: Point,
}

/// The exact order of two lattice points: ascending `|x*|²`, then ascending `Im x`
/// (pixel row), then ascending `Re x` (pixel column).
///
/// ```
/// use qcs::format::ZZeta;
/// use qcs::sites::site_order;
/// use std::cmp::Ordering;
/// let origin = ZZeta::new([0, 0, 0, 0]);
/// assert_eq!(site_order(origin, ZZeta::new([1, 0, 0, 0])), Ordering::Less);
/// ```
pub fn site_order(a: ZZeta, b: ZZeta) -> std::cmp::Ordering {
    order_key(a.star().norm2())
        .cmp(&order_key(b.star().norm2()))
        .then_with(|| tie_order(a, b))
}

/// The tie rule for equal `|x*|²`: pixel row, then pixel column.
fn tie_order(a: ZZeta, b: ZZeta) -> std::cmp::Ordering {
    order_key(a.im_s())
        .cmp(&order_key(b.im_s()))
        .then_with(|| order_key(a.re2()).cmp(&order_key(b.re2())))
}

/// The quasicrystal site sequence of a `width × height` image.
///
/// ```
/// use qcs::sites::Quasicrystal;
/// let q = Quasicrystal::new(64, 48).unwrap();
/// let first = q.first(100);
/// assert_eq!(first.len(), 100);
/// // A prefix of a longer sequence is the shorter sequence.
/// assert_eq!(&q.first(250)[..100], &first[..]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quasicrystal {
    width: u32,
    height: u32,
    frame: Frame,
}

impl Quasicrystal {
    /// The sequence with the default [`Frame`].
    pub fn new(width: u32, height: u32) -> Result<Self, FrameError> {
        Self::with_frame(width, height, Frame::default_for(width, height))
    }

    /// The sequence with an explicit frame.
    pub fn with_frame(width: u32, height: u32, frame: Frame) -> Result<Self, FrameError> {
        frame.validate(width, height)?;
        Ok(Quasicrystal {
            width,
            height,
            frame,
        })
    }

    /// The frame in use.
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// Acceptance radius (unit roots) at which about `count` sites are expected:
    /// `r² = count · ℓ² / (DENSITY · π · W · H)`, ℓ the root length in pixels.
    pub fn radius_for(&self, count: f64) -> f64 {
        let l = self.frame.root_px();
        (count * l * l / (DENSITY * std::f64::consts::PI * self.width as f64 * self.height as f64))
            .sqrt()
    }

    /// The lattice points in the image with `|x*| ≤ r` (about; a superset near `r`), unordered.
    fn enumerate(&self, r: f64, out: &mut Vec<(u32, [i32; 4])>) {
        out.clear();
        let l = self.frame.root_px();
        let o = [
            self.frame.origin[0] as f64 / FX_ONE as f64,
            self.frame.origin[1] as f64 / FX_ONE as f64,
        ];
        let bounds = [
            -o[0] / l,
            (self.width as f64 - o[0]) / l,
            -o[1] / l,
            (self.height as f64 - o[1]) / l,
        ];
        let (w, h) = (self.width, self.height);
        disk_candidates(bounds, r, &mut |x| {
            if self.frame.contains(x, w, h) {
                out.push((0, x.0.map(|v| v as i32)));
            }
        });
    }

    /// The first `count` sites in progressive order.
    ///
    /// Cost is `O(count · log count)`: the acceptance radius is estimated from the density,
    /// and enlarged until the `count`-th site lies safely inside it.
    pub fn first(&self, count: usize) -> Vec<Site> {
        if count == 0 {
            return Vec::new();
        }
        let mut r = self.radius_for(count as f64 * 1.03 + 64.0);
        let mut cand = Vec::new();
        let point = |n: [i32; 4]| ZZeta(n.map(|v| v as i64));
        let mut run: Vec<(i128, i128, i128, [i32; 4])> = Vec::new();
        loop {
            self.enumerate(r, &mut cand);
            if cand.len() >= count {
                // The exact keys K are ≥ 0; their top 32 significant bits order them weakly
                // (truncation is monotone), so a sort on those plus an exact pass over runs of
                // equal truncated keys gives the exact order. A radix sort (four byte passes):
                // a comparison sort was more than half of the sites' instructions.
                let radius2 = r * r * 1.01 + 1e-9;
                let kmax = order_key(ZTau::new(radius2.ceil() as i128 + 1, 0)).max(1) as u128;
                let shift = (128 - kmax.leading_zeros()).saturating_sub(32);
                for c in cand.iter_mut() {
                    let k = order_key(point(c.1).star().norm2()).max(0) as u128;
                    c.0 = (k >> shift).min(u32::MAX as u128) as u32;
                }
                radsort::sort_by_key(&mut cand, |c| c.0);
                let mut start = 0;
                while start < count {
                    let mut end = start + 1;
                    while end < cand.len() && cand[end].0 == cand[start].0 {
                        end += 1;
                    }
                    if end - start > 1 {
                        run.clear();
                        run.extend(cand[start..end].iter().map(|&(_, n)| {
                            let x = point(n);
                            (
                                order_key(x.star().norm2()),
                                order_key(x.im_s()),
                                order_key(x.re2()),
                                n,
                            )
                        }));
                        run.sort_unstable();
                        for (slot, r) in cand[start..end].iter_mut().zip(&run) {
                            slot.1 = r.3;
                        }
                    }
                    start = end;
                }
                let last = point(cand[count - 1].1).star().to_f64();
                // Every point with |x*| ≤ r was enumerated, so the count smallest are right
                // when the largest of them lies strictly inside r (with a float margin).
                if (last.0 * last.0 + last.1 * last.1).sqrt() < r * (1.0 - 1e-9) {
                    break;
                }
            }
            r *= 1.25;
        }
        cand[..count]
            .iter()
            .map(|&(_, n)| {
                let x = point(n);
                Site {
                    lattice: x,
                    pos: self.frame.position(x),
                }
            })
            .collect()
    }
}

