//! Farthest point sampling through an incremental Delaunay triangulation.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use spade::{DelaunayTriangulation, HierarchyHintGenerator, Point2, Triangulation};

use super::{clamp_open, unit_pair};
use crate::samplers::Sampler;
use qcs::sites::Point;

/// Farthest point sampling: each new site is the point of the domain farthest
/// from all previous sites (the centre of the largest empty circle).
///
/// **Domain and boundary.** The domain is the rectangle spanned by the pixel
/// centres, `[0.5, W−0.5] × [0.5, H−0.5]` (so every site lies inside
/// `[0, W) × [0, H)` and corner sites sit on corner pixel centres, as in a discrete
/// FPS over pixels). The farthest point of a rectangle from a finite set is one
/// of: a Voronoi vertex inside the rectangle (a Delaunay circumcentre, at the
/// triangle's circumradius from every site), a point where a Voronoi edge crosses
/// the rectangle's boundary (at equal distance from the edge's two sites), or a
/// corner of the rectangle. Circumcentres outside the rectangle are therefore
/// replaced by the boundary crossings of the Voronoi edges around them.
///
/// **Algorithm.** A max-heap holds candidates with their distance at the time
/// they were created. After each insertion only the faces around the new site
/// change, so only their circumcentres and the boundary crossings of their edges
/// are pushed; stale entries are invalidated lazily: the top candidate is
/// accepted only if its current nearest-site distance (a spade nearest-neighbour
/// query) still equals the stored one — stored values only over-estimate, so an
/// accepted top is the true maximum. Corners are re-pushed with their current
/// distance. Cost: `O(n log n)` expected.
///
/// The first site is uniform in the domain, drawn from `seed`. If the domain is
/// exhausted (every point within 1e−9 px of a site, which needs far more sites
/// than pixels), the remaining sites are drawn uniformly at random.
#[derive(Clone, Copy, Debug, Default)]
pub struct FarthestPoint {
    /// Seed of the first site.
    pub seed: u64,
}

type Tri = DelaunayTriangulation<Point2<f64>, (), (), (), HierarchyHintGenerator<f64>>;

#[derive(Clone, Copy, Debug)]
struct Candidate {
    dist: f64,
    p: [f64; 2],
    corner: bool,
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> Ordering {
        self.dist
            .total_cmp(&other.dist)
            .then_with(|| other.p[1].total_cmp(&self.p[1]))
            .then_with(|| other.p[0].total_cmp(&self.p[0]))
    }
}

#[derive(Clone, Copy)]
struct Rect {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Rect {
    fn contains(&self, p: [f64; 2]) -> bool {
        p[0] >= self.x0 && p[0] <= self.x1 && p[1] >= self.y0 && p[1] <= self.y1
    }
    fn clamp(&self, p: [f64; 2]) -> [f64; 2] {
        [p[0].clamp(self.x0, self.x1), p[1].clamp(self.y0, self.y1)]
    }
    /// Points where `o + t·d`, `t ∈ [t0, t1]`, meets the rectangle's boundary.
    fn crossings(&self, o: [f64; 2], d: [f64; 2], t0: f64, t1: f64, out: &mut Vec<[f64; 2]>) {
        let eps = 1e-12 * (1.0 + self.x1.abs() + self.y1.abs());
        for (axis, value) in [(0, self.x0), (0, self.x1), (1, self.y0), (1, self.y1)] {
            if d[axis] == 0.0 {
                continue;
            }
            let t = (value - o[axis]) / d[axis];
            if !(t >= t0 && t <= t1) {
                continue;
            }
            let other = 1 - axis;
            let v = o[other] + t * d[other];
            let (lo, hi) = if other == 0 {
                (self.x0, self.x1)
            } else {
                (self.y0, self.y1)
            };
            if v >= lo - eps && v <= hi + eps {
                let mut p = [0.0; 2];
                p[axis] = value;
                p[other] = v;
                out.push(self.clamp(p));
            }
        }
    }
}

fn dist(a: [f64; 2], b: Point2<f64>) -> f64 {
    ((a[0] - b.x).powi(2) + (a[1] - b.y).powi(2)).sqrt()
}

fn nearest_dist(t: &Tri, p: [f64; 2]) -> f64 {
    t.nearest_neighbor(Point2::new(p[0], p[1]))
        .map_or(f64::INFINITY, |v| dist(p, v.position()))
}

/// Pushes the candidates created by inserting the vertex with index `v`.
fn push_candidates(
    t: &Tri,
    v: spade::handles::FixedVertexHandle,
    rect: &Rect,
    heap: &mut BinaryHeap<Candidate>,
) {
    let mut crossings = Vec::new();
    let vertex = t.vertex(v);
    for e in vertex.out_edges() {
        if let Some(face) = e.face().as_inner() {
            let c = face.circumcenter();
            let c = [c.x, c.y];
            if rect.contains(c) {
                let d = dist(c, face.vertices()[0].position());
                heap.push(Candidate {
                    dist: d,
                    p: c,
                    corner: false,
                });
            }
        }
        for edge in [e, e.next()] {
            crossings.clear();
            let [a, b] = [edge.from().position(), edge.to().position()];
            let normal = [-(b.y - a.y), b.x - a.x];
            let left = edge.face().as_inner().map(|f| f.circumcenter());
            let right = edge.rev().face().as_inner().map(|f| f.circumcenter());
            match (left, right) {
                (Some(l), Some(r)) => {
                    rect.crossings([l.x, l.y], [r.x - l.x, r.y - l.y], 0.0, 1.0, &mut crossings)
                }
                (Some(c), None) | (None, Some(c)) => {
                    // Hull edge: the Voronoi ray leaves the inner face's circumcentre outwards.
                    let inner_left = left.is_some();
                    // `normal` points to the left of a→b; the outer side is the right when the inner face is left.
                    let dir = if inner_left {
                        [-normal[0], -normal[1]]
                    } else {
                        normal
                    };
                    rect.crossings([c.x, c.y], dir, 0.0, f64::INFINITY, &mut crossings)
                }
                (None, None) => {
                    let m = [(a.x + b.x) / 2.0, (a.y + b.y) / 2.0];
                    rect.crossings(m, normal, f64::NEG_INFINITY, f64::INFINITY, &mut crossings)
                }
            }
            for &p in &crossings {
                heap.push(Candidate {
                    dist: dist(p, a),
                    p,
                    corner: false,
                });
            }
        }
    }
}

impl Sampler for FarthestPoint {
    fn sites(&self, width: u32, height: u32, count: usize) -> Vec<Point> {
        if width == 0 || height == 0 || count == 0 {
            return Vec::new();
        }
        let (w, h) = (width as f64, height as f64);
        let rect = Rect {
            x0: 0.5,
            x1: w - 0.5,
            y0: 0.5,
            y1: h - 0.5,
        };
        let mut out = Vec::with_capacity(count.min(1 << 26));
        let (u, v) = unit_pair(self.seed, 3, 0);
        let first = [
            rect.x0 + u * (rect.x1 - rect.x0),
            rect.y0 + v * (rect.y1 - rect.y0),
        ];
        out.push(first);
        let mut t = Tri::new();
        let mut heap = BinaryHeap::new();
        match t.insert(Point2::new(first[0], first[1])) {
            Ok(_) => {
                for p in [
                    [rect.x0, rect.y0],
                    [rect.x1, rect.y0],
                    [rect.x0, rect.y1],
                    [rect.x1, rect.y1],
                ] {
                    heap.push(Candidate {
                        dist: dist(p, Point2::new(first[0], first[1])),
                        p,
                        corner: true,
                    });
                }
            }
            Err(_) => heap.clear(),
        }
        while out.len() < count {
            let Some(top) = heap.pop() else { break };
            let now = nearest_dist(&t, top.p);
            let tol = 1e-9 * top.dist.max(1.0);
            if now < top.dist - tol {
                if top.corner {
                    heap.push(Candidate { dist: now, ..top });
                }
                continue;
            }
            if now <= 1e-9 {
                break;
            }
            let Ok(handle) = t.insert(Point2::new(top.p[0], top.p[1])) else {
                break;
            };
            out.push(top.p);
            push_candidates(&t, handle, &rect, &mut heap);
        }
        // Exhausted domain (or a failed insertion): fill with uniform sites.
        let mut n = 0u64;
        while out.len() < count {
            let (u, v) = unit_pair(self.seed, 4, n);
            n += 1;
            out.push([clamp_open(u * w, w), clamp_open(v * h, h)]);
        }
        out
    }
    fn name(&self) -> &'static str {
        "farthest"
    }
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn farthest_points_keep_their_distance() {
        use crate::samplers::{FarthestPoint, Sampler};
        let s = FarthestPoint { seed: 1 }.sites(64, 64, 200);
        let min = (0..s.len())
            .flat_map(|i| (0..i).map(move |j| (i, j)))
            .map(|(i, j)| ((s[i][0] - s[j][0]).powi(2) + (s[i][1] - s[j][1]).powi(2)).sqrt())
            .fold(f64::INFINITY, f64::min);
        assert!(min > 0.7 * (64.0 * 64.0 / 200.0f64).sqrt());
    }
}
