#!/usr/bin/env bash
# Range-scan merging benchmarks (issue 7), one line per run:
#   1. pairwise ICP, bun045 -> bun000, from the .conf pose of bun045 moved by
#      a fixed 2° / 2 mm: mint align vs Open3D registration_icp (point to
#      point, same max correspondence distance), time and final RMS;
#   2. the whole bunny: mint align + mint zipper (with consensus) on the 10
#      scans from bun.conf, total time and peak RSS (GNU time).
# Open3D comes from PyPI into scripts/bench/.venv-range; if it cannot be
# installed the Open3D line says so and the rest still runs.
# Usage: scripts/bench/range.sh   (needs ../shared/data)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
data="$root/../shared/data/stanford_bunny_range_scans"
[ -f "$data/bun.conf" ] || { echo "skipped: $data is absent"; exit 0; }
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/work/target-range}"
(cd "$root" && cargo build --release -q)
mint="$CARGO_TARGET_DIR/release/mint"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
for f in "$data"/*.ply; do ln -s "$f" "$tmp/"; done
# bun045 moved by 2° about y and 2 mm along x, relative to bun.conf.
python3 - "$data/bun.conf" "$tmp" <<'PY'
import math, sys
conf, out = sys.argv[1], sys.argv[2]
lines = [l.split() for l in open(conf) if l.startswith("bmesh")]
def qmul(a, b):
    ax, ay, az, aw = a; bx, by, bz, bw = b
    return [aw*bx+ax*bw+ay*bz-az*by, aw*by-ax*bz+ay*bw+az*bx, aw*bz+ax*by-ay*bx+az*bw, aw*bw-ax*bx-ay*by-az*bz]
sets = {}
for l in lines:
    sets[l[1]] = [float(x) for x in l[2:]]
t, q = sets["bun045.ply"][:3], sets["bun045.ply"][3:]
h = math.radians(2.0) / 2
# .conf rotates by the conjugate of q: perturbing the world rotation by D means q' = q * conj(D).
d = [0.0, -math.sin(h), 0.0, math.cos(h)]
q2 = qmul(q, d)
t2 = [t[0] + 0.002, t[1], t[2]]
a = sets["bun000.ply"]
with open(f"{out}/pair.conf", "w") as f:
    f.write("bmesh bun000.ply " + " ".join(map(str, a)) + "\n")
    f.write("bmesh bun045.ply " + " ".join(map(str, t2 + q2)) + "\n")
PY
cp "$data/bun.conf" "$tmp/bun.conf"
t0=$(date +%s.%N)
"$mint" align "$tmp/pair.conf" "$tmp/pair-aligned.conf" --start-distance 0.008 --json > "$tmp/pair.json"
t1=$(date +%s.%N)
python3 - "$tmp/pair.json" "$t0" "$t1" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); s = r["scans"][1]
print(f"pairwise ICP  mint align (Horn, 4 levels)      bun045->bun000  {float(sys.argv[3])-float(sys.argv[2]):.2f}s wall (incl. loading)  rms {s['rms']*1e3:.4f} mm  pairs {s['pairs']}  iterations {s['iterations']}")
PY
venv="$here/.venv-range"
# Open3D needs libusb-1.0 at import (Debian: apt-get install libusb-1.0-0).
if [ ! -x "$venv/bin/python" ]; then python3 -m venv "$venv" >/dev/null 2>&1 && "$venv/bin/pip" -q install open3d >/dev/null 2>&1 || true; fi
if "$venv/bin/python" -c "import open3d" >/dev/null 2>&1; then
  "$venv/bin/python" - "$data" "$tmp/pair.conf" <<'PY'
import sys, time, numpy as np, open3d as o3d
data, conf = sys.argv[1], sys.argv[2]
def pose(vals):
    t = np.array(vals[:3]); x, y, z, w = vals[3:]
    R = np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)], [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)], [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])
    M = np.eye(4); M[:3, :3] = R.T; M[:3, 3] = t; return M
P = {l.split()[1]: pose([float(v) for v in l.split()[2:]]) for l in open(conf)}
def load(n):
    pts = []
    with open(f"{data}/{n}") as f:
        nv = 0
        for line in f:
            if line.startswith("element vertex"): nv = int(line.split()[2])
            if line.startswith("end_header"): break
        for _ in range(nv): pts.append([float(v) for v in f.readline().split()[:3]])
    pc = o3d.geometry.PointCloud(); pc.points = o3d.utility.Vector3dVector(np.array(pts)); return pc
a, b = load("bun000.ply"), load("bun045.ply")
t = time.time()
r = o3d.pipelines.registration.registration_icp(b, a, 0.0015, P["bun045.ply"], o3d.pipelines.registration.TransformationEstimationPointToPoint(), o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=200))
print(f"pairwise ICP  open3d registration_icp (p2p)     bun045->bun000  {time.time()-t:.2f}s (ICP only)  rms {r.inlier_rmse*1e3:.4f} mm  fitness {r.fitness:.3f}")
PY
else
  echo "pairwise ICP  open3d: not installed (pip install open3d failed in $venv)"
fi
/usr/bin/time -f "%e %M" -o "$tmp/t1" "$mint" align "$tmp/bun.conf" "$tmp/aligned.conf" > /dev/null 2> "$tmp/align.log"
/usr/bin/time -f "%e %M" -o "$tmp/t2" "$mint" zipper "$tmp/aligned.conf" "$tmp/bunny.ply" 2> "$tmp/zip.log"
read a_s a_kb < "$tmp/t1"; read z_s z_kb < "$tmp/t2"
echo "whole bunny   10 scans: align ${a_s}s (peak RSS $((a_kb/1024)) MiB), zipper+consensus ${z_s}s (peak RSS $((z_kb/1024)) MiB), total $(python3 -c "print(round($a_s+$z_s,2))")s"
grep -E "zippered|2-manifold|consensus" "$tmp/zip.log" | sed 's/^/  /'
"$mint" distance "$tmp/bunny.ply" "$root/../shared/data/stanford_bunny_zipper_mesh/bun_zipper.ply" --samples 200000 | sed 's/^/  /'
