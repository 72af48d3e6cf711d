#!/usr/bin/env bash
# The driver as a user meets it: SIGTERM stops a run like SIGINT (exit 3, last state written,
# run.json "interrupted", the reason on stderr with --quiet too, every CSV row whole);
# --version; a bare case file name run from the case's own directory.
#   tests/driver_signals.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
fail=0
# a run long enough to be stopped: the quick start to 2000 ns (about 3 minutes)
"$EXE" run "$SRC/cases/quickstart.toml" --out "$TMP/run" --quiet --threads 2 --set run.end_time_ns=2000.0 \
  --set run.diagnostics_interval_ns=0.5 2> "$TMP/stderr" &
pid=$!
for _ in $(seq 1 100); do [ -s "$TMP/run/energy.csv" ] && [ "$(wc -l < "$TMP/run/energy.csv")" -ge 3 ] && break; sleep 0.1; done
kill -TERM "$pid"
wait "$pid"; rc=$?
[ "$rc" = 3 ] || { echo "SIGTERM: exit $rc, expected 3" >&2; fail=1; }
grep -Eq '"status" *: *"interrupted"' "$TMP/run/run.json" || { echo "run.json not 'interrupted'" >&2; fail=1; }
grep -q "interrupted by SIGTERM" "$TMP/run/run.json" || { echo "run.json does not name SIGTERM" >&2; fail=1; }
grep -q "interrupted: interrupted by SIGTERM" "$TMP/stderr" || { echo "no reason on stderr under --quiet" >&2; cat "$TMP/stderr" >&2; fail=1; }
ls "$TMP/run/fields/"snap_*.h5 > /dev/null 2>&1 || { echo "no snapshot written" >&2; fail=1; }
for f in energy.csv series.csv front.csv wall.csv; do
  /usr/bin/python3 - "$TMP/run/$f" <<'PY' || fail=1
import sys
rows = open(sys.argv[1]).read().split("\n")
assert rows[-1] == "", f"{sys.argv[1]}: last row cut: {rows[-1]!r}"
n = len(rows[0].split(","))
bad = [r for r in rows[1:-1] if len(r.split(",")) != n]
assert not bad and len(rows) > 2, f"{sys.argv[1]}: {len(bad)} rows with a wrong column count, {len(rows) - 2} rows"
PY
done
# --version
"$EXE" --version | grep -q "^shockmpm [0-9]" || { echo "--version" >&2; fail=1; }
# a bare file name, from the case's directory (materials.toml found there)
(cd "$SRC/cases" && "$EXE" check quickstart.toml > "$TMP/check.txt" 2>&1) || { echo "check with a bare file name failed:" >&2; cat "$TMP/check.txt" >&2; fail=1; }
[ "$fail" = 0 ] && echo "driver_signals: PASS" || echo "driver_signals: FAIL"
exit "$fail"
