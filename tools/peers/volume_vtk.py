"""mint volume vs VTK's vtkFlyingEdges3D on one voxel volume, for scripts/bench/volume.sh.

Usage:
  volume_vtk.py IN --iso V [--mint PATH] [--threads 2] [--repeat 3] [--name NAME]
  volume_vtk.py RAW --iso V --raw-dims X,Y,Z --raw-type u16|f32|... [--raw-header BYTES]

IN is a NRRD (.nhdr/.nrrd: raw or gzip; one data file, a printf pattern or a
LIST), a MetaImage (.mhd/.mha), a NIfTI-1 (.nii/.nii.gz) or a folder holding one
DICOM series; RAW is raw little-endian samples, X fastest.

Both programs get the same samples in the file's index order (x fastest),
spacing 1, origin 0, so both surfaces are in voxel index coordinates, one
grid node per voxel centre:
  * the samples are read here with numpy (per-slice files for NRRD patterns,
    gzip + vox_offset for .nii.gz, pydicom for DICOM, slices sorted by
    ImagePositionPatient along the slice normal, stored values times
    RescaleSlope plus RescaleIntercept, i.e. HU for CT). VTK's own reader
    (vtkNrrdReader, vtkMetaImageReader, vtkNIFTIImageReader,
    vtkDICOMImageReader) reads the same file too, and the flips that map its
    array onto ours are found and reported ("vtk_reader_flip"), with a check
    that after undoing them the values are equal;
  * mint gets the samples as raw little-endian float32
    (`mint volume RAW OUT.ply --iso V --raw-dims X,Y,Z --raw-type f32`), or,
    for a RAW input, the file itself with its own type;
  * vtkFlyingEdges3D gets a vtkImageData over the same numpy array
    (ComputeNormals, ComputeGradients, ComputeScalars off), with the SMP
    backend STDThread on --threads threads.
mint also runs once on the file itself (its own reader, the file's frame) to
check that its vertex and face counts equal those of the raw run.

Prints one JSON line: sizes, times (best of --repeat; VTK: Update() only,
excluding reading; mint: its seconds_total and the process's wall time),
topology of both surfaces (boundary, non-manifold, degenerate, duplicate
faces; duplicate points), interior vertex counts (every coordinate within
[1, n-2]) and nearest-vertex distances in voxels both ways.
"""
import argparse, glob, gzip, json, os, re, shutil, struct, subprocess, sys, tempfile, time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

RAW_TYPES = {"u8": "u1", "i8": "i1", "u16": "<u2", "i16": "<i2", "u32": "<u4", "i32": "<i4",
             "u64": "<u8", "i64": "<i8", "f32": "<f4", "f64": "<f8"}

# ---------------------------------------------------------------- readers (numpy)

NRRD_TYPES = {
    "signed char": "i1", "int8": "i1", "int8_t": "i1", "uchar": "u1", "unsigned char": "u1",
    "uint8": "u1", "uint8_t": "u1", "short": "i2", "short int": "i2", "signed short": "i2",
    "int16": "i2", "int16_t": "i2", "ushort": "u2", "unsigned short": "u2", "uint16": "u2",
    "uint16_t": "u2", "int": "i4", "signed int": "i4", "int32": "i4", "int32_t": "i4",
    "uint": "u4", "unsigned int": "u4", "uint32": "u4", "uint32_t": "u4", "float": "f4",
    "double": "f8", "longlong": "i8", "int64": "i8", "ulonglong": "u8", "uint64": "u8",
}


def read_nrrd(path):
    """(array [k][j][i], info) from a NRRD; raw or gzip; one data file, pattern or LIST."""
    with open(path, "rb") as f:
        blob = f.read()
    head_end = blob.find(b"\n\n")
    head = blob[: head_end if head_end >= 0 else len(blob)].decode("latin-1").splitlines()
    fields, list_files = {}, None
    for n, line in enumerate(head[1:], 1):
        if line.startswith("#") or ":" not in line:
            continue
        key, val = line.split(":", 1)
        key, val = key.strip().lower(), val.lstrip("=").strip()
        fields[key] = val
        if key in ("data file", "datafile") and val.upper().startswith("LIST"):
            list_files = [l.strip() for l in head[n + 1:] if l.strip()]
            break
    sizes = [int(s) for s in fields["sizes"].split()]
    if len(sizes) != 3:
        raise SystemExit(f"{path}: only 3-D scalar NRRD is handled here (sizes {sizes})")
    nx, ny, nz = sizes
    dt = np.dtype(NRRD_TYPES[fields["type"].lower()])
    if dt.itemsize > 1:
        dt = dt.newbyteorder(">" if fields.get("endian", "little") == "big" else "<")
    enc = fields.get("encoding", "raw").lower()
    if enc not in ("raw", "gzip", "gz"):
        raise SystemExit(f"{path}: encoding {enc} not handled here")
    base = os.path.dirname(path)
    df = fields.get("data file", fields.get("datafile"))
    if df is None:
        files, attached = [None], True
    else:
        attached = False
        if list_files is not None:
            files = [os.path.join(base, l) for l in list_files]
        else:
            parts = df.split()
            if len(parts) >= 4 and "%" in parts[0]:
                lo, hi, step = int(parts[1]), int(parts[2]), int(parts[3])
                files = [os.path.join(base, parts[0] % i) for i in range(lo, hi + (1 if step > 0 else -1), step)]
            else:
                files = [os.path.join(base, df)]
    chunks = []
    for fn in files:
        data = blob[head_end + 2:] if attached else open(fn, "rb").read()
        if enc != "raw":
            data = gzip.decompress(data)
        chunks.append(data)
    n = nx * ny * nz
    per = n // len(files)
    # raw per-file data without byte skip: the samples are the last bytes of each file
    arr = np.concatenate([np.frombuffer(c[len(c) - per * dt.itemsize:], dtype=dt) for c in chunks])
    single = None
    if len(files) == 1 and not attached and enc == "raw" and dt.byteorder in "<|=":
        single = (files[0], os.path.getsize(files[0]) - n * dt.itemsize)
    return arr.reshape(nz, ny, nx), {"format": "NRRD", "files": files if not attached else [path],
                                    "single_raw": single, "type": dt.name}


MET_TYPES = {"MET_UCHAR": "u1", "MET_CHAR": "i1", "MET_USHORT": "u2", "MET_SHORT": "i2",
             "MET_UINT": "u4", "MET_INT": "i4", "MET_FLOAT": "f4", "MET_DOUBLE": "f8",
             "MET_ULONG_LONG": "u8", "MET_LONG_LONG": "i8"}


def read_mhd(path):
    fields, lines = {}, open(path, "rb").read().decode("latin-1").splitlines()
    for line in lines:
        if "=" in line:
            k, v = line.split("=", 1)
            fields[k.strip()] = v.strip()
    nx, ny, nz = [int(s) for s in fields["DimSize"].split()]
    dt = np.dtype(MET_TYPES[fields["ElementType"]])
    msb = fields.get("ElementByteOrderMSB", fields.get("BinaryDataByteOrderMSB", "False")).lower() == "true"
    dt = dt.newbyteorder(">" if msb else "<") if dt.itemsize > 1 else dt
    if fields.get("CompressedData", "False").lower() == "true":
        raise SystemExit(f"{path}: compressed MetaImage not handled here")
    df = fields["ElementDataFile"]
    if df == "LOCAL" or df.split()[0].upper() == "LIST" or "%" in df:
        raise SystemExit(f"{path}: only a single detached data file is handled here")
    fn = os.path.join(os.path.dirname(path), df)
    n = nx * ny * nz
    skip = int(fields.get("HeaderSize", "0"))
    if skip < 0:
        skip = os.path.getsize(fn) - n * dt.itemsize
    arr = np.fromfile(fn, dtype=dt, count=n, offset=skip)
    return arr.reshape(nz, ny, nx), {"format": "MetaImage", "files": [path, fn],
                                    "single_raw": (fn, skip) if dt.byteorder in "<|=" else None,
                                    "type": dt.name}


NIFTI_TYPES = {2: "u1", 4: "i2", 8: "i4", 16: "f4", 64: "f8", 256: "i1", 512: "u2", 768: "u4",
               1024: "i8", 1280: "u8"}


def read_nifti(path):
    raw = open(path, "rb").read()
    if path.endswith(".gz"):
        raw = gzip.decompress(raw)
    e = "<" if struct.unpack("<i", raw[:4])[0] == 348 else ">"
    dims = struct.unpack(e + "8h", raw[40:56])
    dtc = struct.unpack(e + "h", raw[70:72])[0]
    vox_offset = int(struct.unpack(e + "f", raw[108:112])[0])
    slope, inter = struct.unpack(e + "2f", raw[112:120])
    if dims[0] < 3 or any(d > 1 for d in dims[4:dims[0] + 1]):
        raise SystemExit(f"{path}: only 3-D scalar NIfTI is handled here (dim {dims})")
    nx, ny, nz = dims[1:4]
    dt = np.dtype(NIFTI_TYPES[dtc])
    dt = dt.newbyteorder(e) if dt.itemsize > 1 else dt
    arr = np.frombuffer(raw, dtype=dt, count=nx * ny * nz, offset=vox_offset).reshape(nz, ny, nx)
    stored = arr
    if slope not in (0.0, 1.0) or (slope != 0.0 and inter != 0.0):
        arr = arr.astype(np.float64) * slope + inter
    return arr, {"format": "NIfTI-1", "files": [path], "single_raw": None, "type": dt.name,
                 "scl": [slope, inter], "stored": stored}


def read_dicom(folder):
    import pydicom
    files = sorted(glob.glob(os.path.join(folder, "*")))
    ds = []
    for f in files:
        if os.path.isdir(f):
            continue
        try:
            d = pydicom.dcmread(f)
        except Exception:
            continue
        if "PixelData" in d:
            ds.append((f, d))
    if not ds:
        raise SystemExit(f"{folder}: no DICOM image found")
    series = {d.SeriesInstanceUID for _, d in ds}
    if len(series) != 1:
        raise SystemExit(f"{folder}: {len(series)} series; give a folder with one")
    iop = np.array(ds[0][1].ImageOrientationPatient, float)
    normal = np.cross(iop[:3], iop[3:])
    ds.sort(key=lambda fd: float(np.dot(normal, np.array(fd[1].ImagePositionPatient, float))))
    stored = np.stack([d.pixel_array for _, d in ds])
    slopes = {float(getattr(d, "RescaleSlope", 1.0)) for _, d in ds}
    inters = {float(getattr(d, "RescaleIntercept", 0.0)) for _, d in ds}
    if len(slopes) == 1 and len(inters) == 1:
        s, i = slopes.pop(), inters.pop()
        arr = stored.astype(np.float64) * s + i
    else:
        arr = np.stack([d.pixel_array.astype(np.float64) * float(getattr(d, "RescaleSlope", 1.0))
                        + float(getattr(d, "RescaleIntercept", 0.0)) for _, d in ds])
        s, i = None, None
    positions = [float(np.dot(normal, np.array(d.ImagePositionPatient, float))) for _, d in ds]
    return arr, {"format": "DICOM", "files": [f for f, _ in ds], "single_raw": None,
                 "type": stored.dtype.name, "rescale": [s, i],
                 "slice_positions_first_last": [positions[0], positions[-1]],
                 "instance_numbers_first_last": [int(ds[0][1].InstanceNumber), int(ds[-1][1].InstanceNumber)]}


def read_raw(path, dims, typ, header):
    nx, ny, nz = dims
    dt = np.dtype(RAW_TYPES[typ])
    arr = np.memmap(path, dtype=dt, mode="r", offset=header, shape=(nz, ny, nx))
    return arr, {"format": "raw", "files": [path], "single_raw": (path, header), "type": dt.name}


def read_any(args):
    p = args.input
    if args.raw_dims:
        return read_raw(p, [int(s) for s in args.raw_dims.split(",")], args.raw_type, args.raw_header)
    low = p.lower()
    if os.path.isdir(p):
        return read_dicom(p)
    if low.endswith((".nhdr", ".nrrd")):
        return read_nrrd(p)
    if low.endswith((".mhd", ".mha")):
        return read_mhd(p)
    if low.endswith((".nii", ".nii.gz")):
        return read_nifti(p)
    raise SystemExit(f"{p}: unknown volume format")


# ---------------------------------------------------------------- VTK reader check

def vtk_reader_check(args, arr, info):
    """Read the file with VTK's own reader; find the axis flips that map VTK's array
    onto ours and check the values after undoing them."""
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    p, low = args.input, args.input.lower()
    if args.raw_dims:
        return {"reader": None}
    if os.path.isdir(p):
        r = vtk.vtkDICOMImageReader()
        r.SetDirectoryName(p)
        name = "vtkDICOMImageReader"
    elif low.endswith((".nhdr", ".nrrd")):
        r, name = vtk.vtkNrrdReader(), "vtkNrrdReader"
        r.SetFileName(p)
    elif low.endswith((".mhd", ".mha")):
        r, name = vtk.vtkMetaImageReader(), "vtkMetaImageReader"
        r.SetFileName(p)
    else:
        r, name = vtk.vtkNIFTIImageReader(), "vtkNIFTIImageReader"
        r.SetFileName(p)
    r.Update()
    im = r.GetOutput()
    d = im.GetDimensions()
    out = {"reader": name, "dims": list(d)}
    if tuple(d) != (arr.shape[2], arr.shape[1], arr.shape[0]):
        out["match"] = False
        return out
    a = vtk_to_numpy(im.GetPointData().GetScalars()).reshape(d[2], d[1], d[0])
    out["vtk_type"] = str(a.dtype)
    refs = [("values", arr)]
    if "stored" in info:
        refs.append(("stored", info["stored"]))
    for what, ref in refs:
        for flip in ["", "j", "k", "jk", "i", "ij", "ik", "ijk"]:
            sl = (slice(None, None, -1 if "k" in flip else 1),
                  slice(None, None, -1 if "j" in flip else 1),
                  slice(None, None, -1 if "i" in flip else 1))
            if np.array_equal(a[sl].astype(np.float64), np.asarray(ref, dtype=np.float64)):
                out.update({"flip": flip or "none", "equal_after_unflip": True, "compared_with": what})
                if name == "vtkDICOMImageReader":
                    out["rescale"] = [r.GetRescaleSlope(), r.GetRescaleOffset()]
                return out
    out["equal_after_unflip"] = False
    return out


# ---------------------------------------------------------------- meshes and metrics

def read_ply(path):
    with open(path, "rb") as f:
        head = b""
        while not head.endswith(b"end_header\n"):
            line = f.readline()
            if not line:
                raise SystemExit(f"{path}: no end_header")
            head += line
        lines = head.decode("latin-1").splitlines()
        if "format binary_little_endian 1.0" not in lines:
            raise SystemExit(f"{path}: only binary little-endian PLY is read here")
        elems, cur = [], None
        for l in lines:
            t = l.split()
            if t and t[0] == "element":
                cur = [t[1], int(t[2]), []]
                elems.append(cur)
            elif t and t[0] == "property":
                cur[2].append(t[1:])
        ply_np = {"float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8",
                  "uchar": "u1", "uint8": "u1", "char": "i1", "int8": "i1", "int": "<i4",
                  "int32": "<i4", "uint": "<u4", "uint32": "<u4", "short": "<i2", "ushort": "<u2",
                  "int16": "<i2", "uint16": "<u2"}
        V = F = None
        for name, count, props in elems:
            if name == "vertex":
                dt = np.dtype([(p[1], ply_np[p[0]]) for p in props])
                rec = np.fromfile(f, dtype=dt, count=count)
                V = np.stack([rec["x"], rec["y"], rec["z"]], axis=1).astype(np.float64)
            elif name == "face":
                (lt, ct, iname), = [p[1:] for p in props if p[0] == "list"]
                dt = np.dtype([("n", ply_np[lt]), ("v", ply_np[ct], (3,))])
                rec = np.fromfile(f, dtype=dt, count=count)
                if count and not np.all(rec["n"] == 3):
                    raise SystemExit(f"{path}: non-triangle faces")
                F = rec["v"].astype(np.int64)
    return V, F


def polydata_arrays(pd):
    from vtk.util.numpy_support import vtk_to_numpy
    V = vtk_to_numpy(pd.GetPoints().GetData()).astype(np.float64) if pd.GetNumberOfPoints() else np.zeros((0, 3))
    polys = pd.GetPolys()
    if polys.GetNumberOfCells() == 0:
        return V, np.zeros((0, 3), np.int64)
    off = vtk_to_numpy(polys.GetOffsetsArray())
    con = vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    if not np.all(np.diff(off) == 3):
        raise SystemExit("VTK output has non-triangle polys")
    return V, con.reshape(-1, 3)


def topology(V, F):
    nv, nf = len(V), len(F)
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    e.sort(axis=1)
    e = e[e[:, 0] != e[:, 1]]  # a repeated index is counted as a degenerate face, not an edge
    _, cnt = np.unique(e[:, 0] * nv + e[:, 1], return_counts=True)
    rep = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    P = V[F]
    area2 = np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    zero = area2 == 0.0
    fs = np.sort(F, axis=1)
    uf = len(np.unique(fs, axis=0)) if nf else 0
    up = len(np.unique(V, axis=0)) if nv else 0
    used = np.zeros(nv, bool)
    used[F.ravel()] = True
    return {"vertices": nv, "faces": nf, "edges": int(len(cnt)),
            "boundary_edges": int((cnt == 1).sum()), "non_manifold_edges": int((cnt > 2).sum()),
            "degenerate_faces": int((rep | zero).sum()), "degenerate_repeated_index": int(rep.sum()),
            "degenerate_zero_area": int((zero & ~rep).sum()),
            "tiny_faces_area_below_1e-6": int((area2 < 2e-6).sum()),
            "duplicate_faces": int(nf - uf), "duplicate_points": int(nv - up),
            "unreferenced_vertices": int((~used).sum()),
            "euler_characteristic": int(nv - len(cnt) + nf)}


def interior_mask(V, dims):
    n = np.array(dims, float)
    return np.all((V >= 1.0) & (V <= n - 2.0), axis=1)


def nearest(a, b):
    """distances from every point of a to the nearest point of b"""
    if len(a) == 0 or len(b) == 0:
        return np.zeros(0)
    try:
        from scipy.spatial import cKDTree
        return cKDTree(b).query(a, workers=-1)[0]
    except ImportError:
        # numpy grid hash: cells of 1 voxel, search the 27 neighbours (distances above ~1 are clipped)
        keyb = np.floor(b).astype(np.int64)
        best = np.full(len(a), np.inf)
        order = np.lexsort(keyb.T[::-1])
        kb = keyb[order]
        bb = b[order]
        ka = np.floor(a).astype(np.int64)
        sh = np.array([1 << 42, 1 << 21, 1])
        hb = (kb + 2) @ sh
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    h = (ka + 2 + [dx, dy, dz]) @ sh
                    lo, hi = np.searchsorted(hb, h, "left"), np.searchsorted(hb, h, "right")
                    for m in range(int((hi - lo).max(initial=0))):
                        ok = lo + m < hi
                        idx = np.where(ok, lo + m, 0)
                        d = np.linalg.norm(a - bb[idx], axis=1)
                        best = np.where(ok & (d < best), d, best)
        return best


def edge_keys(V, dims):
    """For marching-cubes vertices: the grid edge each lies on, as one integer
    (base node + axis), for vertices with exactly one non-integer coordinate;
    and the mask of vertices on a grid node (all coordinates integer: a sample
    equal to the iso value)."""
    nx, ny, nz = dims
    frac = np.abs(V - np.round(V)) > 1e-9
    nonint = frac.sum(axis=1)
    one = nonint == 1
    axis = np.argmax(frac, axis=1)
    base = np.floor(V).astype(np.int64)
    key = ((((base[:, 2] + 1) * (ny + 2) + base[:, 1] + 1) * (nx + 2) + base[:, 0] + 1) * 3 + axis)
    inside = np.all(base >= 0, axis=1) & np.all(base + np.eye(3, dtype=np.int64)[axis] <= np.array(dims) - 1, axis=1)
    return key, one, nonint == 0, inside


def edge_agreement(MV, VV, dims):
    mk, mone, mnode, minside = edge_keys(MV, dims)
    vk, vone, vnode, _ = edge_keys(VV, dims)
    mset = mk[mone & minside]
    vset = vk[vone]
    missing = np.setdiff1d(vset, mset)
    extra = np.setdiff1d(mset, vset)
    return {"mint_on_one_edge": int(mone.sum()), "mint_on_node": int(mnode.sum()),
            "vtk_on_one_edge": int(vone.sum()), "vtk_on_node": int(vnode.sum()),
            "vtk_edges_not_in_mint": int(len(missing)),
            "mint_edges_within_volume_not_in_vtk": int(len(extra)),
            "mint_edges_across_border": int((mone & ~minside).sum()),
            "duplicate_edge_vertices_mint": int(len(mset) - len(np.unique(mset))),
            "one_to_one": bool(len(missing) == 0 and len(extra) == int(vnode.sum()))}


def dist_stats(d):
    if len(d) == 0:
        return {"n": 0}
    return {"n": int(len(d)), "mean": float(d.mean()), "max": float(d.max()),
            "exact_1e-4": int((d < 1e-4).sum()), "over_0.1": int((d > 0.1).sum())}


# ---------------------------------------------------------------- runs

def run_mint(mint, cmd_tail, repeat):
    best_total, best_wall, summary, walls, totals = None, None, None, [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        p = subprocess.run([mint] + cmd_tail, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if p.returncode != 0:
            raise SystemExit(f"mint failed ({p.returncode}): {' '.join(cmd_tail)}\n{p.stderr}")
        summary = json.loads(p.stdout)
        walls.append(wall)
        totals.append(summary["seconds_total"])
    return summary, min(totals), min(walls), walls


def run_vtk(arr, iso, threads, repeat):
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkSMPTools
    asked = vtkSMPTools.SetBackend("STDThread")
    vtkSMPTools.Initialize(threads)
    backend = vtkSMPTools.GetBackend()
    nthreads = vtkSMPTools.GetEstimatedNumberOfThreads()
    nz, ny, nx = arr.shape
    flat = np.ascontiguousarray(arr).reshape(-1)
    sc = numpy_to_vtk(flat, deep=False)
    sc.SetName("s")
    img = vtk.vtkImageData()
    img.SetDimensions(nx, ny, nz)
    img.SetSpacing(1.0, 1.0, 1.0)
    img.SetOrigin(0.0, 0.0, 0.0)
    img.GetPointData().SetScalars(sc)
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(img)
    fe.SetValue(0, float(iso))
    fe.ComputeNormalsOff()
    fe.ComputeGradientsOff()
    fe.ComputeScalarsOff()
    fe.InterpolateAttributesOff()
    times = []
    for _ in range(repeat):
        fe.Modified()
        t0 = time.perf_counter()
        fe.Update()
        times.append(time.perf_counter() - t0)
    out = vtk.vtkPolyData()
    out.DeepCopy(fe.GetOutput())
    return out, min(times), times, {"backend": backend, "set_stdthread_ok": bool(asked),
                                    "threads": int(nthreads), "scalar_type": str(flat.dtype)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input")
    ap.add_argument("--iso", type=float, required=True)
    ap.add_argument("--raw-dims")
    ap.add_argument("--raw-type", default="f32", choices=sorted(RAW_TYPES))
    ap.add_argument("--raw-header", type=int, default=0)
    ap.add_argument("--mint", default=os.path.join(ROOT, "target", "release", "mint"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--name")
    ap.add_argument("--tmp", help="directory for the raw copy and both meshes [a new temporary one]")
    ap.add_argument("--keep", action="store_true", help="keep the temporary files")
    ap.add_argument("--no-native", action="store_true", help="skip mint's run on the file itself")
    args = ap.parse_args()
    import vtk

    tmp = tempfile.mkdtemp(prefix="volume_vtk-", dir=args.tmp)
    try:
        t0 = time.perf_counter()
        arr, info = read_any(args)
        read_s = time.perf_counter() - t0
        nz, ny, nx = arr.shape
        dims = [nx, ny, nz]
        rec = {"name": args.name or os.path.basename(os.path.normpath(args.input)), "input": args.input,
               "format": info["format"], "dims": dims, "iso": args.iso, "sample_type": info["type"],
               "read_seconds_numpy": read_s, "files": len(info["files"])}
        for k in ("scl", "rescale", "slice_positions_first_last", "instance_numbers_first_last"):
            if k in info:
                rec[k] = info[k]
        rec["vtk_reader_check"] = vtk_reader_check(args, arr, info)

        # the samples both programs see
        if args.raw_dims:
            vol, raw_path, raw_type, raw_hdr = arr, args.input, args.raw_type, args.raw_header
        else:
            vol = np.ascontiguousarray(arr, dtype=np.float32)
            if not np.array_equal(vol.astype(np.float64), np.asarray(arr, np.float64)):
                rec["warning_f32_not_exact"] = True
            raw_path, raw_type, raw_hdr = os.path.join(tmp, "volume.f32.raw"), "f32", 0
            vol.astype("<f4").tofile(raw_path)
        rec["samples_equal_iso"] = int(np.count_nonzero(np.asarray(vol) == np.asarray(args.iso, vol.dtype))) \
            if np.asarray(args.iso, vol.dtype) == args.iso else 0
        rec["samples_at_or_above_iso"] = int(np.count_nonzero(np.asarray(vol) >= args.iso))

        # mint on the raw samples
        mply = os.path.join(tmp, "mint.ply")
        tail = ["volume", raw_path, mply, "--iso", repr(args.iso), "--raw-dims", ",".join(map(str, dims)),
                "--raw-type", raw_type, "--json", "--threads", str(args.threads)]
        if raw_hdr:
            tail += ["--raw-header", str(raw_hdr)]
        ms, m_total, m_wall, m_walls = run_mint(args.mint, tail, args.repeat)
        rec["mint_cmd"] = " ".join([args.mint] + tail)
        rec["mint_seconds_total"] = m_total
        rec["mint_seconds_wall"] = m_wall
        rec["mint_walls"] = m_walls
        rec["mint_peak_rss_bytes"] = ms.get("peak_rss_bytes")
        rec["mint_summary_boundary_edges"] = ms.get("output_boundary_edges")
        rec["mint_warnings"] = ms.get("warnings", []) + ms.get("input_warnings", [])
        MV, MF = read_ply(mply)
        rec["mint"] = topology(MV, MF)
        if not args.no_native and not args.raw_dims:
            nply = os.path.join(tmp, "mint-native.ply")
            p = subprocess.run([args.mint, "volume", args.input, nply, "--iso", repr(args.iso), "--json",
                                "--threads", str(args.threads)], capture_output=True, text=True)
            if p.returncode == 0:
                ns = json.loads(p.stdout)
                rec["mint_native"] = {"vertices": ns["output_vertices"], "faces": ns["output_faces"],
                                      "dims": ns["volume"]["dims"], "frame": ns["volume"]["frame"],
                                      "seconds_total": ns["seconds_total"],
                                      "same_counts_as_raw": ns["output_vertices"] == len(MV) and ns["output_faces"] == len(MF)}
            else:
                rec["mint_native"] = {"error": p.stderr.strip().splitlines()[-1:]}
            if os.path.exists(nply):
                os.remove(nply)

        # VTK flying edges on the same array
        pd, v_best, v_times, smp = run_vtk(vol, args.iso, args.threads, args.repeat)
        rec["vtk_version"] = vtk.vtkVersion.GetVTKVersion()
        rec["vtk_smp"] = smp
        rec["vtk_seconds"] = v_best
        rec["vtk_times"] = v_times
        VV, VF = polydata_arrays(pd)
        rec["vtk"] = topology(VV, VF)

        # agreement away from the border
        mi, vi = interior_mask(MV, dims), interior_mask(VV, dims)
        rec["interior_vertices_mint"] = int(mi.sum())
        rec["interior_vertices_vtk"] = int(vi.sum())
        rec["interior_diff_pct"] = 100.0 * (mi.sum() - vi.sum()) / max(vi.sum(), 1)
        if rec["vtk"]["duplicate_points"]:
            rec["interior_unique_points_vtk"] = int(len(np.unique(VV[vi], axis=0)))
            rec["interior_unique_points_mint"] = int(len(np.unique(MV[mi], axis=0)))
        rec["interior_faces_mint"] = int(mi[MF].all(axis=1).sum())
        rec["interior_faces_vtk"] = int(vi[VF].all(axis=1).sum())
        rec["mint_vertices_within_voxel_centres"] = int(np.all((MV >= 0) & (MV <= np.array(dims) - 1.0), axis=1).sum())
        rec["edges"] = edge_agreement(MV, VV, dims)
        d_vm = nearest(VV, MV)
        d_mv = nearest(MV, VV)
        rec["dist_vtk_to_mint"] = dist_stats(d_vm)
        rec["dist_vtk_to_mint_interior"] = dist_stats(d_vm[vi])
        rec["dist_mint_to_vtk"] = dist_stats(d_mv)
        rec["dist_mint_to_vtk_interior"] = dist_stats(d_mv[mi])
        print(json.dumps(rec), flush=True)
    finally:
        if args.keep:
            print(f"kept {tmp}", file=sys.stderr)
        else:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
