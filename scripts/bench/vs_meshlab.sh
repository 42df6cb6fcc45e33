#!/usr/bin/env bash
# mint resample vs MeshLab's uniform mesh resampling (pymeshlab), same input,
# same cell size, same run: time, peak RSS, output faces, watertightness.
#   scripts/bench/vs_meshlab.sh [CELLS] [INPUT...]
# Defaults: 1e6 cells; a 1M- and a 10M-face generated torus plus the real
# horse and igea scans when ../shared/data exists. (MeshLab runs out of memory
# on mint's generated UV spheres, whose poles have vertices of very high
# valence; pass a sphere explicitly to see it.) pymeshlab is installed in
# scripts/bench/.venv on first use. MeshLab runs under `ulimit -v 16G`.
source "$(dirname "$0")/common.sh"
CELLS=${1:-1000000}; shift || true
build
VENV="$ROOT/scripts/bench/.venv"
if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c 'import pymeshlab' 2>/dev/null; then
  python3 -m venv "$VENV" && "$VENV/bin/pip" install -q pymeshlab
fi
INPUTS=("$@")
if [ ${#INPUTS[@]} -eq 0 ]; then
  INPUTS=("$(gen torus 1000000)" "$(gen torus 10000000)")
  D="$ROOT/../shared/data"
  [ -d "$D" ] && INPUTS+=("$D/cyberware_horse_mesh/horse.ply" "$D/cyberware_igea_mesh/igea.ply")
fi
machine
echo "cells: $CELLS"
for IN in "${INPUTS[@]}"; do
  cat "$IN" > /dev/null
  base=$(basename "$IN" .ply)
  MO="$WORK/$base-mint.ply"; LO="$WORK/$base-meshlab.ply"
  J=$(/usr/bin/time -f '%M' -o "$WORK/rss" "$MINT" resample "$IN" "$MO" --cells "$CELLS" --json --quiet)
  MRSS=$(cat "$WORK/rss")
  H=$(python3 -c "import json,sys; print(json.loads(sys.argv[1])['cell_size'])" "$J")
  L=$( (ulimit -v 16000000; /usr/bin/time -f '%M' -o "$WORK/rss" "$VENV/bin/python" "$ROOT/tools/peers/meshlab_resample.py" "$IN" "$LO" "$H" 2>/dev/null | tail -1) || true)
  LRSS=$(tail -1 "$WORK/rss")
  [ -n "$L" ] || L='{"seconds": -1, "faces": 0}'
  MW=$("$MINT" check "$MO" --json | python3 -c "import json,sys; j=json.load(sys.stdin); print('watertight' if j['watertight'] else 'NOT watertight (%d boundary, %d non-manifold edges)' % (j['boundary_edges'], j['non_manifold_edges']))")
  LW="failed (out of memory at 16 GB?)"
  [ -f "$LO" ] && LW=$("$MINT" check "$LO" --json | python3 -c "import json,sys; j=json.load(sys.stdin); print('watertight' if j['watertight'] else 'NOT watertight (%d boundary, %d non-manifold edges)' % (j['boundary_edges'], j['non_manifold_edges']))")
  python3 - "$base" "$J" "$MRSS" "$L" "$LRSS" "$MW" "$LW" <<'PY'
import json, sys
name, j, mrss, l, lrss, mw, lw = sys.argv[1], json.loads(sys.argv[2]), int(sys.argv[3]), json.loads(sys.argv[4]), int(sys.argv[5]), sys.argv[6], sys.argv[7]
print(f"{name}: cell {j['cell_size']:.6g}")
print(f"  mint    {j['seconds_total']:7.2f}s  peak RSS {mrss/1024:7.0f} MiB (heap {j['peak_heap_bytes']/2**20:.0f} MiB)  {j['output_faces']:>9} faces  {mw}")
print(f"  meshlab {l['seconds']:7.2f}s  peak RSS {lrss/1024:7.0f} MiB                  {l['faces']:>9} faces  {lw}")
PY
  rm -f "$MO" "$LO" "$WORK/rss"
done
