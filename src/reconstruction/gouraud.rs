//! Gouraud shading: linear interpolation over the Delaunay triangles, by scan conversion.
//!
//! With exact lattice points the triangles are those of the canonical Delaunay cells
//! ([`Cells`]): a cell with k ≥ 4 vertices is drawn as k triangles around its vertex centroid,
//! whose colour is the mean of the k vertex colours (`spec/reconstruction.md`).

use spade::Triangulation as _;

use super::cells::Cells;
use super::hull::{colour_of, Boundary};
use super::mesh::Triangulation;
use super::raster::{self, Band, RasterTriangle, RasterVertex};
use super::{fill_unpainted, Frame};
use crate::sites::Point;

/// The inner faces of `mesh` as [`RasterTriangle`]s in output pixels (positions multiplied by
/// `scale`), each with its vertices' colours.
///
/// Vertices are listed starting from the one with the smallest sample index, so the same
/// triangle always gives the same arithmetic whichever way the mesh was built.
pub fn triangles(
    mesh: &Triangulation,
    colours: &[u8],
    channels: usize,
    scale: [f64; 2],
) -> Vec<RasterTriangle> {
    let mut out = Vec::with_capacity(mesh.num_inner_faces());
    for f in mesh.inner_faces() {
        let vs = f.vertices();
        let mut tri = [RasterVertex::default(); 3];
        let mut idx = [0u32; 3];
        for (k, v) in vs.iter().enumerate() {
            let p = v.position();
            idx[k] = v.data().index;
            tri[k] = RasterVertex {
                pos: [p.x * scale[0], p.y * scale[1]],
                colour: colour_of(colours, channels, idx[k] as usize),
            };
        }
        let first = (0..3).min_by_key(|&k| idx[k]).unwrap_or(0);
        tri.rotate_left(first);
        out.push(tri);
    }
    out
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
    let mut out = Vec::with_capacity(positions.len() * 2 + 8);
    for cell in cells.iter() {
        cell_fan(cell, positions, colours, channels, scale, &mut |t| {
            out.push(*t)
        });
    }
    out
}

/// The triangles of one cell (see [`cell_triangles`]), given to `f` in order.
#[inline]
fn cell_fan(
    cell: &[u32],
    positions: &[Point],
    colours: &[u8],
    channels: usize,
    scale: [f64; 2],
    f: &mut dyn FnMut(&RasterTriangle),
) {
    let vertex = |i: u32| {
        let p = positions.get(i as usize).copied().unwrap_or_default();
        RasterVertex {
            pos: [p[0] * scale[0], p[1] * scale[1]],
            colour: colour_of(colours, channels, i as usize),
        }
    };
    let k = cell.len();
    if k < 3 {
        return;
    }
    if k == 3 {
        f(&[vertex(cell[0]), vertex(cell[1]), vertex(cell[2])]);
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
    let mut prev = vertex(cell[0]);
    for s in 0..k {
        let next = vertex(cell[(s + 1) % k]);
        f(&[centre, prev, next]);
        prev = next;
    }
}

/// Renders `mesh` by Gouraud shading into `frame`'s output: over the canonical `cells` when
/// given (their vertices index `positions`), else over `mesh`'s own triangles. Each cell (or
/// triangle) is set up afresh in every band of rows it touches, so nothing per triangle is
/// kept in memory.
pub(crate) fn render(
    mesh: &Triangulation,
    cells: Option<&Cells>,
    positions: &[Point],
    frame: &Frame<'_>,
    parallel: bool,
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
    let finish = |band: &mut Band<'_>| fill_unpainted(band, frame, &boundary);
    let y = |p: Point| p[1] * scale[1];
    match cells {
        Some(cells) => {
            let extent = |k: usize| {
                let cell = cells.get(k).unwrap_or(&[]);
                let ys = cell.iter().map(|&i| y(positions[i as usize]));
                ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                })
            };
            let emit = |k: usize, f: &mut dyn FnMut(&RasterTriangle)| {
                if let Some(cell) = cells.get(k) {
                    cell_fan(cell, positions, colours, c, scale, f);
                }
            };
            raster::paint_groups(cells.len(), extent, emit, (w, h, c), parallel, finish).0
        }
        None => {
            let tris = triangles(mesh, colours, c, scale);
            let extent = |k: usize| {
                let ys = tris[k].map(|v| v.pos[1]);
                (ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]))
            };
            let emit = |k: usize, f: &mut dyn FnMut(&RasterTriangle)| f(&tris[k]);
            raster::paint_groups(tris.len(), extent, emit, (w, h, c), parallel, finish).0
        }
    }
}
