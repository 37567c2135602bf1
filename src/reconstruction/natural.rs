//! Sibson natural-neighbour interpolation (spade's weights), with the hull rule outside.

use spade::{Point2, Triangulation as _};

use super::hull::{colour_of, Boundary};
use super::mesh::SampleMesh;
use super::{per_pixel, Output};

/// Renders `mesh` by natural-neighbour interpolation into `frame`'s output.
pub(crate) fn render(mesh: &SampleMesh, frame: &Output<'_>, parallel: bool) -> Vec<u8> {
    let boundary = Boundary::new(mesh, frame.colours, frame.channels);
    let c = frame.channels;
    per_pixel(
        frame,
        parallel,
        || (mesh.natural_neighbor(), Vec::new(), 0usize),
        |(nn, weights, hint), q| {
            nn.get_weights(Point2::new(q[0], q[1]), weights);
            if weights.is_empty() {
                return boundary.colour(q, hint);
            }
            let mut acc = [0f64; 4];
            for (v, wt) in weights.iter() {
                let col = colour_of(frame.colours, c, mesh.vertex(*v).data().index as usize);
                for k in 0..4 {
                    acc[k] += *wt * col[k] as f64;
                }
            }
            acc.map(|a| a as f32)
        },
    )
}
