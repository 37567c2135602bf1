//! Shepard interpolation: inverse squared distance weighting of the 4 nearest samples.
//!
//! The 4 nearest samples are found exactly with a uniform grid over the samples (the sites are
//! Delone, so a grid of about four samples per cell keeps almost every query to a 3 × 3 block of cells,
//! widened ring by ring only when the 4th distance cannot be proved final).

use crate::sites::Point;

/// Samples per grid cell (mean).
const PER_CELL: f64 = 4.0;

/// A uniform bucket grid over sample positions (source pixels), cells in row-major order.
#[derive(Clone, Debug)]
pub struct Grid {
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

/// The `K` nearest samples of a query: squared distances and sample indices, nearest first.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Nearest<const K: usize> {
    pub(crate) d2: [f64; K],
    pub(crate) id: [u32; K],
    pub(crate) len: usize,
}

impl<const K: usize> Nearest<K> {
    fn new() -> Self {
        Nearest {
            d2: [f64::INFINITY; K],
            id: [u32::MAX; K],
            len: 0,
        }
    }

    #[inline]
    fn offer(&mut self, d: f64, id: u32) {
        // Ties are broken by sample index, so the result does not depend on scan order.
        let last = K - 1;
        if d > self.d2[last] || (d == self.d2[last] && id >= self.id[last]) {
            return;
        }
        let mut k = last;
        while k > 0 && (d < self.d2[k - 1] || (d == self.d2[k - 1] && id < self.id[k - 1])) {
            self.d2[k] = self.d2[k - 1];
            self.id[k] = self.id[k - 1];
            k -= 1;
        }
        self.d2[k] = d;
        self.id[k] = id;
        self.len = (self.len + 1).min(K);
    }
}

impl Grid {
    /// Buckets `positions` (sample `k` has index `k`); `None`-free: any finite input works.
    pub fn new(positions: &[Point]) -> Grid {
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
        Grid {
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

    #[inline]
    fn scan_run<const K: usize>(
        &self,
        cy: usize,
        cx0: usize,
        cx1: usize,
        q: Point,
        best: &mut Nearest<K>,
    ) {
        let a = self.start[cy * self.nx + cx0] as usize;
        let b = self.start[cy * self.nx + cx1 + 1] as usize;
        let xs = &self.xs[a..b];
        let ys = &self.ys[a..b];
        let ids = &self.ids[a..b];
        for k in 0..xs.len() {
            let dx = xs[k] - q[0];
            let dy = ys[k] - q[1];
            best.offer(dx * dx + dy * dy, ids[k]);
        }
    }

    /// The `K` nearest samples of `q` (all of them if there are fewer than `K`).
    pub(crate) fn nearest<const K: usize>(&self, q: Point) -> Nearest<K> {
        let mut best = Nearest::<K>::new();
        let n = self.ids.len();
        if n == 0 {
            return best;
        }
        let need = K.min(n);
        let fx = ((q[0] - self.x0) * self.inv_cs).clamp(0.0, (self.nx - 1) as f64);
        let fy = ((q[1] - self.y0) * self.inv_cs).clamp(0.0, (self.ny - 1) as f64);
        let (cx, cy) = (fx as usize, fy as usize);
        // q projected onto the grid's box: samples outside the scanned block are at least as
        // far from q as from this point.
        let px = q[0].clamp(self.x0, self.x0 + self.nx as f64 * self.cs);
        let py = q[1].clamp(self.y0, self.y0 + self.ny as f64 * self.cs);
        let mut r = 1usize;
        let (mut lx, mut hx, mut ly, mut hy) = (cx, cx, cy, cy);
        // Ring 0.
        self.scan_run(cy, cx, cx, q, &mut best);
        loop {
            // Add ring r: block [cx-r, cx+r] × [cy-r, cy+r] clipped to the grid.
            let nlx = cx.saturating_sub(r);
            let nhx = (cx + r).min(self.nx - 1);
            let nly = cy.saturating_sub(r);
            let nhy = (cy + r).min(self.ny - 1);
            for yy in nly..=nhy {
                if yy < ly || yy > hy {
                    self.scan_run(yy, nlx, nhx, q, &mut best);
                } else {
                    if nlx < lx {
                        self.scan_run(yy, nlx, lx - 1, q, &mut best);
                    }
                    if nhx > hx {
                        self.scan_run(yy, hx + 1, nhx, q, &mut best);
                    }
                }
            }
            (lx, hx, ly, hy) = (nlx, nhx, nly, nhy);
            let whole = lx == 0 && ly == 0 && hx == self.nx - 1 && hy == self.ny - 1;
            if whole {
                break;
            }
            if best.len >= need {
                // Distance from the projected point to the block sides that have cells beyond.
                let mut bound = f64::INFINITY;
                if lx > 0 {
                    bound = bound.min(px - (self.x0 + lx as f64 * self.cs));
                }
                if hx < self.nx - 1 {
                    bound = bound.min(self.x0 + (hx + 1) as f64 * self.cs - px);
                }
                if ly > 0 {
                    bound = bound.min(py - (self.y0 + ly as f64 * self.cs));
                }
                if hy < self.ny - 1 {
                    bound = bound.min(self.y0 + (hy + 1) as f64 * self.cs - py);
                }
                let bound = bound.max(0.0);
                if best.d2[need - 1] < bound * bound {
                    break;
                }
            }
            r += 1;
        }
        best
    }
}

/// Tile side bounds (source pixels) relative to the mean sample spacing: small tiles scan fewer
/// candidates per point, large ones gather candidates for more points at once.
const TILE_MIN: f64 = 0.35;
const TILE_MAX: f64 = 1.0;
/// Preferred tile side in query steps (about this many points per tile side).
const TILE_STEPS: f64 = 8.0;

/// One tile's candidate samples: every sample that can be among the 4 nearest of a point of
/// the tile, sorted by distance to the tile centre.
#[derive(Clone, Debug, Default)]
struct Tile {
    /// Generation that filled it (the tile row it belongs to).
    gen: u64,
    cx: f64,
    cy: f64,
    /// `(distance to centre, x, y, id)`, nearest first.
    cands: Vec<(f64, f64, f64, u32)>,
}

/// Exact 4-nearest queries for points visited row by row (as [`super::per_pixel`] does), sharing
/// work between nearby points: the plane is cut into square tiles, and the candidates of the
/// tile row being visited are gathered once from the [`Grid`].
///
/// The answer is exactly [`Grid::nearest`]'s (same distances, same index tie-break): a sample
/// in the 4 nearest of a point `p` of a tile with centre `c` and half-diagonal `r` is within
/// `D4(p) + r ≤ D4(c) + 2r` of `c`, and while scanning candidates by distance to `c`, one at
/// `key` is at least `key − |p − c|` from `p`.
pub(crate) struct Tiled<'a> {
    grid: &'a Grid,
    /// Tile side in source pixels; `None`: plain per-point queries (tiles would hold < 2 points).
    side: Option<f64>,
    row: i64,
    gen: u64,
    tiles: Vec<Tile>,
}

impl<'a> Tiled<'a> {
    /// Queries on `grid` at points spaced about `step` source pixels apart.
    pub(crate) fn new(grid: &'a Grid, step: [f64; 2]) -> Self {
        let spacing = grid.cs / PER_CELL.sqrt();
        let st = step[0].max(step[1]);
        let side = (TILE_STEPS * st).clamp(TILE_MIN * spacing, TILE_MAX * spacing);
        let useful = grid.len() >= 4 && side.is_finite() && side >= 2.0 * st;
        Tiled {
            grid,
            side: useful.then_some(side),
            row: i64::MIN,
            gen: 0,
            tiles: Vec::new(),
        }
    }

    /// The 4 nearest samples of `q`.
    pub(crate) fn nearest(&mut self, q: Point) -> Nearest<4> {
        let Some(side) = self.side else {
            return self.grid.nearest::<4>(q);
        };
        let g = self.grid;
        let (fx, fy) = ((q[0] - g.x0) / side, (q[1] - g.y0) / side);
        // Far outside the samples' box, or non-finite: no sharing.
        let lim = 1e9;
        if !(fx.abs() < lim && fy.abs() < lim) {
            return g.nearest::<4>(q);
        }
        // ⌊·⌋ without a libm call (|f| < 1e9).
        let floor = |f: f64| {
            let t = f as i64;
            t - i64::from((t as f64) > f)
        };
        let (tx, ty) = (floor(fx), floor(fy));
        if ty != self.row {
            self.row = ty;
            self.gen += 1;
        }
        let col = tx.rem_euclid(4096) as usize;
        if self.tiles.len() <= col {
            self.tiles.resize_with(col + 1, Tile::default);
        }
        let gen = self.gen;
        let tile = &mut self.tiles[col];
        let cx = g.x0 + (tx as f64 + 0.5) * side;
        let cy = g.y0 + (ty as f64 + 0.5) * side;
        if tile.gen != gen || tile.cx != cx || tile.cy != cy {
            tile.gen = gen;
            tile.cx = cx;
            tile.cy = cy;
            g.gather(cx, cy, side, &mut tile.cands);
        }
        let rp = ((q[0] - cx) * (q[0] - cx) + (q[1] - cy) * (q[1] - cy)).sqrt();
        let mut best = Nearest::<4>::new();
        for &(key, x, y, id) in &tile.cands {
            if best.len >= 4 {
                let lb = key - rp - 1e-9 * (1.0 + key);
                if lb > 0.0 && lb * lb > best.d2[3] {
                    break;
                }
            }
            let dx = x - q[0];
            let dy = y - q[1];
            best.offer(dx * dx + dy * dy, id);
        }
        best
    }
}

impl Grid {
    /// Every sample that can be among the 4 nearest of a point of the square tile of side `side`
    /// centred on `(cx, cy)`, as `(distance to centre, x, y, id)` sorted by distance.
    fn gather(&self, cx: f64, cy: f64, side: f64, out: &mut Vec<(f64, f64, f64, u32)>) {
        out.clear();
        let c4 = self.nearest::<4>([cx, cy]);
        let r = side * std::f64::consts::FRAC_1_SQRT_2;
        let reach = (c4.d2[3].sqrt() + 2.0 * r) * (1.0 + 1e-9) + 1e-9;
        let cell = |v: f64, o: f64, n: usize| {
            let f = ((v - o) * self.inv_cs).clamp(0.0, (n - 1) as f64);
            f as usize
        };
        let (lx, hx) = (
            cell(cx - reach, self.x0, self.nx),
            cell(cx + reach, self.x0, self.nx),
        );
        let (ly, hy) = (
            cell(cy - reach, self.y0, self.ny),
            cell(cy + reach, self.y0, self.ny),
        );
        let reach2 = reach * reach;
        for yy in ly..=hy {
            let a = self.start[yy * self.nx + lx] as usize;
            let b = self.start[yy * self.nx + hx + 1] as usize;
            for k in a..b {
                let (dx, dy) = (self.xs[k] - cx, self.ys[k] - cy);
                let d2 = dx * dx + dy * dy;
                if d2 <= reach2 {
                    out.push((d2.sqrt(), self.xs[k], self.ys[k], self.ids[k]));
                }
            }
        }
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    }
}

/// Shepard colour from the 4 nearest samples `nb` (first `channels` channels).
#[inline]
pub(crate) fn colour_from(nb: &Nearest<4>, colours: &[u8], channels: usize) -> [f32; 4] {
    match channels {
        1 => colour_c::<1>(nb, colours),
        2 => colour_c::<2>(nb, colours),
        3 => colour_c::<3>(nb, colours),
        _ => colour_c::<4>(nb, colours),
    }
}

#[inline]
fn colour_c<const C: usize>(nb: &Nearest<4>, colours: &[u8]) -> [f32; 4] {
    let mut out = [0f32; 4];
    if nb.len == 0 {
        return [128.0; 4];
    }
    let col = |id: u32| -> [u8; C] {
        let o = id as usize * C;
        match colours.get(o..o + C) {
            Some(s) => {
                let mut c = [0u8; C];
                c.copy_from_slice(s);
                c
            }
            None => [0u8; C],
        }
    };
    if nb.d2[0] == 0.0 {
        for (k, v) in col(nb.id[0]).iter().enumerate() {
            out[k] = *v as f32;
        }
        return out;
    }
    let mut acc = [0f64; C];
    let mut wsum = 0f64;
    for k in 0..nb.len.min(4) {
        let w = 1.0 / nb.d2[k];
        wsum += w;
        let cc = col(nb.id[k]);
        for c in 0..C {
            acc[c] += w * cc[c] as f64;
        }
    }
    let inv = 1.0 / wsum;
    for c in 0..C {
        out[c] = (acc[c] * inv) as f32;
    }
    out
}

/// Renders by Shepard interpolation over `grid` into `frame`'s output.
pub(crate) fn render(grid: &Grid, frame: &super::Frame<'_>, parallel: bool) -> Vec<u8> {
    let (colours, c) = (frame.colours, frame.channels);
    super::per_pixel(
        frame,
        parallel,
        || Tiled::new(grid, [frame.sx, frame.sy]),
        |t, q| colour_from(&t.nearest(q), colours, c),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Tiled queries give exactly the per-point grid answer, at several query spacings,
    /// including a lattice (many exact ties) and points outside the samples' box.
    #[test]
    fn tiled_equals_per_point() {
        let mut r = rng(11);
        let mut sets: Vec<Vec<Point>> = vec![];
        sets.push((0..3000).map(|_| [r() * 200.0, r() * 100.0]).collect());
        sets.push(
            (0..40)
                .flat_map(|j| (0..40).map(move |i| [i as f64 * 2.0 + 1.0, j as f64 * 2.0 + 1.0]))
                .collect(),
        );
        sets.push((0..7).map(|_| [r() * 50.0, r() * 50.0]).collect());
        for pts in &sets {
            let grid = Grid::new(pts);
            for step in [0.05, 0.25, 0.5, 1.0, 3.0] {
                let mut t = Tiled::new(&grid, [step, step]);
                let mut y = -5.0;
                while y < 110.0 {
                    let mut x = -7.0;
                    while x < 210.0 {
                        let a = t.nearest([x, y]);
                        let b = grid.nearest::<4>([x, y]);
                        assert_eq!(
                            (a.d2, a.id, a.len),
                            (b.d2, b.id, b.len),
                            "({x}, {y}) step {step}"
                        );
                        x += step * 7.3;
                    }
                    y += step * 5.1;
                }
            }
        }
    }
}
