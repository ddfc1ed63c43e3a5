#!/usr/bin/env python3
"""SoftKin against the pressure-driven CalculiX FEM at equal chamber volume (issue: is the physics
right?).

Usage: fidelity_fem.py RESULTS_DIR

Reads RESULTS_DIR/centrelines.csv, fidelity.csv and summary.json (written by
`softkin run experiments/configs/fidelity_fem.json`). Writes RESULTS_DIR/fidelity_fem.png, one row
per case:
  left:  centre lines (surface vertices averaged in slices along the long axis) of the FEM (solid)
         and of SoftKin at the same chamber volume, with its default parameters (dashed) and
         calibrated ones (dotted), one colour per fraction of the FEM's pressure ramp, in the
         plane of the long axis and the bending direction;
  right: tip error (% of the length) against the FEM cavity volume ratio, default and calibrated;
         the case the parameters were fitted on is marked, the others are hold-outs.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fidelity_fem"
LINE_COLS = ["case", "calibrated", "fraction", "model", "slice", "x", "y", "z"]
CMP_COLS = ["case", "calibrated", "fraction", "cavity_ratio", "tip_error_percent", "matched"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    lines = figlib.read_table(NAME, os.path.join(results, "centrelines.csv"), LINE_COLS)
    rows = figlib.read_table(NAME, os.path.join(results, "fidelity.csv"), CMP_COLS)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    cases = summary.get("cases", [])
    if not cases:
        figlib.fail(NAME, f"{results}/summary.json: expected a non-empty 'cases' list")
    calib = summary.get("calibration") or {}

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(cases)
    fig, axes = plt.subplots(n, 2, figsize=(13, 4.6 * n), squeeze=False)
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]
    styles = {0: "--", 1: ":"}
    for ci, case in enumerate(cases):
        mine = [r for r in lines if int(r["case"]) == ci]
        if not mine:
            figlib.fail(NAME, f"{results}/centrelines.csv: no rows for case {ci} ({case.get('case')})")
        fractions = sorted({r["fraction"] for r in mine})
        # The plane: the long axis (largest spread of the FEM line at the first fraction) and the
        # axis of largest deflection at the last one.
        first = [r for r in mine if r["fraction"] == fractions[0] and r["model"] == 0 and
                 r["calibrated"] == 0]
        last = [r for r in mine if r["fraction"] == fractions[-1] and r["model"] == 0 and
                r["calibrated"] == 0]
        keys = ["x", "y", "z"]
        spread = [max(r[k] for r in first) - min(r[k] for r in first) for k in keys]
        ax_long = spread.index(max(spread))
        others = [k for k in range(3) if k != ax_long]
        defl = [abs(last[-1][keys[k]] - last[0][keys[k]]) for k in others]
        ax_bend = others[defl.index(max(defl))]
        a = axes[ci][0]
        for fi, f in enumerate(fractions):
            col = colors[fi % len(colors)]
            for model, cal in [(0, 0), (1, 0), (1, 1)]:
                pts = sorted([r for r in mine if r["fraction"] == f and r["model"] == model and
                              r["calibrated"] == cal], key=lambda r: r["slice"])
                if not pts:
                    continue
                style = "-" if model == 0 else styles[cal]
                label = None
                if fi == 0:
                    label = "FEM" if model == 0 else ("SoftKin" if cal == 0 else
                                                      "SoftKin, calibrated")
                a.plot([p[keys[ax_long]] for p in pts], [p[keys[ax_bend]] for p in pts], style,
                       color=col, lw=1.8 if model == 0 else 1.4, label=label)
        a.set_aspect("equal", adjustable="datalim")
        a.set_xlabel(f"{keys[ax_long]} (mm)")
        a.set_ylabel(f"{keys[ax_bend]} (mm)")
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
        role = case.get("role", "")
        element = case.get("fem_element", summary.get("fem", {}).get("element"))
        a.set_title(f"{case.get('case')} ({case.get('tets')} tets, FEM {element}"
                    f"{', ' + role if role else ''}): "
                    f"centre lines at {', '.join(f'{100 * f:.0f}' for f in fractions)} % of the ramp",
                    fontsize=9)
        b = axes[ci][1]
        for cal in (0, 1):
            pts = sorted([r for r in rows if int(r["case"]) == ci and r["calibrated"] == cal],
                         key=lambda r: r["cavity_ratio"])
            if not pts:
                continue
            b.plot([p["cavity_ratio"] for p in pts], [p["tip_error_percent"] for p in pts],
                   "o" + styles[cal], label="calibrated" if cal else "default parameters")
        b.axhline(5.0, color="gray", lw=0.8, ls="-.", label="5 % of the length")
        b.set_xlabel("chamber volume ratio (FEM cavity = SoftKin)")
        b.set_ylabel("tip error (% of length)")
        stop = "" if case.get("fem_reached_end") else "; FEM stopped early"
        b.set_title(f"FEM to {case.get('fem_end_pressure_mpa', 0):.3g} MPa{stop}", fontsize=9)
        b.grid(True, alpha=0.3)
        b.legend(fontsize=8)
    fem = summary.get("fem", {})
    fit = ""
    if calib:
        fit = (f"; calibrated on {calib.get('fitted_on')}: chamber weight x "
               f"{calib.get('chamber_weight_scale', 0):.3g}, body R_omega "
               f"{calib.get('body_r_omega', 0):.3g}")
    quick = " (quick run)" if summary.get("quick") else ""
    elements = sorted({c.get("fem_element", fem.get("element")) for c in cases})
    fig.suptitle(f"SoftKin vs pressure FEM ({' / '.join(elements)}, {fem.get('law')}, E = "
                 f"{fem.get('young_mpa')} MPa, nu = {fem.get('poisson')}) at equal chamber volume"
                 f"{fit}{quick}", fontsize=10)
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
