"""How well a set of poses makes a Stanford scan set agree with itself,
measured without mint's code: an independent check of `mint align`'s result.

Usage: align_residuals.py SET.conf [OTHER.conf ...] [--max-mm D] [--every K]

For every .conf (the same scans, other poses), each scan's points are moved
to the world, and every K-th point (default 2) of scan i is paired with its
nearest point in each other scan j (scipy's KD-tree) when that point lies
within D mm (default 1: the overlap). The residual is the distance along
scan j's normal there (a plane fitted to j's 12 nearest points), so the
sampling spacing does not count. Printed per .conf: each scan's median and
RMS residual over all its partners, and the whole set's; then, for
comparison, the same per scan side by side. Lower means the scans agree
better under those poses.

Needs numpy and scipy. .conf poses: `bmesh FILE tx ty tz qx qy qz qw` means
p_world = R(q)^T p + t (see crates/mint-range/src/scanset.rs)."""
import os, sys
import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from align_compare import read_conf  # noqa: E402


def read_points(path):
    """The vertices of an ASCII or binary little-endian PLY range scan."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii", "replace").splitlines()
    n, fmt, props, in_vertex = 0, "ascii", [], False
    for line in header:
        tok = line.split()
        if tok[:1] == ["format"]:
            fmt = tok[1]
        elif tok[:1] == ["element"]:
            in_vertex = tok[1] == "vertex"
            if in_vertex:
                n = int(tok[2])
        elif tok[:1] == ["property"] and in_vertex:
            props.append((tok[-1], tok[1]))
    names = [p for p, _ in props]
    if fmt == "ascii":
        rows = data[end:].split(b"\n", n)[:n]
        arr = np.array([[float(v) for v in r.split()[: len(names)]] for r in rows])
    else:
        types = {"float": "<f4", "float32": "<f4", "double": "<f8", "uchar": "u1", "int": "<i4"}
        dt = np.dtype([(p, types[t]) for p, t in props])
        rec = np.frombuffer(data, dtype=dt, count=n, offset=end)
        arr = np.stack([rec[c].astype(float) for c in names], axis=1)
    return arr[:, [names.index("x"), names.index("y"), names.index("z")]]


def normals(points, tree, k=12):
    _, idx = tree.query(points, k=k)
    nb = points[idx] - points[idx].mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", nb, nb)
    _, vecs = np.linalg.eigh(cov)
    return vecs[:, :, 0]


def residuals(conf, max_d, every):
    folder = os.path.dirname(os.path.abspath(conf))
    _, scans = read_conf(conf)
    world = []
    for name, m in scans:
        p = read_points(os.path.join(folder, name))
        world.append(p @ m[:3, :3].T + m[:3, 3])
    trees = [cKDTree(w) for w in world]
    norms = [normals(w, t) for w, t in zip(world, trees)]
    per_scan = []
    for i, wi in enumerate(world):
        q = wi[::every]
        r = []
        for j in range(len(world)):
            if j == i:
                continue
            d, idx = trees[j].query(q, distance_upper_bound=max_d)
            ok = np.isfinite(d)
            if ok.sum() == 0:
                continue
            off = q[ok] - world[j][idx[ok]]
            r.append(np.abs(np.einsum("ni,ni->n", off, norms[j][idx[ok]])))
        r = np.concatenate(r) if r else np.zeros(0)
        per_scan.append((scans[i][0], r))
    return per_scan


def main():
    args, max_mm, every = [], 1.0, 2
    it = iter(sys.argv[1:])
    for a in it:
        if a == "--max-mm":
            max_mm = float(next(it))
        elif a == "--every":
            every = int(next(it))
        else:
            args.append(a)
    if not args:
        sys.exit(__doc__)
    results = [(c, residuals(c, max_mm * 1e-3, every)) for c in args]
    for conf, per in results:
        allr = np.concatenate([r for _, r in per])
        print(f"{conf}: {allr.size} pairs within {max_mm} mm, median {np.median(allr) * 1e3:.4f} mm, "
              f"RMS {np.sqrt(np.mean(allr ** 2)) * 1e3:.4f} mm")
    print("scan" + "".join(f" | {os.path.basename(c)} median / RMS (mm)" for c, _ in results))
    for k in range(len(results[0][1])):
        row = results[0][1][k][0]
        for _, per in results:
            r = per[k][1]
            row += f" | {np.median(r) * 1e3:.4f} / {np.sqrt(np.mean(r ** 2)) * 1e3:.4f}" if r.size else " | -"
        print(row)


if __name__ == "__main__":
    main()
