//! Canonical Delaunay cells: the Delaunay subdivision of sites with exact lattice points.
//!
//! A quasicrystal is full of cocircular sites (golden trapezoids, regular pentagons), so its
//! Delaunay *triangulation* is not unique: a triangulator splits those cells by insertion
//! order and rounding. The Delaunay *subdivision* — every cell a convex polygon whose
//! vertices lie on an empty circle — is unique for a set of sites. It is computed with the
//! exact predicates of [`crate::lattice::incircle`] from a triangulation `spade` returns:
//! the codec's one builder, [`Cells::incremental`] (what a [`super::SampleSet`] uses), has
//! `spade` triangulate the first points and inserts the others with exact predicates, and
//! [`Cells::atlas`] speeds it up for a set that gets no more points; [`Cells::build`] takes
//! `spade`'s triangulation of all the points (the tests' cross-check, and the insertion's
//! retry should it ever give up). From `spade`'s triangles (of the start, or of all the
//! points; an inserted point splits a triangle and gets exact flips around it):
//!
//! 1. triangles that are exactly degenerate (three collinear sites on the convex hull, which
//!    `f64` rounding can show as a sliver) are flipped away or dropped;
//! 2. every edge that the exact test says is not locally Delaunay is flipped (Lawson);
//! 3. the two triangles of every edge whose four sites are exactly cocircular are merged.
//!
//! See `spec/reconstruction.md` for the rule that draws the cells.
//!
//! This module holds the type and what reads it; the builders that make it are beside it and
//! depend on it, not the reverse: [`Cells::build`] and [`Cells::incremental`] in
//! `delaunay.rs`, [`Cells::atlas`] in `atlas.rs`.

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
