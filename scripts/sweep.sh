#!/usr/bin/env bash
# A parameter sweep: one case, one run per list of overrides, each into its own directory, then
# one summary table (scripts/study_summary.py) with the overrides beside each row.
#   bash scripts/sweep.sh CASE.toml OUTROOT [--threads N] [--region R] [--seeds S1,S2,...]
#       [--seed-key KEY] POINT [POINT ...]
# A POINT is one or more --set overrides separated by ';' (TOML values, see the README), e.g.
#   bash scripts/sweep.sh cases/paper/baseline_p050_v1000.toml out/sweep_v \
#     'bodies.target.velocity_m_s=[0.0, -500.0]' 'bodies.target.velocity_m_s=[0.0, -800.0]' \
#     'bodies.target.velocity_m_s=[0.0, -1000.0]'
#   bash scripts/sweep.sh cases/quickstart.toml out/sweep_phi \
#     'bodies.0.voids.porosity=0.3;run.end_time_ns=100.0' 'bodies.0.voids.porosity=0.5;run.end_time_ns=100.0'
# A seed ensemble: --seeds 2010,2011,2012 runs every point once per seed, setting KEY=S (KEY:
# --seed-key, default bodies.target.voids.seed), into OUTROOT/pNN/seed_S; the point's row of
# summary.md gives every number as mean +- sample standard deviation over the seeds, and
# OUTROOT/pNN/series_ensemble.csv every regional statistic of series.csv as mean and sd. One
# point with no override: POINT ''. Without --seeds, point k runs in OUTROOT/pNN (NN = k, from
# 01). OUTROOT/points.tsv maps each run directory to its overrides; OUTROOT/summary.md is the
# table. A point that does not complete is listed with its status and
# the sweep goes on; the exit status is 1 if any point failed (its run.json says why), 2 when the
# case or an override is invalid (checked for every point before anything runs). Every run passes
# --overwrite: rerunning a sweep replaces its results; a killed point resumes with `shockmpm resume`.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ $# -ge 3 ] || { sed -n 2,24p "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
CASE="$1"; OUTROOT="$2"; shift 2
threads=(); region=I; points=(); seeds=(); seed_key=bodies.target.voids.seed
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads=(--threads "$2"); shift 2;;
    --region) region="$2"; shift 2;;
    --seeds) IFS=, read -ra seeds <<< "$2"; shift 2;;
    --seed-key) seed_key="$2"; shift 2;;
    *) points+=("$1"); shift;;
  esac
done
for s in "${seeds[@]}"; do
  [[ "$s" =~ ^[0-9]+$ ]] || { echo "sweep: --seeds takes non-negative integers separated by commas, got '$s'" >&2; exit 2; }
done
[ ${#points[@]} -gt 0 ] || { echo "sweep: no points given" >&2; exit 2; }
EXE="${SHOCKMPM:-$ROOT/build/shockmpm}"
if [ -z "${SHOCKMPM:-}" ]; then BUILD_TARGET=shockmpm source "$ROOT/scripts/setup.sh"; cd "$ROOT"; fi
sets_of() {  # the --set arguments of a point
  local IFS=';' s
  for s in $1; do s="${s#"${s%%[![:space:]]*}"}"; [ -n "$s" ] && printf '%s\0' --set "$s"; done
}
seed_of=("")  # the seed override of each run of a point ('' without --seeds)
[ ${#seeds[@]} -gt 0 ] && seed_of=("${seeds[@]/#/$seed_key=}")
# every point (with its first seed) is checked before any runs: a typo in the last point fails
# now, not in an hour
for p in "${points[@]}"; do
  mapfile -d '' sets < <(sets_of "$p;${seed_of[0]}")
  "$EXE" check "$CASE" "${sets[@]}" > /dev/null || { echo "sweep: point '$p' is invalid (above)" >&2; exit 2; }
done
mkdir -p "$OUTROOT"
printf 'dir\toverrides\tstatus\n' > "$OUTROOT/points.tsv"
outs=(); failed=0; k=0
for p in "${points[@]}"; do
  k=$((k + 1)); pd="$OUTROOT/p$(printf %02d "$k")"
  for so in "${seed_of[@]}"; do
    d="$pd"; [ -n "$so" ] && d="$pd/seed_${so##*=}"
    mapfile -d '' sets < <(sets_of "$p;$so")
    echo "== point $k/${#points[@]}: $p${so:+ ($so)} -> $d"
    if "$EXE" run "$CASE" --out "$d" --overwrite --quiet "${threads[@]}" "${sets[@]}"; then st=completed; else st="failed (exit $?)"; failed=1; fi
    printf '%s\t%s\t%s\n' "${d#"$OUTROOT"/}" "$p${so:+;$so}" "$st" >> "$OUTROOT/points.tsv"
  done
  outs+=("$pd")
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
