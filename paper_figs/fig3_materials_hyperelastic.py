#!/usr/bin/env python3
"""Hyperelastic body elements (thesis Sec. 3.3.1, Eq. 3.6-3.7): the fitted R_omega(strain) and the
uniaxial response against the Mooney-Rivlin curve.

Usage: fig3_materials_hyperelastic.py RESULTS_DIR

Reads RESULTS_DIR/curve.csv and response.csv (written by
`softkin run experiments/configs/fig3_materials_hyperelastic.json`) and summary.json. Writes
RESULTS_DIR/fig3_materials_hyperelastic.png:
  left:  R_omega against the equivalent Hencky strain, one curve per material;
  right: normalised nominal stress against stretch: analytic Mooney-Rivlin (lines), the law's
         homogeneous state (dashed), the simulated bar with the law (dots) and with a constant
         R_omega (crosses).
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import os
import sys

import figlib

NAME = "fig3_materials_hyperelastic"
CURVE = ["material", "strain", "r_omega"]
RESP = ["material", "end_stretch", "mid_stretch", "mooney_rivlin", "law_homogeneous", "sim_hyperelastic",
        "mid_stretch_constant", "sim_constant_r_omega", "lateral_hyperelastic",
        "lateral_constant_r_omega", "iterations"]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    curve = figlib.read_table(NAME, os.path.join(results, "curve.csv"), CURVE, numeric=CURVE[1:])
    resp = figlib.read_table(NAME, os.path.join(results, "response.csv"), RESP, numeric=RESP[1:])
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    materials = []
    for r in curve:
        if r["material"] not in materials:
            materials.append(r["material"])
    colors = ["tab:blue", "tab:red", "tab:green", "tab:purple"]
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12.5, 4.8))
    for i, m in enumerate(materials):
        c = colors[i % len(colors)]
        pts = [r for r in curve if r["material"] == m]
        ax0.plot([r["strain"] for r in pts], [r["r_omega"] for r in pts], "-", color=c, label=m)
        rows = sorted([r for r in resp if r["material"] == m], key=lambda r: r["mid_stretch"])
        if not rows:
            continue
        lam = [r["mid_stretch"] for r in rows]
        ax1.plot(lam, [r["mooney_rivlin"] for r in rows], "-", color=c, lw=2,
                 label=f"{m}: Mooney-Rivlin")
        ax1.plot(lam, [r["law_homogeneous"] for r in rows], "--", color=c, lw=1,
                 label=f"{m}: law, homogeneous")
        ax1.plot(lam, [r["sim_hyperelastic"] for r in rows], "o", color=c, ms=5,
                 label=f"{m}: simulated bar")
        ax1.plot([r["mid_stretch_constant"] for r in rows], [r["sim_constant_r_omega"] for r in rows],
                 "x", color=c, ms=6, label=f"{m}: constant R_omega (Ch. 2)")
    ax0.set_xlabel("equivalent Hencky strain")
    ax0.set_ylabel(r"$R_\omega(\varepsilon)$")
    ax0.set_title("Fitted shape parameter")
    ax0.grid(True, alpha=0.3)
    ax0.legend(fontsize=8)
    ax1.set_xlabel("stretch of the middle third")
    ax1.set_ylabel("nominal stress / small-strain modulus")
    ax1.set_title("Uniaxial tension")
    ax1.grid(True, alpha=0.3)
    ax1.legend(fontsize=7)
    quick = " (quick run)" if summary.get("quick") else ""
    fig.suptitle(f"Hyperelastic body elements (Eq. 3.6-3.7) fitted to Mooney-Rivlin{quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
