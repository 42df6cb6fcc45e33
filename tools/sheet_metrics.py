#!/usr/bin/env python3
"""How well a resampled open sheet keeps its input: orientation and boundary.

    sheet_metrics.py INPUT.ply OUTPUT.ply CELL

Both files are binary little-endian PLY (convert others with `mint convert`).
Prints, as JSON:
- `orientation_agree`: the share of output area (sampled faces) whose normal
  points the same way as the nearest input face's normal;
- `boundary_cells`: distances, in cells, from the output's boundary vertices
  to the input's boundary (edges on one face): max, p99, median;
- counts of boundary edges on both sides.
A checker written apart from mint (numpy only), for the open-sheet rule's
benchmark and for independent review; not used by the tests.
"""
import json
import struct
import sys

import numpy as np

TYPES = {"char": "i1", "uchar": "u1", "int8": "i1", "uint8": "u1", "short": "i2", "ushort": "u2", "int16": "i2",
         "uint16": "u2", "int": "i4", "uint": "u4", "int32": "i4", "uint32": "u4", "float": "f4", "float32": "f4",
         "double": "f8", "float64": "f8"}


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    assert "format binary_little_endian 1.0" in header, f"{path}: binary little-endian PLY only"
    elements = []
    for line in header:
        w = line.split()
        if w and w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w and w[0] == "property":
            elements[-1][2].append(w[1:])
    pos = end
    verts = faces = None
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            dt = np.dtype([(p[1], "<" + TYPES[p[0]]) for p in props])
            arr = np.frombuffer(data, dt, count, pos)
            pos += dt.itemsize * count
            if name == "vertex":
                verts = np.stack([arr["x"], arr["y"], arr["z"]], 1).astype(np.float64)
        else:
            assert name == "face" and len(props) == 1, "faces: one list property"
            ct, it = TYPES[props[0][1]], TYPES[props[0][2]]
            cs, isz = np.dtype(ct).itemsize, np.dtype(it).itemsize
            first = struct.unpack_from("<" + {"u1": "B", "i1": "b", "u4": "I", "i4": "i"}[ct], data, pos)[0]
            assert first == 3
            dt = np.dtype([("n", "<" + ct), ("v", "<" + it, (3,))])
            arr = np.frombuffer(data, dt, count, pos)
            assert (arr["n"] == 3).all(), "triangles only"
            faces = arr["v"].astype(np.int64)
            pos += (cs + 3 * isz) * count
    return verts, faces


def boundary_edges(faces):
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.sort(e, 1)
    uniq, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return e[counts[inv.ravel()] == 1]


def seg_dist(p, a, b):
    """Distance from each point p (N,3) to the nearest segment (a, b) (M,3), in chunks."""
    out = np.full(len(p), np.inf)
    d = b - a
    dd = np.maximum((d * d).sum(1), 1e-300)
    for s in range(0, len(p), 256):
        q = p[s:s + 256, None, :]
        t = np.clip(((q - a[None]) * d[None]).sum(2) / dd[None], 0, 1)
        c = a[None] + t[..., None] * d[None]
        out[s:s + 256] = np.sqrt(((q - c) ** 2).sum(2)).min(1)
    return out


def main():
    vin, fin = read_ply(sys.argv[1])
    vout, fout = read_ply(sys.argv[2])
    cell = float(sys.argv[3])
    rng = np.random.default_rng(1)

    def normals(v, f):
        n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        return n, v[f].mean(1)

    nin, cin = normals(vin, fin)
    nout, cout = normals(vout, fout)
    pick = rng.choice(len(fout), min(len(fout), 4000), replace=False) if len(fout) else np.array([], int)
    agree = total = 0.0
    for s in range(0, len(pick), 128):
        idx = pick[s:s + 128]
        d = ((cout[idx, None, :] - cin[None]) ** 2).sum(2)
        near = d.argmin(1)
        area = np.linalg.norm(nout[idx], axis=1)
        ok = (nout[idx] * nin[near]).sum(1) > 0
        agree += area[ok].sum()
        total += area.sum()
    bin_ = boundary_edges(fin)
    bout = boundary_edges(fout)
    result = {"input_faces": int(len(fin)), "output_faces": int(len(fout)),
              "orientation_agree": agree / total if total else None,
              "input_boundary_edges": int(len(bin_)), "output_boundary_edges": int(len(bout))}
    if len(bout) and len(bin_):
        pts = vout[np.unique(bout.ravel())]
        if len(pts) > 5000:
            pts = pts[rng.choice(len(pts), 5000, replace=False)]
        dist = seg_dist(pts, vin[bin_[:, 0]], vin[bin_[:, 1]]) / cell
        result["boundary_cells"] = {"max": float(dist.max()), "p99": float(np.percentile(dist, 99)),
                                    "median": float(np.median(dist))}
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
