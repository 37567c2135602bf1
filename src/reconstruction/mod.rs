//! Samples → picture, at any output size and from any prefix.
//!
//! # Coordinates
//!
//! Sample positions are in source pixels: pixel `(i, j)` covers `[i, i+1) × [j, j+1)` and its
//! centre is `(i + 0.5, j + 0.5)`. A render at `w × h` from a `W × H` source samples the output
//! pixel centres; source coordinates map to output ones by `x · w / W`, `y · h / H`. Every
//! method defines one continuous picture on the source plane and samples it, so all output
//! sizes show the same picture: Gouraud (affine-invariant) is rasterised in output pixels, as
//! are the cubic patches (their vertex gradients estimated in source pixels), and
//! Shepard and natural-neighbour weights, like the outside-the-hull rule, are computed at the
//! output pixel centre mapped back to source pixels.
//!
//! # Mirror points
//!
//! Gouraud, cubic and natural neighbour triangulate the samples together with their **mirror
//! points**: each sample near an image edge, reflected across it, carrying its colour (see
//! the `mirror` module and `spec/reconstruction.md` §2). The picture is then as well shaped
//! at the edges as inside, and gets better, not worse, as samples arrive there.
//!
//! # Outside the convex hull
//!
//! Gouraud, cubic and natural neighbour are only defined inside the convex hull of the samples
//! and their mirror points, which covers the image from the first sample on (its mirror points
//! surround it) unless the samples are outside the image. A pixel centre outside it takes
//! the colour of the **nearest point of the hull boundary** (distance in source pixels),
//! colours being linear along each hull edge between its two end samples. This continues the interpolation without a seam and leaves no black border. With
//! one sample the whole picture takes its colour; with two (or all collinear) the boundary is
//! the polyline through them. With no sample every pixel is mid-grey (128).
//!
//! # Rounding
//!
//! Every channel is rounded to nearest (halves up) and clamped to 0..=255.
//!
//! ```
//! use qcs::reconstruction::{render, Method};
//! // Three samples of a 4 × 4 source, rendered at 8 × 8.
//! let pos = [[0.5, 0.5], [3.5, 0.5], [0.5, 3.5]];
//! let col = [0u8, 90, 30];
//! let img = render((4, 4), 1, &pos, &col, Method::Gouraud, 8, 8);
//! assert_eq!(img.len(), 64);
//! assert_eq!(img[0], 0); // pixel centre (0.25, 0.25): near sample 0, between its mirror points
//! ```

// Per-channel loops over fixed-size colour arrays read best with indices.
#![allow(clippy::needless_range_loop)]

mod atlas;
mod cells;
mod cubic;
mod delaunay;
mod gouraud;
mod hull;
mod mesh;
mod mirror;
mod natural;
mod raster;
mod shepard;

use rayon::prelude::*;
use spade::Triangulation as _;

use crate::lattice::ZZeta;
use crate::sites::{Frame as LatticeFrame, Point};

pub use cells::Cells;
use delaunay::LiveCells;
pub use gouraud::{cell_triangles, triangles};
pub use mesh::{SampleMesh, Vertex};
#[doc(hidden)]
pub use raster::raster_coverage;
pub use raster::{rasterise, RasterTriangle, RasterVertex};
pub use shepard::SampleGrid;

use hull::Boundary;

/// The mirror images of a set of `positions` in a `width × height` source, as a decode
/// triangulates them (the module's *Mirror points*) once all of them have arrived, for a
/// drawing that should run off the edges rather than stop at the samples' hull (the stylized
/// renderings): each as the index of the sample it reflects, its position and, with
/// `exact`'s lattice points and frame, its own lattice point.
///
/// ```
/// use qcs::sites::Quasicrystal;
/// let sites = Quasicrystal::new(96, 64)?.first(500);
/// let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
/// let images = qcs::reconstruction::mirror_images(&pos, None, 96, 64);
/// // Reflected across the left edge: the same height, the other side of x = 0.
/// assert!(images.iter().any(|&(k, p, _)| p[0] < 0.0 && p[0] == -pos[k][0] && p[1] == pos[k][1]));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn mirror_images(
    positions: &[Point],
    exact: Option<(&[ZZeta], LatticeFrame)>,
    width: u32,
    height: u32,
) -> Vec<(usize, Point, Option<ZZeta>)> {
    let last = positions.len().saturating_sub(1);
    let lines = exact.map(|(_, frame)| Lines::new(frame, width, height));
    let mut out = Vec::new();
    for (k, &p) in positions.iter().enumerate() {
        let x = lines.as_ref().zip(exact).map(|(l, (lattice, _))| (l, lattice[k]));
        mirror_points(last, p, width, height, x, |q, z| out.push((k, q, z)));
    }
    out
}
use mirror::{mirror_points, Lines};
use raster::Band;

/// How a picture is rebuilt from its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Linear interpolation over the Delaunay triangulation.
    Gouraud,
    /// Inverse-distance weighting of the 4 nearest samples (power 2).
    Shepard,
    /// Sibson natural-neighbour interpolation.
    Natural,
    /// Cubic Bézier patches over Gouraud's triangles, from the vertex colours and gradients
    /// estimated at the vertices: smoother than Gouraud, and a little closer to the source.
    Cubic,
}

/// Options of [`SampleSet::render_with`] and [`render_with`].
///
/// ```
/// use qcs::reconstruction::RenderOptions;
/// let single = RenderOptions::default().with_parallel(false);
/// assert!(RenderOptions::default().parallel && !single.parallel);
/// assert_eq!(single, RenderOptions::single_threaded());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub struct RenderOptions {
    /// Split the output into bands of rows rendered on the `rayon` thread pool (default true).
    /// The picture is the same either way.
    pub parallel: bool,
}

impl RenderOptions {
    /// The options with `parallel` set.
    pub fn with_parallel(mut self, parallel: bool) -> Self {
        self.parallel = parallel;
        self
    }

    /// Default options on the calling thread only.
    pub fn single_threaded() -> Self {
        RenderOptions::default().with_parallel(false)
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions { parallel: true }
    }
}

/// The points a [`SampleSet`] triangulates: its samples and their mirror points, each with
/// the colour it carries and its lattice point if it has one.
#[derive(Clone, Debug, Default)]
struct Points {
    positions: Vec<Point>,
    colours: Vec<u8>,
    lattice: Vec<Option<ZZeta>>,
    exact: usize,
}

impl Points {
    fn push(&mut self, p: Point, lattice: Option<ZZeta>, colour: &[u8]) {
        self.positions.push(p);
        self.colours.extend_from_slice(colour);
        self.exact += lattice.is_some() as usize;
        self.lattice.push(lattice);
    }

    fn reserve(&mut self, n: usize, channels: usize) {
        self.positions.reserve_exact(n);
        self.colours.reserve_exact(n * channels);
        self.lattice.reserve_exact(n);
    }
}

/// A growing set of samples of one source image.
///
/// Samples are pushed a few at a time (as a streaming decoder reads them) and the set can be
/// rendered in between. The Delaunay triangulation is kept and the new samples are inserted
/// lazily at the next render (an empty triangulation is bulk loaded); the Shepard grid is
/// rebuilt only when samples were added since the last Shepard render.
///
/// Samples pushed with their exact lattice point ([`SampleSet::push_exact`]) are drawn by
/// Gouraud over the canonical Delaunay cells ([`Cells`], `spec/reconstruction.md`), so the
/// picture depends on the set of samples only, not on the order they were pushed in nor on
/// how the triangulation was built. If any sample lacks an exact point, `spade`'s own
/// triangles are drawn.
///
/// ```
/// use qcs::reconstruction::{Method, SampleSet};
/// let mut set = SampleSet::new(16, 16, 3);
/// assert_eq!(set.render(Method::Gouraud, 2, 2), vec![128; 12]); // no sample: mid-grey
/// set.push([4.0, 4.0], &[200, 100, 0]);
/// assert_eq!(set.render(Method::Shepard, 2, 2), [200, 100, 0].repeat(4)); // one: its colour
/// set.push([12.0, 4.0], &[200, 100, 0]);
/// set.push([8.0, 12.0], &[200, 100, 0]);
/// assert_eq!(set.len(), 3);
/// assert_eq!(set.render(Method::Natural, 3, 3), [200, 100, 0].repeat(9));
/// ```
#[derive(Clone, Debug)]
pub struct SampleSet {
    width: u32,
    height: u32,
    channels: usize,
    positions: Vec<Point>,
    colours: Vec<u8>,
    /// The lattice mirror lines of the frame exact samples are in.
    lines: Lines,
    /// The triangulated points: every sample, each followed by its mirror points.
    points: Points,
    /// The index in `points` of each sample.
    starts: Vec<usize>,
    mesh: SampleMesh,
    synced: usize,
    grid: Option<SampleGrid>,
    /// The exact triangulation behind the cells, updated locally as points arrive.
    live: Option<LiveCells>,
    /// How many times it was built from scratch.
    rebuilds: usize,
    /// Canonical cells and the point count they were computed for.
    cells: Option<(usize, Option<Cells>)>,
}

impl SampleSet {
    /// An empty set for a `source_width × source_height` source with `channels` bytes per colour
    /// (1..=4; other values are clamped into that range).
    ///
    /// Exact samples ([`SampleSet::push_exact`]) are taken to be in the default frame
    /// ([`LatticeFrame::default_for`]); see [`SampleSet::with_frame`] for another.
    pub fn new(source_width: u32, source_height: u32, channels: usize) -> Self {
        let frame = LatticeFrame::default_for(source_width, source_height);
        SampleSet {
            width: source_width,
            height: source_height,
            channels: channels.clamp(1, 4),
            positions: Vec::new(),
            colours: Vec::new(),
            lines: Lines::new(frame, source_width, source_height),
            points: Points::default(),
            starts: Vec::new(),
            mesh: SampleMesh::new(),
            synced: 0,
            grid: None,
            live: None,
            rebuilds: 0,
            cells: None,
        }
    }

    /// The same empty set with exact samples in the lattice frame `frame` (the frame of the
    /// file's sites, [`crate::sites::Quasicrystal::frame`]). It decides where the mirror
    /// points of exact samples are (`spec/reconstruction.md`).
    ///
    /// ```
    /// use qcs::reconstruction::SampleSet;
    /// use qcs::sites::{Frame, Quasicrystal};
    /// let frame = Frame { root_len: 3 << 15, origin: [-5 << 16, -7 << 16] };
    /// let seq = Quasicrystal::with_frame(40, 30, frame)?;
    /// let mut set = SampleSet::new(40, 30, 1).with_frame(seq.frame());
    /// for s in seq.first(50) {
    ///     set.try_push_exact(s.pos, s.lattice, &[9])?;
    /// }
    /// assert!(set.cells().is_some());
    /// // In the wrong frame, a lattice point does not match its position.
    /// let mut wrong = SampleSet::new(40, 30, 1);
    /// let s = seq.first(1)[0];
    /// assert!(wrong.try_push_exact(s.pos, s.lattice, &[9]).is_err());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_frame(mut self, frame: LatticeFrame) -> Self {
        self.lines = Lines::new(frame, self.width, self.height);
        self
    }

    /// Adds one sample: position in source pixels, `channels` colour bytes.
    ///
    /// A position that cannot be triangulated (NaN, ±∞, beyond ±2^200) is ignored; use
    /// [`SampleSet::try_push`] to be told. Missing colour bytes count as 0, extra ones are ignored.
    pub fn push(&mut self, pos: Point, colour: &[u8]) {
        let _ = self.try_push(pos, colour);
    }

    /// Adds one sample like [`SampleSet::push`], or returns an error (and adds nothing) if the
    /// position cannot be triangulated.
    ///
    /// ```
    /// let mut set = qcs::reconstruction::SampleSet::new(8, 8, 1);
    /// assert!(set.try_push([1.0, 2.0], &[7]).is_ok());
    /// assert!(set.try_push([f64::NAN, 2.0], &[7]).is_err());
    /// assert_eq!(set.len(), 1);
    /// ```
    pub fn try_push(&mut self, pos: Point, colour: &[u8]) -> crate::Result<()> {
        self.push_inner(pos, None, colour)
    }

    /// Adds one sample with its exact lattice point `lattice` (`pos` must be its pixel
    /// position in the set's frame, as in a [`crate::sites::Site`]).
    /// Ignored like [`SampleSet::push`] if unusable; see [`SampleSet::try_push_exact`].
    ///
    /// ```
    /// use qcs::reconstruction::{Method, SampleSet};
    /// use qcs::sites::Quasicrystal;
    /// let mut set = SampleSet::new(48, 32, 1);
    /// for s in Quasicrystal::new(48, 32)?.first(100) {
    ///     set.push_exact(s.pos, s.lattice, &[(s.pos[0] * 4.0) as u8]);
    /// }
    /// assert!(set.cells().is_some());
    /// assert_eq!(set.render(Method::Gouraud, 48, 32).len(), 48 * 32);
    /// # Ok::<(), qcs::sites::FrameError>(())
    /// ```
    pub fn push_exact(&mut self, pos: Point, lattice: ZZeta, colour: &[u8]) {
        let _ = self.try_push_exact(pos, lattice, colour);
    }

    /// [`SampleSet::push_exact`], or an error (and nothing added) if the position cannot be
    /// triangulated, a lattice coordinate is beyond [`crate::lattice::EXACT_LIMIT`], or `pos`
    /// is not the lattice point's position in the set's frame ([`SampleSet::with_frame`]).
    ///
    /// ```
    /// use qcs::lattice::ZZeta;
    /// use qcs::sites::Frame;
    /// let frame = Frame::default_for(8, 8);
    /// let mut set = qcs::reconstruction::SampleSet::new(8, 8, 1);
    /// let x = ZZeta::new([5, 3, 0, 1]);
    /// assert!(set.try_push_exact(frame.position(x), x, &[7]).is_ok());
    /// assert!(set.try_push_exact([1.0, 2.0], x, &[7]).is_err()); // not where x is
    /// assert!(set.try_push_exact([1.0, 3.0], ZZeta::new([1 << 40, 0, 0, 0]), &[7]).is_err());
    /// assert_eq!(set.len(), 1);
    /// ```
    pub fn try_push_exact(
        &mut self,
        pos: Point,
        lattice: ZZeta,
        colour: &[u8],
    ) -> crate::Result<()> {
        if !crate::lattice::within_exact_limit(lattice) {
            return Err(crate::Error::invalid(
                "lattice point",
                format_args!("{lattice:?}"),
                "a point within the exact range (lattice::within_exact_limit)",
            ));
        }
        let at = self.lines.frame().position(lattice);
        if (at[0] - pos[0]).abs() > 1e-6 || (at[1] - pos[1]).abs() > 1e-6 {
            return Err(crate::Error::invalid(
                "sample position",
                format_args!("{pos:?}"),
                format!("{at:?}, where lattice point {lattice:?} is in this set's frame"),
            ));
        }
        self.push_inner(pos, Some(lattice), colour)
    }

    fn push_inner(
        &mut self,
        pos: Point,
        lattice: Option<ZZeta>,
        colour: &[u8],
    ) -> crate::Result<()> {
        let Some(p) = mesh::sanitize(pos) else {
            return Err(crate::Error::invalid(
                "sample position",
                format_args!("{pos:?}"),
                "finite coordinates within the triangulation's range",
            ));
        };
        let k = self.positions.len();
        self.positions.push(p);
        let c0 = self.colours.len();
        for k in 0..self.channels {
            self.colours.push(colour.get(k).copied().unwrap_or(0));
        }
        let colour = &self.colours[c0..];
        let points = &mut self.points;
        self.starts.push(points.positions.len());
        points.push(p, lattice, colour);
        let exact = lattice.map(|x| (&self.lines, x));
        mirror_points(k, p, self.width, self.height, exact, |q, x| {
            if let Some(q) = mesh::sanitize(q) {
                points.push(q, x, colour);
            }
        });
        Ok(())
    }

    /// Makes room for `samples` more samples and their mirror points (a few percent more
    /// points), so that a set filled at once holds no doubling slack.
    pub(crate) fn reserve(&mut self, samples: usize) {
        let c = self.channels;
        self.positions.reserve_exact(samples);
        self.colours.reserve_exact(samples * c);
        self.starts.reserve_exact(samples);
        self.points.reserve(samples + samples / 8 + 256, c);
    }

    /// Pushes a site with its exact lattice point (Gouraud then draws the canonical cells),
    /// or without it if it is beyond the exact range, so that sample indices stay aligned.
    pub(crate) fn push_site(&mut self, site: &crate::sites::Site, colour: &[u8]) {
        if self.try_push_exact(site.pos, site.lattice, colour).is_err() {
            self.push(site.pos, colour);
        }
    }

    /// Sets the colours of the samples from `first` on (and of their mirror points),
    /// `channels()` bytes each.
    pub(crate) fn recolour(&mut self, first: usize, colours: &[u8]) {
        let c = self.channels;
        let n = self.positions.len();
        for (k, col) in (first..n).zip(colours.chunks_exact(c)) {
            self.colours[k * c..(k + 1) * c].copy_from_slice(col);
            let end = self.starts.get(k + 1).copied();
            let end = end.unwrap_or(self.points.positions.len());
            for p in self.starts[k]..end {
                self.points.colours[p * c..(p + 1) * c].copy_from_slice(col);
            }
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Bytes per colour.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Source size `(width, height)` in pixels.
    pub fn source_size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Sample positions in push order (source pixels).
    pub fn positions(&self) -> &[Point] {
        &self.positions
    }

    /// Sample colours in push order, `channels()` bytes each.
    pub fn colours(&self) -> &[u8] {
        &self.colours
    }

    /// The points the triangulation is built on (source pixels): every sample followed by its
    /// mirror points (`spec/reconstruction.md`). [`Vertex::index`] and the cells index this.
    ///
    /// ```
    /// let mut set = qcs::reconstruction::SampleSet::new(100, 100, 1);
    /// set.push([50.0, 5.0], &[7]); // the first sample is mirrored across every edge
    /// assert_eq!(set.points().len(), 9);
    /// assert_eq!(set.points()[1], [50.0, -5.0]);
    /// assert_eq!(set.point_colours(), &[7; 9]);
    /// ```
    pub fn points(&self) -> &[Point] {
        &self.points.positions
    }

    /// The colour each of [`SampleSet::points`] carries (its sample's), `channels()` bytes each.
    pub fn point_colours(&self) -> &[u8] {
        &self.points.colours
    }

    /// The exact lattice point of each of [`SampleSet::points`], where it has one.
    pub fn point_lattice(&self) -> &[Option<ZZeta>] {
        &self.points.lattice
    }

    /// The Delaunay triangulation of all points ([`SampleSet::points`]) pushed so far
    /// (inserting pending ones). Vertex data carry the point index; of points with equal
    /// positions only the first is a vertex.
    ///
    /// ```
    /// use qcs::reconstruction::SampleSet;
    /// use spade::Triangulation;
    /// let mut set = SampleSet::new(80, 80, 1);
    /// for p in [[30.0, 30.0], [50.0, 30.0], [30.0, 50.0], [50.0, 50.0], [30.0, 30.0]] {
    ///     set.push(p, &[0]);
    /// }
    /// // The first samples are mirrored: 4 + 4·8 points, the duplicate and its mirrors skipped.
    /// assert_eq!(set.triangulation().num_vertices(), 36);
    /// ```
    pub fn triangulation(&mut self) -> &SampleMesh {
        mesh::sync(&mut self.mesh, &self.points.positions, &mut self.synced);
        &self.mesh
    }

    /// The canonical Delaunay cells of the points ([`SampleSet::points`]), if every sample
    /// has an exact lattice point (and there are at least three points, not all collinear).
    ///
    /// The exact triangulation behind them is kept: points added since the last call are
    /// inserted locally (each splits the triangle it falls in, or joins the hull edges it
    /// sees, exact flips repair the Delaunay property around it, and only the changed
    /// triangles' edges are tested for cocircularity again).
    pub fn cells(&mut self) -> Option<&Cells> {
        self.sync_cells(false);
        self.cells.as_ref().and_then(|(_, c)| c.as_ref())
    }

    /// How many times the cells' triangulation was built from scratch rather than updated
    /// (for tests of the local update).
    #[doc(hidden)]
    pub fn cell_rebuilds(&self) -> usize {
        self.rebuilds
    }

    /// Builds the cells of the points so far: e.g. on another thread, before the colours
    /// are known. Unless `last` (no more points will come), the triangulation behind them
    /// is kept, to insert more points.
    pub(crate) fn build_cells(&mut self, last: bool) {
        self.sync_cells(last);
    }

    /// Prepares a set that will get no more points for `method`'s renders, freeing what only
    /// adding points needs: for the methods that draw the cells (Gouraud, cubic), they are
    /// built and the insertion structure behind them dropped (about 170 bytes a point).
    pub(crate) fn settle(&mut self, method: Method) {
        if matches!(method, Method::Gouraud | Method::Cubic) {
            self.sync_cells(true);
            self.live = None;
        }
    }

    /// Brings the cells up to date: by inserting the new points into the kept
    /// triangulation, or else afresh, by look-up ([`Cells::atlas`]) if `last` (no more
    /// points will come, so no triangulation need be kept), or by exact insertion
    /// ([`Cells::incremental`]'s builder, whose structure is kept). No cells if a point is
    /// not exact or the points have no triangle (fewer than three, or all collinear).
    fn sync_cells(&mut self, last: bool) {
        let pts = &self.points;
        let n = pts.positions.len();
        if self.cells.as_ref().map(|c| c.0) == Some(n) {
            return;
        }
        if pts.exact != n || n < 3 {
            self.live = None;
            self.cells = Some((n, None));
            return;
        }
        let grown = match &mut self.live {
            Some(live) => live.extend(&pts.lattice).is_ok(),
            None => false,
        };
        let mut cells = None;
        if !grown {
            self.rebuilds += 1;
            self.live = None;
            if last {
                cells = Cells::atlas(&pts.positions, &pts.lattice);
            }
            if cells.is_none() {
                self.live = LiveCells::grow(&pts.positions, &pts.lattice);
            }
        }
        let cells = cells.or_else(|| self.live.as_ref().map(LiveCells::cells));
        self.cells = Some((n, cells.filter(|c| !c.is_empty())));
    }

    /// Renders a `width × height` picture, interleaved, `channels` bytes per pixel, in parallel.
    pub fn render(&mut self, method: Method, width: u32, height: u32) -> Vec<u8> {
        self.render_with(method, width, height, RenderOptions::default())
    }

    /// Renders like [`SampleSet::render`] with `options` (e.g. single-threaded).
    ///
    /// ```
    /// use qcs::reconstruction::{Method, RenderOptions, SampleSet};
    /// let mut set = SampleSet::new(4, 4, 1);
    /// for (p, c) in [([0.5, 0.5], 0), ([3.5, 0.5], 60), ([0.5, 3.5], 0), ([3.5, 3.5], 60)] {
    ///     set.push(p, &[c]);
    /// }
    /// let single = RenderOptions::single_threaded();
    /// let a = set.render_with(Method::Gouraud, 4, 4, single);
    /// assert_eq!(&a[..4], &[0, 20, 40, 60]);
    /// assert_eq!(a, set.render(Method::Gouraud, 4, 4));
    /// ```
    pub fn render_with(
        &mut self,
        method: Method,
        width: u32,
        height: u32,
        options: RenderOptions,
    ) -> Vec<u8> {
        let (w, h, c) = (width as usize, height as usize, self.channels);
        if w == 0 || h == 0 {
            return Vec::new();
        }
        if self.positions.is_empty() {
            return vec![128; w * h * c];
        }
        if matches!(method, Method::Gouraud | Method::Cubic) {
            self.sync_cells(false);
        }
        let mut frame = Output {
            width: w,
            height: h,
            channels: c,
            colours: &self.points.colours,
            sx: self.width.max(1) as f64 / width as f64,
            sy: self.height.max(1) as f64 / height as f64,
        };
        let pts = &self.points;
        match method {
            Method::Gouraud | Method::Cubic => {
                let cells = self.cells.as_ref().and_then(|(_, c)| c.as_ref());
                if cells.is_none() {
                    mesh::sync(&mut self.mesh, &pts.positions, &mut self.synced);
                }
                let opts = (options.parallel, method == Method::Cubic);
                gouraud::render(&self.mesh, cells, &pts.positions, &frame, opts)
            }
            Method::Natural => {
                mesh::sync(&mut self.mesh, &pts.positions, &mut self.synced);
                natural::render(&self.mesh, &frame, options.parallel)
            }
            Method::Shepard => {
                if self.grid.as_ref().map(SampleGrid::len) != Some(self.positions.len()) {
                    self.grid = Some(SampleGrid::new(&self.positions));
                }
                let grid = match &self.grid {
                    Some(g) => g,
                    None => return vec![128; w * h * c],
                };
                frame.colours = &self.colours;
                shepard::render(grid, &frame, options.parallel)
            }
        }
    }
}

/// One-shot render of `positions` (source pixels) with `colours` (`channels` bytes each).
///
/// Same rules as [`SampleSet`] (missing colour bytes count as 0); the triangulation is bulk loaded.
pub fn render(
    source: (u32, u32),
    channels: usize,
    positions: &[Point],
    colours: &[u8],
    method: Method,
    width: u32,
    height: u32,
) -> Vec<u8> {
    render_with(
        source,
        channels,
        positions,
        colours,
        method,
        width,
        height,
        RenderOptions::default(),
    )
}

/// [`render`] with `options`.
///
/// ```
/// use qcs::reconstruction::{render_with, Method, RenderOptions};
/// let single = RenderOptions::single_threaded();
/// let img = render_with((2, 2), 1, &[[1.0, 1.0]], &[9], Method::Shepard, 3, 3, single);
/// assert_eq!(img, vec![9; 9]);
/// ```
#[allow(clippy::too_many_arguments)]
pub fn render_with(
    source: (u32, u32),
    channels: usize,
    positions: &[Point],
    colours: &[u8],
    method: Method,
    width: u32,
    height: u32,
    options: RenderOptions,
) -> Vec<u8> {
    let mut set = SampleSet::new(source.0, source.1, channels);
    let c = set.channels;
    for (k, p) in positions.iter().enumerate() {
        let col = colours.get(k * channels..).unwrap_or(&[]);
        set.push(*p, &col[..col.len().min(c)]);
    }
    set.render_with(method, width, height, options)
}

/// What every method needs to know about the output.
pub(crate) struct Output<'a> {
    pub(crate) width: usize,
    pub(crate) height: usize,
    pub(crate) channels: usize,
    pub(crate) colours: &'a [u8],
    /// Output → source scale (`W / w`, `H / h`).
    pub(crate) sx: f64,
    pub(crate) sy: f64,
}

impl Output<'_> {
    /// Centre of output pixel `(i, j)` in source pixels.
    #[inline]
    pub(crate) fn source_point(&self, i: usize, j: usize) -> Point {
        [(i as f64 + 0.5) * self.sx, (j as f64 + 0.5) * self.sy]
    }
}

/// Rows per band for the parallel paths.
pub(crate) fn band_rows(height: usize) -> usize {
    let threads = rayon::current_num_threads().max(1);
    (height / (threads * 8)).clamp(4, 64)
}

#[inline]
fn store(px: &mut [u8], colour: [f32; 4]) {
    for (p, v) in px.iter_mut().zip(colour) {
        // Saturating cast: round half up, clamp to 0..=255 (NaN → 0).
        *p = (v + 0.5) as u8;
    }
}

/// Paints the pixels of `band` that no triangle claimed, by the outside-the-hull rule.
pub(crate) fn fill_unpainted(band: &mut Band<'_>, frame: &Output<'_>, boundary: &Boundary) {
    let (w, c) = (band.width, band.channels);
    let Some(painted) = band.painted.as_deref() else {
        return; // The triangles cover the band.
    };
    let mut hint = 0usize;
    for r in 0..band.rows {
        for i in 0..w {
            if painted[r * w + i] {
                continue;
            }
            let q = frame.source_point(i, band.row0 + r);
            let col = if boundary.is_empty() {
                [128.0; 4]
            } else {
                boundary.colour(q, &mut hint)
            };
            let o = (r * w + i) * c;
            store(&mut band.pixels[o..o + c], col);
        }
    }
}

/// Renders by evaluating `f` at every pixel centre (in source pixels), with per-band state `S`.
pub(crate) fn per_pixel<S, M, F>(frame: &Output<'_>, parallel: bool, make: M, f: F) -> Vec<u8>
where
    M: Fn() -> S + Sync,
    F: Fn(&mut S, Point) -> [f32; 4] + Sync,
{
    let (w, h, c) = (frame.width, frame.height, frame.channels);
    let mut out = vec![0u8; w * h * c];
    let run = |row0: usize, chunk: &mut [u8]| {
        let mut state = make();
        for (r, line) in chunk.chunks_exact_mut(w * c).enumerate() {
            for (i, px) in line.chunks_exact_mut(c).enumerate() {
                store(px, f(&mut state, frame.source_point(i, row0 + r)));
            }
        }
    };
    if parallel {
        let rows = band_rows(h);
        out.par_chunks_mut(rows * w * c)
            .enumerate()
            .for_each(|(b, chunk)| run(b * rows, chunk));
    } else {
        run(0, &mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incremental_sync_keeps_first_duplicate() {
        let mut set = SampleSet::new(8, 8, 1);
        set.push([1.0, 1.0], &[10]);
        set.push([6.0, 1.0], &[10]);
        set.push([1.0, 6.0], &[10]);
        let _ = set.triangulation();
        set.push([1.0, 1.0], &[250]);
        let before = set.points().len();
        let colours = set.point_colours().to_vec();
        let t = set.triangulation();
        // The duplicate and its mirror points (same positions as the first's) are not vertices.
        assert!(t.vertices().all(|v| (v.data().index as usize) < before));
        assert!(t.vertices().all(|v| colours[v.data().index as usize] == 10));
    }
}
