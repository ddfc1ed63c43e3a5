#!/usr/bin/env python3
"""Solver ablation: plain local-global (thesis Alg. 1, Sec. 2.5), Anderson acceleration (Sec. 3.3) and Newton-Krylov.

Usage: aa_ablation.py RESULTS_DIR

Reads RESULTS_DIR/aa_ablation.csv (written by `softkin run experiments/configs/aa_ablation.json`) and, if
present, RESULTS_DIR/summary.json. Writes RESULTS_DIR/aa_ablation.png: grouped bars of the
iteration count of plain local-global (lg) and of each Anderson-accelerated variant
("lg-aa m=<window> <safeguard>") for every robot and actuation level, on a log scale, with the
lg / variant iteration ratio above each Anderson bar; below, the wall-clock time of every variant,
including whole other solvers (for example "newton", whose iterations are Newton iterations and
so are not drawn in the upper panel), with the lg / variant time ratio. Bars of runs that did not
converge are hatched.
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import os
import re
import sys

import figlib

NAME = "aa_ablation"
COLUMNS = ["robot", "level", "variant", "iterations", "time_s", "energy", "status", "aa_accepted",
           "aa_rejected", "iteration_ratio", "time_ratio"]
NUMERIC = ["level", "iterations", "time_s", "energy", "aa_accepted", "aa_rejected",
           "iteration_ratio", "time_ratio"]
PALETTE = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown"]


def fail(msg):
    figlib.fail(NAME, msg)


def read_table(path):
    return figlib.read_table(
        NAME, path, COLUMNS, NUMERIC,
        check=lambda v: None if v["variant"].startswith("lg-aa m=") or
        re.fullmatch(r"[a-z][a-z0-9-]*", v["variant"]) else
        f"variant is '{v['variant']}', expected lg, 'lg-aa m=<window> <safeguard>' or a solver name")


def read_summary(path):
    return figlib.read_summary(NAME, path)


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = read_table(os.path.join(results, "aa_ablation.csv"))
    summary = read_summary(os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    # Groups (robot, level) in the order they first appear; one bar per variant inside each.
    groups, table, variants = [], {}, []
    for r in rows:
        key = (r["robot"], r["level"])
        if key not in table:
            groups.append(key)
            table[key] = {}
        table[key][r["variant"]] = r
        if r["variant"] not in variants:
            variants.append(r["variant"])
    if "lg" in variants:  # plain first
        variants.remove("lg")
        variants.insert(0, "lg")
    colors = {v: ("tab:gray" if v == "lg" else PALETTE[(i - 1) % len(PALETTE)])
              for i, v in enumerate(variants)}

    anderson = [v for v in variants if v == "lg" or v.startswith("lg-aa m=")]
    fig, axes = plt.subplots(2, 1, figsize=(max(8.0, 0.45 * len(groups) * len(variants) + 3.0),
                                            9.6))
    any_failed = False
    for ax, shown, metric, ratio, ylabel in (
            (axes[0], anderson, "iterations", "iteration_ratio",
             "FK iterations to converge (log)"),
            (axes[1], variants, "time_s", "time_ratio", "wall-clock time to converge, s (log)")):
        width = 0.8 / len(shown)
        floor = 1.0 if metric == "iterations" else 1e-3  # log axis: show 0 as the floor
        for s_i, variant in enumerate(shown):
            for g_i, key in enumerate(groups):
                r = table[key].get(variant)
                if r is None:
                    continue
                xpos = g_i + (s_i - (len(shown) - 1) / 2) * width
                failed = r["status"] != "converged"
                any_failed |= failed
                height = max(r[metric], floor)
                ax.bar(xpos, height, width, color=colors[variant], edgecolor="k", linewidth=0.6,
                       hatch="//" if failed else None)
                label = f"{r[metric]:.0f}" if metric == "iterations" else f"{r[metric]:.2g}"
                if variant != "lg" and "lg" in table[key]:
                    label += (f"\n\N{MULTIPLICATION SIGN}{r[ratio]:.1f}" if r[ratio] >= 1.0 else
                              f"\n\N{MULTIPLICATION SIGN}{r[ratio]:.2g}")
                ax.text(xpos, height * 1.05, label, ha="center", va="bottom", fontsize=7)
        ax.set_yscale("log")
        ax.set_xticks(range(len(groups)))
        ax.set_xticklabels([f"{robot}\nlevel {level:g}" for robot, level in groups], fontsize=8)
        ax.set_ylabel(ylabel)
        ax.grid(True, axis="y", which="both", alpha=0.3)
        values = [max(r[metric], floor) for r in rows if r["variant"] in shown]
        ax.set_ylim(max(floor / 2.0, min(values) / 2.0), max(values) * 10.0)
        handles = [Patch(facecolor=colors[v], edgecolor="k",
                         label="lg (plain local-global)" if v == "lg" else v) for v in shown]
        if any_failed:
            handles.append(Patch(facecolor="white", edgecolor="k", hatch="//",
                                 label="not converged"))
        ax.legend(handles=handles, loc="upper left", fontsize=8)
    quick = " (quick run)" if summary.get("quick") else ""
    axes[0].set_title("Ablation (not a thesis figure): FK solvers on one problem{}\n"
                      "above the bars: iterations (top) or seconds (bottom) and the lg / variant "
                      "ratio".format(quick), fontsize=10)
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
