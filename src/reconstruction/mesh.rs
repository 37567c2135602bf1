//! The Delaunay triangulation of the samples, kept across renders and grown lazily.

use spade::{
    DelaunayTriangulation, HasPosition, HierarchyHintGenerator, Point2, Triangulation as _,
};

use crate::sites::Point;

/// A vertex of the [`SampleMesh`]: a sample position (source pixels) and the
/// index of the sample in its [`SampleSet`](super::SampleSet).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// Position in source-image pixel coordinates.
    pub position: Point2<f64>,
    /// Index of the sample (push order) whose colour this vertex carries.
    pub index: u32,
}

impl HasPosition for Vertex {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.position
    }
}

/// The Delaunay triangulation used by every method, in source pixel coordinates.
pub type SampleMesh = DelaunayTriangulation<Vertex, (), (), (), HierarchyHintGenerator<f64>>;

/// Makes a position acceptable to `spade`, or `None` if it cannot be (NaN, ±∞, beyond spade's range).
pub(crate) fn sanitize(pos: Point) -> Option<Point> {
    let p = spade::mitigate_underflow(Point2::new(pos[0], pos[1]));
    if spade::validate_coordinate(p.x).is_ok() && spade::validate_coordinate(p.y).is_ok() {
        Some([p.x, p.y])
    } else {
        None
    }
}

/// Brings `mesh` up to date with `positions[*synced..]`.
///
/// An empty mesh is bulk loaded (stable, so duplicates keep the first sample); a non-empty one
/// gets the new samples inserted one by one (the hierarchy makes each insertion O(log n)).
/// A position that is already a vertex keeps its first sample (spade would overwrite it).
pub(crate) fn sync(mesh: &mut SampleMesh, positions: &[Point], synced: &mut usize) {
    if *synced >= positions.len() {
        return;
    }
    let new = &positions[*synced..];
    let base = *synced;
    // Under `cfg(fuzzing)` (cargo-fuzz sets it for every crate) spade checks its bulk-load
    // hull after every vertex, which is quadratic: a 3199×2 image's 768 samples and their
    // mirror points took 3 s. Fuzz builds insert one by one instead (same cells).
    if mesh.num_vertices() == 0 && new.len() > 16 && !cfg!(fuzzing) {
        let vertices: Vec<Vertex> = new
            .iter()
            .enumerate()
            .map(|(k, p)| Vertex {
                position: Point2::new(p[0], p[1]),
                index: (base + k) as u32,
            })
            .collect();
        // Positions were sanitized on push, so bulk loading cannot fail; fall back to
        // insertion anyway rather than panic.
        match SampleMesh::bulk_load_stable(vertices) {
            Ok(t) => {
                *mesh = t;
                *synced = positions.len();
                return;
            }
            Err(_) => *mesh = SampleMesh::new(),
        }
    }
    for (k, p) in new.iter().enumerate() {
        let position = Point2::new(p[0], p[1]);
        if mesh.locate_vertex(position).is_some() {
            continue;
        }
        let v = Vertex {
            position,
            index: (base + k) as u32,
        };
        // Progressive sites are spread over the whole image, so the hierarchy (not the last
        // vertex) gives the best starting point; a rejected vertex is simply not triangulated.
        let _ = mesh.insert(v);
    }
    *synced = positions.len();
}
