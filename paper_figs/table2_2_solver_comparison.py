#!/usr/bin/env python3
"""Table 2.2: the same bending sweep of pneumatic_finger solved by every FK method.

Usage: table2_2_solver_comparison.py RESULTS_DIR

Reads RESULTS_DIR/trajectories.csv and RESULTS_DIR/summary.json (written by
`softkin run experiments/configs/table2_2_solver_comparison.json`). Writes
RESULTS_DIR/table2_2_solver_comparison.png with two panels:
  left:  cumulative solve time against the bend angle for each method (log time), with the
         thesis's Table 2.2 times at 90/180/240 degrees as markers;
  right: the tip trajectory (x-z) of each method, so the shapes can be compared.
Methods that stopped early (time limit, divergence) end where they stopped; methods not run are
listed in the title. The pressure-driven FEM rows (calculix-pressure-*) give each converged
increment at the cavity volume ratio it reached, and end where CalculiX stopped. Exit status 2 with a message on stderr if an input is missing or malformed.
"""
import os
import sys

import figlib

NAME = "table2_2_solver_comparison"
COLUMNS = ["method", "step", "actuation", "bend_deg", "tip_x", "tip_y", "tip_z", "iterations",
           "time_s", "cumulative_s", "energy", "residual_ratio", "status"]
# energy is empty on the pressure FEM rows (their chambers are hollow), so it is not parsed.
NUMERIC = ["step", "actuation", "bend_deg", "tip_x", "tip_y", "tip_z", "iterations", "time_s",
           "cumulative_s", "residual_ratio"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = figlib.read_table(NAME, os.path.join(results, "trajectories.csv"), COLUMNS, NUMERIC)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    fig, (ax_t, ax_p) = plt.subplots(1, 2, figsize=(13, 5.2))
    palette = plt.get_cmap("tab20").colors  # more methods than the default cycle's 10 colours
    for i, m in enumerate(methods):
        rs = [r for r in rows if r["method"] == m]
        st = summary.get("methods", {}).get(m.replace("-", "_"), {}).get("status", "?")
        label = f"{m} ({st})"
        style = dict(marker="o", ms=3, color=palette[(2 * i) % 20 + (2 * i) // 20 % 2],
                     ls="--" if m.startswith("calculix-pressure") else "-")
        ax_t.plot([0] + [r["bend_deg"] for r in rs], [1e-3] + [max(r["cumulative_s"], 1e-3) for r in rs],
                  label=label, **style)
        ax_p.plot([r["tip_x"] for r in rs], [r["tip_z"] for r in rs], label=m, **style)
    thesis = summary.get("thesis_table_2_2", {})
    for key, style in (("ours", "k*"), ("fem1_abaqus_linear", "bs"), ("fem2_abaqus_nonlinear", "rs"),
                       ("sofa", "g^")):
        t = thesis.get(key)
        if not t:
            continue
        pts = [(a, t.get(f"t{a}_s")) for a in (90, 180, 240) if t.get(f"t{a}_s") is not None]
        if pts:
            ax_t.plot([p[0] for p in pts], [p[1] for p in pts], style, ms=8, mfc="none",
                      label=f"thesis: {key} ({t.get('elements', '?')} el.)")
    ax_t.set_yscale("log")
    ax_t.set_xlabel("bend angle (degrees)")
    ax_t.set_ylabel("cumulative solve time (s)")
    ax_t.grid(True, which="both", alpha=0.3)
    ax_t.legend(fontsize=7)
    ax_p.set_xlabel("tip x (mm)")
    ax_p.set_ylabel("tip z (mm)")
    ax_p.set_aspect("equal", adjustable="datalim")
    ax_p.grid(True, alpha=0.3)
    ax_p.legend(fontsize=7)
    not_run = [k for k, v in summary.get("methods", {}).items() if v.get("status") == "not_run"]
    sp = summary.get("speedup_vs_best_nlp")
    head = f"{summary.get('robot', '?')}, {summary.get('n_tets', '?')} tets"
    if sp is not None:
        bound = ">= " if summary.get("speedup_vs_best_nlp_lower_bound") else ""
        head += f"; lg-aa vs fastest NLP ({summary.get('speedup_vs_best_nlp_method')}): {bound}{sp:.0f}x"
    for fem in ("calculix_pressure_nonlinear", "calculix_pressure_linear"):
        sp = summary.get(f"speedup_vs_{fem}")
        if sp is not None:
            head += (f"; vs {fem.replace('_', '-')} at {summary[f'speedup_vs_{fem}_at_deg']:.0f}"
                     f" deg: {sp:.3g}x")
    if not_run:
        head += "\nnot run: " + ", ".join(not_run)
    fig.suptitle(head, fontsize=10)
    fig.tight_layout()
    figlib.save_figure(fig, results, NAME)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
