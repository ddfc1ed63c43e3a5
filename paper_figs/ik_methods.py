#!/usr/bin/env python3
"""Every IK method x Jacobian mode on the same waypoints (simulation in the loop).

Usage: ik_methods.py RESULTS_DIR

Reads RESULTS_DIR/methods.csv (written by `softkin run experiments/configs/ik_methods.json`) and
RESULTS_DIR/summary.json. Writes RESULTS_DIR/ik_methods.png:
  left:  mean time per waypoint (ms, log scale) of each method, one bar per Jacobian mode;
  right: mean and maximum error (mm) of each, with lambda.
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import os
import sys

import figlib

NAME = "ik_methods"
COLUMNS = ["method", "jacobian", "waypoints", "converged", "ms_per_waypoint", "mean_err_mm",
           "max_err_mm", "fk_calls"]
NUMERIC = COLUMNS[2:]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "methods.csv"), COLUMNS, NUMERIC, min_rows=1)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [f"{r['method']}\n{r['jacobian']}" for r in rows]
    colors = {"fd": "C0", "fd-warm": "C1", "implicit": "C2", "none": "C7"}
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(14, 5.5))
    x = list(range(len(rows)))
    ax.bar(x, [max(r["ms_per_waypoint"], 1e-3) for r in rows],
           color=[colors.get(r["jacobian"], "C4") for r in rows])
    for i, r in enumerate(rows):
        ax.text(i, max(r["ms_per_waypoint"], 1e-3), f"{int(r['converged'])}/{int(r['waypoints'])}",
                ha="center", va="bottom", fontsize=7)
    ax.set_yscale("log")
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=90, fontsize=7)
    ax.set_ylabel("ms per waypoint")
    ax.set_title("Time per waypoint (label: waypoints within lambda)")
    ax.grid(True, alpha=0.3, axis="y")
    ax2.bar([i - 0.2 for i in x], [r["mean_err_mm"] for r in rows], 0.4, label="mean error")
    ax2.bar([i + 0.2 for i in x], [r["max_err_mm"] for r in rows], 0.4, label="max error")
    lam = summary.get("lambda_mm")
    if isinstance(lam, (int, float)):
        ax2.axhline(lam, color="k", ls="--", lw=1, label=f"lambda = {lam:g} mm")
    ax2.set_xticks(x)
    ax2.set_xticklabels(labels, rotation=90, fontsize=7)
    ax2.set_ylabel("error (mm)")
    ax2.set_title("Error")
    ax2.grid(True, alpha=0.3, axis="y")
    ax2.legend(fontsize=8)
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"IK methods x Jacobian modes on {summary.get('robot', '?')} (res "
                 f"{summary.get('res', '?')}, {summary.get('waypoints', '?')} waypoints){quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
