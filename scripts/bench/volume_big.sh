#!/usr/bin/env bash
# Issue 32 benchmark: a volume larger than RAM, cold cache, bounded heap.
#   scripts/bench/volume_big.sh [X,Y,Z] [MEM_LIMIT]   (default 4096,4096,2048: 64 GiB of u16; 512M)
# Generates the field volume (`mint gen volume`, NRRD header + raw, 2 bytes
# per voxel), checks the free disk space first and says what it needs,
# then, each after dropping the page cache (root): `cat RAW > /dev/null`,
# and `mint volume --iso 1000` on the own grid under `prlimit --data`.
# The volume is removed at the end unless KEEP=1.
source "$(dirname "$0")/common.sh"
DIMS=${1:-4096,4096,2048}; LIMIT=${2:-512M}
build
IFS=, read -r X Y Z <<< "$DIMS"
BYTES=$((X * Y * Z * 2))
IN="$WORK/volume-$X-$Y-$Z.nhdr"; RAW="${IN%.nhdr}.raw"
# The volume, and room for shards and output (about 4% of it, measured at 1024^3: 2 GiB in, 150 MB out).
NEED=$((BYTES + BYTES / 16 + (2 << 30)))
FREE=$(df --output=avail -B1 "$WORK" | tail -1)
if [ ! -f "$RAW" ] && [ "$FREE" -lt "$NEED" ]; then
  echo "volume_big.sh: $DIMS u16 needs about $((NEED >> 30)) GiB free in $WORK; $((FREE >> 30)) GiB are free (give smaller dimensions)" >&2; exit 1
fi
machine
[ -f "$RAW" ] || { echo "generating $IN"; timed "$MINT" gen volume "$IN" --dims "$DIMS" --type u16 > /dev/null; }
echo "input: $RAW ($(stat -c %s "$RAW") bytes), RAM $(awk '/MemTotal/{printf "%.1f GiB", $2/1048576}' /proc/meminfo)"
cold() { sync; if [ "$(id -u)" = 0 ]; then echo 3 > /proc/sys/vm/drop_caches 2>/dev/null || echo "(cache not dropped)"; else echo "(not root: cache not dropped)"; fi; }
cold; echo "cat RAW > /dev/null, cold: $(seconds cat "$RAW") s"
cold
MEMB=$(numfmt --from=iec "$LIMIT")
timed prlimit --data="$MEMB" "$MINT" volume "$IN" "$WORK/volume-big-out.ply" --iso 1000 --mem $((MEMB * 3 / 4)) --json --quiet > "$WORK/volume-big.json"
python3 -c 'import json; j=json.load(open("'"$WORK/volume-big.json"'")); print("mint volume, cold: %.1f s (discretize %.1f, reconstruct %.1f, write %.1f), peak heap %.0f MiB, peak RSS %.0f MiB, output %d faces, %d slabs" % (j["seconds_total"], j["seconds_discretize"], j["seconds_reconstruct"], j["seconds_write"], j["peak_heap_bytes"]/2**20, j["peak_rss_bytes"]/2**20, j["output_faces"], j["slabs"]))'
"$MINT" check "$WORK/volume-big-out.ply" --mem 2G | head -1
rm -f "$WORK/volume-big-out.ply" "$WORK/volume-big.json"
[ "${KEEP:-0}" = 1 ] || rm -f "$IN" "$RAW"
