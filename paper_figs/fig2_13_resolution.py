#!/usr/bin/env python3
"""Thesis Fig. 2.13: cost and accuracy of the FK solve as the mesh is refined.

Usage: fig2_13_resolution.py RESULTS_DIR

Reads RESULTS_DIR/resolution.csv (written by `softkin run experiments/configs/fig2_13_resolution.json`)
and, if present, RESULTS_DIR/summary.json. Writes RESULTS_DIR/fig2_13_resolution.png:
  left:   milliseconds per iteration and iteration count against the number of tets (log x);
  middle: tip coordinates against the number of tets;
  right:  distance of each tip to the tip on the finest mesh (convergence).
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import math
import os
import sys

import figlib

NAME = "fig2_13_resolution"
COLUMNS = ["res", "n_vertices", "n_tets", "build_s", "factor_s", "iterations", "solve_s",
           "ms_per_iteration", "us_per_iteration_per_vertex", "tip_x", "tip_y", "tip_z",
           "converged"]


def fail(msg):
    figlib.fail(NAME, msg)


def read_table(path, columns):
    return figlib.read_table(NAME, path, columns, check=lambda v: None if v["n_tets"] > 0 else
                             f"n_tets must be positive, got {v['n_tets']:g}")


def read_summary(path):
    return figlib.read_summary(NAME, path)


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = read_table(os.path.join(results, "resolution.csv"), COLUMNS)
    summary = read_summary(os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows.sort(key=lambda r: r["n_tets"])
    tets = [r["n_tets"] for r in rows]
    finest = max(rows, key=lambda r: r["n_tets"])
    bad = [r for r in rows if r["converged"] < 0.5]

    fig, (ax0, ax1, ax2) = plt.subplots(1, 3, figsize=(15.5, 4.8))

    # Left: per-iteration cost and iteration count.
    ax0.plot(tets, [r["ms_per_iteration"] for r in rows], "-o", color="tab:blue",
             label="ms per iteration")
    ax0.set_xscale("log")
    ax0.set_xlabel("tetrahedra")
    ax0.set_ylabel("time per iteration (ms)", color="tab:blue")
    ax0.tick_params(axis="y", labelcolor="tab:blue")
    ax0.grid(True, which="both", alpha=0.3)
    ax0b = ax0.twinx()
    ax0b.plot(tets, [r["iterations"] for r in rows], "--s", color="tab:orange", label="iterations")
    ax0b.set_ylabel("iterations to converge", color="tab:orange")
    ax0b.tick_params(axis="y", labelcolor="tab:orange")
    ax0b.set_ylim(bottom=0)
    for r in bad:
        ax0b.plot(r["n_tets"], r["iterations"], "o", ms=12, mfc="none", mec="red")
    h0, l0 = ax0.get_legend_handles_labels()
    h1, l1 = ax0b.get_legend_handles_labels()
    if bad:
        from matplotlib.lines import Line2D
        h1.append(Line2D([], [], ls="none", marker="o", ms=10, mfc="none", mec="red"))
        l1.append("not converged")
    ax0.legend(h0 + h1, l0 + l1, loc="upper left", fontsize=8)
    ax0.set_title("Cost per FK iteration")

    # Middle: tip coordinates.
    for key, color in (("tip_x", "tab:red"), ("tip_y", "tab:green"), ("tip_z", "tab:blue")):
        ax1.plot(tets, [r[key] for r in rows], "-o", color=color, label=key.replace("_", " "))
        ax1.axhline(finest[key], color=color, ls=":", lw=0.9)
    ax1.set_xscale("log")
    ax1.set_xlabel("tetrahedra")
    ax1.set_ylabel("tip position (mm)")
    ax1.set_title("Tip position (dotted: finest mesh)")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(loc="best", fontsize=8)

    # Right: distance to the finest tip (the finest mesh itself is 0 and left out of the log plot).
    dist = [math.sqrt(sum((r[k] - finest[k]) ** 2 for k in ("tip_x", "tip_y", "tip_z")))
            for r in rows]
    pts = [(t, d) for t, d, r in zip(tets, dist, rows) if r is not finest]
    if pts and all(d > 0 for _, d in pts):
        ax2.plot([p[0] for p in pts], [p[1] for p in pts], "-o", color="tab:purple")
        ax2.set_yscale("log")
        # Few decades: label the minor ticks too, as plain numbers.
        from matplotlib.ticker import FuncFormatter
        plain = FuncFormatter(lambda v, _: f"{v:g}")
        ax2.yaxis.set_major_formatter(plain)
        ax2.yaxis.set_minor_formatter(plain)
        ax2.tick_params(axis="y", which="minor", labelsize=7)
    else:
        ax2.plot(tets, dist, "-o", color="tab:purple")
    ax2.set_xscale("log")
    ax2.set_xlabel("tetrahedra")
    ax2.set_ylabel("|tip - tip on finest mesh| (mm)")
    ax2.set_title(f"Convergence to the finest mesh ({finest['n_tets']:.0f} tets)")
    ax2.grid(True, which="both", alpha=0.3)

    robot = summary.get("robot", "")
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Thesis Fig. 2.13: FK on meshes from coarse to fine"
                 f"{': ' + robot if robot else ''}{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
