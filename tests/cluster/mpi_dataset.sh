#!/usr/bin/env bash
# `mpirun -n N softkin dataset` equals the one-process dataset byte for byte (N = 2, 3), and a
# rerun after an interrupted job (some units complete, one cut mid-line, others missing) computes
# only what is missing and still gives the same bytes. Usage: mpi_dataset.sh SOFTKIN MPIEXEC
set -euo pipefail
SOFTKIN="$1"
MPIEXEC="$2"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
export OMP_NUM_THREADS=1
ARGS=(dataset --robot three_chamber --res 3 --grid 4 --jacobian implicit --block 8)
MPI=("$MPIEXEC" --allow-run-as-root --oversubscribe)

"$SOFTKIN" "${ARGS[@]}" --quiet --out single.csv
for n in 2 3; do
  "${MPI[@]}" -n "$n" "$SOFTKIN" "${ARGS[@]}" --quiet --out "n$n.csv"
  cmp single.csv "n$n.csv"
  [[ ! -e "n$n.csv.parts" ]] || { echo "n$n.csv.parts was not removed" >&2; exit 1; }
  echo "mpirun -n $n: identical to one process"
done

# An interrupted job: units 0 and 3 of 8 complete, unit 5 cut in the middle of a line.
mkdir resumed.csv.parts
for u in 0 3 5; do
  "$SOFTKIN" "${ARGS[@]}" --quiet --shard "$u/8" --out "resumed.csv.parts/unit-$u-of-8.csv"
done
head -c -40 resumed.csv.parts/unit-5-of-8.csv > cut && mv cut resumed.csv.parts/unit-5-of-8.csv
"${MPI[@]}" -n 2 "$SOFTKIN" "${ARGS[@]}" --out resumed.csv 2> resumed.log
cmp single.csv resumed.csv
# 8 + 8 + 7 samples were already there (the cut line of unit 5 is recomputed).
grep -q "23 already in the file, 41 written" resumed.log || { cat resumed.log >&2; exit 1; }
echo "resumed job: only the missing samples computed, identical to one process"

# A job killed mid-run (SIGKILL to the launcher and its ranks once a few units exist), then
# rerun: nothing lost or duplicated.
setsid "${MPI[@]}" -n 2 "$SOFTKIN" "${ARGS[@]}" --quiet --out killed.csv 2> /dev/null &
job=$!
for _ in $(seq 1 600); do
  n_files=0
  [[ -d killed.csv.parts ]] && n_files=$(find killed.csv.parts -name '*.csv' | wc -l)
  ((n_files >= 3)) && break
  sleep 0.1
done
kill -KILL -- "-$job" 2> /dev/null || true
wait "$job" 2> /dev/null || true
# The ranks are not in the launcher's process group: they exit once they lose it. Rerun only
# then (a rank still appending to a unit while the rerun resumes it would duplicate its lines).
for _ in $(seq 1 300); do
  pgrep -f -- "--out killed.csv" > /dev/null || break
  sleep 0.1
done
if pgrep -f -- "--out killed.csv" > /dev/null; then
  echo "ranks of the killed job still running after 30 s" >&2
  exit 1
fi
[[ ! -e killed.csv ]] || echo "note: the job finished before the kill (a fast machine)"
if ! "${MPI[@]}" -n 2 "$SOFTKIN" "${ARGS[@]}" --out killed.csv 2> killed.log; then
  echo "rerun after the kill failed; the parts were:" >&2
  ls -l killed.csv.parts >&2 || true
  cat killed.log >&2
  exit 1
fi
cmp single.csv killed.csv
echo "killed job rerun: identical to one process ($(grep -o '[0-9]* already' killed.log))"

# A finished dataset rerun under mpirun: checked by rank 0, nothing recomputed.
"${MPI[@]}" -n 2 "$SOFTKIN" "${ARGS[@]}" --out n2.csv 2> again.log
grep -q "64 already in the file, 0 written" again.log || { cat again.log >&2; exit 1; }
cmp single.csv n2.csv
echo "rerun of a finished dataset: nothing recomputed"
