#!/usr/bin/env python3
"""Fig. 3.7 (thesis Sec. 3.3.2, Algorithm 2): the twisting robot inflated with progressive chamber
remeshing, against the same actuation applied at once without remeshing.

Usage: fig3_7_twisting_remesh.py RESULTS_DIR

Reads RESULTS_DIR/shapes.csv (one row per shape, naming its outer and chamber surface OBJ files),
steps.csv (one row per ladder step) and summary.json, written by
`softkin run experiments/configs/fig3_7_twisting_remesh.json`. Writes RESULTS_DIR/fig3_7_twisting_remesh.png:
  top row:    the deformed shapes, progressive (one panel per alpha) and at once (last panel);
              the body surface in grey, the chamber in red; the tip twist in the title;
  bottom row: tip twist and reached chamber volume ratio against the asked alpha, and the tet
              count, remeshes and failed remeshes along the progressive ladder.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig3_7_twisting_remesh"
SHAPES = ["variant", "alpha", "tip_twist_deg", "chamber_volume_ratio", "remeshes", "tets", "inverted_tets",
          "mesh_s", "solver_s", "tip_x", "tip_y", "tip_z", "outer_obj", "chamber_obj", "vtu"]
SHAPES_NUM = ["alpha", "tip_twist_deg", "chamber_volume_ratio", "remeshes", "tets", "inverted_tets", "mesh_s",
              "solver_s", "tip_x", "tip_y", "tip_z"]
STEPS = ["variant", "k", "alpha", "remeshes", "methods", "remesh_failures", "tets", "chamber_tets", "mesh_s", "solver_s",
         "iterations", "status", "chamber_volume_ratio", "max_volume_ratio", "max_distortion", "tip_twist_deg",
         "tip_x", "tip_y", "tip_z"]
STEPS_NUM = ["k", "alpha", "remeshes", "remesh_failures", "tets", "chamber_tets", "mesh_s", "solver_s", "iterations",
             "chamber_volume_ratio", "max_volume_ratio", "max_distortion", "tip_twist_deg", "tip_x", "tip_y",
             "tip_z"]


def read_obj(path):
    """Vertices and triangles of a Wavefront OBJ written by softkin (v / f lines, 1-based)."""
    if not os.path.isfile(path):
        figlib.fail(NAME, f"{path} not found")
    verts, faces = [], []
    with open(path) as f:
        for no, line in enumerate(f, 1):
            parts = line.split()
            if not parts:
                continue
            try:
                if parts[0] == "v":
                    verts.append([float(x) for x in parts[1:4]])
                elif parts[0] == "f":
                    faces.append([int(x.split("/")[0]) - 1 for x in parts[1:4]])
            except (ValueError, IndexError):
                figlib.fail(NAME, f"{path}:{no}: expected 'v x y z' or 'f i j k', got '{line.strip()}'")
    for no, t in enumerate(faces, 1):
        if len(t) != 3 or min(t) < 0 or max(t) >= len(verts):
            figlib.fail(NAME, f"{path}: face {no} has indices {t}, expected 3 in 1..{len(verts)}")
    return verts, faces


def draw(ax, results, row, title):
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    outer_v, outer_f = read_obj(os.path.join(results, row["outer_obj"]))
    ch_v, ch_f = read_obj(os.path.join(results, row["chamber_obj"]))
    ax.add_collection3d(Poly3DCollection([[outer_v[i] for i in t] for t in outer_f], facecolor=(0.6, 0.6, 0.6, 0.18),
                                         edgecolor=(0.3, 0.3, 0.3, 0.15), linewidths=0.2))
    ax.add_collection3d(Poly3DCollection([[ch_v[i] for i in t] for t in ch_f], facecolor=(0.85, 0.1, 0.1, 0.75),
                                         edgecolor="none"))
    pts = outer_v + ch_v
    lo = [min(p[d] for p in pts) for d in range(3)]
    hi = [max(p[d] for p in pts) for d in range(3)]
    c = [(lo[d] + hi[d]) / 2 for d in range(3)]
    r = max(hi[d] - lo[d] for d in range(3)) / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.view_init(elev=15, azim=-60)
    ax.set_title(title, fontsize=9)
    ax.set_axis_off()


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    shapes = figlib.read_table(NAME, os.path.join(results, "shapes.csv"), SHAPES, numeric=SHAPES_NUM,
                               check=lambda v: None if v["variant"] in ("progressive", "at_once")
                               else f"variant is '{v['variant']}', expected progressive or at_once")
    steps = figlib.read_table(NAME, os.path.join(results, "steps.csv"), STEPS, numeric=STEPS_NUM)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prog = sorted([r for r in shapes if r["variant"] == "progressive"], key=lambda r: r["alpha"])
    once = [r for r in shapes if r["variant"] == "at_once"]
    panels = prog + once
    n = max(len(panels), 3)
    fig = plt.figure(figsize=(3.4 * n, 8.2))
    for i, row in enumerate(panels):
        ax = fig.add_subplot(2, n, i + 1, projection="3d")
        kind = "progressive remeshing" if row["variant"] == "progressive" else "at once, no remeshing"
        draw(ax, results, row,
             f"alpha = {row['alpha']:g}, {kind}\n"
             f"tip twist {row['tip_twist_deg']:.0f} deg, chamber x{row['chamber_volume_ratio']:.1f}\n"
             f"{int(row['tets'])} tets, {int(row['remeshes'])} remeshes, {int(row['inverted_tets'])} inverted")

    ps = [r for r in steps if r["variant"] == "progressive"]
    os_ = [r for r in steps if r["variant"] == "at_once"]
    ax = fig.add_subplot(2, n, n + 1)
    ax.plot([r["alpha"] for r in ps], [r["tip_twist_deg"] for r in ps], "o-", color="tab:blue", ms=3,
            label="progressive remeshing")
    ax.plot([r["alpha"] for r in os_], [r["tip_twist_deg"] for r in os_], "s", color="tab:red", ms=7,
            label="at once, no remeshing")
    ax.set_xlabel("alpha asked (chamber volume ratio)")
    ax.set_ylabel("tip twist about the axis (deg)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax = fig.add_subplot(2, n, n + 2)
    ax.plot([r["alpha"] for r in ps], [r["chamber_volume_ratio"] for r in ps], "o-", color="tab:blue", ms=3,
            label="progressive remeshing")
    ax.plot([r["alpha"] for r in os_], [r["chamber_volume_ratio"] for r in os_], "s", color="tab:red", ms=7,
            label="at once")
    top = max([r["alpha"] for r in steps] + [1])
    ax.plot([1, top], [1, top], ":", color="grey", label="reached = asked")
    ax.set_xlabel("alpha asked")
    ax.set_ylabel("chamber volume ratio reached")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax = fig.add_subplot(2, n, n + 3)
    ax.plot([r["alpha"] for r in ps], [r["tets"] for r in ps], "o-", color="tab:green", ms=3, label="tets")
    rem = [r for r in ps if r["remeshes"] > 0]
    ax.plot([r["alpha"] for r in rem], [r["tets"] for r in rem], "kx", ms=8, label="remeshed at this step")
    bad = [r for r in ps if r["remesh_failures"] > 0]
    ax.plot([r["alpha"] for r in bad], [r["tets"] for r in bad], "o", mfc="none", mec="tab:red", ms=7,
            label="remesh failed (kept the mesh)")
    ax.set_xlabel("alpha asked")
    ax.set_ylabel("tets")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    quick = " (quick run)" if summary.get("quick") else ""
    prog_sum = summary.get("progressive", {})
    fig.suptitle(f"Twisting robot, progressive chamber remeshing (Alg. 2): {prog_sum.get('remeshes', '?')} remeshes, "
                 f"alpha_max = d_max = {summary.get('alpha_max', '?')}, chamber rest shape: "
                 f"{summary.get('chamber_rest', 'remeshed')}{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
