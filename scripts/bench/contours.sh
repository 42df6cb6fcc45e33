#!/usr/bin/env bash
# Issue 6 benchmark: marching cubes over a big contour stack, streamed.
#   scripts/bench/contours.sh [SECTIONS] [VERTICES_PER_SECTION] [CUBES]
#   (default 2000 sections x 500 contour vertices = 1,000,000; 512 cubes)
# The stack: a twisting, breathing ellipse of 400 points with a 100-point
# hole through its middle thousand sections (500 points elsewhere), one
# section per 0.01. One line per run: input -> output size, wall time, peak
# heap (counting allocator) and peak RSS; then the same stack by the angle
# method, and the optimizer on the marching-cubes output.
# MINT_BIN=/path/to/mint uses a binary built elsewhere (else: cargo build).
source "$(dirname "$0")/common.sh"
SECTIONS=${1:-2000}; PER=${2:-500}; CUBES=${3:-512}
if [ -n "${MINT_BIN:-}" ]; then MINT="$MINT_BIN"; else build; fi
machine
PRO="$WORK/stack-$SECTIONS-$PER.pro"
if [ ! -f "$PRO" ]; then
  python3 - "$SECTIONS" "$PER" "$PRO" <<'PY'
import math, sys
n, per, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
hole = per // 5
with open(out, "w") as f:
    f.write(f"pro\n# benchmark stack: {n} sections, {n * per} contour vertices\n")
    for k in range(n):
        z = 0.01 * k
        s = 1.0 + 0.3 * math.sin(z * 0.7)
        th = 0.2 * z
        with_hole = n // 4 <= k < 3 * n // 4
        m = per - hole if with_hole else per
        f.write("section\n")
        for i in range(m):
            t = 2 * math.pi * i / m
            x, y = 2.0 * s * math.cos(t), 1.2 * s * math.sin(t)
            f.write(f"{x * math.cos(th) - y * math.sin(th):.9f} {x * math.sin(th) + y * math.cos(th):.9f} {z:.2f}\n")
        if with_hole:
            f.write("contour\n")
            r = 0.3 + 0.1 * math.sin(z)
            for i in range(hole):
                t = 2 * math.pi * i / hole
                f.write(f"{0.2 + r * math.cos(t):.9f} {r * math.sin(t):.9f} {z:.2f}\n")
PY
fi
echo "input: $PRO ($SECTIONS sections, $((SECTIONS * PER)) contour vertices, $(stat -c %s "$PRO") bytes)"
run() {  # run LABEL OUT ARGS...: one line from the status file and GNU time
  local label=$1 out=$2; shift 2
  local st="$WORK/contours-stats.json" tm="$WORK/contours-time.txt"
  if [ -x /usr/bin/time ]; then /usr/bin/time -f '%e %M' -o "$tm" "$MINT" "$@" --stats "$st" --quiet; else "$MINT" "$@" --stats "$st" --quiet; echo "? 0" > "$tm"; fi
  python3 - "$label" "$st" "$tm" "$out" <<'PY'
import json, os, sys
label, st, tm, out = sys.argv[1:5]
j = json.load(open(st)); wall, rss = open(tm).read().split()
print(f"{label}: {j['input_vertices']} vertices in -> {j['vertices']} vertices, {j['faces']} faces "
      f"({os.path.getsize(out) / 2**20:.0f} MiB), {j['seconds']:.2f}s in the command, {wall}s wall, "
      f"peak heap {j['peak_heap_bytes'] / 2**20:.1f} MiB, peak RSS {int(rss) / 1024:.0f} MiB")
PY
}
MC="$WORK/stack-mc-$CUBES.ply"
run "mc, $CUBES cubes, caps" "$MC" contours "$PRO" "$MC" --method mc --cubes "$CUBES" --caps
python3 -c "import json;d=json.load(open('$WORK/contours-stats.json'))['details'];print(f\"  grid {d['grid_cells']}, non-canonical cells {d['non_canonical_cells']}, S intercepts interpolated {d['s_interpolated']}, midpoint {d['s_midpoint']}\")"
AN="$WORK/stack-angle.ply"
run "angle, caps" "$AN" contours "$PRO" "$AN" --method angle --caps
OPT="$WORK/stack-mc-$CUBES-opt.ply"
run "optimize mc output at 5 degrees" "$OPT" optimize "$MC" "$OPT" --angle 5
"$MINT" check "$MC" | head -1
rm -f "$MC" "$AN" "$OPT" "$WORK/contours-stats.json" "$WORK/contours-time.txt"
