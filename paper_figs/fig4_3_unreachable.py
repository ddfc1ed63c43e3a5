#!/usr/bin/env python3
"""Thesis Fig. 4.3: a path that leaves the workspace; IK returns the closest reachable points.

Usage: fig4_3_unreachable.py RESULTS_DIR

Reads RESULTS_DIR/summary.json (written by `softkin run experiments/configs/fig4_3_unreachable.json`),
RESULTS_DIR/path_<name>.csv and RESULTS_DIR/samples.csv. Writes RESULTS_DIR/fig4_3_unreachable.png:
  left:  the target waypoints (red) and the reached points (black), each pair joined by a grey
         dashed line, over the sampled configuration space (x-z, mm);
  right: the distance to the target per waypoint, and the step between neighbouring reached
         points (continuity).
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import math
import sys

import figlib

NAME = "fig4_3_unreachable"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    summary, paths, samples = figlib.read_ik_paths(NAME, results)
    p = paths[0]
    w = figlib.read_path_waypoints(NAME, results, p)
    ok = [r for r in w if r["error_mm"] >= 0]

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    ax.plot([s["x"] for s in samples], [s["z"] for s in samples], ".", color="0.8", ms=4,
            label="configuration-space samples")
    for r in ok:
        ax.plot([r["target_x"], r["reached_x"]], [r["target_z"], r["reached_z"]], "--",
                color="0.5", lw=0.8)
    ax.plot([r["target_x"] for r in w], [r["target_z"] for r in w], "o", color="C3", ms=3,
            label="waypoints")
    ax.plot([r["reached_x"] for r in ok], [r["reached_z"] for r in ok], "k.-", ms=4, lw=0.8,
            label="reached")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_title(f"{p.get('beyond_lambda', '?')} of {len(w)} waypoints out of reach")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax2.plot([r["index"] for r in ok], [r["error_mm"] for r in ok], "o-", ms=3,
             label="distance to the waypoint")
    steps = [math.dist((a["reached_x"], a["reached_y"], a["reached_z"]),
                       (b["reached_x"], b["reached_y"], b["reached_z"])) for a, b in zip(ok, ok[1:])]
    tsteps = [math.dist((a["target_x"], a["target_y"], a["target_z"]),
                        (b["target_x"], b["target_y"], b["target_z"])) for a, b in zip(ok, ok[1:])]
    ax2.plot([r["index"] for r in ok[1:]], steps, "s-", ms=3, label="step between reached points")
    ax2.plot([r["index"] for r in ok[1:]], tsteps, ":", color="C3", label="step between waypoints")
    ax2.set_xlabel("waypoint")
    ax2.set_ylabel("mm")
    ax2.set_title("Distance to the path, and continuity")
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8)
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Thesis Fig. 4.3: {summary.get('robot', '?')}, a path partly outside the "
                 f"workspace{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
