//! Canonical cells by look-up: the atlas of a quasicrystal's local configurations.
//!
//! Every cell around a site `x` has its circumcircle within a small distance of `x`, and a
//! quasicrystal has few local configurations: the sites within a fixed distance `D` of `x`,
//! as lattice vectors from `x` (its *key*), take a few hundred to a thousand values over a
//! whole picture. So the cells around `x` are computed once per key, exactly, from the
//! key's points alone (some twenty), and looked up for every other site with that key. `D`
//! is a little more than the farthest reach of the circles around a few sample sites.
//!
//! A key decides the cells around `x` only when each of them has its circumcircle within
//! `D` of `x`: then no site outside the key can lie in one of those circles, and together
//! they surround `x`, so they are all of `x`'s cells. Sites whose key does not decide (near
//! the hull, or in a configuration seen too rarely to be worth a local build) are
//! *undecided*; the points near them are triangulated exactly, as a whole, and that build
//! supplies the cells whose first vertex is undecided. Each cell is emitted once, by its
//! first vertex (the smallest lattice point), so the two parts never overlap.
//!
//! Why the exact build of those points gives the right cells there: call a decided site
//! *deep* if no undecided point lies within `D` of it, and build all points but the deep
//! ones. A cell with an undecided vertex `u` has no deep vertex `t` (it would be one of
//! `t`'s cells, whose circles lie within `D` of `t`, so `u` would be that near). So the
//! cells around `u` are cells of the smaller set too (its points include their vertices,
//! and an empty circle stays empty), and as they surround `u` within the hull, they are all
//! the cells of the smaller set around `u`.

use byteorder::{ByteOrder, LittleEndian};
use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use super::cells::Cells;
use super::delaunay::Store;
use crate::lattice::{within_exact_limit, ZZeta};
use crate::sites::Point;

/// Below this many points exact insertion alone is as fast.
const MIN_POINTS: usize = 50_000;
/// After this many sites, if too many of them were undecided, the points are in a phase of
/// the quasicrystal where keys are too diverse for look-up to pay, and all are triangulated
/// exactly.
const PROBE: usize = 4096;
/// Distinct lattice vectors a key can use (bits of [`Key`]).
const MAX_VECTORS: usize = 256;
/// How many sites are triangulated locally to find the key's radius `D`.
const PILOT: usize = 64;
/// Their neighbourhoods' radius, in mean spacings of the points (√(area / points)): the
/// circles of an interior site's cells reach 1.6–2.5 of them where look-up pays (up to 3.4
/// in sparse phases; a pilot whose circles reach beyond is not counted).
const PILOT_REACH: f64 = 3.5;
/// The grid's side for the pilot, in mean spacings (then it is half the key's radius).
const PILOT_SIDE: f64 = 1.75;

/// Which lattice vectors (by their index in [`Vectors`]) lead from a site to a point.
type Key = [u64; MAX_VECTORS / 64];

/// A key's cells owned by its site: each as its number of other vertices, then those as
/// indices of [`Vectors`], counter-clockwise after the site itself (which comes first,
/// having the smallest lattice point). `None` if the key does not decide the cells.
type Star = Option<Box<[u8]>>;

/// A hasher for keys (bit sets), which need no protection from collisions.
#[derive(Default)]
struct KeyHash(u64);

impl std::hash::Hasher for KeyHash {
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.write_u64(LittleEndian::read_u64(w));
        }
        for &b in words.remainder() {
            self.write_u64(b.into());
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(23) ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

// `Cells`' builder by look-up (the type is in `cells.rs`, which does not import this module).
impl Cells {
    /// The canonical cells of the points `lattice` (at pixel `positions`), built like
    /// [`Cells::incremental`] near the hull and by look-up elsewhere: a quasicrystal has few
    /// local configurations, so the cells around most sites are computed once per
    /// configuration and copied for the others (`src/reconstruction/atlas.rs` says why that
    /// is exact). The same cells as [`Cells::incremental`] (in another order), about twice
    /// as fast from 50 000 points (`benches/cells.rs`; below that, or where the
    /// configurations are too diverse to pay, it is exact insertion), and `None` in the same
    /// cases. For a set that gets no more points; a growing one keeps
    /// [`Cells::incremental`]'s structure.
    ///
    /// ```
    /// use qcs::reconstruction::{Cells, SampleSet};
    /// use qcs::sites::Quasicrystal;
    /// let mut set = SampleSet::new(256, 256, 1);
    /// for s in Quasicrystal::new(256, 256)?.first(8000) {
    ///     set.push_exact(s.pos, s.lattice, &[0]);
    /// }
    /// let (p, l) = (set.points(), set.point_lattice());
    /// let sorted = |c: Cells| { let mut v: Vec<Vec<u32>> = c.iter().map(<[u32]>::to_vec).collect(); v.sort(); v };
    /// assert_eq!(sorted(Cells::atlas(p, l).unwrap()), sorted(Cells::incremental(p, l).unwrap()));
    /// # Ok::<(), qcs::sites::FrameError>(())
    /// ```
    pub fn atlas(positions: &[Point], lattice: &[Option<ZZeta>]) -> Option<Cells> {
        Some(cells_with(positions, lattice, false)?.0)
    }
}

/// The cells and how many sites were looked up (`force`: even where it does not pay).
fn cells_with(
    positions: &[Point],
    lattice: &[Option<ZZeta>],
    force: bool,
) -> Option<(Cells, usize)> {
    let n = lattice.len().min(positions.len());
    let (positions, lattice) = (&positions[..n], &lattice[..n]);
    let all = || Some((Cells::incremental(positions, lattice)?, 0));
    if n < MIN_POINTS && !force {
        return all();
    }
    let zz: Vec<ZZeta> = lattice
        .iter()
        .map(|x| x.filter(|&x| within_exact_limit(x)))
        .collect::<Option<_>>()?;
    // The key's radius from a grid for the pilot, then a grid for that radius.
    let pilot = PointGrid::new(positions, &zz);
    let Some((reach, grid)) = pilot.and_then(|g| {
        let r = g.radius()?;
        Some((r, g.with_side(r / 2.0)?))
    }) else {
        return all();
    };
    let mut vectors = Vectors::default();
    let mut atlas: HashMap<Key, Star, BuildHasherDefault<KeyHash>> = HashMap::default();
    // New keys are built locally up to this many (one costs about as much as inserting
    // ten points exactly); later ones count as undecided.
    let budget = n / 16;
    let mut decided = vec![false; n];
    let mut offsets = Vec::with_capacity(2 * n + 1);
    offsets.push(0u32);
    let mut vertices = Vec::with_capacity(n * 6);
    let mut local = Local::default();
    // Per vector, the point it leads to from the current site (where the key has its bit).
    let mut at = [0u32; MAX_VECTORS];
    let (mut done, mut decided_count) = (0, 0);
    for pass in [true, false] {
        for c in grid.cells().filter(|&c| grid.inner(c) == pass) {
            for k in grid.range(c) {
                let i = grid.point[k] as usize;
                done += 1;
                if done == PROBE && PROBE - decided_count > PROBE / 8 && !force {
                    return all();
                }
                let mut key = [0u64; MAX_VECTORS / 64];
                let mut ok = true;
                let x = grid.zz[k];
                grid.near(c, k, reach, |j| {
                    let Some(b) = vectors.index(grid.zz[j] - x) else {
                        ok = false;
                        return;
                    };
                    let (word, bit) = ((b >> 6) as usize, b & 63);
                    // (Two points at one lattice point would set a bit twice.)
                    ok &= key[word] >> bit & 1 == 0;
                    key[word] |= 1 << bit;
                    at[b as usize] = grid.point[j];
                });
                if !ok {
                    continue;
                }
                let star = match atlas.get(&key) {
                    Some(star) => star,
                    // Near the edges keys are mostly unique: not worth a local build.
                    None if !pass || atlas.len() >= budget => continue,
                    None => {
                        let star = local.star(&grid, c, k, reach, &mut vectors);
                        let star = star.filter(|s| s.1 <= reach * (1.0 - 1e-9)).map(|s| s.0);
                        atlas.entry(key).or_insert(star)
                    }
                };
                let Some(star) = star else {
                    continue;
                };
                decided[i] = true;
                decided_count += 1;
                let mut rest = &star[..];
                while let Some((&len, tail)) = rest.split_first() {
                    let (cell, tail) = tail.split_at(len as usize);
                    vertices.push(i as u32);
                    vertices.extend(cell.iter().map(|&b| at[b as usize]));
                    offsets.push(vertices.len() as u32);
                    rest = tail;
                }
            }
        }
    }
    // Every point within D of an undecided one goes to the exact build (see the module
    // documentation), with the undecided ones.
    let mut build = vec![false; n];
    for c in grid.cells() {
        for k in grid.range(c) {
            let i = grid.point[k] as usize;
            if !decided[i] {
                build[i] = true;
                grid.near(c, k, reach, |j| build[grid.point[j] as usize] = true);
            }
        }
    }
    let index: Vec<u32> = (0..n as u32).filter(|&i| build[i as usize]).collect();
    let pick = |i: &u32| (positions[*i as usize], lattice[*i as usize]);
    let (sub_pos, sub_zz): (Vec<Point>, Vec<Option<ZZeta>>) = index.iter().map(pick).unzip();
    let sub = Cells::incremental(&sub_pos, &sub_zz)?;
    for cell in sub.iter() {
        if !decided[index[cell[0] as usize] as usize] {
            vertices.extend(cell.iter().map(|&v| index[v as usize]));
            offsets.push(vertices.len() as u32);
        }
    }
    let hull = sub.hull().iter().map(|e| e.map(|v| index[v as usize]));
    let cells = Cells::from_parts(offsets, vertices, hull.collect(), sub.flips());
    Some((cells, decided_count))
}

/// Scratch space for local builds.
#[derive(Default)]
struct Local {
    pos: Vec<Point>,
    zz: Vec<ZZeta>,
    bits: Vec<u8>,
}

impl Local {
    /// The cells of entry `k` (in bucket `c`) that it owns, from the points within `reach`
    /// of it, as a [`Star`] (`vectors` numbers their vectors), and how far their circles
    /// reach from it; `None` if those cells do not surround it.
    fn star(
        &mut self,
        grid: &PointGrid,
        c: usize,
        k: usize,
        reach: f64,
        vectors: &mut Vectors,
    ) -> Option<(Box<[u8]>, f64)> {
        let x = grid.zz[k];
        self.pos.clear();
        self.zz.clear();
        self.bits.clear();
        self.pos.push(grid.pos[k]);
        self.zz.push(x);
        let mut ok = true;
        grid.near(c, k, reach, |j| {
            self.pos.push(grid.pos[j]);
            self.zz.push(grid.zz[j]);
            match vectors.index(grid.zz[j] - x) {
                Some(b) => self.bits.push(b),
                None => ok = false,
            }
        });
        if !ok {
            return None;
        }
        local_star(&self.pos, &self.zz, &self.bits)
    }
}

/// The cells around local point 0 that it owns, as indices of `bits` (local point `j` is
/// `bits[j - 1]`), and how far their circumcircles reach from it, if they surround it.
///
/// The cells are found by turning around point 0: its nearest neighbour `a` is a Delaunay
/// neighbour; the cell left of the edge 0 → `a` has the point `b` left of it whose circle
/// through 0 and `a` holds no other, and every point on that circle; its last vertex is
/// the next neighbour. Exact predicates ([`Store`]) decide every step.
fn local_star(pos: &[Point], zz: &[ZZeta], bits: &[u8]) -> Option<(Box<[u8]>, f64)> {
    let m = zz.len() as u32;
    let mut s = Store::default();
    for (j, &x) in zz.iter().enumerate() {
        s.push(x, j as u32);
    }
    let first = (1..m).min_by_key(|&j| (zz[j as usize] - zz[0]).norm2())?;
    let rel = |v: u32| {
        let p = pos[v as usize];
        [p[0] - pos[0][0], p[1] - pos[0][1]]
    };
    let mut extent = 0.0f64;
    let mut owned = Vec::new();
    let mut cell: Vec<u32> = Vec::new();
    let mut a = first;
    for _ in 0..m {
        let mut best = None;
        for c in 1..m {
            if c != a && s.orient(0, a, c) > 0 {
                match best {
                    Some(b) if s.incircle(0, a, b, c) <= 0 => {}
                    _ => best = Some(c),
                }
            }
        }
        let b = best?; // point 0 is on the hull
        cell.clear();
        cell.extend((1..m).filter(|&c| {
            c == b || (c != a && s.orient(0, a, c) > 0 && s.incircle(0, a, b, c) == 0)
        }));
        // Counter-clockwise after `a`, as seen from it (the cell is convex).
        cell.sort_by(|&p, &q| 0.cmp(&s.orient(a, p, q)));
        cell.insert(0, a);
        cell.insert(0, 0);
        let (centre, radius) = circumcircle(rel(0), rel(a), rel(b))?;
        extent = extent.max(centre[0].hypot(centre[1]) + radius);
        // Point 0 owns the cell if it has the smallest lattice point.
        if cell[1..].iter().all(|&v| zz[v as usize] > zz[0]) {
            owned.push(cell.len() as u8 - 1);
            owned.extend(cell[1..].iter().map(|&v| bits[v as usize - 1]));
        }
        a = *cell.last()?;
        if a == first {
            return Some((owned.into(), extent));
        }
    }
    None
}

/// Centre and radius of the circle through `a`, `b`, `c` (`None` if they are collinear).
fn circumcircle(a: Point, b: Point, c: Point) -> Option<(Point, f64)> {
    let (bx, by, cx, cy) = (b[0] - a[0], b[1] - a[1], c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let (ux, uy) = ((cy * b2 - by * c2) / d, (bx * c2 - cx * b2) / d);
    Some(([a[0] + ux, a[1] + uy], ux.hypot(uy)))
}

/// Lattice vectors numbered as they are first seen (at most [`MAX_VECTORS`]), in an
/// open-addressed table.
struct Vectors {
    slots: Vec<(ZZeta, u16)>,
    count: usize,
}

const EMPTY: u16 = u16::MAX;
const SLOTS: usize = MAX_VECTORS * 4;

impl Default for Vectors {
    fn default() -> Self {
        Vectors {
            slots: vec![(ZZeta::new([0; 4]), EMPTY); SLOTS],
            count: 0,
        }
    }
}

impl Vectors {
    /// The index of `v`, numbering it if it is new (`None` if the table is full).
    fn index(&mut self, v: ZZeta) -> Option<u8> {
        // The four coordinates, 16 bits each (a hash: equal ones are compared whole).
        let [a, b, c, d] = v.0.map(|x| x as u64 & 0xFFFF);
        let h = (a | b << 16 | c << 32 | d << 48).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let mut s = (h >> (64 - SLOTS.trailing_zeros())) as usize;
        loop {
            let (z, k) = self.slots[s % SLOTS];
            if k == EMPTY {
                if self.count == MAX_VECTORS {
                    return None;
                }
                self.slots[s % SLOTS] = (v, self.count as u16);
                self.count += 1;
                return Some((self.count - 1) as u8);
            }
            if z == v {
                return Some(k as u8);
            }
            s += 1;
        }
    }
}

/// The points bucketed in a grid of square cells, with their positions and lattice points
/// stored in bucket order, so that a site's neighbours are near in memory.
struct PointGrid {
    /// The mean spacing of the points, √(area / points), in the box of their central 98 %.
    spacing: f64,
    central: [Point; 2],
    side: f64,
    /// Buckets (columns, rows) well inside that box.
    inner: [std::ops::Range<usize>; 2],
    cols: usize,
    rows: usize,
    /// Bucket `c` holds entries `start[c]..start[c + 1]`.
    start: Vec<u32>,
    point: Vec<u32>,
    pos: Vec<Point>,
    zz: Vec<ZZeta>,
}

impl PointGrid {
    /// The points in buckets of [`PILOT_SIDE`] mean spacings. `None` if they span no area
    /// (or too little for buckets to make sense).
    fn new(positions: &[Point], zz: &[ZZeta]) -> Option<PointGrid> {
        let n = positions.len();
        if positions.iter().flatten().any(|x| !x.is_finite()) {
            return None;
        }
        // The spacing from the box of the central 98 % in x and in y (of a sample): the
        // mirror points of the first samples lie far out, and would make the whole box
        // too sparse.
        let (mut qlo, mut qhi) = ([0.0; 2], [0.0; 2]);
        let mut v = Vec::with_capacity(n);
        for a in 0..2 {
            v.clear();
            v.extend(positions.iter().step_by(n / 8192 + 1).map(|p| p[a]));
            let cut = v.len() / 100;
            qlo[a] = *v.select_nth_unstable_by(cut, f64::total_cmp).1;
            let top = v.len() - 1 - cut;
            qhi[a] = *v.select_nth_unstable_by(top, f64::total_cmp).1;
        }
        let inside = |p: &&Point| (0..2).all(|a| p[a] >= qlo[a] && p[a] <= qhi[a]);
        let count = positions.iter().filter(inside).count();
        let area = (qhi[0] - qlo[0]) * (qhi[1] - qlo[1]);
        let spacing = (area / count as f64).sqrt();
        let point: Vec<u32> = (0..n as u32).collect();
        let central = [qlo, qhi];
        PointGrid::bucket(
            spacing,
            central,
            PILOT_SIDE * spacing,
            &point,
            positions,
            zz,
        )
    }

    /// The same points in buckets of `side`.
    fn with_side(&self, side: f64) -> Option<PointGrid> {
        PointGrid::bucket(
            self.spacing,
            self.central,
            side,
            &self.point,
            &self.pos,
            &self.zz,
        )
    }

    /// Points `point` (at `pos`, `zz`) in buckets of `side` over the box `central` and a
    /// margin; points beyond go to its edge buckets (which keeps every point within a
    /// distance of another within as many buckets).
    fn bucket(
        spacing: f64,
        central: [Point; 2],
        side: f64,
        point: &[u32],
        pos: &[Point],
        zz: &[ZZeta],
    ) -> Option<PointGrid> {
        let [qlo, qhi] = central;
        if !(side.is_finite() && side > 0.0) {
            return None;
        }
        let margin = |a: usize| 0.05 * (qhi[a] - qlo[a]) + 4.0 * side;
        let lo = [qlo[0] - margin(0), qlo[1] - margin(1)];
        let hi = [qhi[0] + margin(0), qhi[1] + margin(1)];
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        let (cols, rows) = ((w / side) as usize + 1, (h / side) as usize + 1);
        if cols.checked_mul(rows)? > 4 * pos.len() + 16 {
            return None;
        }
        // Buckets three or more inside the central box.
        let span = |a: usize| {
            let first = ((qlo[a] - lo[a]) / side) as usize + 3;
            first..(((qhi[a] - lo[a]) / side) as usize).saturating_sub(2)
        };
        let inner = [span(0), span(1)];
        let of: Vec<u32> = (pos.iter())
            .map(|p| {
                // (`as` saturates: negative to 0.)
                let (x, y) = ((p[0] - lo[0]) / side, (p[1] - lo[1]) / side);
                ((y as usize).min(rows - 1) * cols + (x as usize).min(cols - 1)) as u32
            })
            .collect();
        let mut start = vec![0u32; cols * rows + 1];
        for &b in &of {
            start[b as usize + 1] += 1;
        }
        for c in 0..cols * rows {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; pos.len()];
        for (k, &b) in of.iter().enumerate() {
            order[fill[b as usize] as usize] = k as u32;
            fill[b as usize] += 1;
        }
        Some(PointGrid {
            spacing,
            central,
            side,
            inner,
            cols,
            rows,
            start,
            point: order.iter().map(|&k| point[k as usize]).collect(),
            pos: order.iter().map(|&k| pos[k as usize]).collect(),
            zz: order.iter().map(|&k| zz[k as usize]).collect(),
        })
    }

    /// The key's radius `D`: a little more than the farthest any circle of an interior
    /// site's cells reaches from it, over [`PILOT`] sites spread over the interior (a
    /// site whose circles reach farther is undecided). `None` if none of them could tell.
    fn radius(&self) -> Option<f64> {
        let inner: Vec<usize> = self.cells().filter(|&c| self.inner(c)).collect();
        let mut local = Local::default();
        let mut vectors = Vectors::default();
        let reach = PILOT_REACH * self.spacing;
        let mut extent: Option<f64> = None;
        for t in 0..PILOT {
            let c = inner.get(t * inner.len() / PILOT)?;
            let Some(k) = self.range(*c).next() else {
                continue;
            };
            if vectors.count > MAX_VECTORS / 2 {
                vectors = Vectors::default();
            }
            if let Some((_, e)) = local.star(self, *c, k, reach, &mut vectors) {
                if e < reach * 0.99 {
                    extent = Some(extent.map_or(e, |x| x.max(e)));
                }
            }
        }
        extent.map(|e| e * 1.01)
    }

    fn cells(&self) -> std::ops::Range<usize> {
        0..self.cols * self.rows
    }

    /// Whether bucket `c` lies well inside the central box (its sites, the quasicrystal's
    /// interior, are done first, so that their vectors get numbered first).
    fn inner(&self, c: usize) -> bool {
        self.inner[0].contains(&(c % self.cols)) && self.inner[1].contains(&(c / self.cols))
    }

    fn range(&self, c: usize) -> std::ops::Range<usize> {
        self.start[c] as usize..self.start[c + 1] as usize
    }

    /// Calls `f` with every entry other than `k` (in bucket `c`) within `radius` of it.
    fn near(&self, c: usize, k: usize, radius: f64, mut f: impl FnMut(usize)) {
        let rings = (radius / self.side).ceil() as usize;
        let (x, y) = (c % self.cols, c / self.cols);
        let p = self.pos[k];
        let r2 = radius * radius;
        let (a, b) = (x.saturating_sub(rings), (x + rings + 1).min(self.cols));
        for yy in y.saturating_sub(rings)..(y + rings + 1).min(self.rows) {
            let row = yy * self.cols;
            let from = self.start[row + a] as usize;
            let run = &self.pos[from..self.start[row + b] as usize];
            for (j, q) in (from..).zip(run) {
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                if dx * dx + dy * dy <= r2 && j != k {
                    f(j);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reconstruction::{Method, RenderOptions, SampleSet};
    use crate::sites::Quasicrystal;
    use proptest::prelude::*;

    fn set(w: u32, h: u32, n: usize) -> SampleSet {
        let mut set = SampleSet::new(w, h, 1);
        for (k, s) in Quasicrystal::new(w, h).unwrap().first(n).iter().enumerate() {
            set.push_exact(s.pos, s.lattice, &[(k * 37 % 251) as u8]);
        }
        set
    }

    /// Asserts that the look-up gives exact insertion's cells and hull (and those of
    /// spade's triangulation, made exact, if `spade`); returns the share of the points that
    /// were looked up.
    fn check(set: &mut SampleSet, spade: bool) -> f64 {
        if spade {
            let mesh = set.triangulation().clone();
            let (got, want) = (
                Cells::atlas(set.points(), set.point_lattice()),
                Cells::build(&mesh, set.point_lattice()),
            );
            assert_eq!(
                got.as_ref().map(sorted),
                want.as_ref().map(sorted),
                "against spade"
            );
        }
        let (p, l) = (set.points(), set.point_lattice());
        let want = Cells::incremental(p, l).unwrap();
        let (got, decided) = cells_with(p, l, true).unwrap();
        let (g, e) = (sorted(&got), sorted(&want));
        let missing: Vec<_> = e.iter().filter(|c| g.binary_search(c).is_err()).collect();
        let extra: Vec<_> = g.iter().filter(|c| e.binary_search(c).is_err()).collect();
        assert!(
            missing.is_empty() && extra.is_empty() && g.len() == e.len(),
            "{} cells, {} expected; missing {:?}…, extra {:?}…",
            g.len(),
            e.len(),
            &missing[..missing.len().min(5)],
            &extra[..extra.len().min(5)]
        );
        assert_eq!(got.hull(), want.hull());
        decided as f64 / p.len() as f64
    }

    /// The cells, each as its vertex list, sorted.
    fn sorted(c: &Cells) -> Vec<Vec<u32>> {
        let mut v: Vec<Vec<u32>> = c.iter().map(<[u32]>::to_vec).collect();
        v.sort();
        v
    }

    #[test]
    fn same_cells_as_exact_insertion_mostly_looked_up() {
        // Frames and densities in several phases of the window (the key's radius from 2.0
        // to 2.9 mean spacings), looked up even where that does not pay.
        for (w, h, n, share) in [
            (256, 256, 8_000, 0.2),
            (256, 256, 12_000, 0.6),
            (300, 200, 9_000, 0.3),
            (97, 411, 12_000, 0.6),
            (512, 512, 53_000, 0.9),
        ] {
            let got = check(&mut set(w, h, n), n > 50_000);
            assert!(
                got >= share,
                "{w}×{h} at {n}: {got:.3} of the points looked up"
            );
        }
    }

    #[test]
    fn one_shot_renders_match_streaming_ones() {
        // `settle` builds the cells by look-up, a streaming render by exact insertion.
        let (w, h) = (400, 300);
        let mut streaming = set(w, h, 60_000);
        let mut settled = streaming.clone();
        settled.settle(Method::Gouraud);
        let one = RenderOptions::single_threaded();
        for (ow, oh) in [(400, 300), (173, 131)] {
            let a = streaming.render_with(Method::Gouraud, ow, oh, one);
            let b = settled.render_with(Method::Gouraud, ow, oh, one);
            assert!(a == b, "{ow}×{oh}");
        }
    }

    /// The cells of arbitrary lattice points at `10·x + 500` px (with repeats).
    fn scattered(coeffs: &[[i64; 4]]) -> (Vec<Point>, Vec<Option<ZZeta>>) {
        let zz: Vec<ZZeta> = coeffs.iter().map(|&c| ZZeta::new(c)).collect();
        let pos = zz
            .iter()
            .map(|x| x.to_f64())
            .map(|(re, im)| [500.0 + 10.0 * re, 500.0 + 10.0 * im]);
        (pos.collect(), zz.into_iter().map(Some).collect())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        #[test]
        fn any_frame_and_prefix(w in 40u32..500, h in 40u32..500, n in 500usize..12_000) {
            check(&mut set(w, h, n), false);
        }

        #[test]
        fn any_lattice_points(c in proptest::collection::vec(proptest::array::uniform4(-6i64..6), 3..3000)) {
            let (p, l) = scattered(&c);
            let want = Cells::incremental(&p, &l);
            let got = cells_with(&p, &l, true).map(|g| g.0);
            let key = |c: Cells| (sorted(&c), c.hull().to_vec());
            prop_assert_eq!(got.map(key), want.map(key));
        }
    }
}
