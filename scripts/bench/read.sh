#!/usr/bin/env bash
# Issue 2 benchmark: reading a big binary PLY.
#   scripts/bench/read.sh [FACES]      (default 100000000, ~1.9 GB)
# Prints one line per measurement: cat (the floor), mint info, mint validate
# (a full streaming read with positions resolved), mint check (in-core judge).
source "$(dirname "$0")/common.sh"
FACES=${1:-100000000}
build
IN=$(gen sphere "$FACES")
BYTES=$(stat -c %s "$IN")
machine
echo "input: $IN ($FACES faces, $BYTES bytes)"
cat "$IN" > /dev/null   # warm the page cache
for run in 1 2; do
  t=$(seconds cat "$IN"); echo "cat IN > /dev/null        : ${t}s  $(echo "$BYTES/1000000/$t" | bc) MB/s  $(echo "$FACES/$t/1000000" | bc -l | xargs printf '%.1f') M tri/s-equivalent"
done
t=$(seconds "$MINT" info "$IN"); echo "mint info                 : ${t}s"
for run in 1 2; do
  t=$(seconds "$MINT" validate "$IN" --quiet); echo "mint validate (stream all): ${t}s  $(echo "$BYTES/1000000/$t" | bc) MB/s  $(echo "$FACES/$t/1000000" | bc -l | xargs printf '%.1f') M tri/s"
done
echo -n "mint check                : "; timed "$MINT" check "$IN" --json 2>&1 >/dev/null | tail -1
