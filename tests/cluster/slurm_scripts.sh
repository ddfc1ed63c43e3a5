#!/usr/bin/env bash
# The Slurm scripts of scripts/slurm/ run as Slurm would run them (the array's variables set by
# hand, one task after the other), and their merge equals the one-process dataset byte for byte;
# submit_dataset.sh submits the array and a merge job that depends on it (afterok), checked with
# a stand-in sbatch that records its arguments. Usage: slurm_scripts.sh SOURCE_DIR SOFTKIN
set -euo pipefail
SRC="$1"
SOFTKIN="$2"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
export OMP_NUM_THREADS=1
ARGS=(--robot three_chamber --res 3 --grid 4 --block 8 --quiet)
"$SOFTKIN" dataset "${ARGS[@]}" --out single.csv

for k in 0 1 2; do
  SLURM_ARRAY_TASK_ID=$k SLURM_ARRAY_TASK_COUNT=3 \
    bash "$SRC/scripts/slurm/dataset_array.sbatch" "$WORK/array.csv" "$SOFTKIN" "${ARGS[@]}"
done
bash "$SRC/scripts/slurm/dataset_merge.sbatch" "$WORK/array.csv" 3 "$SOFTKIN"
cmp single.csv array.csv
echo "array of 3 shards + merge: identical to one process"

# Without the array's variables the script refuses with its usage.
if bash "$SRC/scripts/slurm/dataset_array.sbatch" x "$SOFTKIN" 2> usage.txt; then exit 1; fi
grep -q "SLURM_ARRAY_TASK_ID" usage.txt

# submit_dataset.sh: the array, then the merge after it.
mkdir bin
cat > bin/sbatch <<'SB'
#!/usr/bin/env bash
echo "$*" >> "$SBATCH_LOG"
if [[ "$*" == *--array* ]]; then echo 4242; else echo 4243; fi
SB
chmod +x bin/sbatch
PATH="$WORK/bin:$PATH" SBATCH_LOG="$WORK/sbatch.log" \
  bash "$SRC/scripts/slurm/submit_dataset.sh" 8 out.csv "$SOFTKIN" --robot three_chamber > submit.txt
grep -q -- "--array=0-7 .*dataset_array.sbatch out.csv .*softkin --robot three_chamber" sbatch.log
grep -q -- "--dependency=afterok:4242 .*dataset_merge.sbatch out.csv 8 " sbatch.log
grep -q "array job 4242 (8 shards), merge job 4243" submit.txt
echo "submit_dataset.sh: array and dependent merge submitted"
