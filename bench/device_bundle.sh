#!/usr/bin/env bash
# Builds bench_scaling (and the driver shockmpm with TARGETS="bench_scaling shockmpm") for a
# machine that has none of the build's packages (the lent 16-core machine): two builds, -march=x86-64-v4 (AVX-512) and -march=x86-64-v3 (AVX2), and every shared
# library they load, the loader included, into BUNDLE (default .devbundle, git-ignored).
# bench/wide_node_device.sh runs it there with the build that the processor supports.
# LEVELS="v4" rebuilds only that one (the other stays as it was).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUNDLE="${1:-$ROOT/.devbundle}"
mkdir -p "$BUNDLE/lib"
for level in ${LEVELS:-v4 v3}; do
  B="$ROOT/build-$level"
  cmake -S "$ROOT" -B "$B" -DCMAKE_BUILD_TYPE=Release -DSHOCKMPM_NATIVE=OFF -DSHOCKMPM_BENCH=ON \
    -DCMAKE_CXX_FLAGS="-march=x86-64-$level" > /dev/null
  for t in ${TARGETS:-bench_scaling}; do
    cmake --build "$B" -j "$(nproc)" --target "$t"
    if [ "$t" = shockmpm ]; then cp "$B/shockmpm" "$BUNDLE/shockmpm-$level"; else cp "$B/bench/$t" "$BUNDLE/$t-$level"; fi
  done
done
# every library but the kernel's vdso, and the loader itself
for bin in "$BUNDLE"/*-v4; do
  ldd "$bin" | awk '/=>/ {print $3} /ld-linux/ {print $1}'
done | sort -u | while read -r lib; do
  [ -f "$lib" ] && cp -L "$lib" "$BUNDLE/lib/"
done
du -sh "$BUNDLE"
