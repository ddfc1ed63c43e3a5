#!/usr/bin/env python3
"""Thesis Table 5.1: IK time per waypoint and error of each IK method, ours beside the thesis's.

Usage: table5_1_ik_methods.py RESULTS_DIR

Reads RESULTS_DIR/summary.json (rows[].{method, label, ms_per_waypoint, mean_err_mm, max_err_mm,
thesis_ms_per_waypoint, thesis_mean_err_mm}; error_measured_by, thesis_error_measured_by) and
RESULTS_DIR/targets.csv (one row per method x target, errors measured by the simulator or twin).
Writes RESULTS_DIR/table5_1_ik_methods.png:
  (a) time per waypoint (ms, log scale), ours and the thesis's, per method;
  (b) mean error (mm), ours and the thesis's; (c) the distribution of our errors per method.
The thesis's bars are hatched and labelled with where their errors were measured (hardware), ours
with ours (the simulator, or a twin): in (b) they are not the same measurement.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "table5_1_ik_methods"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    rows = summary.get("rows")
    if not isinstance(rows, list) or not rows:
        figlib.fail(NAME, f"{results}/summary.json: expected a non-empty 'rows' array")
    for i, r in enumerate(rows):
        for k in ("method", "ms_per_waypoint", "mean_err_mm", "thesis_ms_per_waypoint", "thesis_mean_err_mm"):
            if k not in r:
                figlib.fail(NAME, f"{results}/summary.json: rows[{i}] lacks '{k}'")
    targets = figlib.read_table(NAME, os.path.join(results, "targets.csv"),
                                ["method", "err_mm", "time_ms"], numeric=["err_mm", "time_ms"])

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [r.get("label", r["method"]) for r in rows]
    ours_by = summary.get("error_measured_by", "simulator")
    thesis_by = summary.get("thesis_error_measured_by", "hardware")
    x = list(range(len(rows)))
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(16, 5))
    w = 0.38
    thesis_style = dict(color="white", edgecolor="C1", hatch="//", lw=1)
    a.bar([i - w / 2 for i in x], [max(r["ms_per_waypoint"], 1e-4) for r in rows], w,
          label="SoftKin (this machine)")
    a.bar([i + w / 2 for i in x], [r["thesis_ms_per_waypoint"] for r in rows], w,
          label="thesis (its machine)", **thesis_style)
    a.set_yscale("log")
    a.set_ylabel("time per waypoint (ms)")
    a.set_title("(a) IK time per waypoint")
    b.bar([i - w / 2 for i in x], [r["mean_err_mm"] for r in rows], w,
          label=f"SoftKin, measured by the {ours_by}")
    b.bar([i + w / 2 for i in x], [r["thesis_mean_err_mm"] for r in rows], w,
          label=f"thesis, measured on {thesis_by}", **thesis_style)
    b.set_ylabel("mean error (mm)")
    b.set_title(f"(b) mean tip error: ours by the {ours_by},\nthe thesis's on {thesis_by} "
                "(not the same measurement)", fontsize=10)
    for ax in (a, b):
        ax.set_xticks(x)
        ax.set_xticklabels(names, rotation=20, ha="right", fontsize=8)
        ax.legend(fontsize=8)
        ax.grid(True, axis="y", alpha=0.3)
    data = [[t["err_mm"] for t in targets if t["method"] == r["method"] and t["err_mm"] >= 0] for r in rows]
    c.boxplot([d if d else [0.0] for d in data])
    c.set_xticks([i + 1 for i in x])
    c.set_xticklabels(names, rotation=20, ha="right", fontsize=8)
    c.set_ylabel("error (mm)")
    c.set_title(f"(c) SoftKin's errors per target, by the {ours_by} "
                f"(lambda {summary.get('lambda_mm', 0):.3f} mm)", fontsize=10)
    c.grid(True, axis="y", alpha=0.3)
    figlib.save_figure(fig, results, NAME)


if __name__ == "__main__":
    main(sys.argv)
