#!/usr/bin/env bash
# Issue 12 benchmark: a mesh larger than RAM, cold cache.
#   scripts/bench/giant.sh [FACES] [ORDER]   (default 1500000000 faces, in-order; ORDER: in-order|shuffled)
# Generates a torus of FACES faces (19 bytes per face: about 28.5 GB for
# 1.5 billion), checks the free disk space first and says what it needs,
# then, each after dropping the page cache (root): `cat IN > /dev/null`,
# and `mint resample --cells 10000000` under `prlimit --data=268435456`
# (256 MiB of heap). The input is removed at the end unless KEEP=1.
source "$(dirname "$0")/common.sh"
FACES=${1:-1500000000}; ORDER=${2:-in-order}
build
IN="$WORK/giant-$FACES-$ORDER.ply"
NEED=$((FACES * 19 + (1 << 30)))
FREE=$(df --output=avail -B1 "$WORK" | tail -1)
if [ ! -f "$IN" ] && [ "$FREE" -lt "$NEED" ]; then
  echo "giant.sh: $FACES faces need about $((NEED >> 30)) GiB free in $WORK; $((FREE >> 30)) GiB are free" >&2; exit 1
fi
machine
[ -f "$IN" ] || { echo "generating $IN"; timed "$MINT" gen torus "$IN" --faces "$FACES" --order "$ORDER" > /dev/null; }
echo "input: $IN ($(stat -c %s "$IN") bytes), RAM $(awk '/MemTotal/{printf "%.1f GiB", $2/1048576}' /proc/meminfo)"
cold() { sync; if [ "$(id -u)" = 0 ]; then echo 3 > /proc/sys/vm/drop_caches; else echo "(not root: cache not dropped)"; fi; }
cold; echo "cat IN > /dev/null, cold: $(seconds cat "$IN") s"
cold
timed prlimit --data=268435456 "$MINT" resample "$IN" "$WORK/giant-out.ply" --cells 10000000 --mem 200M --json --quiet > "$WORK/giant.json"
python3 -c 'import json; j=json.load(open("'"$WORK/giant.json"'")); print("mint resample, cold: %.1f s (bounds %.1f, discretize %.1f, census %.1f, reconstruct %.1f, write %.1f), peak heap %.0f MiB, output %d faces; %s" % (j["seconds_total"], j["seconds_bounds"], j["seconds_discretize"], j["seconds_census"], j["seconds_reconstruct"], j["seconds_write"], j["peak_heap_bytes"]/2**20, j["output_faces"], j["deref"]))'
rm -f "$WORK/giant-out.ply" "$WORK/giant.json"
[ "${KEEP:-0}" = 1 ] || rm -f "$IN"
