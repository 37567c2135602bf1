//! Gouraud shading: linear interpolation over the Delaunay triangles, by scan conversion.
//!
//! With exact lattice points the triangles are those of the canonical Delaunay cells
//! ([`Cells`]): a cell with k ≥ 4 vertices is drawn as k triangles around its vertex centroid,
//! whose colour is the mean of the k vertex colours (`spec/reconstruction.md`).

use rayon::prelude::*;
use spade::Triangulation as _;

use super::cells::Cells;
use super::hull::{colour_of, Boundary};
use super::mesh::Triangulation;
use super::raster::{self, Band, RasterTriangle, RasterVertex, Setup};
use super::{band_rows, fill_unpainted, Frame};
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
    let vertex = |i: u32| {
        let p = positions.get(i as usize).copied().unwrap_or_default();
        RasterVertex {
            pos: [p[0] * scale[0], p[1] * scale[1]],
            colour: colour_of(colours, channels, i as usize),
        }
    };
    let mut out = Vec::with_capacity(positions.len() * 2 + 8);
    for cell in cells.iter() {
        let k = cell.len();
        if k < 3 {
            continue;
        }
        if k == 3 {
            out.push([vertex(cell[0]), vertex(cell[1]), vertex(cell[2])]);
            continue;
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
        for s in 0..k {
            out.push([centre, vertex(cell[s]), vertex(cell[(s + 1) % k])]);
        }
    }
    out
}

/// Renders `mesh` by Gouraud shading into `frame`'s output: over the canonical `cells` when
/// given (their vertices index `positions`), else over `mesh`'s own triangles.
pub(crate) fn render(
    mesh: &Triangulation,
    cells: Option<&Cells>,
    positions: &[Point],
    frame: &Frame<'_>,
    parallel: bool,
) -> Vec<u8> {
    let (w, h, c) = (frame.width, frame.height, frame.channels);
    let mut out = vec![0u8; w * h * c];
    let scale = [1.0 / frame.sx, 1.0 / frame.sy];
    let tris = match cells {
        Some(cells) => cell_triangles(cells, positions, frame.colours, c, scale),
        None => triangles(mesh, frame.colours, c, scale),
    };
    let setups = raster::setups(&tris);
    drop(tris);
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
            Boundary::from_edges(edges, frame.colours, c)
        }
        None => Boundary::new(mesh, frame.colours, c),
    };
    if !parallel {
        let mut painted = vec![false; w * h];
        let mut band = Band {
            width: w,
            row0: 0,
            rows: h,
            channels: c,
            pixels: &mut out,
            painted: &mut painted,
        };
        raster::paint(&mut setups.iter(), &mut band);
        fill_unpainted(&mut band, frame, &boundary);
        return out;
    }
    let rows = band_rows(h);
    let nbands = h.div_ceil(rows);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nbands];
    for (k, s) in setups.iter().enumerate() {
        let (r0, r1) = s.rows;
        if r1 < 0 || r0 >= h as i64 {
            continue;
        }
        let b0 = r0.max(0) as usize / rows;
        let b1 = (r1.min(h as i64 - 1) as usize) / rows;
        for bin in &mut bins[b0..=b1] {
            bin.push(k as u32);
        }
    }
    out.par_chunks_mut(rows * w * c)
        .zip(bins.par_iter())
        .enumerate()
        .for_each(|(b, (chunk, bin))| {
            let n = chunk.len() / (w * c);
            let mut painted = vec![false; n * w];
            let mut band = Band {
                width: w,
                row0: b * rows,
                rows: n,
                channels: c,
                pixels: chunk,
                painted: &mut painted,
            };
            let mut it = bin.iter().map(|&k| &setups[k as usize]);
            raster::paint(&mut it as &mut dyn Iterator<Item = &Setup>, &mut band);
            fill_unpainted(&mut band, frame, &boundary);
        });
    out
}
