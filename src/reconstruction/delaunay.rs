//! The exact Delaunay triangulation of lattice points behind the canonical cells.
//!
//! Points are kept under compact internal ids, in the order they were inserted, with their
//! exact point in Z\[ζ\] and the `f64` positions of the point and of its star image: the
//! predicates decide from the cached positions with a proven error bound; near zero (every
//! merged cell of a quasicrystal is an exact zero) the star images' determinant proves a
//! zero by a norm argument ([`norm_says_zero`]), and only what neither decides goes to the
//! exact predicates of [`crate::lattice::incircle`].
//!
//! A triangulation is started from `spade`'s (bulk loaded for a whole set, or for the first
//! few points of a progressive one) and grown by local insertion: a new point splits the
//! triangle (or the two triangles of the edge) it falls in, or is joined to the hull edges it
//! sees from outside, and exact Lawson flips restore the Delaunay property around it. Points
//! are inserted in rounds of doubling size, each round in Z-order, so that consecutive
//! insertions are neighbours in the plane and in memory (the triangulation does not depend
//! on the order, the cells built from it even less).

use spade::Triangulation as _;

use super::cells::Cells;
use super::mesh::{self, SampleMesh};
use crate::lattice::{incircle_exact, orient_value, within_exact_limit, ZZeta};
use crate::sites::Point;

const NONE: u32 = u32::MAX;

/// Lattice points under internal ids: exact, cached in `f64`, and their point index.
#[derive(Clone, Debug, Default)]
pub(crate) struct Store {
    zz: Vec<ZZeta>,
    /// `(Re, Im)` of the point in `f64` and a bound on the error of either.
    xy: Vec<[f64; 3]>,
    /// The same for its star image `x*` ([`ZZeta::star`]).
    st: Vec<[f64; 3]>,
    /// Internal id → point index.
    ext: Vec<u32>,
    /// A box holding every cached position (it may hold the origin too), the largest error
    /// bound of one, and from them an error bound of [`orient_f`] that holds for any three
    /// points of the store (its bound grows with the points' spread and cached error; this
    /// takes the largest of both). An orientation beyond it has its sign without the bound
    /// of its own points, which most do. (The same for the incircle test decides too few.)
    lo: [f64; 2],
    hi: [f64; 2],
    hmax: f64,
    quick_orient: f64,
}

/// `max` without `f64::max`'s NaN handling (no NaN arises here).
#[inline(always)]
fn fmax(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

const EPS: f64 = f64::EPSILON;

/// `(Re, Im)` of `x` with a bound on their error: `to_f64` multiplies exact integers by
/// cos/sin constants (|c| ≤ 1) and adds four terms, within 4ε·Σ|n_k|; doubled for margin.
fn cached(x: ZZeta) -> [f64; 3] {
    let (re, im) = x.to_f64();
    let m: f64 = x.0.iter().map(|&n| n.unsigned_abs() as f64).sum();
    [re, im, 8.0 * EPS * m]
}

/// The orientation determinant of cached points and a bound on its error.
#[inline(always)]
fn orient_f(pa: [f64; 3], pb: [f64; 3], pc: [f64; 3]) -> (f64, f64) {
    let (px, py, qx, qy) = (pb[0] - pa[0], pb[1] - pa[1], pc[0] - pa[0], pc[1] - pa[1]);
    let det = px * qy - py * qx;
    // Each difference errs by ≤ h (both ends' error, and rounding), so each product by
    // ≤ M·h + (M + h)·h; the two roundings of the products and the one of their
    // difference add ≤ 3ε·M². Doubled for margin.
    let mm = fmax(fmax(px.abs(), py.abs()), fmax(qx.abs(), qy.abs()));
    let h = pa[2] + fmax(pb[2], pc[2]) + EPS * mm;
    (det, orient_err(mm, h))
}

/// The error bound of [`orient_f`] for differences up to `mm` that err by up to `h`
/// (increasing in both).
#[inline(always)]
fn orient_err(mm: f64, h: f64) -> f64 {
    2.0 * (4.0 * mm * h + 2.0 * h * h + 3.0 * EPS * mm * mm)
}

/// The incircle determinant of cached points and a bound on its error.
#[inline(always)]
fn incircle_f(pa: [f64; 3], pb: [f64; 3], pc: [f64; 3], pd: [f64; 3]) -> (f64, f64) {
    let (ax, ay) = (pa[0] - pd[0], pa[1] - pd[1]);
    let (bx, by) = (pb[0] - pd[0], pb[1] - pd[1]);
    let (cx, cy) = (pc[0] - pd[0], pc[1] - pd[1]);
    let det = (ax * ax + ay * ay) * (bx * cy - cx * by) - (bx * bx + by * by) * (ax * cy - cx * ay)
        + (cx * cx + cy * cy) * (ax * by - bx * ay);
    // Minors (≤ 2M²) err as an orientation, lifts (≤ 2M²) by ≤ 4Mh + 2h² + 6εM²; three
    // products of ≤ 4M⁴ and two sums add ≤ 24εM⁴ of rounding. Doubled for margin.
    let mm = fmax(
        fmax(fmax(ax.abs(), ay.abs()), fmax(bx.abs(), by.abs())),
        fmax(cx.abs(), cy.abs()),
    );
    let h = pd[2] + fmax(fmax(pa[2], pb[2]), pc[2]) + EPS * mm;
    let m2 = mm * mm;
    let hm = 4.0 * mm * h + 2.0 * h * h + 3.0 * EPS * m2;
    let hw = hm + 3.0 * EPS * m2;
    let bound = 2.0 * (3.0 * (2.0 * m2 * hm + (2.0 * m2 + hm) * hw) + 24.0 * EPS * m2 * m2);
    (det, bound)
}

/// Whether a determinant known to be within `err` of `f`, whose star image's determinant is
/// within `gerr` of `g`, is exactly zero by the norm argument.
///
/// Both determinants are `(sin 72°/2)·D` with `D ∈ Z[τ]` ([`crate::lattice::incircle`]), and
/// the star images' is `(sin 72°/2)·σ(D)/τ` up to sign (σ: τ ↦ −1/τ; the `2·Re` column
/// maps by σ, `Im/sin 72°` by σ then 1/τ, `|x|²` by σ). So `D·σ(D) = a² + ab − b²` for
/// `D = a + bτ` is an integer of absolute value `(4τ/sin²72°)·|f|·|g|` ≈ 7.16·|f|·|g|, at
/// least 1 unless `D = 0`: below 1 means zero. (8 for margin.)
#[inline]
fn norm_says_zero(f: f64, err: f64, g: f64, gerr: f64) -> bool {
    8.0 * (f.abs() + err) * (g.abs() + gerr) < 1.0
}

impl Store {
    pub(crate) fn push(&mut self, x: ZZeta, ext: u32) -> u32 {
        let c = cached(x);
        self.zz.push(x);
        self.xy.push(c);
        self.st.push(cached(x.star()));
        self.ext.push(ext);
        let grows = c[0] < self.lo[0]
            || c[1] < self.lo[1]
            || c[0] > self.hi[0]
            || c[1] > self.hi[1]
            || c[2] > self.hmax;
        if grows {
            for k in 0..2 {
                self.lo[k] = self.lo[k].min(c[k]);
                self.hi[k] = self.hi[k].max(c[k]);
            }
            self.hmax = self.hmax.max(c[2]);
            // Any computed difference of two coordinates is at most the box's side, which
            // its own rounding may understate by a relative 2^-53; the margin covers both.
            let mm = fmax(self.hi[0] - self.lo[0], self.hi[1] - self.lo[1]) * (1.0 + 1e-9);
            // The largest `h` of the bound: two cached errors and the rounding of a
            // difference.
            self.quick_orient = orient_err(mm, 2.0 * self.hmax + EPS * mm);
        }
        self.zz.len() as u32 - 1
    }

    fn reserve(&mut self, n: usize) {
        self.zz.reserve(n);
        self.xy.reserve(n);
        self.st.reserve(n);
        self.ext.reserve(n);
    }

    fn pop(&mut self) {
        self.zz.pop();
        self.xy.pop();
        self.st.pop();
        self.ext.pop();
    }

    fn len(&self) -> usize {
        self.zz.len()
    }

    /// Exact orientation of `a, b, c` (as [`crate::lattice::orient`]): decided from the
    /// cached positions unless they are within their error bound of collinear, then from
    /// the star images' ([`norm_says_zero`]), then exactly.
    #[inline(always)]
    pub(crate) fn orient(&self, a: u32, b: u32, c: u32) -> i32 {
        let [a, b, c] = [a, b, c].map(|i| i as usize);
        let (det, bound) = orient_f(self.xy[a], self.xy[b], self.xy[c]);
        if det.abs() > self.quick_orient {
            return if det > 0.0 { 1 } else { -1 };
        }
        if det > bound {
            1
        } else if det < -bound {
            -1
        } else {
            let (g, gb) = orient_f(self.st[a], self.st[b], self.st[c]);
            if norm_says_zero(det, bound, g, gb) {
                return 0;
            }
            orient_value(self.zz[a], self.zz[b], self.zz[c]).signum()
        }
    }

    /// Exact incircle test of `d` against `a, b, c` (as [`crate::lattice::incircle`]), decided
    /// like [`Store::orient`].
    #[inline]
    pub(crate) fn incircle(&self, a: u32, b: u32, c: u32, d: u32) -> i32 {
        let [a, b, c, d] = [a, b, c, d].map(|i| i as usize);
        let (det, bound) = incircle_f(self.xy[a], self.xy[b], self.xy[c], self.xy[d]);
        if det > bound {
            1
        } else if det < -bound {
            -1
        } else {
            let (g, gb) = incircle_f(self.st[a], self.st[b], self.st[c], self.st[d]);
            if norm_says_zero(det, bound, g, gb) {
                return 0;
            }
            let z = &self.zz;
            incircle_exact(z[a], z[b], z[c], z[d])
        }
    }
}

/// A uniform grid over the points' bounding box holding, per bucket, the last vertex
/// inserted there; a walk starts from a triangle of that vertex. Progressive sites are
/// spread over the whole image, so walking from the last insertion would cross O(√n)
/// triangles; from a vertex in the same bucket it crosses a few.
#[derive(Clone, Debug)]
struct Locator {
    origin: [f64; 2],
    inv: f64,
    side: usize,
    buckets: Vec<u32>,
    /// Vertex count the grid was sized for.
    sized_for: usize,
}

impl Locator {
    /// A grid of about two vertices per bucket.
    fn new(store: &Store) -> Locator {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for c in &store.xy {
            for k in 0..2 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        let side = ((store.len() as f64 / 2.0).sqrt()).clamp(1.0, 4096.0) as usize;
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        let mut l = Locator {
            origin: lo,
            inv: (side as f64 - 1e-9) / extent,
            side,
            buckets: vec![NONE; side * side],
            sized_for: store.len(),
        };
        for (v, &[x, y, _]) in store.xy.iter().enumerate() {
            let k = l.bucket([x, y]);
            l.buckets[k] = v as u32;
        }
        l
    }

    fn bucket(&self, p: [f64; 2]) -> usize {
        // Truncation is the floor here: below 0 the clamp gives 0 either way.
        let f = |k: usize| {
            let v = (p[k] - self.origin[k]) * self.inv;
            v.clamp(0.0, self.side as f64 - 1.0) as usize
        };
        f(1) * self.side + f(0)
    }

    /// A Morton (Z-order) key of `p` on a 2^16 × 2^16 grid over the box.
    fn morton(&self, p: [f64; 2]) -> u64 {
        let scale = self.inv * 65536.0 / self.side as f64;
        let q = |k: usize| ((p[k] - self.origin[k]) * scale).clamp(0.0, 65535.0) as u64;
        let spread = |mut v: u64| {
            v = (v | (v << 8)) & 0x00ff_00ff;
            v = (v | (v << 4)) & 0x0f0f_0f0f;
            v = (v | (v << 2)) & 0x3333_3333;
            (v | (v << 1)) & 0x5555_5555
        };
        spread(q(0)) | (spread(q(1)) << 1)
    }
}

/// Why a point could not be inserted locally (the caller rebuilds from scratch).
#[derive(Debug)]
pub(crate) struct Rebuild;

/// How many points of a progressive set `spade` bulk loads, at the least, before the rest
/// is inserted: a start of several collinear points, which has no triangle to insert into,
/// is `spade`'s to handle (more are bulk loaded if these have no triangle).
const SEED: usize = 64;

// `Cells`' builders over the exact triangulation (the type is in `cells.rs`, which does not
// import this module).
impl Cells {
    /// The canonical cells of `mesh`, whose vertex data index `lattice` (the exact point of
    /// every sample), made exact by sliver removal and Lawson flips. `None` if some vertex
    /// has no exact point, if an exact point is beyond [`crate::lattice::EXACT_LIMIT`], or if
    /// the triangulation is inconsistent with the exact points (then the caller keeps
    /// `mesh`'s own triangles).
    ///
    /// The codec builds the cells by [`Cells::incremental`] (and [`Cells::atlas`]); this
    /// builder, from a whole triangulation made independently of them, serves the tests and
    /// benches as a cross-check, and callers (the lab) that have a `spade` triangulation in
    /// hand.
    ///
    /// ```
    /// use qcs::lattice::ZZeta;
    /// use qcs::reconstruction::{Cells, SampleMesh, Vertex};
    /// use spade::{Point2, Triangulation as _};
    /// // The regular pentagon 1, ζ, …, ζ⁴ (unit roots, pixel = 10 + 5·x).
    /// let z = |k: usize| { let mut n = [0i64; 4]; if k < 4 { n[k] = 1 } else { n = [-1; 4] }; ZZeta::new(n) };
    /// let lattice: Vec<Option<ZZeta>> = (0..5).map(|k| Some(z(k))).collect();
    /// let mut mesh = SampleMesh::new();
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
    pub fn build(mesh: &SampleMesh, lattice: &[Option<ZZeta>]) -> Option<Cells> {
        Some(LiveCells::build(mesh, lattice)?.cells())
    }

    /// The canonical cells of the points `lattice` (exact points, at pixel `positions`), by
    /// exact insertion: `spade` bulk loads the first 64 points (or, while those are all
    /// collinear, twice as many, until they have a triangle or are all the points) and the
    /// others are inserted with exact predicates, in rounds of doubling size. This is how
    /// the codec builds the cells (a [`super::SampleSet`] keeps the structure to insert
    /// more points; [`Cells::atlas`] speeds up a final set). The same cells as
    /// [`Cells::build`] on `spade`'s whole triangulation, and faster on progressive sites
    /// (`benches/cells.rs`). Should the insertion give up (an inconsistency between
    /// `spade`'s start and the exact predicates, never observed), the cells are built once
    /// more from `spade`'s triangulation of all the points.
    ///
    /// `None` if a point has no exact point or is beyond [`crate::lattice::EXACT_LIMIT`]
    /// (or, defensively, if even that second build finds `spade`'s triangulation
    /// inconsistent). Fewer than three points, or all collinear, have no cells (empty).
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
}

/// The exact Delaunay triangulation behind the canonical cells, kept so that new points can
/// be inserted locally (streaming): only the edges of the triangles that changed are tested
/// for cocircularity again.
#[derive(Clone, Debug)]
pub(crate) struct LiveCells {
    store: Store,
    mesh: Mesh,
    /// Per triangle slot: whether the edge opposite vertex `i` joins two cocircular triangles.
    merge: Vec<[bool; 3]>,
    flips: usize,
    /// Points inserted so far (`0..points` of the lattice list).
    pub(crate) points: usize,
    /// Where to start locating a point.
    locator: Locator,
}

impl LiveCells {
    /// From any Delaunay triangulation of `lattice[0..n]` (`mesh` vertices index `lattice`).
    pub(crate) fn build(mesh: &SampleMesh, lattice: &[Option<ZZeta>]) -> Option<LiveCells> {
        let mut store = Store::default();
        // Point index → internal id.
        let mut int_of = vec![NONE; lattice.len()];
        for v in mesh.vertices() {
            let i = v.data().index;
            let x = lattice
                .get(i as usize)
                .copied()
                .flatten()
                .filter(|&x| within_exact_limit(x))?;
            int_of[i as usize] = store.push(x, i);
        }
        let mut m = Mesh::new(mesh, &int_of)?;
        m.remove_slivers(&store)?;
        let (flips, merge) = m.lawson(&store)?;
        m.index_vertices(store.len());
        let locator = Locator::new(&store);
        Some(LiveCells {
            store,
            mesh: m,
            merge,
            flips,
            points: lattice.len(),
            locator,
        })
    }

    /// For a whole progressive set (sample order, mirror points after their sample): the
    /// one builder of the cells ([`Cells::incremental`] says how). `None` if some point is
    /// not exact, or if both the insertion and the build from `spade`'s whole triangulation
    /// give up (defensive).
    pub(crate) fn grow(positions: &[Point], lattice: &[Option<ZZeta>]) -> Option<LiveCells> {
        let n = lattice.len().min(positions.len());
        let (positions, lattice) = (&positions[..n], &lattice[..n]);
        if !lattice.iter().all(|x| x.is_some_and(within_exact_limit)) {
            return None;
        }
        LiveCells::seeded(positions, lattice).or_else(|| LiveCells::whole(positions, lattice))
    }

    /// `spade` bulk loads the first [`SEED`] points, or twice as many while they have no
    /// triangle and more follow; the rest are inserted. A start of exactly collinear points
    /// has no triangle whether `spade` finds none or finds slivers (its `f64` positions
    /// rounded off the line), which [`LiveCells::build`] drops. `None` if the insertion
    /// gives up.
    fn seeded(positions: &[Point], lattice: &[Option<ZZeta>]) -> Option<LiveCells> {
        let n = lattice.len();
        let mut seed = n.min(SEED);
        loop {
            let mut mesh = SampleMesh::new();
            mesh::sync(&mut mesh, &positions[..seed], &mut 0);
            let mut live = LiveCells::build(&mesh, &lattice[..seed])?;
            if seed < n && !live.mesh.alive.contains(&true) {
                seed = n.min(2 * seed);
                continue;
            }
            live.extend(lattice).ok()?;
            return Some(live);
        }
    }

    /// From `spade`'s triangulation of all the points.
    fn whole(positions: &[Point], lattice: &[Option<ZZeta>]) -> Option<LiveCells> {
        let mut mesh = SampleMesh::new();
        mesh::sync(&mut mesh, positions, &mut 0);
        LiveCells::build(&mesh, lattice)
    }

    /// The cells as they are now.
    pub(crate) fn cells(&self) -> Cells {
        self.mesh.cells(&self.store, self.flips, &self.merge)
    }

    /// Inserts points `self.points..lattice.len()`. On [`Rebuild`] (a point that is not exact,
    /// or anything unexpected) the state is unusable and the caller builds afresh.
    pub(crate) fn extend(&mut self, lattice: &[Option<ZZeta>]) -> Result<(), Rebuild> {
        let new = lattice.len().saturating_sub(self.points);
        // Which triangles an insertion made or rewrote (by triangle id).
        let mut touched = vec![false; self.mesh.tri.len()];
        let mut stack = Vec::new();
        let mut round: Vec<u64> = Vec::new();
        self.store.reserve(new);
        self.mesh.reserve(2 * new);
        self.mesh.vtri.reserve(new);
        self.merge.reserve(2 * new);
        let mut lo = self.points;
        while lo < lattice.len() {
            let hi = lattice.len().min(2 * lo).max(lo + 1);
            round.clear();
            for (i, x) in lattice.iter().enumerate().take(hi).skip(lo) {
                let x = x.filter(|&x| within_exact_limit(x)).ok_or(Rebuild)?;
                let (re, im) = x.to_f64();
                round.push(self.locator.morton([re, im]) << 32 | i as u64);
            }
            round.sort_unstable();
            for &key in &round {
                let i = key as u32;
                if let Some(x) = lattice[i as usize] {
                    self.insert(i, x, &mut touched, &mut stack)?;
                }
            }
            if self.store.len() > 2 * self.locator.sized_for {
                self.locator = Locator::new(&self.store);
            }
            lo = hi;
        }
        self.points = lattice.len();
        // Cocircularity of every edge of a triangle that changed.
        let mut mark = touched;
        mark.resize(self.mesh.tri.len(), false);
        for t in 0..mark.len() {
            if !mark[t] {
                continue;
            }
            let v = self.mesh.tri[t];
            for i in 0..3 {
                let u = self.mesh.nbr[t][i] as usize;
                if u < t && mark[u] {
                    continue; // tested from `u`
                }
                let Some((j, d)) = self.mesh.across(t, i) else {
                    self.merge[t][i] = false;
                    continue;
                };
                let cocircular = self.store.incircle(v[0], v[1], v[2], d) == 0;
                self.merge[t][i] = cocircular;
                self.merge[u][j] = cocircular;
            }
        }
        Ok(())
    }

    /// Inserts point `i` at `x`: locate, split, flip.
    /// `stack` is scratch space (the edges left to test), kept from one insertion to the next.
    fn insert(
        &mut self,
        i: u32,
        x: ZZeta,
        touched: &mut Vec<bool>,
        stack: &mut Vec<(u32, u8)>,
    ) -> Result<(), Rebuild> {
        let p = self.store.push(x, i);
        let (m, s) = (&mut self.mesh, &self.store);
        // Visibility walk from a triangle of a vertex near the point.
        let [x0, y0, _] = s.xy[p as usize];
        let b = self.locator.bucket([x0, y0]);
        let mut t = match self.locator.buckets[b] {
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
        // The three orientations of the point against `t`'s edges, or `Err(k)`: outside the
        // hull, beyond `t`'s hull edge opposite vertex `k`.
        // The edge the walk came in through is known: the point is strictly inside it.
        let mut from = NONE;
        let side = 'walk: loop {
            let v = m.tri[t];
            let mut o = [1; 3];
            for k in 0..3 {
                let u = m.nbr[t][k];
                if u == from && u != NONE {
                    continue;
                }
                o[k] = s.orient(v[(k + 1) % 3], v[(k + 2) % 3], p);
                if o[k] < 0 {
                    if u == NONE {
                        break 'walk Err(k);
                    }
                    (from, t) = (t as u32, u as usize);
                    steps += 1;
                    if steps > m.tri.len() + 8 {
                        return Err(Rebuild);
                    }
                    continue 'walk;
                }
            }
            break Ok(o);
        };
        stack.clear();
        // How many of the orientations are zero, and the slot of the first zero (or the
        // hull edge the point is beyond).
        let (zeros, k) = match side {
            Err(k) => (None, k),
            Ok(o) => (
                Some(o.iter().filter(|&&o| o == 0).count()),
                (0..3).find(|&k| o[k] == 0).unwrap_or(0),
            ),
        };
        match zeros {
            None => {
                let first = m.tri.len() as u32;
                m.attach(s, t as u32, k, p)?;
                // Each new triangle is [w, u, p] on an old hull edge u → w.
                stack.extend((first..m.tri.len() as u32).map(|t| (t, 2)));
            }
            Some(1) if m.nbr[t][k] == NONE => {
                // On a hull edge (opposite vertex k of t): split t in two.
                let (a, b, c) = (m.tri[t][k], m.tri[t][(k + 1) % 3], m.tri[t][(k + 2) % 3]);
                let (t_ab, t_ca) = (m.nbr[t][(k + 2) % 3], m.nbr[t][(k + 1) % 3]);
                let (t1, t2) = (t as u32, m.tri.len() as u32);
                m.tri[t] = [a, b, p];
                m.nbr[t] = [NONE, t2, t_ab];
                m.push([a, p, c], [NONE, t_ca, t1]);
                m.relink(t_ca, t1, t2);
                stack.extend([(t1, 2), (t2, 1)]);
            }
            Some(0) => {
                let [a, b, c] = m.tri[t];
                let [na, nb, nc] = m.nbr[t];
                let (t1, t2, t3) = (t as u32, m.tri.len() as u32, m.tri.len() as u32 + 1);
                m.tri[t] = [b, c, p];
                m.nbr[t] = [t2, t3, na];
                m.push([c, a, p], [t3, t1, nb]);
                m.push([a, b, p], [t1, t2, nc]);
                m.relink(nb, t1, t2);
                m.relink(nc, t1, t3);
                stack.extend([(t1, 2), (t2, 2), (t3, 2)]);
            }
            Some(1) => {
                // On the edge opposite vertex k of t: split t and its neighbour into four.
                let Some((j, _)) = m.across(t, k) else {
                    return Err(Rebuild);
                };
                let u = m.nbr[t][k] as usize;
                let (a, b, c) = (m.tri[t][k], m.tri[t][(k + 1) % 3], m.tri[t][(k + 2) % 3]);
                let d = m.tri[u][j];
                let (t_ab, t_ca) = (m.nbr[t][(k + 2) % 3], m.nbr[t][(k + 1) % 3]);
                let (u_dc, u_bd) = (m.nbr[u][(j + 2) % 3], m.nbr[u][(j + 1) % 3]);
                let (t1, u1) = (t as u32, u as u32);
                let (t2, u2) = (m.tri.len() as u32, m.tri.len() as u32 + 1);
                m.tri[t] = [a, b, p];
                m.nbr[t] = [u2, t2, t_ab];
                m.tri[u] = [d, c, p];
                m.nbr[u] = [t2, u2, u_dc];
                m.push([a, p, c], [u1, t_ca, t1]);
                m.push([d, p, b], [t1, u_bd, u1]);
                m.relink(t_ca, t1, t2);
                m.relink(u_bd, u1, u2);
                stack.extend([(t1, 2), (t2, 1), (u1, 2), (u2, 1)]);
            }
            Some(_) => {
                // On a vertex: the same point again (the first is kept).
                let same = m.tri[t].iter().any(|&v| s.zz[v as usize] == x);
                self.store.pop();
                return if same { Ok(()) } else { Err(Rebuild) };
            }
        }
        // The triangles made or rewritten (each on the stack with its edge facing away from
        // the new point): no merge flag yet, cocircularity to be tested again.
        self.merge.resize(m.tri.len(), [false; 3]);
        touched.resize(m.tri.len(), false);
        for &(t, _) in stack.iter() {
            self.merge[t as usize] = [false; 3];
            touched[t as usize] = true;
        }
        // Every triangle on the stack has p, and keeps it through the flips below.
        if let Some(&(t, _)) = stack.first() {
            m.hint(p, t);
        }
        self.locator.buckets[b] = p;
        // Lawson flips around the new point.
        let budget = 8 * m.tri.len() + 64;
        let mut flips = 0usize;
        while let Some((t, e)) = stack.pop() {
            let (t, e) = (t as usize, e as usize);
            let Some((_, d)) = m.across(t, e) else {
                continue;
            };
            let v = m.tri[t];
            if s.incircle(v[0], v[1], v[2], d) <= 0 {
                continue;
            }
            let (a, b, c) = (v[e], v[(e + 1) % 3], v[(e + 2) % 3]);
            if s.orient(a, b, d) <= 0 || s.orient(a, d, c) <= 0 {
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
            touched[t1 as usize] = true;
            touched[t2 as usize] = true;
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
    /// Per vertex: a triangle that had it when it was recorded, or `NONE`. A walk may start
    /// anywhere (it checks that the triangle is alive); one near the point is quicker.
    vtri: Vec<u32>,
}

impl Mesh {
    /// Triangles and adjacency from `spade` (inner face `k` has index `k + 1` there), with
    /// vertices renamed by `int_of`.
    fn new(mesh: &SampleMesh, int_of: &[u32]) -> Option<Mesh> {
        let n = mesh.num_inner_faces();
        let mut tri = vec![[0u32; 3]; n];
        let mut nbr = vec![[NONE; 3]; n];
        for f in mesh.inner_faces() {
            let t = f.fix().index().checked_sub(1).filter(|&t| t < n)?;
            let vs = f.vertices().map(|v| v.fix());
            tri[t] = vs.map(|v| int_of[mesh.vertex(v).data().index as usize]);
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
        Some(Mesh {
            tri,
            nbr,
            alive: vec![true; n],
            vtri: Vec::new(),
        })
    }

    fn reserve(&mut self, triangles: usize) {
        self.tri.reserve(triangles);
        self.nbr.reserve(triangles);
        self.alive.reserve(triangles);
    }

    /// Recomputes [`Mesh::vtri`] from the live triangles.
    fn index_vertices(&mut self, vertices: usize) {
        self.vtri = vec![NONE; vertices];
        for t in 0..self.tri.len() {
            if self.alive[t] {
                for v in self.tri[t] {
                    self.hint(v, t as u32);
                }
            }
        }
    }

    /// Records `t`, a triangle that has vertex `v` now, as where to start a walk near `v`.
    fn hint(&mut self, v: u32, t: u32) {
        let v = v as usize;
        if v >= self.vtri.len() {
            self.vtri.resize(v + 1, NONE);
        }
        self.vtri[v] = t;
    }

    /// The hull edge next to the hull edge opposite vertex `k` of `t`, counter-clockwise
    /// around the hull (`forward`) or clockwise, as (triangle, slot): found by turning
    /// around their shared vertex (the edge's end `b`, or its start `a`). The edge leaving
    /// `b` is opposite the vertex before `b`; the edge arriving at `a`, the vertex after `a`.
    fn hull_next(&self, mut t: usize, k: usize, forward: bool) -> Option<(usize, usize)> {
        let s = if forward { 2 } else { 1 };
        let pivot = self.tri[t][(k + s) % 3];
        for _ in 0..self.tri.len() {
            let i = self.tri[t].iter().position(|&v| v == pivot)?;
            let slot = (i + s) % 3;
            match self.nbr[t][slot] {
                NONE => return Some((t, slot)),
                u => t = u as usize,
            }
        }
        None
    }

    /// Joins `p`, outside the hull beyond the hull edge opposite vertex `k` of `t`, to every
    /// hull edge it strictly sees (a contiguous chain): one new triangle `[w, u, p]` per edge
    /// `u → w`, appended in hull order.
    fn attach(&mut self, s: &Store, t: u32, k: usize, p: u32) -> Result<(), Rebuild> {
        let tri = &self.tri;
        let ends = |(t, k): (usize, usize)| (tri[t][(k + 1) % 3], tri[t][(k + 2) % 3]);
        let sees = |e: (usize, usize)| {
            let (u, w) = ends(e);
            s.orient(u, w, p) < 0
        };
        let start = (t as usize, k);
        let mut chain = vec![start];
        let mut e = start;
        while let Some(f) = self
            .hull_next(e.0, e.1, false)
            .filter(|&f| f != start && sees(f))
        {
            chain.push(f);
            e = f;
        }
        chain.reverse();
        let mut e = start;
        // The chain is contiguous: going forward it can only wrap into its first edge.
        let first = chain[0];
        while let Some(f) = self
            .hull_next(e.0, e.1, true)
            .filter(|&f| f != first && sees(f))
        {
            chain.push(f);
            e = f;
        }
        if chain.len() > self.tri.len() {
            return Err(Rebuild);
        }
        let chain: Vec<(usize, usize, u32, u32)> = chain
            .into_iter()
            .map(|(t, k)| {
                let (u, w) = ends((t, k));
                (t, k, u, w)
            })
            .collect();
        let id0 = self.tri.len() as u32;
        for (n, &(t, k, u, w)) in chain.iter().enumerate() {
            let id = id0 + n as u32;
            let prev = if n == 0 { NONE } else { id - 1 };
            let next = if n + 1 == chain.len() { NONE } else { id + 1 };
            // Opposite w: u → p (shared with the previous new triangle); opposite u:
            // p → w (with the next); opposite p: the old hull edge.
            self.push([w, u, p], [prev, next, t as u32]);
            self.nbr[t][k] = id;
        }
        Ok(())
    }

    /// Appends a triangle.
    fn push(&mut self, tri: [u32; 3], nbr: [u32; 3]) {
        self.tri.push(tri);
        self.nbr.push(nbr);
        self.alive.push(true);
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
        Some((t, u))
    }

    /// Removes exactly degenerate triangles (collinear sites the `f64` positions showed as a
    /// sliver): flips the long edge into the neighbour behind it, or drops a sliver whose
    /// long edge is on the hull.
    fn remove_slivers(&mut self, s: &Store) -> Option<()> {
        let mut budget = 4 * self.tri.len() + 16;
        let mut stack: Vec<u32> = (0..self.tri.len() as u32).collect();
        while let Some(t) = stack.pop() {
            if !self.alive[t as usize] {
                continue;
            }
            let v = self.tri[t as usize];
            match s.orient(v[0], v[1], v[2]) {
                1 => continue,
                -1 => return None,
                _ => {}
            }
            budget = budget.checked_sub(1)?;
            // The middle vertex is opposite the longest edge.
            let l2 = |i: usize| {
                let (p, q) = (
                    s.zz[v[(i + 1) % 3] as usize].0,
                    s.zz[v[(i + 2) % 3] as usize].0,
                );
                ZZeta([p[0] - q[0], p[1] - q[1], p[2] - q[2], p[3] - q[3]]).norm2()
            };
            let i = (0..3).max_by(|&x, &y| l2(x).cmp(&l2(y)))?;
            let u = self.nbr[t as usize][i];
            if u == NONE {
                self.alive[t as usize] = false;
                for n in self.nbr[t as usize] {
                    self.relink(n, t, NONE);
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
    fn lawson(&mut self, s: &Store) -> Option<(usize, Vec<[bool; 3]>)> {
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
            let (a, b, c) = (v[i], v[(i + 1) % 3], v[(i + 2) % 3]);
            let sign = s.incircle(v[0], v[1], v[2], d);
            merge[t][i] = sign == 0;
            merge[u as usize][j] = sign == 0;
            if sign <= 0 {
                continue;
            }
            // Strictly inside the circle and on the far side: the quad is convex.
            if s.orient(a, b, d) <= 0 || s.orient(a, d, c) <= 0 {
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

    /// Lists the cells: triangles joined across exactly cocircular edges (`merge`), each
    /// counter-clockwise from its smallest lattice point, as point indices.
    fn cells(&self, s: &Store, flips: usize, merge: &[[bool; 3]]) -> Cells {
        let pt = |v: u32| s.zz[v as usize];
        let ext = |v: u32| s.ext[v as usize];
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
                let k = (0..3).min_by_key(|&k| pt(v[k])).unwrap_or(0);
                vertices.extend([v[k], v[(k + 1) % 3], v[(k + 2) % 3]].map(ext));
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
                vertices.push(ext(cur));
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
        let hull = hull.into_iter().map(|e| e.map(ext)).collect();
        Cells::from_parts(offsets, vertices, hull, flips)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::{incircle, orient};
    use crate::sites::Quasicrystal;
    use proptest::prelude::*;

    /// `x·ζ`.
    fn turn(x: ZZeta) -> ZZeta {
        let [a, b, c, d] = x.0;
        ZZeta([-d, a - d, b - d, c - d])
    }

    /// `m·x`.
    fn times(m: i64, x: ZZeta) -> ZZeta {
        ZZeta(x.0.map(|n| m * n))
    }

    /// `x + y`.
    fn plus(x: ZZeta, y: ZZeta) -> ZZeta {
        ZZeta([0, 1, 2, 3].map(|k| x.0[k] + y.0[k]))
    }

    /// A degenerate start of about `len` points from `base` along `dir`, by `kind`: 0, on one
    /// line (in a scrambled order, with repeats if `len` is a multiple of 37); 1, on concentric
    /// regular pentagons about `base` (each ring cocircular); 2, pairs mirrored about the
    /// real axis (isosceles trapezoids, cocircular); then the `rest`.
    fn degenerate(kind: u8, len: usize, base: ZZeta, dir: ZZeta, rest: &[ZZeta]) -> Vec<ZZeta> {
        let mut v: Vec<ZZeta> = match kind {
            0 => (0..len)
                .map(|k| plus(base, times((k * 37 % len) as i64, dir)))
                .collect(),
            1 => (1..=len.div_ceil(5) as i64)
                .flat_map(|r| {
                    let mut w = times(r, dir);
                    (0..5).map(move |_| {
                        w = turn(w);
                        plus(base, w)
                    })
                })
                .collect(),
            _ => (0..len.div_ceil(2) as i64)
                .flat_map(|m| {
                    let [a, b, c, d] = plus(base, times(m, dir)).0;
                    [ZZeta([a, b, c, d]), ZZeta([a - b, -b, d - b, c - b])]
                })
                .collect(),
        };
        v.extend_from_slice(rest);
        v
    }

    /// Exact insertion against `spade`'s whole triangulation made exact (the retry, and
    /// [`Cells::build`]): the same cells and hull, and the insertion gives no occasion to
    /// retry.
    fn insertion_matches_whole(zz: &[ZZeta]) -> Result<(), TestCaseError> {
        let positions: Vec<Point> = zz
            .iter()
            .map(|x| x.to_f64())
            .map(|(re, im)| [500.0 + 10.0 * re, 500.0 + 10.0 * im])
            .collect();
        let lattice: Vec<Option<ZZeta>> = zz.iter().copied().map(Some).collect();
        let whole = LiveCells::whole(&positions, &lattice).map(|l| l.cells());
        let seeded = LiveCells::seeded(&positions, &lattice).map(|l| l.cells());
        let key = |c: Cells| {
            let mut v: Vec<Vec<u32>> = c.iter().map(<[u32]>::to_vec).collect();
            v.sort();
            (v, c.hull().to_vec())
        };
        prop_assert!(seeded.is_some(), "insertion gave up");
        prop_assert_eq!(seeded.map(key), whole.map(key));
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn insertion_equals_whole_triangulation_from_degenerate_starts(
            kind in 0u8..3,
            len in 1usize..400,
            base in proptest::array::uniform4(-20i64..20),
            dir in proptest::array::uniform4(-2i64..3),
            rest in proptest::collection::vec(proptest::array::uniform4(-8i64..8), 0..150),
        ) {
            let dir = ZZeta::new(dir);
            prop_assume!(dir != ZZeta::new([0; 4]));
            let rest: Vec<ZZeta> = rest.into_iter().map(ZZeta::new).collect();
            insertion_matches_whole(&degenerate(kind, len, ZZeta::new(base), dir, &rest))?;
        }
    }

    /// Points on a hull edge, beyond a hull edge's line, and outside seeing a straight run
    /// of collinear hull sites: the same cells as spade's triangulation repaired.
    #[test]
    fn hull_edge_and_outside_insertions() {
        let z = |n: [i64; 4]| Some(ZZeta::new(n));
        // 0, 4 and 4ζ; then 2, 1, 3 on the hull edge 0 → 4; 6 beyond it on its line;
        // 2 + 3ζ³ below the real axis (outside, seeing the whole collinear run 0 … 6); 5ζ²
        // on the other side.
        let lattice = [
            z([0, 0, 0, 0]),
            z([4, 0, 0, 0]),
            z([0, 4, 0, 0]),
            z([2, 0, 0, 0]),
            z([1, 0, 0, 0]),
            z([3, 0, 0, 0]),
            z([6, 0, 0, 0]),
            z([2, 0, 0, 3]),
            z([0, 0, 5, 0]),
        ];
        let positions: Vec<Point> = lattice
            .iter()
            .map(|x| {
                let (re, im) = x.unwrap().to_f64();
                [100.0 + 10.0 * re, 100.0 + 10.0 * im]
            })
            .collect();
        let mut seed = SampleMesh::new();
        mesh::sync(&mut seed, &positions[..3], &mut 0);
        let mut live = LiveCells::build(&seed, &lattice[..3]).unwrap();
        for n in 4..=lattice.len() {
            live.extend(&lattice[..n]).unwrap();
            let mut all = SampleMesh::new();
            mesh::sync(&mut all, &positions[..n], &mut 0);
            let sorted = |c: &Cells| {
                let mut v: Vec<Vec<u32>> = c.iter().map(<[u32]>::to_vec).collect();
                v.sort();
                (v, c.hull().to_vec())
            };
            let expected = LiveCells::build(&all, &lattice[..n]).unwrap().cells();
            assert_eq!(sorted(&live.cells()), sorted(&expected), "{n} points");
        }
    }

    /// The norm identity behind [`norm_says_zero`]: for `D = a + bτ`, the determinants of
    /// the points and of their star images multiply to `(sin²72°/4τ)·|a² + ab − b²|`.
    #[test]
    fn star_determinants_multiply_to_the_norm() {
        use crate::lattice::{incircle_value, orient_value, SIN72, TAU};
        let mut next = crate::testing::xorshift(99);
        let mut rnd = || (next() % 13) as i64 - 6;
        let k = 4.0 * TAU / (SIN72 * SIN72);
        let norm = |d: crate::lattice::ZTau| (d.a * d.a + d.a * d.b - d.b * d.b).abs() as f64;
        let mut nonzero = 0;
        for _ in 0..5000 {
            let p: Vec<ZZeta> = (0..4)
                .map(|_| ZZeta::new([rnd(), rnd(), rnd(), rnd()]))
                .collect();
            let (x, y) = (
                p.iter().map(|&q| cached(q)),
                p.iter().map(|&q| cached(q.star())),
            );
            let (x, y): (Vec<_>, Vec<_>) = (x.collect(), y.collect());
            let (f, _) = orient_f(x[0], x[1], x[2]);
            let (g, _) = orient_f(y[0], y[1], y[2]);
            let n = norm(orient_value(p[0], p[1], p[2]));
            assert!(
                (k * (f * g).abs() - n).abs() < 1e-6 * (1.0 + n),
                "orient {n}"
            );
            let (f, _) = incircle_f(x[0], x[1], x[2], x[3]);
            let (g, _) = incircle_f(y[0], y[1], y[2], y[3]);
            let n = norm(incircle_value(p[0], p[1], p[2], p[3]));
            assert!(
                (k * (f * g).abs() - n).abs() < 1e-6 * (1.0 + n),
                "incircle {n}"
            );
            nonzero += (n > 0.0) as usize;
        }
        assert!(nonzero > 4000);
    }

    /// The filtered predicates agree with the exact ones on every triangle and every
    /// neighbour quadruple of real site sets, which are full of exact zeros.
    #[test]
    fn filtered_predicates_match_exact() {
        for (w, h, n) in [(64, 48, 500), (1024, 1024, 3000), (3000, 7, 900)] {
            let sites = Quasicrystal::new(w, h).unwrap().first(n);
            let mut s = Store::default();
            for (k, x) in sites.iter().enumerate() {
                s.push(x.lattice, k as u32);
            }
            let z = |i: u32| s.zz[i as usize];
            let mut zeros = [0usize; 2];
            let mut next = crate::testing::xorshift(12345);
            let mut rnd = |m: usize| (next() % m as u64) as u32;
            for a in 0..n as u32 {
                // Four points near each other: `a` and three of its 8 nearest.
                let pa = s.xy[a as usize];
                let d2 = |i: &u32| {
                    let p = s.xy[*i as usize];
                    (p[0] - pa[0]).powi(2) + (p[1] - pa[1]).powi(2)
                };
                let mut near: Vec<u32> = (0..n as u32).collect();
                near.sort_by(|x, y| d2(x).total_cmp(&d2(y)));
                for _ in 0..10 {
                    let [b, c, d] = [0; 3].map(|_| near[1 + rnd(8) as usize]);
                    let o = s.orient(a, b, c);
                    assert_eq!(o, orient(z(a), z(b), z(c)));
                    let i = s.incircle(a, b, c, d);
                    assert_eq!(i, incircle(z(a), z(b), z(c), z(d)));
                    zeros[0] += (o == 0) as usize;
                    zeros[1] += (i == 0) as usize;
                }
            }
            assert!(zeros[1] > 100, "{zeros:?}: exact zeros must be exercised");
        }
    }
}
