#!/usr/bin/env bash
# Faults on a cluster (issue 26), on a running cluster (CI runs it on the
# local one, scripts/slurm/local-slurm.sh). Three runs of
# `mint slurm resample … --parts 4 --slabs 4 --wait`, each compared byte for
# byte with a one-process `mint resample` of the same input:
#   1. a discretize task killed with SIGKILL while it writes: the command
#      exits 1 with one line naming the stage and saying the task left no
#      error; the same command again finishes with the same bytes;
#   2. a task that fails by itself (its place taken by a file): the line
#      carries the cause from the task's log; with the cause removed, the
#      same command finishes with the same bytes;
#   3. a task requeued by Slurm (`scontrol requeue`) while it runs: the run
#      finishes by itself with the same bytes.
#   scripts/slurm/faults.sh [FACES]     (default 3000000)
# Needs target/release/mint (built by `cargo test --release` or `cargo build --release`).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
MINT="$ROOT/target/release/mint"
FACES=${1:-3000000}
[ -x "$MINT" ] || (cd "$ROOT" && cargo build --release --quiet)
W=$(mktemp -d "${TMPDIR:-/tmp}/mint-slurm-faults.XXXXXX")
cleanup() {
  # Jobs of this script only (their scripts live under $W).
  for id in $(squeue -h -o '%A %o' 2>/dev/null | awk -v w="$W" 'index($2, w) == 1 {print $1}'); do scancel "$id" 2>/dev/null || true; done
  rm -rf "$W"
}
trap cleanup EXIT
fail() { echo "slurm faults: FAILED: $*" >&2; exit 1; }
"$MINT" gen sphere "$W/in.ply" --faces "$FACES" > /dev/null
"$MINT" resample "$W/in.ply" "$W/one.ply" --cells 8000000 --quiet
run() { # run WORK OUT: the Slurm command, stderr to WORK.err; its status
  "$MINT" slurm resample "$W/in.ply" "$2" --cells 8000000 --work "$1" --parts 4 --slabs 4 --wait --quiet 2> "$1.err"
}
# The pid of a process writing a task of STAGE in WORK (from its temporary
# directory's name, .<task>.tmp-<pid>-<n>); waits up to 60 s.
writer_of() {
  local work=$1 stage=$2 t
  for _ in $(seq 1 6000); do
    for t in "$work/$stage"/.*.tmp-*; do
      [ -e "$t" ] || continue
      t=${t##*.tmp-}
      echo "${t%%-*}"
      return 0
    done
    sleep 0.01
  done
  return 1
}

# 1. SIGKILL in the middle of a task, then the same command again.
t0=$(date +%s.%N)
killed=""
for attempt in 1 2 3 4 5; do
  K="$W/kill$attempt"
  run "$K" "$W/k$attempt.ply" & pid=$!
  if victim=$(writer_of "$K" discretize) && kill -KILL "$victim" 2>/dev/null; then
    if wait "$pid"; then
      continue # the task had finished anyway: the run completed; try again
    fi
    killed=$attempt
    break
  fi
  wait "$pid" || true
done
[ -n "$killed" ] || fail "no discretize task could be killed while it wrote (5 attempts)"
K="$W/kill$killed"
err=$(cat "$K.err")
[ "$(wc -l < "$K.err")" -eq 1 ] || fail "killed task: expected one line, got: $err"
case "$err" in *"stage 'discretize' has 1 of 4 tasks not done"*"left no error in its log"*) ;; *) fail "killed task: $err" ;; esac
[ ! -e "$W/k$killed.ply" ] || fail "killed task: an output was written"
run "$K" "$W/k$killed.ply" || fail "killed task: the same command again failed: $(cat "$K.err")"
cmp "$W/one.ply" "$W/k$killed.ply" || fail "killed task: bytes differ"
t1=$(date +%s.%N)
printf 'slurm faults: a discretize task killed with SIGKILL (attempt %s): one line, then the same command resumed to the same bytes (%.1f s)\n' "$killed" "$(awk "BEGIN{print $t1 - $t0}")"

# 2. A task that fails by itself: census task 2's place is taken by a file.
F="$W/fails"
"$MINT" slurm resample "$W/in.ply" "$W/f.ply" --cells 8000000 --work "$F" --parts 4 --slabs 4 --dry-run > /dev/null
mkdir -p "$F/census"
echo "not a task" > "$F/census/00002"
if run "$F" "$W/f.ply"; then fail "failing task: the run succeeded"; fi
err=$(cat "$F.err")
case "$err" in *"stage 'census' has 1 of 4 tasks not done"*"task 2: "*"00002"*) ;; *) fail "failing task: the cause is not in the line: $err" ;; esac
rm "$F/census/00002"
run "$F" "$W/f.ply" || fail "failing task: the same command again failed: $(cat "$F.err")"
cmp "$W/one.ply" "$W/f.ply" || fail "failing task: bytes differ"
t2=$(date +%s.%N)
printf 'slurm faults: a task failing by itself: its cause in the one line (%s), then resumed to the same bytes (%.1f s)\n' "$(e=${err#*task 2: }; echo "${e%%; see *}")" "$(awk "BEGIN{print $t2 - $t1}")"

# 3. A running task requeued by Slurm.
R="$W/requeue"
run "$R" "$W/r.ply" & pid=$!
writer_of "$R" discretize > /dev/null || fail "requeue: no discretize task started"
job=$(squeue -h -n mint-discretize -t RUNNING -o '%i %o' | awk -v w="$W" 'index($2, w) == 1 {print $1; exit}')
[ -n "$job" ] || fail "requeue: no running discretize task in the queue"
scontrol requeue "$job" || fail "requeue: scontrol requeue $job failed"
# Slurm holds a requeued job back for a while (its begin time moves on);
# let it start again at once.
sleep 1
scontrol update JobId="$job" StartTime=now > /dev/null 2>&1 || true
wait "$pid" || fail "requeue: the run failed after $job was requeued: $(cat "$R.err")"
scontrol show job "$job" | grep -q 'Restarts=1' || fail "requeue: $job did not run again"
cmp "$W/one.ply" "$W/r.ply" || fail "requeue: bytes differ"
t3=$(date +%s.%N)
printf 'slurm faults: task %s requeued while it ran: the run finished by itself with the same bytes (%.1f s)\n' "$job" "$(awk "BEGIN{print $t3 - $t2}")"
