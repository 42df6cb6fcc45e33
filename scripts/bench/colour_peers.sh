#!/usr/bin/env bash
# Issue 27 benchmark, against MeshLab: colour through decimation and the
# colour error of resampling.
#   scripts/bench/colour_peers.sh [FACES]       (default 2000000)
# Needs numpy, scipy and pymeshlab in scripts/bench/.venv-tiles (installed
# here when missing). For each per-vertex-coloured scan of
# ../shared/data/colour_scans (RGB-D object, Laurana) and a coloured
# `mint gen sphere` of FACES faces: `mint decimate` and MeshLab's quadric
# edge collapse (tools/peers/meshlab_decimate.py, colour kept per vertex) to
# 10% and 1% of the faces, with the time and the mean ΔE of
# tools/colour_metrics.py (the input's colour at the nearest point as
# truth), and `mint resample` at two grid sizes against the ideal transfer,
# also of the two textured OBJ scans (Pillow decodes their textures).
source "$(dirname "$0")/common.sh"
FACES=${1:-2000000}
build
VENV="$ROOT/scripts/bench/.venv-tiles"
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
"$VENV/bin/python" -c "import numpy, scipy, pymeshlab, PIL" 2> /dev/null || "$VENV/bin/pip" install -q numpy scipy pymeshlab pillow
PY="$VENV/bin/python"
DATA="$ROOT/../shared/data/colour_scans"
sphere="$WORK/sphere-$FACES-colour.ply"
[ -f "$sphere" ] || "$MINT" gen sphere "$sphere" --faces "$FACES" --color > /dev/null
machine
de() { "$PY" "$ROOT/tools/colour_metrics.py" "$1" "$2" 100000 | "$PY" -c "import json,sys; d=json.load(sys.stdin); print(f\"ΔE {d['delta_e_mean']:.3f} (ideal {d['ideal_delta_e_mean']:.3f}, ratio {d['ratio_to_ideal']:.2f})\")"; }
faces_of() { "$PY" -c "import re,sys; d=open(sys.argv[1],'rb').read(4096).decode('latin1'); print(re.search(r'element face (\d+)', d).group(1))" "$1"; }
for IN in "$DATA/rgbd_object_iory/obj.ply" "$DATA/laurana_meshlab/Laurana50k.ply" "$sphere"; do
  n=$(faces_of "$IN")
  echo "== $(basename "$(dirname "$IN")")/$(basename "$IN"): $n faces"
  for pct in 10 1; do
    t=$(( n * pct / 100 ))
    s=$(seconds "$MINT" decimate "$IN" "$WORK/cp-mint.ply" --faces "$t" --quiet)
    echo "  decimate $pct% ($t faces)  mint    ${s}s  $(de "$IN" "$WORK/cp-mint.ply")"
    s=$(seconds "$PY" "$ROOT/tools/peers/meshlab_decimate.py" "$IN" "$WORK/cp-ml.ply" "$t")
    echo "  decimate $pct% ($t faces)  MeshLab ${s}s  $(de "$IN" "$WORK/cp-ml.ply")"
  done
  [ "$IN" = "$sphere" ] && continue
  for cells in 200000 2000000; do
    "$MINT" resample "$IN" "$WORK/cp-res.ply" --cells "$cells" --quiet
    echo "  resample --cells $cells  $(de "$IN" "$WORK/cp-res.ply")"
  done
done
for IN in "$DATA/meshroom_esp32cam/texturedMesh.obj" "$DATA/copyroom_planeopt/copyroom_c2000_opt.obj"; do
  echo "== $(basename "$(dirname "$IN")")/$(basename "$IN") (textured)"
  for cells in 200000 2000000; do
    "$MINT" resample "$IN" "$WORK/cp-res.ply" --cells "$cells" --quiet 2> /dev/null
    echo "  resample --cells $cells  $(de "$IN" "$WORK/cp-res.ply")"
  done
done
