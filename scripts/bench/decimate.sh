#!/usr/bin/env bash
# Issue 14 benchmark: mint decimate against MeshLab's quadric decimation of the whole input
# (pymeshlab, in scripts/bench/.venv, installed on first use), at the same face counts.
#   scripts/bench/decimate.sh [SPHERE_FACES]     (default 22000000)
#   MESHLAB_MAX_FACES=N skips MeshLab on inputs of more than N faces (its columns print -).
# Inputs: a generated sphere and the real meshes in ../shared/data (bunny, horse, igea), each to
# 1% and 0.1% of its faces. Error: Metro-style mean and max distance both ways (`mint distance`,
# 200k samples), relative to the bounding-box diagonal. One line per run.
source "$(dirname "$0")/common.sh"
SPHERE=${1:-22000000}
build
VENV="$ROOT/scripts/bench/.venv"
if ! "$VENV/bin/python" -c "import pymeshlab" 2>/dev/null; then
  python3 -m venv "$VENV" && "$VENV/bin/pip" install -q pymeshlab
fi
DATA="$ROOT/../shared/data"
machine
INPUTS=("$(gen sphere "$SPHERE")")
for f in stanford_bunny_zipper_mesh/bun_zipper.ply cyberware_horse_mesh/horse.ply cyberware_igea_mesh/igea.ply; do
  [ -f "$DATA/$f" ] && INPUTS+=("$DATA/$f")
done
err() { "$MINT" distance "$1" "$2" --samples 200000 --json | python3 -c "
import json,sys; j=json.load(sys.stdin); a,b=j['a_to_b'],j['b_to_a']
print(f\"{max(a['mean_rel'],b['mean_rel']):.3e} {max(a['max_rel'],b['max_rel']):.3e}\")"; }
printf '%-16s %10s %9s | %8s %9s %10s %10s | %8s %9s %10s %10s\n' input faces target mint_s mint_heap mint_mean mint_max meshlab_s ml_rss ml_mean ml_max
for IN in "${INPUTS[@]}"; do
  F=$("$MINT" validate "$IN" --json | python3 -c "import json,sys; print(json.load(sys.stdin)['triangles'])")
  for pct in 1 0.1; do
    T=$(python3 -c "print(max(100, int($F * $pct / 100)))")
    J=$("$MINT" decimate "$IN" "$WORK/dm.ply" --faces "$T" --json --quiet)
    read -r ms mh <<< "$(python3 -c "import json,sys; j=json.loads(sys.argv[1]); print(f\"{j['seconds_total']:.2f} {j['peak_heap_bytes']/2**20:.0f}MiB\")" "$J")"
    read -r me mx <<< "$(err "$IN" "$WORK/dm.ply")"
    if [ "$F" -le "${MESHLAB_MAX_FACES:-1000000000}" ]; then
      K=$("$VENV/bin/python" "$ROOT/tools/peers/meshlab_decimate.py" "$IN" "$WORK/dl.ply" "$T")
      read -r ls lr <<< "$(python3 -c "import json,sys; j=json.loads(sys.argv[1]); print(f\"{j['seconds']:.2f} {j['peak_rss_kib']/1024:.0f}MiB\")" "$K")"
      read -r le lx <<< "$(err "$IN" "$WORK/dl.ply")"
    else
      ls=-; lr=-; le=-; lx=-  # MESHLAB_MAX_FACES: MeshLab skipped (the 22M sphere takes it ~10 min)
    fi
    printf '%-16s %10s %9s | %8s %9s %10s %10s | %8s %9s %10s %10s\n' "$(basename "$IN")" "$F" "$T" "$ms" "$mh" "$me" "$mx" "$ls" "$lr" "$le" "$lx"
  done
done
rm -f "$WORK/dm.ply" "$WORK/dl.ply"
