#!/usr/bin/env bash
# Issue 5 benchmark: union and difference of two generated meshes of 1M and
# 10M faces each, mint bool vs Manifold (PyPI manifold3d, installed by this
# script in scripts/bench/.venv), same inputs, same run.
#   scripts/bench/bool.sh [CELLS]     (default 1000000 cells for mint)
# Manifold is exact (it computes the true mesh boolean and keeps all input
# detail); mint resamples the result on a grid of CELLS cells: its output
# size follows the grid and its error is bounded by the cell.
source "$(dirname "$0")/common.sh"
CELLS=${1:-1000000}
build
VENV="$ROOT/scripts/bench/.venv"
if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c 'import manifold3d, numpy' 2>/dev/null; then
  python3 -m venv "$VENV" && "$VENV/bin/pip" install -q manifold3d numpy
fi
machine
for F in 1000000 10000000; do
  A="$WORK/bool-torus-$F.ply"; B="$WORK/bool-sphere-$F.ply"
  [ -f "$A" ] || "$MINT" gen torus "$A" --faces "$F" > /dev/null 2>&1
  [ -f "$B" ] || "$MINT" gen sphere "$B" --faces "$F" > /dev/null 2>&1
  cat "$A" "$B" > /dev/null
  for OP in union difference; do
    MO="$WORK/bool-mint.ply"; LO="$WORK/bool-manifold.ply"
    J=$(/usr/bin/time -f '%M' -o "$WORK/rss" "$MINT" bool $OP "$A" "$B" "$MO" --cells "$CELLS" --json --quiet)
    MRSS=$(cat "$WORK/rss")
    L=$(/usr/bin/time -f '%M' -o "$WORK/rss" "$VENV/bin/python" "$ROOT/tools/peers/manifold_bool.py" "$A" "$B" $OP "$LO" | tail -1)
    LRSS=$(tail -1 "$WORK/rss")
    MW=$("$MINT" check "$MO" --json | python3 -c "import json,sys; j=json.load(sys.stdin); print('watertight' if j['watertight'] else 'NOT watertight', '%.5f' % j['signed_volume'])")
    LW=$("$MINT" check "$LO" --json | python3 -c "import json,sys; j=json.load(sys.stdin); print('watertight' if j['watertight'] else 'NOT watertight', '%.5f' % j['signed_volume'])")
    python3 - "$F" "$OP" "$J" "$MRSS" "$L" "$LRSS" "$MW" "$LW" <<'PY'
import json, sys
f, op, j, mrss, l, lrss, mw, lw = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), int(sys.argv[4]), json.loads(sys.argv[5]), int(sys.argv[6]), sys.argv[7], sys.argv[8]
print(f"{int(f)//1000000}M+{int(f)//1000000}M faces, {op}:")
print(f"  mint     {j['seconds_total']:7.2f}s  peak RSS {mrss/1024:6.0f} MiB (heap {j['peak_heap_bytes']/2**20:.0f} MiB)  {j['output_faces']:>9} faces  {mw}")
print(f"  manifold {l['seconds']:7.2f}s  peak RSS {lrss/1024:6.0f} MiB  (boolean alone {l['boolean']:.2f}s)  {l['faces']:>9} faces  {lw}")
PY
    rm -f "$MO" "$LO" "$WORK/rss"
  done
done
