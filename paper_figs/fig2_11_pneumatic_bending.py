#!/usr/bin/env python3
"""Thesis Fig. 2.11 / Table 2.2: tip trajectory of the pneumatic finger while it bends.

Usage: fig2_11_pneumatic_bending.py RESULTS_DIR

Reads RESULTS_DIR/trajectory.csv (written by `softkin run experiments/configs/fig2_11_pneumatic_bending.json`)
and, if present, RESULTS_DIR/summary.json. Writes RESULTS_DIR/fig2_11_pneumatic_bending.png:
  left:  tip path in the x-z plane (mm, equal aspect), coloured by actuation, with markers where
         the bend angle first crosses 90, 180 and 240 degrees;
  right: bend angle against the chamber volume ratio the solve achieved.
If RESULTS_DIR/fem_trajectory.csv is there (config key fem_laws), the pressure-driven FEM's ramps
(FEM 1 linear, FEM 2 neo-Hookean; solver/baselines/calculix_pressure.hpp) are drawn beside
SoftKin's: tip paths on the left, bend angle against the FEM's cavity volume ratio on the right,
each ending where the FEM stopped (summary.json says why).
Exit status 2 with a message on stderr if the CSV is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig2_11_pneumatic_bending"
COLUMNS = ["step", "actuation", "bend_deg", "tip_x", "tip_y", "tip_z", "iterations", "time_s",
           "cumulative_s", "energy", "volume_ratio", "residual_ratio", "converged",
           "inverted_elements"]
FEM_COLUMNS = ["law", "increment", "load", "pressure_mpa", "cavity_ratio", "bend_deg", "tip_x",
               "tip_y", "tip_z", "wall_s"]
FEM_STYLE = {"linear": ("FEM 1 (linear, pressure)", "tab:purple", "--"),
             "neo-hooke": ("FEM 2 (neo-Hookean, pressure)", "tab:brown", "-.")}
MILESTONES = (90.0, 180.0, 240.0)


def fail(msg):
    figlib.fail(NAME, msg)


def read_table(path, columns):
    return figlib.read_table(NAME, path, columns, min_rows=2)


def read_summary(path):
    return figlib.read_summary(NAME, path)


def crossings(rows):
    """For each milestone angle: (x, z, actuation, cumulative_s) at the first crossing, by linear
    interpolation between the two bracketing steps, or None if never reached."""
    out = {}
    for m in MILESTONES:
        out[m] = None
        for a, b in zip(rows, rows[1:]):
            if a["bend_deg"] < m <= b["bend_deg"]:
                t = (m - a["bend_deg"]) / (b["bend_deg"] - a["bend_deg"])
                out[m] = tuple(a[k] + t * (b[k] - a[k])
                               for k in ("tip_x", "tip_z", "volume_ratio", "cumulative_s"))
                break
        if out[m] is None and rows[0]["bend_deg"] >= m:
            r = rows[0]
            out[m] = (r["tip_x"], r["tip_z"], r["volume_ratio"], r["cumulative_s"])
    return out


def read_fem(results):
    """FEM rows by law, in file order; {} if the run had no FEM."""
    path = os.path.join(results, "fem_trajectory.csv")
    if not os.path.isfile(path):
        return {}
    numeric = [c for c in FEM_COLUMNS if c != "law"]
    rows = figlib.read_table(NAME, path, FEM_COLUMNS, numeric=numeric, min_rows=0)
    out = {}
    for r in rows:
        out.setdefault(r["law"], []).append(r)
    return out


def fmt_s(v):
    return "not reached" if v is None else f"{v:.2f} s"


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    rows = read_table(os.path.join(results, "trajectory.csv"), COLUMNS)
    summary = read_summary(os.path.join(results, "summary.json"))
    fem = read_fem(results)
    fem_info = summary.get("fem", {}) if isinstance(summary, dict) else {}

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    x = [r["tip_x"] for r in rows]
    z = [r["tip_z"] for r in rows]
    act = [r["actuation"] for r in rows]
    vol = [r["volume_ratio"] for r in rows]
    bend = [r["bend_deg"] for r in rows]
    bad = [i for i, r in enumerate(rows) if r["converged"] < 0.5]
    cross = crossings(rows)
    colors = {90.0: "tab:green", 180.0: "tab:orange", 240.0: "tab:red"}

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12.5, 5.4),
                                   gridspec_kw={"width_ratios": [1.25, 1.0]})
    norm = Normalize(vmin=min(act), vmax=max(act) if max(act) > min(act) else min(act) + 1)

    # Left: tip path in x-z, coloured by actuation.
    segs = [[(x[i], z[i]), (x[i + 1], z[i + 1])] for i in range(len(rows) - 1)]
    lc = LineCollection(segs, cmap="viridis", norm=norm, linewidths=2.0)
    lc.set_array([0.5 * (act[i] + act[i + 1]) for i in range(len(rows) - 1)])
    ax0.add_collection(lc)
    sc = ax0.scatter(x, z, c=act, cmap="viridis", norm=norm, s=14, zorder=3)
    ax0.plot(x[0], z[0], "ks", ms=7, zorder=4, label="rest")
    if bad:
        ax0.scatter([x[i] for i in bad], [z[i] for i in bad], s=60, facecolors="none",
                    edgecolors="red", zorder=5,
                    label="not converged (inverted elements)"
                    if any(rows[i]["inverted_elements"] > 0 for i in bad) else "not converged")
    for m, c in cross.items():
        if c is not None:
            ax0.plot(c[0], c[1], marker="*", ms=15, ls="none", color=colors[m], mec="k",
                     zorder=6, label=f"bend crosses {m:.0f}\N{DEGREE SIGN}")
    for law, frows in fem.items():
        label, color, ls = FEM_STYLE.get(law, (f"FEM ({law})", "0.4", ":"))
        ax0.plot([r["tip_x"] for r in frows], [r["tip_z"] for r in frows], ls=ls, color=color,
                 lw=2.0, marker="o", ms=2.5, zorder=4, label=label)
    ax0.set_aspect("equal", adjustable="datalim")
    ax0.autoscale_view()
    ax0.set_xlabel("tip x (mm)")
    ax0.set_ylabel("tip z (mm)")
    ax0.set_title("Tip trajectory (x-z plane)")
    ax0.grid(True, alpha=0.3)
    ax0.legend(loc="best", fontsize=8)
    cb = fig.colorbar(sc, ax=ax0, shrink=0.85)
    cb.set_label("actuation (chamber volume ratio)")

    # Right: bend angle against the chamber volume ratio reached.
    solver = summary.get("solver", "local-global")
    ax1.plot(vol, bend, "-o", ms=3, color="tab:blue", label=f"SoftKin ({solver})")
    if bad:
        ax1.scatter([vol[i] for i in bad], [bend[i] for i in bad], s=60, facecolors="none",
                    edgecolors="red", zorder=5)
    for law, frows in fem.items():
        label, color, ls = FEM_STYLE.get(law, (f"FEM ({law})", "0.4", ":"))
        info = fem_info.get(law, {})
        end = f", to {info['end_pressure_mpa']:.3g} MPa" if "end_pressure_mpa" in info else ""
        ax1.plot([r["cavity_ratio"] for r in frows], [r["bend_deg"] for r in frows], ls=ls,
                 color=color, lw=2.0, marker="o", ms=2.5, label=label + end)
        if info.get("status") == "stopped":
            last = frows[-1]
            ax1.annotate("stopped", (last["cavity_ratio"], last["bend_deg"]), fontsize=7,
                         color=color, xytext=(4, -10), textcoords="offset points")
    for m in MILESTONES:
        ax1.axhline(m, color=colors[m], ls="--", lw=0.9)
        c = cross[m]
        if c is not None:
            ax1.plot(c[2], m, marker="*", ms=13, color=colors[m], mec="k", zorder=5)
    ax1.set_xlabel("chamber volume ratio reached (FEM: cavity volume ratio)")
    ax1.set_ylabel("bend angle (deg)")
    ax1.set_title("Bend angle vs chamber volume")
    ax1.grid(True, alpha=0.3)

    # Timing box: measured times (from the summary, else from the CSV) next to Table 2.2.
    thesis = summary.get("thesis_table_2_2", {}) if isinstance(summary, dict) else {}
    lines = ["solve time to bend (this run | thesis Table 2.2)"]
    for m in MILESTONES:
        key = f"t{m:.0f}_s"
        if key in summary:
            measured = summary[key]
        else:
            measured = cross[m][3] if cross[m] is not None else None
        ref = thesis.get(key)
        ref_s = f"{ref:.1f} s" if isinstance(ref, (int, float)) else "-"
        lines.append(f"{m:>3.0f}\N{DEGREE SIGN}: {fmt_s(measured)} | {ref_s}")
    if "n_tets" in summary:
        lines.append(f"{summary['n_tets']} tets")
    for law in fem:
        info = fem_info.get(law, {})
        if "time_s" in info:
            lines.append(f"{FEM_STYLE.get(law, (law,))[0].split(' (')[0]} ({fem_info.get('element', '')}): "
                         f"{info['max_bend_deg']:.0f}\N{DEGREE SIGN} in {info['time_s']:.0f} s, "
                         f"{info.get('status', '')}")
    ax1.text(0.03, 0.97, "\n".join(lines), transform=ax1.transAxes, va="top", ha="left",
             fontsize=8, family="monospace",
             bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
    ax1.legend(loc="lower right", fontsize=8)

    robot = summary.get("robot", "pneumatic_finger")
    quick = " (quick run)" if summary.get("quick") else ""
    good = [b for i, b in enumerate(bend) if i not in bad]
    max_bend = max(good) if good else 0.0
    flagged = f", {len(bad)} step(s) not converged" if bad else ""
    fig.suptitle(f"Thesis Fig. 2.11 / Table 2.2: {robot} under pneumatic actuation{quick}; "
                 f"max bend {max_bend:.0f}\N{DEGREE SIGN} (converged steps){flagged}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
