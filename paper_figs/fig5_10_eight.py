#!/usr/bin/env python3
"""Thesis Fig. 5.10: the redundant finger_manipulator on an '8' path, learned-Jacobian IK against
direct IK (also used by fig5_12_singularity.py).

Usage: fig5_10_eight.py RESULTS_DIR

Reads RESULTS_DIR/summary.json (rows[].{method, mean_err_pct, max_err_pct, max_jump}) and
RESULTS_DIR/path_learned.csv, path_direct.csv (i, target_x/y/z, x, y, z: the simulator's tip at
the answer, err_mm, jump, c0..). Writes RESULTS_DIR/<name>.png: (a) target and reached tip in the
x-y plane per method, (b) error per waypoint (% of the workspace width), (c) the actuations along
the path per method (jumps show as steps).
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
    width = summary.get("workspace_width_mm") or 1.0
    paths = {}
    for i, r in enumerate(rows):
        for k in ("method", "mean_err_pct", "max_err_pct", "max_jump"):
            if k not in r:
                figlib.fail(name, f"{results}/summary.json: rows[{i}] lacks '{k}'")
        paths[r["method"]] = figlib.read_table(
            name, os.path.join(results, f"path_{r['method']}.csv"),
            ["i", "target_x", "target_y", "x", "y", "err_mm", "jump", "c0"], min_rows=1)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b, c) = plt.subplots(1, 3, figsize=(17, 5))
    first = next(iter(paths.values()))
    a.plot([p["target_y"] for p in first], [p["target_x"] for p in first], "k-", lw=1, label="target")
    for k, r in enumerate(rows):
        w = paths[r["method"]]
        lab = f"{r['method']}: mean {r['mean_err_pct']:.2f} %, max {r['max_err_pct']:.2f} %, jump {r['max_jump']:.2f}"
        a.plot([p["y"] for p in w], [p["x"] for p in w], ".", color=f"C{k}", ms=3, label=lab)
        b.plot([p["i"] for p in w], [100.0 * p["err_mm"] / width for p in w], "-", color=f"C{k}", label=r["method"])
        acts = sorted(key for key in w[0] if key.startswith("c") and key[1:].isdigit())
        for j, key in enumerate(acts):
            try:
                vals = [float(p[key]) for p in w]
            except ValueError:
                figlib.fail(name, f"path_{r['method']}.csv: column {key} is not numeric")
            c.plot([p["i"] for p in w], vals, ["-", "--", ":"][k % 3], color=f"C{j}",
                   label=f"{r['method']} {key}")
    a.set_xlabel("y (mm)")
    a.set_ylabel("x (mm)")
    a.set_aspect("equal", adjustable="datalim")
    a.set_title("(a) the simulator's tip at each method's answer", fontsize=10)
    a.legend(fontsize=7)
    b.set_xlabel("waypoint")
    b.set_ylabel("error (% of workspace width)")
    b.set_yscale("log")
    b.set_title("(b) error per waypoint, measured by the simulator", fontsize=10)
    b.grid(True, which="both", alpha=0.3)
    b.legend(fontsize=7)
    c.set_xlabel("waypoint")
    c.set_ylabel("actuation")
    c.set_title("(c) actuations along the path", fontsize=10)
    c.legend(fontsize=6, ncol=2)
    figlib.save_figure(fig, results, name)


if __name__ == "__main__":
    plot("fig5_10_eight", sys.argv, __doc__)
