"""Manifold (the manifold3d package) on two binary PLY meshes written by
`mint gen`, for bool.sh. Usage: manifold_bool.py A.ply B.ply union|difference OUT.ply
Prints one JSON line: seconds for load, boolean, save; output faces; volume."""
import json, sys, time
import numpy as np
import manifold3d as m3d

def read_ply(path):
    with open(path, "rb") as f:
        nv = nf = 0
        while True:
            line = f.readline().decode().strip()
            if line.startswith("element vertex"):
                nv = int(line.split()[2])
            elif line.startswith("element face"):
                nf = int(line.split()[2])
            elif line == "end_header":
                break
        v = np.frombuffer(f.read(12 * nv), dtype="<f4").reshape(nv, 3)
        faces = np.frombuffer(f.read(13 * nf), dtype=np.uint8).reshape(nf, 13)
        tri = faces[:, 1:].copy().view("<i4").reshape(nf, 3)
    return v.astype(np.float32), tri.astype(np.uint32)

a, b, op, out = sys.argv[1:5]
t0 = time.time()
va, ta = read_ply(a)
vb, tb = read_ply(b)
ma = m3d.Manifold(m3d.Mesh(vert_properties=va, tri_verts=ta))
mb = m3d.Manifold(m3d.Mesh(vert_properties=vb, tri_verts=tb))
t1 = time.time()
r = ma + mb if op == "union" else ma - mb
mesh = r.to_mesh()
t2 = time.time()
v = np.asarray(mesh.vert_properties)[:, :3].astype("<f4")
t = np.asarray(mesh.tri_verts).astype("<i4")
with open(out, "wb") as f:
    f.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\nelement face {len(t)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
    f.write(v.tobytes())
    rec = np.zeros((len(t), 13), dtype=np.uint8)
    rec[:, 0] = 3
    rec[:, 1:] = t.view(np.uint8).reshape(len(t), 12)
    f.write(rec.tobytes())
t3 = time.time()
print(json.dumps({"load": t1 - t0, "boolean": t2 - t1, "save": t3 - t2, "seconds": t3 - t0, "faces": int(len(t)), "volume": float(r.volume()), "status": str(ma.status())}))
