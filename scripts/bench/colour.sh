#!/usr/bin/env bash
# Issue 27 benchmark: what carrying colour costs.
#   scripts/bench/colour.sh [FACES]            (default 20000000 faces)
# Generates the same sphere of FACES faces without and with per-vertex
# colour (`mint gen sphere --color`: uchar RGB per vertex, binary PLY), and
# times, after `cat` of the same bytes, at two grid sizes (a coarse one,
# where most triangles cross no line and the colour lookups are all
# overhead, and one that gives about a third of the input's faces):
#   - resample geometry only, coloured, and coloured with --no-color;
#   - the coloured run under prlimit --data=256M with --mem 200M (same bytes).
source "$(dirname "$0")/common.sh"
FACES=${1:-20000000}
build
plain="$WORK/sphere-$FACES.ply"
col="$WORK/sphere-$FACES-colour.ply"
[ -f "$plain" ] || "$MINT" gen sphere "$plain" --faces "$FACES" > /dev/null
[ -f "$col" ] || "$MINT" gen sphere "$col" --faces "$FACES" --color > /dev/null
machine
echo "input: $FACES faces; plain $(stat -c %s "$plain") bytes, coloured $(stat -c %s "$col") bytes"
cat "$plain" "$col" > /dev/null
for cells in 10000000 $(( FACES * 25 )); do
  echo "--cells $cells"
  for run in 1 2 3; do
    t=$(seconds cat "$col"); echo "  cat coloured > /dev/null       : ${t}s"
    t=$(seconds "$MINT" resample "$plain" "$WORK/c-plain.ply" --cells "$cells" --quiet); echo "  resample plain                 : ${t}s"
    t=$(seconds "$MINT" resample "$col" "$WORK/c-col.ply" --cells "$cells" --quiet); echo "  resample coloured              : ${t}s"
    t=$(seconds "$MINT" resample "$col" "$WORK/c-nocol.ply" --cells "$cells" --quiet --no-color); echo "  resample coloured --no-color   : ${t}s"
  done
  echo -n "  coloured under prlimit --data=256M --mem 200M: "
  prlimit --data=268435456 "$MINT" resample "$col" "$WORK/c-lim.ply" --cells "$cells" --mem 200M --quiet && cmp "$WORK/c-col.ply" "$WORK/c-lim.ply" && echo "ok, same bytes"
done
