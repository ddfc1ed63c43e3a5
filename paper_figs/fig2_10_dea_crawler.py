#!/usr/bin/env python3
"""Thesis Fig. 2.10: the DEA crawler between its released rest state and its flat state.

Usage: fig2_10_dea_crawler.py RESULTS_DIR

Reads RESULTS_DIR/markers.csv (written by `softkin run experiments/configs/fig2_10_dea_crawler.json`,
one row per variant x step x marker; only the first variant is plotted) and, if present,
RESULTS_DIR/summary.json. Writes RESULTS_DIR/fig2_10_dea_crawler.png:
  left:  side view (x-z, mm, equal aspect) of the body at every step, the polyline
         rear_foot -> apex -> front_foot plus the tip, coloured by the membrane stretch lambda;
  right: leg spacing (the distances of summary.json, e.g. rear_foot-front_foot; without them the
         rear_foot-front_foot distance from the CSV) and apex height z against lambda, on twin
         y axes.
The first step (lambda_init) is the released rest state, lambda = 1 the flat pre-stretched one.
Steps that did not converge are marked with a black x.
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import math
import os
import sys

import figlib

NAME = "fig2_10_dea_crawler"
BODY = ["rear_foot", "apex", "front_foot"]  # required, joined in this order
TIP = "tip"                                 # optional


def fail(msg):
    figlib.fail(NAME, msg)


def read_table(path):
    return figlib.read_marker_table(NAME, path)


def read_summary(path):
    return figlib.read_summary(NAME, path)


def steps_of(rows, path):
    """The first variant's steps in order, each {"step", "value", "converged", marker: row};
    fails if a step lacks a body marker or there are fewer than two steps."""
    variant = rows[0]["variant"]
    by_step = {}
    for r in rows:
        if r["variant"] == variant:
            s = by_step.setdefault(int(r["step"]), {"step": int(r["step"]), "value": r["value"],
                                                    "converged": r["converged"]})
            s[r["marker"]] = r
            s["converged"] = min(s["converged"], r["converged"])
    steps = [by_step[k] for k in sorted(by_step)]
    if len(steps) < 2:
        fail(f"{path}: variant '{variant}' needs at least 2 steps, found {len(steps)}")
    for s in steps:
        missing = [m for m in BODY if m not in s]
        if missing:
            fail(f"{path}: variant '{variant}', step {s['step']} has no rows for marker(s) "
                 f"{', '.join(missing)}; expected {', '.join(BODY)}")
    return variant, steps


def distances(summary, path, variant, steps):
    """[(name, [distance per step])] from summary.json's variant `variant` (else its first
    variant), or, without any, the rear_foot-front_foot distance computed from the CSV."""
    variants = summary.get("variants", [])
    if not isinstance(variants, list) or not all(isinstance(v, dict) for v in variants):
        fail(f"{path}: 'variants' must be a list of objects")
    v = next((v for v in variants if v.get("label") == variant), variants[0] if variants else {})
    names = v.get("distance_names", [])
    dist = v.get("distances", [])
    if not isinstance(names, list) or not isinstance(dist, list):
        fail(f"{path}: distance_names and distances must be lists")
    if names:
        if len(dist) != len(steps):
            fail(f"{path}: {len(dist)} entries in distances, expected one per step "
                 f"({len(steps)}, as in markers.csv)")
        for i, d in enumerate(dist):
            if not isinstance(d, list) or len(d) != len(names) or \
                    not all(isinstance(x, (int, float)) for x in d):
                fail(f"{path}: distances[{i}] must be a list of {len(names)} number(s), one per "
                     f"name in distance_names")
        return [(str(n), [d[j] for d in dist]) for j, n in enumerate(names)]
    a, b = BODY[0], BODY[-1]
    return [(f"{a}-{b} (from markers.csv)",
             [math.dist([s[a][k] for k in "xyz"], [s[b][k] for k in "xyz"]) for s in steps])]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    csv_path = os.path.join(results, "markers.csv")
    rows = read_table(csv_path)
    summary_path = os.path.join(results, "summary.json")
    summary = read_summary(summary_path)
    variant, steps = steps_of(rows, csv_path)
    dists = distances(summary, summary_path, variant, steps)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize
    from matplotlib.lines import Line2D

    lam = [s["value"] for s in steps]
    norm = Normalize(vmin=min(lam), vmax=max(lam) if max(lam) > min(lam) else min(lam) + 1)
    cmap = plt.get_cmap("viridis")
    bad = [s for s in steps if s["converged"] < 0.5]

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(14, 4.8),
                                   gridspec_kw={"width_ratios": [1.45, 1.0]})

    # Left: side view of the body at every step.
    ax0.axhline(0.0, color="0.5", lw=0.8, zorder=0)
    for s in steps:
        c = cmap(norm(s["value"]))
        ax0.plot([s[m]["x"] for m in BODY], [s[m]["z"] for m in BODY], "-o", color=c, ms=3.5,
                 lw=1.6)
        if TIP in s:
            ax0.plot([s[TIP]["x"]], [s[TIP]["z"]], "^", color=c, ms=6, mec="k", mew=0.5)
    for s in bad:
        ms = BODY + ([TIP] if TIP in s else [])
        ax0.plot([s[m]["x"] for m in ms], [s[m]["z"] for m in ms], "x", color="k", ms=8,
                 mew=1.6, zorder=4)
    for m, dz in (("rear_foot", -1.2), ("apex", 0.8), ("front_foot", -1.2)):
        r = steps[0][m]
        ax0.annotate(m, (r["x"], r["z"]), textcoords="offset points", xytext=(0, 10 * dz),
                     ha="center", va="center", fontsize=8)
    # The ground under the feet, shaded without widening the data limits (so after the data).
    lim = ax0.dataLim.frozen()
    ax0.axhspan(-1e4, 0.0, color="0.93", zorder=0)
    ax0.dataLim.set_points(lim.get_points())
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax0, label=r"membrane stretch $\lambda$", fraction=0.05, pad=0.02)
    ax0.set_aspect("equal", adjustable="datalim")
    ax0.set_xlabel("x (mm)")
    ax0.set_ylabel("z (mm, up)")
    ax0.set_title("Side view: rear_foot - apex - front_foot per step")
    ax0.grid(True, alpha=0.3)
    handles = [Line2D([], [], color="0.3", marker="o", ms=3.5, label="body (feet and apex)")]
    if any(TIP in s for s in steps):
        handles.append(Line2D([], [], ls="none", marker="^", color="0.5", mec="k", mew=0.5,
                              label=TIP))
    if bad:
        handles.append(Line2D([], [], ls="none", marker="x", color="k", ms=8, mew=1.6,
                              label="not converged"))
    ax0.legend(handles=handles, loc="upper right", fontsize=8)

    # Right: leg spacing and apex height against lambda.
    for i, (name, d) in enumerate(dists):
        ax1.plot(lam, d, "-o", color="tab:blue" if i == 0 else f"C{i + 2}", ms=4,
                 label=f"leg spacing {name}")
    ax1.set_xlabel(r"membrane stretch $\lambda$")
    ax1.set_ylabel("leg spacing (mm)", color="tab:blue")
    ax1.tick_params(axis="y", labelcolor="tab:blue")
    ax1.grid(True, alpha=0.3)
    ax2 = ax1.twinx()
    apex = [s["apex"]["z"] for s in steps]
    ax2.plot(lam, apex, "--s", color="tab:orange", ms=4, label="apex height z")
    ax2.set_ylabel("apex height z (mm)", color="tab:orange")
    ax2.tick_params(axis="y", labelcolor="tab:orange")
    for s, i in ((s, steps.index(s)) for s in bad):
        for name, d in dists:
            ax1.plot(s["value"], d[i], "x", color="k", ms=8, mew=1.6)
        ax2.plot(s["value"], apex[i], "x", color="k", ms=8, mew=1.6)
    h1, l1 = ax1.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax1.legend(h1 + h2, l1 + l2, loc="upper center", fontsize=8)
    ax1.set_title(r"Leg spacing and body height against $\lambda$")

    robot = summary.get("robot", "") or "DEA crawler"
    quick = " (quick run)" if summary.get("quick") else ""
    total = summary.get("total_solve_s")
    extra = f"; total solve {total:.2f} s" if isinstance(total, (int, float)) else ""
    first, last = steps[0]["value"], steps[-1]["value"]
    fig.suptitle(f"Thesis Fig. 2.10: {robot}{quick}{extra}\n"
                 rf"$\lambda$ = {first:g} ($\lambda_{{init}}$): released rest state;  "
                 rf"$\lambda$ = {last:g}: flat pre-stretched state")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
