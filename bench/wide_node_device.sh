#!/usr/bin/env bash
# On the lent 16-core machine, from the repository root with .devbundle carried
# (bench/device_bundle.sh made it): prints the processor, picks the AVX-512 build where the
# processor has it, runs bench/wide_node.sh and copies the tables to $OUT.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$ROOT/bench/device_env.sh" bench_scaling
export OMP_PROC_BIND="${OMP_PROC_BIND:-close}" OMP_PLACES="${OMP_PLACES:-cores}"
bash "$ROOT/bench/wide_node.sh" /tmp/bench_scaling "${OUT:-/tmp/wide}" "$@"
