#!/usr/bin/env bash
# The reference study: runs every case in cases/paper/ (3-13 min each on 2 cores, docs/performance.md; porosity
# 0.09 and 0.01, at h = 8 um, under 4 min; docs/study.md), makes every figure, and writes the
# summary table to out/paper/summary.md.
#   bash scripts/study.sh [CASE.toml ...]    (default: all of cases/paper/*.toml)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_TARGET=shockmpm source "$ROOT/scripts/setup.sh"
cd "$ROOT"
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(cases/paper/*.toml)
outs=()
for c in "${cases[@]}"; do
  name="$(basename "$c" .toml)"
  out="out/paper/$name"
  echo "== $name"
  "$BUILD_DIR/shockmpm" run "$c" --out "$out" --overwrite || echo "run $name did not complete (see $out/run.json)"
  /usr/bin/python3 scripts/figures.py "$out" --time-ns 500 > /dev/null || true
  outs+=("$out")
done
# sweeps overlaid: velocity (porosity 0.5), porosity (1000 m/s), void size (0.5, 1000 m/s)
sel() { for o in "${outs[@]}"; do case "$o" in *"$1"*) echo "$o";; esac; done; }
mapfile -t vel < <(sel baseline; sel velocity_)
mapfile -t por < <(sel baseline; sel porosity_)
mapfile -t voi < <(sel baseline; sel voidsize_)
[ ${#vel[@]} -gt 1 ] && /usr/bin/python3 scripts/figures.py "${vel[@]}" --only compare --out out/paper/figures/velocity
[ ${#por[@]} -gt 1 ] && /usr/bin/python3 scripts/figures.py "${por[@]}" --only compare --out out/paper/figures/porosity
[ ${#voi[@]} -gt 1 ] && /usr/bin/python3 scripts/figures.py "${voi[@]}" --only compare --out out/paper/figures/voidsize
/usr/bin/python3 scripts/study_summary.py "${outs[@]}" > out/paper/summary.md
cat out/paper/summary.md
