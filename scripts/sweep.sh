#!/usr/bin/env bash
# A parameter sweep: one case, one run per list of overrides, each into its own directory, then
# one summary table (scripts/study_summary.py) with the overrides beside each row.
#   bash scripts/sweep.sh CASE.toml OUTROOT [--threads N] [--region R] POINT [POINT ...]
# A POINT is one or more --set overrides separated by ';' (TOML values, see the README), e.g.
#   bash scripts/sweep.sh cases/paper/baseline_p050_v1000.toml out/sweep_v \
#     'bodies.target.velocity_m_s=[0.0, -500.0]' 'bodies.target.velocity_m_s=[0.0, -800.0]' \
#     'bodies.target.velocity_m_s=[0.0, -1000.0]'
#   bash scripts/sweep.sh cases/quickstart.toml out/sweep_phi \
#     'bodies.0.voids.porosity=0.3;run.end_time_ns=100.0' 'bodies.0.voids.porosity=0.5;run.end_time_ns=100.0'
# Point k runs in OUTROOT/pNN (NN = k, from 01); OUTROOT/points.tsv maps each to its overrides;
# OUTROOT/summary.md is the table. A point that does not complete is listed with its status and
# the sweep goes on; the exit status is 1 if any point failed (its run.json says why), 2 when the
# case or an override is invalid (checked for every point before anything runs). Every run passes
# --overwrite: rerunning a sweep replaces its results; a killed point resumes with `shockmpm resume`.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ $# -ge 3 ] || { sed -n 2,17p "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
CASE="$1"; OUTROOT="$2"; shift 2
threads=(); region=I; points=()
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads=(--threads "$2"); shift 2;;
    --region) region="$2"; shift 2;;
    *) points+=("$1"); shift;;
  esac
done
[ ${#points[@]} -gt 0 ] || { echo "sweep: no points given" >&2; exit 2; }
EXE="${SHOCKMPM:-$ROOT/build/shockmpm}"
if [ -z "${SHOCKMPM:-}" ]; then BUILD_TARGET=shockmpm source "$ROOT/scripts/setup.sh"; cd "$ROOT"; fi
sets_of() {  # the --set arguments of a point
  local IFS=';' s
  for s in $1; do s="${s#"${s%%[![:space:]]*}"}"; [ -n "$s" ] && printf '%s\0' --set "$s"; done
}
# every point is checked before any runs: a typo in the last point fails now, not in an hour
for p in "${points[@]}"; do
  mapfile -d '' sets < <(sets_of "$p")
  "$EXE" check "$CASE" "${sets[@]}" > /dev/null || { echo "sweep: point '$p' is invalid (above)" >&2; exit 2; }
done
mkdir -p "$OUTROOT"
printf 'dir\toverrides\tstatus\n' > "$OUTROOT/points.tsv"
outs=(); failed=0; k=0
for p in "${points[@]}"; do
  k=$((k + 1)); d="$OUTROOT/p$(printf %02d "$k")"
  mapfile -d '' sets < <(sets_of "$p")
  echo "== point $k/${#points[@]}: $p -> $d"
  if "$EXE" run "$CASE" --out "$d" --overwrite --quiet "${threads[@]}" "${sets[@]}"; then st=completed; else st="failed (exit $?)"; failed=1; fi
  printf '%s\t%s\t%s\n' "$(basename "$d")" "$p" "$st" >> "$OUTROOT/points.tsv"
  outs+=("$d")
done
{
  echo "# Sweep of $CASE"
  echo
  echo "| dir | overrides | status |"
  echo "|---|---|---|"
  tail -n +2 "$OUTROOT/points.tsv" | while IFS=$'\t' read -r d o s; do echo "| $d | \`$o\` | $s |"; done
  echo
  /usr/bin/python3 "$ROOT/scripts/study_summary.py" "${outs[@]}" --region "$region" --dir-names || echo "(no summary table: study_summary.py failed)"
} > "$OUTROOT/summary.md"
cat "$OUTROOT/summary.md"
exit "$failed"
