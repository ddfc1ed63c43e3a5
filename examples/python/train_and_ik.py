#!/usr/bin/env python3
"""Learning in Python: a small dataset of three_chamber (FK and implicit Jacobians on a grid),
N_fk and N_J trained on it, and IK on the learned kinematics checked against the simulator.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/train_and_ik.py --out learn_demo
"""
import argparse
import os

import numpy as np

import softkin


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=3, help="robot resolution (rings, 3..16)")
    ap.add_argument("--grid", type=int, default=6, help="samples per actuator")
    ap.add_argument("--out", default="learn_demo", help="folder for the dataset and networks")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    csv = os.path.join(args.out, "three_chamber.csv")
    # Resumable: a second run finds the samples already there.
    softkin.dataset(csv, "three_chamber", res=args.res, grid=args.grid, jacobian="implicit",
                    quiet=True)
    nets = softkin.train(csv, os.path.join(args.out, "nets"), what="fk,jac", hidden=(20,),
                         hidden_jac=(20,), epochs=300, seed=1, quiet=True)

    sim = softkin.SimulatorKinematics(softkin.robot("three_chamber", res=args.res),
                                      points=["tip"])
    rng = np.random.default_rng(7)
    errors = []
    for _ in range(5):
        c_true = sim.lower + rng.random(3) * 0.6 * (sim.upper - sim.lower)
        target = sim.p(c_true)[0]
        r = softkin.ik.solve(nets, target, method="gauss-newton")
        reached = sim.p(r["c"])[0]  # what the simulator does with the learned answer
        errors.append(np.linalg.norm(reached - target))
        print(f"target {np.round(target, 1)} mm: network error {r['error_mm']:.2f} mm, "
              f"simulator error {errors[-1]:.2f} mm")
    print(f"mean simulator error of learned IK: {np.mean(errors):.2f} mm")


if __name__ == "__main__":
    main()
