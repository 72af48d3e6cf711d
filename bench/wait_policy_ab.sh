#!/usr/bin/env bash
# libgomp's default spin (GOMP_SPINCOUNT=300000) against shockmpm's default (nothing set: the
# driver sets GOMP_SPINCOUNT=1000, engine/main.cpp), 2 threads, alternated ROUNDS times in one
# invocation; LOADED=1 runs a `yes > /dev/null` beside every run.
#   bench/wait_policy_ab.sh [BUILD_DIR] [ROUNDS] [CASE --set ...]
# Prints M particle-steps/s (run.json) of each run and the medians.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${1:-$ROOT/build}"; ROUNDS="${2:-5}"; shift 2 || true
[ $# -gt 0 ] || set -- "$ROOT/cases/quickstart.toml"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
speed() { /usr/bin/python3 -c "import json;print(round(json.load(open('$TMP/o/run.json'))['particle_steps_per_s']/1e6,3))"; }
spin=(); passive=()
if [ "${LOADED:-0}" = 1 ]; then yes > /dev/null & YES=$!; trap 'kill $YES; rm -rf "$TMP"' EXIT; fi
for ((r = 0; r < ROUNDS; ++r)); do
  env -u OMP_WAIT_POLICY GOMP_SPINCOUNT=300000 "$BUILD/shockmpm" run "$@" --out "$TMP/o" --overwrite --quiet --threads 2 > /dev/null
  spin+=("$(speed)")
  env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "$BUILD/shockmpm" run "$@" --out "$TMP/o" --overwrite --quiet --threads 2 > /dev/null
  passive+=("$(speed)")
  echo "round $r: libgomp default ${spin[-1]}  shockmpm default (1000 spins) ${passive[-1]}"
done
med() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
echo "median: libgomp default $(med "${spin[@]}")  shockmpm default (1000 spins) $(med "${passive[@]}") M particle-steps/s"
