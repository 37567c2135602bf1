//! Delaunay triangulation drawn as a graph, alone or over a picture.

use image::{Rgb, RgbImage};

use super::{check, draw_line, Scale, Sites, Triangulation, INK};
use crate::Result;

/// The Delaunay edges (dark, 1 px) on a white background.
///
/// ```
/// let sites = [[1.0, 1.0], [9.0, 1.0], [5.0, 9.0]];
/// let img = qcs_lab::styles::delaunay_graph(&sites, (10, 10), (10, 10)).unwrap();
/// assert_eq!(img.get_pixel(5, 1).0, qcs_lab::styles::INK);
/// assert_eq!(img.get_pixel(5, 5).0, [255, 255, 255]);
/// ```
pub fn delaunay_graph<'a>(
    sites: impl Into<Sites<'a>>,
    source: (u32, u32),
    output: (u32, u32),
) -> Result<RgbImage> {
    let sites = sites.into();
    let positions = sites.positions();
    check(positions, None, source, output)?;
    let background = RgbImage::from_pixel(output.0, output.1, Rgb([255, 255, 255]));
    delaunay_over(sites, source, &background)
}

/// The Delaunay edges drawn over `background` (the source image, a
/// reconstruction, …) at the background's size.
///
/// ```
/// let photo = image::RgbImage::from_pixel(20, 20, image::Rgb([10, 200, 10]));
/// let sites = [[1.0, 1.0], [9.0, 1.0], [5.0, 9.0]];
/// let img = qcs_lab::styles::delaunay_over(&sites, (10, 10), &photo).unwrap();
/// assert_eq!(img.get_pixel(10, 10).0, [10, 200, 10]);
/// assert_eq!(img.get_pixel(10, 2).0, qcs_lab::styles::INK);
/// ```
pub fn delaunay_over<'a>(
    sites: impl Into<Sites<'a>>,
    source: (u32, u32),
    background: &RgbImage,
) -> Result<RgbImage> {
    let sites = sites.into();
    let positions = sites.positions();
    let output = background.dimensions();
    check(positions, None, source, output)?;
    let frame = Scale::new(source, output);
    let mut img = background.clone();
    if positions.len() < 2 {
        return Ok(img);
    }
    let tri = Triangulation::of(sites)?;
    for [a, b] in tri.edges() {
        draw_line(
            &mut img,
            frame.to_out(positions[a]),
            frame.to_out(positions[b]),
            INK,
        );
    }
    Ok(img)
}
