#!/bin/sh
# Rebuilds the seed corpus tools/fuzz/corpus/<target>/seed-* from mint's own
# generators (mint gen/convert/slice/scan, 50 faces) and a few hand-written
# files. Usage: tools/fuzz/make-corpus.sh [path/to/mint]   (from the repo root)
set -eu
MINT=$(realpath "${1:-target/release/mint}")
C=$(realpath tools/fuzz)/corpus
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
for s in sphere torus genus; do "$MINT" gen $s $s.ply --faces 50 >/dev/null; done
mkdir -p "$C"
put() { mkdir -p "$C/$1"; cp "$2" "$C/$1/seed-$3"; }
for s in sphere torus; do
  "$MINT" convert -q $s.ply $s-ascii.ply --ascii
  "$MINT" convert -q $s.ply $s-double.ply --double
  "$MINT" convert -q $s.ply $s-ascii.stl --ascii
  "$MINT" convert -q $s.ply $s-binary.stl
  for e in obj off mesh raw wrl 3ds; do "$MINT" convert -q $s.ply $s.$e; put read_$e $s.$e $s.$e; done
  for f in $s-ascii.stl $s-binary.stl; do put read_stl $f $f; done
  for f in $s.ply $s-ascii.ply $s-double.ply; do put read_ply $f $f; done
  "$MINT" slice -q $s.ply $s.pro --sections 4
  put read_pro $s.pro $s.pro
done
put read_ply genus.ply genus-binary.ply
"$MINT" scan sphere.ply scans --views 3 --resolution 8 >/dev/null
"$MINT" scan torus.ply grid --views 2 --resolution 8 --image-format rgrid --perturb-deg 5 --perturb-frac 0.05 >/dev/null
"$MINT" scan torus.ply grid-ascii --views 2 --resolution 6 --image-format rgrid-ascii >/dev/null
put read_ply scans/view_01.ply range-grid.ply
put read_conf scans/scans.conf scans.conf
put read_conf grid/scans-perturbed.conf perturbed.conf
put read_rgrid grid/view_01.rgrid binary.rgrid
put read_rgrid grid-ascii/view_00.rgrid ascii.rgrid
# Big-endian PLY and triangle strips, by hand.
printf 'ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n' > be.ply
printf '\000\000\000\000\000\000\000\000\000\000\000\000\077\200\000\000\000\000\000\000\000\000\000\000\000\000\000\000\077\200\000\000\000\000\000\000\000\000\000\000\000\000\000\000\077\200\000\000' >> be.ply
printf '\003\000\000\000\000\000\000\000\002\000\000\000\001\003\000\000\000\000\000\000\000\001\000\000\000\003\003\000\000\000\001\000\000\000\002\000\000\000\003\003\000\000\000\002\000\000\000\000\000\000\000\003' >> be.ply
put read_ply be.ply tetrahedron-big-endian.ply
printf 'ply\nformat ascii 1.0\ncomment strips\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 1 1\n7 0 1 2 3 -1 3 4\n' > strips.ply
put read_ply strips.ply tristrips.ply
# .aln, by hand (MeshLab's layout).
printf '2\nview_00.ply\n#\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\nview_01.ply\n#\n0 -1 0 0.5\n1 0 0 -0.25\n0 0 1 1e-3\n0 0 0 1\n0\n' > set.aln
put read_aln set.aln two-scans.aln
# CSG scenes.
cat > tree.json <<'J'
{ "union": [
  { "difference": [ { "box": { "size": [2, 2, 2] }, "rotate": [0, 0, 30] }, { "cylinder": { "radius": 0.5, "height": 3 } } ] },
  { "intersection": [ { "sphere": { "radius": 1.3 }, "translate": [0, 0, 1.2] }, { "cone": { "radius": 1.0, "height": 2.5 } } ] },
  { "torus": { "major": 1.4, "minor": 0.2 }, "rotate": [90, 0, 0] },
  { "intersection": [ { "halfspace": { "normal": [0, 0, -1], "offset": 1.0 } }, { "sphere": { "radius": 0.4 }, "translate": [0, 0, -1.0] } ] } ] }
J
cat > defs.json <<'J'
{ "defs": { "hole": { "cylinder": { "radius": 0.3, "height": 3 } } },
  "scene": { "difference": [
      { "box": { "size": [2, 2, 2] }, "rotate": [0, 0, 30] },
      { "sphere": { "radius": 1.2 }, "translate": [0.5, 0, 0], "scale": [1, 2, 0.5] },
      { "ref": "hole" },
      { "mesh": "part.ply", "scale": 0.5 } ] } }
J
put parse_scene tree.json tree.json
put parse_scene defs.json defs.json
# discretize: 12 bytes a tetrahedron (lattice of half cells).
printf '\000\000\000\020\000\000\000\020\000\000\000\020' > tet
printf '\010\010\010\011\010\010\010\011\010\010\010\011\000\004\010\014\020\001\002\003\005\007\013\015\016\006\010\010\010\010\010\010\010\010\010\020\020\020' > tets
put discretize tet unit-corner
put discretize tets flat-and-small
# resample: byte 0 rule and cells, byte 1 vertices - 3, vertices, faces.
# A tetrahedron; a cube (8 corners, 12 faces); a tetrahedron with a hole (3 faces).
printf '\004\001\000\000\000\020\000\000\000\020\000\000\000\020\000\002\001\000\001\003\000\003\002\001\002\003' > tet-res
printf '\010\005\000\000\000\020\000\000\020\020\000\000\020\000\000\000\020\000\020\020\000\020\020\020\020\000\020\000\000\003\002\000\002\001\004\005\006\004\006\007\000\001\005\000\005\004\002\003\007\002\007\006\001\002\006\001\006\005\000\004\007\000\007\003' > cube-res
printf '\021\001\000\000\000\020\000\000\000\020\000\000\000\020\000\002\001\000\001\003\000\003\002' > open-res
put resample tet-res tetrahedron
put resample cube-res cube
put resample open-res open-tetrahedron-parity
# OFF whose keyword and first count run together (public test files have it).
printf 'OFF8 6 12\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n' > glued.off
put read_off glued.off glued-keyword.off
# Staged runs' plans (read_plan): resample, strict, bool, csg.
echo '{"difference": [{"sphere": {"radius": 1}}, {"cylinder": {"radius": 0.5, "height": 3}}]}' > s.json
"$MINT" stage plan resample sphere.ply o.ply --cells 1000 --work w1 --parts 2 --slabs 3 -q > p1; put read_plan p1 resample.json
"$MINT" stage plan resample sphere.ply o3.obj --cells 500 --signs orient --axis z --work w3 -q > p3; put read_plan p3 strict.json
"$MINT" stage plan bool difference sphere.ply torus.ply o2.ply --cell-size 0.05 --signs parity --double --work w2 -q > p2; put read_plan p2 bool.json
"$MINT" stage plan csg s.json o4.ply --cells 2000 --work w4 -q > p4; put read_plan p4 csg.json
ls -R "$C" | head -80
du -sh "$C"
