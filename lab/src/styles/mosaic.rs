//! The paper's mosaic rendering (Fig. 6, far right).

use image::{Rgb, RgbImage};

use super::{check, colour, fill_convex, fill_uncovered, Scale, Sites, Triangulation, INK};
use crate::Result;

/// Mosaic: every cell is split at its edge midpoints; the triangle at each
/// vertex takes that vertex's sampled colour and the central piece (for a
/// Delaunay triangle, the midpoint triangle) is black grout ([`INK`]). Each site
/// thus gets a star-shaped tile made of its corner pieces.
///
/// Pixels outside the convex hull of the sites take the nearest site's colour.
///
/// ```
/// let sites = [[1.0, 1.0], [9.0, 1.0], [1.0, 9.0], [9.0, 9.0]];
/// let colours = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
/// let img = qcs_lab::styles::mosaic(&sites, &colours, (10, 10), (10, 10)).unwrap();
/// assert_eq!(img.get_pixel(1, 1).0, [255, 0, 0]);
/// ```
pub fn mosaic<'a>(
    sites: impl Into<Sites<'a>>,
    colours: &[u8],
    source: (u32, u32),
    output: (u32, u32),
) -> Result<RgbImage> {
    let sites = sites.into();
    let positions = sites.positions();
    check(positions, Some(colours), source, output)?;
    let frame = Scale::new(source, output);
    let mut img = RgbImage::new(output.0, output.1);
    let mut covered = vec![false; output.0 as usize * output.1 as usize];
    if positions.is_empty() {
        return Ok(img);
    }
    let tri = Triangulation::of(sites)?;
    for cell in tri.cells() {
        let n = cell.len();
        let pts: Vec<[f64; 2]> = cell.iter().map(|&k| frame.to_out(positions[k])).collect();
        let mid =
            |a: usize, b: usize| [(pts[a][0] + pts[b][0]) / 2.0, (pts[a][1] + pts[b][1]) / 2.0];
        for k in 0..n {
            let prev = (k + n - 1) % n;
            let next = (k + 1) % n;
            let piece = [pts[k], mid(k, next), mid(prev, k)];
            let c = colour(colours, cell[k]);
            fill_convex(&piece, frame.w, frame.h, |i, j| {
                img.put_pixel(i, j, Rgb(c));
                covered[(j * frame.w + i) as usize] = true;
            });
        }
        let centre: Vec<[f64; 2]> = (0..n).map(|k| mid(k, (k + 1) % n)).collect();
        fill_convex(&centre, frame.w, frame.h, |i, j| {
            img.put_pixel(i, j, Rgb(INK));
            covered[(j * frame.w + i) as usize] = true;
        });
    }
    fill_uncovered(&mut img, &covered, &tri, colours, &frame);
    Ok(img)
}
