#!/usr/bin/env python3
"""Thesis Fig. 4.2: the cable-driven finger following an 'L' path and a flame path (Algorithm 4).

Usage: fig4_2_trajectories.py RESULTS_DIR

Reads RESULTS_DIR/summary.json (written by `softkin run experiments/configs/fig4_2_trajectories.json`),
RESULTS_DIR/path_<name>.csv for every path it lists and RESULTS_DIR/samples.csv. Writes
RESULTS_DIR/fig4_2_trajectories.png, one row per path:
  left:  the target waypoints and the reached tip positions in the finger's motion plane (x-z, mm),
         over the sampled configuration space (grey);
  right: the error |reached - target| per waypoint (mm) with lambda, and our time per waypoint
         beside the thesis's (its total over its number of waypoints, the paths' thesis.waypoints).
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import sys

import figlib

NAME = "fig4_2_trajectories"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    summary, paths, samples = figlib.read_ik_paths(NAME, results)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lam = summary.get("lambda_mm", 0.2)
    fig, axes = plt.subplots(len(paths), 2, figsize=(12, 4.6 * len(paths)), squeeze=False)
    for row, p in enumerate(paths):
        name = p.get("name", "?")
        w = figlib.read_path_waypoints(NAME, results, p)
        ax, ax2 = axes[row]
        ax.plot([s["x"] for s in samples], [s["z"] for s in samples], ".", color="0.8", ms=4,
                label="configuration-space samples")
        ax.plot([r["target_x"] for r in w], [r["target_z"] for r in w], "o-", color="C3", ms=3,
                lw=1, label="target")
        ok = [r for r in w if r["error_mm"] >= 0]
        ax.plot([r["reached_x"] for r in ok], [r["reached_z"] for r in ok], "k.", ms=4,
                label="reached")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("z (mm)")
        ax.set_title(f"'{name}' path, N = {len(w)}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        ax2.plot([r["index"] for r in ok], [r["error_mm"] for r in ok], "o-", ms=3)
        ax2.axhline(lam, color="k", ls="--", lw=1, label=f"lambda = {lam:g} mm")
        ax2.set_xlabel("waypoint")
        ax2.set_ylabel("error (mm)")
        # Times compared per waypoint: a quick run follows fewer waypoints than the thesis.
        t = p.get("total_time_s")
        thesis = p.get("thesis") or {}
        th, th_n = thesis.get("total_time_s"), thesis.get("waypoints")
        title = f"'{name}': error per waypoint"
        if isinstance(t, (int, float)) and w:
            title += f"\nours {t:.1f} s / {len(w)} waypoints = {t / len(w):.2f} s per waypoint"
        if isinstance(th, (int, float)) and isinstance(th_n, int) and th_n > 0:
            title += f"\nthesis {th:g} s / {th_n} waypoints = {th / th_n:.2f} s per waypoint"
        ax2.set_title(title, fontsize=10)
        ax2.grid(True, alpha=0.3)
        ax2.legend(fontsize=8)
    quick = (f" (quick run: res {summary.get('res', '?')}, fewer waypoints)"
             if summary.get("quick") else "")
    fig.suptitle(f"Thesis Fig. 4.2: {summary.get('robot', '?')} following paths (Algorithm 4, "
                 f"{summary.get('method', '?')}, Jacobian {summary.get('jacobian', '?')}){quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
