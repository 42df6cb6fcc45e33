#!/usr/bin/env bash
# Range-scan merging benchmarks (issue 7).
#   1. Pairwise ICP on the bunny scans, around the ring bun000 -> bun045 ->
#      bun090 -> bun180 -> bun270 -> bun315 -> bun000: the source scan starts
#      from its bun.conf pose moved by 2° about a fixed axis and 2 mm; mint
#      align and Open3D's registration_icp (point to point, max
#      correspondence distance 1.5 mm, 200 iterations) run from the same
#      start. Reported per pair: time, each tool's own RMS, and the common
#      measure — the error of the final pose against bun.conf (rotation in
#      degrees, displacement of the scan's centroid in mm).
#   2. The whole bunny, 10 scans from bun.conf: mint align, then mint
#      zipper (with consensus geometry), then mint zipper --method grid;
#      time and peak RSS of each (GNU time), and the distance to
#      bun_zipper.ply.
# Open3D comes from PyPI into scripts/bench/.venv-range; it needs Debian's
# libusb-1.0-0 at import, installed here with apt-get when missing (as root
# or through sudo). If either cannot be installed the Open3D column says so
# and the rest still runs.
# Usage: scripts/bench/range.sh   (needs ../shared/data)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
data="$root/../shared/data/stanford_bunny_range_scans"
[ -f "$data/bun.conf" ] || { echo "skipped: $data is absent"; exit 0; }
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
(cd "$root" && cargo build --release -q)
mint="$CARGO_TARGET_DIR/release/mint"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
for f in "$data"/*.ply; do ln -s "$f" "$tmp/"; done
cp "$data/bun.conf" "$tmp/bun.conf"

venv="$here/.venv-range"
if ! ldconfig -p 2>/dev/null | grep -q libusb-1.0; then
  if [ "$(id -u)" = 0 ]; then apt-get install -y -q libusb-1.0-0 >/dev/null 2>&1 || true
  elif command -v sudo >/dev/null; then sudo -n apt-get install -y -q libusb-1.0-0 >/dev/null 2>&1 || true; fi
fi
if [ ! -x "$venv/bin/python" ]; then python3 -m venv "$venv" >/dev/null 2>&1 && "$venv/bin/pip" -q install open3d >/dev/null 2>&1 || true; fi
py=python3
if "$venv/bin/python" -c "import open3d" >/dev/null 2>&1; then py="$venv/bin/python"; fi

echo "== pairwise ICP (start: bun.conf pose moved by 2 deg and 2 mm) =="
"$py" - "$mint" "$data" "$tmp" <<'PY'
import json, math, subprocess, sys, time
mint, data, tmp = sys.argv[1:4]
try:
    import numpy as np, open3d as o3d
except Exception:
    np = o3d = None
conf = {l.split()[1]: [float(v) for v in l.split()[2:]] for l in open(f"{data}/bun.conf") if l.startswith("bmesh")}

def qmul(a, b):
    ax, ay, az, aw = a; bx, by, bz, bw = b
    return [aw*bx+ax*bw+ay*bz-az*by, aw*by-ax*bz+ay*bw+az*bx, aw*bz+ax*by-ay*bx+az*bw, aw*bw-ax*bx-ay*by-az*bz]
def mat(vals):
    # 4x4 pose (scan frame -> world) of a .conf line, as mint reads it.
    t = vals[:3]; x, y, z, w = vals[3:]
    R = [[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)], [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)], [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]]
    Rt = [[R[j][i] for j in range(3)] for i in range(3)]
    return [Rt[0] + [t[0]], Rt[1] + [t[1]], Rt[2] + [t[2]], [0, 0, 0, 1]]
def mul(A, B): return [[sum(A[i][k]*B[k][j] for k in range(4)) for j in range(4)] for i in range(4)]
def inv(M):
    R = [[M[j][i] for j in range(3)] for i in range(3)]; t = [M[i][3] for i in range(3)]
    ti = [-sum(R[i][k]*t[k] for k in range(3)) for i in range(3)]
    return [R[0] + [ti[0]], R[1] + [ti[1]], R[2] + [ti[2]], [0, 0, 0, 1]]
def apply(M, p): return [sum(M[i][k]*p[k] for k in range(3)) + M[i][3] for i in range(3)]
def load_pts(n):
    pts = []
    with open(f"{data}/{n}") as f:
        nv = 0
        for line in f:
            if line.startswith("element vertex"): nv = int(line.split()[2])
            if line.startswith("end_header"): break
        for _ in range(nv): pts.append([float(v) for v in f.readline().split()[:3]])
    return pts
def errors(truth, est, centroid):
    D = mul(inv(truth), est)
    tr = D[0][0] + D[1][1] + D[2][2]
    deg = math.degrees(math.acos(max(-1, min(1, (tr - 1) / 2))))
    a, b = apply(truth, centroid), apply(est, centroid)
    return deg, 1e3 * math.dist(a, b)

ring = ["bun000.ply", "bun045.ply", "bun090.ply", "bun180.ply", "bun270.ply", "bun315.ply", "bun000.ply"]
h = math.radians(2.0) / 2
axis = [0.6, -0.8, 0.0]
d = [axis[0]*math.sin(h), axis[1]*math.sin(h), axis[2]*math.sin(h), math.cos(h)]
print(f"{'pair':<24} {'tool':<8} {'time':>8} {'own RMS mm':>11} {'rot err':>9} {'trans err':>10}")
for tgt, src in zip(ring[1:], ring[:-1]):
    # src moves onto tgt: tgt is the anchor.
    pts = load_pts(src)
    centroid = [sum(p[k] for p in pts) / len(pts) for k in range(3)]
    t, q = conf[src][:3], conf[src][3:]
    start = [t[0] + 0.002, t[1], t[2]] + qmul(q, d)
    with open(f"{tmp}/pair.conf", "w") as f:
        f.write(f"bmesh {tgt} " + " ".join(map(str, conf[tgt])) + "\n")
        f.write(f"bmesh {src} " + " ".join(map(str, start)) + "\n")
    r = json.loads(subprocess.run([mint, "align", f"{tmp}/pair.conf", f"{tmp}/pair-out.conf", "--start-distance", "0.008", "--json"], capture_output=True, text=True, check=True).stdout)
    out = {l.split()[1]: [float(v) for v in l.split()[2:]] for l in open(f"{tmp}/pair-out.conf") if l.startswith("bmesh")}
    s = r["scans"][1]
    e0 = errors(mat(conf[src]), mat(start), centroid)
    e = errors(mat(conf[src]), mat(out[src]), centroid)
    name = f"{src[:-4]}->{tgt[:-4]}"
    print(f"{name:<24} {'start':<8} {'':>8} {'':>11} {e0[0]:8.3f}° {e0[1]:8.3f}mm")
    print(f"{'':<24} {'mint':<8} {r['register_seconds']:7.2f}s {s['rms']*1e3:11.4f} {e[0]:8.3f}° {e[1]:8.3f}mm")
    if o3d is None:
        print(f"{'':<24} {'open3d':<8} not installed (pip install open3d in scripts/bench/.venv-range failed, or libusb-1.0-0 is missing)")
        continue
    a = o3d.geometry.PointCloud(); a.points = o3d.utility.Vector3dVector(np.array(load_pts(tgt)))
    b = o3d.geometry.PointCloud(); b.points = o3d.utility.Vector3dVector(np.array(pts))
    Ta = mat(conf[tgt])
    init = np.array(mul(inv(Ta), mat(start)))
    t0 = time.time()
    res = o3d.pipelines.registration.registration_icp(b, a, 0.0015, init, o3d.pipelines.registration.TransformationEstimationPointToPoint(), o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=200))
    dt = time.time() - t0
    est = mul(Ta, res.transformation.tolist())
    e = errors(mat(conf[src]), est, centroid)
    print(f"{'':<24} {'open3d':<8} {dt:7.2f}s {res.inlier_rmse*1e3:11.4f} {e[0]:8.3f}° {e[1]:8.3f}mm")
print("(mint: time of registration without loading, RMS point-to-surface; open3d: time of registration_icp, inlier RMSE point-to-nearest-point)")
PY

echo "== the whole bunny, 10 scans from bun.conf =="
/usr/bin/time -f "%e %M" -o "$tmp/t1" "$mint" align "$tmp/bun.conf" "$tmp/aligned.conf" > /dev/null 2> "$tmp/align.log"
/usr/bin/time -f "%e %M" -o "$tmp/t2" "$mint" zipper "$tmp/aligned.conf" "$tmp/bunny.ply" 2> "$tmp/zip.log"
/usr/bin/time -f "%e %M" -o "$tmp/t3" "$mint" zipper "$tmp/aligned.conf" "$tmp/bunny-grid.ply" --method grid --cells 2000000 2> "$tmp/grid.log"
read a_s a_kb < "$tmp/t1"; read z_s z_kb < "$tmp/t2"; read g_s g_kb < "$tmp/t3"
echo "align ${a_s}s (peak RSS $((a_kb/1024)) MiB) + zipper with consensus ${z_s}s (peak RSS $((z_kb/1024)) MiB) = $(python3 -c "print(round($a_s+$z_s,2))")s; grid merge at 2M cells ${g_s}s (peak RSS $((g_kb/1024)) MiB)"
sed 's/^/  /' "$tmp/zip.log" "$tmp/grid.log"
ref="$root/../shared/data/stanford_bunny_zipper_mesh/bun_zipper.ply"
for m in bunny bunny-grid; do
  "$mint" distance "$tmp/$m.ply" "$ref" --samples 300000 | sed "s/^/  $m: /" | head -2
  "$mint" distance "$ref" "$tmp/$m.ply" --samples 300000 | sed "s/^/  $m: /" | head -2
done
TIMEFORMAT=%3R
echo "cat of the 10 scans (the floor): $( { time cat "$data"/*.ply > /dev/null; } 2>&1 )s ($(du -shL "$data" | cut -f1) of PLY)"
