#!/usr/bin/env bash
# `mpirun -n 2 softkin run CONFIG` of a sweep (experiments/sweep.hpp) equals the one-process run:
# a tiny fig5_5 architecture sweep (its dataset shared over the ranks too) gives the same table,
# each network trained once; a rerun after losing two rows trains only those two; an experiment
# that is not a sweep, or a command that does not share work (fk), is refused under mpirun.
# Usage: mpi_sweep.sh SOFTKIN MPIEXEC
set -euo pipefail
SOFTKIN="$1"
MPIEXEC="$2"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
export OMP_NUM_THREADS=1
MPI=("$MPIEXEC" --allow-run-as-root --oversubscribe)

cat > arch.json <<'JSON'
{
  "name": "arch",
  "experiment": "learn_architecture",
  "seed": 3,
  "datasets": [{"robot": "three_chamber", "res": 3, "grid": 4, "block": 16, "jacobian": true,
                "gradient_tolerance": 1e-4}],
  "layers": [1, 2],
  "neurons": [4, 8],
  "jac_layers": [1],
  "jac_neurons": [4, 6],
  "epochs": 15
}
JSON
units=6  # 2 x 2 N_fk + 1 x 2 N_J

# The table without its time column (wall time is not reproducible).
table() { cut -d, -f1-10,12 "$1/arch/architecture.csv"; }
rows() {  # the summary's rows without time_s, one per line
  /usr/bin/python3 -c 'import json,sys
for r in json.load(open(sys.argv[1]))["rows"]:
    r.pop("time_s"); print(json.dumps(r, sort_keys=True))' "$1/arch/summary.json"
}

"$SOFTKIN" run arch.json --no-plot --results serial 2> serial.log || { cat serial.log >&2; exit 1; }
"${MPI[@]}" -n 2 "$SOFTKIN" run arch.json --no-plot --results mpi 2> mpi.log ||
  { cat mpi.log >&2; exit 1; }
diff <(table serial) <(table mpi)
diff <(rows serial) <(rows mpi)
# The dataset, computed by both ranks (4 units of 16 samples), equals the one-process dataset.
dataset=three_chamber_r3_g4_b16_J_gt0.0001_tip.csv
cmp "serial/_datasets/$dataset" "mpi/_datasets/$dataset"
[[ $(wc -l < mpi/arch/architecture.jsonl) -eq $units ]] ||
  { echo "the MPI journal has $(wc -l < mpi/arch/architecture.jsonl) rows, not $units" >&2; exit 1; }
grep -q "rank 0: unit" mpi.log && grep -q "rank 1: unit" mpi.log ||
  { echo "both ranks should have trained networks:" >&2; cat mpi.log >&2; exit 1; }
[[ $(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["mpi_ranks"])' \
  mpi/arch/run.json) -eq 2 ]]
echo "mpirun -n 2: the same table as one process, each of the $units networks trained once"

# Two rows lost (as if their ranks had been killed before journaling them): a rerun trains only
# those two and the table is the same.
head -n $((units - 2)) mpi/arch/architecture.jsonl > cut && mv cut mpi/arch/architecture.jsonl
"${MPI[@]}" -n 2 "$SOFTKIN" run arch.json --no-plot --results mpi 2> rerun.log ||
  { cat rerun.log >&2; exit 1; }
[[ $(grep -c ": unit .* done" rerun.log) -eq 2 ]] ||
  { echo "the rerun should train 2 networks:" >&2; cat rerun.log >&2; exit 1; }
[[ $(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["resumed_rows"])' \
  mpi/arch/summary.json) -eq $((units - 2)) ]]
diff <(table serial) <(table mpi)
echo "rerun after losing 2 rows: 2 trained, $((units - 2)) resumed, the same table"

# An experiment that is not a sweep is refused, with the reason.
cat > bend.json <<'JSON'
{"name": "bend", "experiment": "pneumatic_bending", "seed": 0, "robot": "three_chamber", "res": 3}
JSON
if "${MPI[@]}" -n 2 "$SOFTKIN" run bend.json --no-plot --results refused 2> refused.log; then
  echo "a non-sweep experiment ran under mpirun" >&2
  exit 1
fi
grep -q "is not a sweep of independent units; run it as one process" refused.log ||
  { cat refused.log >&2; exit 1; }
[[ ! -e refused/bend/summary.json ]]
echo "a non-sweep experiment under mpirun: refused"

# A command that does not share work over ranks is refused under mpirun, before it writes anything.
if "${MPI[@]}" -n 2 "$SOFTKIN" fk --robot three_chamber --res 2 --actuation 1.2 \
  --vtu fk.vtu 2> fk.log; then
  echo "softkin fk ran under mpirun -n 2" >&2
  exit 1
fi
grep -q "fk: started by an MPI launcher with 2 processes" fk.log || { cat fk.log >&2; exit 1; }
[[ ! -e fk.vtu ]]
echo "softkin fk under mpirun: refused"
