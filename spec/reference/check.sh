#!/bin/sh
# Checks the spec-only decoder (qcs_ref.py) against the conformance vectors: for every
# spec/vectors/NAME.qcs, whole and cut to its first floor(len/2) bytes, the samples it reads
# must equal NAME[.half].samples.csv (exactly; positions within 1e-5 px), and its first sites
# of three image sizes must equal spec/vectors/sites-*.csv. Then checks the spec-only
# picture (qcs_picture.py, spec/reconstruction.md): for every NAME.qcs, whole and half, every
# channel of every pixel must be within +-1 of NAME[.half].png (and the whole file drawn at
# another size, of NAME.WxH.png), and the worked example of reconstruction.md §6 must give
# its three pixels. For a version-3 file (or prefix) whose refinement header is complete the
# picture is the refinement's (qcs_refine.py, spec/refinement.md, at another size resized by
# its §8) and must equal the PNG exactly; before, it is the levels' (+-1).
# Prints PASS/FAIL per case and exits 1 on any failure. Needs python3 only.
set -u
D=$(cd "$(dirname "$0")" && pwd)
V="$D/../vectors"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
fail=0
for f in "$V"/*.qcs; do
  name=$(basename "$f" .qcs)
  len=$(wc -c < "$f")
  for case in whole half; do
    if [ "$case" = whole ]; then tag=$name; cut=$len; else tag=$name.half; cut=$((len / 2)); fi
    python3 "$D/qcs_ref.py" "$f" "$cut" > "$OUT/$tag.csv" 2> "$OUT/$tag.err"
    python3 - "$V/$tag.samples.csv" "$OUT/$tag.csv" "$tag" <<'PY' || fail=1
import csv, sys
want, got, tag = sys.argv[1:4]
a, b = list(csv.reader(open(want))), list(csv.reader(open(got)))
msg = None
if len(a) != len(b) or a[0] != b[0]:
    msg = "expected %d samples, got %d" % (len(a) - 1, len(b) - 1)
for ra, rb in zip(a[1:], b[1:]):
    if msg:
        break
    if ra[:5] != rb[:5] or ra[7] != rb[7] or max(abs(float(ra[k]) - float(rb[k])) for k in (5, 6)) > 1e-5:
        msg = "sample %s: expected %s, got %s" % (ra[0], ",".join(ra), ",".join(rb))
print("PASS %s" % tag if msg is None else "FAIL %s: %s" % (tag, msg))
sys.exit(msg is not None)
PY
  done
done
python3 - "$D" "$V" <<'PY' || fail=1
import csv, sys
sys.path.insert(0, sys.argv[1])
import qcs_ref as q
bad_any = False
for w, h in [(64, 64), (480, 320), (1000, 17)]:
    rows = list(csv.DictReader(open("%s/sites-%dx%d.csv" % (sys.argv[2], w, h))))
    L, cx, cy = 1 << 16, -w * (1 << 15), -((h << 16) // 3)
    got = q.sites(len(rows), w, h, L, cx, cy)
    bad = 0
    for s, r in zip(got, rows):
        n = tuple(int(r[k]) for k in ("n0", "n1", "n2", "n3"))
        x, y = q.pixel_position(s["n"], L, cx, cy)
        same = s["n"] == n and q.star_norm(n) == (int(r["p"]), int(r["q"]))
        bad += not (same and abs(x - float(r["x"])) <= 1e-6 and abs(y - float(r["y"])) <= 1e-6)
    print("%s sites-%dx%d (%d sites)" % ("PASS" if bad == 0 else "FAIL", w, h, len(rows)))
    bad_any |= bad > 0
sys.exit(bad_any)
PY
python3 - "$D" "$V" <<'PY' || fail=1
import glob, os, re, sys
sys.path.insert(0, sys.argv[1])
import qcs_picture as qp
import qcs_refine as qr
bad_any = False
for f in sorted(glob.glob(os.path.join(sys.argv[2], "*.qcs"))):
    name = os.path.basename(f)[:-4]
    data = open(f, "rb").read()
    # the whole file and its first half at the image's size, the whole file at another
    cases = [(name, len(data), None), (name + ".half", len(data) // 2, None)]
    for p in sorted(os.listdir(sys.argv[2])):
        m = re.fullmatch(re.escape(name) + r"\.(\d+)x(\d+)\.png", p)
        if m:
            cases.append((p[:-4], len(data), (int(m.group(1)), int(m.group(2)))))
    for tag, cut, size in cases:
        w, h, ch, want = qp.read_png(open(os.path.join(sys.argv[2], tag + ".png"), "rb").read())
        try:
            # the refinement's picture once its header is complete, else the levels' (qcs_picture)
            head, got, refined = qr.picture_of_file(data[:cut], size=size)
        except Exception as err:
            print("FAIL picture %s: %s: %s" % (tag, type(err).__name__, err))
            bad_any = True
            continue
        if head is None or (w, h, ch) != (len(got[0]), len(got), head.channels):
            print("FAIL picture %s: the PNG is %dx%d with %d channels, the picture is not" % (tag, w, h, ch))
            bad_any = True
            continue
        worst, off1, first = qp.compare(want, got)
        if refined:
            if worst == 0:
                print("PASS picture %s (refinement, exact)" % tag)
            else:
                print("FAIL picture %s (refinement, max diff %d, %d pixels off by 1)%s"
                      % (tag, worst, off1, "" if first is None else ": first pixel off by more "
                         "than 1: x %d, y %d, channel %d, expected %d, got %d" % first))
                bad_any = True
        elif first is None:
            print("PASS picture %s (max diff %d, %d pixels off by 1)" % (tag, worst, off1))
        else:
            print("FAIL picture %s (max diff %d): first pixel off by more than 1: "
                  "x %d, y %d, channel %d, expected %d, got %d" % ((tag, worst) + first))
            bad_any = True
# reconstruction.md §6: 32x32 grey, L = 8 px, origin (16, 16) px, the five unit roots with
# colours 0, 50, 100, 150, 200; pixels (20, 16) = 42, (16, 20) = 74, (12, 12) = 139.
roots = [(1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1), (-1, -1, -1, -1)]
pic = qp.picture([(n, (50 * m,)) for m, n in enumerate(roots)], 32, 32, 8 << 16, 16 << 16, 16 << 16, 1)
got = [(x, y, pic[y][x][0]) for x, y in ((20, 16), (16, 20), (12, 12))]
ok = got == [(20, 16, 42), (16, 20, 74), (12, 12, 139)]
print("%s picture worked example (reconstruction.md §6: %s)"
      % ("PASS" if ok else "FAIL", ", ".join("(%d,%d)=%d" % g for g in got)))
sys.exit(bad_any or not ok)
PY
# Every listed prefix of every vector: samples, which picture, and the refinement's exactly.
python3 "$D/check_cuts.py" || fail=1
exit $fail
