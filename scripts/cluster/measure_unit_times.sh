#!/usr/bin/env bash
# Measures what scripts/cluster/predict_wall_time.py needs to predict a dataset's wall time on
# many MPI ranks (docs/cluster.md): the time of warm-start units spread over the whole serpentine
# order, and the time of a cold sample (the first of each unit, solved from rest).
#
#   scripts/cluster/measure_unit_times.sh OUT.csv SOFTKIN [dataset args without --out/--block]
#
# Runs `softkin dataset ... --block B --shard k/U` for K units k spread evenly over the U units of
# block B (default B=64, K=12), then the same samples' neighbourhood with --block 1 (every sample
# cold) for C units of 16 samples (C=4), one process and one thread each. Writes
#   kind,block,unit,units,samples,seconds
# to OUT.csv (appending as it goes; rerun to resume). Environment: BLOCK, UNITS_MEASURED, COLD_RUNS.
set -euo pipefail
usage() { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; }
case "${1:-}" in -h | --help) usage; exit 0 ;; esac
if [[ $# -lt 2 ]]; then
  usage >&2
  exit 2
fi
out=$1 softkin=$2
shift 2
block=${BLOCK:-64} measured=${UNITS_MEASURED:-12} cold_runs=${COLD_RUNS:-4}
for var in BLOCK:$block UNITS_MEASURED:$measured COLD_RUNS:$cold_runs; do
  if [[ ! ${var#*:} =~ ^[1-9][0-9]*$ ]]; then
    echo "measure_unit_times: ${var%%:*}: expected an integer >= 1, got '${var#*:}'" >&2
    exit 2
  fi
done
work=$(mktemp -d "${TMPDIR:-/tmp}/softkin-measure.XXXXXX")
trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1

# The number of samples (the plan of --dry-run; softkin names a bad argument and exits 2).
plan=$("$softkin" dataset "$@" --block "$block" --out "$work/plan.csv" --dry-run) || exit $?
total=$(/usr/bin/python3 -c 'import json,sys; print(json.loads(sys.argv[1])["samples"])' "$plan")
units=$(( (total + block - 1) / block ))
[[ -f $out ]] || echo "kind,block,unit,units,samples,seconds" > "$out"

run_one() {  # kind block unit units
  local kind=$1 b=$2 k=$3 n=$4
  if grep -q "^$kind,$b,$k,$n," "$out"; then return; fi
  rm -f "$work/u.csv" "$work/u.csv.json"
  local t0 t1
  t0=$(date +%s.%N)
  "$softkin" dataset "${args[@]}" --block "$b" --shard "$k/$n" --out "$work/u.csv" --quiet
  t1=$(date +%s.%N)
  local samples=$(( $(wc -l < "$work/u.csv") - 1 ))
  echo "$kind,$b,$k,$n,$samples,$(awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.3f", b - a}')" >> "$out"
  echo "measure: $kind unit $k/$n: $samples samples in $(awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.3f", b - a}') s" >&2
}
args=("$@")
set --
for (( i = 0; i < measured; i++ )); do
  run_one warm "$block" $(( i * (units - 1) / (measured - 1 > 0 ? measured - 1 : 1) )) "$units"
done
cold_units=$(( (total + 15) / 16 ))
for (( i = 0; i < cold_runs; i++ )); do
  # --block 1 and shards of 16 samples: every sample is solved from rest.
  run_one cold 1 $(( i * (cold_units - 1) / (cold_runs - 1 > 0 ? cold_runs - 1 : 1) )) "$cold_units"
done
