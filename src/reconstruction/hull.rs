//! The colour of points outside the convex hull of the samples.
//!
//! **Rule**: a point outside the hull takes the colour of the nearest point of the hull boundary
//! (Euclidean distance in source pixel coordinates), and along a hull edge colours are linear
//! between the edge's two end samples. This continues the Gouraud interpolation (which is the
//! same linear function on the hull edge) without a seam, and leaves no black border.
//! Degenerate sets use the same rule on their "boundary": one sample is a single point (so the
//! whole picture takes its colour), collinear samples are the polyline through them in order
//! along the line.

use spade::Triangulation as _;

use super::mesh::SampleMesh;

/// One piece of the boundary: end points (source pixels) and their colours.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Segment {
    a: [f64; 2],
    d: [f64; 2],
    inv_len2: f64,
    ca: [f32; 4],
    cb: [f32; 4],
}

impl Segment {
    fn new(a: [f64; 2], b: [f64; 2], ca: [f32; 4], cb: [f32; 4]) -> Segment {
        let d = [b[0] - a[0], b[1] - a[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let inv_len2 = if l2 > 0.0 { 1.0 / l2 } else { 0.0 };
        Segment {
            a,
            d,
            inv_len2,
            ca,
            cb,
        }
    }

    /// Squared distance from `q` and the parameter of the nearest point.
    #[inline]
    fn nearest(&self, q: [f64; 2]) -> (f64, f64) {
        let (qx, qy) = (q[0] - self.a[0], q[1] - self.a[1]);
        let t = ((qx * self.d[0] + qy * self.d[1]) * self.inv_len2).clamp(0.0, 1.0);
        let (ex, ey) = (qx - t * self.d[0], qy - t * self.d[1]);
        (ex * ex + ey * ey, t)
    }
}

/// The boundary of the samples' hull, ready for nearest-point queries.
#[derive(Clone, Debug, Default)]
pub(crate) struct Boundary {
    segments: Vec<Segment>,
}

/// Colour of sample `index` as `f32`s.
#[inline]
pub(crate) fn colour_of(colours: &[u8], channels: usize, index: usize) -> [f32; 4] {
    let mut c = [0f32; 4];
    if let Some(s) = colours.get(index * channels..index * channels + channels) {
        for (k, v) in s.iter().enumerate() {
            c[k] = *v as f32;
        }
    }
    c
}

impl Boundary {
    /// The hull boundary of `mesh` (see the module rule for degenerate sets).
    pub(crate) fn new(mesh: &SampleMesh, colours: &[u8], channels: usize) -> Boundary {
        let vertex = |v: spade::handles::VertexHandle<'_, super::mesh::Vertex>| {
            let p = v.position();
            (
                [p.x, p.y],
                colour_of(colours, channels, v.data().index as usize),
            )
        };
        let mut segments = Vec::new();
        if mesh.num_vertices() == 0 {
        } else if !mesh.all_vertices_on_line() {
            for e in mesh.convex_hull() {
                let (a, ca) = vertex(e.from());
                let (b, cb) = vertex(e.to());
                // Canonical direction, so the value on an edge does not depend on spade's order.
                if (a[0], a[1]) <= (b[0], b[1]) {
                    segments.push(Segment::new(a, b, ca, cb));
                } else {
                    segments.push(Segment::new(b, a, cb, ca));
                }
            }
        } else {
            let mut pts: Vec<([f64; 2], [f32; 4])> = mesh.vertices().map(vertex).collect();
            pts.sort_by(|p, q| {
                (p.0[0], p.0[1])
                    .partial_cmp(&(q.0[0], q.0[1]))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            if pts.len() == 1 {
                segments.push(Segment::new(pts[0].0, pts[0].0, pts[0].1, pts[0].1));
            }
            for w in pts.windows(2) {
                segments.push(Segment::new(w[0].0, w[1].0, w[0].1, w[1].1));
            }
        }
        Boundary { segments }
    }

    /// The boundary made of the given hull edges (end points in source pixels, sample indices).
    pub(crate) fn from_edges(
        edges: impl Iterator<Item = ([f64; 2], [f64; 2], usize, usize)>,
        colours: &[u8],
        channels: usize,
    ) -> Boundary {
        let segments = edges
            .map(|(a, b, ia, ib)| {
                let (ca, cb) = (
                    colour_of(colours, channels, ia),
                    colour_of(colours, channels, ib),
                );
                Segment::new(a, b, ca, cb)
            })
            .collect();
        Boundary { segments }
    }

    /// Whether every point of `qs` (source pixels) is inside the hull, farther than rounding
    /// from its boundary (never for a degenerate hull: one point or a polyline).
    pub(crate) fn contains(&self, qs: &[[f64; 2]]) -> bool {
        let n = self.segments.len();
        if n < 3 {
            return false;
        }
        // The mean of the hull's vertices (each is the end of two edges) is strictly inside.
        let mut g = [0.0; 2];
        for s in &self.segments {
            g[0] += s.a[0] + 0.5 * s.d[0];
            g[1] += s.a[1] + 0.5 * s.d[1];
        }
        let g = g.map(|v| v / n as f64);
        let cross = |s: &Segment, q: [f64; 2]| s.d[0] * (q[1] - s.a[1]) - s.d[1] * (q[0] - s.a[0]);
        self.segments.iter().all(|s| {
            let inner = cross(s, g);
            qs.iter().all(|&q| {
                let size = 1.0 + s.a[0].abs().max(s.a[1].abs()) + q[0].abs().max(q[1].abs());
                let margin = 1e-9 * size * s.d[0].hypot(s.d[1]);
                cross(s, q) * inner.signum() > margin && inner.abs() > margin
            })
        })
    }

    /// Whether there is no sample at all.
    pub(crate) fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// Colour at `q` (source pixels) by the outside rule; `hint` is the segment that was nearest
    /// for the previous query (consecutive pixels usually share it) and is updated.
    #[inline]
    pub(crate) fn colour(&self, q: [f64; 2], hint: &mut usize) -> [f32; 4] {
        let n = self.segments.len();
        if n == 0 {
            return [128.0; 4];
        }
        let mut best = (*hint).min(n - 1);
        let (mut bd, mut bt) = self.segments[best].nearest(q);
        for (k, s) in self.segments.iter().enumerate() {
            let (d, t) = s.nearest(q);
            if d < bd || (d == bd && k < best) {
                bd = d;
                bt = t;
                best = k;
            }
        }
        *hint = best;
        let s = &self.segments[best];
        let t = bt as f32;
        let mut c = [0f32; 4];
        for k in 0..4 {
            c[k] = s.ca[k] + t * (s.cb[k] - s.ca[k]);
        }
        c
    }
}
