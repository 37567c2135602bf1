//! Stylized renderings of a sample set: the paper's mosaic, paint strokes,
//! Voronoi and Delaunay diagrams, the site order (Fig. 7), Fourier power spectra
//! (Fig. 9) and the quasicrystal phase function (Fig. 2).
//!
//! Every renderer takes the site positions in source pixels (`[0, W) × [0, H)`
//! of the source image), RGB8 colours (3 bytes per site) where it needs them, the
//! source size and the output size, and returns an [`image::RgbImage`]. Output
//! pixel `(i, j)` shows the source point `((i + ½)·W/w, (j + ½)·H/h)`.
//! Inputs are validated: colour buffers of the wrong length, empty sizes,
//! non-finite positions or outputs over [`qcs::Limits::default`]'s
//! `max_output_pixels` give [`crate::Error::InvalidArgument`] / [`crate::Error::Limits`].
//!
//! The cell-based styles (mosaic, strokes, the Delaunay wireframe) draw the cells of
//! [`Triangulation::cells`]: the canonical Delaunay cells, cocircular triangles merged into
//! polygons, decided exactly for quasicrystal sites given with their lattice points
//! ([`Sites::exact`]), and with a relative tolerance of 1e−9 for other sites.
//!
//! ```
//! use qcs_lab::samplers::{Sampler, Periodic};
//! let sites = Periodic.sites(64, 64, 81);
//! let colours = vec![200u8; 3 * sites.len()];
//! let img = qcs_lab::styles::mosaic(&sites, &colours, (64, 64), (128, 128)).unwrap();
//! assert_eq!(img.dimensions(), (128, 128));
//! ```

mod graph;
mod mosaic;
mod order;
mod phase;
mod spectrum;
mod strokes;
mod voronoi;

pub use graph::{delaunay_graph, delaunay_over};
pub use mosaic::mosaic;
pub use order::{order, order_colour};
pub use phase::{phase_contour, phase_level_set, phase_sites, phase_value, PhaseWindow};
pub use spectrum::{power_spectrum, spectrum};
pub use strokes::{strokes, strokes_with, DEFAULT_SHARPNESS};
pub use voronoi::voronoi;

use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation as _};

use crate::{Error, Result};
use qcs::lattice::ZZeta;
use qcs::reconstruction::{Cells, SampleMesh as Mesh, Vertex};
use qcs::sites::Point;

/// The sites a style draws: positions in source pixels and, for quasicrystal sites, their
/// exact lattice points. Plain position slices convert into it.
///
/// ```
/// use qcs::sites::Quasicrystal;
/// use qcs_lab::styles::{Sites, Triangulation};
/// let sites = Quasicrystal::new(64, 64)?.first(300);
/// let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
/// let lat: Vec<_> = sites.iter().map(|s| s.lattice).collect();
/// let exact = Triangulation::of(Sites::exact(&pos, &lat))?;
/// assert!(exact.is_exact() && !Triangulation::of(&pos)?.is_exact());
/// assert!(exact.cells().iter().any(|c| c.len() == 5)); // pentagons
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Sites<'a> {
    positions: &'a [Point],
    lattice: Option<&'a [ZZeta]>,
}

impl<'a> Sites<'a> {
    /// Sites with their lattice points (`lattice[k]` is the point of `positions[k]`, in any
    /// frame: cells only depend on orientation and incircle signs, which a frame keeps).
    pub fn exact(positions: &'a [Point], lattice: &'a [ZZeta]) -> Self {
        Sites {
            positions,
            lattice: Some(lattice),
        }
    }

    /// The positions.
    pub fn positions(&self) -> &'a [Point] {
        self.positions
    }
}

impl<'a> From<&'a [Point]> for Sites<'a> {
    fn from(positions: &'a [Point]) -> Self {
        Sites {
            positions,
            lattice: None,
        }
    }
}

impl<'a> From<&'a Vec<Point>> for Sites<'a> {
    fn from(positions: &'a Vec<Point>) -> Self {
        positions.as_slice().into()
    }
}

impl<'a, const N: usize> From<&'a [Point; N]> for Sites<'a> {
    fn from(positions: &'a [Point; N]) -> Self {
        positions.as_slice().into()
    }
}

/// Colour of grout, edges and lines.
pub const INK: [u8; 3] = [24, 24, 24];

/// Sites with their mirror images across the edges of the `source` frame, as a decode
/// triangulates them ([`qcs::reconstruction::mirror_images`]), each image with its site's
/// colour (3 bytes a site): what the cell-based styles (mosaic, strokes, the Delaunay
/// wireframe) draw so that their cells run off the frame, rather than stopping at the sites'
/// convex hull, beyond which each pixel takes its nearest site's colour (a band of stripes
/// along the edges). With `exact`'s lattice points and frame, the images have theirs (an image
/// beyond the lattice's exact range is left out, as a decode leaves it).
///
/// ```
/// use qcs_lab::styles::with_mirror_images;
/// let sites = [[1.0, 1.0], [9.0, 1.0], [1.0, 9.0], [9.0, 9.0]];
/// let colours = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
/// let (pos, lattice, col) = with_mirror_images(&sites, None, &colours, (10, 10));
/// assert!(pos.len() > 4 && lattice.is_none() && col.len() == 3 * pos.len());
/// assert!(pos.contains(&[-1.0, 1.0]) && pos.contains(&[-1.0, -1.0]));
/// ```
pub fn with_mirror_images(
    positions: &[Point],
    exact: Option<(&[ZZeta], qcs::sites::Frame)>,
    colours: &[u8],
    source: (u32, u32),
) -> (Vec<Point>, Option<Vec<ZZeta>>, Vec<u8>) {
    let images = qcs::reconstruction::mirror_images(positions, exact, source.0, source.1);
    let mut pos = positions.to_vec();
    let mut lattice = exact.map(|(l, _)| l.to_vec());
    let mut col = colours.to_vec();
    for (k, p, z) in images {
        match (&mut lattice, z) {
            (Some(lattice), Some(z)) => lattice.push(z),
            (Some(_), None) => continue,
            (None, _) => {}
        }
        pos.push(p);
        col.extend_from_slice(&colours[3 * k..3 * k + 3]);
    }
    (pos, lattice, col)
}

#[derive(Clone, Copy, Debug)]
struct Site {
    pos: Point2<f64>,
    index: usize,
}

impl HasPosition for Site {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

/// The Delaunay triangulation of a site set, keeping each vertex's site index, and its
/// canonical cells.
///
/// Sites at an identical position are merged (the first kept is one of them).
///
/// ```
/// let t = qcs_lab::styles::Triangulation::new(&[[0.0, 0.0], [4.0, 0.0], [0.0, 4.0], [4.0, 4.0]]).unwrap();
/// assert_eq!(t.cells().len(), 1); // the square is one canonical cell
/// assert_eq!(t.triangles().len(), 2);
/// assert_eq!(t.edges().len(), 4); // the square's sides, not its diagonal
/// assert_eq!(t.nearest([3.9, 0.2]), Some(1));
/// ```
pub struct Triangulation {
    mesh: DelaunayTriangulation<Site>,
    /// The exact canonical cells, for sites with lattice points.
    exact: Option<Vec<Vec<usize>>>,
}

impl Triangulation {
    /// Triangulates `sites`; with lattice points ([`Sites::exact`]) the cells are decided by
    /// the exact predicates ([`Cells`]), as Gouraud draws them.
    pub fn of<'a>(sites: impl Into<Sites<'a>>) -> Result<Self> {
        let sites = sites.into();
        let mut t = Triangulation::new(sites.positions)?;
        if let Some(lattice) = sites.lattice.filter(|l| l.len() == sites.positions.len()) {
            let vertices: Vec<Vertex> = t
                .mesh
                .vertices()
                .map(|v| Vertex {
                    position: v.position(),
                    index: v.data().index as u32,
                })
                .collect();
            let points: Vec<Option<ZZeta>> = lattice.iter().copied().map(Some).collect();
            let mesh = Mesh::bulk_load_stable(vertices).map_err(refused)?;
            t.exact = Cells::build(&mesh, &points).map(|c| {
                c.iter()
                    .map(|c| c.iter().map(|&i| i as usize).collect())
                    .collect()
            });
        }
        Ok(t)
    }

    /// Whether the cells are the exact ones (sites with lattice points).
    pub fn is_exact(&self) -> bool {
        self.exact.is_some()
    }

    /// Triangulates `positions`; fails on non-finite or out-of-range coordinates.
    pub fn new(positions: &[Point]) -> Result<Self> {
        let sites: Vec<Site> = positions
            .iter()
            .enumerate()
            .map(|(index, p)| Site {
                pos: Point2::new(p[0], p[1]),
                index,
            })
            .collect();
        for s in &sites {
            spade::validate_vertex(s).map_err(|e| {
                crate::invalid(
                    "site position",
                    format_args!("{:?} (site {}: {e})", positions[s.index], s.index),
                    "finite coordinates within spade's range",
                )
            })?;
        }
        let mesh = DelaunayTriangulation::bulk_load(sites).map_err(refused)?;
        Ok(Triangulation { mesh, exact: None })
    }

    /// The cells to draw, each a convex polygon of site indices in boundary order.
    ///
    /// These are the *canonical cells* of the Delaunay triangulation: adjacent
    /// triangles whose four sites are cocircular are merged into one inscribed polygon, so
    /// that a square of a periodic grid or a pentagon of a quasicrystal is one cell whatever
    /// diagonals the triangulator chose. Cocircularity is exact for sites with lattice
    /// points ([`Triangulation::of`]), else within a relative tolerance of 1e−9. Elsewhere
    /// the cells are the Delaunay triangles. This is the single place that decides what the
    /// styles draw.
    pub fn cells(&self) -> Vec<Vec<usize>> {
        if let Some(cells) = &self.exact {
            return cells.clone();
        }
        let faces: Vec<_> = self.mesh.inner_faces().collect();
        let nf = self.mesh.all_faces().len();
        let mut parent: Vec<usize> = (0..nf).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for e in self.mesh.undirected_edges() {
            let d = e.as_directed();
            let (Some(f), Some(g)) = (d.face().as_inner(), d.rev().face().as_inner()) else {
                continue;
            };
            let Some(opp) = d.rev().opposite_vertex() else {
                continue;
            };
            let (c, r) = circle(f.positions());
            let q = opp.position();
            let dist = ((q.x - c[0]).powi(2) + (q.y - c[1]).powi(2)).sqrt();
            if (dist - r).abs() <= 1e-9 * r.max(1e-300) {
                let (a, b) = (
                    find(&mut parent, f.fix().index()),
                    find(&mut parent, g.fix().index()),
                );
                if a != b {
                    parent[a] = b;
                }
            }
        }
        let mut groups: std::collections::BTreeMap<usize, Vec<usize>> =
            std::collections::BTreeMap::new();
        for f in &faces {
            let root = find(&mut parent, f.fix().index());
            groups.entry(root).or_default().push(f.fix().index());
        }
        // Per face: its three (position, vertex index, site index).
        let mut corners: std::collections::HashMap<usize, [(Point2<f64>, usize, usize); 3]> =
            std::collections::HashMap::with_capacity(faces.len());
        for f in &faces {
            corners.insert(
                f.fix().index(),
                f.vertices()
                    .map(|v| (v.position(), v.fix().index(), v.data().index)),
            );
        }
        let mut out = Vec::with_capacity(groups.len());
        for members in groups.values() {
            let Some(first) = corners.get(&members[0]) else {
                continue;
            };
            if members.len() == 1 {
                out.push(first.iter().map(|v| v.2).collect());
                continue;
            }
            let (c, _) = circle(first.map(|v| v.0));
            let mut verts: Vec<(f64, usize, usize)> = members
                .iter()
                .filter_map(|m| corners.get(m))
                .flatten()
                .map(|&(p, vi, si)| ((p.y - c[1]).atan2(p.x - c[0]), vi, si))
                .collect();
            verts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            verts.dedup_by_key(|v| v.1);
            out.push(verts.into_iter().map(|v| v.2).collect());
        }
        out
    }

    /// The cells split into triangles (fans from each cell's first vertex).
    pub fn triangles(&self) -> Vec<[usize; 3]> {
        let mut out = Vec::new();
        for cell in self.cells() {
            for k in 1..cell.len().saturating_sub(1) {
                out.push([cell[0], cell[k], cell[k + 1]]);
            }
        }
        out
    }

    /// The edges of the cells as pairs of site indices (`a < b`, sorted): the Delaunay edges
    /// without the diagonals a triangulator draws inside cocircular cells.
    pub fn edges(&self) -> Vec<[usize; 2]> {
        let mut out: Vec<[usize; 2]> = Vec::new();
        for cell in self.cells() {
            for k in 0..cell.len() {
                let (a, b) = (cell[k], cell[(k + 1) % cell.len()]);
                out.push([a.min(b), a.max(b)]);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Index of the site nearest to `p` (`None` for an empty set).
    pub fn nearest(&self, p: Point) -> Option<usize> {
        self.mesh
            .nearest_neighbor(Point2::new(p[0], p[1]))
            .map(|v| v.data().index)
    }
}

/// Circumcentre and circumradius of a triangle.
fn circle(p: [Point2<f64>; 3]) -> ([f64; 2], f64) {
    let (ax, ay) = (p[0].x, p[0].y);
    let (bx, by) = (p[1].x - ax, p[1].y - ay);
    let (cx, cy) = (p[2].x - ax, p[2].y - ay);
    let d = 2.0 * (bx * cy - by * cx);
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    ([ax + ux, ay + uy], (ux * ux + uy * uy).sqrt())
}

/// Sites the triangulation refused.
fn refused(e: spade::InsertionError) -> Error {
    crate::invalid(
        "site positions",
        format_args!("refused by the triangulation ({e})"),
        "finite coordinates within spade's range",
    )
}

/// Checks the common inputs of the renderers.
pub(crate) fn check(
    positions: &[Point],
    colours: Option<&[u8]>,
    source: (u32, u32),
    output: (u32, u32),
) -> Result<()> {
    if source.0 == 0 || source.1 == 0 {
        return Err(crate::invalid(
            "source size",
            format_args!("{}×{}", source.0, source.1),
            "at least 1×1",
        ));
    }
    if output.0 == 0 || output.1 == 0 {
        return Err(crate::invalid(
            "output size",
            format_args!("{}×{}", output.0, output.1),
            "at least 1×1",
        ));
    }
    qcs::Limits::default().check_output(output.0 as u64, output.1 as u64)?;
    if let Some(c) = colours {
        if c.len() != positions.len().saturating_mul(3) {
            return Err(crate::invalid(
                "colours",
                format_args!("{} bytes for {} sites", c.len(), positions.len()),
                "3 bytes per site",
            ));
        }
    }
    if let Some(p) = positions
        .iter()
        .find(|p| !p[0].is_finite() || !p[1].is_finite())
    {
        return Err(crate::invalid(
            "site position",
            format_args!("{p:?}"),
            "finite coordinates",
        ));
    }
    Ok(())
}

/// Source → output pixel scale.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scale {
    pub sx: f64,
    pub sy: f64,
    pub w: u32,
    pub h: u32,
}

impl Scale {
    pub fn new(source: (u32, u32), output: (u32, u32)) -> Self {
        Scale {
            sx: output.0 as f64 / source.0 as f64,
            sy: output.1 as f64 / source.1 as f64,
            w: output.0,
            h: output.1,
        }
    }
    /// Source point → output coordinates.
    pub fn to_out(self, p: Point) -> [f64; 2] {
        [p[0] * self.sx, p[1] * self.sy]
    }
    /// Centre of output pixel `(i, j)` in source coordinates.
    pub fn to_source(self, i: u32, j: u32) -> Point {
        [(i as f64 + 0.5) / self.sx, (j as f64 + 0.5) / self.sy]
    }
}

pub(crate) fn colour(colours: &[u8], k: usize) -> [u8; 3] {
    [colours[3 * k], colours[3 * k + 1], colours[3 * k + 2]]
}

/// Edge function of `p` against the edge `a → b`, computed from the
/// lexicographically smaller endpoint so that the two polygons sharing an
/// edge get exactly opposite values (needed for the tie rule).
fn edge_fn(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> (f64, bool) {
    let swap = (b[0], b[1]) < (a[0], a[1]);
    let (lo, hi) = if swap { (b, a) } else { (a, b) };
    let e = (hi[0] - lo[0]) * (p[1] - lo[1]) - (hi[1] - lo[1]) * (p[0] - lo[0]);
    (if swap { -e } else { e }, swap)
}

/// Calls `f(i, j)` for every output pixel whose centre is inside the convex
/// polygon `poly` (output coordinates, either orientation). A pixel centre on an
/// edge shared by two polygons goes to exactly one of them.
pub(crate) fn fill_convex(poly: &[[f64; 2]], w: u32, h: u32, mut f: impl FnMut(u32, u32)) {
    let n = poly.len();
    if n < 3 {
        return;
    }
    let mut area2 = 0.0;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        area2 += a[0] * b[1] - b[0] * a[1];
    }
    if area2 == 0.0 || !area2.is_finite() {
        return;
    }
    let sign = if area2 > 0.0 { 1.0 } else { -1.0 };
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in poly {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let i0 = ((x0 - 0.5).ceil().max(0.0)) as i64;
    let i1 = ((x1 - 0.5).floor().min(w as f64 - 1.0)) as i64;
    let j0 = ((y0 - 0.5).ceil().max(0.0)) as i64;
    let j1 = ((y1 - 0.5).floor().min(h as f64 - 1.0)) as i64;
    for j in j0..=j1 {
        for i in i0..=i1 {
            let p = [i as f64 + 0.5, j as f64 + 0.5];
            let inside = (0..n).all(|k| {
                let (e, swapped) = edge_fn(poly[k], poly[(k + 1) % n], p);
                let e = e * sign;
                // Ties: keep the pixel for the polygon that walks the edge in its
                // canonical (not swapped) direction.
                e > 0.0 || (e == 0.0 && !swapped)
            });
            if inside {
                f(i as u32, j as u32);
            }
        }
    }
}

/// Draws a 1-pixel line from `a` to `b` (output coordinates).
pub(crate) fn draw_line(img: &mut image::RgbImage, a: [f64; 2], b: [f64; 2], c: [u8; 3]) {
    let (w, h) = img.dimensions();
    let steps = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).clamp(1, 1 << 20);
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let x = (a[0] + t * (b[0] - a[0])).floor();
        let y = (a[1] + t * (b[1] - a[1])).floor();
        if x >= 0.0 && y >= 0.0 && x < w as f64 && y < h as f64 {
            img.put_pixel(x as u32, y as u32, image::Rgb(c));
        }
    }
}

/// Fills every pixel with `covered[k] == false` with its nearest site's colour.
pub(crate) fn fill_uncovered(
    img: &mut image::RgbImage,
    covered: &[bool],
    tri: &Triangulation,
    colours: &[u8],
    frame: &Scale,
) {
    for j in 0..frame.h {
        for i in 0..frame.w {
            if !covered[(j * frame.w + i) as usize] {
                if let Some(k) = tri.nearest(frame.to_source(i, j)) {
                    img.put_pixel(i, j, image::Rgb(colour(colours, k)));
                }
            }
        }
    }
}
