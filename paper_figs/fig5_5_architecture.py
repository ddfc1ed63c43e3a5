#!/usr/bin/env python3
"""Thesis Fig. 5.5: test error of N_fk and N_J against the hidden layers h and neurons b.

Usage: fig5_5_architecture.py RESULTS_DIR

Reads RESULTS_DIR/architecture.csv (robot, net, h, b, test_mean_pct, test_max_pct, ...), written
by `softkin run experiments/configs/fig5_5_architecture.json`. Writes RESULTS_DIR/fig5_5_architecture.png:
one panel per robot and network, the mean test error (% of the workspace width) against b, one
line per h, with the thesis's chosen architecture marked where it is in the sweep.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig5_5_architecture"
THESIS = {("three_chamber", "fk"): (2, 35, 0.34), ("finger_manipulator", "fk"): (3, 30, 0.58)}


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "architecture.csv"),
                             ["robot", "net", "h", "b", "test_mean_pct", "test_max_pct"],
                             numeric=["h", "b", "test_mean_pct", "test_max_pct"],
                             check=lambda v: None if v["net"] in ("fk", "jac") else "net must be fk or jac")
    panels = sorted({(r["robot"], r["net"]) for r in rows})

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 4.5), squeeze=False)
    for ax, (robot, net) in zip(axes[0], panels):
        sel = [r for r in rows if r["robot"] == robot and r["net"] == net]
        for h in sorted({int(r["h"]) for r in sel}):
            line = sorted((r["b"], r["test_mean_pct"]) for r in sel if int(r["h"]) == h)
            ax.plot([p[0] for p in line], [p[1] for p in line], "o-", label=f"h = {h}")
        t = THESIS.get((robot, net))
        if t:
            ax.axhline(t[2], color="k", ls=":", lw=1, label=f"thesis h={t[0]}, b={t[1]}: {t[2]} %")
        ax.set_yscale("log")
        ax.set_xlabel("neurons per hidden layer b")
        ax.set_ylabel("mean test error (% of workspace width)")
        what = "N_fk (tip distance)" if net == "fk" else "N_J (tip error of a 1/10-range step)"
        ax.set_title(f"{robot}: {what}", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    figlib.save_figure(fig, results, NAME)


if __name__ == "__main__":
    main(sys.argv)
