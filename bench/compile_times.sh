#!/usr/bin/env bash
# Wall seconds of every compiled file in a clean build of the test script's targets (all_tests),
# slowest first, and the build's total wall time (docs/performance.md).
#   bash bench/compile_times.sh BUILD_DIR [cmake arguments ...]
# e.g. the sanitizer build as scripts/test.sh configures it:
#   bash bench/compile_times.sh /tmp/asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSHOCKMPM_SANITIZE=ON \
#     -DSHOCKMPM_NATIVE=OFF -DSHOCKMPM_BENCH=OFF
# BUILD_DIR is removed first (refused unless it is missing, empty or a CMake build directory).
# JOBS (default 2) sets the parallel jobs. The script is its own compiler launcher: the build
# directory's launcher is `env SMPM_COMPILE_LOG=LOG compile_times.sh`, which runs the compiler
# command it is given and appends "seconds source" to LOG (also on later builds in BUILD_DIR).
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
if [ -e "$BUILD" ] && [ ! -f "$BUILD/CMakeCache.txt" ] && [ -n "$(ls -A "$BUILD" 2> /dev/null || echo file)" ]; then
  echo "compile_times.sh: BUILD_DIR '$BUILD' exists and is not a CMake build directory: not removed" >&2
  exit 2
fi
rm -rf "$BUILD"
mkdir -p "$BUILD"
LOG="$(cd "$BUILD" && pwd)/compile_times.txt"
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release "$@" \
  -DCMAKE_CXX_COMPILER_LAUNCHER="env;SMPM_COMPILE_LOG=$LOG;$ROOT/bench/compile_times.sh" >/dev/null
start=$(date +%s)
cmake --build "$BUILD" -j "${JOBS:-2}" --target all_tests >/dev/null
echo "build of all_tests: $(( $(date +%s) - start )) s wall"
sort -rn "$LOG" | sed "s|$ROOT/||"
awk '{s += $1} END {printf "compiles: %.0f CPU-seconds in %d files\n", s, NR}' "$LOG"
