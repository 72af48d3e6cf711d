#!/usr/bin/env bash
# The rate of one bench scene against another's, the two runs alternated in each round (the
# VM's drift between sittings moves single rates by up to 16 %): particle-steps per second from
# run.json, per round and the median of the per-round ratios B / A.
#   [OMP_NUM_THREADS=1] bash bench/scene_ratio.sh N "SCENE_A [KEY=VALUE ...]" "SCENE_B [KEY=VALUE ...]" [DRIVER] [STEPS]
# SCENE: a file of cases/bench/ without .toml; KEY=VALUE: --set overrides. Example, the dense
# 3D column against the dense 2D strip at 1e6 points on one thread (docs/performance.md, "3D"):
#   bash bench/scene_ratio.sh 5 "dense_shock grid.cell_size_um=1.25" "dense_shock_3d grid.cell_size_um=4.0"
# The scene "mls_yardstick" is the colored MLS-MPM reference, build/bench/bench_mls (the elastic
# block's scene; its KEY=VALUE: grid.cell_size_m, run.max_steps), rated by its steps alone. With
# RATE=step the driver's runs are rated by their steps alone too (particle-steps over the sum of
# run.json's phase seconds less output and diagnostics); the default RATE=run takes the whole
# run's wall time. The yardstick at 1e6 points against the elastic block (docs/performance.md):
#   RATE=step OMP_NUM_THREADS=2 bash bench/scene_ratio.sh 5 "mls_yardstick" "elastic_block"
# threads=N in a scene's list runs that scene with N threads (OMP_NUM_THREADS otherwise): the
# 2-thread speed-up of whole runs, 1 and 2 threads alternated (docs/performance.md):
#   RATE=step bash bench/scene_ratio.sh 5 "porous_shock threads=1" "porous_shock threads=2"
# PHASES=1 also prints, per phase of the step (run.json phase_seconds), the median ns per
# particle-step of A and B and the median of the rounds' A / B times (the speed-up of B).
set -euo pipefail
n=$1; a=$2; b=$3; drv=${4:-build/shockmpm}; steps=${5:-100}
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
rate="${RATE:-run}"
[[ $rate == run || $rate == step ]] || { echo "scene_ratio.sh: RATE=$rate: allowed 'run' or 'step'" >&2; exit 2; }
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
run() {  # run "SCENE [threads=N] KEY=VALUE ..." LABEL -> M particle-steps/s
  local spec=($1) args=() threads=$OMP_NUM_THREADS kv
  for kv in "${spec[@]:1}"; do
    if [[ $kv == threads=* ]]; then threads=${kv#threads=}; else args+=("$kv"); fi
  done
  if [[ ${spec[0]} == mls_yardstick ]]; then
    OMP_NUM_THREADS=$threads "$(dirname "$drv")/bench/bench_mls" --rounds 1 run.max_steps="$steps" "${args[@]}" |
      sed -n 's/.* \([0-9.]*\) M particle-steps\/s.*/\1/p'
    return
  fi
  local sets=()
  for kv in "${args[@]}"; do sets+=(--set "$kv"); done
  rm -rf "$tmp/run"  # a failed run must not leave the last round's run.json to be read
  OMP_NUM_THREADS=$threads "$drv" run "$root/cases/bench/${spec[0]}.toml" --quiet --set run.max_steps="$steps" "${sets[@]}" --overwrite \
    --out "$tmp/run" > /dev/null || { echo "scene_ratio.sh: the run of '$1' failed" >&2; return 1; }
  /usr/bin/python3 - "$tmp/run/run.json" "$rate" "$tmp/phases_$2.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
with open(sys.argv[3], "a") as f:  # ns per particle-step of each phase, one line per run
    f.write(json.dumps({k: v / (r["particles"] * r["steps"]) * 1e9 for k, v in r["phase_seconds"].items()}) + "\n")
if sys.argv[2] == "run":
    print(r["particle_steps_per_s"] / 1e6)
else:
    t = sum(v for k, v in r["phase_seconds"].items() if k not in ("output", "diagnostics"))
    print(r["particles"] * r["steps"] / t / 1e6)
PY
}
for i in $(seq "$n"); do
  ra=$(run "$a" A) && rb=$(run "$b" B) || exit 1
  echo "$i $ra $rb"
done | tee "$tmp/rounds.txt"
/usr/bin/python3 - "$tmp/rounds.txt" "$a" "$b" "$OMP_NUM_THREADS" "$rate" <<'PY'
import statistics, sys
rows = [tuple(map(float, l.split()[1:])) for l in open(sys.argv[1])]
r = [b / a for a, b in rows]
print(f"{sys.argv[3]} / {sys.argv[2]}, {sys.argv[4]} thread(s), {sys.argv[5]} rate: rates {statistics.median(a for a, _ in rows):.3f} / "
      f"{statistics.median(b for _, b in rows):.3f} M/s (medians); ratio median {statistics.median(r):.3f}, "
      f"range {min(r):.3f}-{max(r):.3f} over {len(r)} rounds")
PY
if [[ ${PHASES:-0} == 1 && -f $tmp/phases_A.txt && -f $tmp/phases_B.txt ]]; then
  /usr/bin/python3 - "$tmp/phases_A.txt" "$tmp/phases_B.txt" <<'PY'
import json, statistics, sys
A = [json.loads(l) for l in open(sys.argv[1])]
B = [json.loads(l) for l in open(sys.argv[2])]
print(f"{'phase':14s} {'A ns/p-step':>12s} {'B ns/p-step':>12s} {'A / B (range)':>22s}")
for k in A[0]:
    if not any(a[k] for a in A):  # phases the scene does not have (contact, heat)
        continue
    r = [a[k] / b[k] for a, b in zip(A, B) if b[k] > 0]
    print(f"{k:14s} {statistics.median(a[k] for a in A):12.2f} {statistics.median(b[k] for b in B):12.2f} "
          f"{statistics.median(r):8.3f} ({min(r):.2f}-{max(r):.2f})")
PY
fi
