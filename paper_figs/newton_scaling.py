#!/usr/bin/env python3
"""Issue #33's scaling study: FK solvers under mesh refinement.

Usage: newton_scaling.py RESULTS_DIR

Reads RESULTS_DIR/scaling.csv (written by `softkin run experiments/configs/newton_scaling.json`)
and, if present, RESULTS_DIR/summary.json. Writes RESULTS_DIR/newton_scaling.png:
  left:  iterations to tolerance against the number of tets (log x), per robot and solver;
  right: solve time per vertex (microseconds) against the number of tets.
Runs that did not converge are circled in red.
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import os
import sys

import figlib

NAME = "newton_scaling"
COLUMNS = ["robot", "solver", "res", "n_vertices", "n_tets", "iterations", "linear_iterations",
           "solve_s", "us_per_vertex", "residual_ratio", "converged"]
NUMERIC = COLUMNS[2:]


def read_rows(path):
    return figlib.read_table(NAME, path, COLUMNS, numeric=NUMERIC,
                             check=lambda v: None if v["n_tets"] > 0 else
                             f"n_tets must be positive, got {v['n_tets']:g}")


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = read_rows(os.path.join(results, "scaling.csv"))
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    series = {}
    for r in rows:
        series.setdefault((r["robot"], r["solver"]), []).append(r)
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 4.8))
    markers = {"newton": "o", "lg-aa": "s", "lg": "^"}
    for (robot, solver), rs in sorted(series.items()):
        rs.sort(key=lambda r: r["n_tets"])
        tets = [r["n_tets"] for r in rs]
        label = f"{robot}, {solver}"
        m = markers.get(solver, "d")
        ls = "-" if solver == "newton" else "--"
        line, = ax0.plot(tets, [r["iterations"] for r in rs], ls, marker=m, label=label)
        ax1.plot(tets, [r["us_per_vertex"] for r in rs], ls, marker=m, color=line.get_color(),
                 label=label)
        for r in rs:
            if r["converged"] < 0.5:
                for ax, key in ((ax0, "iterations"), (ax1, "us_per_vertex")):
                    ax.plot(r["n_tets"], r[key], "o", ms=12, mfc="none", mec="red")
    ax0.set_xscale("log")
    ax0.set_yscale("log")
    ax0.set_xlabel("tetrahedra")
    ax0.set_ylabel("iterations to tolerance")
    ax0.set_title("Iterations (newton: Newton steps; lg-aa: local-global)")
    ax0.grid(True, which="both", alpha=0.3)
    ax0.legend(fontsize=8)
    ax1.set_xscale("log")
    ax1.set_yscale("log")
    ax1.set_xlabel("tetrahedra")
    ax1.set_ylabel("solve time per vertex (us)")
    ax1.set_title("Time per vertex, from rest")
    ax1.grid(True, which="both", alpha=0.3)
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"FK solvers under mesh refinement{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
