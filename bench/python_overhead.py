#!/usr/bin/env python3
"""Timing of the Python package's overheads (issue #36's targets), printed as JSON:

- solve: one FkSolver.solve on the default pneumatic_finger (alpha = 2, from rest) from Python,
  against the same solve's own C++ time (FkResult.time_s, measured inside FkSolver::Solve). The
  overhead is what the binding adds: argument checks, the GIL, copying positions out.
- learned: p(c) and J(c) of learned kinematics (N_fk and N_J trained here on a small
  three_chamber dataset, or --nets DIR), per call from Python, over many calls.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [--repeats 3]
"""
import argparse
import json
import os
import tempfile
import time

import numpy as np

import softkin


def time_solve(repeats):
    scene = softkin.robot("pneumatic_finger")  # default resolution: 46,656 tets
    solver = softkin.FkSolver(scene)
    rows = []
    for _ in range(repeats):
        t = time.perf_counter()
        r = solver.solve(2.0)
        wall = time.perf_counter() - t
        rows.append({"wall_s": wall, "cpp_s": r.time_s, "overhead_s": wall - r.time_s,
                     "overhead_percent": 100 * (wall - r.time_s) / r.time_s,
                     "iterations": r.iterations, "status": r.status})
    return {"robot": "pneumatic_finger", "tets": scene.num_elements, "runs": rows,
            "max_overhead_percent": max(r["overhead_percent"] for r in rows)}


def time_learned(nets_dir, calls):
    if nets_dir is None:
        work = tempfile.mkdtemp()
        csv = os.path.join(work, "d.csv")
        softkin.dataset(csv, "three_chamber", res=3, grid=4, jacobian="implicit", quiet=True)
        nets = softkin.train(csv, os.path.join(work, "nets"), what="fk,jac", hidden=(35, 35),
                             hidden_jac=(64, 64), epochs=20, quiet=True)
    else:
        nets = softkin.load_nets(nets_dir)
    c = (nets.lower + nets.upper) / 2
    out = {"name": nets.name}
    for label, f in [("p", nets.p), ("J", nets.J)]:
        f(c)
        t = time.perf_counter()
        for _ in range(calls):
            f(c)
        out[f"{label}_us_per_call"] = 1e6 * (time.perf_counter() - t) / calls
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="finger solves")
    ap.add_argument("--calls", type=int, default=20000, help="learned-model calls per function")
    ap.add_argument("--nets", help="a softkin train directory (default: train a small one)")
    args = ap.parse_args()
    print(json.dumps({"solve": time_solve(args.repeats),
                      "learned": time_learned(args.nets, args.calls)}, indent=2))


if __name__ == "__main__":
    main()
