#!/usr/bin/env bash
# The shape of the paper's Table 1: one input at about 10k, 100k, 1M and 10M
# cells, with output faces and time for each.
#   scripts/bench/table1.sh [INPUT]   (default: a generated 10M-face genus-3 solid)
source "$(dirname "$0")/common.sh"
build
IN=${1:-$(gen genus 10000000)}
machine
echo "input: $IN"
printf '%10s %14s %12s %10s\n' cells grid out_faces seconds
for c in 10000 100000 1000000 10000000; do
  OUT="$WORK/t1-$c.ply"
  J=$("$MINT" resample "$IN" "$OUT" --cells "$c" --json --quiet)
  python3 -c "import json,sys; j=json.loads(sys.argv[1]); print('%10s %14s %12d %10.2f' % (sys.argv[2], 'x'.join(map(str,j['grid_cells'])), j['output_faces'], j['seconds_total']))" "$J" "$c"
  rm -f "$OUT"
done
