#!/usr/bin/env python3
"""The refinement's picture of a version-3 `.qcs` file, written from the spec alone.

Written clean-room from spec/refinement.md and spec/format.md (never from the Rust code),
in Python with the standard library only. The container (header, levels, the R chunks'
refinement header and segment tables) comes from qcs_ref.py, the spec-only decoder of the
samples next to this file; this file adds the refinement:

* refinement.md §1, the coded channels (times 2^F, YCoCg-R, centred);
* §2, the inverse of the integer 5/3 or 9/7 lifting transform, 32-bit wrap-around;
* §3, the bands, their 32 x 32 blocks in spread order, stripes, the L + 1 streams;
* §4, the prediction of the low-low band from the levels' samples;
* §5, the passes of each stream in key order, cut by the header's key or counts;
* §6, the bit-plane coder over each stream's bytes with format.md's range decoder, every
  byte after those received unknown, applied unit by unit;
* §7, the coefficient values; §8, the picture at the image's size and at any other.

Usage:
  python3 qcs_refine.py FILE.qcs [BYTES] > out.png          # the picture as a PNG
  python3 qcs_refine.py FILE.qcs [BYTES] --compare REF.png  # equal to a PNG, exactly?
  python3 qcs_refine.py FILE.qcs --size 71x22 > out.png     # at another size

BYTES cuts the file to its first BYTES bytes (a cut download). Once the refinement header
is complete the picture is the refinement's (this file); before, it is the levels' Gouraud
picture, drawn by qcs_picture.py (and compared within +-1, reconstruction.md §5).
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import qcs_ref  # noqa: E402  (header, levels, samples, R chunks, range decoder)
import qcs_picture  # noqa: E402  (PNG writer/reader, the levels' picture before the refinement)


def wrap32(v):
    """v modulo 2^32 as a signed 32-bit value (two's complement)."""
    return ((v + 0x80000000) & 0xFFFFFFFF) - 0x80000000


# ---------------------------------------------------------------------------
# refinement.md §1: coded channels
# ---------------------------------------------------------------------------

# per layout: [(centred, class, weight(channel) of §5)] in coded-channel order
CODED = {
    0: [(True, 0, 0)],                                               # grey
    1: [(True, 0, 0), (True, 2, 0)],                                 # grey, alpha
    2: [(True, 0, 13), (False, 1, -8), (False, 1, -3)],              # Y, Co, Cg
    3: [(True, 0, 13), (False, 1, -8), (False, 1, -3), (True, 2, 0)],  # Y, Co, Cg, alpha
}


def to_coded(colour, layout, F):
    """A colour in layout channels -> coded channels with F fraction bits, centred (§1):
    the layout values times 2^F, YCoCg-R, minus 128 * 2^F in the centred channels."""
    colour = [v << F for v in colour]
    centre = 128 << F
    if layout < 2:
        return [v - centre for v in colour]
    R, G, B = colour[0], colour[1], colour[2]
    Co = R - B
    t = B + (Co >> 1)
    Cg = G - t
    Y = t + (Cg >> 1)
    out = [Y - centre, Co, Cg]
    if layout == 3:
        out.append(colour[3] - centre)
    return out


def from_coded(vals, layout, F=0):
    """Coded channel values (not centred, F fraction bits) -> layout channels (§8): for
    F >= 1 the values doubled (S = F + 1 fraction bits), else as they are (S = 0); inverse
    YCoCg-R; each channel rounded to a whole level (halves to even) and clamped."""
    D = 1 if F >= 1 else 0
    S = F + D
    vals = [v << D for v in vals]

    def level(v):
        if S > 0:
            v = (v + (1 << (S - 1)) - 1 + ((v >> S) & 1)) >> S
        return max(0, min(255, v))
    if layout < 2:
        return tuple(level(v) for v in vals)
    Y, Co, Cg = vals[0], vals[1], vals[2]
    t = Y - (Cg >> 1)
    G = Cg + t
    B = t - (Co >> 1)
    R = B + Co
    out = [R, G, B] + ([vals[3]] if layout == 3 else [])
    return tuple(level(v) for v in out)


# ---------------------------------------------------------------------------
# refinement.md §2: the transform (inverse)
# ---------------------------------------------------------------------------

def lift(c):
    return lambda a, b: (c * (a + b) + 2048) >> 12


# wavelet -> [(kind, f)], kind 'p' (predict) or 'u' (update), in forward order
STEPS = {
    0: [("p", lambda a, b: -((a + b) >> 1)), ("u", lambda a, b: (a + b + 2) >> 2)],
    1: [("p", lift(-6497)), ("u", lift(-217)), ("p", lift(3616)), ("u", lift(1817))],
}


def inverse_1d(x, wavelet):
    """Undo the lifting of one signal: x = s (the first ceil(n/2)) followed by d."""
    n = len(x)
    if n < 2:
        return list(x)
    nl, nh = (n + 1) // 2, n // 2
    s, d = list(x[:nl]), list(x[nl:])
    for kind, f in reversed(STEPS[wavelet]):
        if kind == "u":
            for i in range(nl):
                s[i] = wrap32(s[i] - f(d[max(i - 1, 0)], d[min(i, nh - 1)]))
        else:
            for i in range(nh):
                d[i] = wrap32(d[i] - f(s[i], s[min(i + 1, nl - 1)]))
    out = [0] * n
    out[0::2] = s
    out[1::2] = d
    return out


def region_sizes(W, H, L):
    """[(w_k, h_k)] for k = 0..L: w_0 = W, w_{k+1} = ceil(w_k / 2)."""
    sizes = [(W, H)]
    for _ in range(L):
        w, h = sizes[-1]
        sizes.append(((w + 1) // 2, (h + 1) // 2))
    return sizes


def inverse_2d(plane, W, H, L, wavelet):
    """Invert L levels in place on a W x H plane (a flat list, row by row): for k = L - 1
    down to 0, on the w_k x h_k region, every column, then every row."""
    sizes = region_sizes(W, H, L)
    for k in range(L - 1, -1, -1):
        w, h = sizes[k]
        for x in range(w):
            col = inverse_1d([plane[y * W + x] for y in range(h)], wavelet)
            for y in range(h):
                plane[y * W + x] = col[y]
        for y in range(h):
            plane[y * W:y * W + w] = inverse_1d(plane[y * W:y * W + w], wavelet)


# ---------------------------------------------------------------------------
# refinement.md §3: bands, blocks, streams
# ---------------------------------------------------------------------------

LL, HL, LH, HH = 0, 1, 2, 3


class Band:
    def __init__(self, order, stream, orient, level, x0, y0, x1, y1):
        self.order, self.stream, self.orient, self.level = order, stream, orient, level
        self.x0, self.y0, self.w, self.h = x0, y0, x1 - x0, y1 - y0


def bands_of(W, H, L):
    """The bands in the order of §3: LL, then HL_l, LH_l, HH_l for l = L down to 1."""
    sizes = region_sizes(W, H, L)
    wL, hL = sizes[L]
    out = [Band(0, 0, LL, L, 0, 0, wL, hL)]
    for lev in range(L, 0, -1):
        w, h = sizes[lev - 1]
        w1, h1 = sizes[lev]
        s = L - lev + 1
        out.append(Band(len(out), s, HL, lev, w1, 0, w, h1))
        out.append(Band(len(out), s, LH, lev, 0, h1, w1, h))
        out.append(Band(len(out), s, HH, lev, w1, h1, w, h))
    return out


def spread_order(bw, bh):
    """The blocks (bx, by) of a bw x bh grid in spread order (§3)."""
    m = 0
    while (1 << m) < max(bw, bh):
        m += 1
    out = []
    for t in range(1 << (2 * m)):
        r = 0
        for j in range(2 * m):
            if t >> j & 1:
                r |= 1 << (2 * m - 1 - j)
        bx = by = 0
        for j in range(m):
            bx |= (r >> (2 * j) & 1) << j
            by |= (r >> (2 * j + 1) & 1) << j
        if bx < bw and by < bh:
            out.append((bx, by))
    return out


# ---------------------------------------------------------------------------
# refinement.md §4: the prediction of the low-low band
# ---------------------------------------------------------------------------

GAIN97 = [65536, 80602, 99131, 121919, 149946, 184416, 226810, 278950, 343076, 421943,
          518940, 638236, 784955, 965403, 1187333, 1460280, 1795973, 2208837, 2716611,
          3341113, 4109177, 5053807, 6215590, 7644448, 9401775, 11563082, 14221236,
          17490455, 21511211, 26456269, 32538112]


def splits(W, H, L):
    """The one-dimensional splits L levels make: a side shorter than 2 is not split."""
    return sum((w >= 2) + (h >= 2) for (w, h) in region_sizes(W, H, L)[:L])


def ll_prediction(h, ref, values, positions, wL, hL):
    """pred[c][j][i] for LL coefficient (i, j) in coded channel c (§4). values: each
    sample's centred coded-channel values (F fraction bits, §1); positions: its (X, Y) in 1/256 px."""
    L, F = ref.L, ref.F
    G = 65536 if ref.wavelet == 0 else GAIN97[splits(h.W, h.H, L)]
    nc = len(CODED[h.layout])
    pred = [[[0] * wL for _ in range(hL)] for _ in range(nc)]
    for j in range(hL):
        qy = j * (1 << L) * 256 + 128
        for i in range(wL):
            qx = i * (1 << L) * 256 + 128
            near = sorted(((X - qx) ** 2 + (Y - qy) ** 2, k)
                          for k, (X, Y) in enumerate(positions))[:4]
            ws = [(1 << 62) // (d + 4096) for d, _ in near]
            wsum = sum(ws)
            for c in range(nc):
                p = (sum(w * values[k][c] for w, (_, k) in zip(ws, near)) + wsum // 2) // wsum
                pred[c][j][i] = (p * G + (1 << 15)) >> 16
    return pred


# ---------------------------------------------------------------------------
# refinement.md §5: passes and their order
# ---------------------------------------------------------------------------

# weight(band) for l = 1..15 (index l - 1), per wavelet: LL_l, HL_l/LH_l, HH_l
BAND_WEIGHT = {
    0: {LL: [9, 23, 39, 55, 71, 87, 103, 119, 135, 151, 167, 183, 199, 215, 231],
        HL: [1, 11, 25, 40, 56, 72, 88, 104, 120, 136, 152, 168, 184, 200, 216],
        HH: [-8, -2, 11, 26, 41, 57, 73, 89, 105, 121, 137, 153, 169, 185, 201]},
    1: {LL: [6, 14, 21, 27, 34, 40, 46, 53, 59, 66, 72, 79, 85, 92, 98],
        HL: [0, 6, 14, 21, 27, 34, 40, 47, 53, 60, 66, 73, 79, 85, 92],
        HH: [-6, -1, 7, 15, 21, 28, 34, 41, 47, 54, 60, 66, 73, 79, 86]},
}

PROP, REFN, CLEAN = 0, 1, 2


def band_weight(wavelet, band):
    if band.orient == LL and band.level == 0:
        return 0  # L = 0: the low-low band is the picture itself
    table = BAND_WEIGHT[wavelet][HL if band.orient == LH else band.orient]
    return table[band.level - 1]


def stream_passes(ref, layout, bands, s):
    """The passes of stream s in order (§5), cut by the header's key or count:
    [(key, kind, band, channel, p)]."""
    out = []
    for band in bands:
        if band.stream != s:
            continue
        for c, (_centred, _cls, wch) in enumerate(CODED[layout]):
            for p in range(ref.P[c] - 1, -1, -1):
                for kind in (PROP, REFN, CLEAN):
                    key = 16 * p + band_weight(ref.wavelet, band) + wch - (0 if kind == PROP else 8)
                    out.append((key, kind, band, c, p))
    out.sort(key=lambda t: (-t[0], t[1], t[2].order, t[3]))
    if ref.count_mode:
        return out[:ref.counts[s]]
    return [t for t in out if t[0] >= ref.K]


# ---------------------------------------------------------------------------
# refinement.md §6: coding a pass
# ---------------------------------------------------------------------------

class StreamDecoder(qcs_ref.RangeDecoder):
    """format.md's range decoder over a stream's bytes, every byte after those received
    unknown (read as 0x00 by lo, 0xFF by hi), also when the file is complete (§6)."""

    def __init__(self, data):
        super().__init__(data, float("inf"))

    def _missing(self):
        # the code window is bytes pos-4 .. pos-1; one is missing iff pos-1 >= len(data)
        return self.pos > len(self.payload)


class Contexts:
    """A stream's probabilities for one (class, orientation): 24 (§6)."""

    def __init__(self):
        P = qcs_ref.Prob
        self.SIG = [P() for _ in range(9)]
        self.SIGN = [P() for _ in range(5)]
        self.REF = [P() for _ in range(3)]
        self.RUN = P()
        self.UNI = [P(), P()]
        self.BLOCK = [P() for _ in range(3)]
        self.BAND = P()


# (hc, vc) -> (context, flip)
SIGN_CTX = {(1, 1): (4, 0), (1, 0): (3, 0), (1, -1): (2, 0), (0, 1): (1, 0), (0, 0): (0, 0),
            (0, -1): (1, 1), (-1, 1): (2, 1), (-1, 0): (3, 1), (-1, -1): (4, 1)}


def sig_context(orient, h, v, d):
    """Significance context (§6; JPEG 2000 Table D.1)."""
    if orient == HH:
        hv = h + v
        if d >= 3:
            return 8
        if d == 2:
            return 7 if hv >= 1 else 6
        if d == 1:
            return 5 if hv >= 2 else (4 if hv == 1 else 3)
        return 2 if hv >= 2 else (1 if hv == 1 else 0)
    if orient == HL:
        h, v = v, h
    if h == 2:
        return 8
    if h == 1:
        return 7 if v >= 1 else (6 if d >= 1 else 5)
    if v == 2:
        return 4
    if v == 1:
        return 3
    return 2 if d >= 2 else (1 if d == 1 else 0)



class BandChannel:
    """The coding state of one band in one channel (§6, State), with an undo log of the
    current unit so that a unit the bytes do not decide is not applied."""

    def __init__(self, band):
        self.band = band
        w, h = band.w, band.h
        self.S = S = w + 2  # padded: a ring of never-significant coefficients around
        n = S * (h + 2)
        self.st = [0] * n        # 0: not significant; +1 / -1: significant, its sign
        self.m = [0] * n
        self.k = [0] * n
        self.visited = [0] * n
        self.refined = [0] * n
        self.active = False
        self.bw, self.bh = (w + 31) // 32, (h + 31) // 32
        self.block_active = [0] * (self.bw * self.bh)
        self.order = spread_order(self.bw, self.bh) if w and h else []
        # per block: its stripe columns, each a list of padded indices from the top
        self.columns = {}
        for bx, by in self.order:
            cols = []
            y0, y1 = by * 32, min(by * 32 + 32, h)
            x0, x1 = bx * 32, min(bx * 32 + 32, w)
            for ys in range(y0, y1, 4):
                for x in range(x0, x1):
                    cols.append([(y + 1) * S + x + 1 for y in range(ys, min(ys + 4, y1))])
            self.columns[(bx, by)] = cols
        self.log = []

    # --- state with undo ---
    def unit(self):
        self.log = []

    def touch(self, i):
        self.log.append((i, self.st[i], self.m[i], self.k[i], self.visited[i], self.refined[i]))

    def rollback(self):
        for e in reversed(self.log):
            if e[0] == "block":
                self.block_active[e[1]] = e[2]
            elif e[0] == "band":
                self.active = e[1]
            else:
                i = e[0]
                self.st[i], self.m[i], self.k[i], self.visited[i], self.refined[i] = e[1:]
        self.log = []

    def nb(self, i):
        st, S = self.st, self.S
        h = (st[i - 1] != 0) + (st[i + 1] != 0)
        v = (st[i - S] != 0) + (st[i + S] != 0)
        d = ((st[i - S - 1] != 0) + (st[i - S + 1] != 0)
             + (st[i + S - 1] != 0) + (st[i + S + 1] != 0))
        return h, v, d

    def become_significant(self, i, negative, p, blk):
        self.st[i] = -1 if negative else 1
        self.m[i] = 1 << p
        self.k[i] = p
        b = blk[1] * self.bw + blk[0]
        if not self.block_active[b]:
            self.log.append(("block", b, 0))
            self.block_active[b] = 1
        if not self.active:
            self.log.append(("band", False))
            self.active = True

    def decode_sign(self, rd, ctx, i):
        st, S = self.st, self.S
        hc = max(-1, min(1, st[i - 1] + st[i + 1]))
        vc = max(-1, min(1, st[i - S] + st[i + S]))
        c, flip = SIGN_CTX[(hc, vc)]
        return (rd.bit(ctx.SIGN[c]) ^ flip) == 1

    def code_significance(self, rd, ctx, i, p, blk):
        h, v, d = self.nb(i)
        if rd.bit(ctx.SIG[sig_context(self.band.orient, h, v, d)]):
            neg = self.decode_sign(rd, ctx, i)
            self.become_significant(i, neg, p, blk)

    # --- the three passes ---
    def propagation(self, rd, ctx, p):
        for blk in self.order:
            if not self.block_active[blk[1] * self.bw + blk[0]]:
                continue
            for col in self.columns[blk]:
                self.unit()
                for i in col:
                    if self.st[i] == 0 and sum(self.nb(i)) > 0:
                        self.touch(i)
                        self.code_significance(rd, ctx, i, p, blk)
                        self.visited[i] = 1

    def refinement(self, rd, ctx, p):
        for blk in self.order:
            if not self.block_active[blk[1] * self.bw + blk[0]]:
                continue
            for col in self.columns[blk]:
                self.unit()
                for i in col:
                    if self.st[i] != 0 and not self.visited[i]:
                        c = 2 if self.refined[i] else (1 if sum(self.nb(i)) > 0 else 0)
                        r = rd.bit(ctx.REF[c])
                        self.touch(i)
                        self.m[i] |= r << p
                        self.k[i] = p
                        self.refined[i] = 1

    def cleanup(self, rd, ctx, p):
        if not self.active:
            self.unit()
            if rd.bit(ctx.BAND) == 0:
                return
        for blk in self.order:
            bx, by = blk
            if not self.block_active[by * self.bw + bx]:
                self.unit()
                n = 0
                for nx, ny in ((bx - 1, by), (bx + 1, by), (bx, by - 1), (bx, by + 1)):
                    if 0 <= nx < self.bw and 0 <= ny < self.bh:
                        n += self.block_active[ny * self.bw + nx]
                if rd.bit(ctx.BLOCK[min(n, 2)]) == 0:
                    continue
            for col in self.columns[blk]:
                self.unit()
                start = 0
                if len(col) == 4 and all(self.st[i] == 0 and not self.visited[i]
                                         and sum(self.nb(i)) == 0 for i in col):
                    if rd.bit(ctx.RUN) == 0:
                        continue
                    j = 2 * rd.bit(ctx.UNI[0])
                    j += rd.bit(ctx.UNI[1])
                    i = col[j]
                    self.touch(i)
                    neg = self.decode_sign(rd, ctx, i)
                    self.become_significant(i, neg, p, blk)
                    start = j + 1
                for i in col[start:]:
                    if self.st[i] == 0 and not self.visited[i]:
                        self.touch(i)
                        self.code_significance(rd, ctx, i, p, blk)
                for i in col:
                    if self.visited[i]:
                        self.touch(i)
                        self.visited[i] = 0

    # --- §7 ---
    def values(self):
        """[(x, y, value)] of the significant coefficients, band coordinates (§7)."""
        out = []
        S = self.S
        for i, s in enumerate(self.st):
            if s:
                k = self.k[i]
                out.append((i % S - 1, i // S - 1, s * (self.m[i] + ((3 << k) >> 3))))
        return out


def decode_stream(data, passes, coders, layout):
    """Run a stream's passes over its bytes until one is not decided (§6)."""
    rd = StreamDecoder(data)
    contexts = {}
    decided_passes = 0
    for _key, kind, band, c, p in passes:
        bc = coders[(band.order, c)]
        if band.w == 0 or band.h == 0:
            decided_passes += 1
            continue  # an empty band codes nothing
        cls = CODED[layout][c][1]
        ctx = contexts.setdefault((cls, band.orient), Contexts())
        try:
            if kind == PROP:
                bc.propagation(rd, ctx, p)
            elif kind == REFN:
                bc.refinement(rd, ctx, p)
            else:
                bc.cleanup(rd, ctx, p)
        except qcs_ref.Undecided:
            bc.rollback()
            break
        decided_passes += 1
    return decided_passes


# ---------------------------------------------------------------------------
# refinement.md §8: the picture
# ---------------------------------------------------------------------------

def refined_picture(h, colours, stats=None):
    """Rows of layout-channel tuples: the refinement's picture at W x H (§8), from the
    header h (with h.refinement, its header complete) and the levels' samples."""
    ref = h.refinement
    W, H, L, F = h.W, h.H, ref.L, ref.F
    layout = h.layout
    coded = CODED[layout]
    bands = bands_of(W, H, L)
    coders = {(b.order, c): BandChannel(b) for b in bands for c in range(len(coded))}
    streams = ref.streams()
    for s in range(L + 1):
        passes = stream_passes(ref, layout, bands, s)
        done = decode_stream(streams[s], passes, coders, layout)
        if stats is not None:
            stats.append((s, len(streams[s]), done, len(passes)))
    # §4: the prediction of LL from all N samples
    site_list = qcs_ref.sites(len(colours), W, H, h.L, h.Cx, h.Cy)
    positions = [qcs_ref.fixed_position(st["n"], h.L, h.Cx, h.Cy) for st in site_list]
    values = [to_coded(col, layout, F) for col in colours]
    wL, hL = bands[0].w, bands[0].h
    pred = ll_prediction(h, ref, values, positions, wL, hL)
    # §7: coefficient values into each channel's plane; §2: inverse transform
    planes = []
    for c in range(len(coded)):
        plane = [0] * (W * H)
        for b in bands:
            for x, y, v in coders[(b.order, c)].values():
                plane[(b.y0 + y) * W + b.x0 + x] = v
        for j in range(hL):
            for i in range(wL):
                plane[j * W + i] = wrap32(plane[j * W + i] + pred[c][j][i])
        inverse_2d(plane, W, H, L, ref.wavelet)
        planes.append(plane)
    rows = []
    for y in range(H):
        row = []
        for x in range(W):
            vals = []
            for c, (centred, _cls, _w) in enumerate(coded):
                v = planes[c][y * W + x]
                vals.append(v + (128 << F) if centred else v)
            row.append(from_coded(vals, layout, F))
        rows.append(row)
    return rows


def axis_weights(n, m):
    """§8, at another size, one axis: for each of the m output pixels, [(input pixel,
    integer weight)] from the n input pixels."""
    out = []
    for j in range(m):
        if m < n:
            # smaller: overlap of output [j·n, (j+1)·n) and input [x·m, (x+1)·m), in 1/m px
            lo, hi = j * n, (j + 1) * n
            out.append([(x, min(hi, (x + 1) * m) - max(lo, x * m))
                        for x in range(lo // m, (hi + m - 1) // m)])
        elif m > n:
            # larger: t = ((2j+1)·n − m) / (2m) clamped to [0, n − 1], in units of 1/(2m)
            t = min(max((2 * j + 1) * n - m, 0), (n - 1) * 2 * m)
            x, f = divmod(t, 2 * m)
            out.append([(x, 2 * m - f)] + ([(x + 1, f)] if f else []))
        else:
            out.append([(j, 1)])
    return out


def resized(pic, w, h):
    """§8, at another size: the W x H picture pic (rows of tuples) at w x h, each axis by
    its weights, each channel rounded once: floor((2·Σ + T) / (2·T)), T the weights' sum."""
    W, H = len(pic[0]), len(pic)
    wx, wy = axis_weights(W, w), axis_weights(H, h)
    out = []
    for j in range(h):
        row = []
        for i in range(w):
            acc = [0] * len(pic[0][0])
            total = 0
            for y, ky in wy[j]:
                for x, kx in wx[i]:
                    k = kx * ky
                    total += k
                    for c, v in enumerate(pic[y][x]):
                        acc[c] += k * v
            row.append(tuple((2 * a + total) // (2 * total) for a in acc))
        out.append(row)
    return out


def picture_of_file(data, stats=None, size=None):
    """(header, picture, refined) of a .qcs file or prefix: the refinement's picture once
    its header is complete, else the levels' (qcs_picture.py), at the image's size or at
    size = (w, h). header is None when the prefix ends inside the header."""
    h, colours, _verified = qcs_ref.decode(data)
    if h is None:
        return None, None, False
    w, hh = size or (h.W, h.H)
    if h.refinement is None or not h.refinement.header_complete:
        # the levels' picture (reconstruction.md), as qcs_picture.picture_of_file draws it,
        # at the output's pixel centres
        site_list = qcs_ref.sites(len(colours), h.W, h.H, h.L, h.Cx, h.Cy) if colours else []
        samples = [(s["n"], c) for s, c in zip(site_list, colours)]
        pic = qcs_picture.picture(samples, h.W, h.H, h.L, h.Cx, h.Cy, h.channels, w, hh)
        return h, pic, False
    pic = refined_picture(h, colours, stats)
    return h, pic if (w, hh) == (h.W, h.H) else resized(pic, w, hh), True


def main(argv):
    args = argv[1:]
    ref = None
    if "--compare" in args:
        k = args.index("--compare")
        ref = args[k + 1]
        del args[k:k + 2]
    size = None
    if "--size" in args:
        k = args.index("--size")
        size = tuple(int(v) for v in args[k + 1].split("x"))
        del args[k:k + 2]
    if not args:
        sys.stderr.write(__doc__)
        sys.exit(2)
    data = open(args[0], "rb").read()
    if len(args) > 1:
        data = data[:int(args[1])]
    stats = []
    try:
        h, pic, refined = picture_of_file(data, stats, size)
    except qcs_ref.QcsError as err:
        sys.stderr.write("error: %s\n" % err)
        sys.exit(1)
    if h is None:
        sys.stderr.write("the prefix ends inside the header: no picture\n")
        sys.exit(1)
    for s, nbytes, done, total in stats:
        sys.stderr.write("stream %d: %d bytes, %d of %d passes decided\n" % (s, nbytes, done, total))
    if ref is None:
        sys.stdout.buffer.write(qcs_picture.png_bytes(pic, h.channels))
        return
    w, hh, ch, want = qcs_picture.read_png(open(ref, "rb").read())
    if (w, hh, ch) != (len(pic[0]), len(pic), h.channels):
        print("FAIL: %s is %dx%d with %d channels, the picture %dx%d with %d"
              % (ref, w, hh, ch, len(pic[0]), len(pic), h.channels))
        sys.exit(1)
    worst, off1, first = qcs_picture.compare(want, pic)
    tolerance = 0 if refined else 1
    what = "refinement" if refined else "levels"
    if worst <= tolerance:
        print("PASS %s (max diff %d, %d pixels off by 1)" % (what, worst, off1))
    else:
        x, y = next((x, y) for y, (ra, rb) in enumerate(zip(want, pic))
                    for x, (pa, pb) in enumerate(zip(ra, rb))
                    if max(abs(a - b) for a, b in zip(pa, pb)) > tolerance)
        print("FAIL %s (max diff %d): first pixel off: x %d, y %d, expected %s, got %s"
              % (what, worst, x, y, want[y][x], pic[y][x]))
        sys.exit(1)


if __name__ == "__main__":
    main(sys.argv)
