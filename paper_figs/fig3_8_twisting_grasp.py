#!/usr/bin/env python3
"""The twisting robot grasping a cylinder (thesis Sec. 3.4.1, Fig. 3.8): the tip's path in the x-z
plane with and without the obstacle response, and how the grasp tightens with the chamber ratio.

Usage: fig3_8_twisting_grasp.py RESULTS_DIR

Reads RESULTS_DIR/steps.csv and summary.json (written by
`softkin run experiments/configs/fig3_8_twisting_grasp.json`). Writes RESULTS_DIR/fig3_8_twisting_grasp.png:
  left:  tip paths in the x-z plane, per variant, with the cylinder's cross-section;
  right: vertices touching the cylinder (within the contact distance), vertices inside it, the
         deepest penetration into the cylinder, and the deepest self "contact" of the exact check
         (chamber tets tangled through the body, which the obstacle response does not touch),
         against the chamber volume ratio asked for.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig3_8_twisting_grasp"
COLS = ["variant", "step", "actuation_scale", "tip_x", "tip_z", "contact_vertices",
        "obstacle_contacts", "obstacle_penetration_mm", "self_penetration_mm"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "steps.csv"), COLS, numeric=COLS[1:])
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    variants = summary.get("variants")
    if not isinstance(variants, list) or not variants:
        figlib.fail(NAME, f"{results}/summary.json: expected a non-empty 'variants' list")
    cfg = summary.get("config", {})
    end = (cfg.get("actuation") or {}).get("chamber")
    if not isinstance(end, (int, float)):
        figlib.fail(NAME, f"{results}/summary.json: expected config.actuation.chamber (a number)")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.8))
    colors = ["tab:blue", "tab:red", "tab:green"]
    ax1b = ax1.twinx()
    for i, v in enumerate(variants):
        name = v.get("name", f"variant {i}")
        pts = [r for r in rows if r["variant"] == name]
        c = colors[i % 3]
        ax0.plot([0.0] + [r["tip_x"] for r in pts], [100.0] + [r["tip_z"] for r in pts], "o-",
                 color=c, label=name)
        alpha = [1.0 + r["actuation_scale"] * (end - 1.0) for r in pts]
        ax1.plot(alpha, [r["contact_vertices"] for r in pts], "o-", color=c,
                 label=f"{name}: touching vertices")
        ax1.plot(alpha, [r["obstacle_contacts"] for r in pts], "x:", color=c,
                 label=f"{name}: vertices inside the cylinder")
        ax1b.plot(alpha, [r["obstacle_penetration_mm"] for r in pts], "s--", color=c, alpha=0.6,
                  label=f"{name}: max penetration into the cylinder")
        ax1b.plot(alpha, [r["self_penetration_mm"] for r in pts], "^-.", color=c, alpha=0.35,
                  label=f"{name}: max self depth (tangles)")
    figlib.plot_cylinder_sections(ax0, cfg)
    ax0.plot([-10, 10, 10, -10, -10], [0, 0, 100, 100, 0], ":", color="gray", label="robot at rest")
    ax0.set_xlabel("tip x (mm)")
    ax0.set_ylabel("tip z (mm)")
    ax0.set_aspect("equal", adjustable="datalim")
    ax0.grid(True, alpha=0.3)
    ax0.legend(fontsize=8)
    ax0.set_title("Tip paths (start: tip at rest, z = 100)")
    ax1.set_xlabel("chamber volume ratio asked for, α")
    ax1.set_ylabel("vertices")
    ax1b.set_ylabel("depth (mm)")
    ax1.grid(True, alpha=0.3)
    h0, l0 = ax1.get_legend_handles_labels()
    h1, l1 = ax1b.get_legend_handles_labels()
    ax1.legend(h0 + h1, l0 + l1, fontsize=8, loc="upper left")
    ax1.set_title("Grasp against actuation")
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Twisting robot grasping a cylinder{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
