#!/usr/bin/env bash
# Submits a SoftKin dataset to Slurm as a job array of N shards and a merge job that depends on
# it (afterok), and prints their job ids (docs/cluster.md).
#   scripts/slurm/submit_dataset.sh N OUT SOFTKIN [softkin dataset args...]
# e.g. scripts/slurm/submit_dataset.sh 64 finger.csv build/bin/softkin --robot finger_manipulator \
#        --grid 29 --jacobian implicit --points tip
set -euo pipefail
usage() { sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'; }
case "${1:-}" in -h | --help) usage; exit 0 ;; esac
if [[ $# -lt 3 ]]; then
  usage >&2
  exit 2
fi
n="$1"
out="$2"
softkin="$(readlink -f "$3")"
shift 3
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
array=$(sbatch --parsable --array="0-$((n - 1))" "$here/dataset_array.sbatch" "$out" "$softkin" "$@")
merge=$(sbatch --parsable --dependency="afterok:${array%%;*}" "$here/dataset_merge.sbatch" "$out" "$n" "$softkin")
echo "array job $array ($n shards), merge job $merge -> $out"
