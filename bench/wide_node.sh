#!/usr/bin/env bash
# Thread scaling on a wide node: bench_scaling for the three bench scenes at about 1e6 and 4e6
# particles over a thread list, each with the bitwise check across the thread counts
# (--verify-steps). Prints each table and writes them to OUTDIR.
#   bench/wide_node.sh BENCH_SCALING OUTDIR [THREADS] [SIZES]
#     BENCH_SCALING  the bench_scaling executable (build/bench/bench_scaling)
#     THREADS        thread list, default 1,2,4,8,16
#     SIZES          "1e6 4e6" (default), or one of them
# Rounds (10 at 1e6, 6 at 4e6, times ROUNDS_SCALE, default 1) and steps are sized so that the
# whole table takes about 80 s on 16 cores (ROUNDS_SCALE=3: about 4 minutes); the lent 16-core
# machine runs it through bench/wide_node_device.sh.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
EXE="$1"; OUT="$2"; THREADS="${3:-1,2,4,8,16}"; SIZES="${4:-1e6 4e6}"
mkdir -p "$OUT"
# scene, the key that sets its size, its value at 1e6 and at 4e6 particles
SCENES=("elastic_block grid.cell_size_m 0.0008 0.0004"
        "dense_shock grid.cell_size_um 1.25 0.625"
        "porous_shock grid.cell_size_um 0.8 0.4")
status=0
for size in $SIZES; do
  for s in "${SCENES[@]}"; do
    read -r name key v1 v4 <<< "$s"
    value=$v1; rounds=10; steps=2
    if [ "$size" = 4e6 ]; then value=$v4; rounds=6; steps=1; fi
    rounds=$(( rounds * ${ROUNDS_SCALE:-1} ))
    log="$OUT/scaling-$name-$size.txt"
    echo "== $name $size ($key=$value), threads $THREADS" | tee "$log"
    start=$(date +%s)
    "$EXE" "$ROOT/cases/bench/$name.toml" --set "$key=$value" --threads "$THREADS" --rounds $rounds \
      --steps-per-round $steps --warmup 3 --verify-steps 3 2>&1 | tee -a "$log" || status=1
    echo "# $(( $(date +%s) - start )) s" | tee -a "$log"
  done
done
exit $status
