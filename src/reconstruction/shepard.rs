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

/// Shepard colour (first `channels` channels) at `q` from its 4 nearest samples.
#[inline]
pub(crate) fn colour_at(grid: &Grid, colours: &[u8], channels: usize, q: Point) -> [f32; 4] {
    let nb = grid.nearest::<4>(q);
    let mut out = [0f32; 4];
    if nb.len == 0 {
        return [128.0; 4];
    }
    let col = |id: u32| {
        let o = id as usize * channels;
        colours.get(o..o + channels).unwrap_or(&[])
    };
    if nb.d2[0] == 0.0 {
        for (k, v) in col(nb.id[0]).iter().enumerate() {
            out[k] = *v as f32;
        }
        return out;
    }
    let mut acc = [0f64; 4];
    let mut wsum = 0f64;
    for k in 0..nb.len {
        let w = 1.0 / nb.d2[k];
        wsum += w;
        for (c, v) in col(nb.id[k]).iter().enumerate() {
            acc[c] += w * *v as f64;
        }
    }
    for c in 0..channels.min(4) {
        out[c] = (acc[c] / wsum) as f32;
    }
    out
}
