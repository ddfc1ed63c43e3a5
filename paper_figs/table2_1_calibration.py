#!/usr/bin/env python3
"""Thesis Table 2.1 / Fig. 2.6: calibration of the shape parameter R_omega.

Usage: table2_1_calibration.py RESULTS_DIR

Reads RESULTS_DIR/curve.csv, calibration.csv and twist.csv (written by
`softkin run experiments/configs/table2_1_calibration.json`) and summary.json. Writes
RESULTS_DIR/table2_1_calibration.png:
  left:   the calibration curve, simulated R_m against R_omega^A / R_omega^B, with the calibrated
          points and the thesis's Table 2.1 pairs;
  middle: the calibrated ratio against the number of tets (mesh sensitivity), thesis values dotted;
  right:  the twisting test with the calibrated parameters: each material's twist.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "table2_1_calibration"
CURVE = ["res", "r_omega_ratio", "r_omega_b", "rm", "dl1_mm", "iterations", "time_s"]
CAL = ["rm", "res", "tets", "r_omega_ratio", "r_omega_a", "r_omega_b", "achieved_rm", "evaluations",
       "thesis_ratio"]
TWIST = ["rm", "r_omega_ratio", "twist_deg", "angle_a_deg", "angle_b_deg", "a_mid_deg", "b_mid_deg",
         "twist_ratio_b_over_a", "shear_ratio"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    curve = figlib.read_table(NAME, os.path.join(results, "curve.csv"), CURVE)
    cal = figlib.read_table(NAME, os.path.join(results, "calibration.csv"), CAL,
                            numeric=[c for c in CAL if c != "thesis_ratio"])
    twist = figlib.read_table(NAME, os.path.join(results, "twist.csv"), TWIST)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def thesis(r):
        try:
            return float(r["thesis_ratio"])
        except (TypeError, ValueError):
            return float("nan")

    fig, (ax0, ax1, ax2) = plt.subplots(1, 3, figsize=(15.5, 4.8))
    res0 = summary.get("res")
    rows = summary.get("rows", [])

    # Left: calibration curve.
    curve.sort(key=lambda r: r["r_omega_ratio"])
    ax0.plot([r["r_omega_ratio"] for r in curve], [r["rm"] for r in curve], "-o", color="tab:blue",
             label=f"simulated elongation test (res {res0})")
    for i, row in enumerate(rows):
        ax0.plot(row["r_omega_ratio"], row["rm"], "*", ms=14, color="tab:red",
                 label="calibrated (ours)" if i == 0 else None)
        if row.get("thesis_ratio") is not None:
            ax0.plot(row["thesis_ratio"], row["rm"], "s", ms=9, mfc="none", mec="black",
                     label="thesis Table 2.1" if i == 0 else None)
    ax0.set_xscale("log")
    ax0.set_xlabel(r"$R_\omega^A / R_\omega^B$")
    ax0.set_ylabel(r"elasticity ratio $R_m$ (Eq. 2.9)")
    ax0.set_title("Calibration curve")
    ax0.grid(True, which="both", alpha=0.3)
    ax0.legend(fontsize=8)

    # Middle: mesh sensitivity.
    colors = ["tab:red", "tab:green", "tab:purple", "tab:orange"]
    for i, rm in enumerate(sorted({r["rm"] for r in cal})):
        pts = sorted([r for r in cal if r["rm"] == rm], key=lambda r: r["tets"])
        seen, uniq = set(), []
        for r in pts:  # the default resolution appears twice (headline and sweep)
            if r["res"] not in seen:
                seen.add(r["res"])
                uniq.append(r)
        c = colors[i % len(colors)]
        ax1.plot([r["tets"] for r in uniq], [r["r_omega_ratio"] for r in uniq], "-o", color=c,
                 label=f"$R_m$ = {rm:g}")
        th = thesis(pts[0])
        if th == th:
            ax1.axhline(th, color=c, ls=":", lw=1.0, label=f"thesis {th:g}")
    ax1.set_xscale("log")
    ax1.set_xlabel("tetrahedra")
    ax1.set_ylabel(r"calibrated $R_\omega^A / R_\omega^B$")
    ax1.set_title("Sensitivity to the mesh")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)

    # Right: twisting test.
    labels = [f"$R_m$ = {r['rm']:g}" for r in twist]
    x = range(len(twist))
    ax2.bar([i - 0.2 for i in x], [r["angle_a_deg"] for r in twist], 0.4, label="material A (fixed end)",
            color="tab:blue")
    ax2.bar([i + 0.2 for i in x], [r["angle_b_deg"] for r in twist], 0.4, label="material B (free end)",
            color="tab:orange")
    for i, r in enumerate(twist):
        ax2.text(i - 0.2, r["angle_a_deg"] + 2, f"twist per mm\nB/A = {r['shear_ratio']:.2f}",
                 ha="center", va="bottom", fontsize=8)
    ax2.set_xticks(list(x))
    ax2.set_xticklabels(labels)
    ax2.set_ylabel("twist of the material (degrees)")
    ax2.set_title(f"Twisting test, end turned {twist[0]['twist_deg']:g} deg")
    ax2.legend(fontsize=8, loc="upper left")
    ax2.set_ylim(0, 1.15 * max(max(r["angle_a_deg"], r["angle_b_deg"]) for r in twist))
    ax2.grid(True, axis="y", alpha=0.3)

    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Thesis Table 2.1 / Fig. 2.6: calibrating R_omega on bimaterial_bar{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
