#!/bin/bash
# A real single-node Slurm for `viewcloth batch --emit slurm` (issue 15), run by tests/slurm.rs:
#   tests/slurm/run.sh VIEWCLOTH_BINARY WORK_DIR
# Installs Debian's slurm-wlm and munge when missing (needs root and the package registry),
# starts munged, slurmctld and slurmd by hand from a minimal slurm.conf written here
# (proctrack/linuxproc and task/none: no cgroups; no accounting database, so squeue and the
# outputs are polled), submits a two-shot array from `--emit slurm`, sends task 1 SIGTERM
# mid-run (it checkpoints, exits 75 and requeues itself), waits for both tasks, and checks both
# shots' frames are byte-identical to `simulate`'s. The daemons it started are stopped by PID.
# Exit 0: passed; 3: Slurm could not be installed or started (the message says why); else failed.
set -uo pipefail
BIN=$1
WORK=$2
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
say() { echo "slurm-test: $*"; }
unavailable() { echo "SLURM UNAVAILABLE: $*"; exit 3; }
fail() { echo "SLURM TEST FAILED: $*"; for f in "$WORK"/slurmctld.log "$WORK"/slurmd.log "$WORK"/emit/logs/*; do [ -f "$f" ] && { echo "--- $f"; tail -n 25 "$f"; }; done; exit 1; }
start=$(date +%s)
rm -rf "$WORK" && mkdir -p "$WORK"/{munge,state,spool,out} || exit 1

# 1. Slurm and munge, installed when missing.
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
    [ "$(id -u)" = 0 ] || unavailable "slurm-wlm and munge are not installed and this is not root"
    command -v apt-get >/dev/null || unavailable "slurm-wlm and munge are not installed and there is no apt-get"
    say "installing slurm-wlm and munge"
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        slurm-wlm munge; } >"$WORK/apt.log" 2>&1 ||
        { tail -n 5 "$WORK/apt.log"; unavailable "apt-get install slurm-wlm munge failed (log: $WORK/apt.log)"; }
fi
[ "$(id -u)" = 0 ] || unavailable "the daemons are started as root here, and this is not root"
say "installed after $(( $(date +%s) - start )) s: $(slurmctld -V)"

# 2. The daemons, stopped by their PIDs on every exit.
PIDS=()
cleanup() {
    for p in "${PIDS[@]}"; do kill -TERM "$p" 2>/dev/null; done
    sleep 1
    for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
    for p in "${PIDS[@]}"; do wait "$p" 2>/dev/null; done
}
trap cleanup EXIT
M="$WORK/munge"
dd if=/dev/urandom of="$M/munge.key" bs=1024 count=1 status=none && chmod 400 "$M/munge.key"
chmod 700 "$M"
munged --foreground --force --key-file="$M/munge.key" --socket="$M/munge.socket" --pid-file="$M/munged.pid" \
    --log-file="$M/munged.log" --seed-file="$M/munged.seed" >"$M/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$M/munge.socket" ] && break; sleep 0.1; done
[ -S "$M/munge.socket" ] || { cat "$M/munged.out" "$M/munged.log" 2>/dev/null; unavailable "munged did not start"; }

HOST=$(hostname -s)
CPUS=$(nproc)
# Ports of this test's own cluster (not the default 6817/6818, which a real one may use).
PORT=${VIEWCLOTH_SLURM_PORT:-16817}
export SLURM_CONF="$WORK/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=viewcloth-test
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
AuthType=auth/munge
AuthInfo=socket=$M/munge.socket
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SlurmdParameters=config_overrides
JobRequeue=1
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS State=UNKNOWN
PartitionName=test Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -D -c -f "$SLURM_CONF" >"$WORK/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -f "$SLURM_CONF" -N "$HOST" >"$WORK/slurmd.out" 2>&1 &
PIDS+=($!)
state=""
for _ in $(seq 150); do
    state=$(sinfo -h -o %T 2>/dev/null | head -n 1)
    [ "$state" = idle ] && break
    sleep 0.2
done
[ "$state" = idle ] || { cat "$WORK"/slurmctld.out "$WORK"/slurmd.out; tail -n 20 "$WORK"/slurmctld.log "$WORK"/slurmd.log; unavailable "the node did not come up (state '$state')"; }
say "cluster up after $(( $(date +%s) - start )) s"

# 3. Two shots: task 1 long enough to be signalled mid-run.
cd "$WORK" || exit 1
cat >shots.json <<JSON
{ "version": 1, "shots": [
  { "scene": "$ROOT/scenes/flag_wind.json", "frames": 6, "out": "out/flag" },
  { "scene": "$ROOT/scenes/hanging_sheet.json", "frames": 60, "out": "out/sheet", "checkpoint_every": 25 }
] }
JSON
"$BIN" batch shots.json --emit slurm --out emit --threads 1 || fail "--emit slurm"
job=$(sbatch --parsable emit/shots.sbatch) || fail "sbatch"
job=${job%%;*}
say "submitted array job $job"

# 4. SIGTERM to task 1 once it has written frame 8 (checkpoints are every 25 frames, so
#    what resumes is the checkpoint the signal wrote).
t0=$(date +%s)
until [ -f out/sheet/frame_0008.obj ]; do
    [ $(( $(date +%s) - t0 )) -lt 120 ] || fail "task 1 did not reach frame 8"
    sleep 0.05
done
scancel --batch --signal=TERM "${job}_1" || fail "scancel --signal=TERM"
say "sent SIGTERM to task ${job}_1"

# 5. Wait for both tasks to leave the queue (a requeued one starts again by itself).
t0=$(date +%s)
while [ -n "$(squeue -h -j "$job" -o %i 2>/dev/null)" ]; do
    [ $(( $(date +%s) - t0 )) -lt 150 ] || { squeue -j "$job"; fail "the array did not finish"; }
    # A requeued job may wait for its begin time; release it now.
    squeue -h -j "$job" -t PD -o "%i %r" | while read -r id reason; do
        [ "$reason" = BeginTime ] && scontrol update JobId="$id" StartTime=now >/dev/null 2>&1
    done
    sleep 0.5
done
say "array finished after $(( $(date +%s) - start )) s"

# 6. The signalled task checkpointed, exited 75, requeued itself and resumed; both shots match
#    simulate's frames byte for byte.
log1=$(ls emit/logs/*_"${job}"_1.log 2>/dev/null | head -n 1)
[ -n "$log1" ] || fail "no log of task 1"
grep -q "interrupted after frame" "$log1" || fail "task 1 was not interrupted at a checkpoint"
grep -q "exit 75" "$log1" || fail "task 1 did not exit 75"
grep -q "restart 1" "$log1" || fail "task 1 was not requeued"
grep -q '"status": "resumed"' emit/shots.shot1.batch.json || fail "shot 1 did not resume"
grep -q '"status": "done"' emit/shots.shot0.batch.json || fail "shot 0 did not finish"
grep -q "sheet_on\|hanging_sheet): frame 60/60" "$log1" || fail "no progress line of frame 60 in task 1's log"
"$BIN" simulate "$ROOT/scenes/flag_wind.json" --frames 6 --out ref/flag --quiet --threads 1 || fail "simulate flag"
"$BIN" simulate "$ROOT/scenes/hanging_sheet.json" --frames 60 --out ref/sheet --quiet --threads 1 || fail "simulate sheet"
for shot in flag sheet; do
    n=0
    for f in ref/$shot/frame_*.obj; do
        cmp -s "$f" "out/$shot/$(basename "$f")" || fail "out/$shot/$(basename "$f") differs from simulate's"
        n=$((n + 1))
    done
    say "$shot: $n frames identical to simulate's"
done
say "passed in $(( $(date +%s) - start )) s"
