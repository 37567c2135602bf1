//! Gouraud shading: linear interpolation over the Delaunay triangles, by scan conversion.
//!
//! With exact lattice points the triangles are those of the canonical Delaunay cells
//! ([`Cells`]): a cell with k ≥ 4 vertices is drawn as k triangles around its vertex centroid,
//! whose colour is the mean of the k vertex colours (`spec/reconstruction.md`).

use spade::Triangulation as _;

use super::cells::Cells;
use super::cubic;
use super::hull::{colour_of, Boundary};
use super::mesh::SampleMesh;
use super::raster::{self, fmax, fmin, Band, RasterTriangle, RasterVertex};
use super::{fill_unpainted, Output};
use crate::sites::Point;

/// The inner faces of `mesh` as triples of point indices, each starting from its smallest
/// index, so the same triangle always gives the same arithmetic whichever way the mesh was
/// built.
fn faces(mesh: &SampleMesh) -> Vec<[u32; 3]> {
    let mut out = Vec::with_capacity(mesh.num_inner_faces());
    for f in mesh.inner_faces() {
        let [a, b, c] = f.vertices().map(|v| v.data().index);
        out.push(if a < b && a < c {
            [a, b, c]
        } else if b < c {
            [b, c, a]
        } else {
            [c, a, b]
        });
    }
    out
}

/// Every point as a [`RasterVertex`]: position in output pixels (multiplied by `scale`) and
/// colour.
fn vertices(
    positions: &[Point],
    colours: &[u8],
    channels: usize,
    scale: [f64; 2],
) -> Vec<RasterVertex> {
    let vertex = |(k, p): (usize, &Point)| RasterVertex {
        pos: [p[0] * scale[0], p[1] * scale[1]],
        colour: colour_of(colours, channels, k),
    };
    positions.iter().enumerate().map(vertex).collect()
}

/// Vertex `i`, or the origin in black for an index out of range.
#[inline]
fn at(vertices: &[RasterVertex], i: u32) -> &RasterVertex {
    const NONE: &RasterVertex = &RasterVertex {
        pos: [0.0; 2],
        colour: [0.0; 4],
    };
    vertices.get(i as usize).unwrap_or(NONE)
}

/// The inner faces of `mesh` as [`RasterTriangle`]s in output pixels (positions multiplied by
/// `scale`), each with its vertices' colours.
///
/// Vertices are listed starting from the one with the smallest sample index, so the same
/// triangle always gives the same arithmetic whichever way the mesh was built.
pub fn triangles(
    mesh: &SampleMesh,
    colours: &[u8],
    channels: usize,
    scale: [f64; 2],
) -> Vec<RasterTriangle> {
    let mut positions = vec![[0.0; 2]; mesh.num_vertices()];
    for v in mesh.vertices() {
        let (i, p) = (v.data().index as usize, v.position());
        if i >= positions.len() {
            positions.resize(i + 1, [0.0; 2]);
        }
        positions[i] = [p.x, p.y];
    }
    let verts = vertices(&positions, colours, channels, scale);
    let tri = |f: [u32; 3]| f.map(|i| *at(&verts, i));
    faces(mesh).into_iter().map(tri).collect()
}

/// The canonical cells as [`RasterTriangle`]s in output pixels (positions multiplied by
/// `scale`): a 3-vertex cell is itself, a cell with k ≥ 4 vertices is k triangles
/// `(centroid, v_i, v_{i+1})`.
///
/// The centroid is `(Σ p_i)/k` summed in `f64` in the cell's canonical vertex order (from
/// its smallest lattice point, counter-clockwise), its colour the exact integer sum of the k
/// vertex colours divided by k in `f32`; so the triangles, and the picture, do not depend on
/// how the cells were found.
///
/// ```
/// use qcs::reconstruction::{cell_triangles, SampleSet};
/// use qcs::sites::Quasicrystal;
/// let mut set = SampleSet::new(32, 32, 1);
/// for (k, s) in Quasicrystal::new(32, 32)?.first(60).iter().enumerate() {
///     set.push_exact(s.pos, s.lattice, &[k as u8]);
/// }
/// let positions = set.positions().to_vec();
/// let colours = set.colours().to_vec();
/// let cells = set.cells().unwrap().clone();
/// let tris = cell_triangles(&cells, &positions, &colours, 1, [1.0, 1.0]);
/// let expected: usize = cells.iter().map(|c| if c.len() == 3 { 1 } else { c.len() }).sum();
/// assert_eq!(tris.len(), expected);
/// # Ok::<(), qcs::sites::FrameError>(())
/// ```
pub fn cell_triangles(
    cells: &Cells,
    positions: &[Point],
    colours: &[u8],
    channels: usize,
    scale: [f64; 2],
) -> Vec<RasterTriangle> {
    let verts = vertices(positions, colours, channels, scale);
    let mut out = Vec::with_capacity(positions.len() * 2 + 8);
    for cell in cells.iter() {
        cell_fan(cell, positions, colours, channels, scale, &verts, |t| {
            out.push(t.map(|v| *v))
        });
    }
    out
}

/// The triangles of one cell (see [`cell_triangles`]), given to `f` in order; `verts` are the
/// points as [`vertices`].
#[inline]
fn cell_fan(
    cell: &[u32],
    positions: &[Point],
    colours: &[u8],
    channels: usize,
    scale: [f64; 2],
    verts: &[RasterVertex],
    mut f: impl FnMut([&RasterVertex; 3]),
) {
    let k = cell.len();
    if k < 3 {
        return;
    }
    if k == 3 {
        f([at(verts, cell[0]), at(verts, cell[1]), at(verts, cell[2])]);
        return;
    }
    let mut sum_pos = [0f64; 2];
    let mut sum_col = [0u32; 4];
    for &i in cell {
        let p = positions.get(i as usize).copied().unwrap_or_default();
        sum_pos[0] += p[0];
        sum_pos[1] += p[1];
        if let Some(s) = colours.get(i as usize * channels..(i as usize + 1) * channels) {
            for (acc, &v) in sum_col.iter_mut().zip(s) {
                *acc += v as u32;
            }
        }
    }
    let kf = k as f64;
    let centre = RasterVertex {
        pos: [sum_pos[0] / kf * scale[0], sum_pos[1] / kf * scale[1]],
        colour: sum_col.map(|v| v as f32 / k as f32),
    };
    let mut prev = at(verts, cell[0]);
    for s in 0..k {
        let next = at(verts, cell[(s + 1) % k]);
        f([&centre, prev, next]);
        prev = next;
    }
}

/// Renders `mesh` by Gouraud shading (or, if `cubic`, by the cubic patches of
/// [`super::cubic`]) into `frame`'s output: over the canonical `cells` when given (their
/// vertices index `positions`), else over `mesh`'s own triangles. Each cell (or triangle) is
/// set up afresh in every band of rows it touches, so nothing per triangle is kept in memory.
pub(crate) fn render(
    mesh: &SampleMesh,
    cells: Option<&Cells>,
    positions: &[Point],
    frame: &Output<'_>,
    (parallel, cubic): (bool, bool),
) -> Vec<u8> {
    let (w, h, c) = (frame.width, frame.height, frame.channels);
    let scale = [1.0 / frame.sx, 1.0 / frame.sy];
    let colours = frame.colours;
    let boundary = match cells {
        // The exact hull: sites that are exactly on a hull edge are boundary vertices.
        Some(cells) => {
            let at = |i: u32| positions.get(i as usize).copied().unwrap_or_default();
            let edges = cells.hull().iter().map(|&[a, b]| {
                let (pa, pb) = (at(a), at(b));
                // Canonical direction, as for spade's hull.
                if (pa[0], pa[1]) <= (pb[0], pb[1]) {
                    (pa, pb, a as usize, b as usize)
                } else {
                    (pb, pa, b as usize, a as usize)
                }
            });
            Boundary::from_edges(edges, colours, c)
        }
        None => Boundary::new(mesh, colours, c),
    };
    // The fill rule paints every pixel centre inside the hull exactly once: when the hull
    // holds the corner pixel centres it holds them all, and no mask is needed.
    let (iw, jh) = (w.max(1) - 1, h.max(1) - 1);
    let corners = [(0, 0), (iw, 0), (0, jh), (iw, jh)].map(|(i, j)| frame.source_point(i, j));
    let mask = !boundary.contains(&corners);
    let finish = |band: &mut Band<'_>| fill_unpainted(band, frame, &boundary);
    let verts = vertices(positions, colours, c, scale);
    let y = |i: u32| at(&verts, i).pos[1];
    let opts = (parallel, mask);
    match cells {
        Some(cells) => {
            let extent = |k: usize| {
                let cell = cells.get(k).unwrap_or(&[]);
                let ys = cell.iter().map(|&i| y(i));
                ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (fmin(v, a), fmax(v, b))
                })
            };
            let patches =
                cubic.then(|| cubic::vertices(&verts, cells.iter(), c, (scale, parallel)));
            let emit = |k: usize, band: &mut Band<'_>| {
                let Some(cell) = cells.get(k) else { return };
                if let Some(patches) = &patches {
                    cubic::paint_cell(cell, patches, band);
                } else {
                    let paint = |t: [&RasterVertex; 3]| raster::paint(t, band);
                    cell_fan(cell, positions, colours, c, scale, &verts, paint);
                }
            };
            raster::paint_groups(cells.len(), extent, emit, (w, h, c), opts, finish).0
        }
        None => {
            let tris = faces(mesh);
            let extent = |k: usize| {
                let [a, b, c] = tris[k].map(y);
                (fmin(fmin(a, b), c), fmax(fmax(a, b), c))
            };
            let patches = cubic.then(|| {
                cubic::vertices(&verts, tris.iter().map(|t| &t[..]), c, (scale, parallel))
            });
            let emit = |k: usize, band: &mut Band<'_>| match &patches {
                Some(patches) => cubic::paint_cell(&tris[k], patches, band),
                None => raster::paint(tris[k].map(|i| at(&verts, i)), band),
            };
            raster::paint_groups(tris.len(), extent, emit, (w, h, c), opts, finish).0
        }
    }
}
