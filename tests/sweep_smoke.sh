#!/usr/bin/env bash
# scripts/sweep.sh: every point checked before any runs (a typo in the last point: exit 2, nothing
# run); each point in its own directory with its overrides in points.tsv and a row of summary.md.
#   tests/sweep_smoke.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
fail=0
say() { echo "$*" >&2; fail=1; }
export SHOCKMPM="$EXE"
small='run.end_time_ns=2.0;grid.x_range_um=[0.0, 60.0];bodies.0.x_range_um=[0.0, 60.0]'
SHOCKMPM="$EXE" bash "$SRC/scripts/sweep.sh" "$SRC/cases/quickstart.toml" "$TMP/bad" "$small" \
  "$small;bodies.0.voids.porosty=0.3" > "$TMP/bad.log" 2>&1
rc=$?
[ "$rc" = 2 ] || say "invalid point: exit $rc, expected 2"
grep -q "did you mean 'porosity'" "$TMP/bad.log" || say "invalid point: the typo not named: $(cat "$TMP/bad.log")"
[ -e "$TMP/bad/p01" ] && say "a point ran although another was invalid"
bash "$SRC/scripts/sweep.sh" "$SRC/cases/quickstart.toml" "$TMP/sw" --threads 2 "$small;bodies.0.voids.porosity=0.3" \
  "$small;bodies.target.velocity_m_s=[0.0, -800.0]" > "$TMP/sw.log" 2>&1 || say "sweep: exit $?: $(cat "$TMP/sw.log")"
for d in p01 p02; do
  grep -Eq '"status" *: *"completed"' "$TMP/sw/$d/run.json" || say "$d not completed"
  grep -q "^| $d | 0.[0-9]* | [0-9]* |" "$TMP/sw/summary.md" || say "$d: no row in summary.md"
done
grep -q "^| p01 | 0.3" "$TMP/sw/summary.md" || say "p01 is not the porosity 0.3 point: $(cat "$TMP/sw/summary.md")"
grep -q "^| p02 | 0.50[0-9] | 800 |" "$TMP/sw/summary.md" || say "p02 is not the 800 m/s point: $(cat "$TMP/sw/summary.md")"
[ "$(wc -l < "$TMP/sw/points.tsv")" = 3 ] || say "points.tsv: $(cat "$TMP/sw/points.tsv")"
# a seed ensemble: one point, two seeds
bash "$SRC/scripts/sweep.sh" "$SRC/cases/quickstart.toml" "$TMP/ens" --threads 2 --seeds 7,8 \
  --seed-key bodies.0.voids.seed "$small" > "$TMP/ens.log" 2>&1 || say "seed sweep: exit $?: $(cat "$TMP/ens.log")"
for s in 7 8; do
  grep -Eq '"status" *: *"completed"' "$TMP/ens/p01/seed_$s/run.json" || say "seed $s not completed"
  grep -q "seed = $s\$" "$TMP/ens/p01/seed_$s/case_resolved.toml" || say "seed $s: the seed is not in its resolved case"
done
grep -q "^| p01 | 2 | 0.[0-9]* +- 0.[0-9]* |" "$TMP/ens/summary.md" || say "ensemble row not mean +- sd over 2 seeds: $(cat "$TMP/ens/summary.md")"
/usr/bin/python3 - "$TMP/ens/p01" <<'PY' || say "series_ensemble.csv is not the mean and sd of the seeds' series.csv"
import csv, statistics, sys
d = sys.argv[1]
ens = list(csv.DictReader(open(f"{d}/series_ensemble.csv")))
a, b = (list(csv.DictReader(open(f"{d}/seed_{s}/series.csv"))) for s in (7, 8))
assert ens and ens[0]["n_seeds"] == "2", ens[:1]
assert a[0]["time_ns"] == ens[0]["time_ns"] and a[0]["region"] == ens[0]["region"]
for c in ("count", "rho_mean_gcc", "open_porosity"):
    x, y = float(a[0][c]), float(b[0][c])
    m, sd = float(ens[0][c + "_mean"]), float(ens[0][c + "_sd"])
    assert abs(m - (x + y) / 2) <= 1e-6 * abs(m) + 1e-12, (c, m, x, y)
    assert abs(sd - statistics.stdev([x, y])) <= 1e-6 * abs(sd) + 1e-9, (c, sd, x, y)
PY
bash "$SRC/scripts/sweep.sh" "$SRC/cases/quickstart.toml" "$TMP/ens_bad" --seeds 1,x "$small" > /dev/null 2>&1
[ $? = 2 ] || say "--seeds 1,x accepted"
[ "$fail" = 0 ] && echo "sweep_smoke: PASS" || echo "sweep_smoke: FAIL"
exit "$fail"
