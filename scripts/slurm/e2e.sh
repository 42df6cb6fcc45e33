#!/usr/bin/env bash
# End-to-end check of `mint slurm` on a running cluster (CI runs it on the
# local one, scripts/slurm/local-slurm.sh): a real `mint slurm resample ...
# --wait` of a few-million-face mesh in several parts and slabs, compared
# byte for byte with a one-process `mint resample` of the same input.
#   scripts/slurm/e2e.sh [FACES]     (default 3000000)
# Needs target/release/mint (built by `cargo test --release` or `cargo build --release`).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
MINT="$ROOT/target/release/mint"
FACES=${1:-3000000}
[ -x "$MINT" ] || (cd "$ROOT" && cargo build --release --quiet)
# The work directory must be visible to every node: on the local cluster, any local path.
W=$(mktemp -d "${TMPDIR:-/tmp}/mint-slurm-e2e.XXXXXX")
trap 'rm -rf "$W"' EXIT
"$MINT" gen sphere "$W/in.ply" --faces "$FACES" > /dev/null
t0=$(date +%s.%N)
"$MINT" resample "$W/in.ply" "$W/one.ply" --cells 8000000 --quiet
t1=$(date +%s.%N)
"$MINT" slurm resample "$W/in.ply" "$W/slurm.ply" --cells 8000000 --work "$W/work" --parts 3 --slabs 4 --wait
t2=$(date +%s.%N)
cmp "$W/one.ply" "$W/slurm.ply"
"$MINT" stage status "$W/work"
printf 'slurm e2e: %s faces, one process %.2f s, Slurm (3 parts, 4 slabs, %s tasks) %.2f s; outputs byte-identical\n' \
  "$FACES" "$(awk "BEGIN{print $t1 - $t0}")" "$(ls -d "$W"/work/*/0* | wc -l)" "$(awk "BEGIN{print $t2 - $t1}")"
