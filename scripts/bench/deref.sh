#!/usr/bin/env bash
# Issue 12 benchmark: dereferencing faces by memory map or by sort, and the
# bounded `mint check`.
#   scripts/bench/deref.sh [FACES] [CELLS] [CGROUP_MIB]
#     (default 100000000 faces, 10000000 cells, a 400 MiB memory cgroup;
#      the runs inside it get --mem of half the cgroup)
# 1. Warm cache: `mint resample --deref mmap|sort` on a torus in generation
#    order and shuffled (`mint gen torus --order shuffled`), beside `cat`.
# 2. Positions larger than the memory the process may use: each run inside a
#    cgroup-v1 memory limit of CGROUP_MIB (page cache included), cold cache.
#    Needs root and /sys/fs/cgroup/memory; skipped with a message otherwise.
#    mmap of the shuffled mesh is stopped after 300 s.
# 3. `mint check --mem 256M` of the ordered torus under prlimit --data=512M.
source "$(dirname "$0")/common.sh"
FACES=${1:-100000000}; CELLS=${2:-10000000}; CG_MIB=${3:-400}
build
IN=$(gen torus "$FACES")
SH="$WORK/torus-$FACES-shuffled.ply"
[ -f "$SH" ] || "$MINT" gen torus "$SH" --faces "$FACES" --order shuffled > /dev/null
machine
echo "input: $IN and $SH ($FACES faces, $(stat -c %s "$IN") bytes each), --cells $CELLS"
line() { python3 - "$@" <<'PY'
import json, sys
name, j = sys.argv[1], json.loads(sys.argv[2])
print("  %s: %.2f s (discretize %.2f s), peak heap %.0f MiB, spilled %.1f GiB; %s" % (name, j["seconds_total"], j["seconds_discretize"], j["peak_heap_bytes"] / 2**20, j["deref_spilled_bytes"] / 2**30, j["deref"]))
PY
}
echo "1. warm cache"
cat "$IN" > /dev/null; echo "  cat: $(seconds cat "$IN") s"
for f in "$IN" "$SH"; do
  for d in mmap sort; do
    cat "$f" > /dev/null
    line "$(basename "$f") --deref $d" "$("$MINT" resample "$f" "$WORK/dr.ply" --cells "$CELLS" --deref "$d" --json --quiet)"
  done
done
MEM=$((CG_MIB / 2))M
echo "2. cold cache, in a ${CG_MIB} MiB memory cgroup (page cache included), --mem $MEM"
CG=/sys/fs/cgroup/memory/mint-bench
if [ "$(id -u)" = 0 ] && [ -d /sys/fs/cgroup/memory ] && mkdir -p "$CG" 2>/dev/null; then
  echo $((CG_MIB << 20)) > "$CG/memory.limit_in_bytes"
  cold() { sync; echo 3 > /proc/sys/vm/drop_caches; }
  cold; echo "  cat (cold, no cgroup): $(seconds cat "$SH") s"
  for run in "$IN mmap" "$SH sort" "$SH auto" "$SH mmap"; do
    set -- $run; cold
    t0=$(date +%s)
    out=$(bash -c "echo \$\$ > $CG/cgroup.procs; exec timeout -s KILL 300 $MINT resample $1 $WORK/dr.ply --cells $CELLS --deref $2 --mem $MEM --json --quiet" 2> "$WORK/dr.err") && rc=0 || rc=$?
    if [ "$rc" = 0 ]; then line "$(basename "$1") --deref $2" "$out"
    elif [ $(( $(date +%s) - t0 )) -ge 300 ]; then echo "  $(basename "$1") --deref $2: stopped after 300 s"
    else echo "  $(basename "$1") --deref $2: failed (exit $rc): $(tail -1 "$WORK/dr.err")"; fi
  done
  rmdir "$CG" 2>/dev/null || true
else
  echo "  skipped: needs root and a cgroup-v1 memory controller at /sys/fs/cgroup/memory"
fi
echo "3. mint check --mem 256M under prlimit --data=512M, warm"
cat "$IN" > /dev/null
timed prlimit --data=536870912 "$MINT" check "$IN" --mem 256M --json > "$WORK/check.json"
python3 - "$WORK/check.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print("  watertight %s, genus %d, spilled %.1f GiB" % (j["watertight"], j["genus_total"], j["spilled_bytes"] / 2**30))
PY
rm -f "$WORK/dr.ply" "$WORK/dr.err" "$WORK/check.json"
