#!/usr/bin/env python3
"""Bends the embedded pneumatic finger over its range and plots the tip's path (x, z) with
matplotlib, with the implicit Jacobian's tangent at the middle of the range.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/bend_finger.py --out tip.png
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import softkin


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=6, help="robot resolution (cells across, 5..40)")
    ap.add_argument("--steps", type=int, default=8, help="actuation samples over [1, max]")
    ap.add_argument("--out", default="finger_tip.png", help="PNG figure to write")
    args = ap.parse_args()

    scene = softkin.robot("pneumatic_finger", res=args.res)
    solver = softkin.FkSolver(scene, solver="lg-aa")
    alphas = np.linspace(scene.rest[0], scene.upper[0], args.steps)
    tips, X = [], None
    for a in alphas:  # each solve starts from the previous state, as a sweep does
        r = solver.solve(a, warm_start=X)
        if not r.converged:
            raise SystemExit(f"alpha = {a:.2f}: {r.status}: {r.message}")
        X = r.positions
        tips.append(r.markers["tip"])
        print(f"alpha {a:5.2f}: tip {np.round(r.markers['tip'], 2)} mm, {r.iterations} iterations")
    tips = np.array(tips)
    mid = alphas[len(alphas) // 2]
    jac = solver.jacobian(mid)
    p, d = jac["result"].markers["tip"], jac["markers"]["tip"][:, 0]

    fig, ax = plt.subplots(figsize=(4.5, 4))
    ax.plot(tips[:, 0], tips[:, 2], "o-", label="tip, FK (lg-aa)")
    ax.annotate("", xy=(p[0] + d[0], p[2] + d[2]), xytext=(p[0], p[2]),
                arrowprops=dict(arrowstyle="->", color="C3"))
    ax.plot([], [], color="C3", label=f"d tip / d alpha at {mid:.2f}")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_aspect("equal")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
