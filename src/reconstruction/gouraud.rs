//! Gouraud shading: linear interpolation over the Delaunay triangles, by scan conversion.

use rayon::prelude::*;
use spade::Triangulation as _;

use super::hull::{colour_of, Boundary};
use super::mesh::Triangulation;
use super::raster::{self, Band, RasterTriangle, RasterVertex, Setup};
use super::{band_rows, fill_unpainted, Frame};

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

/// Renders `mesh` by Gouraud shading into `frame`'s output.
pub(crate) fn render(mesh: &Triangulation, frame: &Frame<'_>, parallel: bool) -> Vec<u8> {
    let (w, h, c) = (frame.width, frame.height, frame.channels);
    let mut out = vec![0u8; w * h * c];
    let scale = [1.0 / frame.sx, 1.0 / frame.sy];
    let tris = triangles(mesh, frame.colours, c, scale);
    let setups = raster::setups(&tris);
    drop(tris);
    let boundary = Boundary::new(mesh, frame.colours, c);
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
