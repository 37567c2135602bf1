//! Scan conversion of colour triangles, with an exact top-left-style fill rule.
//!
//! The rasteriser works on plain [`RasterTriangle`]s (positions in output pixels, colours as
//! `f32` per channel), not on `spade` faces, so that any planar subdivision can be drawn: a
//! Delaunay cell with k ≥ 4 cocircular vertices can be given as k triangles around a synthetic
//! centre vertex.
//!
//! # Fill rule
//!
//! Pixel `(i, j)` is sampled at its centre `(i + 0.5, j + 0.5)`. A centre belongs to a triangle
//! when it is on the inner side of its three edges. Each edge's side test is evaluated in one
//! canonical way (from the lexicographically smaller end point), so two triangles sharing an
//! edge see bitwise opposite values and never both claim a centre, nor both miss it. A centre
//! exactly on an edge (or vertex) is decided as if it were moved by an infinitesimal
//! `(ε, ε²)` to the right and down, which gives every such point to exactly one triangle of
//! a conforming mesh (the usual top-left rule, in symbolic-perturbation form).
//!
//! Spans are found per row from the edge lines in floating point and the exact side test is
//! only evaluated for the (rare) pixel centres within rounding distance of an edge.

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

#[derive(Clone, Copy, Debug)]
enum Side {
    /// Bounds the span on the left (inside for x ≥ line).
    Left,
    /// Bounds the span on the right (inside for x ≤ line).
    Right,
    /// Horizontal: decides whole rows.
    Row,
}

#[derive(Clone, Copy, Debug)]
struct Edge {
    // Canonical end points: (ax, ay) ≤ (bx, by) lexicographically.
    ax: f64,
    ay: f64,
    bx: f64,
    by: f64,
    /// The triangle's inside is where the canonical edge function is negative.
    flip: bool,
    /// Inside when the edge function is exactly zero (symbolic perturbation).
    tie: bool,
    /// dx / dy along the line.
    slope: f64,
    /// The part of the crossing's rounding bound that does not depend on the row.
    m0: f64,
    side: Side,
}

impl Edge {
    fn new(a: [f64; 2], b: [f64; 2]) -> Edge {
        // Directed a → b with the triangle on its inner (E ≥ 0) side.
        let tie = if a[1] != b[1] {
            a[1] > b[1]
        } else {
            b[0] > a[0]
        };
        let side = if b[1] > a[1] {
            Side::Right
        } else if b[1] < a[1] {
            Side::Left
        } else {
            Side::Row
        };
        let (c, d, flip) = if (a[0], a[1]) <= (b[0], b[1]) {
            (a, b, false)
        } else {
            (b, a, true)
        };
        let dy = d[1] - c[1];
        let slope = if dy != 0.0 { (d[0] - c[0]) / dy } else { 0.0 };
        Edge {
            ax: c[0],
            ay: c[1],
            bx: d[0],
            by: d[1],
            flip,
            tie,
            slope,
            m0: 64.0 * f64::EPSILON * (1.0 + c[0].abs() + d[0].abs()),
            side,
        }
    }

    /// The exact (canonical) side test at `(px, py)`.
    #[inline]
    fn inside(&self, px: f64, py: f64) -> bool {
        let v = (self.bx - self.ax) * (py - self.ay) - (self.by - self.ay) * (px - self.ax);
        let v = if self.flip { -v } else { v };
        v > 0.0 || (v == 0.0 && self.tie)
    }

    /// Where the line crosses the row `py`, and a bound on the rounding error in pixels.
    #[inline]
    fn crossing(&self, py: f64) -> (f64, f64) {
        let t = (py - self.ay) * self.slope;
        let x = self.ax + t;
        let m = self.m0 + 64.0 * f64::EPSILON * (x.abs() + t.abs());
        (x, m)
    }
}

/// `⌈u⌉`, clamped to ±10^15 (NaN → 0), without a libm call (baseline
/// x86-64 has no rounding instruction).
#[inline]
fn ceil_i64(u: f64) -> i64 {
    let u = u.clamp(-1e15, 1e15);
    let t = u as i64;
    if (t as f64) < u {
        t + 1
    } else {
        t
    }
}

/// `⌊u⌋`, clamped to ±10^15 (NaN → 0).
#[inline]
fn floor_i64(u: f64) -> i64 {
    let u = u.clamp(-1e15, 1e15);
    let t = u as i64;
    if (t as f64) > u {
        t - 1
    } else {
        t
    }
}

/// A triangle prepared for scanning: edges, row range, colour plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup {
    edges: [Edge; 3],
    /// First and last row (inclusive) whose centres can be inside.
    pub(crate) rows: (i64, i64),
    x0: f64,
    y0: f64,
    c0: [f64; 4],
    gx: [f64; 4],
    gy: [f64; 4],
}

impl Setup {
    /// Prepares `t`; `None` for degenerate (zero-area or non-finite) triangles and for those
    /// whose bounding box holds no pixel centre.
    pub(crate) fn new(t: &RasterTriangle) -> Option<Setup> {
        let [p0, mut p1, mut p2] = [t[0], t[1], t[2]];
        let area = |p1: &RasterVertex, p2: &RasterVertex| {
            (p1.pos[0] - p0.pos[0]) * (p2.pos[1] - p0.pos[1])
                - (p1.pos[1] - p0.pos[1]) * (p2.pos[0] - p0.pos[0])
        };
        let mut det = area(&p1, &p2);
        if !det.is_finite() || det == 0.0 {
            return None;
        }
        if det < 0.0 {
            std::mem::swap(&mut p1, &mut p2);
            det = -det;
        }
        let ymin = p0.pos[1].min(p1.pos[1]).min(p2.pos[1]);
        let ymax = p0.pos[1].max(p1.pos[1]).max(p2.pos[1]);
        // Row j is sampled at j + 0.5. Rows whose centre line is farther than a rounding margin
        // outside [ymin, ymax] cannot hold an inside centre; the margin (far larger than any
        // rounding of the side tests) keeps apex rows that rounding could decide either way.
        let my = 1e-7 * (1.0 + ymin.abs().max(ymax.abs()));
        let rows = (ceil_i64(ymin - 0.5 - my), floor_i64(ymax - 0.5 + my));
        if rows.0 > rows.1 {
            return None;
        }
        // Likewise columns: most triangles of a downscaled render hold no pixel centre at all
        // and are dropped here, before their edges and colour plane are set up.
        let xmin = p0.pos[0].min(p1.pos[0]).min(p2.pos[0]);
        let xmax = p0.pos[0].max(p1.pos[0]).max(p2.pos[0]);
        let mx = 1e-7 * (1.0 + xmin.abs().max(xmax.abs()));
        if ceil_i64(xmin - 0.5 - mx) > floor_i64(xmax - 0.5 + mx) {
            return None;
        }
        let edges = [
            Edge::new(p0.pos, p1.pos),
            Edge::new(p1.pos, p2.pos),
            Edge::new(p2.pos, p0.pos),
        ];
        let (d1x, d1y) = (p1.pos[0] - p0.pos[0], p1.pos[1] - p0.pos[1]);
        let (d2x, d2y) = (p2.pos[0] - p0.pos[0], p2.pos[1] - p0.pos[1]);
        let mut c0 = [0.0; 4];
        let mut gx = [0.0; 4];
        let mut gy = [0.0; 4];
        let inv = 1.0 / det;
        for k in 0..4 {
            let a = p0.colour[k] as f64;
            let e1 = p1.colour[k] as f64 - a;
            let e2 = p2.colour[k] as f64 - a;
            c0[k] = a;
            gx[k] = (e1 * d2y - e2 * d1y) * inv;
            gy[k] = (e2 * d1x - e1 * d2x) * inv;
        }
        Some(Setup {
            edges,
            rows,
            x0: p0.pos[0],
            y0: p0.pos[1],
            c0,
            gx,
            gy,
        })
    }

    /// The pixels `[i0, i1)` of row `j` (image `width` wide) whose centres are inside.
    #[inline]
    pub(crate) fn span(&self, j: i64, width: i64) -> (i64, i64) {
        let py = j as f64 + 0.5;
        let mut lo = 0i64;
        let mut hi = width;
        for e in &self.edges {
            match e.side {
                Side::Row => {
                    if !e.inside(0.0, py) {
                        return (0, 0);
                    }
                }
                Side::Left => {
                    // First index whose centre is at or right of the line.
                    let (x, m) = e.crossing(py);
                    let mut t = ceil_i64((x - 0.5).clamp(-1.0, width as f64 + 1.0));
                    if t >= 0 && t <= width {
                        let c = t as f64 + 0.5;
                        if c - x < m || x - (c - 1.0) < m {
                            while t > 0 && e.inside((t - 1) as f64 + 0.5, py) {
                                t -= 1;
                            }
                            while t < width && !e.inside(t as f64 + 0.5, py) {
                                t += 1;
                            }
                        }
                    }
                    lo = lo.max(t);
                }
                Side::Right => {
                    // One past the last index whose centre is at or left of the line.
                    let (x, m) = e.crossing(py);
                    let mut t =
                        (floor_i64((x - 0.5).clamp(-2.0, width as f64 + 1.0)) + 1).min(width + 1);
                    if t >= 0 && t <= width {
                        let c = t as f64 + 0.5;
                        if c - x < m || x - (c - 1.0) < m {
                            while t < width && e.inside(t as f64 + 0.5, py) {
                                t += 1;
                            }
                            while t > 0 && !e.inside((t - 1) as f64 + 0.5, py) {
                                t -= 1;
                            }
                        }
                    }
                    hi = hi.min(t);
                }
            }
            if lo >= hi {
                return (0, 0);
            }
        }
        (lo, hi)
    }

    /// Colour (first `C` channels) at pixel centre `(i + 0.5, j + 0.5)` and its step along x.
    #[inline]
    fn start<const C: usize>(&self, i: i64, j: i64) -> ([f32; C], [f32; C]) {
        let dx = i as f64 + 0.5 - self.x0;
        let dy = j as f64 + 0.5 - self.y0;
        let mut v = [0f32; C];
        let mut g = [0f32; C];
        for k in 0..C {
            v[k] = (self.c0[k] + self.gx[k] * dx + self.gy[k] * dy) as f32;
            g[k] = self.gx[k] as f32;
        }
        (v, g)
    }
}

/// A band of output rows being painted: `pixels` and `painted` hold rows `row0..row0 + rows`.
pub(crate) struct Band<'a> {
    pub(crate) width: usize,
    pub(crate) row0: usize,
    pub(crate) rows: usize,
    pub(crate) channels: usize,
    pub(crate) pixels: &'a mut [u8],
    pub(crate) painted: &'a mut [bool],
}

/// Rows of `s` that fall in the band, as a half-open range.
#[inline]
fn band_rows(s: &Setup, row0: usize, rows: usize) -> (i64, i64) {
    let lo = s.rows.0.max(row0 as i64);
    let hi = (s.rows.1 + 1).min((row0 + rows) as i64);
    (lo, hi)
}

#[inline]
fn paint_c<const C: usize>(s: &Setup, band: &mut Band<'_>) {
    let w = band.width;
    let (r0, r1) = band_rows(s, band.row0, band.rows);
    for j in r0..r1 {
        let (i0, i1) = s.span(j, w as i64);
        if i0 >= i1 {
            continue;
        }
        let (mut v, g) = s.start::<C>(i0, j);
        let row = j as usize - band.row0;
        let base = row * w;
        let px = &mut band.pixels[(base + i0 as usize) * C..(base + i1 as usize) * C];
        for p in px.chunks_exact_mut(C) {
            for k in 0..C {
                // Saturating float → int cast: rounds half up and clamps to 0..=255.
                p[k] = (v[k] + 0.5) as u8;
                v[k] += g[k];
            }
        }
        band.painted[base + i0 as usize..base + i1 as usize].fill(true);
    }
}

/// Paints the pixels of `band` covered by triangle `t` and marks them painted.
#[inline]
pub(crate) fn paint(t: &RasterTriangle, band: &mut Band<'_>) {
    let Some(s) = Setup::new(t) else {
        return;
    };
    match band.channels {
        1 => paint_c::<1>(&s, band),
        2 => paint_c::<2>(&s, band),
        3 => paint_c::<3>(&s, band),
        _ => paint_c::<4>(&s, band),
    }
}

/// Output rows per band of [`paint_groups`]: 32 rows of a 1024-pixel RGB picture are 96 KiB,
/// so a band's pixels stay in cache while its triangles are drawn.
const BAND: usize = 32;

/// Paints a `width × height × channels` picture from groups of triangles (e.g. the fan of a
/// Delaunay cell), band by band: each group is binned by the rows its vertices span
/// (`y_extent`, output pixels), then each band draws the triangles `emit` gives for its
/// groups, in group order, and `finish` paints what no triangle claimed. Bands run on the
/// `rayon` pool when `parallel`; the picture is the same either way. Returns the pixels and
/// the mask of pixels a triangle claimed.
pub(crate) fn paint_groups<E, Y, F>(
    groups: usize,
    y_extent: Y,
    emit: E,
    (width, height, channels): (usize, usize, usize),
    parallel: bool,
    finish: F,
) -> (Vec<u8>, Vec<bool>)
where
    Y: Fn(usize) -> (f64, f64),
    E: Fn(usize, &mut dyn FnMut(&RasterTriangle)) + Sync,
    F: Fn(&mut Band<'_>) + Sync,
{
    let (w, h, c) = (width, height, channels);
    let mut out = vec![0u8; w * h * c];
    let mut mask = vec![false; w * h];
    if w == 0 || h == 0 {
        return (out, mask);
    }
    let nbands = h.div_ceil(BAND);
    // Counting sort of the groups into the bands they touch.
    let span = |g: usize| {
        let (y0, y1) = y_extent(g);
        let m = 1e-7 * (1.0 + y0.abs().max(y1.abs()));
        let r0 = ceil_i64(y0 - 0.5 - m).max(0);
        let r1 = floor_i64(y1 - 0.5 + m).min(h as i64 - 1);
        (r0 <= r1).then_some((r0 as usize / BAND, r1.max(0) as usize / BAND))
    };
    let spans: Vec<Option<(usize, usize)>> = (0..groups).map(span).collect();
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
    let run = |b: usize, chunk: &mut [u8], painted: &mut [bool]| {
        let mut band = Band {
            width: w,
            row0: b * BAND,
            rows: painted.len() / w,
            channels: c,
            pixels: chunk,
            painted,
        };
        for &g in &bins[start[b] as usize..start[b + 1] as usize] {
            emit(g as usize, &mut |t| paint(t, &mut band));
        }
        finish(&mut band);
    };
    if parallel {
        use rayon::prelude::*;
        out.par_chunks_mut(BAND * w * c)
            .zip(mask.par_chunks_mut(BAND * w))
            .enumerate()
            .for_each(|(b, (chunk, painted))| run(b, chunk, painted));
    } else {
        let bands = out.chunks_mut(BAND * w * c).zip(mask.chunks_mut(BAND * w));
        for (b, (chunk, painted)) in bands.enumerate() {
            run(b, chunk, painted);
        }
    }
    (out, mask)
}

/// The y extent of a triangle.
fn y_extent(t: &RasterTriangle) -> (f64, f64) {
    let ys = t.map(|v| v.pos[1]);
    (ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]))
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
    for s in triangles.iter().filter_map(Setup::new) {
        let (r0, r1) = band_rows(&s, 0, h);
        for j in r0..r1 {
            let (i0, i1) = s.span(j, w as i64);
            for i in i0..i1 {
                count[j as usize * w + i as usize] += 1;
            }
        }
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
        |k, f| f(&triangles[k]),
        (width as usize, height as usize, c),
        false,
        |_| {},
    )
}
