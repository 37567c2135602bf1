#!/usr/bin/env python3
"""Checks the spec-only decoders against spec/vectors/NAME.cuts.csv: for every listed prefix
of NAME.qcs, the number of samples qcs_ref.py reads, whether the picture is the
refinement's, and, when it is, the CRC-32 of the pixels qcs_refine.py draws (the layout's
bytes row by row; spec/refinement.md fixes them exactly).

    python3 spec/reference/check_cuts.py [NAME ...]     # default: every vector with a cuts.csv

Prints PASS/FAIL per vector and exits 1 on any failure. Standard library only.
"""
import csv
import glob
import os
import sys
import zlib

D = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, D)
import qcs_ref  # noqa: E402
import qcs_refine  # noqa: E402

V = os.path.join(D, "..", "vectors")


def check(name):
    data = open(os.path.join(V, name + ".qcs"), "rb").read()
    rows = list(csv.DictReader(open(os.path.join(V, name + ".cuts.csv"))))
    for r in rows:
        cut = int(r["bytes"])
        prefix = data[:cut]
        h, colours, _ = qcs_ref.decode(prefix)
        if len(colours) != int(r["samples"]):
            return "at %d bytes: %d samples, expected %s" % (cut, len(colours), r["samples"])
        if h is None:
            refined = False
        else:
            h, pic, refined = qcs_refine.picture_of_file(prefix)
        if refined != (r["refined"] == "1"):
            return "at %d bytes: refined %s, expected %s" % (cut, refined, r["refined"])
        if refined:
            raw = bytes(v for row in pic for px in row for v in px)
            got = "%08x" % zlib.crc32(raw)
            if got != r["crc32"]:
                return "at %d bytes: picture CRC %s, expected %s" % (cut, got, r["crc32"])
    return None


def main(names):
    if not names:
        names = sorted(os.path.basename(p)[:-len(".cuts.csv")]
                       for p in glob.glob(os.path.join(V, "*.cuts.csv")))
    failed = False
    for name in names:
        msg = check(name)
        print("PASS cuts %s" % name if msg is None else "FAIL cuts %s: %s" % (name, msg))
        failed |= msg is not None
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main(sys.argv[1:])
