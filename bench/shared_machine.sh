#!/usr/bin/env bash
# Throughput on an idle and on a loaded machine, for OpenMP wait policies (a run must
# keep its speed when another CPU-bound process shares the cores).
#   bench/shared_machine.sh [BUILD_DIR] [STEPS]
# For each policy, each load (idle; one CPU-bound process beside the run: a single `yes > /dev/null`) and 1 and 2
# threads: the quick-start case for STEPS steps, M particle-steps/s from run.json (median of 3).
# Policies: "libgomp default" (GOMP_SPINCOUNT=300000, what libgomp does when nothing is set),
# "spin 1k" (GOMP_SPINCOUNT=1000),
# "passive" (OMP_WAIT_POLICY=passive), "spin 10k" (GOMP_SPINCOUNT=10000), and "shockmpm default"
# (nothing set: the driver's own choice, engine/main.cpp). POLICIES="NAME,NAME" runs those only.
# After each policy's rows: its loaded 2-thread rate over its idle 1-thread rate (what a run
# keeps of one idle core when a CPU hog shares the two).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${1:-$ROOT/build}"
STEPS="${2:-300}"
EXE="$BUILD/shockmpm"
TMP="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$TMP"' EXIT
run_one() {  # env-assignments threads -> M/s
  local t=$1; shift
  env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "$@" "$EXE" run "$ROOT/cases/quickstart.toml" --out "$TMP/o" --overwrite --quiet \
    --threads "$t" --set run.max_steps="$STEPS" > /dev/null
  /usr/bin/python3 -c "import json;print(json.load(open('$TMP/o/run.json'))['particle_steps_per_s']/1e6)"
}
median3() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
printf '%-16s %-6s %8s %8s %10s\n' policy load "1 thr" "2 thr" "2thr/1thr"
for policy in "libgomp default:GOMP_SPINCOUNT=300000" "passive:OMP_WAIT_POLICY=passive" \
              "spin 10k:GOMP_SPINCOUNT=10000" "spin 1k:GOMP_SPINCOUNT=1000" "shockmpm default:SMPM_NONE=1"; do
  name="${policy%%:*}"; envs="${policy#*:}"
  [[ -z ${POLICIES:-} || ",$POLICIES," == *",$name,"* ]] || continue
  for load in idle loaded; do
    pids=()
    if [ "$load" = loaded ]; then yes > /dev/null & pids+=($!); fi
    r=()
    for t in 1 2; do
      a=$(run_one "$t" $envs); b=$(run_one "$t" $envs); c=$(run_one "$t" $envs)
      r+=("$(median3 "$a" "$b" "$c")")
    done
    [ ${#pids[@]} -gt 0 ] && kill "${pids[@]}" 2>/dev/null && wait "${pids[@]}" 2>/dev/null || true
    printf '%-16s %-6s %8.2f %8.2f %10.2f\n' "$name" "$load" "${r[0]}" "${r[1]}" "$(echo "${r[1]} / ${r[0]}" | bc -l)"
    if [ "$load" = idle ]; then idle1=${r[0]}; else
      printf '%-16s loaded 2 threads / idle 1 thread: %.2f\n' "$name" "$(echo "${r[1]} / $idle1" | bc -l)"
    fi
  done
done
