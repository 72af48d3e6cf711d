#!/usr/bin/env bash
# Wall seconds of every compiled file in a clean build of the test script's targets (all_tests),
# slowest first, and the build's total wall time (docs/performance.md).
#   bash bench/compile_times.sh BUILD_DIR [cmake arguments ...]
# e.g. the sanitizer build as scripts/test.sh configures it:
#   bash bench/compile_times.sh /tmp/asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSHOCKMPM_SANITIZE=ON \
#     -DSHOCKMPM_NATIVE=OFF -DSHOCKMPM_BENCH=OFF
# BUILD_DIR is removed first. JOBS (default 2) sets the parallel jobs. The script is its own
# compiler launcher: with SMPM_COMPILE_LOG set it runs the compiler command it is given and
# appends "seconds source" to that file.
set -euo pipefail
if [ -n "${SMPM_COMPILE_LOG:-}" ]; then
  start=$(date +%s%N)
  rc=0
  "$@" || rc=$?
  end=$(date +%s%N)
  src=""
  for a in "$@"; do case "$a" in *.cpp) src="$a" ;; esac; done
  ms=$(( (end - start) / 1000000 ))
  printf '%d.%01d %s\n' $(( ms / 1000 )) $(( ms % 1000 / 100 )) "$src" >> "$SMPM_COMPILE_LOG"
  exit $rc
fi
[ $# -ge 1 ] || { echo "usage: bash bench/compile_times.sh BUILD_DIR [cmake arguments ...]" >&2; exit 2; }
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="$1"; shift
rm -rf "$BUILD"
mkdir -p "$BUILD"
LOG="$(cd "$BUILD" && pwd)/compile_times.txt"
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release "$@" \
  -DCMAKE_CXX_COMPILER_LAUNCHER="$ROOT/bench/compile_times.sh" >/dev/null
start=$(date +%s)
SMPM_COMPILE_LOG="$LOG" cmake --build "$BUILD" -j "${JOBS:-2}" --target all_tests >/dev/null
echo "build of all_tests: $(( $(date +%s) - start )) s wall"
sort -rn "$LOG" | sed "s|$ROOT/||"
awk '{s += $1} END {printf "compiles: %.0f CPU-seconds in %d files\n", s, NR}' "$LOG"
