#!/usr/bin/env python3
"""Thesis Fig. 4.1(b, c): the sampled configuration space and the convergence of IK from the rest
configuration against the closest sample.

Usage: fig4_1_initial_guess.py RESULTS_DIR

Reads RESULTS_DIR/summary.json, RESULTS_DIR/samples.csv and RESULTS_DIR/history.csv (written by
`softkin run experiments/configs/fig4_1_initial_guess.json`). Writes RESULTS_DIR/fig4_1_initial_guess.png:
  left:  the tip positions of the configuration-space samples (x-z, mm), the target (star) and the
         closest sample (triangle), the initial guess of the sampled start;
  right: the objective O = |p - p_t|^2 (mm^2, log scale) against the iteration, from rest and from
         the closest sample, with lambda.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig4_1_initial_guess"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    samples = figlib.read_samples(NAME, os.path.join(results, "samples.csv"))
    hist = figlib.read_table(NAME, os.path.join(results, "history.csv"),
                             ["start", "iteration", "objective"], ["iteration", "objective"],
                             check=lambda v: None if v["objective"] >= 0 else "negative objective",
                             min_rows=2)
    target = summary.get("target")
    closest = (summary.get("closest_sample") or {}).get("point")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    ax.plot([s["x"] for s in samples], [s["z"] for s in samples], "o", color="C0", ms=4,
            alpha=0.6, label=f"{len(samples)} samples")
    if isinstance(target, list) and len(target) == 3:
        ax.plot([target[0]], [target[2]], "k*", ms=14, label="target")
    if isinstance(closest, list) and len(closest) == 3:
        ax.plot([closest[0]], [closest[2]], "r^", ms=10, label="closest sample")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_title("(b) sampled configuration space of the tip")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    for start, color in (("rest", "C0"), ("sampled", "C3")):
        h = [r for r in hist if r["start"] == start]
        if h:
            ax2.semilogy([r["iteration"] for r in h], [max(r["objective"], 1e-12) for r in h], "o-",
                         color=color, ms=3,
                         label="from rest" if start == "rest" else "from the closest sample")
    lam = summary.get("lambda_mm")
    if isinstance(lam, (int, float)) and lam > 0:
        ax2.axhline(lam * lam, color="k", ls="--", lw=1, label=f"lambda = ({lam:g} mm)^2")
    ax2.set_xlabel("iteration")
    ax2.set_ylabel("objective (mm^2)")
    ax2.set_title("(c) convergence of the IK objective (Eq. 4.4)")
    ax2.grid(True, alpha=0.3, which="both")
    ax2.legend(fontsize=8)
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Thesis Fig. 4.1: {summary.get('robot', '?')}, initial guess for IK "
                 f"({summary.get('method', '?')}){quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
