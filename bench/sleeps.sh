#!/usr/bin/env bash
# Where the threads of a run go to sleep. A thread that waits longer than its spin (the driver's
# GOMP_SPINCOUNT=1000, engine/main.cpp) sleeps in the kernel, and the thread it waited for must
# wake it: a system call and a reschedule on the step's critical path. Records a run of STEPS steps
# with perf (sched:sched_switch with call graphs) and prints the sleeps per step, all and by the
# engine function they happen in ("start_thread": a worker waiting between parallel regions;
# the setup's few are counted too; perf cannot always unwind through libgomp, and then says so).
#   bash bench/sleeps.sh DRIVER STEPS CASE [--set KEY=VALUE ...]
# Example (docs/performance.md, "Work split between paired threads"):
#   bash bench/sleeps.sh build/shockmpm 300 cases/bench/dense_shock.toml --set grid.cell_size_um=4.0
# Needs perf with access to tracepoints (root, or kernel.perf_event_paranoid <= -1); 2 threads
# unless OMP_NUM_THREADS says otherwise.
set -euo pipefail
[ $# -ge 3 ] || { sed -n "2,13p" "$0"; exit 2; }
DRIVER="$1"; STEPS="$2"; shift 2
command -v perf > /dev/null || { echo "sleeps.sh: perf is not installed (Debian: linux-perf)" >&2; exit 2; }
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
perf record -q -e sched:sched_switch --call-graph dwarf,16384 -o "$TMP/rec" "$DRIVER" run "$@" \
  --set run.max_steps="$STEPS" --out "$TMP/o" --overwrite --quiet > /dev/null 2>&1
# the innermost frame of the engine (or start_thread) in each sleeping stack
perf script -i "$TMP/rec" 2> /dev/null | awk -v s="$STEPS" '
  /sched:sched_switch/ { site = ""; sleeping = ($0 ~ /prev_state=S/); next }
  NF >= 2 && site == "" && ($2 ~ /^smpm::/ || $2 ~ /^start_thread/) { site = $2; sub(/[<(+].*/, "", site) }
  /^$/ { if (sleeping && site != "") n[site]++; sleeping = 0 }
  END { for (k in n) printf "%8.2f per step  %s\n", n[k] / s, k }' | sort -rn > "$TMP/sites" || true
all=$(perf script -i "$TMP/rec" 2> /dev/null | grep -c "sched:sched_switch:.*prev_state=S" || true)
echo "sleeps: $all in $STEPS steps, $(awk -v a="$all" -v s="$STEPS" 'BEGIN {printf "%.2f", a / s}') per step"
if [ -s "$TMP/sites" ]; then head -12 "$TMP/sites"; else echo "(perf did not unwind the sleeping stacks this time: run again)"; fi
