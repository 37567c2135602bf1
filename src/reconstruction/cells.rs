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
        Some(m.cells(&pt, flips, &merge))
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

/// Triangles with neighbours: `nbr[t][i]` is across the edge opposite `tri[t][i]`.
struct Mesh {
    tri: Vec<[u32; 3]>,
    nbr: Vec<[u32; 3]>,
    alive: Vec<bool>,
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
        let alive = vec![true; n];
        Some(Mesh { tri, nbr, alive })
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
