#!/usr/bin/env python3
"""Per-sample difference of the tracked points of two softkin datasets made on the same actuations
(e.g. a nominal robot and its twin, or two resolutions): prints, per point, the mean, RMS and
maximum distance in mm over the samples both have as ok (matched by actuation), and the mean
difference vector (for a twin: its marker offset plus the systematic model difference).
Usage: scripts/dataset_diff.py A.csv B.csv"""
import csv
import math
import sys


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    cs = [i for i, h in enumerate(head) if h[0] == "c" and h[1:].isdigit()]
    pts = [h[:-2] for h in head if h.endswith("_x") and not h.startswith("J_")]
    out = {}
    for r in body:
        if r[1] != "ok":
            continue
        key = tuple(round(float(r[i]), 12) for i in cs)
        out[key] = {p: [float(r[head.index(p + "_" + d)]) for d in "xyz"] for p in pts}
    return pts, out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    pa, a = load(sys.argv[1])
    pb, b = load(sys.argv[2])
    keys = sorted(set(a) & set(b))
    if not keys:
        sys.exit("no common ok samples")
    print(f"{len(keys)} common samples ({len(a)} ok in A, {len(b)} ok in B)")
    for p in [p for p in pa if p in pb]:
        d = [[b[k][p][i] - a[k][p][i] for i in range(3)] for k in keys]
        n = [math.sqrt(sum(x * x for x in v)) for v in d]
        mean_v = [sum(v[i] for v in d) / len(d) for i in range(3)]
        print(f"{p}: |B - A| mean {sum(n) / len(n):.3f} mm, rms {math.sqrt(sum(x * x for x in n) / len(n)):.3f} mm, "
              f"max {max(n):.3f} mm; mean B - A = ({mean_v[0]:.3f}, {mean_v[1]:.3f}, {mean_v[2]:.3f}) mm")


if __name__ == "__main__":
    main()
