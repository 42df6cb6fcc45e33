"""MeshLab's quadric edge-collapse decimation (pymeshlab) of one input to a face count, for
decimate.sh. Usage: meshlab_decimate.py IN OUT FACES
Prints one JSON line: seconds (load+filter+save) and filter seconds, faces, peak RSS (KiB)."""
import json, resource, sys, time
import pymeshlab as ml

inp, out, faces = sys.argv[1], sys.argv[2], int(sys.argv[3])
t0 = time.time()
ms = ml.MeshSet()
ms.load_new_mesh(inp)
t1 = time.time()
ms.meshing_decimation_quadric_edge_collapse(targetfacenum=faces, preservetopology=True, preservenormal=True, qualitythr=0.3)
t2 = time.time()
ms.save_current_mesh(out, binary=True)
t3 = time.time()
m = ms.current_mesh()
print(json.dumps({"seconds": t3 - t0, "filter_seconds": t2 - t1, "faces": m.face_number(),
                  "peak_rss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))
