#!/usr/bin/env python3
"""Thesis Fig. 5.7: path following on the twins with learned-Jacobian IK, without and with the
sim-to-real layer (also used by fig5_8_box_s2r.py).

Usage: fig5_7_flower_s2r.py RESULTS_DIR

Reads RESULTS_DIR/summary.json (rows[].{twin, s2r, mean_err_mm, max_err_mm, csv}) and each row's
path CSV (i, target_x/y/z, x, y, z: the twin's tip, err_mm). Writes RESULTS_DIR/<name>.png: per
twin, the target and the twin's tip in the x-z plane without and with s2r, and the error per
waypoint.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib


def plot(name, argv, doc):
    results = figlib.results_dir(name, argv, doc)
    summary = figlib.read_summary(name, os.path.join(results, "summary.json"))
    rows = summary.get("rows")
    if not isinstance(rows, list) or not rows:
        figlib.fail(name, f"{results}/summary.json: expected a non-empty 'rows' array")
    twins = []
    for i, r in enumerate(rows):
        for k in ("twin", "s2r", "mean_err_mm", "max_err_mm", "csv"):
            if k not in r:
                figlib.fail(name, f"{results}/summary.json: rows[{i}] lacks '{k}'")
        if r["twin"] not in twins:
            twins.append(r["twin"])
    cols = ["i", "target_x", "target_y", "target_z", "x", "y", "z", "err_mm"]

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(twins), 2, figsize=(12, 5 * len(twins)), squeeze=False)
    for t, twin in enumerate(twins):
        a, b = axes[t]
        first = True
        for r in rows:
            if r["twin"] != twin:
                continue
            w = figlib.read_table(name, os.path.join(results, r["csv"]), cols)
            if first:
                a.plot([p["target_x"] for p in w], [p["target_z"] for p in w], "k-", lw=1, label="target")
                first = False
            style = "C2" if r["s2r"] else "C3"
            lab = ("with s2r" if r["s2r"] else "without s2r") + f": mean {r['mean_err_mm']:.2f}, max {r['max_err_mm']:.2f} mm"
            a.plot([p["x"] for p in w], [p["z"] for p in w], ".", color=style, ms=3, label=lab)
            b.plot([p["i"] for p in w], [p["err_mm"] for p in w], "-", color=style, label=lab)
        a.set_aspect("equal", adjustable="datalim")
        a.set_xlabel("x (mm)")
        a.set_ylabel("z (mm)")
        a.set_title(f"{twin} (twin data): the twin's tip, top view", fontsize=10)
        a.legend(fontsize=7)
        b.set_xlabel("waypoint")
        b.set_ylabel("error on the twin (mm)")
        b.set_title("error per waypoint", fontsize=10)
        b.grid(True, alpha=0.3)
        b.legend(fontsize=7)
    figlib.save_figure(fig, results, name)


if __name__ == "__main__":
    plot("fig5_7_flower_s2r", sys.argv, __doc__)
