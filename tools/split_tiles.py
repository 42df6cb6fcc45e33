#!/usr/bin/env python3
"""Cut a binary little-endian PLY written by `mint gen` (float x y z; uchar
count + 3 int indices) into N x N spatial tiles by the x and y of each
face's first corner, each tile a binary PLY with only the vertices it uses.
Every face lands in exactly one tile. Needs numpy.

    python3 tools/split_tiles.py IN.ply OUTDIR N
"""
import sys, os
import numpy as np

def main():
    src, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    data = np.memmap(src, dtype=np.uint8, mode="r")
    head_end = bytes(data[:4096]).index(b"end_header\n") + len("end_header\n")
    head = bytes(data[:head_end]).decode()
    nv = int(head.split("element vertex ")[1].split()[0])
    nf = int(head.split("element face ")[1].split()[0])
    assert "property float x" in head and "binary_little_endian" in head
    v = np.frombuffer(data[head_end:head_end + 12 * nv], dtype="<f4").reshape(nv, 3)
    f = np.frombuffer(data[head_end + 12 * nv:head_end + 12 * nv + 13 * nf], dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]))
    assert (f["n"] == 3).all()
    idx = f["i"]
    first = v[idx[:, 0]]
    lo, hi = v.min(axis=0), v.max(axis=0)
    cx = np.clip(((first[:, 0] - lo[0]) / (hi[0] - lo[0]) * n).astype(int), 0, n - 1)
    cy = np.clip(((first[:, 1] - lo[1]) / (hi[1] - lo[1]) * n).astype(int), 0, n - 1)
    tile = cx * n + cy
    os.makedirs(out, exist_ok=True)
    for t in range(n * n):
        faces = idx[tile == t]
        if len(faces) == 0:
            continue
        used, inv = np.unique(faces.ravel(), return_inverse=True)
        rec = np.empty(len(faces), dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]))
        rec["n"] = 3
        rec["i"] = inv.reshape(-1, 3)
        with open(os.path.join(out, "t%03d.ply" % t), "wb") as o:
            o.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (len(used), len(faces))).encode())
            o.write(np.ascontiguousarray(v[used], dtype="<f4").tobytes())
            o.write(rec.tobytes())

main()
