#!/usr/bin/env bash
# Old build against new on the porous benchmark scene, alternated, 2 threads: the particle-steps
# per second the driver reports (run.json), median of N runs each. Issue 14's cost check.
#   [CASE=FILE] bash bench/porous_ab.sh OLD_SHOCKMPM NEW_SHOCKMPM [N=3] [STEPS=300] [EXTRA --set ...]
# CASE: another scene (default cases/bench/porous_shock.toml). OLD and NEW may be wrapper
# scripts that add --set keys (e.g. `exec build/shockmpm "$@" --set contact.void_face_fields=4`).
set -euo pipefail
old="$1"; new="$2"; n="${3:-3}"; steps="${4:-300}"; shift 4 || shift $#
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
case_file="${CASE:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/cases/bench/porous_shock.toml}"
tmp="$(mktemp -d)"
for i in $(seq "$n"); do
  for which in old new; do
    bin=$old; [ "$which" = new ] && bin=$new
    "$bin" run "$case_file" --quiet --set run.max_steps="$steps" "$@" --overwrite --out "$tmp/$which" > /dev/null
    v=$(grep -o '"particle_steps_per_s" : [0-9.e+]*' "$tmp/$which/run.json" | awk '{print $3}')
    echo "$which $i $v"
  done
done | tee "$tmp/all.txt"
for which in old new; do
  printf '%s median: ' "$which"
  grep "^$which " "$tmp/all.txt" | awk '{print $3}' | sort -g | awk '{a[NR]=$1} END {printf "%.4g particle-steps/s\n", (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'
done
rm -rf "$tmp"
