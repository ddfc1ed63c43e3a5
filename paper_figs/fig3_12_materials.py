#!/usr/bin/env python3
"""Two materials around a round obstacle (thesis Sec. 3.4.2, Fig. 3.12): the tip trajectories of
the Dragon Skin 20 and Ecoflex 00-30 fingers bending onto a cylinder, and the size of their contact
regions.

Usage: fig3_12_materials.py RESULTS_DIR

Reads RESULTS_DIR/steps.csv and summary.json (written by
`softkin run experiments/configs/fig3_12_materials.json`). Writes RESULTS_DIR/fig3_12_materials.png:
  left:  tip trajectories in the x-z plane with the obstacle's cross-section;
  right: contact region per material: vertices touching and the touching area.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig3_12_materials"
COLS = ["variant", "step", "tip_x", "tip_z"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "steps.csv"), COLS, numeric=COLS[1:])
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    variants = summary.get("variants")
    if not isinstance(variants, list) or not variants:
        figlib.fail(NAME, f"{results}/summary.json: expected a non-empty 'variants' list")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.8))
    colors = ["tab:blue", "tab:red", "tab:green"]
    names, verts, areas = [], [], []
    for i, v in enumerate(variants):
        name = v.get("name", f"variant {i}")
        pts = [r for r in rows if r["variant"] == name]
        ax0.plot([r["tip_x"] for r in pts], [r["tip_z"] for r in pts], "o-", color=colors[i % 3],
                 label=name)
        contact = (v.get("contact") or [{}])[0]
        names.append(name)
        verts.append(contact.get("vertices", 0))
        areas.append(contact.get("area_mm2", 0.0))
    cfg = summary.get("config", {})
    figlib.plot_cylinder_sections(ax0, cfg)
    ax0.set_xlabel("tip x (mm)")
    ax0.set_ylabel("tip z (mm)")
    ax0.set_aspect("equal", adjustable="datalim")
    ax0.grid(True, alpha=0.3)
    ax0.legend(fontsize=8)
    ax0.set_title("Tip trajectories")
    x = range(len(names))
    ax1.bar([i - 0.2 for i in x], verts, width=0.4, label="touching vertices")
    ax1b = ax1.twinx()
    ax1b.bar([i + 0.2 for i in x], areas, width=0.4, color="tab:orange", label="touching area (mm²)")
    ax1.set_xticks(list(x))
    ax1.set_xticklabels(names)
    ax1.set_ylabel("vertices within contact distance")
    ax1b.set_ylabel("area (mm²)")
    ax1.set_title("Contact region")
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Two materials around a round obstacle{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
