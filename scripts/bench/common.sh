# Shared helpers for the benchmark scripts (sourced).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
MINT="$ROOT/target/release/mint"
WORK="${MINT_BENCH_DIR:-$ROOT/scripts/bench/out}"
mkdir -p "$WORK"

build() { (cd "$ROOT" && cargo build --release --quiet); }

# machine line for the record
machine() {
  echo "machine: $(nproc) cores, $(awk '/MemTotal/{printf "%.0f GiB", $2/1048576}' /proc/meminfo), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
}

# seconds <command...>: wall time of a command, stdout discarded
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null; t1=$(date +%s.%N); echo "$t1 - $t0" | bc -l | xargs printf '%.3f'; }

# peak RSS (KiB) and wall time of a command via GNU time if present
timed() {
  if [ -x /usr/bin/time ]; then /usr/bin/time -f '%e s, peak RSS %M KiB' "$@"; else "$@"; fi
}

# gen SHAPE FACES -> path (cached)
gen() {
  local shape=$1 faces=$2 out="$WORK/$1-$2.ply"
  [ -f "$out" ] || "$MINT" gen "$shape" "$out" --faces "$faces" > /dev/null
  echo "$out"
}
