#!/usr/bin/env bash
# Builds bench_kernels (Release, build-bench/) and runs it with OMP_NUM_THREADS=1 and =2,
# saving one JSON file per thread count to bench/results/ and printing a table of median
# particle-steps/s (1 vs 2 threads) with the P2G colored/atomic and colored/serial ratios.
#
# Usage: bench/run_kernels.sh [benchmark args...]
#   bench/run_kernels.sh --benchmark_filter='.*/65536' --benchmark_min_time=0.05      # smoke
#   bench/run_kernels.sh --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#   bench/run_kernels.sh --benchmark_filter='P2G.*<quadratic>' --benchmark_repetitions=5
# Environment: THREADS (default "1 2"), BUILD_DIR (default build-bench), OMP_PROC_BIND and
# other OpenMP variables are passed through unchanged.
# Re-print the table of earlier runs: python3 bench/kernels_table.py bench/results/kernels-STAMP-t*.json
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"
build="${BUILD_DIR:-$root/build-bench}"
threads="${THREADS:-1 2}"

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DSHOCKMPM_BENCH=ON > /dev/null
cmake --build "$build" --target bench_kernels -j 2

bin="$build/bench/bench_kernels"
out="$here/results"
mkdir -p "$out"
stamp="$(date +%Y%m%d-%H%M%S)"
files=()
for t in $threads; do
  json="$out/kernels-$stamp-t$t.json"
  echo "== OMP_NUM_THREADS=$t -> $json" >&2
  OMP_NUM_THREADS="$t" "$bin" --benchmark_out="$json" --benchmark_out_format=json "$@"
  files+=("$json")
done
echo
python3 "$here/kernels_table.py" "${files[@]}"
