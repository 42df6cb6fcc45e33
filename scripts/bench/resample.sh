#!/usr/bin/env bash
# Issue 3 benchmark: out-of-core resampling of a big generated mesh.
#   scripts/bench/resample.sh [FACES] [CELLS...]   (default 100000000; 1e6 and 1e7 cells)
# For each grid: wall time per phase, input triangles/s, peak heap (counting
# allocator) and peak RSS, next to `cat IN > /dev/null` in the same run.
source "$(dirname "$0")/common.sh"
FACES=${1:-100000000}; shift || true
CELLS=("${@:-1000000 10000000}"); [ $# -gt 0 ] && CELLS=("$@") || CELLS=(1000000 10000000)
build
IN=$(gen sphere "$FACES")
BYTES=$(stat -c %s "$IN")
machine
echo "input: $IN ($FACES faces, $BYTES bytes)"
cat "$IN" > /dev/null
t=$(seconds cat "$IN"); echo "cat IN > /dev/null: ${t}s"
for c in "${CELLS[@]}"; do
  OUT="$WORK/resampled-$c.ply"
  J=$("$MINT" resample "$IN" "$OUT" --cells "$c" --json --quiet)
  python3 - "$c" "$FACES" <<PY "$J"
import json,sys
c, faces = sys.argv[1], int(sys.argv[2])
j = json.loads(sys.argv[3])
print(f"cells {c:>9}: grid {'x'.join(map(str,j['grid_cells']))}, {j['output_faces']} faces out, "
      f"total {j['seconds_total']:.2f}s (bounds {j['seconds_bounds']:.2f}, discretize {j['seconds_discretize']:.2f}, "
      f"reconstruct {j['seconds_reconstruct']:.2f}, write {j['seconds_write']:.2f}), "
      f"{faces/j['seconds_total']/1e6:.1f} M tri/s, peak heap {j['peak_heap_bytes']/2**20:.0f} MiB, "
      f"peak RSS {j['peak_rss_bytes']/2**20:.0f} MiB, non-canonical {j['non_canonical_cells']}")
PY
  rm -f "$OUT"
done
