#!/usr/bin/env python3
"""three_chamber's tip follows a three-petal path with IK (Gauss-Newton on the implicit
Jacobian), and the reached points are plotted over the path with matplotlib.

The path is one the robot can reach: the tip positions of a three-lobed actuation loop, each
chamber inflating in turn (the thesis's flower, Fig. 4.5, mapped to this robot, is the
fig4_5_flower experiment: softkin run experiments/configs/fig4_5_flower.json).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/follow_path.py --out path.png
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import softkin


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=4, help="robot resolution (rings, 3..16)")
    ap.add_argument("--waypoints", type=int, default=24, help="points along the path")
    ap.add_argument("--out", default="follow_path.png", help="PNG figure to write")
    args = ap.parse_args()

    scene = softkin.robot("three_chamber", res=args.res)
    kin = softkin.SimulatorKinematics(scene, jacobian="implicit", points=["tip"])
    t = np.linspace(0, 2 * np.pi, args.waypoints, endpoint=False)
    petal = lambda phase: 1.0 + 0.5 * np.clip(np.cos(t - phase), 0, None) ** 2
    loop = np.stack([petal(0.0), petal(2 * np.pi / 3), petal(4 * np.pi / 3)], axis=1)
    path = np.array([kin.p(c)[0] for c in loop])
    kin.reset()

    result = softkin.ik.follow(kin, path, method="gauss-newton", samples_per_axis=3)
    print(f"{result['num_converged']} of {len(path)} waypoints within 0.2 mm; mean error "
          f"{result['mean_error_mm']:.3f} mm, max {result['max_error_mm']:.3f} mm, "
          f"{result['time_s']:.1f} s")

    # The path seen along the robot's long axis (y): x and z.
    fig, ax = plt.subplots(figsize=(4.5, 4.5))
    closed = np.vstack([path, path[:1]])
    ax.plot(closed[:, 0], closed[:, 2], "-", color="0.6", label="path")
    ax.plot(result["reached"][:, 0], result["reached"][:, 2], "o", ms=4, label="IK (reached)")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_aspect("equal")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")
    if result["num_converged"] != len(path):
        raise SystemExit("some waypoints were not reached")


if __name__ == "__main__":
    main()
