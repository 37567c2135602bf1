#!/usr/bin/env python3
"""A second decoder of the `.qcs` format, versions 2 and 3, written from the spec alone.

Written clean-room from spec/format.md and spec/sites.md (never from the Rust code), in
Python with the standard library only, to show that the spec suffices. It decodes the
samples (sites, positions, colours), not the picture. `check.sh` compares it with the
conformance vectors' sample lists, spec/vectors/NAME[.half].samples.csv.

Usage: python3 qcs_ref.py FILE.qcs [BYTES] > out.csv

Decodes the file (or its first BYTES bytes, as a cut download) and prints every
sample a conforming decoder obtains from those bytes: verified samples of complete
levels plus the complete, unverified samples of a partial level (format.md
§Truncation), as CSV `index,n0,n1,n2,n3,x,y,colour`.
"""

import functools
import math
import sys
import zlib


class QcsError(Exception):
    """A format error (format.md §Error checklist)."""


class NeedMoreData(Exception):
    """The prefix ends before the item being read (not an error, format.md §Truncation)."""


# ---------------------------------------------------------------------------
# format.md §Conventions
# ---------------------------------------------------------------------------

def read_varint(buf, pos, max_bytes):
    """Unsigned LEB128 (format.md §Conventions). max_bytes = 5 (u32) or 10 (u64).

    Returns (value, new_pos). Raises NeedMoreData if the prefix ends inside it,
    QcsError for overflow or a non-minimal encoding."""
    value = 0
    shift = 0
    for i in range(max_bytes):
        if pos + i >= len(buf):
            raise NeedMoreData()
        b = buf[pos + i]
        if i == max_bytes - 1:
            # last allowed byte: 5th byte of a u32 <= 0x0F, 10th byte of a u64 <= 0x01
            limit = 0x0F if max_bytes == 5 else 0x01
            if b > limit:
                raise QcsError("malformed varint (overflow)")
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            if i >= 1 and b == 0x00:
                raise QcsError("malformed varint (non-minimal)")
            return value, pos + i + 1
    raise QcsError("malformed varint (too long)")


def unzigzag(u):
    """zigzag u32 -> i32 (format.md §Conventions)."""
    return (u >> 1) ^ -(u & 1)


def crc8_smbus(data):
    """CRC-8/SMBUS, polynomial 0x07, init 0 (format.md §Header, check byte)."""
    c = 0
    for b in data:
        c ^= b
        for _ in range(8):
            c = ((c << 1) ^ (0x07 if c & 0x80 else 0)) & 0xFF
    return c


# ---------------------------------------------------------------------------
# format.md §Header
# ---------------------------------------------------------------------------

CHANNELS = {0: 1, 1: 2, 2: 3, 3: 4}  # layout -> number of channels


class Header:
    pass


def parse_header(buf):
    """Parse the header (format.md §Header). Raises NeedMoreData if incomplete."""
    h = Header()
    if len(buf) < 1:
        raise NeedMoreData()
    if buf[0] != 0x71:
        raise QcsError("bad magic")
    if len(buf) < 2:
        raise NeedMoreData()
    if buf[1] != 0x63:
        raise QcsError("bad magic")
    if len(buf) < 3:
        raise NeedMoreData()
    fmt = buf[2]
    # (a pre-release version-1 file began "qcs" 0x01: 0x73 is now a version-3 format byte
    # like any other, and such a file fails its header check; format.md §Header)
    version = fmt >> 5
    if version not in (2, 3):
        raise QcsError("unsupported version %d" % version)
    h.version = version
    h.has_lattice = bool(fmt & 0x10)
    h.defaults = bool(fmt & 0x08)
    h.coding = (fmt >> 2) & 1
    h.layout = fmt & 3
    h.channels = CHANNELS[h.layout]
    pos = 3
    h.W, pos = read_varint(buf, pos, 5)
    h.H, pos = read_varint(buf, pos, 5)
    if h.defaults:
        # format.md §Header, bit 3: version 2: d = 64, L0 = 127;
        # version 3: N = min(64, W*H), L0 = 64 (one level)
        if version == 2:
            d = 64
            h.L0 = 127
        else:
            d = None
            h.N = min(64, h.W * h.H)
            h.L0 = 64
    else:
        if pos >= len(buf):
            raise NeedMoreData()
        d = buf[pos]
        pos += 1
    if d == 0:
        h.N, pos = read_varint(buf, pos, 10)
    elif d is not None:
        h.N = max(1, h.W * h.H * d // 256)
    if not h.defaults:
        h.L0, pos = read_varint(buf, pos, 10)
    if pos >= len(buf):
        raise NeedMoreData()
    h.param = buf[pos]
    pos += 1
    if h.has_lattice:
        h.L, pos = read_varint(buf, pos, 5)
        zx, pos = read_varint(buf, pos, 5)
        zy, pos = read_varint(buf, pos, 5)
        h.Cx = unzigzag(zx)
        h.Cy = unzigzag(zy)
    else:
        # default frame (sites.md §2): L = 2^16, Cx = -W*2^15, Cy = -floor(H*2^16/3)
        h.L = 1 << 16
        h.Cx = -h.W * (1 << 15)
        h.Cy = -((h.H << 16) // 3)
    if pos >= len(buf):
        raise NeedMoreData()
    if crc8_smbus(buf[:pos]) != buf[pos]:
        raise QcsError("header check byte mismatch")
    pos += 1
    h.length = pos
    h.refinement = Refinement() if version == 3 else None
    # value rules (format.md §Header, order of checks)
    if h.W < 1 or h.H < 1 or h.N < 1 or h.L0 < 1:
        raise QcsError("W, H, N or L0 is 0")
    if h.coding == 0 and not 1 <= h.param <= 8:
        raise QcsError("raw B not in 1..=8")
    if h.coding == 1 and h.param < 1:
        raise QcsError("predictive step 0")
    if h.L < 1:
        raise QcsError("root length 0")
    # sites.md §2 bounds and §4 (N <= W*H)
    if h.W > 65535 or h.H > 65535 or not (1 << 16) <= h.L <= (1 << 24):
        raise QcsError("frame out of the bounds of sites.md §2")
    if h.N > h.W * h.H:
        raise QcsError("N > W*H")
    h.levels = level_bounds(h.N, h.L0)
    if h.coding == 0:
        for s, e in h.levels:
            if raw_payload_length(e - s, h.channels, h.param) > 0xFFFFFFFF:
                raise QcsError("raw level payload over 2^32-1 bytes")
    return h


# ---------------------------------------------------------------------------
# format.md §Levels
# ---------------------------------------------------------------------------

def level_bounds(N, L0):
    """[(s_k, e_k)]: s_0 = 0, e_0 = min(L0, N), e_{k+1} = min(2 e_k, N)."""
    levels = []
    s, e = 0, min(L0, N)
    while True:
        levels.append((s, e))
        if e == N:
            return levels
        s, e = e, min(2 * e, N)


# ---------------------------------------------------------------------------
# sites.md §1: Z[tau] arithmetic and the lattice
# ---------------------------------------------------------------------------

TAU = (1 + math.sqrt(5)) / 2


def sign_int(v):
    return (v > 0) - (v < 0)


def zt_sign(a, b):
    """sign(a + b*tau) (sites.md §1, Signs): u = 2a + b, v = b, sign(u + v*sqrt5)."""
    u, v = 2 * a + b, b
    su, sv = sign_int(u), sign_int(v)
    if sv == 0 or su == sv:
        return su
    if su == 0:
        return sv
    return su if u * u > 5 * v * v else sv


def zt_mul(x, y):
    """(a + b tau)(c + d tau) with tau^2 = tau + 1."""
    a, b = x
    c, d = y
    return (a * c + b * d, a * d + b * c + b * d)


def zt_sign_us(u, v):
    """sign(u + s*v) for u, v in Z[tau], s = sin 72 deg (sites.md §1, Signs)."""
    su, sv = zt_sign(*u), zt_sign(*v)
    if sv == 0 or su == sv:
        return su
    if su == 0:
        return sv
    u2 = zt_mul(u, u)
    v2 = zt_mul(zt_mul(v, v), (2, 1))  # (2 + tau) v^2
    return su if zt_sign(4 * u2[0] - v2[0], 4 * u2[1] - v2[1]) > 0 else sv


def re2(n):
    """2 Re x = (2n0 - n1) + (n1 - n2 - n3) tau (sites.md §1)."""
    n0, n1, n2, n3 = n
    return (2 * n0 - n1, n1 - n2 - n3)


def im_s(n):
    """Im x / sin72 = (n1 - n2 + n3) + (n2 - n3) tau (sites.md §1)."""
    n0, n1, n2, n3 = n
    return (n1 - n2 + n3, n2 - n3)


def star_norm(n):
    """|x*|^2 = p + q tau (sites.md §1), via m = (n0 - n2, n3 - n2, n1 - n2, -n2)."""
    n0, n1, n2, n3 = n
    m0, m1, m2, m3 = n0 - n2, n3 - n2, n1 - n2, -n2
    S0 = m0 * m0 + m1 * m1 + m2 * m2 + m3 * m3
    A1 = m0 * m1 + m1 * m2 + m2 * m3
    A2 = m0 * m2 + m0 * m3 + m1 * m3
    return (S0 - A1, A1 - A2)


def zt_float(a, b):
    return a + b * TAU


# ---------------------------------------------------------------------------
# sites.md §2: the frame and the exact viewing-window test
# ---------------------------------------------------------------------------

def in_window(n, W, H, L, Cx, Cy):
    """0 <= X < W and 0 <= Y < H decided exactly (sites.md §2)."""
    A, B = re2(n)
    # sign(2Cx + L*(2 Re x)) >= 0 and sign(2Cx - 2W*2^16 + L*(2 Re x)) < 0
    if zt_sign(2 * Cx + L * A, L * B) < 0:
        return False
    if zt_sign(2 * Cx - 2 * W * 65536 + L * A, L * B) >= 0:
        return False
    U, V = im_s(n)
    v = (L * U, L * V)
    # sign(Cy + s*L*(Im x/s)) >= 0 and sign(Cy - H*2^16 + s*L*(Im x/s)) < 0
    if zt_sign_us((Cy, 0), v) < 0:
        return False
    if zt_sign_us((Cy - H * 65536, 0), v) >= 0:
        return False
    return True


def pixel_position(n, L, Cx, Cy):
    """X = (Cx + L Re x)/2^16, Y = (Cy + L Im x)/2^16 (sites.md §2), in floating point
    (for output only)."""
    A, B = re2(n)
    U, V = im_s(n)
    s72 = math.sin(math.radians(72))
    re = zt_float(A, B) / 2
    im = zt_float(U, V) * s72
    return (Cx + L * re) / 65536.0, (Cy + L * im) / 65536.0


# ---------------------------------------------------------------------------
# sites.md §3: the progressive order
# ---------------------------------------------------------------------------

def site_cmp(s1, s2):
    """Ascending |x*|^2, then Im x, then Re x, all exact in Z[tau] (sites.md §3)."""
    for key in ("norm", "im", "re"):
        a, b = s1[key], s2[key]
        sg = zt_sign(b[0] - a[0], b[1] - a[1])  # sign(b - a)
        if sg > 0:
            return -1
        if sg < 0:
            return 1
    return 0


def one_d_cut_and_project(lo1, hi1, lo2, hi2):
    """All (m, k) with m + k tau in [lo1, hi1] and m + k (1 - tau) in [lo2, hi2]
    (floating-point candidate search with a margin; sites.md §5, informative).
    v - v' = k sqrt5."""
    eps = 1e-7
    sq5 = math.sqrt(5)
    out = []
    kmin = math.floor((lo1 - hi2) / sq5 - eps)
    kmax = math.ceil((hi1 - lo2) / sq5 + eps)
    for k in range(kmin, kmax + 1):
        mlo = max(lo1 - k * TAU, lo2 - k * (1 - TAU))
        mhi = min(hi1 - k * TAU, hi2 - k * (1 - TAU))
        for m in range(math.floor(mlo - eps), math.ceil(mhi + eps) + 1):
            out.append((m, k))
    return out


def enumerate_window(W, H, L, Cx, Cy, r):
    """Candidate lattice points with |x*| <= r (plus a margin) whose physical point may be
    in the viewing window; sites.md §5 (informative). Exact filtering is done by the
    caller. x = a + b zeta, n = (a0 + b1, b0 + b1, b1 - a1, -a1)."""
    ell = L / 65536.0
    cx, cy = Cx / 65536.0, Cy / 65536.0
    x0, x1 = -cx / ell, (W - cx) / ell  # Re x range (root units)
    y0, y1 = -cy / ell, (H - cy) / ell  # Im x range
    s72 = math.sin(math.radians(72))
    s36 = math.sin(math.radians(36))
    c72 = math.cos(math.radians(72))
    m = 1e-6
    rr = r + m
    out = []
    # b: b sin72 in [y0, y1], |b' sin36| <= r
    for b0, b1 in one_d_cut_and_project(y0 / s72 - m, y1 / s72 + m, -rr / s36, rr / s36):
        b = b0 + b1 * TAU
        bs = b0 + b1 * (1 - TAU)
        rem = rr * rr - (bs * s36) ** 2
        if rem < 0:
            continue
        w = math.sqrt(rem)
        # a: a + b cos72 in [x0, x1];  a' within +-w of b' tau / 2
        c = bs * TAU / 2
        for a0, a1 in one_d_cut_and_project(x0 - b * c72 - m, x1 - b * c72 + m,
                                            c - w - m, c + w + m):
            out.append((a0 + b1, b0 + b1, b1 - a1, -a1))
    return out


def sites(k, W, H, L, Cx, Cy):
    """The first k sites in progressive order (sites.md §3): list of dicts with n, norm,
    im, re. Radius from the density formula for 1.03k + 64 sites, enlarged x1.25 until the
    k-th site lies strictly inside r."""
    ell = L / 65536.0
    kk = 1.03 * k + 64
    r2 = kk * ell * ell / (0.3577709 * math.pi * W * H)
    r = math.sqrt(r2)
    while True:
        pts = []
        for n in set(enumerate_window(W, H, L, Cx, Cy, r)):
            if not in_window(n, W, H, L, Cx, Cy):
                continue
            nm = star_norm(n)
            if zt_float(*nm) > r * r + 1e-6:
                continue
            pts.append({"n": n, "norm": nm, "im": im_s(n), "re": re2(n)})
        pts.sort(key=functools.cmp_to_key(site_cmp))
        if len(pts) >= k and (k == 0 or zt_float(*pts[k - 1]["norm"]) < r * r - 1e-6):
            return pts[:k]
        r *= 1.25


# ---------------------------------------------------------------------------
# format.md §Codings, 0 — raw
# ---------------------------------------------------------------------------

def raw_payload_length(count, channels, B):
    return (count * channels * B + 7) // 8


def decode_raw(payload, count, channels, B):
    """Samples of a raw level (format.md §0 — raw). With a partial payload, the
    floor(bytes*8/(channels*B)) complete samples (at most count)."""
    avail = min(count, len(payload) * 8 // (channels * B))
    maxq = (1 << B) - 1
    bitpos = 0
    out = []
    for _ in range(avail):
        sample = []
        for _ in range(channels):
            q = 0
            for _ in range(B):
                byte = payload[bitpos >> 3]
                q = (q << 1) | ((byte >> (7 - (bitpos & 7))) & 1)
                bitpos += 1
            sample.append((q * 255 + (maxq - 1) // 2) // maxq)
        out.append(tuple(sample))
    return out


# ---------------------------------------------------------------------------
# format.md §Codings, 1 — predictive
# ---------------------------------------------------------------------------

T_CONST = 6949403065
S_CONST = 4084756634


def fixed_position(n, L, Cx, Cy):
    """Sample position in 1/256 px (format.md §1 — predictive, Positions)."""
    a, b = re2(n)
    u, v = im_s(n)
    X = ((1 << 33) * Cx + L * ((1 << 32) * a + T_CONST * b) + (1 << 40)) >> 41
    Y = ((1 << 64) * Cy + L * S_CONST * ((1 << 32) * u + T_CONST * v) + (1 << 71)) >> 72
    return X, Y


def bitlen(n):
    return n.bit_length()


class Prob:
    """Adaptive probability of a 0 bit, in 1/4096, with a count (format.md
    §Probabilities and coder)."""
    __slots__ = ("p", "n")

    def __init__(self):
        self.p = 2048
        self.n = 0

    def update(self, bit):
        k = min(1 + self.n // 2, 5)
        if bit == 0:
            self.p += (4096 - self.p) >> k
        else:
            self.p -= self.p >> k
        self.n = min(self.n + 1, 16)


class Undecided(Exception):
    """A bit the received bytes do not decide (format.md §1, Truncation)."""


class RangeDecoder:
    """The binary range decoder with two code values lo, hi (format.md §1 — predictive,
    Probabilities and coder; Truncation). `payload` is the payload bytes received so
    far, `length` the payload length announced by the chunk."""
    MASK = 0xFFFFFFFF

    def __init__(self, payload, length):
        self.payload = payload
        self.length = length
        self.range = 0xFFFFFFFF
        self.lo = 0
        self.hi = 0
        self.pos = 0  # index of the next payload byte to shift in
        for _ in range(4):
            self._shift()

    def _byte(self, i):
        """(lo byte, hi byte) of payload byte i."""
        if i < len(self.payload):
            return self.payload[i], self.payload[i]
        if i >= self.length:
            return 0, 0  # bytes past the payload's end read as 0x00
        return 0x00, 0xFF  # not yet received

    def _shift(self):
        bl, bh = self._byte(self.pos)
        self.lo = ((self.lo << 8) | bl) & self.MASK
        self.hi = ((self.hi << 8) | bh) & self.MASK
        self.pos += 1

    def _missing(self):
        """Is a byte of the code window (the last 4 bytes shifted in) not yet received?"""
        first = self.pos - 4
        return any(len(self.payload) <= i < self.length for i in range(first, self.pos))

    def bit(self, prob):
        bound = (self.range >> 12) * prob.p
        if self._missing():
            if not self.hi < self.range:
                raise Undecided()
            if self.hi < bound:
                bit = 0
            elif self.lo >= bound:
                bit = 1
            else:
                raise Undecided()
        else:
            bit = 0 if self.lo < bound else 1
        if bit == 0:
            self.range = bound
        else:
            self.lo -= bound
            self.hi -= bound
            self.range -= bound
        while self.range < (1 << 24):
            self.range <<= 8
            self._shift()
        prob.update(bit)
        return bit


class PredictiveState:
    """Per-file state of the predictive coding: probabilities (carried over from level to
    level), the decoded samples' coded-channel values, |q| of channel 0, positions."""

    def __init__(self, header):
        self.step = header.param
        if header.layout >= 2:
            # Y, Co, Cg (then A): ranges and steps (format.md §1, Coded channels)
            self.ranges = [(0, 255), (-255, 255), (-255, 255)]
            self.steps = [self.step, 2 * self.step - 1, 2 * self.step - 1]
            if header.layout == 3:
                self.ranges.append((0, 255))
                self.steps.append(self.step)
        else:
            self.ranges = [(0, 255)] * header.channels
            self.steps = [self.step] * header.channels
        nc = len(self.ranges)
        # (c, act, cls) -> 12 probabilities Z, N, E0..E9
        self.ctx = [[[[Prob() for _ in range(12)] for _ in range(3)] for _ in range(8)]
                    for _ in range(nc)]
        # (c, act) -> M[e][b], 1 <= e <= 9, 0 <= b < e
        self.mant = [[[[Prob() for _ in range(e)] for e in range(10)] for _ in range(8)]
                     for _ in range(nc)]
        self.values = []  # decoded coded-channel values per sample
        self.q0 = []      # |q| of channel 0 per sample
        self.pos = []     # fixed-point positions

    def neighbours(self, i):
        """Up to 4 earlier samples with smallest squared distance, ties by smaller j."""
        Xi, Yi = self.pos[i]
        cand = []
        for j in range(i):
            Xj, Yj = self.pos[j]
            cand.append(((Xj - Xi) ** 2 + (Yj - Yi) ** 2, j))
        cand.sort()
        return cand[:4]


def decode_residual(rd, probs, mant):
    """One channel's q (format.md §1, Contexts)."""
    if rd.bit(probs[0]) == 0:  # bit q != 0 with Z
        return 0
    neg = rd.bit(probs[1])      # bit q < 0 with N
    e = 0
    g = 0
    while g < 9:                # unary E0.. : bit g < e
        if rd.bit(probs[2 + g]) == 0:
            break
        e += 1
        g += 1
    m = 1
    for b in range(e - 1, -1, -1):  # the e bits below the top bit, MSB first
        m = (m << 1) | rd.bit(mant[e][b])
    return -m if neg else m


def decode_predictive(payload, length, start, count, st, site_list, header):
    """Decode the complete samples of a predictive level (format.md §1). Returns the list
    of coded-channel value tuples for samples start.. (as many as are complete)."""
    rd = RangeDecoder(payload, length)
    out = []
    nc = len(st.ranges)
    for i in range(start, start + count):
        st.pos.append(fixed_position(site_list[i]["n"], header.L, header.Cx, header.Cy))
        nb = st.neighbours(i)
        vals = []
        qs = []
        try:
            for c in range(nc):
                lo, hi = st.ranges[c]
                step = st.steps[c]
                if not nb:
                    pred = (lo + hi + 1) // 2
                    spread = 0
                else:
                    ws = [(1 << 62) // (d + 4096) for d, _ in nb]
                    Wsum = sum(ws)
                    vs = [st.values[j][c] for _, j in nb]
                    pred = (sum(w * v for w, v in zip(ws, vs)) + Wsum // 2) // Wsum
                    spread = max(vs) - min(vs)
                act = min(7, bitlen(spread // step))
                if c == 0:
                    cls = min(2, bitlen(sum(min(255, st.q0[j]) for _, j in nb)))
                else:
                    cls = min(2, bitlen(abs(qs[0])))
                q = decode_residual(rd, st.ctx[c][act][cls], st.mant[c][act])
                qs.append(q)
                vals.append(max(lo, min(hi, pred + q * step)))
        except Undecided:
            st.pos.pop()
            break
        st.values.append(tuple(vals))
        st.q0.append(abs(qs[0]))
        out.append(tuple(vals))
    return out


def to_layout(vals, layout):
    """Coded channels -> layout channels (inverse YCoCg-R for RGB(A), clamped)."""
    if layout < 2:
        return tuple(vals)
    Y, Co, Cg = vals[0], vals[1], vals[2]
    t = Y - (Cg >> 1)
    G = Cg + t
    B = t - (Co >> 1)
    R = B + Co
    out = tuple(max(0, min(255, v)) for v in (R, G, B))
    if layout == 3:
        out += (vals[3],)
    return out


# ---------------------------------------------------------------------------
# format.md §Refinement chunks (version 3): the refinement header, segment tables
# ---------------------------------------------------------------------------

class Refinement:
    """What the R chunks received so far say (format.md §Refinement chunks): the
    refinement header's fields once it is complete, and per layer its segment lengths
    and the bytes of each segment received. The meaning is refinement.md's (qcs_refine.py).

    Fields once `header_complete`: wavelet (0 = 5/3, 1 = 9/7), L, F, count_mode (bit 7),
    P (bit-planes per coded channel), layers, K (key limit) or counts (passes per stream).
    """

    def __init__(self):
        self.header_complete = False
        self.layers = None       # declared number of layers (once layer 0's header is read)
        self.layer_list = []     # [(lengths, [received bytes of each segment], verified)]

    def stream_passes(self, s):
        """The number of passes of stream s: 3 sum P_c (stream 0), 9 sum P_c (others)."""
        return (3 if s == 0 else 9) * sum(self.P)

    def streams(self):
        """The bytes received of each of the L + 1 streams: its segments in layer order."""
        out = [bytearray() for _ in range(self.L + 1)]
        for _lengths, segs, _verified in self.layer_list:
            for s, seg in enumerate(segs):
                out[s] += seg
        return [bytes(b) for b in out]

    def verified_layers(self):
        return sum(1 for _l, _s, v in self.layer_list if v)


def parse_layer(data, length, first, channels, ref, chunk_done):
    """Parse an R chunk's payload (format.md §Refinement chunks). `data` is the part of the
    payload received (at most `length` bytes), `first` is layer 0 (the refinement header
    comes first), `chunk_done` says the chunk's CRC has arrived. Fills `ref`'s header
    fields; returns (lengths, received segments) once the segment table is complete, else
    None. Each check is made at the byte that completes its field; a payload that ends
    before its table is complete is an error once the chunk is done (at its CRC)."""
    pos = 0

    def cut():
        if len(data) >= length and chunk_done:
            raise QcsError("R chunk payload ends before its segment table is complete")
        raise NeedMoreData()

    def byte():
        nonlocal pos
        if pos >= len(data):
            cut()
        b = data[pos]
        pos += 1
        return b

    def varint():
        nonlocal pos
        try:
            v, pos = read_varint(data, pos, 5)
        except NeedMoreData:
            cut()
        return v

    try:
        if first:
            tb = byte()
            ref.L = tb & 15
            ref.wavelet = (tb >> 4) & 1
            ref.F = (tb >> 5) & 3        # F <= 3 holds by its two bits
            ref.count_mode = bool(tb & 0x80)
            ref.P = []
            for _ in range(channels):
                pc = byte()
                if pc > 30:
                    raise QcsError("refinement header: P_c = %d > 30" % pc)
                ref.P.append(pc)
            ref.layers = varint()
            if ref.layers < 1:
                raise QcsError("refinement header: 0 layers")
            if ref.count_mode:
                ref.K = None
                ref.counts = []
                for s in range(ref.L + 1):
                    c = varint()
                    if c > ref.stream_passes(s):
                        raise QcsError("refinement header: stream %d pass count %d above its %d "
                                       "passes" % (s, c, ref.stream_passes(s)))
                    ref.counts.append(c)
            else:
                ref.counts = None
                ref.K = unzigzag(varint())
            ref.header_complete = True
        n = varint()
        if n > ref.L + 1:
            raise QcsError("segment table: %d segments for %d streams" % (n, ref.L + 1))
        lengths = [varint() for _ in range(n)]
    except NeedMoreData:
        return None
    if sum(lengths) != length - pos:
        raise QcsError("segment table: lengths %d, payload after the table %d"
                       % (sum(lengths), length - pos))
    segs = []
    for ln in lengths:
        segs.append(bytes(data[pos:pos + ln]))
        pos += ln
    return lengths, segs


# ---------------------------------------------------------------------------
# format.md §Layout, §Level 0, §Chunks, §Truncation
# ---------------------------------------------------------------------------

def decode(buf):
    """Returns (header or None, list of samples (index, colour tuple), verified count)."""
    try:
        h = parse_header(buf)
    except NeedMoreData:
        return None, [], 0
    samples = []
    verified = 0
    st = h.predictive = PredictiveState(h) if h.coding == 1 else None
    site_list = []  # computed lazily, up to the end of the level being decoded
    level = 0
    pos = h.length
    meta_icc = meta_exif = 0

    def decode_level(k, payload, length):
        s, e = h.levels[k]
        if h.coding == 0:  # payload length already checked against the level's count
            return decode_raw(payload, e - s, h.channels, h.param)
        if len(site_list) < e:
            site_list[:] = sites(e, h.W, h.H, h.L, h.Cx, h.Cy)
        vals = decode_predictive(payload, length, s, e - s, st, site_list, h)
        return [to_layout(v, h.layout) for v in vals]

    # Level 0: length, payload, CRC over every byte of the file before it
    try:
        length, p = read_varint(buf, pos, 5)
    except NeedMoreData:
        return h, samples, verified
    if h.coding == 0 and length != raw_payload_length(h.levels[0][1], h.channels, h.param):
        raise QcsError("raw level 0 payload length mismatch")
    payload = buf[p:p + length]
    got = decode_level(0, payload, length)
    if p + length + 4 > len(buf):
        samples.extend(got)
        return h, samples, verified
    crc = int.from_bytes(buf[p + length:p + length + 4], "little")
    if zlib.crc32(buf[:p + length]) != crc:
        raise QcsError("CRC mismatch in chunk 0 (L, offset %d)" % pos)
    samples.extend(got)
    verified = len(samples)
    pos = p + length + 4
    level = 1
    chunk_index = 1
    ref = h.refinement
    layer = 0
    while pos < len(buf):
        tag = buf[pos]
        critical = not tag & 0x20
        if critical and tag not in (0x4C, 0x52):
            raise QcsError("unknown critical chunk %r at %d" % (tag, pos))
        if tag == 0x4C and level >= len(h.levels):
            raise QcsError("L chunk after the last level at %d" % pos)
        if tag == 0x52:
            if h.version != 3:
                raise QcsError("R chunk in a version-2 file at %d" % pos)
            if level < len(h.levels):
                raise QcsError("R chunk before the last level at %d" % pos)
            if ref.layers is not None and layer >= ref.layers:
                raise QcsError("R chunk after the last layer at %d" % pos)
        try:
            length, p = read_varint(buf, pos + 1, 5)
        except NeedMoreData:
            break
        payload = buf[p:p + length]
        complete = p + length + 4 <= len(buf)
        if tag == 0x52:
            got_layer = parse_layer(payload, length, layer == 0, h.channels, ref, complete)
            if not complete:
                if got_layer is not None:  # its table is complete: the segments' bytes so far
                    ref.layer_list.append(got_layer + (False,))
                break
        elif tag == 0x4C:
            if h.coding == 0 and length != raw_payload_length(
                    h.levels[level][1] - h.levels[level][0], h.channels, h.param):
                raise QcsError("raw L payload length mismatch at %d" % pos)
            got = decode_level(level, payload, length)
            if not complete:
                samples.extend(got)  # complete but unverified samples
                break
        elif not complete:
            break  # a partial ancillary chunk is ignored
        crc = int.from_bytes(buf[p + length:p + length + 4], "little")
        if zlib.crc32(buf[pos:p + length]) != crc:
            raise QcsError("CRC mismatch in chunk %d (tag %r, offset %d)"
                           % (chunk_index, chr(tag), pos))
        if tag == 0x4C:
            samples.extend(got)
            verified = len(samples)
            level += 1
        elif tag == 0x52:
            ref.layer_list.append(got_layer + (True,))
            layer += 1
        elif tag == 0x69:  # i: ICC profile, at most one
            meta_icc += 1
            if meta_icc > 1:
                raise QcsError("second i chunk")
        elif tag == 0x65:  # e: Exif, at most one
            meta_exif += 1
            if meta_exif > 1:
                raise QcsError("second e chunk")
        elif tag == 0x74:  # t: key (>=1 byte, no 0x00) 0x00 value, UTF-8
            z = payload.find(b"\x00")
            if z < 1:
                raise QcsError("bad t chunk")
            try:
                payload[:z].decode("utf-8")
                payload[z + 1:].decode("utf-8")
            except UnicodeDecodeError:
                raise QcsError("t chunk not UTF-8")
        pos = p + length + 4
        chunk_index += 1
    return h, samples, verified


def main(argv):
    data = open(argv[1], "rb").read()
    if len(argv) > 2:
        data = data[:int(argv[2])]
    try:
        h, samples, verified = decode(data)
    except QcsError as err:
        sys.stderr.write("error: %s\n" % err)
        sys.exit(1)
    w = sys.stdout.write
    w("index,n0,n1,n2,n3,x,y,colour\n")
    if h is None:
        return
    site_list = sites(len(samples), h.W, h.H, h.L, h.Cx, h.Cy) if samples else []
    for i, col in enumerate(samples):
        n = site_list[i]["n"]
        x, y = pixel_position(n, h.L, h.Cx, h.Cy)
        w("%d,%d,%d,%d,%d,%.6f,%.6f,%s\n" % (i, n[0], n[1], n[2], n[3], x, y,
                                             " ".join(str(v) for v in col)))
    sys.stderr.write("samples: %d verified, %d available\n" % (verified, len(samples)))
    ref = h.refinement
    if ref is not None:
        sys.stderr.write("refinement: header %s, layers %d verified of %s, %d received\n"
                         % ("complete" if ref.header_complete else "incomplete",
                            ref.verified_layers(), ref.layers if ref.layers else "?",
                            len(ref.layer_list)))


if __name__ == "__main__":
    main(sys.argv)
