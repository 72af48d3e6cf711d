#!/usr/bin/env bash
# On the lent 16-core machine, from the repository root with .devbundle carried
# (TARGETS="shockmpm" bash bench/device_bundle.sh made it): the study's 8 cases at once, 2
# threads each, the first and last snapshot only, each stopped by SIGTERM after DEADLINE seconds
# (default 540; the driver then keeps what it wrote and run.json says "interrupted"). Copies each
# run's run.json, series.csv, front.csv, energy.csv, voids.csv and log to $OUT/paper/NAME;
# scripts/study_summary.py tabulates them. With NAME:THREADS arguments only those cases run, each
# with its own thread count (their sum at most the 16 cores), e.g.
#   bash bench/study_device.sh 540 baseline_p050_v1000:3 velocity_p050_v500:2
#   bash bench/study_device.sh [DEADLINE] [NAME:THREADS ...]
# SETS="grid.cell_size_um=2.0 run.end_time_ns=1200.0" passes each word as a --set override to
# every case (the study at another resolution; run.json's case_resolved shows what ran).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$ROOT/bench/device_env.sh" shockmpm
# set here: the driver would otherwise start itself again through /proc/self/exe (the loader)
export GOMP_SPINCOUNT=1000 OMP_NUM_THREADS=2
deadline="${1:-540}"
shift || true
runs=("$@")
if [ ${#runs[@]} -eq 0 ]; then
  for c in "$ROOT"/cases/paper/*.toml; do runs+=("$(basename "$c" .toml):2"); done
fi
out="${OUT:-/tmp/out}/paper"
mkdir -p "$out"
cd "$ROOT"
for r in "${runs[@]}"; do
  name="${r%%:*}" threads="${r##*:}"
  [ -f "cases/paper/$name.toml" ] || { echo "no case cases/paper/$name.toml" >&2; exit 2; }
  sets=()
  for kv in ${SETS:-}; do sets+=(--set "$kv"); done
  (timeout -s TERM "$deadline" /tmp/shockmpm run "cases/paper/$name.toml" --quiet --threads "$threads" \
     --set run.snapshot_interval_ns=0 "${sets[@]}" --out "/tmp/paper/$name" > "/tmp/paper-$name.log" 2>&1; echo "$name exit $?") &
done
wait
for r in "${runs[@]}"; do
  name="${r%%:*}"
  mkdir -p "$out/$name"
  for f in run.json series.csv front.csv energy.csv voids.csv case_resolved.toml; do
    [ -f "/tmp/paper/$name/$f" ] && cp "/tmp/paper/$name/$f" "$out/$name/"
  done
  cp "/tmp/paper-$name.log" "$out/$name/log.txt"
done
# the device tool returns only a few files: everything in one archive as well
tar czf "${OUT:-/tmp/out}/paper.tgz" -C "$(dirname "$out")" paper
