#!/usr/bin/env bash
# `vanefit batch --slurm` against a real Slurm, not a mock.
#
# Starts its own munged (as user munge, on a socket in a temporary folder), slurmctld and
# slurmd (one node "localhost", 2 CPUs, config in the temporary folder, passed as
# SLURM_CONF), submits a fleet of 8 small datasets as a job array with a dependent merge
# job, requeues one array task and cancels another while they are in the middle of a fit,
# resubmits, waits, and compares the merged summary.csv with a local run byte for byte.
# Stops the daemons it started on exit. Installs nothing: .ci/slurm.sh does that.
#
# Needs: root, Debian's slurm-wlm and munge (Slurm 22.05 checked), a release build of
# vanefit (VANEFIT_BIN, default target/release/vanefit; built here if missing).
# Last line: "slurm: N passed, N failed"; exit status 0 only if nothing failed.
set -uo pipefail

ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BIN=${VANEFIT_BIN:-$ROOT/target/release/vanefit}
PASSED=0
FAILED=0
T0=$(date +%s)

say() { echo "[slurm-test $(($(date +%s) - T0)) s] $*"; }
pass() { PASSED=$((PASSED + 1)); say "ok: $1"; }
fail() { FAILED=$((FAILED + 1)); say "FAILED: $1"; }
check() { # check "what" command...
  local what=$1
  shift
  if "$@"; then pass "$what"; else fail "$what"; fi
}
finish() {
  echo "slurm: $PASSED passed, $FAILED failed"
  [ "$FAILED" -eq 0 ]
  exit
}
loud() { # the daemons (or a prerequisite) are not there: say so loudly, fail, stop
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!" >&2
  echo "!!! SLURM TEST NOT RUN: $*" >&2
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!" >&2
  fail "$*"
  finish
}

# --- prerequisites -------------------------------------------------------------------------
[ "$(id -u)" -eq 0 ] || loud "needs root (slurmd runs jobs as root here, munged as user munge)"
for c in munged munge unmunge slurmctld slurmd sbatch squeue scontrol scancel sinfo runuser; do
  command -v "$c" >/dev/null 2>&1 || loud "'$c' is missing: install Debian's slurm-wlm and munge (.ci/slurm.sh does)"
done
id munge >/dev/null 2>&1 || loud "no user 'munge' (the munge package creates it)"
if [ ! -x "$BIN" ]; then
  say "building vanefit (release)"
  (cd "$ROOT" && cargo build --release --quiet) || loud "cannot build vanefit"
fi
say "$(slurmctld -V), vanefit at $BIN"

# --- daemons -------------------------------------------------------------------------------
WORK=$(mktemp -d /tmp/vanefit-slurm.XXXXXX)
chmod 755 "$WORK"
STARTED_PIDFILES=()
stop_daemons() {
  for f in "${STARTED_PIDFILES[@]}"; do
    [ -s "$f" ] && kill "$(cat "$f")" 2>/dev/null
  done
  sleep 1
  for f in "${STARTED_PIDFILES[@]}"; do
    [ -s "$f" ] && kill -9 "$(cat "$f")" 2>/dev/null
  done
  if [ "${KEEP_WORK:-0}" = 1 ]; then say "kept $WORK"; else rm -rf "$WORK"; fi
}
trap stop_daemons EXIT

# munged insists: the key in a folder only munge can read, the socket in one all can enter.
M=$WORK/munge
mkdir -p "$M/key"
dd if=/dev/urandom of="$M/key/munge.key" bs=1024 count=1 status=none
chown -R munge:munge "$M"
chmod 755 "$M"
chmod 700 "$M/key"
chmod 400 "$M/key/munge.key"
SOCK=$M/munge.socket
runuser -u munge -- munged --socket="$SOCK" --key-file="$M/key/munge.key" \
  --pid-file="$M/munged.pid" --log-file="$M/munged.log" --seed-file="$M/munged.seed" \
  || loud "munged did not start: $(tail -5 "$M/munged.log" 2>/dev/null)"
STARTED_PIDFILES+=("$M/munged.pid")
munge -S "$SOCK" -n | unmunge -S "$SOCK" >/dev/null || loud "munge does not work on $SOCK"

PORT=$((20000 + RANDOM % 20000))
mkdir -p "$WORK/state" "$WORK/spool"
export SLURM_CONF=$WORK/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=vanefit-test
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$SOCK
CredType=cred/munge
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
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
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobRequeue=1
MinJobAge=300
NodeName=localhost CPUs=2 State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -c || loud "slurmctld did not start: $(tail -5 "$WORK/slurmctld.log" 2>/dev/null)"
STARTED_PIDFILES+=("$WORK/slurmctld.pid")
slurmd -N localhost || loud "slurmd did not start: $(tail -5 "$WORK/slurmd.log" 2>/dev/null)"
STARTED_PIDFILES+=("$WORK/slurmd.pid")
for _ in $(seq 60); do
  state=$(sinfo -h -n localhost -o %T 2>/dev/null)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "${state:-}" = idle ] || loud "the node never became idle (state '${state:-}'): slurmctld: $(tail -3 "$WORK/slurmctld.log") slurmd: $(tail -3 "$WORK/slurmd.log")"
pass "munged, slurmctld and slurmd up (node localhost idle, port $PORT)"

# --- the fleet -----------------------------------------------------------------------------
F=$WORK/fleet
mkdir -p "$F/ds"
for i in 1 2 3 4 5 6 7 8; do
  "$BIN" synth "$F/ds/m$i" --noise "$(((i % 3) + 1))" --seed "$i" >/dev/null || loud "vanefit synth failed"
done
cat >"$F/manifest.toml" <<'EOF'
[batch]
datasets = ["ds/*"]
tasks = ["fit", "predict"]

[fit]
starts = 10
seed = 5
max_iters = 400
uncertainty = "curvature"
estimate = ["c_in1", "c_out2", "c_ext", "t_coulomb"]
plots = false

[predict]
pressures = [4, 6]
EOF
chmod -R a+rX "$WORK"
OUT=$F/slurm-run

# units in the shard of array task i of 4: datasets i and i+4 (round robin), fit then predict.

# Catching a fit in the middle of its starts, under any load. A start takes about 0.1 s of
# one core and a fit's ten about 1 s, so a poll that forks (sed, wc, sleep) several times per
# look fell behind on a loaded machine: beside pytest it first saw m6's fit after all its
# starts and the requeue came too late to test a resume. So: the poll looks with bash
# builtins only (no process started per look); it holds the array task's processes
# (SIGSTOP) the moment it sees the fit running with a start done, so that the fit cannot
# finish while scontrol is slow to requeue or cancel (Slurm sends SIGCONT before it ends
# a job's processes); and the task's pids are looked up before the fit begins.
exec {NAP_FD}<> <(:) # a pipe nobody writes to: `read -t` on it is a sleep without a fork
nap() { read -r -t "$1" -u "$NAP_FD" _ || true; }
# Sets N_STARTS and UNIT_STATE of unit $1 (dataset/task), with builtins only.
look_at_unit() {
  local starts=$OUT/$1/fit.starts.jsonl status=$OUT/$1/status.json text=
  local -a lines=()
  N_STARTS=0
  UNIT_STATE=
  if [ -f "$starts" ] && mapfile -t lines <"$starts" 2>/dev/null && [ "${#lines[@]}" -gt 1 ]; then
    N_STARTS=$((${#lines[@]} - 1))
  fi
  [ -f "$status" ] && { IFS= read -r -d '' text <"$status" 2>/dev/null || true; }
  if [[ $text =~ \"status\":\ \"([a-z]*)\" ]]; then UNIT_STATE=${BASH_REMATCH[1]}; fi
}
# Sets TASK_PIDS to the processes of running array task $1 (waits up to 60 s for it to run).
task_pids() {
  local task=$1 job
  TASK_PIDS=()
  for _ in $(seq 300); do
    job=$(scontrol show job "${ARRAY}_$task" 2>/dev/null)
    if [[ $job =~ JobId=([0-9]+).*JobState=RUNNING ]]; then
      mapfile -t TASK_PIDS < <(scontrol listpids "${BASH_REMATCH[1]}" 2>/dev/null |
        awk '$1 ~ /^[0-9]+$/ && $1 > 1 { print $1 }')
      [ "${#TASK_PIDS[@]}" -gt 0 ] && return 0
    fi
    sleep 0.2
  done
  return 1
}
# Waits until the fit of dataset $1, run by array task $2, has finished at least one start
# and is still running, then holds the task's processes; prints the starts done.
hold_mid_fit() {
  local ds=$1 task=$2
  task_pids "$task" || { say "array task $task never ran"; return 1; }
  for _ in $(seq 12000); do
    look_at_unit "$ds/fit"
    if [ "$UNIT_STATE" = running ] && [ "$N_STARTS" -ge 1 ]; then
      kill -STOP "${TASK_PIDS[@]}" 2>/dev/null
      look_at_unit "$ds/fit" # what it did between the look and the hold
      echo "$N_STARTS"
      [ "$UNIT_STATE" = running ] && [ "$N_STARTS" -lt 10 ]
      return
    fi
    nap 0.01
  done
  return 1
}

say "submitting: vanefit batch manifest.toml --out $OUT --slurm --shards 4 --cpus-per-task 1"
(cd "$F" && "$BIN" batch manifest.toml --out "$OUT" --slurm --shards 4 --cpus-per-task 1) >"$WORK/submit1.txt" 2>&1
cat "$WORK/submit1.txt"
ARRAY=$(sed -n 's/^submitted array job \([0-9]*\).*/\1/p' "$WORK/submit1.txt")
MERGE=$(sed -n 's/^submitted merge job \([0-9]*\).*/\1/p' "$WORK/submit1.txt")
[ -n "$ARRAY" ] && [ -n "$MERGE" ] || loud "submission printed no job ids"
check "submission prints how to watch (squeue -j)" grep -q "squeue -j" "$WORK/submit1.txt"
check "array script next to the results, with --requeue and --open-mode=append" \
  grep -q -- "--requeue" "$OUT/slurm/batch.sbatch"

# Requeue task 2 while dataset m6's fit (its second unit) is running, as a preemption or a
# node failure would; cancel task 3 while m7's fit is running, as a time limit would.
if n=$(hold_mid_fit m6 2); then
  scontrol requeue "${ARRAY}_2" && pass "requeued array task 2 in the middle of m6/fit ($n of 10 starts done)"
  # Slurm holds a requeued job back (BeginTime, about 3 min here) once its old allocation
  # has been cleaned up; let it go at once.
  for _ in $(seq 100); do
    job2=$(scontrol show job "${ARRAY}_2" 2>/dev/null)
    if echo "$job2" | grep -q "JobState=PENDING" && echo "$job2" | grep -q "Reason=BeginTime"; then
      scontrol update JobId="${ARRAY}_2" StartTime=now && break
    fi
    sleep 0.2
  done
  say "array task 2: $(scontrol show job "${ARRAY}_2" | grep -o 'JobState=[A-Z_]* Reason=[A-Za-z_]*')"
else
  fail "m6/fit was never held in the middle of its starts (${n:-0} of 10 done when held)"
fi
if n=$(hold_mid_fit m7 3); then
  scancel "${ARRAY}_3" && pass "cancelled array task 3 in the middle of m7/fit ($n of 10 starts done)"
  CANCELLED_AT=$n
else
  fail "m7/fit was never held in the middle of its starts (${n:-0} of 10 done when held)"
  CANCELLED_AT=0
fi
for _ in $(seq 900); do
  [ -z "$(squeue -h -j "$ARRAY" 2>/dev/null)" ] && break
  sleep 0.2
done
check "the array ended" test -z "$(squeue -h -j "$ARRAY" 2>/dev/null)"
sleep 1
check "task 2 ran again after its requeue (its log is appended to)" \
  grep -q "restart 1" "$OUT/slurm/shard-2.log"
check "the requeued task resumed m6/fit from its starts file" \
  grep -q "m6/fit: 10 starts, [0-9]* read back from its starts file (resumed)" "$OUT/slurm/shard-2.log"
check "the requeued task skipped m2, finished before" grep -q "m2/predict: done before, skipped" "$OUT/slurm/shard-2.log"
look_at_unit m7/fit
state7=$UNIT_STATE n7=$N_STARTS
# Interrupted means not done: Slurm signals the step's processes after scancel returns, so
# on a fast machine the fit may have finished its ten starts (and be in its profiles) when
# the kill lands; how many starts it kept is the scheduler's timing, not vanefit's doing.
check "the cancelled unit m7/fit is left interrupted (status '$state7', $n7 of 10 starts kept)" \
  test "$state7" = running -a "$n7" -ge 1
merge_state() { scontrol show job "$MERGE" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }
for _ in $(seq 100); do
  [ "$(merge_state)" = PENDING ] || break
  sleep 0.2
done
say "merge job $MERGE: $(scontrol show job "$MERGE" 2>/dev/null | grep -o 'JobState=[A-Z_]* Reason=[A-Za-z_]*' || echo gone)"
check "the merge job was cancelled, not run, after a cancelled task (afterok, kill-on-invalid-dep)" \
  test "$(merge_state)" = CANCELLED -a ! -e "$OUT/summary.csv"

say "resubmitting with --wait"
(cd "$F" && timeout 150 "$BIN" batch manifest.toml --out "$OUT" --slurm --shards 4 --cpus-per-task 1 --wait) >"$WORK/submit2.txt" 2>&1
rc=$?
cat "$WORK/submit2.txt"
check "resubmission with --wait ended well (exit $rc)" test "$rc" -eq 0
check "task 3 resumed m7/fit from the $CANCELLED_AT+ starts it kept" \
  grep -q "m7/fit: 10 starts, [0-9]* read back from its starts file (resumed)" "$OUT/slurm/shard-3.log"
check "task 3 skipped m3, finished before" grep -q "m3/fit: done before, skipped" "$OUT/slurm/shard-3.log"
check "shard logs carry progress lines (units done/total)" grep -q "shard 1/4 (4/4 units): shard finished" "$OUT/slurm/shard-1.log"
check "the merge job wrote summary.csv, summary.md, fleet.svg" \
  test -s "$OUT/summary.csv" -a -s "$OUT/summary.md" -a -s "$OUT/fleet.svg"

say "the same manifest on this machine, without Slurm"
(cd "$F" && "$BIN" batch manifest.toml --out local --threads 2 >/dev/null 2>"$WORK/local.err" && "$BIN" merge local >/dev/null) \
  || fail "local run: $(tail -3 "$WORK/local.err")"
check "16 units done in the Slurm summary" test "$(grep -c ',done,' "$OUT/summary.csv")" -eq 16
check "summary.csv of the Slurm run == the local run's, byte for byte" cmp "$OUT/summary.csv" "$F/local/summary.csv"
say "a batch with a broken dataset: the array ends well, the merge reports the failure"
mkdir -p "$F/broken"
printf '[motor\n' >"$F/broken/rig.toml"
cat >"$F/failing.toml" <<'EOF'
[batch]
datasets = ["ds/m1", "broken"]
tasks = ["fit"]

[fit]
starts = 2
max_iters = 200
uncertainty = "none"
plots = false
EOF
chmod -R a+rX "$F"
(cd "$F" && timeout 120 "$BIN" batch failing.toml --out "$F/failing" --slurm --wait) >"$WORK/submit3.txt" 2>&1
rc=$?
tail -2 "$WORK/submit3.txt"
check "--wait exits 1 when a unit failed (exit $rc)" test "$rc" -eq 1
check "the merge ran and recorded the failure with its place" \
  grep -q '^broken,fit,failed,.*rig.toml:1:' "$F/failing/summary.csv"
check "the good unit of that batch is done" grep -q '^m1,fit,done,' "$F/failing/summary.csv"
say "took $(($(date +%s) - T0)) s"
finish
