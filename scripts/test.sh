#!/usr/bin/env bash
# Install what is missing, build Release, run the whole test suite under ctest with 2 OpenMP
# threads; then the same suite under AddressSanitizer + UndefinedBehaviorSanitizer
# (SANITIZE=0 skips that half).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
# the tests' targets only (tests/CMakeLists.txt all_tests): the benchmarks are not built here
BUILD_TARGET=all_tests source "$ROOT/scripts/setup.sh"
if [ "${SANITIZE:-1}" != 0 ]; then
  echo "== sanitizer build (ASan + UBSan)"
  BUILD_DIR="$ROOT/build-asan" BUILD_TYPE=RelWithDebInfo BUILD_TARGET=all_tests \
    CMAKE_ARGS="-DSHOCKMPM_SANITIZE=ON -DSHOCKMPM_NATIVE=OFF -DSHOCKMPM_BENCH=OFF" \
    source "$ROOT/scripts/setup.sh"
  # the accuracy harness (label accuracy) checks numbers, not memory, and figures_smoke (label
  # python) checks scripts/figures.py, running the driver for one step only: Release only
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 SHOCKMPM_FUZZ_SECONDS=5 \
    ctest --test-dir "$ROOT/build-asan" --output-on-failure -j 1 -LE "accuracy|python"
fi
echo "== Release build, OMP_NUM_THREADS=$OMP_NUM_THREADS"
ctest --test-dir "$ROOT/build" --output-on-failure
