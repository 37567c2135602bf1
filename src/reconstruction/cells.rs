//! Canonical Delaunay cells: the Delaunay subdivision of sites with exact lattice points.
//!
//! A quasicrystal is full of cocircular sites (golden trapezoids, regular pentagons), so its
//! Delaunay *triangulation* is not unique: a triangulator splits those cells by insertion
//! order and rounding. The Delaunay *subdivision* — every cell a convex polygon whose
//! vertices lie on an empty circle — is unique for a set of sites. It is computed here from
//! any triangulation `spade` returns, with the exact predicates of
//! [`crate::lattice::incircle`]:
//!
//! 1. triangles that are exactly degenerate (three collinear sites on the convex hull, which
//!    `f64` rounding can show as a sliver) are flipped away or dropped;
//! 2. every edge that the exact test says is not locally Delaunay is flipped (Lawson);
//! 3. the two triangles of every edge whose four sites are exactly cocircular are merged.
//!
//! See `spec/reconstruction.md` for the rule that draws the cells.

use spade::Triangulation as _;

use super::mesh::Triangulation;
use crate::lattice::{incircle, orient, ZZeta};

const NONE: u32 = u32::MAX;

/// The Delaunay subdivision of a sample set into convex cells.
///
/// Each cell lists the sample indices of its vertices counter-clockwise (in pixel
/// coordinates read as Cartesian numbers, i.e. clockwise on screen, y down), starting from
/// the vertex with the smallest lattice point (`ZZeta`'s `Ord`), so each list depends on the
/// sites only, not on how they were triangulated (the order of the cells is unspecified).
///
/// ```
/// use qcs::reconstruction::SampleSet;
/// use qcs::sites::Quasicrystal;
/// let sites = Quasicrystal::new(64, 64)?.first(200);
/// let mut set = SampleSet::new(64, 64, 1);
/// for s in &sites {
///     set.push_exact(s.pos, s.lattice, &[0]);
/// }
/// let cells = set.cells().expect("every sample has an exact point");
/// // A k-cell holds k − 2 of spade's triangles (spade may add slivers of collinear hull sites).
/// let triangles: usize = cells.iter().map(|c| c.len() - 2).sum();
/// assert!(cells.iter().any(|c| c.len() >= 4)); // cocircular cells are everywhere
/// assert!(triangles <= set.triangulation().num_inner_faces());
/// # use spade::Triangulation as _;
/// # Ok::<(), qcs::sites::FrameError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Cells {
    offsets: Vec<u32>,
    vertices: Vec<u32>,
    hull: Vec<[u32; 2]>,
    flips: usize,
}

impl Cells {
    /// The canonical cells of `mesh`, whose vertex data index `lattice` (the exact point of
    /// every sample). `None` if some vertex has no exact point, if an exact point is beyond
    /// [`crate::lattice::EXACT_LIMIT`], or if the triangulation is inconsistent with the
    /// exact points (then the caller keeps `mesh`'s own triangles).
    ///
    /// ```
    /// use qcs::lattice::ZZeta;
    /// use qcs::reconstruction::{Cells, Triangulation, Vertex};
    /// use spade::{Point2, Triangulation as _};
    /// // The regular pentagon 1, ζ, …, ζ⁴ (unit roots, pixel = 10 + 5·x).
    /// let z = |k: usize| { let mut n = [0i64; 4]; if k < 4 { n[k] = 1 } else { n = [-1; 4] }; ZZeta::new(n) };
    /// let lattice: Vec<Option<ZZeta>> = (0..5).map(|k| Some(z(k))).collect();
    /// let mut mesh = Triangulation::new();
    /// for (k, x) in lattice.iter().enumerate() {
    ///     let (re, im) = x.unwrap().to_f64();
    ///     mesh.insert(Vertex { position: Point2::new(10.0 + 5.0 * re, 10.0 + 5.0 * im), index: k as u32 }).unwrap();
    /// }
    /// assert_eq!(mesh.num_inner_faces(), 3);
    /// let cells = Cells::build(&mesh, &lattice).unwrap();
    /// assert_eq!(cells.len(), 1);
    /// // Counter-clockwise from the smallest lattice point, ζ⁴ = (−1, −1, −1, −1).
    /// assert_eq!(cells.get(0), Some(&[4u32, 0, 1, 2, 3][..]));
    /// ```
    pub fn build(mesh: &Triangulation, lattice: &[Option<ZZeta>]) -> Option<Cells> {
        let live = LiveCells::build(mesh, lattice)?;
        Some(live.cells(lattice))
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Whether there is no cell (fewer than three non-collinear sites).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The vertices (sample indices) of cell `k`, counter-clockwise.
    pub fn get(&self, k: usize) -> Option<&[u32]> {
        let a = *self.offsets.get(k)? as usize;
        let b = *self.offsets.get(k + 1)? as usize;
        self.vertices.get(a..b)
    }

    /// The cells in order, each as its vertices' sample indices.
    pub fn iter(&self) -> impl Iterator<Item = &[u32]> + '_ {
        self.offsets
            .windows(2)
            .map(|w| &self.vertices[w[0] as usize..w[1] as usize])
    }

    /// The edges of the convex hull (sample indices `a → b`, counter-clockwise), every
    /// site exactly on the hull boundary included, sorted by lattice point of `a`.
    pub fn hull(&self) -> &[[u32; 2]] {
        &self.hull
    }

    /// How many exact edge flips the repair needed (0 when `spade`'s triangulation was
    /// already exactly Delaunay).
    pub fn flips(&self) -> usize {
        self.flips
    }

    /// Number of cells with `k` vertices, for `k = 0..=max` (index `k`).
    ///
    /// ```
    /// let cells = qcs::reconstruction::Cells::default();
    /// assert_eq!(cells.histogram(), Vec::<usize>::new());
    /// ```
    pub fn histogram(&self) -> Vec<usize> {
        let mut h = Vec::new();
        for c in self.iter() {
            if h.len() <= c.len() {
                h.resize(c.len() + 1, 0);
            }
            h[c.len()] += 1;
        }
        h
    }
}

/// The exact Delaunay triangulation behind the canonical cells, kept so that new points can
/// be inserted locally (streaming): a new point splits the triangle (or the two triangles of
/// the edge) it falls in, exact flips restore the Delaunay property around it, and only the
/// edges of the triangles that changed are tested for cocircularity again.
#[derive(Clone, Debug)]
pub(crate) struct LiveCells {
    mesh: Mesh,
    /// Per triangle slot: whether the edge opposite vertex `i` joins two cocircular triangles.
    merge: Vec<[bool; 3]>,
    flips: usize,
    /// Points inserted so far (`0..points` of the lattice list).
    pub(crate) points: usize,
    /// Where to start locating a point.
    locator: Locator,
}

/// A uniform grid over the points' bounding box (in lattice coordinates) holding, per
/// bucket, the last vertex inserted there; a walk starts from a triangle of that vertex.
/// Progressive sites are spread over the whole image, so walking from the last insertion
/// would cross O(√n) triangles; from a vertex in the same bucket it crosses a few.
#[derive(Clone, Debug)]
struct Locator {
    origin: [f64; 2],
    inv: f64,
    side: usize,
    buckets: Vec<u32>,
    /// Point count the grid was sized for.
    sized_for: usize,
}

impl Locator {
    /// A grid of about two vertices per bucket over the vertices of `mesh`.
    fn new(mesh: &Mesh, pt: &impl Fn(u32) -> ZZeta, points: usize) -> Locator {
        let at: Vec<(u32, [f64; 2])> = (0..mesh.vtri.len() as u32)
            .filter(|&v| mesh.vtri[v as usize] != NONE)
            .map(|v| {
                let (re, im) = pt(v).to_f64();
                (v, [re, im])
            })
            .collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (_, c) in &at {
            for k in 0..2 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        let side = ((at.len() as f64 / 2.0).sqrt()).clamp(1.0, 4096.0) as usize;
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        let mut l = Locator {
            origin: lo,
            inv: (side as f64 - 1e-9) / extent,
            side,
            buckets: vec![NONE; side * side],
            sized_for: points,
        };
        for &(v, c) in &at {
            let k = l.bucket(c);
            l.buckets[k] = v;
        }
        l
    }

    fn bucket(&self, p: [f64; 2]) -> usize {
        let f = |k: usize| {
            let v = ((p[k] - self.origin[k]) * self.inv).floor();
            v.clamp(0.0, self.side as f64 - 1.0) as usize
        };
        f(1) * self.side + f(0)
    }

    /// A Morton (Z-order) key of `x`'s position on a 2^16 × 2^16 grid over the box.
    fn morton(&self, x: ZZeta) -> u64 {
        let (re, im) = x.to_f64();
        let scale = self.inv * 65536.0 / self.side as f64;
        let q = |v: f64, o: f64| ((v - o) * scale).clamp(0.0, 65535.0) as u64;
        let spread = |mut v: u64| {
            v = (v | (v << 8)) & 0x00ff_00ff;
            v = (v | (v << 4)) & 0x0f0f_0f0f;
            v = (v | (v << 2)) & 0x3333_3333;
            (v | (v << 1)) & 0x5555_5555
        };
        spread(q(re, self.origin[0])) | (spread(q(im, self.origin[1])) << 1)
    }

    /// A vertex near `x`, if its bucket has one.
    fn hint(&self, x: ZZeta) -> u32 {
        let (re, im) = x.to_f64();
        self.buckets[self.bucket([re, im])]
    }

    fn note(&mut self, x: ZZeta, v: u32) {
        let (re, im) = x.to_f64();
        let k = self.bucket([re, im]);
        self.buckets[k] = v;
    }
}

/// Why a point could not be inserted locally (the caller rebuilds from scratch).
#[derive(Debug)]
pub(crate) struct Rebuild;

impl LiveCells {
    /// From any Delaunay triangulation of `lattice[0..n]` (`mesh` vertices index `lattice`).
    pub(crate) fn build(mesh: &Triangulation, lattice: &[Option<ZZeta>]) -> Option<LiveCells> {
        let point = |i: u32| lattice.get(i as usize).copied().flatten();
        for v in mesh.vertices() {
            if !point(v.data().index).is_some_and(crate::lattice::within_exact_limit) {
                return None;
            }
        }
        // Every lattice point was checked above, so this lookup cannot fail.
        let pt = |i: u32| point(i).unwrap_or(ZZeta([0; 4]));
        let mut m = Mesh::new(mesh)?;
        m.remove_slivers(&pt)?;
        let (flips, merge) = m.lawson(&pt)?;
        m.index_vertices();
        let locator = Locator::new(&m, &pt, lattice.len());
        Some(LiveCells {
            mesh: m,
            merge,
            flips,
            points: lattice.len(),
            locator,
        })
    }

    /// The cells as they are now.
    pub(crate) fn cells(&self, lattice: &[Option<ZZeta>]) -> Cells {
        let pt = |i: u32| {
            lattice
                .get(i as usize)
                .copied()
                .flatten()
                .unwrap_or(ZZeta([0; 4]))
        };
        self.mesh.cells(&pt, self.flips, &self.merge)
    }

    /// Inserts points `self.points..lattice.len()`. On [`Rebuild`] (a point outside the hull,
    /// or anything unexpected) the state is unusable and the caller builds afresh.
    pub(crate) fn extend(&mut self, lattice: &[Option<ZZeta>]) -> Result<(), Rebuild> {
        let mut touched = Vec::new();
        let pt = |j: u32| {
            lattice
                .get(j as usize)
                .copied()
                .flatten()
                .unwrap_or(ZZeta([0; 4]))
        };
        // Rounds of doubling size, each in Morton order: progressive points are spread over
        // the whole image, so inserting them as they come touches cold memory at every
        // step, while the cells do not depend on the insertion order.
        let mut round: Vec<(u64, u32)> = Vec::new();
        let mut lo = self.points;
        while lo < lattice.len() {
            let hi = lattice.len().min(2 * lo).max(lo + 1);
            round.clear();
            for i in lo..hi {
                let x = lattice[i]
                    .filter(|&x| crate::lattice::within_exact_limit(x))
                    .ok_or(Rebuild)?;
                round.push((self.locator.morton(x), i as u32));
            }
            round.sort_unstable();
            for &(_, i) in &round {
                self.insert(i, pt(i), &pt, &mut touched)?;
            }
            if hi > 2 * self.locator.sized_for {
                self.locator = Locator::new(&self.mesh, &pt, hi);
            }
            lo = hi;
        }
        self.points = lattice.len();
        // Cocircularity of every edge of a triangle that changed, seen from both sides.
        let pt = |j: u32| lattice[j as usize].unwrap_or(ZZeta([0; 4]));
        let mut mark = vec![false; self.mesh.tri.len()];
        for &t in &touched {
            mark[t as usize] = true;
        }
        for t in 0..mark.len() {
            if !mark[t] {
                continue;
            }
            let v = self.mesh.tri[t].map(pt);
            for i in 0..3 {
                let u = self.mesh.nbr[t][i] as usize;
                if u < t && mark[u] {
                    continue; // tested from `u`
                }
                let Some((j, d)) = self.mesh.across(t, i) else {
                    self.merge[t][i] = false;
                    continue;
                };
                let cocircular = incircle(v[0], v[1], v[2], pt(d)) == 0;
                self.merge[t][i] = cocircular;
                self.merge[self.mesh.nbr[t][i] as usize][j] = cocircular;
            }
        }
        Ok(())
    }

    /// Inserts point `i` at `x`: locate, split, flip.
    fn insert(
        &mut self,
        i: u32,
        x: ZZeta,
        pt: &impl Fn(u32) -> ZZeta,
        touched: &mut Vec<u32>,
    ) -> Result<(), Rebuild> {
        let m = &mut self.mesh;
        // Visibility walk from a triangle near the point.
        let mut t = match self.locator.hint(x) {
            NONE => NONE as usize,
            v => m
                .vtri
                .get(v as usize)
                .map_or(NONE as usize, |&t| t as usize),
        };
        if t >= m.tri.len() || !m.alive[t] {
            t = m.alive.iter().position(|&a| a).ok_or(Rebuild)?;
        }
        let mut steps = 0usize;
        let side = loop {
            let v = m.tri[t].map(pt);
            let o = [
                orient(v[1], v[2], x),
                orient(v[2], v[0], x),
                orient(v[0], v[1], x),
            ];
            match (0..3).find(|&k| o[k] < 0) {
                Some(k) => {
                    let u = m.nbr[t][k];
                    if u == NONE {
                        return Err(Rebuild); // outside the hull
                    }
                    t = u as usize;
                    steps += 1;
                    if steps > m.tri.len() + 8 {
                        return Err(Rebuild);
                    }
                }
                None => break o,
            }
        };
        let zeros: Vec<usize> = (0..3).filter(|&k| side[k] == 0).collect();
        let mut stack: Vec<(u32, u8)> = Vec::new();
        match zeros.len() {
            0 => {
                let [a, b, c] = m.tri[t];
                let [na, nb, nc] = m.nbr[t];
                let (t1, t2, t3) = (t as u32, m.tri.len() as u32, m.tri.len() as u32 + 1);
                m.tri[t] = [b, c, i];
                m.nbr[t] = [t2, t3, na];
                m.push([c, a, i], [t3, t1, nb]);
                m.push([a, b, i], [t1, t2, nc]);
                m.relink(nb, t1, t2);
                m.relink(nc, t1, t3);
                m.touch(t1);
                self.merge.resize(m.tri.len(), [false; 3]);
                self.merge[t] = [false; 3];
                stack.extend([(t1, 2), (t2, 2), (t3, 2)]);
                touched.extend([t1, t2, t3]);
            }
            1 => {
                // On the edge opposite vertex k of t: split t and its neighbour into four.
                let k = zeros[0];
                let Some((j, _)) = m.across(t, k) else {
                    return Err(Rebuild); // on the hull boundary
                };
                let u = m.nbr[t][k] as usize;
                let (a, b, c) = (m.tri[t][k], m.tri[t][(k + 1) % 3], m.tri[t][(k + 2) % 3]);
                let d = m.tri[u][j];
                let (t_ab, t_ca) = (m.nbr[t][(k + 2) % 3], m.nbr[t][(k + 1) % 3]);
                let (u_dc, u_bd) = (m.nbr[u][(j + 2) % 3], m.nbr[u][(j + 1) % 3]);
                let (t1, u1) = (t as u32, u as u32);
                let (t2, u2) = (m.tri.len() as u32, m.tri.len() as u32 + 1);
                m.tri[t] = [a, b, i];
                m.nbr[t] = [u2, t2, t_ab];
                m.tri[u] = [d, c, i];
                m.nbr[u] = [t2, u2, u_dc];
                m.push([a, i, c], [u1, t_ca, t1]);
                m.push([d, i, b], [t1, u_bd, u1]);
                m.relink(t_ca, t1, t2);
                m.relink(u_bd, u1, u2);
                m.touch(t1);
                m.touch(u1);
                self.merge.resize(m.tri.len(), [false; 3]);
                self.merge[t] = [false; 3];
                self.merge[u] = [false; 3];
                stack.extend([(t1, 2), (t2, 1), (u1, 2), (u2, 1)]);
                touched.extend([t1, t2, u1, u2]);
            }
            _ => {
                // On a vertex: the same point again (the first is kept).
                let v = m.tri[t].map(pt);
                return if v.contains(&x) { Ok(()) } else { Err(Rebuild) };
            }
        }
        self.locator.note(x, i);
        // Lawson flips around the new point.
        let budget = 8 * m.tri.len() + 64;
        let mut flips = 0usize;
        while let Some((t, e)) = stack.pop() {
            let (t, e) = (t as usize, e as usize);
            let Some((_, d)) = m.across(t, e) else {
                continue;
            };
            let v = m.tri[t];
            let sign = incircle(pt(v[0]), pt(v[1]), pt(v[2]), pt(d));
            if sign <= 0 {
                continue;
            }
            let (a, b, c) = (pt(v[e]), pt(v[(e + 1) % 3]), pt(v[(e + 2) % 3]));
            if orient(a, b, pt(d)) <= 0 || orient(a, pt(d), c) <= 0 {
                return Err(Rebuild);
            }
            flips += 1;
            if flips > budget {
                return Err(Rebuild);
            }
            let (t1, t2) = m.flip(t as u32, e).ok_or(Rebuild)?;
            // New triangles are [a, b, d] and [a, d, c], a the new point: their edges
            // opposite a are the ones to check.
            stack.extend([(t1, 0), (t2, 0)]);
            touched.extend([t1, t2]);
        }
        self.flips += flips;
        Ok(())
    }
}

/// Triangles with neighbours: `nbr[t][i]` is across the edge opposite `tri[t][i]`.
#[derive(Clone, Debug)]
struct Mesh {
    tri: Vec<[u32; 3]>,
    nbr: Vec<[u32; 3]>,
    alive: Vec<bool>,
    /// Per vertex (point index): a live triangle that has it, or `NONE`.
    vtri: Vec<u32>,
}

impl Mesh {
    /// Triangles and adjacency from `spade` (inner face `k` has index `k + 1` there).
    fn new(mesh: &Triangulation) -> Option<Mesh> {
        let n = mesh.num_inner_faces();
        let mut tri = vec![[0u32; 3]; n];
        let mut nbr = vec![[NONE; 3]; n];
        for f in mesh.inner_faces() {
            let t = f.fix().index().checked_sub(1).filter(|&t| t < n)?;
            let vs = f.vertices().map(|v| v.fix());
            tri[t] = vs.map(|v| mesh.vertex(v).data().index);
            for e in f.adjacent_edges() {
                // Edge v_k → v_{k+1} is opposite v_{k+2}.
                let k = vs.iter().position(|&v| v == e.from().fix())?;
                if vs[(k + 1) % 3] != e.to().fix() {
                    return None;
                }
                if let Some(g) = e.rev().face().as_inner() {
                    nbr[t][(k + 2) % 3] = g.fix().index().checked_sub(1).filter(|&u| u < n)? as u32;
                }
            }
        }
        let mut m = Mesh {
            tri,
            nbr,
            alive: vec![true; n],
            vtri: Vec::new(),
        };
        m.index_vertices();
        Some(m)
    }

    /// Recomputes [`Mesh::vtri`] from the live triangles.
    fn index_vertices(&mut self) {
        let top = self
            .tri
            .iter()
            .flatten()
            .max()
            .map_or(0, |&v| v as usize + 1);
        self.vtri = vec![NONE; top];
        for t in 0..self.tri.len() {
            if self.alive[t] {
                self.touch(t as u32);
            }
        }
    }

    /// Records `t` as the triangle of each of its vertices.
    fn touch(&mut self, t: u32) {
        for v in self.tri[t as usize] {
            let v = v as usize;
            if v >= self.vtri.len() {
                self.vtri.resize(v + 1, NONE);
            }
            self.vtri[v] = t;
        }
    }

    /// Appends a triangle.
    fn push(&mut self, tri: [u32; 3], nbr: [u32; 3]) {
        self.tri.push(tri);
        self.nbr.push(nbr);
        self.alive.push(true);
        self.touch(self.tri.len() as u32 - 1);
    }

    /// The neighbour across the edge opposite vertex `i` of `t`: its slot `j` for that edge
    /// and its vertex `d` there, if any.
    fn across(&self, t: usize, i: usize) -> Option<(usize, u32)> {
        let u = self.nbr[t][i];
        if u == NONE {
            return None;
        }
        let v = self.tri[t];
        let uv = self.tri[u as usize];
        let j = (0..3)
            .find(|&j| uv[(j + 1) % 3] == v[(i + 2) % 3] && uv[(j + 2) % 3] == v[(i + 1) % 3])?;
        Some((j, uv[j]))
    }

    /// Replaces `old` by `new` in `t`'s neighbour list.
    fn relink(&mut self, t: u32, old: u32, new: u32) {
        if t == NONE {
            return;
        }
        for s in &mut self.nbr[t as usize] {
            if *s == old {
                *s = new;
                return;
            }
        }
    }

    /// Flips the edge opposite vertex `i` of `t`. Returns the two new triangles (same ids).
    fn flip(&mut self, t: u32, i: usize) -> Option<(u32, u32)> {
        let u = self.nbr[t as usize][i];
        if u == NONE {
            return None;
        }
        let tv = self.tri[t as usize];
        let (a, b, c) = (tv[i], tv[(i + 1) % 3], tv[(i + 2) % 3]);
        let uv = self.tri[u as usize];
        let j = (0..3).find(|&j| uv[(j + 1) % 3] == c && uv[(j + 2) % 3] == b)?;
        let d = uv[j];
        let nt_b = self.nbr[t as usize][(i + 1) % 3]; // across c→a
        let nt_c = self.nbr[t as usize][(i + 2) % 3]; // across a→b
        let nu_c = self.nbr[u as usize][(j + 1) % 3]; // across b→d
        let nu_b = self.nbr[u as usize][(j + 2) % 3]; // across d→c
        self.tri[t as usize] = [a, b, d];
        self.nbr[t as usize] = [nu_c, u, nt_c];
        self.tri[u as usize] = [a, d, c];
        self.nbr[u as usize] = [nu_b, nt_b, t];
        self.relink(nu_c, u, t);
        self.relink(nt_b, t, u);
        self.touch(t);
        self.touch(u);
        Some((t, u))
    }

    /// Removes exactly degenerate triangles (collinear sites the `f64` positions showed as a
    /// sliver): flips the long edge into the neighbour behind it, or drops a sliver whose
    /// long edge is on the hull.
    fn remove_slivers(&mut self, pt: &impl Fn(u32) -> ZZeta) -> Option<()> {
        let mut budget = 4 * self.tri.len() + 16;
        let mut stack: Vec<u32> = (0..self.tri.len() as u32).collect();
        while let Some(t) = stack.pop() {
            if !self.alive[t as usize] {
                continue;
            }
            let v = self.tri[t as usize].map(pt);
            match orient(v[0], v[1], v[2]) {
                1 => continue,
                -1 => return None,
                _ => {}
            }
            budget = budget.checked_sub(1)?;
            // The middle vertex is opposite the longest edge.
            let len = |i: usize| (v[(i + 1) % 3].0, v[(i + 2) % 3].0);
            let l2 = |i: usize| {
                let (p, q) = len(i);
                ZZeta([p[0] - q[0], p[1] - q[1], p[2] - q[2], p[3] - q[3]]).norm2()
            };
            let i = (0..3).max_by(|&x, &y| l2(x).cmp(&l2(y)))?;
            let u = self.nbr[t as usize][i];
            if u == NONE {
                self.alive[t as usize] = false;
                for s in self.nbr[t as usize] {
                    self.relink(s, t, NONE);
                }
                self.nbr[t as usize] = [NONE; 3];
            } else {
                let (t1, t2) = self.flip(t, i)?;
                stack.push(t1);
                stack.push(t2);
            }
        }
        Some(())
    }

    /// Lawson's flips until every edge is exactly locally Delaunay; returns the flip count
    /// and, per triangle slot, whether that edge's four sites are exactly cocircular.
    fn lawson(&mut self, pt: &impl Fn(u32) -> ZZeta) -> Option<(usize, Vec<[bool; 3]>)> {
        let mut merge = vec![[false; 3]; self.tri.len()];
        let mut stack: Vec<(u32, u8)> = Vec::new();
        for t in 0..self.tri.len() as u32 {
            if self.alive[t as usize] {
                for i in 0..3u8 {
                    if self.nbr[t as usize][i as usize] > t {
                        stack.push((t, i));
                    }
                }
            }
        }
        let mut flips = 0usize;
        let budget = 8 * self.tri.len() + 64;
        while let Some((t, i)) = stack.pop() {
            let (t, i) = (t as usize, i as usize);
            let u = self.nbr[t][i];
            if u == NONE {
                continue;
            }
            let v = self.tri[t];
            let uv = self.tri[u as usize];
            let Some(j) = (0..3).find(|&j| uv[(j + 1) % 3] == v[(i + 2) % 3]) else {
                continue;
            };
            let d = uv[j];
            let [a, b, c] = [v[i], v[(i + 1) % 3], v[(i + 2) % 3]].map(pt);
            let sign = incircle(pt(v[0]), pt(v[1]), pt(v[2]), pt(d));
            merge[t][i] = sign == 0;
            merge[u as usize][j] = sign == 0;
            if sign <= 0 {
                continue;
            }
            // Strictly inside the circle and on the far side: the quad is convex.
            if orient(a, b, pt(d)) <= 0 || orient(a, pt(d), c) <= 0 {
                return None;
            }
            flips += 1;
            if flips > budget {
                return None;
            }
            let (t1, t2) = self.flip(t as u32, i)?;
            merge[t1 as usize] = [false; 3];
            merge[t2 as usize] = [false; 3];
            // New triangles are [a, b, d] and [a, d, c]: recheck their outer edges.
            stack.extend([(t1, 0), (t1, 2), (t2, 0), (t2, 1)]);
        }
        Some((flips, merge))
    }

    /// Lists the cells: triangles joined across exactly cocircular edges (`merge`).
    fn cells(&self, pt: &impl Fn(u32) -> ZZeta, flips: usize, merge: &[[bool; 3]]) -> Cells {
        let n = self.tri.len();
        let mut offsets = Vec::with_capacity(n + 1);
        let mut vertices = Vec::with_capacity(n * 3);
        offsets.push(0u32);
        let mut seen = vec![false; n];
        let mut stack = Vec::new();
        let mut edges: Vec<(u32, u32)> = Vec::new();
        for t0 in 0..n {
            if seen[t0] || !self.alive[t0] {
                continue;
            }
            if !merge[t0].contains(&true) {
                seen[t0] = true;
                let v = self.tri[t0];
                let s = (0..3).min_by_key(|&k| pt(v[k])).unwrap_or(0);
                vertices.extend_from_slice(&[v[s], v[(s + 1) % 3], v[(s + 2) % 3]]);
                offsets.push(vertices.len() as u32);
                continue;
            }
            // Flood the cell, collecting its boundary edges a → b.
            edges.clear();
            stack.push(t0);
            seen[t0] = true;
            while let Some(t) = stack.pop() {
                let v = self.tri[t];
                for i in 0..3 {
                    if merge[t][i] {
                        let u = self.nbr[t][i] as usize;
                        if u < n && !seen[u] {
                            seen[u] = true;
                            stack.push(u);
                        }
                    } else {
                        edges.push((v[(i + 1) % 3], v[(i + 2) % 3]));
                    }
                }
            }
            edges.sort_unstable();
            let Some(start) = edges.iter().map(|x| x.0).min_by_key(|&i| pt(i)) else {
                continue;
            };
            let mut cur = start;
            for _ in 0..edges.len() {
                vertices.push(cur);
                match edges.binary_search_by_key(&cur, |x| x.0) {
                    Ok(k) => cur = edges[k].1,
                    Err(_) => break,
                }
                if cur == start {
                    break;
                }
            }
            offsets.push(vertices.len() as u32);
        }
        let mut hull = Vec::new();
        for t in 0..n {
            if self.alive[t] {
                let v = self.tri[t];
                for i in 0..3 {
                    if self.nbr[t][i] == NONE {
                        hull.push([v[(i + 1) % 3], v[(i + 2) % 3]]);
                    }
                }
            }
        }
        hull.sort_by_key(|e| pt(e[0]));
        Cells {
            offsets,
            vertices,
            hull,
            flips,
        }
    }
}
