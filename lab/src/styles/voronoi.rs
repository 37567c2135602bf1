//! Voronoi diagram of the sites, cells filled with their sample colour.

use image::{Rgb, RgbImage};

use super::{check, colour, Scale, Sites, Triangulation, INK};
use crate::Result;

/// Voronoi diagram: each output pixel takes the colour of its nearest site, and
/// pixels with a 4-neighbour in another cell are drawn dark ([`INK`]) as edges.
///
/// ```
/// let sites = [[2.0, 5.0], [8.0, 5.0]];
/// let colours = [255, 0, 0, 0, 0, 255];
/// let img = qcs_lab::styles::voronoi(&sites, &colours, (10, 10), (10, 10)).unwrap();
/// assert_eq!(img.get_pixel(1, 5).0, [255, 0, 0]);
/// assert_eq!(img.get_pixel(8, 5).0, [0, 0, 255]);
/// assert_eq!(img.get_pixel(4, 5).0, qcs_lab::styles::INK);
/// ```
pub fn voronoi<'a>(
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
    if positions.is_empty() {
        return Ok(img);
    }
    let tri = Triangulation::of(sites)?;
    let (w, h) = (output.0 as usize, output.1 as usize);
    let mut owner = vec![0usize; w * h];
    for j in 0..h {
        for i in 0..w {
            owner[j * w + i] = tri
                .nearest(frame.to_source(i as u32, j as u32))
                .unwrap_or(0);
        }
    }
    for j in 0..h {
        for i in 0..w {
            let k = owner[j * w + i];
            let edge = (i + 1 < w && owner[j * w + i + 1] != k)
                || (j + 1 < h && owner[(j + 1) * w + i] != k);
            let c = if edge { INK } else { colour(colours, k) };
            img.put_pixel(i as u32, j as u32, Rgb(c));
        }
    }
    Ok(img)
}
