#!/usr/bin/env bash
# Issue 30 benchmark: decimation that keeps thin parts.
#   scripts/bench/thin.sh [intermediates|meshlab|all]     (default all)
# Inputs: three generated thin shapes (mint csg, fine grid: a thin plate with
# holes, a torus whose tube radius is 2% of its size, a branching tree of thin
# cylinders) and the real meshes in ../shared/data (horse, Igea, bunny, the
# Laurana colour scan).
#   meshlab:        mint decimate and mint simplify against MeshLab's quadric
#                   decimation (pymeshlab, default quality settings of
#                   tools/peers/meshlab_decimate.py) at 10%, 1% and 0.1% of the faces;
#   intermediates:  mint decimate to 1% with --intermediate 2N, 4N, ..., 64N
#                   (capped at the input's faces x 16): the error must not grow.
# Error: `mint distance` both ways, 200k samples; the larger mean and max,
# relative to the bounding-box diagonal. MESHLAB_PY (default
# scripts/bench/.venv-tiles/bin/python) must have pymeshlab.
source "$(dirname "$0")/common.sh"
WHAT=${1:-all}
build
PY=${MESHLAB_PY:-$ROOT/scripts/bench/.venv-tiles/bin/python}
DATA="$ROOT/../shared/data"
machine

# The thin shapes, resampled from analytic CSG at a fine grid.
scene() { # name json cell-size (about 300k faces each)
  local out="$WORK/thin-$1.ply"
  if [ ! -f "$out" ]; then
    echo "$2" > "$WORK/thin-$1.json"
    "$MINT" csg "$WORK/thin-$1.json" "$out" --cell-size "$3" --quiet
  fi
  echo "$out"
}
PLATE=$(scene plate '{"difference": [{"box": {"size": [2, 2, 0.03]}},
  {"cylinder": {"radius": 0.3, "height": 1}, "translate": [0.5, 0.5, 0]},
  {"cylinder": {"radius": 0.2, "height": 1}, "translate": [-0.5, 0.4, 0]},
  {"cylinder": {"radius": 0.1, "height": 1}, "translate": [0.3, -0.6, 0]},
  {"box": {"size": [0.6, 0.05, 1]}, "translate": [-0.4, -0.4, 0]}]}' 0.009)
TORUS=$(scene torus '{"torus": {"major": 1, "minor": 0.0416}}' 0.004)
TREE=$(scene tree '{"union": [
  {"cylinder": {"radius": 0.03, "height": 2}},
  {"cylinder": {"radius": 0.02, "height": 1.2}, "rotate": [40, 0, 0], "translate": [0, -0.35, 0.6]},
  {"cylinder": {"radius": 0.02, "height": 1.2}, "rotate": [-40, 0, 0], "translate": [0, 0.35, 0.3]},
  {"cylinder": {"radius": 0.015, "height": 0.8}, "rotate": [0, 45, 0], "translate": [0.25, 0, 0.8]},
  {"cylinder": {"radius": 0.015, "height": 0.8}, "rotate": [0, -45, 0], "translate": [-0.25, 0, -0.2]},
  {"cylinder": {"radius": 0.01, "height": 0.5}, "rotate": [30, 30, 0], "translate": [0.1, -0.5, 1.0]},
  {"cylinder": {"radius": 0.01, "height": 0.5}, "rotate": [-30, -30, 0], "translate": [-0.1, 0.5, 0.7]}]}' 0.003)
INPUTS=("$PLATE" "$TORUS" "$TREE")
for f in cyberware_horse_mesh/horse.ply cyberware_igea_mesh/igea.ply stanford_bunny_zipper_mesh/bun_zipper.ply colour_scans/laurana_meshlab/Laurana50k.ply; do
  [ -f "$DATA/$f" ] && INPUTS+=("$DATA/$f")
done

err() { "$MINT" distance "$1" "$2" --samples 200000 --json | python3 -c "
import json,sys; j=json.load(sys.stdin); a,b=j['a_to_b'],j['b_to_a']
print(f\"{max(a['mean_rel'],b['mean_rel']):.3e} {max(a['max_rel'],b['max_rel']):.3e}\")"; }
faces_of() { "$MINT" validate "$1" --json | python3 -c "import json,sys; print(json.load(sys.stdin)['triangles'])"; }
secs() { python3 -c "import json,sys; print(f\"{json.loads(sys.argv[1])['seconds_total']:.2f}\")" "$1"; }

if [ "$WHAT" = all ] || [ "$WHAT" = meshlab ]; then
  echo
  echo "## mint decimate / mint simplify / MeshLab at 10%, 1%, 0.1% (error: mean, max of the diagonal; ratios to MeshLab)"
  printf '%-14s %8s %7s | %6s %9s %9s | %6s %9s %9s | %6s %9s %9s | %6s %6s %6s %6s\n' input faces target dec_s dec_mean dec_max sim_s sim_mean sim_max ml_s ml_mean ml_max dMean dMax sMean sMax
  for IN in "${INPUTS[@]}"; do
    F=$(faces_of "$IN")
    for pct in 10 1 0.1; do
      T=$(python3 -c "print(max(100, int($F * $pct / 100)))")
      J=$("$MINT" decimate "$IN" "$WORK/td.ply" --faces "$T" --json --quiet --no-color)
      read -r dm dx <<< "$(err "$IN" "$WORK/td.ply")"
      S=$("$MINT" simplify "$IN" "$WORK/ts.ply" --faces "$T" --json --quiet --no-color)
      read -r sm sx <<< "$(err "$IN" "$WORK/ts.ply")"
      K=$("$PY" "$ROOT/tools/peers/meshlab_decimate.py" "$IN" "$WORK/tl.ply" "$T")
      ls=$(python3 -c "import json,sys; print(f\"{json.loads(sys.argv[1])['seconds']:.2f}\")" "$K")
      read -r lm lx <<< "$(err "$IN" "$WORK/tl.ply")"
      r() { python3 -c "print(f'{$1/$2:.2f}')"; }
      printf '%-14s %8s %7s | %6s %9s %9s | %6s %9s %9s | %6s %9s %9s | %6s %6s %6s %6s\n' "$(basename "$IN" .ply)" "$F" "$T" "$(secs "$J")" "$dm" "$dx" "$(secs "$S")" "$sm" "$sx" "$ls" "$lm" "$lx" "$(r "$dm" "$lm")" "$(r "$dx" "$lx")" "$(r "$sm" "$lm")" "$(r "$sx" "$lx")"
    done
  done
fi

if [ "$WHAT" = all ] || [ "$WHAT" = intermediates ]; then
  echo
  echo "## mint decimate to 1% with --intermediate kN (mean error of the diagonal; ratio to the coarser one)"
  for IN in "${INPUTS[@]}"; do
    F=$(faces_of "$IN")
    T=$(python3 -c "print(max(100, int($F / 100)))")
    line="$(basename "$IN" .ply) ($F faces to $T):"
    prev=""
    for k in 2 4 8 16 32 64; do
      M=$((k * T))
      [ "$M" -gt $((16 * F)) ] && break
      if ! "$MINT" decimate "$IN" "$WORK/ti.ply" --faces "$T" --intermediate "$M" --quiet --no-color 2>/dev/null; then
        line="$line  ${k}N (resampling empty: thinner than a cell)"
        continue
      fi
      read -r im ix <<< "$(err "$IN" "$WORK/ti.ply")"
      ratio=""
      [ -n "$prev" ] && ratio=" ($(python3 -c "print(f'{$im/$prev:.2f}')")x)"
      line="$line  ${k}N $im$ratio"
      prev=$im
    done
    echo "$line"
  done
fi
