#!/usr/bin/env bash
# Before/after of `mint simplify`: two (or more) binaries interleaved, N
# rounds, wall clock of the whole command with the default summary, on the
# shared meshes at 10% (Igea also at 1%) and a 2M-face sphere to 200k.
#   scripts/bench/simplify_ab.sh N OLD_BIN NEW_BIN ...   (MINT_BENCH_DIR, default /tmp/bench)
set -euo pipefail
N=$1; shift; BINS=("$@")
D="$(cd "$(dirname "$0")/../../.." && pwd)/shared/data"
DIR=${MINT_BENCH_DIR:-/tmp/bench}; mkdir -p "$DIR"
SPH="$DIR/sphere2m.ply"
[ -f "$SPH" ] || "${BINS[0]}" gen sphere "$SPH" --faces 2000000 --quiet
for i in $(seq "$N"); do for b in "${BINS[@]}"; do
  line="$b:"
  for c in "$D/cyberware_horse_mesh/horse.ply 9696" "$D/cyberware_horse_mesh/horse.ply 969" "$D/cyberware_igea_mesh/igea.ply 26868" "$D/cyberware_igea_mesh/igea.ply 2686" "$D/stanford_bunny_zipper_mesh/bun_zipper.ply 6945" "$D/colour_scans/laurana_meshlab/Laurana50k.ply 4995" "$SPH 200000"; do
    set -- $c
    s=$( { /usr/bin/time -f "%e" "$b" simplify "$1" "$DIR/ab.ply" --faces "$2" --quiet --no-color; } 2>&1 | tail -1)
    line="$line $(basename "$1" .ply | cut -c1-6)/$2=$s"
  done
  echo "$line"
done; done
rm -f "$DIR/ab.ply"
