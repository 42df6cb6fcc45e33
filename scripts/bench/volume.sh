#!/usr/bin/env bash
# Issue 32 benchmark: `mint volume` against VTK's vtkFlyingEdges3D (its
# Python wheel from PyPI) on the same samples, both on 2 threads:
#   * the four shared volumes at their own resolution (CT head NRRD with one
#     file per slice, MR head MetaImage, abdominal CT NIfTI, chest CT DICOM);
#   * a generated 256^3 u16 volume with a thin sheet (`mint gen volume`);
#   * a generated 1024^3 u16 volume (2 GiB), with `cat RAW > /dev/null` on a
#     warm cache beside it.
# Each line is the JSON record of tools/peers/volume_vtk.py: vertex counts
# away from the border, distances both ways in voxels, boundary,
# non-manifold, degenerate and duplicate faces of both surfaces, times
# (mint: the whole process including reading; VTK: Update() only, the
# samples already in memory). A table follows.
#
#   scripts/bench/volume.sh [--quick]     (--quick: skip the 1024^3 volume)
# The venv with vtk, numpy, scipy and pydicom is scripts/bench/.venv-vtk.
source "$(dirname "$0")/common.sh"
QUICK=${1:-}
VENV="$ROOT/scripts/bench/.venv-vtk"
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip
fi
"$VENV/bin/python" -c 'import vtk, numpy, scipy, pydicom' 2>/dev/null || "$VENV/bin/python" -m pip install --quiet vtk numpy scipy pydicom
build
machine
DATA="$ROOT/../shared/data/volumes"
OUT="$WORK/volume-vtk.jsonl"; : > "$OUT"
peer() { "$VENV/bin/python" "$ROOT/tools/peers/volume_vtk.py" --mint "$MINT" --threads 2 --repeat 3 --tmp "$WORK" "$@" | tee -a "$OUT"; }

peer "$DATA/ct-head-headsq-nrrd/quarter.nhdr" --iso 1150 --name "CT head (NRRD, 93 files)"
peer "$DATA/mr-head-mhd-vtk/HeadMRVolume.mhd" --iso 60 --name "MR head (MetaImage)"
peer "$DATA/ct-body-nifti-totalsegmentator/example_ct.nii.gz" --iso 300 --name "CT body (NIfTI gz)"
peer "$DATA/ct-chest-dicom-series-lungpetctdx" --iso 300 --name "CT chest (DICOM, 30 slices)"

S="$WORK/volume-256.nhdr"
[ -f "$S" ] || "$MINT" gen volume "$S" --dims 256,256,256 --type u16 > /dev/null
peer "${S%.nhdr}.raw" --raw-dims 256,256,256 --raw-type u16 --iso 1000 --name "generated 256^3 u16 (thin sheet)"

if [ "$QUICK" != --quick ]; then
  G="$WORK/volume-1024.nhdr"
  [ -f "$G" ] || "$MINT" gen volume "$G" --dims 1024,1024,1024 --type u16 > /dev/null
  cat "${G%.nhdr}.raw" > /dev/null
  echo "cat RAW > /dev/null, warm (1024^3 u16, 2 GiB): $(seconds cat "${G%.nhdr}.raw") s"
  peer "${G%.nhdr}.raw" --raw-dims 1024,1024,1024 --raw-type u16 --iso 1000 --repeat 2 --name "generated 1024^3 u16"
fi

"$VENV/bin/python" - "$OUT" <<'EOF'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
print()
print("| volume | dims | iso | mint s | VTK s | interior vertices mint / VTK (diff) | mean / max dist VTK->mint (vox, interior) | boundary edges mint / VTK | non-manifold mint / VTK | degenerate mint / VTK | duplicate faces mint / VTK |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    m, v, d = r["mint"], r["vtk"], r["dist_vtk_to_mint_interior"]
    print(f"| {r['name']} | {'x'.join(map(str, r['dims']))} | {r['iso']:g} | {r['mint_seconds_wall']:.3f} | {r['vtk_seconds']:.3f} "
          f"| {r['interior_vertices_mint']:,} / {r['interior_vertices_vtk']:,} ({r['interior_diff_pct']:+.3f}%) "
          f"| {d.get('mean', 0):.2e} / {d.get('max', 0):.2e} "
          f"| {m['boundary_edges']} / {v['boundary_edges']} | {m['non_manifold_edges']} / {v['non_manifold_edges']} "
          f"| {m['degenerate_faces']} / {v['degenerate_faces']} | {m['duplicate_faces']} / {v['duplicate_faces']} |")
EOF
