#!/usr/bin/env bash
# The rate of one bench scene against another's, the two runs alternated in each round (the
# VM's drift between sittings moves single rates by up to 16 %): particle-steps per second from
# run.json, per round and the median of the per-round ratios B / A.
#   [OMP_NUM_THREADS=1] bash bench/scene_ratio.sh N "SCENE_A [KEY=VALUE ...]" "SCENE_B [KEY=VALUE ...]" [DRIVER] [STEPS]
# SCENE: a file of cases/bench/ without .toml; KEY=VALUE: --set overrides. Example, the dense
# 3D column against the dense 2D strip at 1e6 points on one thread (docs/performance.md, "3D"):
#   bash bench/scene_ratio.sh 5 "dense_shock grid.cell_size_um=1.25" "dense_shock_3d grid.cell_size_um=4.0"
set -euo pipefail
n=$1; a=$2; b=$3; drv=${4:-build/shockmpm}; steps=${5:-100}
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
run() {  # run "SCENE KEY=VALUE ..." -> M particle-steps/s
  local spec=($1) args=()
  for kv in "${spec[@]:1}"; do args+=(--set "$kv"); done
  "$drv" run "$root/cases/bench/${spec[0]}.toml" --quiet --set run.max_steps="$steps" "${args[@]}" --overwrite \
    --out "$tmp/run" > /dev/null
  /usr/bin/python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['particle_steps_per_s'] / 1e6)" \
    "$tmp/run/run.json"
}
for i in $(seq "$n"); do
  ra=$(run "$a"); rb=$(run "$b")
  echo "$i $ra $rb"
done | tee "$tmp/rounds.txt"
/usr/bin/python3 - "$tmp/rounds.txt" "$a" "$b" "$OMP_NUM_THREADS" <<'PY'
import statistics, sys
rows = [tuple(map(float, l.split()[1:])) for l in open(sys.argv[1])]
r = [b / a for a, b in rows]
print(f"{sys.argv[3]} / {sys.argv[2]}, {sys.argv[4]} thread(s): rates {statistics.median(a for a, _ in rows):.3f} / "
      f"{statistics.median(b for _, b in rows):.3f} M/s (medians); ratio median {statistics.median(r):.3f}, "
      f"range {min(r):.3f}-{max(r):.3f} over {len(r)} rounds")
PY
