#!/usr/bin/env python3
"""Per-step computing cost of the collision-aware simulator (thesis Table 3.1).

Usage: table3_1_costs.py RESULTS_DIR

Reads RESULTS_DIR/summary.json (written by `softkin run experiments/configs/table3_1_costs.json`). Writes
RESULTS_DIR/table3_1_costs.png: per robot, stacked bars of mesh generation, collision check,
collision response and iterative solver per step, ours beside the thesis's, labelled with tet
counts; above our bars, the contacts the exact check left (and how many of them lie in tangles) and
the body tets left inverted. Exit status 2 with a message on stderr if the summary is missing
or malformed.
"""
import os
import sys
import textwrap

import figlib

NAME = "table3_1_costs"
PARTS = [("mesh_gen_s", "mesh generation"), ("col_check_s", "collision check"),
         ("col_resp_s", "collision response"), ("solver_s", "iterative solver")]


def main(argv):
    results = figlib.results_dir(NAME, argv, __doc__)
    summary = figlib.read_summary(NAME, os.path.join(results, "summary.json"))
    rows = summary.get("rows")
    if not isinstance(rows, list) or not rows:
        figlib.fail(NAME, f"{results}/summary.json: expected a non-empty 'rows' list (run the experiment first)")
    for i, r in enumerate(rows):
        for k, _ in PARTS:
            if not isinstance(r.get(k), (int, float)):
                figlib.fail(NAME, f"{results}/summary.json: rows[{i}].{k}: expected a number")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    bars = sum(1 + isinstance(r.get("thesis"), dict) for r in rows)
    fig, ax = plt.subplots(figsize=(max(8.5, 1.25 * bars + 1.5), 5.2))
    colors = ["tab:gray", "tab:blue", "tab:orange", "tab:green"]
    labels, x = [], 0
    for r in rows:
        for who, src in (("ours", r), ("thesis", r.get("thesis"))):
            if not isinstance(src, dict):
                continue
            bottom = 0.0
            for (k, name), c in zip(PARTS, colors):
                v = float(src.get(k, 0.0))
                ax.bar(x, v, bottom=bottom, color=c, label=name if x == 0 else None,
                       hatch="//" if who == "thesis" else None, edgecolor="k", lw=0.5)
                bottom += v
            fc = r.get("final_check") if isinstance(r.get("final_check"), dict) else {}
            notes = []
            if who == "ours" and r.get("collision_free") is False:
                notes.append(f"contacts left\n({fc.get('self_contacts', '?')} self, "
                             f"{fc.get('obstacle_contacts', '?')} obstacle;\n"
                             f"{fc.get('tangled_contacts', '?')} in tangles)")
            if who == "ours" and fc.get("inverted_body_elements"):
                notes.append(f"{fc['inverted_body_elements']} inverted\nbody tets")
            if notes:
                ax.annotate("\n".join(notes), (x, bottom), xytext=(0, 3), textcoords="offset points",
                            ha="center", fontsize=7, color="tab:red")
            tets = src.get("tets", r.get("tets"))
            remesh = r.get("remesh") if who == "ours" else None
            if isinstance(remesh, dict) and "tets_final" in remesh:
                tets = f"{tets}->{remesh['tets_final']}"  # remeshed during the run
            name = "\n".join(textwrap.wrap(str(r.get("label", r["robot"])), 20, break_long_words=False))
            labels.append(f"{name}\n{who}\n{tets} tets")
            x += 1
    ax.set_xticks(range(len(labels)))
    ax.set_xticklabels(labels, fontsize=7)
    ax.set_ylabel("seconds per step")
    ax.set_yscale("symlog", linthresh=0.01)
    ax.set_ylim(top=4.0 * max(ax.get_ylim()[1], 0.01))  # room for the contact notes
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    quick = " (quick run)" if summary.get("quick") else ""
    ax.set_title(f"Computing cost per step (Table 3.1){quick}")
    figlib.save_figure(fig, results, NAME)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
