#!/usr/bin/env bash
# The accuracy harness's quick matrix still runs, and the dense errors stay under their bounds
# (bench/accuracy.py BOUNDS, on every dense run but the linear hat: Us 2 %, wall stress 3 %, P 2 %,
# rho 1 %, T 5 %, energy 1 %), so a regression in accuracy fails CI the way a crash does.
#   tests/accuracy_quick.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
/usr/bin/python3 "$SRC/bench/accuracy.py" --quick --check --no-charts --driver "$EXE" --out "$TMP" \
  --threads "${OMP_NUM_THREADS:-2}" > "$TMP/report.md" 2> "$TMP/err"
rc=$?
cat "$TMP/report.md"
[ "$rc" = 0 ] || { echo "accuracy_quick: FAIL (exit $rc)"; cat "$TMP/err"; exit 1; }
echo "accuracy_quick: PASS"
