#!/usr/bin/env bash
# Benchmarks of the Python package against the command line and against the
# Python peers (pyfqmr, fast-simplification) on the same arrays, in one run:
#
#   1. the array `resample` of a 2M-face mesh against `mint resample` of the
#      same mesh from a binary PLY on a warm cache (target: <= 1.1x);
#   2. `simplify` of a 2M-face sphere and of the shared real meshes to 10%
#      and 1% of their faces: time and mean two-sided error (mint distance,
#      the same sampler for every tool) for mint, pyfqmr and
#      fast-simplification;
#   3. `decimate_file` of a BIG-face mesh to 1M faces from Python against
#      the CLI (target: <= 1.05x). BIG defaults to 100000000 (a 1.8 GB file
#      in MINT_BENCH_DIR).
#
# Usage: scripts/bench/python.sh [BIG]      (MINT_BENCH_DIR, default /tmp/bench;
#        SECTIONS, default 123: which of the three to run)
# It builds the wheel into scripts/bench/.venv-python with the peers from PyPI.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIG=${1:-100000000}
DIR=${MINT_BENCH_DIR:-/tmp/bench}
VENV=scripts/bench/.venv-python
mkdir -p "$DIR"
if [ ! -x "$VENV/bin/python" ]; then
    python3 -m venv "$VENV"
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
fi
"$VENV/bin/python" -m pip install --quiet ./python pyfqmr fast-simplification
cargo build --release --quiet
MINT=$PWD/target/release/mint
echo "machine: $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GiB, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
echo "versions: $("$VENV/bin/python" -c 'import mint_mesh, pyfqmr, fast_simplification, numpy, importlib.metadata as m; print("mint_mesh", mint_mesh.__version__, "pyfqmr", m.version("pyfqmr"), "fast-simplification", m.version("fast-simplification"), "numpy", numpy.__version__)')"
SECTIONS="${SECTIONS:-123}" MINT="$MINT" DIR="$DIR" BIG="$BIG" SHARED="$(cd .. && pwd)/shared/data" "$VENV/bin/python" - <<'EOF'
import os, subprocess, time, statistics, json
import numpy as np
import mint_mesh, pyfqmr, fast_simplification

MINT, DIR, BIG, SHARED = os.environ["MINT"], os.environ["DIR"], int(os.environ["BIG"]), os.environ["SHARED"]
SECTIONS = os.environ["SECTIONS"]

def timed(f, n=5):
    ts = []
    for _ in range(n):
        t = time.perf_counter(); r = f(); ts.append(time.perf_counter() - t)
    return statistics.median(ts), min(ts), r

# 1. array resample against the CLI from a binary PLY, warm cache.
def section1():
    print("\n## 1. array resample (2M faces) against mint resample from a binary PLY")
    src = os.path.join(DIR, "py-torus-2m.ply")
    if not os.path.exists(src):
        subprocess.run([MINT, "gen", "torus", src, "--faces", "2000000", "--order", "shuffled"], check=True)
    v, f = mint_mesh.read(src)
    subprocess.run(["cat", src], stdout=subprocess.DEVNULL, check=True)
    for cells in (1_000_000, 20_000_000):
        out = os.path.join(DIR, "py-out.ply")
        cli, cli_min, _ = timed(lambda: subprocess.run([MINT, "resample", src, out, "--cells", str(cells), "--quiet"], check=True))
        arr, arr_min, r = timed(lambda: mint_mesh.resample(v, f, cells=cells))
        print(f"cells {cells:>10}: CLI {cli:.3f} s (min {cli_min:.3f}), array {arr:.3f} s (min {arr_min:.3f}): {arr / cli:.2f}x; {len(r.faces)} faces out")

# 2. simplify against pyfqmr and fast-simplification.
def section2():
    print("\n## 2. simplify: mint vs pyfqmr vs fast-simplification (median of 3; mean/max two-sided error, mint distance, 200k samples)")
    meshes = []
    sph = os.path.join(DIR, "py-sphere-2m.ply")
    if not os.path.exists(sph):
        subprocess.run([MINT, "gen", "sphere", sph, "--faces", "2000000"], check=True)
    meshes.append(("sphere 2M", sph))
    for name, rel in (("horse", "cyberware_horse_mesh/horse.ply"), ("igea", "cyberware_igea_mesh/igea.ply"), ("bunny", "stanford_bunny_zipper_mesh/bun_zipper.ply"), ("laurana", "colour_scans/laurana_meshlab/Laurana50k.ply")):
        p = os.path.join(SHARED, rel)
        if os.path.exists(p):
            meshes.append((name, p))
        else:
            print(f"(missing {p})")

    def err(a, b):
        d = mint_mesh.distance(a, b, samples=200000)
        ab, ba = d["a_to_b"], d["b_to_a"]
        return (ab["mean"] + ba["mean"]) / 2, max(ab["max"], ba["max"]), d.get("diagonal") or None

    for name, p in meshes:
        v, f = mint_mesh.read(p)[:2]
        diag = float(np.linalg.norm(v.max(0) - v.min(0)))
        for frac in (0.1, 0.01):
            target = max(4, int(len(f) * frac))
            rows = []
            t, _, m = timed(lambda: mint_mesh.simplify(v, f, target_faces=target), 3)
            rows.append(("mint", t, m[0], m[1]))
            t, _, m = timed(lambda: mint_mesh.simplify(v, f, target_faces=target, error_samples=0), 3)
            rows.append(("mint error_samples=0", t, m[0], m[1]))
            def fq():
                s = pyfqmr.Simplify(); s.setMesh(v, f.astype(np.int32))
                s.simplify_mesh(target_count=target, aggressiveness=7, preserve_border=True, verbose=False)
                vv, ff, _ = s.getMesh(); return vv, ff
            t, _, m = timed(fq, 3)
            rows.append(("pyfqmr", t, m[0], m[1]))
            t, _, m = timed(lambda: fast_simplification.simplify(v.astype(np.float32), f.astype(np.int32), target_reduction=1 - target / len(f)), 3)
            rows.append(("fast-simplification", t, m[0], m[1]))
            for tool, t, vv, ff in rows:
                mean, mx, _ = err((v, f), (np.asarray(vv, np.float64), np.asarray(ff, np.int64)))
                print(f"{name:>10} to {frac:>4.0%} ({target:>7} faces) {tool:>20}: {t:7.3f} s, {len(ff):>7} faces, mean {mean / diag:.3e}, max {mx / diag:.3e} (of the diagonal)")

# 3. decimate_file of a big mesh against the CLI.
def section3():
    print(f"\n## 3. decimate_file of {BIG} faces to 1M against the CLI")
    big = os.path.join(DIR, f"py-big-{BIG}.ply")
    if not os.path.exists(big):
        subprocess.run([MINT, "gen", "sphere", big, "--faces", str(BIG)], check=True)
    t = time.perf_counter(); subprocess.run(["cat", big], stdout=subprocess.DEVNULL, check=True); cat = time.perf_counter() - t
    out = os.path.join(DIR, "py-big-out.ply")
    cli, cli_min, _ = timed(lambda: subprocess.run([MINT, "decimate", big, out, "--faces", "1000000", "--quiet"], check=True), 3)
    py, py_min, s = timed(lambda: mint_mesh.decimate_file(big, out, target_faces=1000000), 3)
    print(f"cat {cat:.2f} s; CLI {cli:.2f} s (min {cli_min:.2f}), Python {py:.2f} s (min {py_min:.2f}): {py / cli:.3f}x; {s['output_faces']} faces")

for k, sec in (("1", section1), ("2", section2), ("3", section3)):
    if k in SECTIONS:
        sec()
EOF
