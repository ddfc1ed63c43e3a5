#!/usr/bin/env python3
"""Membrane shaped by four chambers through contact (thesis Sec. 3.4.3, Fig. 3.13).

Usage: fig3_13_membrane.py RESULTS_DIR

Reads RESULTS_DIR/surface_membrane.csv (the membrane's vertices, rest and final positions) and
summary.json (written by `softkin run experiments/configs/fig3_13_membrane.json`). Writes
RESULTS_DIR/fig3_13_membrane.png: the membrane's upward displacement over its rest position
(top-face vertices), as a colour map, with the chamber actuations in the title.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig3_13_membrane"
COLS = ["x0", "y0", "z0", "x", "y", "z"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "surface_membrane.csv"), COLS)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    ztop = max(r["z0"] for r in rows)
    top = [r for r in rows if abs(r["z0"] - ztop) < 1e-6]
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    sc = ax.tricontourf([r["x"] for r in top], [r["y"] for r in top], [r["z"] - r["z0"] for r in top],
                        levels=20, cmap="viridis")
    fig.colorbar(sc, ax=ax, label="upward displacement (mm)")
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    act = summary.get("config", {}).get("actuation", {})
    txt = ", ".join(f"{k} = {v}" for k, v in act.items())
    quick = " (quick run)" if summary.get("quick") else ""
    ax.set_title(f"Membrane driven by contact: {txt}{quick}", fontsize=9)
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
