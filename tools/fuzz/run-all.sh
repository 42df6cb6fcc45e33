#!/bin/sh
# Runs every fuzz target (or those named) for SECS seconds each, one after
# the other, from the repo root:   tools/fuzz/run-all.sh SECS [TARGET...]
# New inputs go to $FUZZ_WORK/<target> (default /tmp/mint-fuzz-work), the
# committed seeds are only read; crashes land in tools/fuzz/artifacts/.
set -u
SECS=${1:-300}
shift || true
TARGETS=${*:-"read_ply read_obj read_stl read_off read_mesh read_raw read_wrl read_3ds read_pro read_conf read_aln read_rgrid parse_scene discretize resample simplify"}
WORK=${FUZZ_WORK:-/tmp/mint-fuzz-work}
# Needs the nightly toolchain and cargo-fuzz (not part of a fresh machine).
if ! cargo +nightly fuzz --version > /dev/null 2>&1; then
  echo "run-all.sh: cargo-fuzz is missing; install it with: cargo install cargo-fuzz --locked (about 3 minutes)" >&2
  exit 1
fi
for t in $TARGETS; do
  mkdir -p "$WORK/$t"
  echo "== $t ($SECS s)"
  cargo +nightly fuzz run --fuzz-dir tools/fuzz -O "$t" "$WORK/$t" "tools/fuzz/corpus/$t" -- \
    -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 2>&1 |
    grep -E "^(stat::|==[0-9]+==|.*panicked|.*Test unit written|.*SUMMARY|Done)|^#[0-9]+.*DONE" || true
done
