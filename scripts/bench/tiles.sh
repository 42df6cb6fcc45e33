#!/usr/bin/env bash
# Issue 28 benchmark: several files as one surface, and glTF reading.
#   scripts/bench/tiles.sh [FACES] [TILES]     (default 20000000 faces, 64 tiles)
# Cuts a generated sphere of FACES faces into TILES spatial binary-PLY tiles
# (tools/split_tiles.py, numpy in scripts/bench/.venv-tiles; each face in
# one tile, each tile with its own vertices), and times, after `cat` of the
# same bytes:
#   - resample of the whole file against the tiles as a directory (same bytes);
#   - the tiles as OBJ, --parts 1 against --parts 2 (one part per file group);
#   - `mint validate` of the whole file as GLB against binary PLY, and the GLB
#     under prlimit --data=256M.
source "$(dirname "$0")/common.sh"
FACES=${1:-20000000}
TILES=${2:-64}
CELLS=${CELLS:-20000000}
build
D="$WORK/tiles-$FACES-$TILES"
mkdir -p "$D/ply" "$D/obj"
VENV="$ROOT/scripts/bench/.venv-tiles"
[ -x "$VENV/bin/python" ] || { python3 -m venv "$VENV" && "$VENV/bin/pip" install -q numpy; }
[ -f "$D/whole.ply" ] || "$MINT" gen sphere "$D/whole.ply" --faces "$FACES" > /dev/null
SIDE=$(python3 -c "import math; print(round(math.sqrt($TILES)))")
[ -n "$(ls "$D/ply")" ] || "$VENV/bin/python" "$ROOT/tools/split_tiles.py" "$D/whole.ply" "$D/ply" "$SIDE"
for f in "$D"/ply/*.ply; do
  o="$D/obj/$(basename "$f" .ply).obj"
  [ -f "$o" ] || "$MINT" convert "$f" "$o" --double --quiet
done
per="$(( FACES / TILES )) (about)"
[ -f "$D/whole.glb" ] || "$MINT" convert "$D/whole.ply" "$D/whole.glb" --quiet
machine
echo "input: $TILES tiles of $per faces; whole.ply $(stat -c %s "$D/whole.ply") bytes; obj tiles $(du -sb "$D/obj" | cut -f1) bytes"
cat "$D"/ply/* "$D/whole.ply" "$D/whole.glb" "$D"/obj/* > /dev/null
for run in 1 2; do
  t=$(seconds cat "$D/whole.ply"); echo "cat whole.ply > /dev/null          : ${t}s"
  t=$(seconds "$MINT" resample "$D/whole.ply" "$D/o-whole.ply" --cells "$CELLS" --quiet); echo "resample whole.ply                 : ${t}s"
  t=$(seconds "$MINT" resample "$D/ply" "$D/o-tiles.ply" --cells "$CELLS" --quiet); echo "resample ply/ ($TILES tiles)          : ${t}s"
  cmp "$D/o-whole.ply" "$D/o-tiles.ply" && echo "  same bytes"
  t=$(seconds cat "$D"/obj/*); echo "cat obj/* > /dev/null              : ${t}s"
  for p in 1 2; do
    t=$(seconds "$MINT" resample "$D/obj" "$D/o-obj$p.ply" --cells "$CELLS" --parts "$p" --quiet); echo "resample obj/ --parts $p            : ${t}s"
  done
  cmp "$D/o-whole.ply" "$D/o-obj2.ply" && echo "  same bytes (obj tiles, 2 parts)"
  t=$(seconds cat "$D/whole.glb"); echo "cat whole.glb > /dev/null          : ${t}s"
  t=$(seconds "$MINT" validate "$D/whole.ply" --quiet); echo "validate whole.ply                 : ${t}s"
  t=$(seconds "$MINT" validate "$D/whole.glb" --quiet); echo "validate whole.glb                 : ${t}s"
done
echo -n "validate whole.glb under prlimit --data=256M: "
prlimit --data=268435456 "$MINT" validate "$D/whole.glb" --quiet && echo ok
