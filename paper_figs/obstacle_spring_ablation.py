#!/usr/bin/env python3
"""Obstacle spring ablation (docs/collision_response.md): the frictionless 'plane' obstacle spring
against Eq. 3.5's 'point' spring on the same contact, in iterations and seconds per step.

Usage: obstacle_spring_ablation.py RESULTS_DIR

Reads RESULTS_DIR/steps.csv and summary.json (written by
`softkin run experiments/configs/obstacle_spring_ablation.json`). Writes
RESULTS_DIR/obstacle_spring_ablation.png:
  left:  local-global iterations per step, one bar per variant;
  right: seconds per step, with each variant's total and the distance between the final tips.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import math
import os
import sys

import figlib

NAME = "obstacle_spring_ablation"
COLS = ["variant", "step", "iterations", "time_s", "contact_vertices"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "steps.csv"), COLS, numeric=COLS[1:])
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    variants = summary.get("variants")
    if not isinstance(variants, list) or len(variants) < 2:
        figlib.fail(NAME, f"{results}/summary.json: expected a 'variants' list of at least two")
    tips = []
    for i, v in enumerate(variants):
        tip = v.get("tip")
        if not isinstance(tip, list) or len(tip) != 3:
            figlib.fail(NAME, f"{results}/summary.json: variants[{i}].tip: expected [x, y, z]")
        tips.append(tip)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.4))
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red"]
    width = 0.8 / len(variants)
    totals = []
    for i, v in enumerate(variants):
        name = v.get("name", f"variant {i}")
        pts = sorted((r for r in rows if r["variant"] == name), key=lambda r: r["step"])
        if not pts:
            figlib.fail(NAME, f"{results}/steps.csv: no rows for variant '{name}'")
        xs = [r["step"] + (i - (len(variants) - 1) / 2) * width for r in pts]
        ax0.bar(xs, [r["iterations"] for r in pts], width=width, color=colors[i % 4], label=name)
        ax1.bar(xs, [r["time_s"] for r in pts], width=width, color=colors[i % 4],
                label=f"{name}: {sum(r['time_s'] for r in pts):.2f} s in all")
        totals.append(sum(r["iterations"] for r in pts))
    for ax, label in ((ax0, "iterations"), (ax1, "seconds")):
        ax.set_xlabel("step")
        ax.set_ylabel(label)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=8)
    ax0.set_title("Local-global iterations per step")
    gap = math.dist(tips[0], tips[1])
    ax1.set_title(f"Time per step (final tips {gap:.3f} mm apart)")
    quick = " (quick run)" if summary.get("quick") else ""
    ratio = totals[1] / totals[0] if totals[0] else float("nan")
    fig.suptitle(f"Obstacle springs: {variants[1].get('name')} needs {ratio:.1f}x the iterations of "
                 f"{variants[0].get('name')}{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
