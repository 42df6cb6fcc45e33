#!/usr/bin/env bash
# `mint check` within its memory bound (issue 12), warm cache, 2 threads:
# `cat IN > /dev/null` (the floor), then `mint check` of the generated
# 100M-face torus in generation order and shuffled (`--order shuffled`),
# each under `prlimit --data=536870912` (512 MiB of heap), RUNS times, with
# per-phase times (MINT_CHECK_TRACE) and the bytes spilled.
# Usage: scripts/bench/check.sh [FACES] [RUNS]
source "$(dirname "$0")/common.sh"
FACES=${1:-100000000}
RUNS=${2:-3}
build
machine
IN=$(gen torus "$FACES")
SH="$WORK/torus-$FACES-shuffled.ply"
[ -f "$SH" ] || "$MINT" gen torus "$SH" --faces "$FACES" --order shuffled > /dev/null
for f in "$IN" "$SH"; do
  echo "== $(basename "$f")"
  cat "$f" > /dev/null
  for r in $(seq "$RUNS"); do
    echo "cat: $(seconds cat "$f") s"
    MINT_CHECK_TRACE=1 prlimit --data=536870912 /usr/bin/time -f 'check: %e s wall, %U s user, %S s system, peak RSS %M KiB' \
      "$MINT" check "$f" --json 2> "$WORK/check.err" > "$WORK/check.json" || { echo "FAILED:"; tail -3 "$WORK/check.err"; continue; }
    grep '^check:' "$WORK/check.err" | tr '\n' ' '
    python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print("| spilled", r.get("spilled_bytes"), "| watertight", r["watertight"], "genus", r["genus_total"])' "$WORK/check.json"
  done
done
rm -f "$WORK/check.err" "$WORK/check.json"
