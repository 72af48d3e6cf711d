#!/usr/bin/env bash
# bench/experiment_hugoniot.py --quick on one measured row of bench/data/porous_iron_hugoniot.csv:
# row 3 (sintered iron, distention 1.316, up 0.788 km/s, measured Us 2.742 km/s), one seed,
# h = 4 um, voids of 10 um, the library's iron. The harness runs end to end (case, run, front fit,
# frame change, tables, chart) and the engine's Us stays within TOL of the measured Us.
# Measured: +6.8 % (Us 2.929 km/s; 13.9 k particles, 1095 steps; the test 7 s on 2 threads sharing the
# 2 cores with another run). TOL = 12 %: that error plus the seed-to-seed spread of this row at
# h = 4 um (sample standard deviation 4.8 % over seeds 1-3: 2.929, 2.978, 2.720 km/s), the most a
# build that perturbs the void collapse could move one seed's front. A lost frame change (Us
# without + up) is -22 % and fails. It guards against regressions of the harness and of the
# engine at this resolution; it is not the validation claim (the full table at h = 4 and 2 um,
# 3 seeds; at h = 2 um this row is +4.7 % +- 5.4 %, 0.1 % from h = 4). Release only.
#   tests/experiment_quick.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
ROW=3
TOL=12
/usr/bin/python3 "$SRC/bench/experiment_hugoniot.py" --data "$SRC/bench/data/porous_iron_hugoniot.csv" \
  --out "$TMP" --driver "$EXE" --threads "${OMP_NUM_THREADS:-2}" --material iron \
  --quick --rows "$ROW" --h 4 --check "$TOL"
rc=$?
for f in experiment.json experiment.md experiment_us_up.png; do
  [ -s "$TMP/$f" ] || { echo "experiment_quick: $f missing"; rc=1; }
done
[ "$rc" = 0 ] && echo "experiment_quick: PASS" || echo "experiment_quick: FAIL (exit $rc)"
exit $rc
