"""Interleaved simplify times, mint (array call, error_samples=0) against
pyfqmr, on the shared meshes and the 2M-face sphere at 10% and 1%: the
medians of N runs each (default 7), and the minima. This VM's times wander
between runs, so each pair runs back to back.

    scripts/bench/.venv-python/bin/python scripts/bench/python_times.py [N]

(the venv that scripts/bench/python.sh builds; the sphere is the one it
generates in MINT_BENCH_DIR, default /tmp/bench)."""
import os
import sys, time, statistics, numpy as np, mint_mesh, pyfqmr
S = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared", "data") + "/"
meshes = [("horse", S+"cyberware_horse_mesh/horse.ply"), ("igea", S+"cyberware_igea_mesh/igea.ply"), ("bunny", S+"stanford_bunny_zipper_mesh/bun_zipper.ply"), ("laurana", S+"colour_scans/laurana_meshlab/Laurana50k.ply"), ("sphere2M", os.path.join(os.environ.get("MINT_BENCH_DIR", "/tmp/bench"), "py-sphere-2m.ply"))]
N = int(sys.argv[1]) if len(sys.argv) > 1 else 7
for name, p in meshes:
    v, f = mint_mesh.read(p)[:2]
    for frac in (0.1, 0.01):
        target = int(len(f) * frac)
        tm, tp = [], []
        for _ in range(N if name != "sphere2M" else 3):
            t = time.perf_counter(); mint_mesh.simplify(v, f, target_faces=target, error_samples=0); tm.append(time.perf_counter() - t)
            t = time.perf_counter()
            s = pyfqmr.Simplify(); s.setMesh(v, f.astype(np.int32)); s.simplify_mesh(target_count=target, aggressiveness=7, preserve_border=True, verbose=False); s.getMesh()
            tp.append(time.perf_counter() - t)
        mm, mp = statistics.median(tm), statistics.median(tp)
        print(f"{name:>9} {frac:>4.0%}: mint {mm:.3f} (min {min(tm):.3f})  pyfqmr {mp:.3f} (min {min(tp):.3f})  ratio median {mm/mp:.2f}, min {min(tm)/min(tp):.2f}", flush=True)
