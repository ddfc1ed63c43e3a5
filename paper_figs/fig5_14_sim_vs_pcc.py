#!/usr/bin/env python3
"""Thesis Fig. 5.14: sim-to-real on networks learned from the simulator or from the PCC model.

Usage: fig5_14_sim_vs_pcc.py RESULTS_DIR

Reads RESULTS_DIR/errors.csv (source, ts, sample, err_mm, err_pct: one row per held-out twin
sample, per data source and number TS# of s2r training samples) and RESULTS_DIR/summary.json.
Writes RESULTS_DIR/fig5_14_sim_vs_pcc.png: (a) mean error (% of workspace width) against TS# for
both sources, with the errors without s2r; (b) histograms of the errors (% of width) per TS#, one
row per source, with the 1 % line.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig5_14_sim_vs_pcc"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "errors.csv"),
                             ["source", "ts", "sample", "err_mm", "err_pct"],
                             numeric=["ts", "sample", "err_mm", "err_pct"],
                             check=lambda v: None if v["err_mm"] >= 0 else "err_mm must be >= 0")
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    width = summary.get("workspace_width_mm", 0) or 1.0
    sources = sorted({r["source"] for r in rows}, key=lambda s: s != "simulator")
    sizes = sorted({int(r["ts"]) for r in rows})

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(4 + 3 * len(sizes), 4 + 2.5 * len(sources)))
    gs = fig.add_gridspec(len(sources), len(sizes) + 1)
    a = fig.add_subplot(gs[:, 0])
    for k, s in enumerate(sources):
        m = [sum(r["err_pct"] for r in rows if r["source"] == s and int(r["ts"]) == t) /
             max(1, sum(1 for r in rows if r["source"] == s and int(r["ts"]) == t)) for t in sizes]
        a.plot(sizes, m, "o-", color=f"C{k}", label=f"N_fk from {s} + s2r")
        for src in summary.get("sources", []):
            if src.get("source") == s and "twin_mean_err_without_s2r_mm" in src:
                a.axhline(100.0 * src["twin_mean_err_without_s2r_mm"] / width, color=f"C{k}", ls=":",
                          label=f"{s}, no s2r")
    a.axhline(1.0, color="k", lw=0.8, ls="--", label="1 % of width")
    a.set_yscale("log")
    a.set_xlabel("TS# (twin samples for s2r)")
    a.set_ylabel("mean error on held-out twin samples (% of width)")
    a.set_title("(a) error against TS#")
    a.legend(fontsize=7)
    a.grid(True, which="both", alpha=0.3)
    for i, s in enumerate(sources):
        for j, t in enumerate(sizes):
            ax = fig.add_subplot(gs[i, j + 1])
            e = [r["err_pct"] for r in rows if r["source"] == s and int(r["ts"]) == t]
            ax.hist(e, bins=20, color=f"C{i}")
            ax.axvline(1.0, color="k", ls="--", lw=0.8)
            within = 100.0 * sum(1 for v in e if v <= 1.0) / max(1, len(e))
            ax.set_title(f"(b) {s}, TS# = {t}: {within:.0f} % within 1 %", fontsize=8)
            ax.set_xlabel("error (% of width)", fontsize=8)
    figlib.save_figure(fig, results, NAME)


if __name__ == "__main__":
    main(sys.argv)
