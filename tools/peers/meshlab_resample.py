"""MeshLab's uniform mesh resampling (pymeshlab) on one input, for the side-by-side
benchmark in vs_meshlab.sh. Usage: meshlab_resample.py IN OUT CELL_SIZE
Prints one JSON line: seconds (load+filter+save, like mint's total) and filter seconds."""
import json, sys, time
import pymeshlab as ml

inp, out, cell = sys.argv[1], sys.argv[2], float(sys.argv[3])
t0 = time.time()
ms = ml.MeshSet()
ms.load_new_mesh(inp)
t1 = time.time()
# The filter takes the cell size as a percentage of the bounding-box diagonal.
diag = ms.current_mesh().bounding_box().diagonal()
ms.generate_resampled_uniform_mesh(cellsize=ml.PercentageValue(100.0 * cell / diag))
t2 = time.time()
ms.save_current_mesh(out, binary=True)
t3 = time.time()
m = ms.current_mesh()
print(json.dumps({"seconds": t3 - t0, "filter_seconds": t2 - t1, "faces": m.face_number(), "vertices": m.vertex_number()}))
