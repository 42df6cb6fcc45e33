#!/usr/bin/env python3
"""How well a resampled mesh keeps its input's per-vertex colour: mean CIELAB
colour difference against the input at the nearest point, beside the ideal
vertex attribute transfer on the same output geometry.

    colour_metrics.py INPUT.ply OUTPUT.ply [SAMPLES]

OUTPUT is a binary little-endian PLY with uchar red, green, blue per
vertex; INPUT too, or a textured OBJ (`mtllib`, `usemtl`, `vt`, one
`map_Kd` image per material, decoded by Pillow; v up, repeat). The output surface is sampled
(SAMPLES points, area-weighted, fixed seed; default 200000); at each sample
the output's colour (its vertex colours interpolated) is compared with the
input's colour at the nearest input point (the corner colours interpolated
at the exact closest point, among the triangles of the 16 nearest
centroids). The *ideal* transfer colours each output vertex from the input's
nearest point (rounded to bytes, as a file stores it) and is measured the
same way. Prints JSON: ΔE (CIE76, sRGB D65)
mean and p95 for mint and the ideal, and their ratio.

A checker written apart from mint (numpy and scipy's k-d tree), for the
colour benchmark and independent review; not used by the tests.
"""
import json
import sys

import numpy as np
from scipy.spatial import cKDTree

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
    verts = cols = faces = None
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            dt = np.dtype([(p[1], "<" + TYPES[p[0]]) for p in props])
            arr = np.frombuffer(data, dt, count, pos)
            pos += dt.itemsize * count
            if name == "vertex":
                verts = np.stack([arr["x"], arr["y"], arr["z"]], 1).astype(np.float64)
                names = dt.names
                assert all(c in names for c in ("red", "green", "blue")), f"{path}: no vertex colour"
                cols = np.stack([arr["red"], arr["green"], arr["blue"]], 1).astype(np.float64)
                if arr["red"].dtype.kind == "f":
                    cols = np.clip(np.round(cols * 255), 0, 255)
                elif arr["red"].dtype.itemsize == 2:
                    cols = np.floor(cols / 256)
        else:
            assert name == "face", "faces: a list property first"
            ct, it = TYPES[props[0][1]], TYPES[props[0][2]]
            rest = [(p[1], "<" + TYPES[p[0]]) for p in props[1:]]
            dt = np.dtype([("n", "<" + ct), ("v", "<" + it, (3,))] + rest)
            arr = np.frombuffer(data, dt, count, pos)
            assert (arr["n"] == 3).all(), "triangles only"
            faces = arr["v"].astype(np.int64)
            pos += dt.itemsize * count
    return verts, cols, faces


def read_obj_textured(path):
    """An OBJ with `mtllib`/`usemtl`/`vt` and one `map_Kd` texture per
    material (Pillow decodes it): positions, faces (fanned), and per face
    corner (u, v) and its material's image (None: the material's Kd)."""
    import os
    from PIL import Image
    base = os.path.dirname(path)
    v, vt, faces, fuv, fmat = [], [], [], [], []
    mats, cur, libs = {}, None, []
    with open(path, "r", errors="replace") as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                v.append([float(x) for x in w[1:4]])
            elif w[0] == "vt":
                vt.append([float(w[1]), float(w[2]) if len(w) > 2 else 0.0])
            elif w[0] == "mtllib":
                libs.append(line.split(None, 1)[1].strip())
            elif w[0] == "usemtl":
                cur = line.split(None, 1)[1].strip()
            elif w[0] == "f":
                c = [x.split("/") for x in w[1:]]
                vi = [int(x[0]) - 1 if int(x[0]) > 0 else len(v) + int(x[0]) for x in c]
                ti = [(int(x[1]) - 1 if int(x[1]) > 0 else len(vt) + int(x[1])) if len(x) > 1 and x[1] else -1 for x in c]
                for k in range(1, len(c) - 1):
                    faces.append([vi[0], vi[k], vi[k + 1]])
                    fuv.append([ti[0], ti[k], ti[k + 1]])
                    fmat.append(cur)
    for lib in libs:
        name = None
        for line in open(os.path.join(base, lib), errors="replace"):
            w = line.split()
            if not w:
                continue
            if w[0] == "newmtl":
                name = line.split(None, 1)[1].strip()
                mats[name] = {"kd": np.array([255.0, 255.0, 255.0]), "img": None}
            elif w[0] == "Kd" and name:
                mats[name]["kd"] = np.clip(np.array([float(x) for x in w[1:4]]) * 255, 0, 255)
            elif w[0] == "map_Kd" and name:
                img = Image.open(os.path.join(base, w[-1])).convert("RGB")
                mats[name]["img"] = np.asarray(img, dtype=np.float64)
    return np.array(v), np.array(faces, dtype=np.int64), np.array(fuv, dtype=np.int64), np.array(vt), fmat, mats


def textured_colour(points, verts, faces, fuv, vt, fmat, mats, tree):
    """The texture's colour at the input's nearest point to each point
    (bilinear, texel centres, v up, repeat)."""
    out = np.empty((len(points), 3))
    face_best, bary_best = nearest_points(points, verts, faces, tree)
    for i in range(len(points)):
        fi = face_best[i]
        m = mats.get(fmat[fi], {"kd": np.array([255.0] * 3), "img": None})
        t = fuv[fi]
        if m["img"] is None or (t < 0).any():
            out[i] = m["kd"]
            continue
        uv = bary_best[i] @ vt[t]
        img = m["img"]
        h, w = img.shape[:2]
        x, y = uv[0] * w - 0.5, (1.0 - uv[1]) * h - 0.5
        x0, y0 = np.floor(x), np.floor(y)
        fx, fy = x - x0, y - y0
        xa, xb = int(x0) % w, int(x0 + 1) % w
        ya, yb = int(y0) % h, int(y0 + 1) % h
        top = img[ya, xa] * (1 - fx) + img[ya, xb] * fx
        bot = img[yb, xa] * (1 - fx) + img[yb, xb] * fx
        out[i] = top * (1 - fy) + bot * fy
    return out


def srgb_to_lab(rgb):
    c = rgb / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    m = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750], [0.0193339, 0.1191920, 0.9503041]])
    xyz = lin @ m.T / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])], 1)


def closest_on_triangles(p, a, b, c):
    """Closest points of p (n, 3) on triangles (a, b, c) (n, 3 each), as
    barycentric weights (n, 3) (Ericson, Real-Time Collision Detection 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp = p - b
    d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    cp = p - c
    d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = vb / denom
        w = vc / denom
        w_ab = d1 / (d1 - d3)
        w_ac = d2 / (d2 - d6)
        w_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    out = np.stack([1 - v - w, v, w], 1)
    e = lambda cond, bary: np.where(cond[:, None], bary, out)  # noqa: E731
    z, o = np.zeros_like(v), np.ones_like(v)
    # Regions, from the last assigned (lowest priority) to the first.
    out = e((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), np.stack([z, 1 - w_bc, w_bc], 1))
    out = e((vb <= 0) & (d2 >= 0) & (d6 <= 0), np.stack([1 - w_ac, z, w_ac], 1))
    out = e((vc <= 0) & (d1 >= 0) & (d3 <= 0), np.stack([1 - w_ab, w_ab, z], 1))
    out = e((d6 >= 0) & (d5 <= d6), np.stack([z, z, o], 1))
    out = e((d3 >= 0) & (d4 <= d3), np.stack([z, o, z], 1))
    out = e((d1 <= 0) & (d2 <= 0), np.stack([o, z, z], 1))
    return np.nan_to_num(out, nan=1 / 3)


def nearest_points(points, verts, faces, tree, k=16, batch=20000):
    """For each point, the input face nearest to it (among those of the k
    nearest centroids) and the barycentric weights of the closest point."""
    face_best = np.zeros(len(points), dtype=np.int64)
    bary_best = np.zeros((len(points), 3))
    for s in range(0, len(points), batch):
        p = points[s:s + batch]
        _, idx = tree.query(p, k=k)
        best = np.full(len(p), np.inf)
        for j in range(k):
            f = faces[idx[:, j]]
            a, b, c = verts[f[:, 0]], verts[f[:, 1]], verts[f[:, 2]]
            bary = closest_on_triangles(p, a, b, c)
            q = bary[:, 0:1] * a + bary[:, 1:2] * b + bary[:, 2:3] * c
            d = ((q - p) ** 2).sum(1)
            better = d < best
            best[better] = d[better]
            bary_best[s:s + batch][better] = bary[better]
            face_best[s:s + batch][better] = idx[better, j]
    return face_best, bary_best


def colour_at_nearest(points, verts, cols, faces, tree):
    """The per-vertex colour at the input's nearest point to each point."""
    fi, w = nearest_points(points, verts, faces, tree)
    f = faces[fi]
    return w[:, 0:1] * cols[f[:, 0]] + w[:, 1:2] * cols[f[:, 1]] + w[:, 2:3] * cols[f[:, 2]]


def main():
    inp, outp = sys.argv[1], sys.argv[2]
    n = int(sys.argv[3]) if len(sys.argv) > 3 else 200000
    ov, oc, of = read_ply(outp)
    if inp.lower().endswith(".obj"):
        iv, if_, fuv, vt, fmat, mats = read_obj_textured(inp)
        tree = cKDTree(iv[if_].mean(1))
        colour_at = lambda pts: textured_colour(pts, iv, if_, fuv, vt, fmat, mats, tree)  # noqa: E731
    else:
        iv, ic, if_ = read_ply(inp)
        tree = cKDTree(iv[if_].mean(1))
        colour_at = lambda pts: colour_at_nearest(pts, iv, ic, if_, tree)  # noqa: E731
    rng = np.random.default_rng(1)
    a, b, c = ov[of[:, 0]], ov[of[:, 1]], ov[of[:, 2]]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    pick = rng.choice(len(of), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.stack([1 - s, s * (1 - r2), s * r2], 1)
    f = of[pick]
    pts = bary[:, 0:1] * ov[f[:, 0]] + bary[:, 1:2] * ov[f[:, 1]] + bary[:, 2:3] * ov[f[:, 2]]
    truth = srgb_to_lab(colour_at(pts))
    # Stored as bytes, as any output file stores them.
    ideal_vertex = np.clip(np.round(colour_at(ov)), 0, 255)

    def at_samples(vc):
        return srgb_to_lab(bary[:, 0:1] * vc[f[:, 0]] + bary[:, 1:2] * vc[f[:, 1]] + bary[:, 2:3] * vc[f[:, 2]])

    de_mint = np.linalg.norm(at_samples(oc) - truth, axis=1)
    de_ideal = np.linalg.norm(at_samples(ideal_vertex) - truth, axis=1)
    print(json.dumps({
        "samples": n,
        "delta_e_mean": float(de_mint.mean()),
        "delta_e_p95": float(np.percentile(de_mint, 95)),
        "ideal_delta_e_mean": float(de_ideal.mean()),
        "ideal_delta_e_p95": float(np.percentile(de_ideal, 95)),
        "ratio_to_ideal": float(de_mint.mean() / max(de_ideal.mean(), 1e-12)),
    }, indent=1))


if __name__ == "__main__":
    main()
