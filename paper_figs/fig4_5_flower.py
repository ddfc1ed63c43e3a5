#!/usr/bin/env python3
"""Thesis Fig. 4.5: the three-chamber actuator's tip following the flower path (Algorithm 4).

Usage: fig4_5_flower.py RESULTS_DIR

Reads RESULTS_DIR/summary.json (written by `softkin run experiments/configs/fig4_5_flower.json`),
RESULTS_DIR/path_<name>.csv and RESULTS_DIR/samples.csv. Writes RESULTS_DIR/fig4_5_flower.png:
  (a) the sampled tip workspace and the mapped target path, side view (x against y = long axis);
  (b) top view (x-z): target and tracked tip;
  (c) the error per waypoint (mm) and (d) the IK time per waypoint (s), with the thesis's values.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import sys

import figlib

NAME = "fig4_5_flower"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    summary, paths, samples = figlib.read_ik_paths(NAME, results)
    p = paths[0]
    w = figlib.read_path_waypoints(NAME, results, p)
    ok = [r for r in w if r["error_mm"] >= 0]

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ((a, b), (c, d)) = plt.subplots(2, 2, figsize=(12, 9.5))
    a.plot([s["x"] for s in samples], [s["y"] for s in samples], ".", color="C3", alpha=0.4, ms=4,
           label="sampled tip positions")
    a.plot([r["target_x"] for r in w], [r["target_y"] for r in w], "b-", lw=1, label="target")
    a.set_xlabel("x (mm)")
    a.set_ylabel("y, long axis (mm)")
    a.set_title("(a) workspace samples and the mapped flower, side view")
    a.legend(fontsize=8)
    a.grid(True, alpha=0.3)
    b.plot([r["target_x"] for r in w], [r["target_z"] for r in w], "b-", lw=1, label="target")
    b.plot([r["reached_x"] for r in ok], [r["reached_z"] for r in ok], "r.", ms=4, label="tracked tip")
    b.set_aspect("equal", adjustable="datalim")
    b.set_xlabel("x (mm)")
    b.set_ylabel("z (mm)")
    b.set_title("(b) top view")
    b.legend(fontsize=8)
    b.grid(True, alpha=0.3)
    c.plot([r["index"] for r in ok], [r["error_mm"] for r in ok], "o-", ms=3, label="ours")
    th = (p.get("thesis") or {}).get("max_error_mm")
    if isinstance(th, (int, float)):
        c.axhline(th, color="k", ls="--", lw=1, label=f"thesis bound {th:g} mm")
    c.set_xlabel("waypoint")
    c.set_ylabel("error (mm)")
    c.set_title("(c) position error of the tip")
    c.legend(fontsize=8)
    c.grid(True, alpha=0.3)
    d.plot([r["index"] for r in w], [r["time_s"] for r in w], "o-", ms=3, label="ours")
    tt = (p.get("thesis") or {}).get("s_per_waypoint")
    if isinstance(tt, (int, float)):
        d.set_title(f"(d) IK time per waypoint (thesis: {tt:g} s per waypoint)")
    else:
        d.set_title("(d) IK time per waypoint")
    d.set_xlabel("waypoint")
    d.set_ylabel("s")
    d.grid(True, alpha=0.3)
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Thesis Fig. 4.5: three_chamber following the flower path (res "
                 f"{summary.get('res', '?')}, {summary.get('method', '?')}, Jacobian "
                 f"{summary.get('jacobian', '?')}){quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
