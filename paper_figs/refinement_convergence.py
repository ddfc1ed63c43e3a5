#!/usr/bin/env python3
"""Convergence under mesh refinement, robot by robot.

Usage: refinement_convergence.py RESULTS_DIR

Reads RESULTS_DIR/refinement.csv (written by
`softkin run experiments/configs/refinement_convergence.json`) and RESULTS_DIR/summary.json.
Writes RESULTS_DIR/refinement_convergence.png:
  left:  the tracked point's change from the previous resolution, against the resolution
         (a converging case falls; log scale);
  right: its distance to the finest mesh's, as a percentage of the robot's length.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "refinement_convergence"
COLUMNS = ["case", "res", "n_elements", "tip_x", "tip_y", "tip_z", "change_mm", "to_finest_mm",
           "status"]
NUMERIC = ["res", "n_elements", "tip_x", "tip_y", "tip_z", "to_finest_mm"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "refinement.csv"), COLUMNS, NUMERIC)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    lengths = {c["label"]: c["length_mm"] for c in summary.get("cases", [])}
    # Dashed: the strain form of the element energy (robot parameter element_energy = 1).
    strain = {c["label"] for c in summary.get("cases", [])
              if c.get("robot_params", {}).get("element_energy") == 1}

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = []
    for r in rows:
        if r["case"] not in cases:
            cases.append(r["case"])
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(14, 5.2))
    cmap = plt.get_cmap("tab20")
    for i, label in enumerate(cases):
        mine = sorted((r for r in rows if r["case"] == label), key=lambda r: r["res"])
        color = cmap(i % 20)
        style = "--" if label in strain else "-"
        pts = []
        for r in mine[1:]:
            try:
                pts.append((r["res"], float(r["change_mm"])))
            except ValueError:
                figlib.fail(NAME, f"case {label}: change_mm '{r['change_mm']}' is not a number")
        ax0.plot([p[0] for p in pts], [max(p[1], 1e-3) for p in pts], style, marker="o",
                 color=color, label=label)
        # A red ring on each point whose solve did not converge (inverted, capped).
        for res, change in pts:
            if any(r["res"] == res and r["status"] != "converged" for r in mine):
                ax0.plot(res, change, "o", ms=11, mfc="none", mec="red")
        length = lengths.get(label, 0.0)
        if length > 0:
            ax1.plot([r["res"] for r in mine[:-1]],
                     [100.0 * r["to_finest_mm"] / length for r in mine[:-1]], style, marker="o",
                     color=color, label=label)
            for r in mine[:-1]:
                if r["status"] != "converged":
                    ax1.plot(r["res"], 100.0 * r["to_finest_mm"] / length, "o", ms=11,
                             mfc="none", mec="red")
    ax0.set_yscale("log")
    ax0.set_xlabel("resolution (--res)")
    ax0.set_ylabel("change of the tracked point from the previous resolution (mm)")
    ax0.set_title("Change per refinement step (falling: converging)")
    ax0.grid(True, which="both", alpha=0.3)
    ax0.legend(fontsize=7, loc="best")
    ax1.set_xlabel("resolution (--res); red rings: the solve did not converge")
    ax1.set_ylabel("distance to the finest mesh's point (% of the robot's length)")
    ax1.set_title("Distance to the finest mesh")
    ax1.grid(True, alpha=0.3)
    n = summary.get("n_cases", len(cases))
    k = summary.get("cases_whose_changes_shrink", "?")
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Convergence under refinement: the changes shrink in {k} of {n} cases{quick}")
    fig.tight_layout()
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
