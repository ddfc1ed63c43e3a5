#!/usr/bin/env python3
"""Thesis Fig. 2.9: two cable grippers with different material distributions; trajectories of the
three boundary markers m1, m2, m3 as the cable is shortened.

Usage: fig2_9_multimaterial.py RESULTS_DIR

Reads RESULTS_DIR/markers.csv (written by `softkin run experiments/configs/fig2_9_multimaterial.json`,
one row per variant x step x marker) and, if present, RESULTS_DIR/summary.json (robot, the
robot_params of each variant, solve times). Writes RESULTS_DIR/fig2_9_multimaterial.png:
  one panel per variant (same x-z limits, mm, equal aspect; x the long axis, z up): the paths of
         m1, m2, m3 and of the tip (dashed) from their rest positions (black squares) as the
         cable length ratio s goes from 1 down;
  last:  the m3 paths of all variants overlaid, the positions of the same step joined by thin
         grey lines and the last step circled.
Steps that did not converge are marked with a black x.
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig2_9_multimaterial"
MARKERS = ["m1", "m2", "m3"]  # required, plotted in this order
TIP = "tip"                   # optional, dashed
COMPARE = "m3"                # overlaid across the variants in the last panel
COLORS = {"m1": "tab:blue", "m2": "tab:green", "m3": "tab:red", TIP: "0.35"}


def fail(msg):
    figlib.fail(NAME, msg)


def read_table(path):
    return figlib.read_marker_table(NAME, path)


def read_summary(path):
    return figlib.read_summary(NAME, path)


def tracks(rows, path):
    """{variant: {"steps": [...], marker: [row per step]}} in CSV order of the variants; fails if a
    variant lacks a required marker, has fewer than two steps or a marker misses a step."""
    out = {}
    for r in rows:
        out.setdefault(r["variant"], {}).setdefault(r["marker"], []).append(r)
    for variant, markers in out.items():
        missing = [m for m in MARKERS if m not in markers]
        if missing:
            fail(f"{path}: variant '{variant}' has no rows for marker(s) {', '.join(missing)}; "
                 f"expected {', '.join(MARKERS)}")
        steps = sorted(int(r["step"]) for r in markers[MARKERS[0]])
        if len(steps) < 2:
            fail(f"{path}: variant '{variant}' needs at least 2 steps, found {len(steps)}")
        for m, mr in markers.items():
            mr.sort(key=lambda r: r["step"])
            have = [int(r["step"]) for r in mr]
            if have != steps:
                lack = sorted(set(steps) - set(have)) or sorted(set(have) - set(steps))
                fail(f"{path}: variant '{variant}', marker '{m}': steps differ from those of "
                     f"{MARKERS[0]} (step(s) {', '.join(map(str, lack))})")
        markers["steps"] = steps
    return out


def variant_info(summary, path):
    """{label: variant dict} from summary.json; fails on a malformed 'variants' entry."""
    variants = summary.get("variants", [])
    if not isinstance(variants, list) or not all(isinstance(v, dict) for v in variants):
        fail(f"{path}: 'variants' must be a list of objects")
    out = {}
    for i, v in enumerate(variants):
        if not isinstance(v.get("robot_params", {}), dict):
            fail(f"{path}: variants[{i}].robot_params must be an object")
        out[v.get("label", f"variant {i}")] = v
    return out


def params_text(label, info):
    """'joint_weight 1 / link_weight 8': the robot_params of a variant as summary.json has them."""
    params = info.get(label, {}).get("robot_params", {})
    return " / ".join(f"{k} {v:g}" if isinstance(v, (int, float)) else f"{k} {v}"
                      for k, v in params.items())


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    csv_path = os.path.join(results, "markers.csv")
    rows = read_table(csv_path)
    summary_path = os.path.join(results, "summary.json")
    summary = read_summary(summary_path)
    data = tracks(rows, csv_path)
    info = variant_info(summary, summary_path)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    labels = list(data)
    n = len(labels)
    fig, axes = plt.subplots(1, n + 1, figsize=(5.0 * (n + 1), 5.6))
    shown = MARKERS + [TIP]

    # Same limits everywhere: the box around every plotted point, padded, made square-ish later
    # by the equal aspect.
    xs = [r["x"] for r in rows if r["marker"] in shown]
    zs = [r["z"] for r in rows if r["marker"] in shown]
    pad = 0.06 * max(max(xs) - min(xs), max(zs) - min(zs), 1.0)
    xlim = (min(xs) - pad, max(xs) + pad)
    zlim = (min(zs) - pad, max(zs) + pad)

    def not_converged(ax, mr):
        bad = [r for r in mr if r["converged"] < 0.5]
        if bad:
            ax.plot([r["x"] for r in bad], [r["z"] for r in bad], "x", color="k", ms=8, mew=1.6,
                    zorder=4)
        return bool(bad)

    any_bad = False
    for ax, label in zip(axes, labels):
        d = data[label]
        for m in shown:
            if m not in d:
                continue
            mr = d[m]
            ax.plot([r["x"] for r in mr], [r["z"] for r in mr], "--" if m == TIP else "o-",
                    color=COLORS[m], ms=3, lw=1.2 if m == TIP else 1.5, label=m)
            any_bad |= not_converged(ax, mr)
        ax.plot([d[m][0]["x"] for m in shown if m in d], [d[m][0]["z"] for m in shown if m in d],
                "ks", ms=5, zorder=3, label="rest")
        first, last = d[MARKERS[0]][0]["value"], d[MARKERS[0]][-1]["value"]
        params = params_text(label, info)
        v = info.get(label, {})
        solve = v.get("solve_s")
        iters = v.get("iterations")
        stats = []
        if isinstance(solve, (int, float)):
            stats.append(f"solve {solve:.2f} s")
        if isinstance(iters, (int, float)):
            stats.append(f"{iters:.0f} iterations")
        ax.set_title(f"{label}" + (f" ({params})" if params else "") +
                     f"\ns = {first:g} to {last:g}" + (f"; {', '.join(stats)}" if stats else ""),
                     fontsize=10)

    cax = axes[-1]
    # Thin grey lines join the positions of the same step in consecutive variants.
    for a, b in zip(labels, labels[1:]):
        by_step = {int(r["step"]): r for r in data[b][COMPARE]}
        for r in data[a][COMPARE]:
            q = by_step.get(int(r["step"]))
            if q is not None:
                cax.plot([r["x"], q["x"]], [r["z"], q["z"]], "-", color="0.7", lw=0.8, zorder=1)
    for i, label in enumerate(labels):
        mr = data[label][COMPARE]
        cax.plot([r["x"] for r in mr], [r["z"] for r in mr], "o-", color=f"C{i}", ms=3,
                 label=label, zorder=2)
        cax.plot([mr[-1]["x"]], [mr[-1]["z"]], "o", color=f"C{i}", ms=8, mfc="none", zorder=3)
        any_bad |= not_converged(cax, mr)
    cax.plot([data[labels[0]][COMPARE][0]["x"]], [data[labels[0]][COMPARE][0]["z"]], "ks", ms=5,
             zorder=3, label="rest")
    end = data[labels[0]][COMPARE][-1]["value"]
    cax.set_title(f"{COMPARE} of the variants overlaid\n(grey: same step; circled: s = {end:g})",
                  fontsize=10)

    for ax in axes:
        ax.set_xlim(*xlim)
        ax.set_ylim(*zlim)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("x (mm, long axis)")
        ax.set_ylabel("z (mm, up)")
        ax.grid(True, alpha=0.3)
        handles, names = ax.get_legend_handles_labels()
        if any_bad:
            handles.append(Line2D([], [], ls="none", marker="x", color="k", ms=8, mew=1.6))
            names.append("not converged")
        ax.legend(handles, names, loc="best", fontsize=8)

    robot = summary.get("robot", "")
    quick = " (quick run)" if summary.get("quick") else ""
    total = summary.get("total_solve_s")
    extra = f"; total solve {total:.2f} s" if isinstance(total, (int, float)) else ""
    nc = summary.get("non_converged_steps")
    extra += f"; {nc:.0f} step(s) not converged" if isinstance(nc, (int, float)) and nc else ""
    versus = " vs ".join(label + (f" ({p})" if (p := params_text(label, info)) else "")
                         for label in labels)
    fig.suptitle(f"Thesis Fig. 2.9: {robot + ', ' if robot else ''}cable shortened with "
                 f"{len(labels)} material distributions{quick}\n{versus}{extra}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
