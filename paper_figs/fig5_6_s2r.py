#!/usr/bin/env python3
"""Thesis Fig. 5.6: the sim-to-real network's train and test error against eta and against the
number of twin samples.

Usage: fig5_6_s2r.py RESULTS_DIR

Reads RESULTS_DIR/s2r_sweep.csv (twin, sweep, eta, samples, neurons, train_mm, test_mm,
without_mm). Writes RESULTS_DIR/fig5_6_s2r.png: (a) error against eta, (b) error against the
number of twin samples; train (dashed) and test (solid) per twin, and the error without s2r.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig5_6_s2r"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "s2r_sweep.csv"),
                             ["twin", "sweep", "eta", "samples", "train_mm", "test_mm", "without_mm"],
                             numeric=["eta", "samples", "train_mm", "test_mm", "without_mm"],
                             check=lambda v: None if v["sweep"] in ("eta", "samples") else "sweep must be eta or samples")
    twins = sorted({r["twin"] for r in rows})

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for ax, sweep, key, label in ((axes[0], "eta", "eta", "eta (neurons per training sample)"),
                                  (axes[1], "samples", "samples", "twin samples for N_s2r")):
        for k, t in enumerate(twins):
            sel = sorted((r for r in rows if r["twin"] == t and r["sweep"] == sweep), key=lambda r: r[key])
            if not sel:
                continue
            x = [r[key] for r in sel]
            ax.plot(x, [r["test_mm"] for r in sel], "o-", color=f"C{k}", label=f"{t} test")
            ax.plot(x, [r["train_mm"] for r in sel], "s--", color=f"C{k}", alpha=0.6, label=f"{t} train")
            ax.axhline(sel[0]["without_mm"], color=f"C{k}", ls=":", label=f"{t} without s2r")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(label)
        ax.set_ylabel("mean tip error (mm, twin data)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_title("(a) against eta")
    axes[1].set_title("(b) against the number of twin samples (eta = 1/4)")
    figlib.save_figure(fig, results, NAME)


if __name__ == "__main__":
    main(sys.argv)
