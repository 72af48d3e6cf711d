#!/usr/bin/env bash
# On the lent 16-core machine, from the repository root with .devbundle carried
# (bench/device_bundle.sh made it): prints the processor, picks the AVX-512 build where the
# processor has it, runs bench/wide_node.sh and copies the tables to $OUT.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
B="$ROOT/.devbundle"
grep -m1 "model name" /proc/cpuinfo; nproc; free -g | head -2
level=v3; grep -qw avx512f /proc/cpuinfo && grep -qw avx512bw /proc/cpuinfo && level=v4
echo "build: x86-64-$level"
LOADER=$(ls "$B"/lib/ld-linux-x86-64.so.* | head -1)
cat > /tmp/bench_scaling <<EOS
#!/bin/sh
exec "$LOADER" --library-path "$B/lib" "$B/bench_scaling-$level" "\$@"
EOS
chmod +x /tmp/bench_scaling
export OMP_PROC_BIND="${OMP_PROC_BIND:-close}" OMP_PLACES="${OMP_PLACES:-cores}"
bash "$ROOT/bench/wide_node.sh" /tmp/bench_scaling "${OUT:-/tmp/wide}" "$@"
