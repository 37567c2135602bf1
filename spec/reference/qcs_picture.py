#!/usr/bin/env python3
"""The Gouraud picture of a `.qcs` file, written from the spec alone.

Written clean-room from spec/reconstruction.md (with spec/sites.md and spec/format.md, and
the conformance vectors), never from the Rust code, in Python with the standard library
only. The samples (sites, positions, colours) come from qcs_ref.py, the spec-only decoder of
the samples next to this file; this file adds the picture:

* reconstruction.md §2, the mirror points of the samples (exact lattice points);
* §3, the orientation and incircle signs, exact in Z[tau] with Python integers;
* §4, the canonical cells: a Delaunay triangulation of the points built with exact
  predicates (Bowyer-Watson with "ghost" triangles for the hull), then the triangles of
  every edge whose four points are cocircular merged into one cell;
* §5, the rule: a triangle is linear, a cell of k >= 4 vertices is a fan of k triangles
  around its vertex centroid with the mean colour, outside the hull the colour of the
  nearest hull point; each channel rounded half up and clamped.

Which pixel centre lies in which triangle, and the interpolation, are floating point
(the +-1 tolerance of §5 covers that). Written to be read, not to be fast.

Usage:
  python3 qcs_picture.py FILE.qcs [BYTES] > out.png          # the picture as a PNG
  python3 qcs_picture.py FILE.qcs [BYTES] --compare REF.png  # compare with a PNG (+-1)

BYTES cuts the file to its first BYTES bytes (a cut download); the picture is then that
of every sample qcs_ref.py reads from the prefix (verified levels plus the complete,
unverified samples of a partial level). The picture has the image's own size W x H and
the file's layout: grey, grey+alpha, RGB or RGBA, 8 bits per channel.
"""

import math
import os
import random
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import qcs_ref  # noqa: E402  (the samples: header, sites, colours)

ONE = 1 << 16   # 16.16 fixed point

# ---------------------------------------------------------------------------
# Z[tau] arithmetic (sites.md §1). An element a + b*tau is the pair (a, b).
# ---------------------------------------------------------------------------


def zt_add(x, y):
    return (x[0] + y[0], x[1] + y[1])


def zt_sub(x, y):
    return (x[0] - y[0], x[1] - y[1])


zt_mul = qcs_ref.zt_mul      # (a + b tau)(c + d tau), tau^2 = tau + 1
zt_sign = qcs_ref.zt_sign    # exact sign of a + b tau (sites.md §1, Signs)


def lattice_sub(n, m):
    return tuple(a - b for a, b in zip(n, m))


def norm2(n):
    """|x|^2 = p + q tau for x = sum n_k zeta^k (sites.md §1, the |y|^2 formula applied to
    the coordinates of x itself)."""
    n0, n1, n2, n3 = n
    S0 = n0 * n0 + n1 * n1 + n2 * n2 + n3 * n3
    A1 = n0 * n1 + n1 * n2 + n2 * n3
    A2 = n0 * n2 + n0 * n3 + n1 * n3
    return (S0 - A1, A1 - A2)


# ---------------------------------------------------------------------------
# reconstruction.md §3: the exact predicates
#
# With U = 2 Re x and V = Im x / sin72 (both in Z[tau]):
#   orient(a, b, c)       ~ D = U_p V_q - V_p U_q,         p = b - a, q = c - a
#   incircle(a, b, c, d)  ~ E = det [U_r  V_r  |r|^2],     r = a - d, b - d, c - d
# (both up to the positive factor sin72/2). D > 0: a, b, c counter-clockwise in the
# (Re, Im) plane. For a, b, c counter-clockwise, E > 0 iff d is strictly inside their
# circle, E = 0 iff the four are cocircular. Every sign is computed exactly, with Python
# integers (no floating-point filter: at the vectors' sizes it would save little).
# ---------------------------------------------------------------------------


class Point:
    """A point of the triangulation: a sample or a mirror point (reconstruction.md §2)."""
    __slots__ = ("n", "U", "V", "x", "y", "colour")

    def __init__(self, n, colour, L, Cx, Cy):
        self.n = n
        self.U = qcs_ref.re2(n)    # 2 Re x   (sites.md §1)
        self.V = qcs_ref.im_s(n)   # Im x / sin72
        self.x, self.y = qcs_ref.pixel_position(n, L, Cx, Cy)   # P(x), reconstruction.md §1
        self.colour = colour


def orient(a, b, c):
    """Sign of D for points a, b, c (reconstruction.md §3)."""
    Up, Vp = zt_sub(b.U, a.U), zt_sub(b.V, a.V)
    Uq, Vq = zt_sub(c.U, a.U), zt_sub(c.V, a.V)
    return zt_sign(*zt_sub(zt_mul(Up, Vq), zt_mul(Vp, Uq)))


def det3_zt(rows):
    """Exact 3x3 determinant over Z[tau]."""
    (a, b, c), (d, e, f), (g, h, i) = rows
    m = zt_mul
    t1 = m(a, zt_sub(m(e, i), m(f, h)))
    t2 = m(b, zt_sub(m(d, i), m(f, g)))
    t3 = m(c, zt_sub(m(d, h), m(e, g)))
    return zt_add(zt_sub(t1, t2), t3)


def incircle(a, b, c, d):
    """Sign of E for points a, b, c, d (reconstruction.md §3)."""
    rows = []
    for r in (a, b, c):
        diff = lattice_sub(r.n, d.n)
        rows.append((zt_sub(r.U, d.U), zt_sub(r.V, d.V), norm2(diff)))
    return zt_sign(*det3_zt(rows))


def strictly_between(a, b, p):
    """For p on the line through a and b: is p strictly between them? (Exact: the sign of
    (p - a).(b - a) and of (p - b).(a - b) in the (U, V) coordinates; for collinear points
    any positive scaling of the axes keeps these signs.)"""
    def dot_sign(o, u, v):
        du = zt_add(zt_mul(zt_sub(u.U, o.U), zt_sub(v.U, o.U)),
                    zt_mul(zt_sub(u.V, o.V), zt_sub(v.V, o.V)))
        return zt_sign(*du)
    return dot_sign(a, p, b) > 0 and dot_sign(b, p, a) > 0


# ---------------------------------------------------------------------------
# reconstruction.md §2: mirror points
# ---------------------------------------------------------------------------

def mirror_lines(W, H, L, Cx, Cy):
    """The four lattice mirror lines (reconstruction.md §2, table): integers
    (a_left, a_right) of the lines Re x = a/2 and (b_top, b_bottom) of Im x = b sin72."""
    # largest a with 2Cx + L a <= 0, smallest a with 2Cx + L a >= 2 W 2^16
    a_left = (-2 * Cx) // L
    a_right = -((2 * Cx - 2 * W * ONE) // L)

    def sign_row(c, b):
        # sign(c + sin72 * L * b): the form u + s v of sites.md §1, u = c, v = L b
        return qcs_ref.zt_sign_us((c, 0), (L * b, 0))

    s72 = math.sin(math.radians(72))
    # largest b with Cy + L sin72 b <= 0 (start from a float guess, settle exactly)
    b_top = math.floor(-Cy / (L * s72))
    while sign_row(Cy, b_top + 1) <= 0:
        b_top += 1
    while sign_row(Cy, b_top) > 0:
        b_top -= 1
    # smallest b with Cy + L sin72 b >= H 2^16
    b_bottom = math.ceil((H * ONE - Cy) / (L * s72))
    while sign_row(Cy - H * ONE, b_bottom - 1) >= 0:
        b_bottom -= 1
    while sign_row(Cy - H * ONE, b_bottom) < 0:
        b_bottom += 1
    return a_left, a_right, b_top, b_bottom


def conj(n):
    """Complex conjugate: (n0, n1, n2, n3) -> (n0 - n1, -n1, n3 - n1, n2 - n1)."""
    n0, n1, n2, n3 = n
    return (n0 - n1, -n1, n3 - n1, n2 - n1)


def reflect_vertical_line(n, a):
    """Across Re x = a/2: x -> a - conj(x)."""
    c = conj(n)
    return (a - c[0], -c[1], -c[2], -c[3])


def reflect_horizontal_line(n, b):
    """Across Im x = b sin72: x -> conj(x) + b (zeta - zeta^4), zeta - zeta^4 = (1, 2, 1, 1)."""
    c = conj(n)
    return (c[0] + b, c[1] + 2 * b, c[2] + b, c[3] + b)


def near_edges(k, X, Y, W, H):
    """Which edges sample k (0-based) at (X, Y) is near (reconstruction.md §2), decided in
    f64 exactly as written: A = 4 W H, X*X*(k+1) < A, etc."""
    A = float(4 * W * H)
    k1 = float(k + 1)
    left = X >= 0 and X * X * k1 < A
    right = W - X >= 0 and (W - X) * (W - X) * k1 < A
    top = Y >= 0 and Y * Y * k1 < A
    bottom = H - Y >= 0 and (H - Y) * (H - Y) * k1 < A
    return left, right, top, bottom


def points_of(samples, W, H, L, Cx, Cy):
    """The points of reconstruction.md §2 in order: each sample followed by its mirror
    points. samples = [(n, colour)] in file order. A point at the position (lattice point)
    of an earlier one is the same vertex (it keeps the earlier point's colour); a mirror
    point with a coordinate |n_k| >= 2^20 is left out."""
    a_left, a_right, b_top, b_bottom = mirror_lines(W, H, L, Cx, Cy)
    pts = []
    seen = set()

    def add(n, colour):
        if n in seen:
            return
        seen.add(n)
        pts.append(Point(n, colour, L, Cx, Cy))

    for k, (n, colour) in enumerate(samples):
        add(n, colour)
        X, Y = qcs_ref.pixel_position(n, L, Cx, Cy)
        left, right, top, bottom = near_edges(k, X, Y, W, H)
        verticals = [a for a, near in ((a_left, left), (a_right, right)) if near]
        horizontals = [b for b, near in ((b_top, top), (b_bottom, bottom)) if near]
        mirrors = [reflect_vertical_line(n, a) for a in verticals]
        mirrors += [reflect_horizontal_line(n, b) for b in horizontals]
        # a corner: the vertical reflection followed by the horizontal one
        mirrors += [reflect_horizontal_line(reflect_vertical_line(n, a), b)
                    for a in verticals for b in horizontals]
        for m in mirrors:
            if max(abs(c) for c in m) < (1 << 20):
                add(m, colour)
    return pts


# ---------------------------------------------------------------------------
# reconstruction.md §4: a Delaunay triangulation with exact predicates
#
# Bowyer-Watson: inserting p removes every triangle whose circle strictly contains p (the
# "cavity", which is star-shaped from p) and joins p to the cavity's boundary. The hull is
# handled with ghost triangles (u, v, GHOST), one per hull edge, where u -> v runs along the
# hull with the outside on its left; p conflicts with a ghost when it lies strictly outside
# that edge, or on the open edge itself. Real triangles are stored counter-clockwise
# (orient > 0). The order of insertion does not change the subdivision (§4).
# ---------------------------------------------------------------------------

GHOST = -1


class Triangulation:
    def __init__(self, pts):
        self.pts = pts
        self.tri = {}        # id -> (a, b, c) vertex indices; c may be GHOST
        self.edge = {}       # directed edge (u, v) -> id of the triangle that has it
        self.next_id = 0
        self.last = None     # where the next point location starts
        self.rng = random.Random(1)   # for the walk only (never changes the result)
        self.ok = self._build()

    # -- bookkeeping --

    def _add(self, a, b, c):
        t = self.next_id
        self.next_id += 1
        self.tri[t] = (a, b, c)
        for e in ((a, b), (b, c), (c, a)):
            self.edge[e] = t
        self.last = t
        return t

    def _remove(self, t):
        a, b, c = self.tri.pop(t)
        for e in ((a, b), (b, c), (c, a)):
            if self.edge.get(e) == t:
                del self.edge[e]

    # -- predicates on triangles --

    def conflict(self, t, i):
        """Does point i lie strictly inside the circle of triangle t (for a ghost: strictly
        outside its hull edge, or on the open edge)?"""
        a, b, c = self.tri[t]
        P = self.pts
        if c == GHOST:
            o = orient(P[a], P[b], P[i])
            if o != 0:
                return o > 0
            return strictly_between(P[a], P[b], P[i])
        return incircle(P[a], P[b], P[c], P[i]) > 0

    # -- construction --

    def _build(self):
        P = self.pts
        if len(P) < 3:
            return False
        # insertion order: Morton (Z-order) of the pixel positions, to keep walks short
        xs = [p.x for p in P]
        ys = [p.y for p in P]
        x0, y0 = min(xs), min(ys)
        span = max(max(xs) - x0, max(ys) - y0, 1e-9)

        def morton(i):
            qx = int((P[i].x - x0) / span * 65535)
            qy = int((P[i].y - y0) / span * 65535)
            code = 0
            for bit in range(16):
                code |= ((qx >> bit) & 1) << (2 * bit) | ((qy >> bit) & 1) << (2 * bit + 1)
            return code

        order = sorted(range(len(P)), key=morton)
        # the first triangle: the first two points and the first point not on their line
        i0, i1 = order[0], order[1]
        i2 = None
        for i in order[2:]:
            if orient(P[i0], P[i1], P[i]) != 0:
                i2 = i
                break
        if i2 is None:
            return False   # every point on one line: no triangle (the hull rule of §5)
        if orient(P[i0], P[i1], P[i2]) < 0:
            i1, i2 = i2, i1
        self._add(i0, i1, i2)
        self._add(i1, i0, GHOST)
        self._add(i2, i1, GHOST)
        self._add(i0, i2, GHOST)
        for i in order:
            if i not in (i0, i1, i2):
                self._insert(i)
        return True

    def _locate(self, i):
        """A triangle in conflict with point i: walk from the last triangle towards i."""
        P = self.pts
        t = self.last if self.last in self.tri else next(iter(self.tri))
        for _ in range(4 * len(self.tri) + 10):
            a, b, c = self.tri[t]
            if c == GHOST:
                if self.conflict(t, i):
                    return t
                t = self.edge[(b, a)]   # step inside, to the hull triangle
                continue
            edges = [(a, b), (b, c), (c, a)]
            k = self.rng.randrange(3)
            for u, v in edges[k:] + edges[:k]:
                if orient(P[u], P[v], P[i]) < 0:   # i strictly beyond edge u -> v
                    t = self.edge[(v, u)]
                    break
            else:
                return t   # i in the closed triangle: inside its circle (i is no vertex)
        for t in self.tri:   # fallback, never needed so far
            if self.conflict(t, i):
                return t
        raise AssertionError("no triangle in conflict with point %d" % i)

    def _insert(self, i):
        t0 = self._locate(i)
        cavity = {t0}
        checked = {t0}
        stack = [t0]
        while stack:
            a, b, c = self.tri[stack.pop()]
            for u, v in ((a, b), (b, c), (c, a)):
                n = self.edge[(v, u)]
                if n not in checked:
                    checked.add(n)
                    if self.conflict(n, i):
                        cavity.add(n)
                        stack.append(n)
        boundary = []
        for t in cavity:
            a, b, c = self.tri[t]
            for u, v in ((a, b), (b, c), (c, a)):
                if self.edge[(v, u)] not in cavity:
                    boundary.append((u, v))
        for t in cavity:
            self._remove(t)
        for u, v in boundary:
            if u == GHOST:
                self._add(v, i, GHOST)      # (GHOST, v, i) rotated
            elif v == GHOST:
                self._add(i, u, GHOST)      # (u, GHOST, i) rotated
            else:
                self._add(u, v, i)

    # -- results --

    def real_triangles(self):
        return [t for t, (a, b, c) in self.tri.items() if c != GHOST]

    def hull_edges(self):
        """Hull edges (u, v) as vertex pairs."""
        return [(a, b) for (a, b, c) in self.tri.values() if c == GHOST]


def canonical_cells(tr):
    """reconstruction.md §4: merge the two triangles of every edge whose four points are
    cocircular (E = 0); the connected groups are the cells. Returns each cell as its
    vertices in counter-clockwise boundary order, starting from the smallest lattice
    point (lexicographic n)."""
    P = tr.pts
    tris = tr.real_triangles()
    parent = {t: t for t in tris}

    def find(t):
        while parent[t] != t:
            parent[t] = parent[parent[t]]
            t = parent[t]
        return t

    for t in tris:
        a, b, c = tr.tri[t]
        for u, v in ((a, b), (b, c), (c, a)):
            t2 = tr.edge[(v, u)]
            a2, b2, c2 = tr.tri[t2]
            if c2 == GHOST or t2 < t:
                continue
            w = [x for x in (a2, b2, c2) if x not in (u, v)][0]
            if incircle(P[a], P[b], P[c], P[w]) == 0:
                parent[find(t2)] = find(t)
    groups = {}
    for t in tris:
        groups.setdefault(find(t), []).append(t)
    cells = []
    for members in groups.values():
        # boundary: the directed edges of the group not matched by their reverse
        directed = set()
        for t in members:
            a, b, c = tr.tri[t]
            directed.update(((a, b), (b, c), (c, a)))
        succ = {u: v for (u, v) in directed if (v, u) not in directed}
        start = min(succ, key=lambda i: P[i].n)
        poly = [start]
        while succ[poly[-1]] != start:
            poly.append(succ[poly[-1]])
        assert len(poly) == len(succ)
        cells.append(poly)
    return cells


# ---------------------------------------------------------------------------
# reconstruction.md §5: the rule
# ---------------------------------------------------------------------------

def render_triangles(pts, cells):
    """The triangles F is affine on, as ((x, y, colour) * 3) with float colours: a cell of
    3 vertices as it is, a cell of k >= 4 vertices as the fan (g, v_i, v_{i+1}) around its
    vertex centroid g (mean position, mean colour, no rounding)."""
    out = []
    for cell in cells:
        vs = [(pts[i].x, pts[i].y, tuple(float(c) for c in pts[i].colour)) for i in cell]
        if len(vs) == 3:
            out.append(tuple(vs))
            continue
        k = len(vs)
        gx = sum(v[0] for v in vs) / k
        gy = sum(v[1] for v in vs) / k
        gc = tuple(sum(v[2][ch] for v in vs) / k for ch in range(len(vs[0][2])))
        g = (gx, gy, gc)
        for j in range(k):
            out.append((g, vs[j], vs[(j + 1) % k]))
    return out


def lerp(c0, c1, t):
    return tuple(a + (b - a) * t for a, b in zip(c0, c1))


def nearest_on_segments(qx, qy, segments):
    """F outside the hull: the colour at the nearest point of the given boundary segments
    (Euclidean distance in source pixels), linear along each segment."""
    best = None
    for (x0, y0, c0), (x1, y1, c1) in segments:
        dx, dy = x1 - x0, y1 - y0
        ll = dx * dx + dy * dy
        t = 0.0 if ll == 0 else max(0.0, min(1.0, ((qx - x0) * dx + (qy - y0) * dy) / ll))
        px, py = x0 + t * dx, y0 + t * dy
        d = (qx - px) ** 2 + (qy - py) ** 2
        if best is None or d < best[0]:
            best = (d, lerp(c0, c1, t))
    return best[1]


def round_channel(v):
    """Round to nearest, halves up; clamp to 0..=255 (§5, Rounding)."""
    return max(0, min(255, math.floor(v + 0.5)))


def picture_of_points(pts, W, H, channels, w=None, h=None):
    """F of the points (samples and mirror points) at the centres of a w x h output (the
    image's own size by default), rounded: a list of h rows of w colour tuples."""
    w = W if w is None else w
    h = H if h is None else h
    # output pixel (i, j) samples F at ((i + 1/2) W / w, (j + 1/2) H / h)  (§1)
    cx = [(i + 0.5) * W / w for i in range(w)]
    cy = [(j + 0.5) * H / h for j in range(h)]
    value = [[None] * w for _ in range(h)]

    if not pts:
        grey = tuple(128 for _ in range(channels))   # no site: F = 128
        return [[grey] * w for _ in range(h)]

    tr = Triangulation(pts)
    if tr.ok:
        cells = canonical_cells(tr)
        # inside the hull: each triangle's pixel centres (a centre on a shared edge gets
        # either triangle's value; F is continuous there)
        for (x0, y0, c0), (x1, y1, c1), (x2, y2, c2) in render_triangles(pts, cells):
            den = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
            eps = -1e-9
            lo_x, hi_x = min(x0, x1, x2), max(x0, x1, x2)
            lo_y, hi_y = min(y0, y1, y2), max(y0, y1, y2)
            for j in range(h):
                qy = cy[j]
                if qy < lo_y - 1e-9 or qy > hi_y + 1e-9:
                    continue
                for i in range(w):
                    qx = cx[i]
                    if qx < lo_x - 1e-9 or qx > hi_x + 1e-9:
                        continue
                    # barycentric weights of (qx, qy)
                    l1 = ((qx - x0) * (y2 - y0) - (x2 - x0) * (qy - y0)) / den
                    l2 = ((x1 - x0) * (qy - y0) - (qx - x0) * (y1 - y0)) / den
                    l0 = 1.0 - l1 - l2
                    if l0 < eps or l1 < eps or l2 < eps:
                        continue
                    value[j][i] = tuple(l0 * a + l1 * b + l2 * c
                                        for a, b, c in zip(c0, c1, c2))
        P = pts
        boundary = [((P[u].x, P[u].y, P[u].colour), (P[v].x, P[v].y, P[v].colour))
                    for u, v in tr.hull_edges()]
    else:
        # fewer than three points or all on one line: the boundary is the polyline
        # through them in order along the line (one point: F is constant)
        ref, far = pts[0], pts[-1]
        along = sorted(pts, key=lambda p: (p.x - ref.x) * (far.x - ref.x)
                       + (p.y - ref.y) * (far.y - ref.y))
        boundary = [((p.x, p.y, p.colour), (r.x, r.y, r.colour))
                    for p, r in zip(along, along[1:])]
        if not boundary:
            p = pts[0]
            boundary = [((p.x, p.y, p.colour), (p.x, p.y, p.colour))]
    boundary = [((x0, y0, tuple(map(float, c0))), (x1, y1, tuple(map(float, c1))))
                for (x0, y0, c0), (x1, y1, c1) in boundary]

    out = []
    for j in range(h):
        row = []
        for i in range(w):
            v = value[j][i]
            if v is None:   # outside the hull (§5): F at the nearest hull point
                v = nearest_on_segments(cx[i], cy[j], boundary)
            row.append(tuple(round_channel(c) for c in v))
        out.append(row)
    return out


def picture(samples, W, H, L, Cx, Cy, channels, w=None, h=None):
    """The Gouraud picture of samples [(n, colour)] (file order) of a W x H image with
    frame (L, Cx, Cy): reconstruction.md §2 (points) + §4 (cells) + §5 (rule)."""
    return picture_of_points(points_of(samples, W, H, L, Cx, Cy), W, H, channels, w, h)


def picture_of_file(data):
    """(header, picture) of a .qcs file or prefix (bytes). header is None when the prefix
    ends inside the header (then there is no size to draw at)."""
    h, colours, _verified = qcs_ref.decode(data)
    if h is None:
        return None, None
    site_list = qcs_ref.sites(len(colours), h.W, h.H, h.L, h.Cx, h.Cy) if colours else []
    samples = [(s["n"], c) for s, c in zip(site_list, colours)]
    return h, picture(samples, h.W, h.H, h.L, h.Cx, h.Cy, h.channels)


# ---------------------------------------------------------------------------
# PNG (8-bit, non-interlaced), standard library only
# ---------------------------------------------------------------------------

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
COLOUR_TYPE = {1: 0, 2: 4, 3: 2, 4: 6}      # channels -> PNG colour type
CHANNELS_OF = {0: 1, 4: 2, 2: 3, 6: 4}      # PNG colour type -> channels


def png_bytes(pixels, channels):
    """PNG file bytes of rows of colour tuples (filter 0 on every row)."""
    h, w = len(pixels), len(pixels[0])
    raw = bytearray()
    for row in pixels:
        raw.append(0)
        for px in row:
            raw.extend(px)

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    ihdr = struct.pack(">IIBBBBB", w, h, 8, COLOUR_TYPE[channels], 0, 0, 0)
    return (PNG_SIGNATURE + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw), 9))
            + chunk(b"IEND", b""))


def read_png(data):
    """(width, height, channels, rows of colour tuples) of an 8-bit, non-interlaced PNG of
    colour type 0, 2, 4 or 6 (all five row filters)."""
    if data[:8] != PNG_SIGNATURE:
        raise ValueError("not a PNG")
    pos = 8
    idat = b""
    ihdr = None
    while pos < len(data):
        length, = struct.unpack(">I", data[pos:pos + 4])
        tag = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        if zlib.crc32(tag + body) & 0xFFFFFFFF != struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])[0]:
            raise ValueError("PNG chunk CRC mismatch")
        if tag == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif tag == b"IDAT":
            idat += body
        elif tag == b"IEND":
            break
        pos += 12 + length
    w, h, depth, ctype, _comp, _filt, interlace = ihdr
    if depth != 8 or ctype not in CHANNELS_OF or interlace != 0:
        raise ValueError("unsupported PNG (depth %d, colour type %d, interlace %d)"
                         % (depth, ctype, interlace))
    ch = CHANNELS_OF[ctype]
    raw = zlib.decompress(idat)
    stride = w * ch
    prev = bytearray(stride)
    rows = []
    for y in range(h):
        ftype = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - ch] if x >= ch else 0      # left
            b = prev[x]                               # up
            c = prev[x - ch] if x >= ch else 0       # up-left
            if ftype == 0:
                pred = 0
            elif ftype == 1:
                pred = a
            elif ftype == 2:
                pred = b
            elif ftype == 3:
                pred = (a + b) // 2
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            else:
                raise ValueError("bad PNG filter %d" % ftype)
            line[x] = (line[x] + pred) & 0xFF
        rows.append([tuple(line[x * ch:(x + 1) * ch]) for x in range(w)])
        prev = line
    return w, h, ch, rows


def compare(want, got):
    """(max diff, pixels off by exactly 1 in some channel and by no more, first pixel off
    by more than 1 as (x, y, channel, expected, got) or None). want, got: rows of tuples."""
    worst = 0
    off1 = 0
    first = None
    for y, (ra, rb) in enumerate(zip(want, got)):
        for x, (pa, pb) in enumerate(zip(ra, rb)):
            d = max(abs(a - b) for a, b in zip(pa, pb))
            worst = max(worst, d)
            if d == 1:
                off1 += 1
            if d > 1 and first is None:
                c = [k for k in range(len(pa)) if abs(pa[k] - pb[k]) > 1][0]
                first = (x, y, c, pa[c], pb[c])
    return worst, off1, first


def main(argv):
    args = argv[1:]
    ref = None
    if "--compare" in args:
        k = args.index("--compare")
        ref = args[k + 1]
        del args[k:k + 2]
    if not args:
        sys.stderr.write(__doc__)
        sys.exit(2)
    data = open(args[0], "rb").read()
    if len(args) > 1:
        data = data[:int(args[1])]
    try:
        h, pic = picture_of_file(data)
    except qcs_ref.QcsError as err:
        sys.stderr.write("error: %s\n" % err)
        sys.exit(1)
    if h is None:
        sys.stderr.write("the prefix ends inside the header: no picture\n")
        sys.exit(1)
    if ref is None:
        sys.stdout.buffer.write(png_bytes(pic, h.channels))
        return
    w, hh, ch, want = read_png(open(ref, "rb").read())
    if (w, hh, ch) != (h.W, h.H, h.channels):
        print("FAIL: %s is %dx%d with %d channels, the picture %dx%d with %d"
              % (ref, w, hh, ch, h.W, h.H, h.channels))
        sys.exit(1)
    worst, off1, first = compare(want, pic)
    if first is None:
        print("PASS (max diff %d, %d pixels off by 1)" % (worst, off1))
    else:
        print("FAIL (max diff %d): first pixel off by more than 1: x %d, y %d, channel %d, "
              "expected %d, got %d" % ((worst,) + first))
        sys.exit(1)


if __name__ == "__main__":
    main(sys.argv)
