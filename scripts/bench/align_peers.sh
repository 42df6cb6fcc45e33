#!/usr/bin/env bash
# Issue 17: mint align against Open3D's sequential point-to-plane ICP
# (registration_icp, 2 mm correspondences, 200 iterations; each scan in file
# order against the union of the ones before it) from the same perturbed
# starts, on the dragon stand and the bunny (tools/peers/align_compare.py).
# Every scan but the first is moved by DEG degrees about a random axis
# through the model's centre and MM mm; errors are each scan's pose relative
# to the first against the same in the .conf (worst scan: degrees, mm).
# Open3D comes from PyPI into scripts/bench/.venv-range (it needs Debian's
# libusb-1.0-0 at import: apt-get install libusb-1.0-0).
#   scripts/bench/align_peers.sh [SEEDS]    (default 5; needs ../shared/data)
set -euo pipefail
source "$(dirname "$0")/common.sh"
SEEDS=${1:-5}
build
VENV="$ROOT/scripts/bench/.venv-range"
if ! "$VENV/bin/python" -c "import open3d" 2>/dev/null; then
  python3 -m venv "$VENV" && "$VENV/bin/pip" install -q open3d
fi
DATA="$ROOT/../shared/data"
machine
for set in stanford_dragon_stand_range_scans/dragonStandRight.conf stanford_bunny_range_scans/bun.conf; do
  [ -f "$DATA/$set" ] || { echo "skipped: $DATA/$set is absent"; continue; }
  for dm in "3 3" "5 5"; do
    echo "== $set, ${dm% *}° / ${dm#* } mm"
    "$VENV/bin/python" "$ROOT/tools/peers/align_compare.py" "$MINT" "$DATA/$set" $dm "$SEEDS"
  done
done
