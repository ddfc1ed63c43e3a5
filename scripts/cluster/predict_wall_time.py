#!/usr/bin/python3
"""Predicts the wall time of a dataset on R MPI ranks (docs/cluster.md, "Predicted scale").

  scripts/cluster/predict_wall_time.py TIMES.csv --samples N [--ranks 64 512]
      [--blocks 4 8 16 24 32 48 64] [--startup S] [--merge-ms-per-sample M] [--out TABLE.csv]

TIMES.csv comes from scripts/cluster/measure_unit_times.sh: the wall times of whole warm-start
units of a real run (block B0, spread over the serpentine order) and of runs in which every sample
is cold (block 1).

The model:
  * t_cold: the time of a sample solved from rest (the first of every unit): the mean over the
    cold runs, less the process start-up.
  * t_warm(i): the time of a warm-started sample at position i of the order: each measured unit
    gives (T_unit - startup - t_cold) / (B0 - 1) at its middle sample; between them, linear
    interpolation.
  * A unit of block b starting at sample i costs t_cold + sum over its other samples of t_warm.
  * Rank 0 hands the units out in order to whichever rank is free first (dataset_mpi.cpp); the
    ranks start after `startup` and the job ends when the last unit is done, plus rank 0's merge
    (merge-ms-per-sample x N). The dispatch itself is free (rank 0 answers between samples).
For each rank count the block with the shortest predicted wall time is marked; speed-ups are
against one rank with the largest block asked for. A malformed TIMES.csv or option exits with
status 2 and a message naming the file and line, or the option.
"""
import argparse
import csv
import heapq
import sys

import numpy as np


def fail(message):
    """Bad input: the message on stderr, exit status 2."""
    print(f"predict_wall_time: {message}", file=sys.stderr)
    sys.exit(2)


COLUMNS = ["kind", "block", "unit", "units", "samples", "seconds"]


def read_times(path):
    """The warm and cold rows of TIMES.csv; exits 2 naming the file and line of a bad one."""
    warm, cold = [], []
    try:
        f = open(path, newline="")
    except OSError as e:
        fail(f"cannot read {path}: {e.strerror}")
    with f:
        reader = csv.DictReader(f)
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            fail(f"{path}:1: expected the columns {','.join(COLUMNS)} "
                     f"(measure_unit_times.sh writes them); missing {','.join(missing)}")
        for row in reader:
            line = reader.line_num
            try:
                rec = (int(row["block"]), int(row["unit"]), int(row["units"]),
                       int(row["samples"]), float(row["seconds"]))
            except (TypeError, ValueError):
                fail(f"{path}:{line}: expected integers block, unit, units, "
                         f"samples and a number of seconds, got {row}")
            if row["kind"] not in ("warm", "cold") or rec[0] < 1 or rec[3] < 1 or rec[4] <= 0:
                fail(f"{path}:{line}: expected kind warm or cold, block and "
                         f"samples >= 1 and seconds > 0, got {row}")
            (warm if row["kind"] == "warm" else cold).append(rec)
    if not warm or not cold:
        fail(f"{path}: needs 'warm' and 'cold' rows "
                 "(measure_unit_times.sh writes both)")
    return warm, cold


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("times")
    ap.add_argument("--samples", type=int, required=True, help="samples of the dataset (N)")
    ap.add_argument("--ranks", type=int, nargs="+", default=[64, 512])
    ap.add_argument("--blocks", type=int, nargs="+", default=[4, 8, 12, 16, 24, 32, 48, 64])
    ap.add_argument("--startup", type=float, default=0.1, help="process start-up, s")
    ap.add_argument("--merge-ms-per-sample", type=float, default=0.15)
    ap.add_argument("--out", help="also write the table as CSV")
    a = ap.parse_args()
    if a.samples < 1 or min(a.ranks) < 1 or min(a.blocks) < 1:
        ap.error("--samples, --ranks and --blocks must be >= 1")
    warm, cold = read_times(a.times)
    n = a.samples

    t_cold = float(np.mean([(t - a.startup) / s for _, _, _, s, t in cold]))
    pos, rate = [], []
    for b0, k, units, s, t in warm:
        if s < 2:
            continue
        first = k * b0  # units of the measured run are whole blocks of b0
        pos.append(first + s / 2)
        rate.append(max(0.0, (t - a.startup - t_cold) / (s - 1)))
    order = np.argsort(pos)
    pos, rate = np.array(pos)[order], np.array(rate)[order]
    t_warm = np.interp(np.arange(n) + 0.5, pos, rate)
    cum = np.concatenate([[0.0], np.cumsum(t_warm)])
    reference = max(a.blocks)  # speed-ups are against one rank with the largest block
    serial = None
    print(f"model: t_cold {t_cold:.3f} s, t_warm {t_warm.mean():.3f} s mean "
          f"({t_warm.min():.3f}..{t_warm.max():.3f}), {n} samples")

    rows = []
    for ranks in [1] + a.ranks:
        best = None
        for b in a.blocks:
            starts = np.arange(0, n, b)
            ends = np.minimum(starts + b, n)
            unit = t_cold + (cum[ends] - cum[starts + 1])
            free = [(a.startup, r) for r in range(ranks)]
            heapq.heapify(free)
            busy = np.zeros(ranks)
            for u in unit:
                t, r = heapq.heappop(free)
                busy[r] += u
                heapq.heappush(free, (t + u, r))
            makespan = max(t for t, _ in free)
            wall = makespan + a.merge_ms_per_sample * 1e-3 * n
            balance = busy.max() / busy.mean() if busy.mean() > 0 else 1.0
            row = {"ranks": ranks, "block": b, "units": len(unit), "wall_s": wall,
                   "busiest_over_mean": balance, "cpu_s": float(unit.sum())}
            rows.append(row)
            if best is None or wall < best["wall_s"]:
                best = row
            if ranks == 1 and b == reference:
                serial = wall
        best["best"] = True
    print(f"speed-up: against one rank with block {reference}")
    print(f"{'ranks':>6} {'block':>6} {'units':>6} {'wall':>10} {'speed-up':>9} {'balance':>8}")
    for r in rows:
        mark = "  <- shortest" if r.get("best") else ""
        print(f"{r['ranks']:>6} {r['block']:>6} {r['units']:>6} {r['wall_s']:>9.0f}s "
              f"{serial / r['wall_s']:>8.1f}x {r['busiest_over_mean']:>8.3f}{mark}")
    if a.out:
        with open(a.out, "w", newline="") as f:
            w = csv.DictWriter(f, ["ranks", "block", "units", "wall_s", "speedup_vs_one_rank",
                                   "reference_block", "busiest_over_mean", "cpu_s", "best"])
            w.writeheader()
            for r in rows:
                w.writerow({**r, "speedup_vs_one_rank": serial / r["wall_s"],
                            "reference_block": reference,
                            "best": int(bool(r.get("best")))})


if __name__ == "__main__":
    main()
