//! Scan conversion of colour triangles, with an exact top-left-style fill rule.
//!
//! The rasteriser works on plain [`RasterVertex`] triples (positions in output pixels, colours
//! as `f32` per channel), not on `spade` faces, so that any planar subdivision can be drawn: a
//! Delaunay cell with k ≥ 4 cocircular vertices can be given as k triangles around a synthetic
//! centre vertex.
//!
//! # Fill rule
//!
//! Pixel `(i, j)` is sampled at its centre `(i + 0.5, j + 0.5)`. A centre belongs to a triangle
//! when it is inside; a centre exactly on an edge or a vertex is decided as if it were moved by
//! an infinitesimal `(ε, ε²)` to the right and down, which gives every such point to exactly one
//! triangle of a conforming mesh (the usual top-left rule, in symbolic-perturbation form).
//!
//! In scanline form: row `j` belongs to a triangle when `top ≤ j + 0.5 < bottom` (its vertices'
//! y extent), and on that row every edge crossing it gives one number, the first pixel whose
//! centre is at or right of the edge, `⌈x − 0.5⌉` for the crossing `x`. A triangle's span is
//! `[first of its left edge, first of its right edge)`. Two triangles sharing an edge read the
//! same number from it, so they neither overlap nor leave a gap, by construction.
//!
//! The numbers are exact: the crossing is computed in `f64` with a bound on its rounding error,
//! and only when a pixel centre is within that bound of the edge is the side decided by an
//! exact orientation predicate (`robust::orient2d`) on the original `f64` coordinates. So there
//! is no snapping, no limited coordinate range, and the partition holds for any finite input.

use robust::{orient2d, Coord};

/// One corner of a [`RasterTriangle`]: a position in output pixel coordinates and a colour
/// (`f32` per channel; only the first `channels` entries are used).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct RasterVertex {
    /// Position in output pixels (`x` right, `y` down).
    pub pos: [f64; 2],
    /// Colour, 0.0..=255.0 per channel.
    pub colour: [f32; 4],
}

/// A triangle to rasterise, vertices in any order (either orientation).
pub type RasterTriangle = [RasterVertex; 3];

/// `max(a, b)`, `b` if either is NaN: one `maxsd` (`f64::max` also orders NaN, at a cost).
#[inline(always)]
pub(crate) fn fmax(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// `min(a, b)`, `b` if either is NaN.
#[inline(always)]
pub(crate) fn fmin(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

/// 1.5·2^52: adding it to an `f64` of magnitude below 2^51 rounds it to an integer, which
/// its bits then hold (minus those of `MAGIC`), with no float → int conversion.
const MAGIC: f64 = 6_755_399_441_055_744.0;

/// `u` rounded to the nearest integer (ties to even), for `|u| < 2^51`.
#[inline(always)]
fn round_i64(u: f64) -> i64 {
    ((u + MAGIC).to_bits() as i64).wrapping_sub(MAGIC.to_bits() as i64)
}

/// `⌊u⌋` for `|u| < 2^51`.
#[inline(always)]
fn floor_i64(u: f64) -> i64 {
    let (c, d) = ceil_frac(u);
    c - (d > 0.0) as i64
}

/// `⌈u⌉` for `|u| < 2^51`, and `⌈u⌉ − u`.
#[inline(always)]
fn ceil_frac(u: f64) -> (i64, f64) {
    let r = (u + MAGIC) - MAGIC;
    let n = round_i64(u);
    let d = r - u;
    // `d < 0` from its sign bit (`d` is never −0: `r − u` is +0 when they are equal), without
    // a branch: the sign is a coin toss, which a branch predictor loses.
    let up = (d.to_bits() >> 63) as i64;
    (n + up, d + up as f64)
}

/// The first row `k` in `lo..=hi` (`0 ≤ lo ≤ hi < 2^51`) whose centre line `k + 0.5` is at
/// or below `y` (`hi` if none): `⌈y − 0.5⌉` clamped, exact because `y − 0.5` is exact in
/// `f64` for `0.25 ≤ y < 2^52`, and either side of that range the clamp decides.
#[inline(always)]
fn first_row(y: f64, lo: i64, hi: i64) -> i64 {
    ceil_frac(fmin(fmax(y - 0.5, lo as f64), hi as f64)).0
}

/// A non-horizontal edge from its upper end `a` to its lower end `b`, as a function of the row.
#[derive(Clone, Copy, Debug)]
struct Edge {
    a: [f64; 2],
    b: [f64; 2],
    /// `a.x − 0.5`.
    ah: f64,
    /// dx / dy.
    slope: f64,
    /// Bound on the rounding error of the crossing computed by [`Edge::first`], and 1 − it.
    margin: f64,
    margin1: f64,
    /// Whether both ends are within the picture's centres (`0.5 ≤ x ≤ w − 0.5`).
    inner: bool,
}

impl Edge {
    #[inline(always)]
    fn new(a: [f64; 2], b: [f64; 2], w: i64) -> Edge {
        let slope = (b[0] - a[0]) / (b[1] - a[1]);
        // For a row between a and b, |t| ≤ |bx − ax| and the operations of `first` add up to
        // less than 10·2^-53·(|ax| + |bx| + 1); the margin is three times that. An edge too
        // steep for its slope to be a float is decided exactly everywhere.
        let margin = if slope.is_finite() {
            16.0 * f64::EPSILON * (1.0 + a[0].abs() + b[0].abs())
        } else {
            f64::INFINITY
        };
        Edge {
            a,
            b,
            ah: a[0] - 0.5,
            slope,
            margin,
            margin1: 1.0 - margin,
            inner: fmin(a[0], b[0]) >= 0.5 && fmax(a[0], b[0]) <= w as f64 - 0.5,
        }
    }

    /// Whether the centre of pixel `i` on the row through `yc` is strictly left of the edge
    /// (exact).
    #[inline]
    fn left_of(&self, i: i64, yc: f64) -> bool {
        let c = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
        // Counter-clockwise in y-up terms, i.e. left of a → b with y down.
        orient2d(
            c(self.a),
            c(self.b),
            Coord {
                x: i as f64 + 0.5,
                y: yc,
            },
        ) > 0.0
    }

    /// The first pixel `i` of the row through `yc` (`a.y ≤ yc ≤ b.y`) whose centre is at or right
    /// of the edge, `⌈x − 0.5⌉` for the crossing `x`, clamped to `0..=w`.
    #[inline]
    fn first(&self, yc: f64, w: i64) -> i64 {
        let u = self.ah + (yc - self.a[1]) * self.slope;
        if self.inner {
            // u is within 0..=w − 1 (but for rounding, which `first_exact` sees to). Its
            // distance e from the nearest integer n decides ⌈u⌉ when it exceeds the margin.
            let n = round_i64(u);
            let e = u - ((u + MAGIC) - MAGIC);
            if e.abs() >= self.margin {
                return n + (e > 0.0) as i64;
            }
            return self.first_exact(yc, u, n, w);
        }
        // Left of the picture (u < 0) the answer is 0; `first_exact` sees to u < −1 + margin.
        let c = fmin(fmax(u, 0.0), 1e15);
        let (i, d) = ceil_frac(c);
        let d = d + (c - u);
        if d >= self.margin && d <= self.margin1 {
            // No integer within rounding distance of u: ⌈u⌉ is exact.
            return i.min(w);
        }
        self.first_exact(yc, u, i, w)
    }

    /// [`Edge::first`] when `u` (estimate `i`) may be on the wrong side of an integer.
    #[cold]
    #[inline(never)]
    fn first_exact(&self, yc: f64, u: f64, i: i64, w: i64) -> i64 {
        // The exact crossing is within the margin of u.
        if u + self.margin <= 0.0 {
            return 0;
        }
        if u - self.margin > (w - 1) as f64 {
            return w;
        }
        let mut i = i.clamp(0, w);
        while i > 0 && !self.left_of(i - 1, yc) {
            i -= 1;
        }
        while i < w && self.left_of(i, yc) {
            i += 1;
        }
        i
    }
}

/// Calls `span(j, i0, i1)` for every row `j` in `lo..hi` that holds centres inside the
/// triangle `p`, with the pixels `i0..i1` (within `0..w`, non-empty) whose centres are inside.
#[inline(always)]
fn scan(p: [[f64; 2]; 3], (lo, hi): (i64, i64), w: i64, mut span: impl FnMut(i64, i64, i64)) {
    // Sort by y: top, mid, bottom.
    let [mut t, mut m, mut b] = p;
    if m[1] < t[1] {
        std::mem::swap(&mut t, &mut m);
    }
    if b[1] < m[1] {
        std::mem::swap(&mut m, &mut b);
        if m[1] < t[1] {
            std::mem::swap(&mut t, &mut m);
        }
    }
    // Rows (NaN never compares, so a non-finite triangle has none).
    let r0 = first_row(t[1], lo, hi);
    let r1 = first_row(b[1], lo, hi);
    if r0 >= r1 {
        return;
    }
    // Columns: a centre at the rightmost x is never inside (right edges exclude it).
    let xmin = fmin(fmin(t[0], m[0]), b[0]);
    let xmax = fmax(fmax(t[0], m[0]), b[0]);
    if !(xmax > 0.5 && xmin <= w as f64 - 0.5) {
        return;
    }
    let c = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
    let o = orient2d(c(t), c(b), c(m));
    if o == 0.0 || !o.is_finite() {
        return; // Degenerate (no inside), or not finite.
    }
    // The long edge t → b is on the left when m is right of it (clockwise with y down).
    let long_left = o < 0.0;
    let long = Edge::new(t, b, w);
    let rm = first_row(m[1], r0, r1);
    let mut run = |e: Edge, rows: std::ops::Range<i64>| {
        let (l, r) = if long_left { (&long, &e) } else { (&e, &long) };
        for j in rows {
            let yc = j as f64 + 0.5;
            let (i0, i1) = (l.first(yc, w), r.first(yc, w));
            if i0 < i1 {
                span(j, i0, i1);
            }
        }
    };
    if r0 < rm {
        run(Edge::new(t, m, w), r0..rm);
    }
    if rm < r1 {
        run(Edge::new(m, b, w), rm..r1);
    }
}

/// A triangle whose vertices are all within this many pixels of its first one (in x and in
/// y) paints too few pixels to pay for the fixed-point set-up of [`Plane::new`]: it is drawn
/// on the `f64` path. (At 4, one-core callgrind of a 1024² decode: raster 705 → 586 M
/// instructions from 262 144 samples, 266 → 246 M from 65 536, 106 M either way from 16 384;
/// at 6 and up the 16 384 case loses.)
const SMALL: f64 = 4.0;

/// Fraction bits of the fixed-point colours of [`Plane`].
const FRAC: u32 = 32;

/// A triangle's colour plane: the colour at `(x0, y0)` and its gradient, in `f64`, and the
/// same plane in fixed point over pixel indices when it is tame enough (see [`Plane::new`]).
struct Plane<const C: usize> {
    x0: f64,
    y0: f64,
    c0: [f64; C],
    gx: [f64; C],
    gy: [f64; C],
    /// The plane in fixed point; `None` for the `f64` path.
    fixed: Option<Fixed<C>>,
}

/// Anchor pixel `(ia, ja)`, then the colour + ½ there and the steps per pixel in x and y,
/// each scaled by 2^FRAC.
type Fixed<const C: usize> = ((i64, i64), [[i64; C]; 3]);

impl<const C: usize> Plane<C> {
    #[inline(always)]
    fn new(v: [&RasterVertex; 3]) -> Self {
        let [p0, p1, p2] = v.map(|v| v.pos);
        let (d1x, d1y) = (p1[0] - p0[0], p1[1] - p0[1]);
        let (d2x, d2y) = (p2[0] - p0[0], p2[1] - p0[1]);
        let inv = 1.0 / (d1x * d2y - d1y * d2x);
        // A triangle too thin for its area to be a float is drawn in its first colour.
        let inv = if inv.is_finite() { inv } else { 0.0 };
        let mut c0 = [0.0; C];
        let mut gx = [0.0; C];
        let mut gy = [0.0; C];
        for k in 0..C {
            let a = v[0].colour[k] as f64;
            let e1 = v[1].colour[k] as f64 - a;
            let e2 = v[2].colour[k] as f64 - a;
            c0[k] = a;
            gx[k] = (e1 * d2y - e2 * d1y) * inv;
            gy[k] = (e2 * d1x - e1 * d2x) * inv;
        }
        // Fixed point when every number fits with room to spare: vertex colours within
        // 0..=255, gradients below 2^8 per pixel and the triangle under 2^20 pixels across, so
        // that products stay below 2^61 and the rounding of the steps (2^-33 each) adds up to
        // less than 2^-12 across the triangle. Every centre a triangle paints is inside it
        // (the fill rule is exact), where the plane is between its vertex colours: the
        // fixed-point colour + ½ is then within [2^-2, 256 − 2^-2), its integer part a byte.
        let ext = fmax(fmax(d1x.abs(), d2x.abs()), fmax(d1y.abs(), d2y.abs()));
        if ext < SMALL {
            return Plane {
                x0: p0[0],
                y0: p0[1],
                c0,
                gx,
                gy,
                fixed: None,
            };
        }
        let mut tame = ext < (1 << 20) as f64 && p0[0].abs() < 1e15 && p0[1].abs() < 1e15;
        for v in v {
            for &c in &v.colour[..C] {
                tame &= (0.0..=255.0).contains(&c);
            }
        }
        let (ia, ja) = if tame {
            (floor_i64(p0[0]), floor_i64(p0[1]))
        } else {
            (0, 0)
        };
        let one = (1u64 << FRAC) as f64;
        let mut f = [[0i64; C]; 3];
        let (dx, dy) = (ia as f64 + 0.5 - p0[0], ja as f64 + 0.5 - p0[1]);
        for k in 0..C {
            let at = c0[k] + gx[k] * dx + gy[k] * dy + 0.5;
            tame &= at.abs() < 1024.0 && gx[k].abs() < 256.0 && gy[k].abs() < 256.0;
            f[0][k] = round_i64(at * one);
            f[1][k] = round_i64(gx[k] * one);
            f[2][k] = round_i64(gy[k] * one);
        }
        Plane {
            x0: p0[0],
            y0: p0[1],
            c0,
            gx,
            gy,
            fixed: tame.then_some(((ia, ja), f)),
        }
    }
}

/// A band of output rows being painted: `pixels` (and `painted`, when kept) hold rows
/// `row0..row0 + rows`.
pub(crate) struct Band<'a> {
    pub(crate) width: usize,
    pub(crate) row0: usize,
    pub(crate) rows: usize,
    pub(crate) channels: usize,
    pub(crate) pixels: &'a mut [u8],
    /// Which pixels a triangle claimed; `None` when the triangles are known to cover the band.
    pub(crate) painted: Option<&'a mut [bool]>,
}

/// What paints a triangle's pixels row by row: [`Plane`] for Gouraud, the cubic patches.
pub(crate) trait Shader {
    /// Paints `px`, the pixels `i0..` of row `j` (all the shader's channels for each).
    fn fill(&self, px: &mut [u8], i0: i64, j: i64);
}

impl<const C: usize> Shader for Plane<C> {
    /// Paints `px`, the pixels `i0..` of row `j` (`C` channels each): each channel of the
    /// plane at the pixel centre, rounded half up and clamped to 0..=255.
    #[inline(always)]
    fn fill(&self, px: &mut [u8], i0: i64, j: i64) {
        if let Some(((ia, ja), [k0, kx, ky])) = &self.fixed {
            // The integer part of the fixed-point colour (+ ½) is the byte (see `new`).
            let (di, dj) = (i0 - ia, j - ja);
            let mut v = [0i64; C];
            for k in 0..C {
                v[k] = k0[k] + kx[k] * di + ky[k] * dj;
            }
            for p in px.chunks_exact_mut(C) {
                for k in 0..C {
                    p[k] = (v[k] >> FRAC) as u8;
                    v[k] += kx[k];
                }
            }
            return;
        }
        let dy = j as f64 + 0.5 - self.y0;
        for (i, p) in (i0..).zip(px.chunks_exact_mut(C)) {
            let dx = i as f64 + 0.5 - self.x0;
            for k in 0..C {
                // Saturating float → int cast: clamps to 0..=255.
                p[k] = (self.c0[k] + self.gx[k] * dx + self.gy[k] * dy + 0.5) as u8;
            }
        }
    }
}

/// Paints the pixels of `band` whose centres are inside the triangle `p`, `C` channels each,
/// with the shader `make` builds (only if the triangle has a pixel in the band), and marks
/// them painted.
#[inline(always)]
pub(crate) fn paint_with<const C: usize, S: Shader>(
    p: [[f64; 2]; 3],
    band: &mut Band<'_>,
    make: impl Fn() -> S,
) {
    let (w, row0) = (band.width, band.row0);
    let rows = (row0 as i64, (row0 + band.rows) as i64);
    let mut shader = None;
    let pixels = &mut *band.pixels;
    let mut painted = band.painted.as_deref_mut();
    scan(p, rows, w as i64, |j, i0, i1| {
        let base = (j as usize - row0) * w;
        let (o0, o1) = (base + i0 as usize, base + i1 as usize);
        let shader = shader.get_or_insert_with(&make);
        shader.fill(&mut pixels[o0 * C..o1 * C], i0, j);
        if let Some(m) = painted.as_deref_mut() {
            mark(&mut m[o0..o1]);
        }
    });
}

/// Sets a span of the painted mask: one or two fixed-size stores for the few pixels a span
/// usually has, where `fill` alone would call `memset`.
#[inline(always)]
fn mark(m: &mut [bool]) {
    let n = m.len();
    let mut set = |k: usize, len: usize| m[k..k + len].copy_from_slice(&[true; 8][..len]);
    match n {
        0 => {}
        1..=3 => {
            set(0, 1);
            set(n / 2, 1);
            set(n - 1, 1);
        }
        4..=7 => {
            set(0, 4);
            set(n - 4, 4);
        }
        8..=16 => {
            set(0, 8);
            set(n - 8, 8);
        }
        _ => m.fill(true),
    }
}

/// Paints the pixels of `band` covered by the triangle `v` (and marks them painted).
#[inline]
pub(crate) fn paint(v: [&RasterVertex; 3], band: &mut Band<'_>) {
    let p = v.map(|v| v.pos);
    match band.channels {
        1 => paint_with::<1, _>(p, band, || Plane::<1>::new(v)),
        2 => paint_with::<2, _>(p, band, || Plane::<2>::new(v)),
        3 => paint_with::<3, _>(p, band, || Plane::<3>::new(v)),
        _ => paint_with::<4, _>(p, band, || Plane::<4>::new(v)),
    }
}

/// Output rows per band of [`paint_groups`]: a power of two, at most about 1 MiB of pixels,
/// so that a band stays in cache while its triangles are drawn, and when `parallel` at most
/// a quarter of a thread's share of the rows, so that the bands balance. A triangle that
/// crosses bands is set up once in each, and its divisions cost more time than
/// instructions: on one core, 1024² RGB in 341-row bands drew 4% / 3% fewer instructions
/// than 32-row bands from 16k / 65k sites' triangles, at 1.2 / 1.3 / 1.6× the speed from
/// 16k / 65k / 262k, and 256-row bands (this rule) as fast again
/// (`cargo bench --bench render -- raster_only`).
fn band_height(width: usize, height: usize, channels: usize, parallel: bool) -> usize {
    let rows = (1 << 20) / (width * channels).max(1);
    let rows = if parallel {
        rows.min(height.div_ceil(4 * rayon::current_num_threads()))
    } else {
        rows
    };
    // A power of two, so that binning shifts rather than divides.
    1 << rows.max(16).ilog2()
}

/// Paints a `width × height × channels` picture from groups of triangles (e.g. the fan of a
/// Delaunay cell), band by band: each group is binned by the rows its vertices span
/// (`y_extent`, output pixels), then each band draws its groups in group order (`emit` paints
/// a group into a band with [`paint`]), and `finish` paints what no triangle claimed. Bands
/// run on the `rayon` pool when `parallel`; the picture is the same either way. Returns the
/// pixels and, if `mask`, which pixels a triangle claimed (else the triangles are taken to
/// cover the picture and nothing is tracked).
pub(crate) fn paint_groups<E, Y, F>(
    groups: usize,
    y_extent: Y,
    emit: E,
    (width, height, channels): (usize, usize, usize),
    (parallel, mask): (bool, bool),
    finish: F,
) -> (Vec<u8>, Vec<bool>)
where
    Y: Fn(usize) -> (f64, f64) + Sync,
    E: Fn(usize, &mut Band<'_>) + Sync,
    F: Fn(&mut Band<'_>) + Sync,
{
    let (w, h, c) = (width, height, channels);
    let mut out = vec![0u8; w * h * c];
    let mut painted = vec![false; if mask { w * h } else { 0 }];
    if w == 0 || h == 0 {
        return (out, painted);
    }
    let band = band_height(w, h, c, parallel);
    let shift = band.trailing_zeros();
    let nbands = h.div_ceil(band);
    // Counting sort of the groups into the bands they touch (rows whose centre line is in
    // [y0, y1), widened by a margin far beyond rounding).
    let span = |g: usize| {
        let (y0, y1) = y_extent(g);
        let m = 1e-7 * (1.0 + fmax(y0.abs(), y1.abs()));
        let row = |y: f64| ceil_frac(fmin(fmax(y, -1.0), h as f64)).0;
        let (r0, r1) = (row(y0 - 0.5 - m), row(y1 - 0.5 + m).min(h as i64) - 1);
        (r0 <= r1).then_some((r0.max(0) as usize >> shift, r1.max(0) as usize >> shift))
    };
    // The groups' vertices are read in sample order, scattered over the picture: with many
    // groups that is the render's largest serial step, so it is shared out too.
    let spans: Vec<Option<(usize, usize)>> = if parallel {
        use rayon::prelude::*;
        (0..groups).into_par_iter().map(span).collect()
    } else {
        (0..groups).map(span).collect()
    };
    let mut start = vec![0u32; nbands + 1];
    for (b0, b1) in spans.iter().flatten() {
        for b in *b0..=*b1 {
            start[b + 1] += 1;
        }
    }
    for b in 0..nbands {
        start[b + 1] += start[b];
    }
    let mut fill = start.clone();
    let mut bins = vec![0u32; start[nbands] as usize];
    for (g, s) in spans.iter().enumerate() {
        if let Some((b0, b1)) = s {
            for b in *b0..=*b1 {
                bins[fill[b] as usize] = g as u32;
                fill[b] += 1;
            }
        }
    }
    drop(spans);
    let run = |b: usize, chunk: &mut [u8], painted: Option<&mut [bool]>| {
        let mut band = Band {
            width: w,
            row0: b * band,
            rows: chunk.len() / (w * c),
            channels: c,
            pixels: chunk,
            painted,
        };
        for &g in &bins[start[b] as usize..start[b + 1] as usize] {
            emit(g as usize, &mut band);
        }
        finish(&mut band);
    };
    let masks: Vec<Option<&mut [bool]>> = if mask {
        painted.chunks_mut(band * w).map(Some).collect()
    } else {
        (0..nbands).map(|_| None).collect()
    };
    if parallel {
        use rayon::prelude::*;
        out.par_chunks_mut(band * w * c)
            .zip(masks)
            .enumerate()
            .for_each(|(b, (chunk, m))| run(b, chunk, m));
    } else {
        for (b, (chunk, m)) in out.chunks_mut(band * w * c).zip(masks).enumerate() {
            run(b, chunk, m);
        }
    }
    (out, painted)
}

/// The y extent of a triangle.
fn y_extent(t: &RasterTriangle) -> (f64, f64) {
    let [a, b, c] = t.map(|v| v.pos[1]);
    (fmin(fmin(a, b), c), fmax(fmax(a, b), c))
}

/// How many triangles claim each pixel of a `width × height` output (row-major).
///
/// For a conforming triangulation every pixel centre inside the union gets exactly 1 and every
/// other pixel 0. Exposed for tests of the fill rule.
///
/// ```
/// use qcs::reconstruction::{raster_coverage, RasterVertex};
/// let v = |x: f64, y: f64| RasterVertex { pos: [x, y], colour: [0.0; 4] };
/// // Two triangles sharing the diagonal of a 4 × 4 square.
/// let tris = [[v(0.0, 0.0), v(4.0, 0.0), v(4.0, 4.0)], [v(0.0, 0.0), v(4.0, 4.0), v(0.0, 4.0)]];
/// assert!(raster_coverage(&tris, 4, 4).iter().all(|&n| n == 1));
/// ```
#[doc(hidden)]
pub fn raster_coverage(triangles: &[RasterTriangle], width: u32, height: u32) -> Vec<u32> {
    let (w, h) = (width as usize, height as usize);
    let mut count = vec![0u32; w.saturating_mul(h)];
    for t in triangles {
        scan(t.map(|v| v.pos), (0, h as i64), w as i64, |j, i0, i1| {
            let row = j as usize * w;
            for n in &mut count[row + i0 as usize..row + i1 as usize] {
                *n += 1;
            }
        });
    }
    count
}

/// Rasterises `triangles` into a `width × height` picture with `channels` bytes per pixel
/// (1..=4), Gouraud-interpolating their vertex colours; returns the pixels and a mask of the
/// pixels that were painted (single-threaded).
///
/// ```
/// use qcs::reconstruction::{rasterise, RasterVertex};
/// let v = |x: f64, y: f64, c: f32| RasterVertex { pos: [x, y], colour: [c; 4] };
/// let tri = [[v(0.0, 0.0, 0.0), v(8.0, 0.0, 80.0), v(0.0, 8.0, 0.0)]];
/// let (pixels, painted) = rasterise(&tri, 8, 8, 1);
/// assert!(painted[0] && !painted[63]);
/// assert_eq!(pixels[3], 35); // 10 per pixel along x, sampled at x = 3.5
/// ```
pub fn rasterise(
    triangles: &[RasterTriangle],
    width: u32,
    height: u32,
    channels: usize,
) -> (Vec<u8>, Vec<bool>) {
    let c = channels.clamp(1, 4);
    paint_groups(
        triangles.len(),
        |k| y_extent(&triangles[k]),
        |k, band| {
            let [a, b, c] = &triangles[k];
            paint([a, b, c], band)
        },
        (width as usize, height as usize, c),
        (false, true),
        |_| {},
    )
}
