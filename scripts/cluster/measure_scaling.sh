#!/usr/bin/env bash
# The MPI scaling figures of docs/cluster.md, measured in one run and written to
# RESULTS/cluster_scaling/summary.json (with the git commit and the machine):
#   - one process, `mpirun -n 1` and `mpirun -n 2` on the same dataset (default: three_chamber
#     res 3, a 10^3 grid with implicit Jacobians), one thread per rank: wall times, the ratios,
#     whether the three files are identical, and the load balance the 2-rank job reports;
#   - the predicted wall time of the 29^3 finger_manipulator dataset on 64 and 512 ranks, from the
#     unit times in scripts/cluster/measured/ (predict_wall_time.py), as prediction.csv.
#
#   scripts/cluster/measure_scaling.sh [SOFTKIN [RESULTS]]   (defaults: build/bin/softkin, results)
# Environment: MPIEXEC (default mpirun), GRID (default 10). Takes about 4 minutes on 2 cores.
set -euo pipefail
case "${1:-}" in -h | --help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;; esac
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
softkin="$(readlink -f "${1:-$root/build/bin/softkin}")"
results="${2:-results}"
mpiexec="${MPIEXEC:-mpirun}"
grid="${GRID:-10}"
[[ -x $softkin ]] || { echo "measure_scaling: $softkin: not an executable softkin" >&2; exit 2; }
[[ $grid =~ ^[1-9][0-9]*$ ]] || { echo "measure_scaling: GRID: expected an integer >= 1, got '$grid'" >&2; exit 2; }
command -v "$mpiexec" > /dev/null || { echo "measure_scaling: $mpiexec not found (install openmpi-bin)" >&2; exit 2; }
out="$results/cluster_scaling"
mkdir -p "$out"
work=$(mktemp -d "${TMPDIR:-/tmp}/softkin-scaling.XXXXXX")
trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1
args=(dataset --robot three_chamber --res 3 --grid "$grid" --jacobian implicit)
mpi=("$mpiexec" --allow-run-as-root --oversubscribe)
now() { date +%s.%N; }

t0=$(now); "$softkin" "${args[@]}" --quiet --out "$work/one.csv"
t1=$(now); "${mpi[@]}" -n 1 "$softkin" "${args[@]}" --quiet --out "$work/n1.csv"
t2=$(now); "${mpi[@]}" -n 2 "$softkin" "${args[@]}" --out "$work/n2.csv" 2> "$work/n2.log"
t3=$(now)
balance=$(sed -n 's/.*busiest \/ mean \([0-9.eE+-]*\).*/\1/p' "$work/n2.log" | tail -1)
identical=true
cmp -s "$work/one.csv" "$work/n1.csv" && cmp -s "$work/one.csv" "$work/n2.csv" || identical=false
"$here/predict_wall_time.py" "$here/measured/finger_manipulator_r6_g29_unit_times.csv" \
  --samples 24389 --startup 0.08 --out "$out/prediction.csv" > "$out/prediction.txt"

/usr/bin/python3 - "$out" "$t0" "$t1" "$t2" "$t3" "${balance:-nan}" "$identical" "$grid" \
  "$(git -C "$root" rev-parse HEAD 2> /dev/null || echo unknown)" "${args[*]}" << 'PY'
import csv, json, os, platform, sys
out, t0, t1, t2, t3, balance, identical, grid, commit, command = sys.argv[1:]
t0, t1, t2, t3 = map(float, (t0, t1, t2, t3))
one, n1, n2 = t1 - t0, t2 - t1, t3 - t2
pred = list(csv.DictReader(open(os.path.join(out, "prediction.csv"))))
best = {int(r["ranks"]): r for r in pred if r["best"] == "1"}
summary = {
    "name": "cluster_scaling",
    "command": "softkin " + command,
    "samples": int(grid) ** 3,
    "one_process_s": one, "mpirun_n1_s": n1, "mpirun_n2_s": n2,
    "speedup_n2_vs_one_process": one / n2,
    "mpi_overhead_n1_vs_one_process": one / n1,
    "busiest_over_mean_n2": float(balance),
    "outputs_identical": identical == "true",
    "target_speedup_n2": 1.8,
    "predicted_finger29": {str(k): {"block": int(v["block"]), "wall_s": float(v["wall_s"]),
                                    "busiest_over_mean": float(v["busiest_over_mean"])}
                           for k, v in sorted(best.items())},
    "git_commit": commit,
    "machine": {"host": platform.node(), "cpus": os.cpu_count(), "system": platform.platform()},
}
tmp = os.path.join(out, "summary.json.tmp")
with open(tmp, "w") as f:
    json.dump(summary, f, indent=2)
    f.write("\n")
os.replace(tmp, os.path.join(out, "summary.json"))
print(f"one process {one:.1f} s, mpirun -n 1 {n1:.1f} s, -n 2 {n2:.1f} s: "
      f"{one / n2:.2f}x (target 1.8x), balance {balance}, identical {identical}; "
      f"wrote {out}/summary.json")
PY
[[ $identical == true ]] || { echo "measure_scaling: the MPI datasets differ from one process" >&2; exit 1; }
