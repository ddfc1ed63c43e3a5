#!/usr/bin/env python3
"""Thesis Fig. 2.12: the three-chamber actuator with its chambers inflated alone and together.

Usage: fig2_12_three_chamber.py RESULTS_DIR

Reads RESULTS_DIR/paths.csv (written by `softkin run experiments/configs/fig2_12_three_chamber.json`) and,
if present, RESULTS_DIR/summary.json. Writes RESULTS_DIR/fig2_12_three_chamber.png:
  left:  tip trajectories seen along the robot's long axis (x-z cross-section plane, mm), one per
         actuation path (e.g. c1, c1+c2, c1+c2+c3), starting at the rest tip;
  right: tip height y (along the long axis) against the actuation value for each path.
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig2_12_three_chamber"
COLUMNS = ["path", "step", "value", "tip_x", "tip_y", "tip_z", "iterations", "time_s", "converged"]
NUMERIC = ["step", "value", "tip_x", "tip_y", "tip_z", "iterations", "time_s", "converged"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "paths.csv"), COLUMNS, NUMERIC, min_rows=2)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    for r in rows:
        if r["path"] not in paths:
            paths.append(r["path"])
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5.2))
    for i, p in enumerate(paths):
        pr = [r for r in rows if r["path"] == p]
        color = f"C{i}"
        ax.plot([r["tip_x"] for r in pr], [r["tip_z"] for r in pr], "o-", color=color, ms=3, label=p)
        failed = [r for r in pr if r["converged"] != 1]
        if failed:
            ax.plot([r["tip_x"] for r in failed], [r["tip_z"] for r in failed], "x", color="k")
        ax2.plot([r["value"] for r in pr], [r["tip_y"] for r in pr], "o-", color=color, ms=3, label=p)
    ax.plot([rows[0]["tip_x"]], [rows[0]["tip_z"]], "ks", label="rest")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("tip x (mm)")
    ax.set_ylabel("tip z (mm)")
    ax.set_title("Tip trajectories, seen along the long axis y")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax2.set_xlabel("chamber volume ratio")
    ax2.set_ylabel("tip y (mm, along the long axis)")
    ax2.set_title("Elongation")
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8)
    quick = " (quick run)" if summary.get("quick") else ""
    total = summary.get("total_solve_s")
    extra = f"; total solve {total:.2f} s" if isinstance(total, (int, float)) else ""
    fig.suptitle(f"Thesis Fig. 2.12: three_chamber, chambers inflated alone and together{quick}{extra}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
