#!/usr/bin/env bash
# Issue 11 benchmark: the staged engine.
#   scripts/bench/stages.sh [FACES] [CELLS]     (default 100000000 faces, 10000000 cells)
# 1. One process: `cat IN > /dev/null` (the floor), the pre-engine mint (MINT_OLD=path, or
#    built from OLD_REV, default 103c149, in a worktree under the bench dir), and the staged
#    engine with a temporary work dir and with --work and 4 parts x 4 slabs; median of 3 each.
# 2. Per-stage wall times and bytes on disk per input face and per cell (for docs/SCALE.md).
# 3. With a local Slurm cluster up (scripts/slurm/local-slurm.sh up): the same run through
#    `mint slurm --wait` (4 parts, 4 slabs), and its overhead over one process.
source "$(dirname "$0")/common.sh"
FACES=${1:-100000000}; CELLS=${2:-10000000}
build
IN=$(gen torus "$FACES")
machine
echo "input: $IN ($FACES faces, $(stat -c %s "$IN") bytes), --cells $CELLS"
OLD=${MINT_OLD:-}
if [ -z "$OLD" ]; then
  REV=${OLD_REV:-103c149}
  if [ ! -x "$WORK/old-$REV/target/release/mint" ]; then
    rm -rf "$WORK/old-$REV"; git -C "$ROOT" worktree add -f -q "$WORK/old-$REV" "$REV"
    (cd "$WORK/old-$REV" && cargo build --release --quiet)
  fi
  OLD="$WORK/old-$REV/target/release/mint"
fi
median() { sort -n | awk '{a[NR]=$1} END{print a[int((NR+1)/2)]}'; }
cat "$IN" > /dev/null
echo "cat IN > /dev/null: $(for i in 1 2 3; do seconds cat "$IN"; echo; done | median) s (median of 3)"
run() { local label=$1; shift; local ts=(); for i in 1 2 3; do rm -rf "$WORK/stage-w"; ts+=("$(seconds "$@")"); done
        echo "$label: $(printf '%s\n' "${ts[@]}" | median) s (runs: ${ts[*]})"; }
run "pre-engine mint resample      " "$OLD" resample "$IN" "$WORK/old.ply" --cells "$CELLS" --quiet
run "staged, temporary work dir    " "$MINT" resample "$IN" "$WORK/new.ply" --cells "$CELLS" --quiet
run "staged, --work, 4 parts 4 slabs" "$MINT" resample "$IN" "$WORK/new4.ply" --cells "$CELLS" --quiet --work "$WORK/stage-w" --parts 4 --slabs 4
cmp "$WORK/old.ply" "$WORK/new.ply" && cmp "$WORK/new.ply" "$WORK/new4.ply" && echo "outputs: byte-identical"
rm -rf "$WORK/stage-w"
J=$("$MINT" resample "$IN" "$WORK/new4.ply" --cells "$CELLS" --json --quiet --work "$WORK/stage-w" --parts 4 --slabs 4)
S=$("$MINT" stage status "$WORK/stage-w" --json)
python3 - "$FACES" "$J" "$S" <<'PY'
import json, sys
faces = int(sys.argv[1]); j = json.loads(sys.argv[2]); s = json.loads(sys.argv[3])
cells = j["grid_cells"][0] * j["grid_cells"][1] * j["grid_cells"][2]
print(f"grid {'x'.join(map(str, j['grid_cells']))} = {cells} cells; {j['intercepts_found']} intercepts; {j['output_faces']} faces out")
print(f"stage seconds (4 parts, 4 slabs, one process): bounds {j['seconds_bounds']:.2f}, discretize {j['seconds_discretize']:.2f}, "
      f"census {j['seconds_census']:.2f}, holes+reconstruct {j['seconds_reconstruct']:.2f}, write {j['seconds_write']:.2f}, total {j['seconds_total']:.2f}")
for st in s["stages"]:
    print(f"  {st['name']:<12} {st['tasks']:>3} tasks  {st['bytes']:>12} bytes on disk  {st['bytes']/faces:8.4f} B/input face  {st['bytes']/cells:8.4f} B/cell")
PY
if bash "$ROOT/scripts/slurm/local-slurm.sh" status > /dev/null 2>&1; then
  rm -rf "$WORK/slurm-w"
  t=$(seconds "$MINT" slurm resample "$IN" "$WORK/slurm.ply" --cells "$CELLS" --work "$WORK/slurm-w" --parts 4 --slabs 4 --wait --quiet)
  cmp "$WORK/new.ply" "$WORK/slurm.ply" && echo "local Slurm, 4 parts x 4 slabs (19 tasks): ${t} s, output byte-identical"
  rm -rf "$WORK/slurm-w"
else
  echo "local Slurm: not up (scripts/slurm/local-slurm.sh up), skipped"
fi
rm -rf "$WORK/stage-w" "$WORK"/old.ply "$WORK"/new*.ply "$WORK/slurm.ply"
