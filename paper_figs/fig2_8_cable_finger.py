#!/usr/bin/env python3
"""Thesis Fig. 2.8: tip trajectory of the cable-driven finger as its tendons are shortened.

Usage: fig2_8_cable_finger.py RESULTS_DIR

Reads RESULTS_DIR/trajectory.csv (written by `softkin run experiments/configs/fig2_8_cable_finger.json`)
and, if present, RESULTS_DIR/summary.json. Writes RESULTS_DIR/fig2_8_cable_finger.png:
  left:  tip path in the x-z plane (mm, equal aspect), coloured by the shortening ratio s;
  right: bend angle of the tip face and the solve time of each step against the shortening
         1 - s (percent).
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig2_8_cable_finger"
COLUMNS = ["step", "actuation", "bend_deg", "tip_x", "tip_y", "tip_z", "iterations", "time_s",
           "cumulative_s", "energy", "volume_ratio", "residual_ratio", "converged"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "trajectory.csv"), COLUMNS, min_rows=2)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = [r["actuation"] for r in rows]
    x = [r["tip_x"] for r in rows]
    z = [r["tip_z"] for r in rows]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    ax.plot(x, z, "-", color="0.6", zorder=1)
    sc = ax.scatter(x, z, c=s, cmap="viridis_r", zorder=2, s=28)
    ax.plot(x[0], z[0], "ks", label="rest")
    fig.colorbar(sc, ax=ax, label="tendon length ratio s")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("tip x (mm)")
    ax.set_ylabel("tip z (mm)")
    ax.set_title("Tip trajectory (x-z plane)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)

    short = [100.0 * (1.0 - v) for v in s]
    ax2.plot(short, [r["bend_deg"] for r in rows], "o-", label="bend angle of the tip face")
    ax2.set_xlabel("tendon shortening 1 - s (%)")
    ax2.set_ylabel("bend angle (deg)")
    ax2.grid(True, alpha=0.3)
    ax3 = ax2.twinx()
    ax3.bar(short[1:], [r["time_s"] for r in rows[1:]], width=2.0, alpha=0.3, color="tab:orange",
            label="solve time of the step")
    ax3.set_ylabel("solve time per step (s)")
    h1, l1 = ax2.get_legend_handles_labels()
    h2, l2 = ax3.get_legend_handles_labels()
    ax2.legend(h1 + h2, l1 + l2, loc="upper left", fontsize=8)
    total = summary.get("total_solve_s") if isinstance(summary, dict) else None
    acts = ", ".join(summary.get("actuators", [])) if isinstance(summary, dict) else ""
    quick = " (quick run)" if isinstance(summary, dict) and summary.get("quick") else ""
    extra = f"; total solve {total:.2f} s" if isinstance(total, (int, float)) else ""
    ax2.set_title(f"Tendons {acts} shortened together{extra}", fontsize=10)
    fig.suptitle(f"Thesis Fig. 2.8: cable_finger under cable actuation{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
