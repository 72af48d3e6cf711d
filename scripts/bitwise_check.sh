#!/usr/bin/env bash
# Runs a fixed set of cases with one driver build and, given a second output tree, compares
# every CSV byte for byte and every dataset of series.h5 and of the last snapshot with h5diff.
# The set: the quick start, the dense impact, the porous strip, 300 steps of each of the eight
# paper cases, and variants of the porous strip (MUSL/APIC, MUSL/FLIP, USL/FLIP, linear, uGIMP,
# cubic, heat conduction) and the two-disk contact case.
#   bash scripts/bitwise_check.sh DRIVER OUTDIR [REFDIR]
# Without REFDIR it only runs. With REFDIR it prints one line per case and exits non-zero when
# any file differs. FILTER=regex runs only the matching case names; RERUN=1 runs again the
# cases whose output is there already. Needs h5diff (Debian package hdf5-tools).
set -uo pipefail
drv=$(readlink -f "$1"); out=$2; ref=${3:-}
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cases=(
  "quickstart|cases/quickstart.toml|"
  "dense_impact_1000|cases/verify/dense_impact_1000.toml|"
  "porous_strip|cases/verify/porous_strip.toml|"
  "strip_musl_apic|cases/verify/porous_strip.toml|--set solver.scheme=\"musl\" --set contact.void_faces=\"single_field\" --set run.max_steps=300"
  "strip_musl_flip|cases/verify/porous_strip.toml|--set solver.scheme=\"musl\" --set solver.transfer=\"flip\" --set contact.void_faces=\"single_field\" --set run.max_steps=300"
  "strip_usl_flip|cases/verify/porous_strip.toml|--set solver.transfer=\"flip\" --set run.max_steps=300"
  "strip_linear|cases/verify/porous_strip.toml|--set solver.shape=\"linear\" --set run.max_steps=300"
  "strip_ugimp|cases/verify/porous_strip.toml|--set solver.shape=\"ugimp\" --set run.max_steps=300"
  "strip_cubic|cases/verify/porous_strip.toml|--set solver.shape=\"cubic\" --set run.max_steps=300"
  "strip_heat|cases/verify/porous_strip.toml|--set solver.heat_conduction=true --set run.max_steps=300"
  "elastic_disks|cases/verify/elastic_disks.toml|--set run.max_steps=300"
)
for f in "$ROOT"/cases/paper/*.toml; do
  cases+=("paper_$(basename "$f" .toml)|cases/paper/$(basename "$f")|--set run.max_steps=300")
done
mkdir -p "$out"
fail=0
for c in "${cases[@]}"; do
  IFS='|' read -r name file args <<<"$c"
  [[ -n "${FILTER:-}" && ! "$name" =~ ${FILTER} ]] && continue
  if [[ ! -f "$out/$name/run.json" || -n "${RERUN:-}" ]]; then
    # shellcheck disable=SC2086
    (cd "$ROOT" && "$drv" run "$file" --out "$out/$name" --overwrite --quiet $args) >"$out/$name.log" 2>&1 \
      || { echo "$name: run failed (exit $?, $out/$name.log)"; fail=1; continue; }
  fi
  [[ -z "$ref" ]] && { echo "$name: ran"; continue; }
  bad=()
  for a in "$ref/$name"/*.csv; do
    cmp -s "$a" "$out/$name/$(basename "$a")" || bad+=("$(basename "$a")")
  done
  for h in series.h5 $(cd "$ref/$name" && ls fields/snap_*.h5 2>/dev/null | sort -V | tail -n 1); do
    [[ -f "$ref/$name/$h" ]] || continue
    h5diff -q "$ref/$name/$h" "$out/$name/$h" >/dev/null 2>&1 || bad+=("$h")
  done
  if ((${#bad[@]})); then echo "$name: DIFFERS ${bad[*]}"; fail=1; else echo "$name: identical"; fi
done
exit $fail
