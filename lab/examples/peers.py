#!/usr/bin/env python3
"""qcs side by side with the peer codecs, in one run: the numbers of the README's comparison.

Install (Debian/Ubuntu) and run, from the repository's root:

    apt-get install libopenjp2-tools libjpeg-turbo-progs webp optipng
    pip install numpy pillow scikit-image
    cargo build --release
    python3 lab/examples/peers.py ../shared/corpus/dev/*.png                # full run, minutes
    python3 lab/examples/peers.py --quick ../shared/corpus/dev/*.png        # a subset, faster
    QCS=/path/to/qcs python3 lab/examples/peers.py --csv rows.csv --work out/ IMAGE...

Options: `--sections 1,2,3,4` runs only some of the measurements, `--csv PATH` names the CSV of
every raw row (default `peers.csv`), `--work DIR` keeps every encoded and decoded file there
(default: a temporary directory, removed at the end). The qcs binary is `$QCS`, by default
`target/release/qcs` of this repository. Everything runs one process at a time.

Quality is measured on the full-size picture: PSNR over R, G, B with the MSE pooled over the
three channels (100 dB for identical pictures), SSIM as
`skimage.metrics.structural_similarity(a, b, channel_axis=2, data_range=255)`.
A rate R in bits per pixel means R·W·H/8 bytes of whole file.

Tables printed (Markdown on standard output):

1. Whole file at equal bytes, for R in 0.2 … 2.5 bpp: mean PSNR, mean SSIM and mean actual
   bits per pixel of each codec. qcs: `--target-size` (the file checked to be at most the
   target). JPEG 2000: OpenJPEG `opj_compress -I -r` (9/7, one layer), the ratio bisected to
   the largest file at most the target. WebP: `cwebp -m 6 -q`, q bisected likewise (cwebp's
   own `-size` overshoots). JPEG: `cjpeg -optimize -progressive -quality q` for q = 5..100,
   PSNR and SSIM interpolated at the target rate on the (log rate, quality) curve. "(k/n)":
   only k of the n photographs reach that rate within the codec's range. Then how full each
   file is (file / target bytes; WebP cannot exceed its q = 100 size), BD-PSNR of qcs
   against each peer (Bjøntegaard: PSNR fitted as a cubic in log rate for each codec over
   its points in 0.2–2.5 bpp, at the files' actual rates; the difference of the fits
   integrated over the common range, divided by its length; > 0: qcs is better), per photo
   and mean, and where qcs's PSNR is below a peer's: rates where the mean is, and every
   single photograph and rate where it is (with qcs's file / target, since a file that
   leaves bytes unused loses at equal target bytes what BD-PSNR, at actual rates, keeps).
2. Previews: mean PSNR of the full-size picture decoded from the first B bytes of one file.
   qcs at default quality (`qcs decode --bytes B`). JPEG 2000 with 18 quality layers
   (`opj_compress -I -r` at the ratios 16·2^(k/2), k = 17..0, i.e. 5793 … 16: half-octave
   layers from about 130 bytes to 1.5 bpp; peers-dev.md does not give its ladder: this one
   comes within 0.11 dB of its j2k-layers row from 1 to 8 KiB and is above it at 256 and
   512 B and at the full file) cut back to the last complete packet before B
   ("j2k-layers": the packet lengths are read from the PLT markers of a second encoding with
   `-PLT`, whose packets are byte for byte the same) or cut at B ("j2k-layers-rawcut"), both
   decoded by `opj_decompress -allow-partial` (no EOC marker appended: OpenJPEG reads an
   appended FF D9 as the start of another packet and the picture collapses). Progressive JPEG
   q75 (`cjpeg -optimize -progressive -quality 75`) cut at B, decoded by djpeg, which
   tolerates a cut file. A prefix that does not decode counts as flat grey (128). Then the
   best peer's numbers from ../shared/peers-dev.md (ThumbHash up to 256 B, its j2k-layers
   from 512 B) and qcs's margin over them and over the best peer measured here.
3. Lossless: `qcs encode --lossless`, checked to decode to exactly the input's pixels (same
   channels, same values), against `optipng -o2` of the same picture as PNG; the photographs,
   then a 301×199 crop of the first one as grey (L), grey+alpha (LA), RGB and RGBA, the alpha
   a diagonal gradient 0..255.
4. Speed and memory, one thread (`RAYON_NUM_THREADS=1` for qcs; OpenJPEG 2.5 as it runs by
   default, without `-threads` and with OPJ_NUM_THREADS unset: one thread, no thread pool,
   where `-threads 1` adds a worker thread and doubles opj_decompress's CPU time;
   libjpeg-turbo's tools do not thread), median over 3 runs of `/usr/bin/time` (CPU = user +
   sys seconds, peak = max RSS), on a 12-megapixel picture (4000×3000: a 4×4 grid of
   1000×750 cells, each a dev photograph scaled by Lanczos to cover the cell and centre-
   cropped, the photographs in turn, mirrored on their second use) and on the input photo
   closest to 0.3 Mpx. Encode from PPM: qcs at default quality, `opj_compress -I -r` at the
   ratio that gives qcs's file size, `cjpeg -quality 85`. Decode to PPM: `qcs decode`,
   `opj_decompress`, `djpeg`. Thumbnail of 1/8 the size: `qcs decode --size W/8xH/8`,
   `opj_decompress -r 3`, `djpeg -scale 1/8`.

`--quick`: rates 0.25 / 0.5 / 1 / 2 bpp, budgets 64 / 512 / 2048 / 8192 B, JPEG q in steps of
5, one timing run and a 3-megapixel (2000×1500) picture instead of 12.
"""
import argparse
import csv
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from PIL import Image
from skimage.metrics import structural_similarity

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
QCS = os.environ.get('QCS', os.path.join(REPO, 'target', 'release', 'qcs'))
os.environ.pop('OPJ_NUM_THREADS', None)  # OpenJPEG's thread pool: none, one thread

RATES = [0.2, 0.25, 0.35, 0.5, 0.7, 1.0, 1.4, 2.0, 2.5]
BUDGETS = [32, 64, 128, 256, 512, 1024, 2048, 4096, 8192]
QUICK_RATES = [0.25, 0.5, 1.0, 2.0]
QUICK_BUDGETS = [64, 512, 2048, 8192]
J2K_LAYER_RATIOS = [16 * 2 ** (k / 2) for k in range(17, -1, -1)]
# ../shared/peers-dev.md: the best peer at each budget (ThumbHash, then j2k-layers).
PEERS_DEV_BEST = {32: 15.34, 64: 15.34, 128: 15.34, 256: 15.34, 512: 19.13, 1024: 21.80,
                  2048: 23.82, 4096: 25.77, 8192: 28.13}
PEERS_DEV_FLOOR = 10.36
GREY = 128
PEER_NAMES = {'j2k': 'JPEG 2000', 'jpeg': 'JPEG'}
CSV_FIELDS = ['section', 'image', 'width', 'height', 'codec', 'setting', 'target_bytes',
              'bytes', 'bpp', 'psnr', 'ssim', 'exact', 'wall_s', 'user_s', 'sys_s',
              'maxrss_kb', 'note']


# ---------------------------------------------------------------- plumbing

class Run:
    """Where files go and where raw rows are collected."""

    def __init__(self, work, quick):
        self.work = work
        self.quick = quick
        self.rows = []

    def path(self, *parts):
        p = os.path.join(self.work, *parts)
        os.makedirs(os.path.dirname(p), exist_ok=True)
        return p

    def row(self, **fields):
        self.rows.append(fields)
        return fields


def sh(cmd, env=None, check=True):
    """Run a command quietly; its output is not parsed (files are)."""
    full_env = dict(os.environ, **(env or {}))
    r = subprocess.run([str(c) for c in cmd], capture_output=True, env=full_env)
    if check and r.returncode != 0:
        raise RuntimeError('%s failed (%d): %s' % (' '.join(map(str, cmd)), r.returncode,
                                                    r.stderr.decode(errors='replace')[-500:]))
    return r


def size(path):
    return os.path.getsize(path)


def load(path):
    with Image.open(path) as im:
        return np.array(im.convert('RGB'))


def psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return 100.0 if mse == 0 else min(100.0, 10 * np.log10(255.0 ** 2 / mse))


def ssim(a, b):
    return float(structural_similarity(a, b, channel_axis=2, data_range=255))


def grey_like(a):
    return np.full_like(a, GREY)


def bpp(nbytes, w, h):
    return nbytes * 8.0 / (w * h)


def mean(xs):
    xs = [x for x in xs if x is not None]
    return sum(xs) / len(xs) if xs else None


def largest_under(encode, lo, hi, target, out, iters=12, log=False, close=0.998):
    """Bisect a parameter x in [lo, hi] (on a log scale if `log`) whose file size grows with
    x, for the largest file of at most `target` bytes, stopping once within `close` of it.
    `encode(x, path)` writes a file. Leaves the best file at `out` and returns its x, or None
    when even `lo` gives a file above the target."""
    root, ext = os.path.splitext(out)
    trial = root + '-try' + ext
    to_x, from_x = (np.exp, np.log) if log else (float, float)
    best = {}

    def fits(x):
        encode(x, trial)
        n = size(trial)
        if n <= target and n > best.get('bytes', -1):
            shutil.copyfile(trial, out)
            best.update(x=x, bytes=n)
        return n <= target

    if not fits(hi):
        a, b = from_x(lo), from_x(hi)
        for _ in range(iters):
            x = to_x((a + b) / 2)
            if fits(x):
                if best['bytes'] >= close * target:
                    break
                a = from_x(x)
            else:
                b = from_x(x)
        if not best:
            fits(lo)
    os.remove(trial)
    return best.get('x')


# ---------------------------------------------------------------- codecs

def qcs_encode(src, out, *opts):
    sh([QCS, 'encode', '-q', *opts, src, out])


def qcs_decode(qf, out, *opts, check=True):
    """The picture of a qcs file (or of its first --bytes); None if it does not decode."""
    if os.path.exists(out):
        os.remove(out)
    r = sh([QCS, 'decode', '-q', qf, out, *opts], check=check)
    return load(out) if r.returncode == 0 and os.path.exists(out) else None


def j2k_encode(ppm, out, ratios, *opts):
    sh(['opj_compress', '-i', ppm, '-o', out, '-I',
        '-r', ','.join('%.6g' % r for r in ratios), *opts])


def j2k_decode(cs, out, *opts):
    """The picture of a (possibly cut) JPEG 2000 codestream; None if it does not decode."""
    if os.path.exists(out):
        os.remove(out)
    r = sh(['opj_decompress', '-i', cs, '-o', out, '-allow-partial', *opts],
           check=False)
    return load(out) if r.returncode == 0 and os.path.exists(out) and size(out) else None


def webp_encode(ppm, out, q):
    sh(['cwebp', '-quiet', '-m', '6', '-q', '%.3f' % q, ppm, '-o', out])


def webp_decode(f, out):
    sh(['dwebp', '-quiet', f, '-ppm', '-o', out])
    return load(out)


def jpeg_encode(ppm, out, q, *opts):
    sh(['cjpeg', *opts, '-quality', str(q), '-outfile', out, ppm])


def jpeg_decode(f, out):
    """djpeg's picture of a (possibly cut) JPEG; None if it makes none."""
    if os.path.exists(out):
        os.remove(out)
    r = sh(['djpeg', '-outfile', out, f], check=False)  # 2: warnings, e.g. a cut file
    if r.returncode in (0, 2) and os.path.exists(out) and size(out):
        try:
            return load(out)
        except Exception:
            return None
    return None


def cut(src, nbytes, out):
    with open(src, 'rb') as f:
        data = f.read(nbytes)
    with open(out, 'wb') as f:
        f.write(data)
    return out


def j2k_tile_parts(cs):
    """[(start of the packets, end of the tile-part, [packet lengths from PLT])] of a
    codestream; lengths are empty without PLT markers."""
    u16 = lambda p: int.from_bytes(cs[p:p + 2], 'big')
    p = 2  # after SOC
    while u16(p) != 0xFF90:  # main header markers up to the first SOT
        p += 2 + u16(p + 2)
    parts = []
    while p + 2 <= len(cs) and u16(p) == 0xFF90:
        psot = int.from_bytes(cs[p + 6:p + 10], 'big')
        end = p + psot if psot else len(cs) - 2
        q, lens = p + 12, []
        while u16(q) != 0xFF93:  # tile-part header markers up to SOD
            seg = u16(q + 2)
            if u16(q) == 0xFF58:  # PLT: Zplt, then lengths, 7 bits a byte, high bit: more
                v = 0
                for byte in cs[q + 5:q + 2 + seg]:
                    v = (v << 7) | (byte & 0x7F)
                    if not byte & 0x80:
                        lens.append(v)
                        v = 0
            q += 2 + seg
        parts.append((q + 2, end, lens))
        p = end
    return parts


def j2k_packet_ends(plain, with_plt):
    """Byte offsets in the codestream `plain` at which a packet ends, from the PLT markers of
    `with_plt`, the same encoding with -PLT."""
    with open(plain, 'rb') as f:
        a = f.read()
    with open(with_plt, 'rb') as f:
        b = f.read()
    pa, pb = j2k_tile_parts(a), j2k_tile_parts(b)
    if len(pa) != len(pb):
        raise RuntimeError('PLT and plain encodings differ in tile-parts')
    ends = []
    for (sa, ea, _), (sb, eb, lens) in zip(pa, pb):
        if a[sa:ea] != b[sb:eb] or sum(lens) != ea - sa:
            raise RuntimeError('PLT and plain encodings differ in their packets')
        ends.extend(sa + int(x) for x in np.cumsum(lens))
    return ends


# ---------------------------------------------------------------- inputs

class Photo:
    def __init__(self, run, path):
        self.name = os.path.splitext(os.path.basename(path))[0]
        self.src = path
        self.px = load(path)
        self.h, self.w = self.px.shape[:2]
        self.ppm = run.path(self.name, 'src.ppm')
        Image.fromarray(self.px).save(self.ppm)

    def rate_bytes(self, rate):
        return int(rate * self.w * self.h / 8)

    def bpp(self, nbytes):
        return bpp(nbytes, self.w, self.h)


# ---------------------------------------------------------------- 1. whole file

def whole_file_points(run, photo, rates):
    """Rows (codec, rate) -> {'bpp', 'psnr', 'ssim', 'bytes'} for the four codecs."""
    d = lambda f: run.path(photo.name, 'whole', f)
    out = {}

    def record(codec, rate, target, f, pic, setting, note=''):
        n = size(f)
        r = run.row(section='1-whole', image=photo.name, width=photo.w, height=photo.h,
                    codec=codec, setting=setting, target_bytes=target, bytes=n,
                    bpp=photo.bpp(n), psnr=psnr(photo.px, pic), ssim=ssim(photo.px, pic),
                    note=note)
        out[codec, rate] = r

    for rate in rates:
        target = photo.rate_bytes(rate)
        # qcs: its own size target
        qf = d('qcs-%g.qcs' % rate)
        qcs_encode(photo.src, qf, '--target-size', target)
        note = '' if size(qf) <= target else 'OVER TARGET'
        record('qcs', rate, target, qf, qcs_decode(qf, d('qcs-%g.png' % rate)),
               '--target-size %d' % target, note)
        # JPEG 2000, one layer: bisect the rate in bpp (ratio = 24 / bpp)
        f = d('j2k-%g.j2k' % rate)
        x = largest_under(lambda x, o: j2k_encode(photo.ppm, o, [24 / x]),
                          rate * 0.7, rate * 1.3, target, f, log=True)
        if x is not None:
            record('j2k', rate, target, f, j2k_decode(f, d('j2k-%g.ppm' % rate)),
                   '-r %.5g' % (24 / x))
        # WebP: bisect q
        f = d('webp-%g.webp' % rate)
        x = largest_under(lambda q, o: webp_encode(photo.ppm, o, q), 0, 100, target, f)
        if x is not None:
            record('webp', rate, target, f, webp_decode(f, d('webp-%g.ppm' % rate)),
                   '-q %.3f' % x)
    out.update(jpeg_interpolated(run, photo, rates))
    return out


def jpeg_interpolated(run, photo, rates):
    """cjpeg q = 5..100, PSNR and SSIM interpolated at each rate on the log-rate curve."""
    d = lambda f: run.path(photo.name, 'jpeg-sweep', f)
    step = 5 if run.quick else 1
    sweep = []
    for q in range(5, 101, step):
        f = d('q%d.jpg' % q)
        jpeg_encode(photo.ppm, f, q, '-optimize', '-progressive')
        pic = jpeg_decode(f, d('q%d.ppm' % q))
        sweep.append({'q': q, 'bytes': size(f), 'psnr': psnr(photo.px, pic), 'pic': pic})
        run.row(section='1-jpeg-sweep', image=photo.name, width=photo.w, height=photo.h,
                codec='jpeg', setting='-quality %d' % q, bytes=size(f), bpp=photo.bpp(size(f)),
                psnr=sweep[-1]['psnr'])
    sweep.sort(key=lambda s: s['bytes'])
    out = {}
    for rate in rates:
        target = photo.rate_bytes(rate)
        i = next((i for i, s in enumerate(sweep) if s['bytes'] >= target), None)
        if i is None or i == 0 and sweep[0]['bytes'] > target:
            continue  # outside q = 5..100
        lo, hi = sweep[max(i - 1, 0)], sweep[i]
        t = 0.0 if hi is lo else ((np.log(target) - np.log(lo['bytes']))
                                   / (np.log(hi['bytes']) - np.log(lo['bytes'])))
        for s in (lo, hi):
            if 'ssim' not in s:
                s['ssim'] = ssim(photo.px, s['pic'])
        lerp = lambda k: lo[k] + t * (hi[k] - lo[k])
        out['jpeg', rate] = run.row(
            section='1-whole', image=photo.name, width=photo.w, height=photo.h, codec='jpeg',
            setting='interpolated q%d..q%d' % (lo['q'], hi['q']), target_bytes=target,
            bytes=target, bpp=photo.bpp(target), psnr=lerp('psnr'), ssim=lerp('ssim'))
    for s in sweep:
        s.pop('pic')
    return out


def bd_psnr(ref, test):
    """Bjøntegaard delta PSNR of `test` over `ref`, each [(bpp, psnr)]: cubic fits in log
    rate, integrated over the common range, divided by its length; None if < 4 points or no
    overlap."""
    if len(ref) < 4 or len(test) < 4:
        return None
    fits = []
    for pts in (ref, test):
        lr = np.log([p[0] for p in pts])
        fits.append((np.polyfit(lr, [p[1] for p in pts], 3), lr.min(), lr.max()))
    lo, hi = max(f[1] for f in fits), min(f[2] for f in fits)
    if hi <= lo:
        return None
    area = [np.polyval(np.polyint(p), hi) - np.polyval(np.polyint(p), lo) for p, _, _ in fits]
    return (area[1] - area[0]) / (hi - lo)


def section_whole(run, photos, rates):
    codecs = ['qcs', 'j2k', 'webp', 'jpeg']
    peers = codecs[1:]
    names = {'qcs': 'qcs (`--target-size`)', 'j2k': 'JPEG 2000 (OpenJPEG 9/7, one layer)',
             'webp': 'WebP (libwebp, -m 6)', 'jpeg': 'JPEG (libjpeg-turbo, progressive, optimized)'}
    pts = {}
    for p in photos:
        t = time.time()
        pts[p.name] = whole_file_points(run, p, rates)
        print('  [1] %s: %.0f s' % (p.name, time.time() - t), file=sys.stderr, flush=True)
    n = len(photos)

    def cell(codec, rate, key, fmt):
        vals = [pts[p.name][codec, rate][key] for p in photos if (codec, rate) in pts[p.name]]
        if not vals:
            return '–'
        s = fmt % (sum(vals) / len(vals))
        return s if len(vals) == n else '%s (%d/%d)' % (s, len(vals), n)

    head = '| codec | ' + ' | '.join('%g bpp' % r for r in rates) + ' |\n|---|' + '---|' * len(rates)
    for title, key, fmt in (('mean PSNR (dB)', 'psnr', '%.2f'), ('mean SSIM', 'ssim', '%.4f'),
                            ('mean actual bits per pixel of the file', 'bpp', '%.3f')):
        print('\n### 1. Whole file at equal bytes: %s, %d photographs\n' % (title, n))
        print(head)
        for c in codecs:
            print('| %s | %s |' % (names[c], ' | '.join(cell(c, r, key, fmt) for r in rates)))
    print('\nFile / target bytes (mean, min); files under 98 % of the target:\n')
    for c in codecs[:3]:
        got = [(p.name, r, pts[p.name][c, r]) for p in photos for r in rates
               if (c, r) in pts[p.name]]
        fill = [(x, r, v['bytes'] / v['target_bytes']) for x, r, v in got]
        over = [f for f in fill if f[2] > 1]
        short = ['%s@%g %.0f%%' % (x, r, 100 * f) for x, r, f in fill if f < 0.98]
        print('- %s: %.3f, %.3f;%s %s' % (
            c, np.mean([f[2] for f in fill]), min(f[2] for f in fill),
            ' **%d over the target**;' % len(over) if over else '',
            ', '.join(short) if short else 'none'))
    print('\n### 1. BD-PSNR of qcs against each peer (dB, > 0: qcs better), 0.2–2.5 bpp\n')
    print('| photo | ' + ' | '.join('vs %s' % c for c in peers) + ' |\n|---|' + '---|' * len(peers))
    bd = {c: [] for c in peers}
    for p in photos:
        curve = lambda c: sorted((v['bpp'], v['psnr']) for (cc, _), v in pts[p.name].items()
                                 if cc == c)
        cells = []
        for c in peers:
            v = bd_psnr(curve(c), curve('qcs'))
            bd[c].append(v)
            cells.append('–' if v is None else '%+.2f' % v)
            run.row(section='1-bd-psnr', image=p.name, codec='qcs', setting='vs ' + c, psnr=v)
        print('| %s | %s |' % (p.name, ' | '.join(cells)))
    print('| **mean** | %s |' % ' | '.join(
        '–' if mean(bd[c]) is None else '**%+.2f**' % mean(bd[c]) for c in peers))

    print('\nWhere qcs is below a peer at equal target bytes (photo@bpp, dB, qcs file / '
          'target):\n')
    for c in peers:
        below_mean, below = [], []
        for r in rates:
            both = [p.name for p in photos if (c, r) in pts[p.name]]
            d = {x: pts[x]['qcs', r]['psnr'] - pts[x][c, r]['psnr'] for x in both}
            if d and np.mean(list(d.values())) < 0:
                below_mean.append('%g bpp (%+.2f)' % (r, np.mean(list(d.values()))))
            below += ['%s@%g %+.2f (%.0f%%)' % (x, r, v, 100 * pts[x]['qcs', r]['bytes']
                                                / pts[x]['qcs', r]['target_bytes'])
                      for x, v in d.items() if v < 0]
        print('- vs %s: mean below at %s; single photographs below at %d of %d points%s' % (
            c, ', '.join(below_mean) or 'no rate',
            len(below), sum(1 for x in photos for r in rates if (c, r) in pts[x.name]),
            ': ' + ', '.join(below) if below else ''))


# ---------------------------------------------------------------- 2. previews

def preview_curves(run, photo, budgets):
    """{codec: {budget or 'full': psnr}} and {codec: file size} of one photograph."""
    d = lambda f: run.path(photo.name, 'prefix', f)
    grey = psnr(photo.px, grey_like(photo.px))
    res, sizes = {}, {}

    def curve(codec, f, decode_prefix):
        n = size(f)
        sizes[codec] = n
        res[codec] = {}
        for b in budgets + ['full']:
            pic = decode_prefix(min(n, b) if b != 'full' else n, b)
            v = grey if pic is None else psnr(photo.px, pic)
            res[codec][b] = v
            run.row(section='2-prefix', image=photo.name, width=photo.w, height=photo.h,
                    codec=codec, setting='first %s bytes' % b, target_bytes=b if b != 'full' else n,
                    bytes=min(n, b) if b != 'full' else n, bpp=photo.bpp(n), psnr=v,
                    note='' if pic is not None else 'no picture: flat grey')

    qf = d('default.qcs')
    qcs_encode(photo.src, qf)
    curve('qcs', qf, lambda n, b: qcs_decode(qf, d('qcs-%s.png' % b), '--bytes', n, check=False))

    plain, plt = d('layers.j2k'), d('layers-plt.j2k')
    j2k_encode(photo.ppm, plain, J2K_LAYER_RATIOS)
    j2k_encode(photo.ppm, plt, J2K_LAYER_RATIOS, '-PLT')
    ends = j2k_packet_ends(plain, plt)

    def j2k_packets(n, b):
        if n == size(plain):
            return j2k_decode(plain, d('j2k-full.ppm'))
        last = max((e for e in ends if e <= n), default=None)
        if last is None:
            return None
        return j2k_decode(cut(plain, last, d('j2k-%s.j2k' % b)), d('j2k-%s.ppm' % b))
    curve('j2k-layers', plain, j2k_packets)
    curve('j2k-layers-rawcut', plain, lambda n, b: j2k_decode(
        cut(plain, n, d('j2kraw-%s.j2k' % b)), d('j2kraw-%s.ppm' % b)))

    jf = d('prog-q75.jpg')
    jpeg_encode(photo.ppm, jf, 75, '-optimize', '-progressive')
    curve('jpeg-prog-q75', jf, lambda n, b: jpeg_decode(cut(jf, n, d('jpeg-%s.jpg' % b)),
                                                       d('jpeg-%s.ppm' % b)))
    return grey, res, sizes


def section_previews(run, photos, budgets):
    rows, grey, sizes = {}, [], {}
    for p in photos:
        t = time.time()
        g, res, sz = preview_curves(run, p, budgets)
        grey.append(g)
        for c, v in res.items():
            rows.setdefault(c, []).append(v)
            sizes.setdefault(c, []).append((sz[c], p.bpp(sz[c])))
        print('  [2] %s: %.0f s' % (p.name, time.time() - t), file=sys.stderr, flush=True)
    cols = budgets + ['full']
    m = {c: {b: mean([v[b] for v in vs]) for b in cols} for c, vs in rows.items()}
    fmtb = lambda b: '%d B' % b
    print('\n### 2. Previews: mean PSNR (dB) of the full-size picture from the first N bytes, '
          '%d photographs\n' % len(photos))
    print('| codec | ' + ' | '.join(map(fmtb, budgets)) + ' | full file | mean size | bpp |')
    print('|---|' + '---|' * (len(budgets) + 3))
    print('| *flat grey (floor)* | ' + ' | '.join('%.2f' % mean(grey) for _ in budgets) + ' | | | |')
    labels = {'qcs': '**qcs** (default quality 85)'}
    for c in rows:
        s = sizes[c]
        print('| %s | %s | %.2f | %s B | %.3f |' % (
            labels.get(c, c), ' | '.join('%.2f' % m[c][b] for b in budgets), m[c]['full'],
            format(round(mean([x[0] for x in s])), ','), mean([x[1] for x in s])))
    best_here = {b: max(m[c][b] for c in rows if c != 'qcs') for b in budgets}
    dev = [PEERS_DEV_BEST.get(b) for b in budgets]
    print('| *best peer, peers-dev.md* | ' + ' | '.join(
        '–' if v is None else '%.2f %s' % (v, 'ThumbHash' if b <= 256 else 'j2k-layers')
        for b, v in zip(budgets, dev)) + ' | | | |')
    print('| qcs − best peer of peers-dev.md | ' + ' | '.join(
        '–' if v is None else '%+.2f' % (m['qcs'][b] - v) for b, v in zip(budgets, dev)) + ' | | | |')
    print('| qcs − best peer measured here | ' + ' | '.join(
        '%+.2f' % (m['qcs'][b] - best_here[b]) for b in budgets) + ' | | | |')
    print('\nFloor here %.2f dB (peers-dev.md: %.2f). The best peer measured here is the best '
          'of the other rows at each budget.' % (mean(grey), PEERS_DEV_FLOOR))


# ---------------------------------------------------------------- 3. lossless

def lossless_cases(run, photos):
    """(name, kind, PNG path) of every lossless test picture: the photographs as they are,
    then crops of the first one in four modes."""
    for p in photos:
        yield p.name, 'photographs', p.src
    base = photos[0]
    w, h = 301, 199
    x0, y0 = (base.w - w) // 2, (base.h - h) // 2
    crop = Image.fromarray(base.px[y0:y0 + h, x0:x0 + w])
    yy, xx = np.mgrid[0:h, 0:w]
    alpha = Image.fromarray(np.round(255 * (xx + yy) / (w + h - 2)).astype(np.uint8))
    grey = crop.convert('L')
    for mode, im in (('L', grey), ('LA', Image.merge('LA', (grey, alpha))), ('RGB', crop),
                     ('RGBA', Image.merge('RGBA', (*crop.split(), alpha)))):
        name = '%s-%dx%d-%s' % (base.name, w, h, mode)
        path = run.path('lossless', name + '.png')
        im.save(path)
        yield name, 'crops', path


def lossless_check(src, decoded):
    """'yes' if the decoded PNG has the source's channels and values, else what differs."""
    with Image.open(src) as a:
        mode, orig = a.mode, np.array(a)
    try:
        with Image.open(decoded) as b:
            got_mode, got = b.mode, np.array(b if b.mode == mode else b.convert(mode))
    except (OSError, FileNotFoundError):
        return '**NO** (does not decode)'
    if got.shape != orig.shape or not np.array_equal(got, orig):
        return '**NO** (%d values differ)' % (np.sum(got != orig) if got.shape == orig.shape
                                             else orig.size)
    return 'yes' if got_mode == mode else 'values only (decoded as %s)' % got_mode


def section_lossless(run, photos):
    print('\n### 3. Lossless: qcs `--lossless` against `optipng -o2`\n')
    print('| picture | mode | size | exact | qcs bytes | qcs bpp | optipng bytes | optipng bpp '
          '| qcs / optipng |\n|---|---|---|---|---|---|---|---|---|')
    kinds = {}
    for name, kind, src in lossless_cases(run, photos):
        d = lambda ext: run.path('lossless', name + ext)
        qf, dec, opt = d('.qcs'), d('.qcs.png'), d('.optipng.png')
        for f in (dec, opt):
            if os.path.exists(f):
                os.remove(f)
        qcs_encode(src, qf, '--lossless')
        qcs_decode(qf, dec, check=False)
        verdict = lossless_check(src, dec)
        sh(['optipng', '-quiet', '-o2', '-out', opt, src])
        with Image.open(src) as im:
            (w, h), mode = im.size, im.mode
        qn, on = size(qf), size(opt)
        kinds.setdefault(kind, []).append((bpp(qn, w, h), bpp(on, w, h), qn / on))
        print('| %s | %s | %d×%d | %s | %s | %.3f | %s | %.3f | %.3f |' % (
            name, mode, w, h, verdict, format(qn, ','), bpp(qn, w, h), format(on, ','),
            bpp(on, w, h), qn / on))
        for codec, n in (('qcs', qn), ('optipng', on)):
            run.row(section='3-lossless', image=name, width=w, height=h, codec=codec,
                    setting=mode, bytes=n, bpp=bpp(n, w, h),
                    exact=verdict == 'yes' if codec == 'qcs' else '',
                    note=verdict if codec == 'qcs' else '')
    for kind, r in kinds.items():
        print('| **mean, %s** | | | | | %.3f | | %.3f | %.3f |' % (
            kind, mean([x[0] for x in r]), mean([x[1] for x in r]), mean([x[2] for x in r])))


# ---------------------------------------------------------------- 4. speed and memory

def big_picture(run, photos, w, h):
    """A w×h picture: a 4×4 grid of cells, each a photograph (in turn, mirrored on its second
    use) scaled by Lanczos to cover the cell and centre-cropped."""
    cw, ch = w // 4, h // 4
    canvas = Image.new('RGB', (w, h))
    for k in range(16):
        p = photos[k % len(photos)]
        im = Image.fromarray(p.px)
        if (k // len(photos)) % 2:
            im = im.transpose(Image.Transpose.FLIP_LEFT_RIGHT)
        s = max(cw / p.w, ch / p.h)
        sw, sh_ = max(cw, round(p.w * s)), max(ch, round(p.h * s))
        im = im.resize((sw, sh_), Image.Resampling.LANCZOS)
        x0, y0 = (sw - cw) // 2, (sh_ - ch) // 2
        canvas.paste(im.crop((x0, y0, x0 + cw, y0 + ch)), ((k % 4) * cw, (k // 4) * ch))
    path = run.path('speed', 'big-%dx%d.png' % (w, h))
    canvas.save(path)
    return path


def timed(run, cmd, runs, env=None):
    """Median wall seconds, CPU (user + sys) seconds and peak RSS (KB) over `runs` runs of
    `cmd` under /usr/bin/time. The peak is time's %M; the CPU seconds are the same rusage read
    to the microsecond with os.wait4 (time prints them to 10 ms, which rounds the peers' runs
    on small pictures to 0.00); they include time's own start, well under a millisecond."""
    tf = run.path('speed', 'time.txt')
    got = []
    for _ in range(runs):
        t0 = time.perf_counter()
        proc = subprocess.Popen(['/usr/bin/time', '-o', tf, '-f', '%e %U %S %M', *map(str, cmd)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                env=dict(os.environ, **(env or {})))
        _, status, ru = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode:
            raise RuntimeError('%s failed (%d)' % (' '.join(map(str, cmd)), proc.returncode))
        with open(tf) as f:
            rss = int(f.read().split()[-1])
        got.append((wall, ru.ru_utime, ru.ru_stime, rss))
    med = lambda i: statistics.median(g[i] for g in got)
    return {'wall_s': med(0), 'user_s': med(1), 'sys_s': med(2),
            'cpu': statistics.median(g[1] + g[2] for g in got), 'maxrss_kb': med(3)}


def speed_one(run, label, src_png, runs):
    """File sizes {codec: bytes} and timings {(task, codec): timing} of one picture."""
    d = lambda f: run.path('speed', label, f)
    im = load(src_png)
    h, w = im.shape[:2]
    ppm = d('src.ppm')
    Image.fromarray(im).save(ppm)
    one = {'RAYON_NUM_THREADS': '1'}
    qf, jf, pf = d('f.qcs'), d('f.j2k'), d('f.jpg')
    t = {}
    t['encode', 'qcs'] = timed(run, [QCS, 'encode', '-q', ppm, qf], runs, one)
    ratio = 3.0 * w * h / size(qf)
    t['encode', 'j2k'] = timed(run, ['opj_compress', '-i', ppm, '-o', jf, '-I',
                                     '-r', '%.6g' % ratio], runs)
    t['encode', 'jpeg'] = timed(run, ['cjpeg', '-quality', '85', '-outfile', pf, ppm], runs)
    t['decode', 'qcs'] = timed(run, [QCS, 'decode', '-q', qf, d('qcs.ppm')], runs, one)
    t['decode', 'j2k'] = timed(run, ['opj_decompress', '-i', jf, '-o', d('j2k.ppm')], runs)
    t['decode', 'jpeg'] = timed(run, ['djpeg', '-outfile', d('jpeg.ppm'), pf], runs)
    tw, th = w // 8, h // 8
    t['thumb', 'qcs'] = timed(run, [QCS, 'decode', '-q', qf, d('qcs-t.ppm'), '--size',
                                    '%dx%d' % (tw, th)], runs, one)
    t['thumb', 'j2k'] = timed(run, ['opj_decompress', '-i', jf, '-o', d('j2k-t.ppm'),
                                    '-r', '3'], runs)
    t['thumb', 'jpeg'] = timed(run, ['djpeg', '-scale', '1/8', '-outfile', d('jpeg-t.ppm'), pf],
                               runs)
    files = {'qcs': size(qf), 'j2k': size(jf), 'jpeg': size(pf)}
    for (task, codec), v in t.items():
        run.row(section='4-speed', image=label, width=w, height=h, codec=codec, setting=task,
                bytes=files[codec], bpp=bpp(files[codec], w, h), wall_s=v['wall_s'],
                user_s=v['user_s'], sys_s=v['sys_s'], maxrss_kb=v['maxrss_kb'],
                note='median of %d runs, one thread' % runs)
    return files, t


def section_speed(run, photos, runs):
    bw, bh = (2000, 1500) if run.quick else (4000, 3000)
    big = big_picture(run, photos, bw, bh)
    small = min(photos, key=lambda p: abs(p.w * p.h - 300000))
    print('\n### 4. Speed and memory, one thread, median of %d run%s\n'
          % (runs, 's' if runs > 1 else ''))
    print('| picture | task | peer | qcs CPU s | peer CPU s | qcs / peer | qcs peak MB | '
          'peer peak MB | qcs / peer |\n|---|---|---|---|---|---|---|---|---|')
    notes = []
    tasks = {'encode': 'encode', 'decode': 'decode', 'thumb': '1/8 thumbnail'}
    for label, src in (('%.0f Mpx %d×%d' % (bw * bh / 1e6, bw, bh), big),
                       ('%s %d×%d' % (small.name, small.w, small.h), small.src)):
        files, t = speed_one(run, os.path.splitext(os.path.basename(src))[0], src, runs)
        notes.append('%s: qcs %s B, JPEG 2000 %s B, JPEG q85 %s B' % (
            label, format(files['qcs'], ','), format(files['j2k'], ','),
            format(files['jpeg'], ',')))
        for task in tasks:
            q = t[task, 'qcs']
            for peer in ('j2k', 'jpeg'):
                v = t[task, peer]
                print('| %s | %s | %s | %.3f | %.3f | %.1f | %.1f | %.1f | %.1f |' % (
                    label, tasks[task], PEER_NAMES[peer], q['cpu'], v['cpu'],
                    q['cpu'] / v['cpu'], q['maxrss_kb'] / 1024,
                    v['maxrss_kb'] / 1024, q['maxrss_kb'] / v['maxrss_kb']))
    print('\nFile sizes: ' + '; '.join(notes) + '.')


# ---------------------------------------------------------------- main

def tool_versions():
    """One line per peer tool, from its own version output."""
    def first(cmd, word):
        r = sh(cmd, check=False)
        text = (r.stdout + r.stderr).decode(errors='replace')
        return next((l.strip() for l in text.splitlines() if word in l), '?')
    return ['opj_compress: ' + first(['opj_compress', '-h'], 'library v'),
            'cjpeg: ' + first(['cjpeg', '-version'], 'version'),
            'cwebp ' + first(['cwebp', '-version'], '.'),
            first(['optipng', '-v'], 'OptiPNG version')]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('images', nargs='+')
    ap.add_argument('--quick', action='store_true', help='a subset of rates and budgets')
    ap.add_argument('--sections', default='1,2,3,4')
    ap.add_argument('--csv', default='peers.csv')
    ap.add_argument('--work', help='keep every file in this directory')
    args = ap.parse_args()
    if not os.path.exists(QCS):
        sys.exit('no qcs binary at %s: cargo build --release, or set QCS' % QCS)
    sections = {int(s) for s in args.sections.split(',')}
    images = [os.path.abspath(p) for p in args.images]
    csv_path = os.path.abspath(args.csv)
    work = os.path.abspath(args.work) if args.work else tempfile.mkdtemp(prefix='qcs-peers-')
    os.makedirs(work, exist_ok=True)
    run = Run(work, args.quick)
    start = time.time()
    try:
        photos = [Photo(run, p) for p in images]
        print('# qcs and its peers on %d photograph%s%s\n' % (
            len(photos), 's' if len(photos) > 1 else '', ' (--quick)' if args.quick else ''))
        print('qcs: `%s`. Peers: %s.\n\nPhotographs: %s.' % (
            QCS, '; '.join(tool_versions()),
            ', '.join('%s %d×%d' % (p.name, p.w, p.h) for p in photos)))
        rates = QUICK_RATES if args.quick else RATES
        budgets = QUICK_BUDGETS if args.quick else BUDGETS
        if 1 in sections:
            section_whole(run, photos, rates)
        if 2 in sections:
            section_previews(run, photos, budgets)
        if 3 in sections:
            section_lossless(run, photos)
        if 4 in sections:
            section_speed(run, photos, 1 if args.quick else 3)
    finally:
        with open(csv_path, 'w', newline='') as f:
            wr = csv.DictWriter(f, fieldnames=CSV_FIELDS)
            wr.writeheader()
            for r in run.rows:
                wr.writerow({k: ('%.6g' % v if isinstance(v, float) else v)
                             for k, v in r.items()})
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)
    print('\nRaw rows: `%s`. Wall time of the run: %.0f s.' % (csv_path, time.time() - start))


if __name__ == '__main__':
    main()
