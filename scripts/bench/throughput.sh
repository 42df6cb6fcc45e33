#!/usr/bin/env bash
# Issue 12 benchmark: resampling at read speed, in any vertex order.
#   scripts/bench/throughput.sh [FACES] [CELLS]   (default 100000000 faces, 10000000 cells)
# Warm cache, 2 threads: `cat IN > /dev/null` (the floor), `mint resample` of a generated
# torus in generation order and the same torus with vertices and faces shuffled
# (`mint gen torus --order shuffled`); median of 5 runs each, with per-phase times.
source "$(dirname "$0")/common.sh"
FACES=${1:-100000000}; CELLS=${2:-10000000}
build
IN=$(gen torus "$FACES")
SH="$WORK/torus-$FACES-shuffled.ply"
[ -f "$SH" ] || "$MINT" gen torus "$SH" --faces "$FACES" --order shuffled > /dev/null
machine
echo "input: $IN and $SH ($FACES faces, $(stat -c %s "$IN") bytes each), --cells $CELLS"
median() { sort -n | awk '{a[NR]=$1} END{print a[int((NR+1)/2)]}'; }
cat "$IN" > /dev/null
C=$(for i in 1 2 3 4 5; do seconds cat "$IN"; echo; done | median)
echo "cat IN > /dev/null: ${C} s (median of 5)"
for f in "$IN" "$SH"; do
  cat "$f" > /dev/null
  ts=(); last=""
  for i in 1 2 3 4 5; do
    t0=$(date +%s.%N)
    last=$("$MINT" resample "$f" "$WORK/tp.ply" --cells "$CELLS" --json --quiet)
    t1=$(date +%s.%N)
    ts+=("$(awk "BEGIN{printf \"%.3f\", $t1 - $t0}")")
  done
  m=$(printf '%s\n' "${ts[@]}" | median)
  python3 - "$f" "$m" "$C" "$FACES" "$last" "${ts[*]}" <<'PY'
import json, sys
f, m, c, faces, j, runs = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]), json.loads(sys.argv[5]), sys.argv[6]
print(f"{f.split('/')[-1]}: {m:.2f} s median ({m/c:.1f}x cat, {faces/m/1e6:.0f} M tri/s; runs {runs}); last run: bounds {j['seconds_bounds']:.2f}, "
      f"discretize {j['seconds_discretize']:.2f}, census {j['seconds_census']:.2f}, reconstruct {j['seconds_reconstruct']:.2f}, write {j['seconds_write']:.2f}, "
      f"peak heap {j['peak_heap_bytes']/2**20:.0f} MiB")
PY
done
rm -f "$WORK/tp.ply"
