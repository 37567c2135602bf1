//! Canonical Delaunay cells: the Delaunay subdivision of sites with exact lattice points.
//!
//! A quasicrystal is full of cocircular sites (golden trapezoids, regular pentagons), so its
//! Delaunay *triangulation* is not unique: a triangulator splits those cells by insertion
//! order and rounding. The Delaunay *subdivision* — every cell a convex polygon whose
//! vertices lie on an empty circle — is unique for a set of sites. It is computed with the
//! exact predicates of [`crate::lattice::incircle`], either from any triangulation `spade`
//! returns ([`Cells::build`]) or by exact incremental insertion ([`Cells::incremental`], what
//! a [`super::SampleSet`] uses):
//!
//! 1. triangles that are exactly degenerate (three collinear sites on the convex hull, which
//!    `f64` rounding can show as a sliver) are flipped away or dropped;
//! 2. every edge that the exact test says is not locally Delaunay is flipped (Lawson);
//! 3. the two triangles of every edge whose four sites are exactly cocircular are merged.
//!
//! See `spec/reconstruction.md` for the rule that draws the cells.

use super::delaunay::LiveCells;
use super::mesh::Triangulation;
use crate::lattice::ZZeta;
use crate::sites::Point;

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
        Some(LiveCells::build(mesh, lattice)?.cells())
    }

    /// The canonical cells of the points `lattice` (exact points, at pixel `positions`),
    /// built without a whole `spade` triangulation: `spade` bulk loads the first few points
    /// and the others are inserted with exact predicates, in rounds of doubling size.
    /// Faster than [`Cells::build`] on progressive sites (`benches/cells.rs`), and the same
    /// cells. `None` if a point has no exact point or is beyond
    /// [`crate::lattice::EXACT_LIMIT`] (or, defensively, if the insertion finds the mesh
    /// inconsistent: then [`Cells::build`] is the fallback).
    ///
    /// ```
    /// use qcs::reconstruction::{Cells, SampleSet};
    /// use qcs::sites::Quasicrystal;
    /// let mut set = SampleSet::new(64, 64, 1);
    /// for s in Quasicrystal::new(64, 64)?.first(300) {
    ///     set.push_exact(s.pos, s.lattice, &[0]);
    /// }
    /// let grown = Cells::incremental(set.points(), set.point_lattice()).expect("exact points");
    /// let built = Cells::build(&set.triangulation().clone(), set.point_lattice()).unwrap();
    /// let sorted = |c: &Cells| { let mut v: Vec<Vec<u32>> = c.iter().map(<[u32]>::to_vec).collect(); v.sort(); v };
    /// assert_eq!(sorted(&grown), sorted(&built));
    /// # Ok::<(), qcs::sites::FrameError>(())
    /// ```
    pub fn incremental(positions: &[Point], lattice: &[Option<ZZeta>]) -> Option<Cells> {
        Some(LiveCells::grow(positions, lattice)?.cells())
    }

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
        super::atlas::cells(positions, lattice)
    }

    pub(crate) fn from_parts(
        offsets: Vec<u32>,
        vertices: Vec<u32>,
        hull: Vec<[u32; 2]>,
        flips: usize,
    ) -> Cells {
        Cells {
            offsets,
            vertices,
            hull,
            flips,
        }
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
