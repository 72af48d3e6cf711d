#!/usr/bin/env bash
# On the lent 16-core machine, from the repository root with .devbundle carried
# (TARGETS="shockmpm" bash bench/device_bundle.sh made it): the study's 8 cases at once, 2
# threads each, the first and last snapshot only, each stopped by SIGTERM after DEADLINE seconds
# (default 540; the driver then keeps what it wrote and run.json says "interrupted"). Copies each
# run's run.json, series.csv, front.csv, energy.csv, voids.csv and log to $OUT/paper/NAME;
# scripts/study_summary.py tabulates them.
#   bash bench/study_device.sh [DEADLINE]
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$ROOT/bench/device_env.sh" shockmpm
# set here: the driver would otherwise start itself again through /proc/self/exe (the loader)
export GOMP_SPINCOUNT=1000 OMP_NUM_THREADS=2
deadline="${1:-540}"
out="${OUT:-/tmp/out}/paper"
mkdir -p "$out"
cd "$ROOT"
for c in cases/paper/*.toml; do
  name="$(basename "$c" .toml)"
  (timeout -s TERM "$deadline" /tmp/shockmpm run "$c" --quiet --set run.snapshot_interval_ns=0 --out "/tmp/paper/$name" \
     > "/tmp/paper-$name.log" 2>&1; echo "$name exit $?") &
done
wait
for c in cases/paper/*.toml; do
  name="$(basename "$c" .toml)"
  mkdir -p "$out/$name"
  for f in run.json series.csv front.csv energy.csv voids.csv case_resolved.toml; do
    [ -f "/tmp/paper/$name/$f" ] && cp "/tmp/paper/$name/$f" "$out/$name/"
  done
  cp "/tmp/paper-$name.log" "$out/$name/log.txt"
done
# the device tool returns only a few files: everything in one archive as well
tar czf "${OUT:-/tmp/out}/paper.tgz" -C "$(dirname "$out")" paper
