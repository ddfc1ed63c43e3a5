#!/usr/bin/env python3
"""Self-collision of the PneuNet finger (thesis Sec. 3.4.2, Fig. 3.10): the tip trajectory with
and without the spring collision response, and how deep the walls pass through each other without
it.

Usage: fig3_10_selfcollision_tip.py RESULTS_DIR

Reads RESULTS_DIR/steps.csv and summary.json (written by
`softkin run experiments/configs/fig3_10_selfcollision_tip.json`). Writes
RESULTS_DIR/fig3_10_selfcollision_tip.png:
  left:  tip trajectory in the x-z plane, one curve per variant, from the rest tip;
  right: exact check per step: the deepest penetration left (mm) per variant.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig3_10_selfcollision_tip"
COLS = ["variant", "step", "actuation_scale", "tip_x", "tip_z", "max_penetration_mm", "self_contacts",
        "springs"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "steps.csv"), COLS, numeric=COLS[1:])
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    variants = []
    for r in rows:
        if r["variant"] not in variants:
            variants.append(r["variant"])
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.8))
    colors = ["tab:blue", "tab:red", "tab:green", "tab:purple"]
    for i, v in enumerate(variants):
        pts = [r for r in rows if r["variant"] == v]
        c = colors[i % len(colors)]
        ax0.plot([r["tip_x"] for r in pts], [r["tip_z"] for r in pts], "o-", color=c, label=v)
        ax1.plot([r["step"] for r in pts], [r["max_penetration_mm"] for r in pts], "o-", color=c,
                 label=v)
    ax0.set_xlabel("tip x (mm)")
    ax0.set_ylabel("tip z (mm)")
    ax0.set_aspect("equal", adjustable="datalim")
    ax0.set_title("Tip trajectory")
    ax0.grid(True, alpha=0.3)
    ax0.legend()
    ax1.set_xlabel("step")
    ax1.set_ylabel("deepest penetration left (mm)")
    ax1.set_title("Exact collision check of each state")
    ax1.grid(True, alpha=0.3)
    ax1.legend()
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"PneuNet finger with self-collision, with and without response{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
