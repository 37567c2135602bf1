//! "Paint strokes": Gouraud shading with sharpened barycentric weights.

use image::{Rgb, RgbImage};

use super::{check, colour, fill_convex, fill_uncovered, Scale, Sites, Triangulation};
use crate::Result;

/// The sharpness [`strokes`] uses.
pub const DEFAULT_SHARPNESS: f64 = 4.0;

/// Paint strokes with [`DEFAULT_SHARPNESS`]; see [`strokes_with`].
///
/// ```
/// let sites = [[0.0, 0.0], [20.0, 0.0], [0.0, 20.0], [20.0, 20.0]];
/// let colours = [0, 0, 0, 255, 255, 255, 0, 0, 0, 255, 255, 255];
/// let img = qcs_lab::styles::strokes(&sites, &colours, (20, 20), (20, 20)).unwrap();
/// assert!(img.get_pixel(1, 10).0[0] < 20); // near the black sites: black
/// ```
pub fn strokes<'a>(
    sites: impl Into<Sites<'a>>,
    colours: &[u8],
    source: (u32, u32),
    output: (u32, u32),
) -> Result<RgbImage> {
    strokes_with(sites, colours, source, output, DEFAULT_SHARPNESS)
}

/// Paint strokes: geometric subdivision of each cell plus nonlinear interpolation.
///
/// Each cell is fanned into triangles and every output pixel is shaded from
/// its triangle's three site colours with the weights `λᵢ^s / Σ λⱼ^s`, where
/// `λ` are the pixel's barycentric coordinates and `s = sharpness` (`s = 1` is
/// Gouraud shading, larger `s` keeps each site's colour flat over the part of
/// the triangle nearest to it and makes the transitions between sampled colours
/// steep, like overlapping brush strokes). This is the limit of subdividing each
/// triangle ever finer and interpolating linearly between sharpened vertex
/// weights. Pixels outside the convex hull take the nearest site's colour.
/// `sharpness` is clamped to `[1, 64]`.
///
/// ```
/// let sites = [[0.0, 0.0], [20.0, 0.0], [0.0, 20.0]];
/// let colours = [255, 0, 0, 0, 255, 0, 0, 0, 255];
/// let flat = qcs_lab::styles::strokes_with(&sites, &colours, (20, 20), (20, 20), 1.0).unwrap();
/// let sharp = qcs_lab::styles::strokes_with(&sites, &colours, (20, 20), (20, 20), 8.0).unwrap();
/// assert!(sharp.get_pixel(3, 3).0[0] > flat.get_pixel(3, 3).0[0]);
/// ```
pub fn strokes_with<'a>(
    sites: impl Into<Sites<'a>>,
    colours: &[u8],
    source: (u32, u32),
    output: (u32, u32),
    sharpness: f64,
) -> Result<RgbImage> {
    let sites = sites.into();
    let positions = sites.positions();
    check(positions, Some(colours), source, output)?;
    let s = if sharpness.is_finite() {
        sharpness.clamp(1.0, 64.0)
    } else {
        DEFAULT_SHARPNESS
    };
    let frame = Scale::new(source, output);
    let mut img = RgbImage::new(output.0, output.1);
    let mut covered = vec![false; output.0 as usize * output.1 as usize];
    if positions.is_empty() {
        return Ok(img);
    }
    let tri = Triangulation::of(sites)?;
    for t in tri.triangles() {
        let p = t.map(|k| frame.to_out(positions[k]));
        let c = t.map(|k| colour(colours, k));
        let det =
            (p[1][1] - p[2][1]) * (p[0][0] - p[2][0]) + (p[2][0] - p[1][0]) * (p[0][1] - p[2][1]);
        if det == 0.0 {
            continue;
        }
        fill_convex(&p, frame.w, frame.h, |i, j| {
            let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
            let l0 =
                ((p[1][1] - p[2][1]) * (x - p[2][0]) + (p[2][0] - p[1][0]) * (y - p[2][1])) / det;
            let l1 =
                ((p[2][1] - p[0][1]) * (x - p[2][0]) + (p[0][0] - p[2][0]) * (y - p[2][1])) / det;
            let l = [l0.max(0.0), l1.max(0.0), (1.0 - l0 - l1).max(0.0)];
            let wts = l.map(|v| v.powf(s));
            let sum: f64 = wts.iter().sum();
            let mut out = [0u8; 3];
            for (ch, o) in out.iter_mut().enumerate() {
                let v = if sum > 0.0 {
                    (0..3).map(|k| wts[k] * c[k][ch] as f64).sum::<f64>() / sum
                } else {
                    c[0][ch] as f64
                };
                *o = v.round().clamp(0.0, 255.0) as u8;
            }
            img.put_pixel(i, j, Rgb(out));
            covered[(j * frame.w + i) as usize] = true;
        });
    }
    fill_uncovered(&mut img, &covered, &tri, colours, &frame);
    Ok(img)
}
