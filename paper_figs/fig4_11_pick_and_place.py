#!/usr/bin/env python3
"""Thesis Fig. 4.7(b) / 4.11: the three IK stages of pick-and-place on multi_segment_gripper.

Usage: fig4_11_pick_and_place.py RESULTS_DIR

Reads RESULTS_DIR/summary.json, RESULTS_DIR/stages.csv and RESULTS_DIR/shapes.csv (written by
`softkin run experiments/configs/fig4_11_pick_and_place.json`). Writes RESULTS_DIR/fig4_11_pick_and_place.png:
  left:  side view (x-z, mm) of the robot's side-face vertices at rest and after each stage, with
         the object (circle of radius R) at its pick and place positions;
  right: the objective of each stage (Eq. 4.5 pick, Eq. 4.7 grasp, place) at its start and end
         (mm^2, log scale).
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import math
import os
import sys

import figlib

NAME = "fig4_11_pick_and_place"
STAGES = ["rest", "pick", "grasp", "place"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    stages = figlib.read_table(NAME, os.path.join(results, "stages.csv"),
                               ["stage", "c1", "c2", "c3", "initial_objective", "final_objective"],
                               ["c1", "c2", "c3", "initial_objective", "final_objective"], min_rows=3)
    shapes = figlib.read_table(NAME, os.path.join(results, "shapes.csv"), ["stage", "x", "z"], ["x", "z"],
                               check=lambda v: None if v["stage"] in STAGES else f"unknown stage {v['stage']}")
    obj = summary.get("object", {})

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 5.5), gridspec_kw={"width_ratios": [1.6, 1]})
    colors = {"rest": "orange", "pick": "green", "grasp": "0.4", "place": "C0"}
    for st in STAGES:
        pts = [r for r in shapes if r["stage"] == st]
        ax.plot([r["x"] for r in pts], [r["z"] for r in pts], ".", ms=2, color=colors[st], label=st)
    R = obj.get("radius_mm")
    for key, label, color in (("center", "object (pick)", "k"), ("place_center", "object (place)", "C0")):
        c = obj.get(key)
        if isinstance(R, (int, float)) and isinstance(c, list) and len(c) == 3:
            t = [2 * math.pi * i / 100 for i in range(101)]
            ax.plot([c[0] + R * math.cos(a) for a in t], [c[2] + R * math.sin(a) for a in t], "-",
                    color=color, lw=1.5, label=label)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_title("Side view: rest, pick (Eq. 4.5), grasp (Eq. 4.7), place")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, markerscale=4)
    names = [r["stage"] for r in stages]
    x = range(len(stages))
    ax2.bar([i - 0.2 for i in x], [max(r["initial_objective"], 1e-8) for r in stages], 0.4,
            label="start")
    ax2.bar([i + 0.2 for i in x], [max(r["final_objective"], 1e-8) for r in stages], 0.4, label="end")
    ax2.set_yscale("log")
    ax2.set_xticks(list(x))
    ax2.set_xticklabels([f"{n}\nc=({r['c1']:.2f}, {r['c2']:.2f}, {r['c3']:.2f})"
                         for n, r in zip(names, stages)], fontsize=8)
    ax2.set_ylabel("objective (mm^2)")
    ax2.set_title("Objective of each stage")
    ax2.grid(True, alpha=0.3, axis="y")
    ax2.legend(fontsize=8)
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Thesis Fig. 4.11: pick-and-place with multi_segment_gripper (res "
                 f"{summary.get('res', '?')}){quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
