#!/usr/bin/env python3
"""Would a transform-coded residual on top of a qcs prefix beat JPEG 2000 alone?

For each photograph and total budget T (1, 2, 4, 8 KiB): JPEG 2000 alone in T bytes, against
the first B0 bytes of the qcs file (quality 50) rendered by Gouraud plus JPEG 2000 of the
residual (original - render, offset by 128) in the remaining T - B0 bytes. Both JPEG 2000
streams are OpenJPEG, irreversible 9/7, one quality layer, the compression ratio bisected to
fill the budget. Prints the PSNR (dB, MSE pooled over R, G, B) of each.

    apt-get install libopenjp2-tools; pip install numpy pillow
    cargo build --release
    python3 lab/examples/hybrid_j2k.py ../shared/corpus/dev/{astronaut,boats,coffee,fruits}.png
"""
import os, subprocess, sys, tempfile
import numpy as np
from PIL import Image

QCS = os.path.join(os.path.dirname(__file__), '..', '..', 'target', 'release', 'qcs')
BUDGETS = [1024, 2048, 4096, 8192]
BASES = [384, 512, 768, 1024, 1536]
TMP = tempfile.mkdtemp()


def psnr(a, b):
    return 10 * np.log10(255 ** 2 / np.mean((a.astype(float) - b.astype(float)) ** 2))


def j2k(pixels, budget):
    """The picture JPEG 2000 makes of `pixels` in at most `budget` bytes."""
    src, cs, out = (os.path.join(TMP, n) for n in ('in.ppm', 'cs.j2k', 'out.ppm'))
    Image.fromarray(pixels).save(src)
    run = lambda r: subprocess.run(['opj_compress', '-i', src, '-o', cs, '-r', str(r), '-I'],
                                   capture_output=True, check=True)
    lo, hi, best = 1.0, 20000.0, 20000.0
    for _ in range(18):
        r = (lo * hi) ** 0.5
        run(r)
        if os.path.getsize(cs) <= budget:
            best, hi = r, r
        else:
            lo = r
    run(best)
    subprocess.run(['opj_decompress', '-i', cs, '-o', out], capture_output=True, check=True)
    return np.array(Image.open(out).convert('RGB'))


for path in sys.argv[1:]:
    name = os.path.splitext(os.path.basename(path))[0]
    orig = np.array(Image.open(path).convert('RGB'))
    qf, base_png = os.path.join(TMP, 'f.qcs'), os.path.join(TMP, 'base.png')
    subprocess.run([QCS, 'encode', '-q', '--quality', '50', path, qf], check=True)
    for t in BUDGETS:
        cols = ['j2k %.2f' % psnr(j2k(orig, t), orig)]
        for b0 in (b for b in BASES if b < t):
            subprocess.run([QCS, 'decode', '-q', '--bytes', str(b0), qf, base_png], check=True)
            base = np.array(Image.open(base_png).convert('RGB')).astype(int)
            res = np.clip(orig.astype(int) - base + 128, 0, 255).astype(np.uint8)
            rec = np.clip(base + j2k(res, t - b0).astype(int) - 128, 0, 255)
            cols.append('qcs %d B + j2k %.2f' % (b0, psnr(rec, orig)))
        print(name, t, ', '.join(cols), flush=True)
