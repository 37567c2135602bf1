//! Shepard interpolation: inverse squared distance weighting of the 4 nearest samples.
//!
//! The 4 nearest samples are found exactly. The output is rendered in blocks of pixels about
//! 1.6 sample spacings wide: each block gathers once, from a uniform grid over the samples,
//! every sample that can be among the 4 nearest of one of its pixel centres (within
//! `D4(c) + 2r` of its centre `c`, `r` the half-diagonal), sorted by distance to `c`, and each
//! pixel scans that list nearest first until no later candidate can come nearer than its 4th.
//!
//! Four pixels of a row scan the list together (`lanes`, in vectors of four of the `wide`
//! crate: safe code, two SSE2 registers each at the baseline x86-64 target), without branches;
//! a pixel whose 4 nearest a tie in distance could decide is redone by the per-pixel path,
//! which applies the tie rule. Both give the same bytes.

use crate::sites::Point;

/// Samples per grid cell (mean).
const PER_CELL: f64 = 2.0;

/// A uniform bucket grid over sample positions (source pixels), cells in row-major order.
#[derive(Clone, Debug)]
pub struct SampleGrid {
    x0: f64,
    y0: f64,
    inv_cs: f64,
    cs: f64,
    nx: usize,
    ny: usize,
    /// `start[c]..start[c + 1]` are the samples of cell `c` in `xs`, `ys`, `ids`.
    start: Vec<u32>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    ids: Vec<u32>,
}

impl SampleGrid {
    /// Buckets `positions` (sample `k` has index `k`); `None`-free: any finite input works.
    pub fn new(positions: &[Point]) -> SampleGrid {
        let n = positions.len().max(1);
        let (mut xmin, mut ymin, mut xmax, mut ymax) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for p in positions {
            xmin = xmin.min(p[0]);
            ymin = ymin.min(p[1]);
            xmax = xmax.max(p[0]);
            ymax = ymax.max(p[1]);
        }
        if positions.is_empty() {
            (xmin, ymin, xmax, ymax) = (0.0, 0.0, 0.0, 0.0);
        }
        let (bw, bh) = (xmax - xmin, ymax - ymin);
        // About PER_CELL samples per cell.
        let mut cs = (bw * bh * PER_CELL / n as f64).sqrt();
        if !(cs.is_finite() && cs > 0.0) {
            cs = bw.max(bh) * PER_CELL / n as f64;
        }
        if !(cs.is_finite() && cs > 0.0) {
            cs = 1.0;
        }
        let cells = |cs: f64| ((bw / cs) as usize + 1, (bh / cs) as usize + 1);
        let (mut nx, mut ny) = cells(cs);
        // Very elongated or clustered sets: never more than ~4 cells per sample.
        while (nx as u64) * (ny as u64) > 4 * n as u64 + 64 {
            cs *= 2.0;
            (nx, ny) = cells(cs);
        }
        let inv_cs = 1.0 / cs;
        let cell_of = |p: &Point| {
            let cx = (((p[0] - xmin) * inv_cs) as usize).min(nx - 1);
            let cy = (((p[1] - ymin) * inv_cs) as usize).min(ny - 1);
            cy * nx + cx
        };
        let mut start = vec![0u32; nx * ny + 1];
        for p in positions {
            start[cell_of(p) + 1] += 1;
        }
        for c in 0..nx * ny {
            start[c + 1] += start[c];
        }
        let mut fill: Vec<u32> = start[..nx * ny].to_vec();
        let m = positions.len();
        let (mut xs, mut ys, mut ids) = (vec![0.0; m], vec![0.0; m], vec![0u32; m]);
        for (k, p) in positions.iter().enumerate() {
            let c = cell_of(p);
            let o = fill[c] as usize;
            fill[c] += 1;
            xs[o] = p[0];
            ys[o] = p[1];
            ids[o] = k as u32;
        }
        SampleGrid {
            x0: xmin,
            y0: ymin,
            inv_cs,
            cs,
            nx,
            ny,
            start,
            xs,
            ys,
            ids,
        }
    }

    /// Number of samples in the grid.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Whether the grid holds no sample.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Mean distance between samples (source pixels).
    fn spacing(&self) -> f64 {
        self.cs / PER_CELL.sqrt()
    }
}

/// Relative slack on every distance bound: far above the few ulps of rounding in the
/// distances, squared distances and square roots the bounds compare, far below any gap that
/// would make a bound useless.
const SLACK: f64 = 1.0 + 1e-9;

/// The 4 nearest samples of a point among a block's candidates: squared distances and
/// candidate numbers, nearest first (ties by smaller sample index); `len` < 4 only when there
/// are fewer samples.
#[derive(Clone, Copy, Debug)]
struct Nearest {
    d2: [f64; 4],
    k: [usize; 4],
    len: usize,
}

/// Candidate samples of one block of output pixels: every sample that can be among the 4
/// nearest of one of its pixel centres, nearest to the block centre first (structure of
/// arrays, so the per-pixel scan reads only what it needs), with their colours.
struct Cands<const C: usize> {
    /// A lower bound of the distance to the block centre, ascending.
    key: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
    id: Vec<u32>,
    /// Colours, padded with zeros to four channels.
    colour: Vec<[f64; 4]>,
    /// Gathering scratch: squared distance bits (low `IDX_BITS` bits cleared) | index into
    /// `slots`, and the grid slots found.
    found: Vec<u64>,
    slots: Vec<u32>,
}

/// Low bits of a packed squared distance that hold an index (the distance loses them, a
/// relative change below 2⁻³⁶, far inside [`SLACK`]).
const IDX_BITS: u32 = 16;
const IDX_MASK: u64 = (1 << IDX_BITS) - 1;

impl<const C: usize> Cands<C> {
    fn new() -> Self {
        Cands {
            key: Vec::new(),
            x: Vec::new(),
            y: Vec::new(),
            id: Vec::new(),
            colour: Vec::new(),
            found: Vec::new(),
            slots: Vec::new(),
        }
    }

    /// Every sample within `reach` of `c` into `found` and `slots`, sorted.
    fn collect(&mut self, g: &SampleGrid, c: Point, reach: f64) {
        let cell = |v: f64, o: f64, n: usize| {
            let f = ((v - o) * g.inv_cs).clamp(0.0, (n - 1) as f64);
            f as usize
        };
        let (lx, hx) = (
            cell(c[0] - reach, g.x0, g.nx),
            cell(c[0] + reach, g.x0, g.nx),
        );
        let (ly, hy) = (
            cell(c[1] - reach, g.y0, g.ny),
            cell(c[1] + reach, g.y0, g.ny),
        );
        let reach2 = reach * reach;
        let mut n = 0;
        for yy in ly..=hy {
            let a = g.start[yy * g.nx + lx] as usize;
            let b = g.start[yy * g.nx + hx + 1] as usize;
            // Room for every sample of the run; the ones within reach are kept.
            self.found.resize(n + b - a, 0);
            self.slots.resize(n + b - a, 0);
            let (xs, ys) = (&g.xs[a..b], &g.ys[a..b]);
            for (k, (&x, &y)) in xs.iter().zip(ys).enumerate() {
                let (dx, dy) = (x - c[0], y - c[1]);
                let d2 = dx * dx + dy * dy;
                // d2 ≥ 0: its bits order like its value.
                self.found[n] = (d2.to_bits() & !IDX_MASK) | (n as u64 & IDX_MASK);
                self.slots[n] = (a + k) as u32;
                n += usize::from(d2 <= reach2);
            }
        }
        self.found.truncate(n);
        self.slots.truncate(n);
        if n > IDX_MASK as usize {
            // Too many to pack an index: sort by (distance, slot) and renumber.
            let mut pairs: Vec<(u64, u32)> = (self.found.iter().map(|e| e & !IDX_MASK))
                .zip(self.slots.iter().copied())
                .collect();
            pairs.sort_unstable();
            self.found = pairs.iter().map(|e| e.0).collect();
            self.slots = pairs.iter().map(|e| e.1).collect();
        } else {
            self.found.sort_unstable();
        }
    }

    /// Gathers every sample that can be among the 4 nearest of a point within `r` of `c`,
    /// sorted by distance to `c`. `d4` bounds the 4th nearest distance of `c` (unknown if 0).
    ///
    /// A sample `j` among the 4 nearest of `p` is no farther from `p` than the 4 nearest of `c`
    /// are: `|p − j| ≤ D4(p) ≤ D4(c) + |p − c|`, so `|c − j| ≤ D4(c) + 2r`.
    fn gather(&mut self, g: &SampleGrid, colours: &[u8], c: Point, r: f64, d4: f64) {
        // Blocks far apart bound each other poorly: then start from a few spacings and widen.
        let guess = 2.0 * g.spacing();
        let d4 = if d4 > 0.0 && d4 <= guess { d4 } else { guess };
        let mut reach = (d4 + 2.0 * r) * SLACK;
        if !(reach > 0.0 && reach.is_finite()) {
            reach = 1.0;
        }
        let need = loop {
            self.collect(g, c, reach);
            if self.found.len() < 4 && self.found.len() < g.len() {
                reach *= 2.0;
                continue;
            }
            let Some(e) = self.found.get(3) else {
                break f64::INFINITY;
            };
            let need = (f64::from_bits(e & !IDX_MASK).sqrt() + 2.0 * r) * SLACK;
            if need <= reach {
                break need;
            }
            reach = need;
        };
        let need2 = need * need;
        let keep = self
            .found
            .partition_point(|e| f64::from_bits(e & !IDX_MASK) <= need2);
        let packed = self.slots.len() <= IDX_MASK as usize;
        self.key.resize(keep, 0.0);
        self.x.resize(keep, 0.0);
        self.y.resize(keep, 0.0);
        self.id.resize(keep, 0);
        self.colour.resize(keep, [0.0; 4]);
        let soa = (self.key.iter_mut().zip(&mut self.x).zip(&mut self.y))
            .zip(self.id.iter_mut().zip(&mut self.colour));
        for (n, (((key, x), y), (id, colour))) in soa.enumerate() {
            let e = self.found[n];
            let k = self.slots[if packed { (e & IDX_MASK) as usize } else { n }] as usize;
            *key = f64::from_bits(e & !IDX_MASK).sqrt();
            (*x, *y, *id) = (g.xs[k], g.ys[k], g.ids[k]);
            let o = *id as usize * C;
            // Missing colour bytes count as 0.
            *colour = [0.0; 4];
            if let Some(s) = colours.get(o..o + C) {
                for (c, &v) in colour.iter_mut().zip(s) {
                    *c = f64::from(v);
                }
            }
        }
    }

    /// The 4 nearest of `q` among the candidates, `q` being in the block they were gathered
    /// for, whose centre is `c`.
    #[inline]
    fn nearest(&self, q: Point, c: Point) -> Nearest {
        let m = self.id.len();
        let (key, xs, ys, ids) = (&self.key[..m], &self.x[..m], &self.y[..m], &self.id[..m]);
        let d2 = |k: usize| {
            let dx = xs[k] - q[0];
            let dy = ys[k] - q[1];
            dx * dx + dy * dy
        };
        // (d2, candidate) pairs: nearer, or as near with a smaller sample index.
        let before =
            |a: (f64, usize), b: (f64, usize)| a.0 < b.0 || (a.0 == b.0 && ids[a.1] < ids[b.1]);
        let insert = |b: &mut [(f64, usize); 4], e: (f64, usize)| {
            let mut i = 3;
            while i > 0 && before(e, b[i - 1]) {
                b[i] = b[i - 1];
                i -= 1;
            }
            b[i] = e;
        };
        let mut b = [(f64::INFINITY, 0); 4];
        let head = m.min(8);
        if let (Some(x8), Some(y8)) = (xs.first_chunk::<8>(), ys.first_chunk::<8>()) {
            // The first eight at once, the 4 nearest of them chosen by a network of minima and
            // maxima; then the rest while they can still be nearer.
            let mut d = [0.0; 8];
            for k in 0..8 {
                let (dx, dy) = (x8[k] - q[0], y8[k] - q[1]);
                d[k] = dx * dx + dy * dy;
            }
            // Without branches: which of two candidates is nearer is a coin toss, which a
            // branch predictor loses (one-core callgrind of a 16k-site render: 4.9 → 1.6 M
            // mispredicts). Keys `d² << 64 | sample index << 32 | candidate` order like
            // `before` (d² ≥ 0: its bits order like its value).
            let key = |k: usize| {
                (u128::from(d[k].to_bits()) << 64) | (u128::from(ids[k]) << 32) | k as u128
            };
            let cas = |e: &mut [u128; 4], i: usize, j: usize| {
                let (x, y) = (e[i], e[j]);
                e[i] = x.min(y);
                e[j] = x.max(y);
            };
            let sort4 = |e: &mut [u128; 4]| {
                for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
                    cas(e, i, j);
                }
            };
            // The 4 least of two sorted fours, then sorted (a bitonic merge).
            let mut e = [key(0), key(1), key(2), key(3)];
            let mut f = [key(4), key(5), key(6), key(7)];
            sort4(&mut e);
            sort4(&mut f);
            for i in 0..4 {
                e[i] = e[i].min(f[3 - i]);
            }
            for (i, j) in [(0, 2), (1, 3), (0, 1), (2, 3)] {
                cas(&mut e, i, j);
            }
            b = e.map(|e| (f64::from_bits((e >> 64) as u64), e as u32 as usize));
        } else {
            // Fewer than eight candidates (only in very small sample sets).
            for k in 0..m {
                let e = (d2(k), k);
                if k < 4 || before(e, b[3]) {
                    insert(&mut b, e);
                }
            }
        }
        if m > head {
            let rq = ((q[0] - c[0]) * (q[0] - c[0]) + (q[1] - c[1]) * (q[1] - c[1])).sqrt();
            // A candidate at `key` from c is at least `key − rq` from q: once that exceeds
            // the 4th distance, no later candidate can enter.
            let mut limit = (b[3].0.sqrt() + rq) * SLACK;
            for (k, &key) in key.iter().enumerate().skip(head) {
                if key > limit {
                    break;
                }
                let e = (d2(k), k);
                if e.0 <= b[3].0 && before(e, b[3]) {
                    insert(&mut b, e);
                    limit = (b[3].0.sqrt() + rq) * SLACK;
                }
            }
        }
        Nearest {
            d2: [b[0].0, b[1].0, b[2].0, b[3].0],
            k: [b[0].1, b[1].1, b[2].1, b[3].1],
            len: m.min(4),
        }
    }

    /// The Shepard colour of a pixel from its 4 nearest candidates `nb`, rounded like every
    /// method: `Σ wₖ cₖ / Σ wₖ` with `wₖ = 1 / d²ₖ` summed nearest first, or the colour of a
    /// sample the pixel centre is on.
    #[inline]
    fn shade(&self, nb: &Nearest, px: &mut [u8; C]) {
        let col = |k: usize| self.colour.get(k).copied().unwrap_or([0.0; 4]);
        let mut out = [0f32; C];
        if nb.len == 0 {
            out = [128.0; C];
        } else if nb.d2[0] == 0.0 {
            let c = col(nb.k[0]);
            out = std::array::from_fn(|i| c[i] as f32);
        } else if nb.len == 4 {
            let w = [
                1.0 / nb.d2[0],
                1.0 / nb.d2[1],
                1.0 / nb.d2[2],
                1.0 / nb.d2[3],
            ];
            let inv = 1.0 / (((w[0] + w[1]) + w[2]) + w[3]);
            let cs = [col(nb.k[0]), col(nb.k[1]), col(nb.k[2]), col(nb.k[3])];
            for c in 0..C {
                let acc = ((w[0] * cs[0][c] + w[1] * cs[1][c]) + w[2] * cs[2][c]) + w[3] * cs[3][c];
                out[c] = (acc * inv) as f32;
            }
        } else {
            let mut acc = [0f64; C];
            let mut wsum = 0f64;
            for k in 0..nb.len {
                let w = 1.0 / nb.d2[k];
                wsum += w;
                let cc = col(nb.k[k]);
                for c in 0..C {
                    acc[c] += w * cc[c];
                }
            }
            let inv = 1.0 / wsum;
            for c in 0..C {
                out[c] = (acc[c] * inv) as f32;
            }
        }
        for (p, v) in px.iter_mut().zip(out) {
            // Saturating cast: round half up, clamp to 0..=255 (NaN → 0), as `super::store`.
            *p = (v + 0.5) as u8;
        }
    }
}

/// Block side in sample spacings: larger blocks gather candidates for more pixels at once,
/// smaller ones leave fewer candidates to scan per pixel. Blocks are a whole number of fours
/// of pixels in both directions: wide, because a partial four wastes lanes; tall, because
/// where samples are dense a block of 3 rows gathers too often. (callgrind, 1024² output from
/// 16k / 65k / 262k sites, with the AVX path of then, per block width × height in pixels: 16k
/// best at 8×8 to 12×12, 16×16 +7%; 65k best at 8×8, 8×6 +3%, 4×4 +9%; 262k best at 4×4, 4×3
/// +9%, 8×8 +15%. At 1.6 spacings the sides round to 12, 8 and 4, each well inside its
/// rounding interval; at 1.5, 65k's 6 px sat on the boundary between 4 and 8.)
const BLOCK: f64 = 1.6;

/// Output pixels per block side: blocks about `BLOCK` sample spacings wide, in whole `unit`s
/// (up to 32 pixels); single pixels when one `unit` would be more than 4 times that, as in a
/// thumbnail of a large image, where a block of `unit` pixels would span many spacings and
/// gather (and sort) every sample in it for each block. (callgrind, 5 Shepard thumbnails of
/// 128² from a 1024² source, `QCS_ONCE=shepard:N:128` in `benches/render.rs`: from 262k /
/// 65k sites, where a unit spans 16 / 8 spacings, blocks of 4 took 1 624 / 421 M
/// instructions and single pixels take 290 / 259 M; from 16k, 4 spacings, single pixels
/// would take 228 M against 126 M.)
fn block_size(grid: &SampleGrid, step: f64, unit: usize) -> usize {
    let side = BLOCK * grid.spacing() / step;
    if !side.is_finite() {
        return unit;
    }
    if side * 4.0 < unit as f64 {
        return 1;
    }
    (side / unit as f64).round().clamp(1.0, (32 / unit) as f64) as usize * unit
}

/// Renders by Shepard interpolation over `grid` into `frame`'s output.
pub(crate) fn render(grid: &SampleGrid, frame: &super::Output<'_>, parallel: bool) -> Vec<u8> {
    match frame.channels {
        1 => render_c::<1>(grid, frame, parallel),
        2 => render_c::<2>(grid, frame, parallel),
        3 => render_c::<3>(grid, frame, parallel),
        _ => render_c::<4>(grid, frame, parallel),
    }
}

fn render_c<const C: usize>(
    grid: &SampleGrid,
    frame: &super::Output<'_>,
    parallel: bool,
) -> Vec<u8> {
    let (w, h) = (frame.width, frame.height);
    let mut out = vec![0u8; w * h * C];
    let (bw, bh) = (block_size(grid, frame.sx, 4), block_size(grid, frame.sy, 4));
    let four = !scalar_only();
    let run = |row0: usize, band: &mut [u8]| {
        let mut cands = Cands::<C>::new();
        let rows = band.len() / (w * C);
        // 4th nearest distance of the first block centre of the row.
        let mut d4_row = 0.0;
        let mut row_centre: Option<Point> = None;
        let mut last: Option<Point> = None;
        for by in (0..rows).step_by(bh) {
            let rh = bh.min(rows - by);
            for bx in (0..w).step_by(bw) {
                let rw = bw.min(w - bx);
                let (j0, j1) = (row0 + by, row0 + by + rh - 1);
                let (a, b) = (
                    frame.source_point(bx, j0),
                    frame.source_point(bx + rw - 1, j1),
                );
                let c = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                let dist = |p: Point| {
                    ((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1])).sqrt()
                };
                let r = [a, b, [a[0], b[1]], [b[0], a[1]]]
                    .into_iter()
                    .map(dist)
                    .fold(0.0, f64::max)
                    * SLACK;
                // A bound of D4(c): the 4th nearest of c among the previous block's
                // candidates, or (starting a row) the row above's D4 plus the distance, D4
                // being 1-Lipschitz.
                let bound = match (bx, last, row_centre) {
                    (0, _, Some(p)) => (d4_row + dist(p)) * SLACK,
                    (0, _, None) => 0.0,
                    (_, Some(p), _) => cands.nearest(c, p).d2[3].sqrt() * SLACK,
                    _ => 0.0,
                };
                cands.gather(grid, frame.colours, c, r, bound);
                last = Some(c);
                if bx == 0 {
                    row_centre = Some(c);
                    d4_row = cands.key.get(3).copied().unwrap_or(0.0);
                }
                let block = Block {
                    at: (bx, by, j0),
                    size: (rw, rh),
                    c,
                };
                // Four at once where the candidates' numbers fit in a key and no squared
                // distance can overflow (`r` and every `key` far below 1e150).
                let far = cands.key.last().map_or(0.0, |&k| k + r);
                if four && (4..=IDX_MASK as usize + 1).contains(&cands.id.len()) && far < 1e150 {
                    shade_block(&cands, frame, &block, w, band, |qx, qy| {
                        lanes::nearest4(&cands, qx, qy, block.c)
                    });
                    continue;
                }
                shade_block(&cands, frame, &block, w, band, |_, _| [None; 4]);
            }
        }
    };
    if parallel {
        use rayon::prelude::*;
        let rows = super::band_rows(h).div_ceil(bh) * bh;
        out.par_chunks_mut(rows * w * C)
            .enumerate()
            .for_each(|(k, band)| run(k * rows, band));
    } else {
        run(0, &mut out);
    }
    out
}

/// A block of output pixels: its first column and row in the band, its first row in the
/// picture, its width and height, and its centre in source pixels.
struct Block {
    at: (usize, usize, usize),
    size: (usize, usize),
    c: Point,
}

/// Shades the pixels of `block` into `band` (rows of `w` pixels) from `cands`, gathered for
/// it, four pixels of a row at a time: `four` (x of each, y) returns what it found of their
/// 4 nearest, for [`Cands::nearest`] to complete and [`Cands::shade`] to shade.
#[inline(always)]
fn shade_block<const C: usize>(
    cands: &Cands<C>,
    frame: &super::Output<'_>,
    block: &Block,
    w: usize,
    band: &mut [u8],
    four: impl Fn([f64; 4], f64) -> [Option<Nearest>; 4],
) {
    let ((bx, by, j0), (rw, rh), c) = (block.at, block.size, block.c);
    for j in 0..rh {
        for i in (0..rw).step_by(4) {
            // The last four of a row repeat its last pixel.
            let q: [Point; 4] =
                std::array::from_fn(|l| frame.source_point(bx + (i + l).min(rw - 1), j0 + j));
            let n = 4.min(rw - i);
            let o = ((by + j) * w + bx + i) * C;
            let Some(px) = band.get_mut(o..o + n * C) else {
                continue;
            };
            let found = four(q.map(|q| q[0]), q[0][1]);
            for (l, px) in px.chunks_exact_mut(C).enumerate() {
                let nb = found[l].unwrap_or_else(|| cands.nearest(q[l], c));
                cands.shade(&nb, px.try_into().expect("C bytes"));
            }
        }
    }
}

/// Four pixels of a row at once, a lane of `wide`'s vectors each: their 4 nearest in one pass
/// over the candidates. (Safe code; `wide` measured faster than plain arrays of four, which
/// the compiler vectorises only in part: see MEASUREMENTS.md.)
mod lanes {
    use wide::{f64x4, CmpGt};

    use super::{Cands, Nearest, Point, IDX_MASK, SLACK};

    /// All bits but the low [`IDX_MASK`] ones, as a double in every lane.
    fn high() -> f64x4 {
        f64x4::splat(f64::from_bits(!IDX_MASK))
    }

    /// The 4 nearest of the points `(qx[l], qy)` among `cands`, as [`Cands::nearest`] finds
    /// them, with one pass over the candidates for the four lanes; `None` in a lane where a
    /// tie could decide. The candidates must number 4 to 2¹⁶, and every squared distance from
    /// a point to a candidate must be finite.
    ///
    /// Each candidate enters the lanes' sorted fours as a key, its squared distance with the
    /// low `IDX_BITS` bits replaced by the candidate number (as in [`Cands::collect`]), by
    /// minima and maxima only, without branches: keys are never NaN and never equal. Keys
    /// order like the distances rounded down (those bits cleared), then by candidate number;
    /// a lane where two of these rounded distances could be equal is left out, for
    /// [`Cands::nearest`] to redo with the exact ones and the tie rule. That is exact: a
    /// distance rounded down below another is below it, so with the final four and the least
    /// key left out (on rejection or on eviction) strictly increasing when rounded, and the
    /// candidates not scanned farther by the bound, the four are the nearest, in order, with
    /// no tie for the tie rule to settle.
    #[inline(always)]
    pub(super) fn nearest4<const C: usize>(
        cands: &Cands<C>,
        qx: [f64; 4],
        qy: f64,
        c: Point,
    ) -> [Option<Nearest>; 4] {
        let m = cands.id.len();
        let (key, xs, ys) = (&cands.key[..m], &cands.x[..m], &cands.y[..m]);
        let qxv = f64x4::from(qx);
        // Squared distances as `Cands::nearest` computes them, the candidate number in their
        // low bits.
        let keys = |k: usize| {
            let dy = ys[k] - qy;
            let dx = f64x4::splat(xs[k]) - qxv;
            ((dx * dx + f64x4::splat(dy * dy)) & high()) | f64x4::splat(f64::from_bits(k as u64))
        };
        let mut d = [keys(0), keys(1), keys(2), keys(3)];
        // The first four sorted by a network (keys are never NaN, and never equal).
        for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
            (d[i], d[j]) = (d[i].fast_min(d[j]), d[i].fast_max(d[j]));
        }
        let (dcx, dy) = (qxv - f64x4::splat(c[0]), qy - c[1]);
        let rq = (dcx * dcx + f64x4::splat(dy * dy)).sqrt();
        // The least key left out (on rejection or on eviction).
        let mut fifth = f64x4::splat(f64::INFINITY);
        let mut n = 4;
        while n < m {
            // A candidate at `key` from c is at least `key − rq` from q (see `nearest`): once
            // that exceeds every lane's 4th distance, no later candidate can enter. Checked
            // every 4 candidates (scanning more than needed changes nothing).
            let limit = (d[3].sqrt() + rq) * f64x4::splat(SLACK);
            if f64x4::splat(key[n]).cmp_gt(limit).all() {
                break;
            }
            for n in n..m.min(n + 4) {
                // Into its place in the four, the greater of each pair carried on: out goes
                // the greatest.
                let mut x = keys(n);
                for d in &mut d {
                    (*d, x) = (d.fast_min(x), d.fast_max(x));
                }
                fifth = fifth.fast_min(x);
            }
            n += 4;
        }
        let (d, fifth) = (d.map(|d| d.to_array()), fifth.to_array());
        let mut found = [None; 4];
        for (l, found) in found.iter_mut().enumerate() {
            let (d, q) = ([d[0][l], d[1][l], d[2][l], d[3][l]], [qx[l], qy]);
            let t = d.map(|d| d.to_bits() & !IDX_MASK);
            if t[0] < t[1] && t[1] < t[2] && t[2] < t[3] && t[3] < fifth[l].to_bits() & !IDX_MASK {
                let k = d.map(|d| (d.to_bits() & IDX_MASK) as usize);
                let d2 = |k: usize| {
                    let (dx, dy) = (xs[k] - q[0], ys[k] - q[1]);
                    dx * dx + dy * dy
                };
                *found = Some(Nearest {
                    d2: [d2(k[0]), d2(k[1]), d2(k[2]), d2(k[3])],
                    k,
                    len: 4,
                });
            }
        }
        found
    }
}

/// Whether renders take the per-pixel path for every pixel: never, but in tests.
#[cfg(not(test))]
fn scalar_only() -> bool {
    false
}

#[cfg(test)]
fn scalar_only() -> bool {
    tests::SCALAR_ONLY.load(std::sync::atomic::Ordering::Relaxed)
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};

    use super::super::{render_with, Method, RenderOptions};
    use crate::sites::{Point, Quasicrystal};

    /// See [`super::scalar_only`]. Both paths give the same pictures, so the other tests
    /// running meanwhile see no difference.
    pub(super) static SCALAR_ONLY: AtomicBool = AtomicBool::new(false);

    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut next = crate::testing::xorshift(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        move || (next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Shepard by brute force: every sample's squared distance, sorted with ties by index,
    /// the 4 first weighted as the renderer's rule says.
    fn brute(src: (u32, u32), c: usize, pts: &[Point], cols: &[u8], w: u32, h: u32) -> Vec<u8> {
        let sx = src.0.max(1) as f64 / w as f64;
        let sy = src.1.max(1) as f64 / h as f64;
        let mut out = Vec::new();
        let mut d: Vec<(f64, usize)> = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let q = [(i as f64 + 0.5) * sx, (j as f64 + 0.5) * sy];
                d.clear();
                for (k, p) in pts.iter().enumerate() {
                    let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
                    d.push((dx * dx + dy * dy, k));
                }
                let order =
                    |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
                if d.len() > 5 {
                    d.select_nth_unstable_by(4, order);
                    d.truncate(5);
                }
                d.sort_by(order);
                let col =
                    |k: usize, ch: usize| f64::from(cols.get(k * c + ch).copied().unwrap_or(0));
                let mut px = [0f32; 4];
                if d[0].0 == 0.0 {
                    for ch in 0..c {
                        px[ch] = col(d[0].1, ch) as f32;
                    }
                } else {
                    let (mut acc, mut ws) = ([0f64; 4], 0f64);
                    for &(dd, k) in d.iter().take(4) {
                        ws += 1.0 / dd;
                        for ch in 0..c {
                            acc[ch] += (1.0 / dd) * col(k, ch);
                        }
                    }
                    for ch in 0..c {
                        px[ch] = (acc[ch] * (1.0 / ws)) as f32;
                    }
                }
                out.extend(px[..c].iter().map(|v| (v + 0.5) as u8));
            }
        }
        out
    }

    /// Whole renders equal the brute-force ones byte for byte, single-threaded and in
    /// parallel: random, quasicrystal and lattice sites (exact ties), duplicates, collinear and
    /// clustered samples, 1–5 samples, samples outside the picture, odd output sizes, up- and
    /// downscaled (blocks of single pixels and of whole fours).
    #[test]
    fn renders_equal_brute_force() {
        let mut r = rng(11);
        let mut sets: Vec<((u32, u32), Vec<Point>)> = Vec::new();
        for n in [1usize, 2, 3, 4, 5, 9, 40, 700] {
            sets.push(((60, 45), (0..n).map(|_| [r() * 60.0, r() * 45.0]).collect()));
        }
        let qc = Quasicrystal::new(96, 64).expect("frame");
        sets.push(((96, 64), qc.first(900).into_iter().map(|s| s.pos).collect()));
        let mut lattice = Vec::new();
        for j in 0..16 {
            for i in 0..20 {
                // On pixel centres at 2× and 0.5×; every 5th twice.
                lattice.push([i as f64 * 2.0 + 0.25, j as f64 * 2.0 + 0.75]);
                if (i + j) % 5 == 0 {
                    lattice.push([i as f64 * 2.0 + 0.25, j as f64 * 2.0 + 0.75]);
                }
            }
        }
        sets.push(((40, 32), lattice));
        // Near ties: a lattice with every site moved by up to 1e-12, distances that often
        // differ in their low 16 bits only (the keys of `lanes` cannot tell them apart).
        let near = (0..320)
            .map(|k| {
                let (i, j) = ((k % 20) as f64, (k / 20) as f64);
                [i * 2.0 + 0.25 + r() * 1e-12, j * 2.0 + 0.75 + r() * 1e-12]
            })
            .collect();
        sets.push(((40, 32), near));
        sets.push(((40, 32), (0..30).map(|k| [k as f64 * 1.3, 11.0]).collect()));
        sets.push((
            (40, 32),
            (0..30).map(|k| [k as f64 * 1.3, k as f64]).collect(),
        ));
        sets.push(((40, 32), vec![[7.0, 9.0]; 6]));
        let cluster = (0..200)
            .map(|_| [20.0 + r() * 0.01, 9.0 + r() * 0.01])
            .collect();
        sets.push(((40, 32), cluster));
        let outside = (0..300)
            .map(|_| [r() * 120.0 - 40.0, r() * 90.0 - 30.0])
            .collect();
        sets.push(((40, 32), outside));
        for (src, pts) in &sets {
            for c in 1..=4 {
                let cols: Vec<u8> = (0..pts.len() * c).map(|_| (r() * 256.0) as u8).collect();
                let (w0, h0) = *src;
                for (w, h) in [
                    (w0, h0),
                    (1, 1),
                    (7, 5),
                    (w0 / 3 + 1, h0 / 4 + 1),
                    (2 * w0 / 5 + 1, 2 * h0 / 5 + 1),
                    (2 * w0 + 1, 2 * h0),
                    (5 * w0, 3 * h0 + 1),
                ] {
                    let want = brute(*src, c, pts, &cols, w, h);
                    for (parallel, scalar) in [(false, false), (true, false), (false, true)] {
                        SCALAR_ONLY.store(scalar, Ordering::Relaxed);
                        let opts = RenderOptions::default().with_parallel(parallel);
                        let got = render_with(*src, c, pts, &cols, Method::Shepard, w, h, opts);
                        assert!(
                            got == want,
                            "{} samples, {c} channels, {w}x{h}, scalar {scalar}",
                            pts.len()
                        );
                    }
                    SCALAR_ONLY.store(false, Ordering::Relaxed);
                }
            }
        }
    }
}
