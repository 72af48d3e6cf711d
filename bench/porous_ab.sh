#!/usr/bin/env bash
# Old build against new on the porous benchmark scene, alternated, 2 threads: the particle-steps
# per second the driver reports (run.json), median of N runs each, with the median wall time and
# phase times (run.json's phase_seconds) and the median of the new/old ratios of each round.
#   [CASE=FILE] [ALSO="B3 B4 ..."] bash bench/porous_ab.sh OLD_SHOCKMPM NEW_SHOCKMPM [N=3] [STEPS=300] [EXTRA --set ...]
# CASE: another scene (default cases/bench/porous_shock.toml). OLD and NEW may be wrapper
# scripts that add --set keys (e.g. `exec build/shockmpm "$@" --set grid.tile_cells=8`).
# ALSO: more builds or wrappers, run in the same rounds after NEW (a sweep of settings); each is
# reported under its file name and compared with OLD.
set -euo pipefail
old="$1"; new="$2"; n="${3:-3}"; steps="${4:-300}"; shift 4 || shift $#
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
case_file="${CASE:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/cases/bench/porous_shock.toml}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
labels=(old new); bins=("$old" "$new")
for b in ${ALSO:-}; do labels+=("$(basename "$b")"); bins+=("$b"); done
for i in $(seq "$n"); do
  for k in "${!bins[@]}"; do
    "${bins[$k]}" run "$case_file" --quiet --set run.max_steps="$steps" "$@" --overwrite --out "$tmp/run" > /dev/null
    /usr/bin/python3 - "$tmp/run/run.json" "${labels[$k]}" "$i" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
ph = j["phase_seconds"]
print(sys.argv[2], sys.argv[3], j["particle_steps_per_s"], j["wall_seconds"],
      *(ph.get(k, 0.0) for k in ("p2g", "g2p", "contact", "grid", "constitutive", "sort")))
PY
  done
done | tee "$tmp/all.txt"
/usr/bin/python3 - "$tmp/all.txt" <<'PY'
import collections, statistics, sys
rows = collections.defaultdict(dict)
for line in open(sys.argv[1]):
    label, i, *v = line.split()
    rows[label][int(i)] = [float(x) for x in v]
names = ["wall", "p2g", "g2p", "contact", "grid", "constitutive", "sort"]
for label, runs in rows.items():
    med = [statistics.median(r[c] for r in runs.values()) for c in range(len(names) + 1)]
    line = f"{label} median: {med[0]:.4g} particle-steps/s; seconds " + ", ".join(
        f"{n} {m:.3f}" for n, m in zip(names, med[1:]))
    if label != "old":
        ratios = [runs[i][0] / rows["old"][i][0] for i in runs if i in rows["old"]]
        line += f"; rate ratio to old, median of rounds {statistics.median(ratios):.3f}"
    print(line)
PY
