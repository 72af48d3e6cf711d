#!/usr/bin/env bash
# Install what is missing, build Release, run the whole test suite under ctest with 2 OpenMP
# threads; then the same suite under AddressSanitizer + UndefinedBehaviorSanitizer
# (SANITIZE=0 skips that half).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
source "$ROOT/scripts/setup.sh"
if [ "${SANITIZE:-1}" != 0 ]; then
  echo "== sanitizer build (ASan + UBSan)"
  BUILD_DIR="$ROOT/build-asan" BUILD_TYPE=RelWithDebInfo \
    CMAKE_ARGS="-DSHOCKMPM_SANITIZE=ON -DSHOCKMPM_NATIVE=OFF -DSHOCKMPM_BENCH=OFF" \
    source "$ROOT/scripts/setup.sh"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir "$ROOT/build-asan" --output-on-failure -j 1
fi
echo "== Release build, OMP_NUM_THREADS=$OMP_NUM_THREADS"
ctest --test-dir "$ROOT/build" --output-on-failure
