#!/usr/bin/env bash
# A real single-node Slurm (Debian slurmctld, slurmd, slurm-client, munge; scripts/setup.sh
# installs them): munged, slurmctld and slurmd are started as this user in a temporary folder
# (no systemd, no cgroups: proctrack/linuxproc, task/none), then scripts/slurm/submit_dataset.sh
# submits a 3-task dataset array and its afterok merge job. The merged file must equal the
# one-process dataset byte for byte. Exits 77 (ctest: skipped, with the reason) when the Slurm or
# munge programs are missing. Usage: slurm_cluster.sh SOURCE_DIR SOFTKIN
set -euo pipefail
SRC="$1"
SOFTKIN="$(readlink -f "$2")"
for prog in munged munge slurmctld slurmd sbatch squeue sinfo scontrol; do
  if ! command -v "$prog" > /dev/null && [[ ! -x /usr/sbin/$prog ]]; then
    echo "skipped: $prog is not installed (bash scripts/setup.sh installs slurmctld, slurmd," \
      "slurm-client and munge)"
    exit 77
  fi
done
export PATH="$PATH:/usr/sbin"
WORK="$(mktemp -d)"
D="$WORK/slurm"
mkdir -p "$D/munge" "$D/state" "$D/spool" "$D/log" "$WORK/run"
chmod 755 "$D/munge"

stop() {
  for pidfile in "$D/slurmd.pid" "$D/slurmctld.pid" "$D/munge/munged.pid"; do
    [[ -f $pidfile ]] && kill "$(cat "$pidfile")" 2> /dev/null || true
  done
  sleep 1
  rm -rf "$WORK"
}
trap stop EXIT
fail() {
  echo "$*" >&2
  for log in "$D"/log/*.log "$WORK"/run/*.log; do
    [[ -f $log ]] && { echo "--- $log" >&2; tail -20 "$log" >&2; }
  done
  exit 1
}

# Ports of their own, so that the test does not meet another Slurm on this machine.
base=$((20000 + ($$ % 20000) * 2))
host="$(hostname -s)"
mem=$(free -m | awk '/^Mem:/ {print int($2 * 0.8)}')
msock="$D/munge/munge.socket.2"
dd if=/dev/urandom of="$D/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$D/munge/munge.key"
cat > "$D/slurm.conf" << CONF
ClusterName=softkintest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$base
SlurmdPort=$((base + 1))
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$msock
MailProg=/bin/true
MpiDefault=pmix
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pid
SlurmdPidFile=$D/slurmd.pid
SlurmctldLogFile=$D/log/slurmctld.log
SlurmdLogFile=$D/log/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$D/slurm.conf"

t0=$(date +%s.%N)
munged --force --key-file="$D/munge/munge.key" --socket="$msock" \
  --pid-file="$D/munge/munged.pid" --log-file="$D/log/munged.log" \
  --seed-file="$D/munge/munged.seed"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
state=""
for _ in $(seq 1 120); do
  state=$(sinfo -h -n "$host" -o %t 2> /dev/null || true)
  [[ $state == idle ]] && break
  sleep 0.5
done
[[ $state == idle ]] || fail "the Slurm node did not become idle within 60 s (state '$state')"
echo "single-node Slurm $(sinfo -V | awk '{print $2}') up in $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}') s"

# The dataset: one process, then the array of 3 shards and the merge job through Slurm.
cd "$WORK/run"
export OMP_NUM_THREADS=1
ARGS=(--robot three_chamber --res 3 --grid 4 --jacobian implicit --block 8)
"$SOFTKIN" dataset "${ARGS[@]}" --quiet --out single.csv
t0=$(date +%s.%N)
submitted=$(bash "$SRC/scripts/slurm/submit_dataset.sh" 3 "$WORK/run/slurm.csv" "$SOFTKIN" "${ARGS[@]}")
echo "$submitted"
array=$(echo "$submitted" | awk '{print $3}')
merge=$(echo "$submitted" | awk '{print $8}')
for _ in $(seq 1 600); do
  squeue -h -j "$array,$merge" 2> /dev/null | grep -q . || break
  # A merge job whose array failed waits forever (DependencyNeverSatisfied): stop at once.
  if squeue -h -j "$merge" -o %r 2> /dev/null | grep -q DependencyNeverSatisfied; then
    fail "an array task failed: the merge job's dependency can never be satisfied"
  fi
  sleep 0.5
done
squeue -h -j "$array,$merge" 2> /dev/null | grep -q . && fail "the jobs did not finish in 300 s"
scontrol show job "$merge" | grep -q "JobState=COMPLETED" ||
  fail "the merge job did not complete: $(scontrol show job "$merge" | grep -o 'JobState=[A-Z]*')"
[[ -f slurm.csv ]] || fail "the merge job wrote no slurm.csv"
cmp single.csv slurm.csv || fail "the Slurm dataset differs from the one-process dataset"
for k in 0 1 2; do
  [[ -f softkin-dataset-${array}_$k.log ]] || fail "no log of array task $k"
done
echo "Slurm array of 3 shards + afterok merge: identical to one process" \
  "($(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}') s from submission)"

# The MPI batch script: srun starts 2 ranks (PMIx) that share the samples.
t0=$(date +%s.%N)
job=$(sbatch --parsable --ntasks=2 --mem-per-cpu=1G "$SRC/scripts/slurm/dataset_mpi.sbatch" \
  "$SOFTKIN" dataset "${ARGS[@]}" --out "$WORK/run/srun.csv")
for _ in $(seq 1 600); do
  squeue -h -j "$job" 2> /dev/null | grep -q . || break
  sleep 0.5
done
scontrol show job "$job" | grep -q "JobState=COMPLETED" ||
  fail "the MPI job did not complete: $(scontrol show job "$job" | grep -o 'JobState=[A-Z]*')"
cmp single.csv srun.csv || fail "the srun dataset differs from the one-process dataset"
grep -q "softkin dataset: 2 ranks" "softkin-mpi-$job.log" ||
  fail "the job did not run as 2 MPI ranks: $(cat "softkin-mpi-$job.log")"
echo "sbatch --ntasks=2 dataset_mpi.sbatch (srun, PMIx): identical to one process" \
  "($(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}') s from submission)"
