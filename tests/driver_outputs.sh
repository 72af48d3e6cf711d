#!/usr/bin/env bash
# The output directory as a user meets it: run.json's provenance; case_resolved.toml
# reruns to the same result; an earlier run's
# results are never replaced without --overwrite; --overwrite clears that run's outputs (stale
# figures/, a killed run's .tmp files) and keeps the user's own files; a write that fails (a
# full disk, emulated by /dev/full) ends the run with exit 1 and run.json "failed" naming the
# file and the errno text; so does a write that fails at the first snapshot, the XDMF index,
# series.h5 or a checkpoint. Snapshots carry the velocity field of each point (`field`).
#   tests/driver_outputs.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
fail=0
# the quick start narrowed to 60 um (its voids of 8 um still use both velocity fields) and 4 ns
run() { "$EXE" run "$SRC/cases/quickstart.toml" --quiet --threads 2 --set run.end_time_ns=4.0 \
          --set run.snapshot_interval_ns=2.0 --set run.diagnostics_interval_ns=1.0 \
          --set 'grid.x_range_um=[0.0, 60.0]' --set 'bodies.0.x_range_um=[0.0, 60.0]' "$@"; }
say() { echo "$*" >&2; fail=1; }

run --out "$TMP/a" > /dev/null 2>&1 || say "first run failed"
/usr/bin/python3 - "$TMP/a/run.json" <<'PY' || fail=1
import json, sys
p = json.load(open(sys.argv[1]))["provenance"]
for k in ("git_commit", "git_dirty", "compiler", "build_type", "cxx_flags", "date_utc", "host", "threads", "command_line"):
    assert k in p and p[k] != "", f"provenance lacks {k}: {p}"
assert "--out" in p["command_line"] and "quickstart.toml" in p["command_line"], p["command_line"]
PY
# the snapshot names each point's velocity field (the quickstart's void faces use both)
/usr/bin/python3 - "$TMP/a/fields/snap_00000000.h5" <<'PY' || { say "snapshot lacks a field dataset of 0s and 1s"; }
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")["particles"]
v = f["field"][:]
assert v.shape == f["id"].shape and set(np.unique(v).tolist()) == {0.0, 1.0}, np.unique(v)
PY
cp "$TMP/a/run.json" "$TMP/run.json.first"

# case_resolved.toml runs again, anywhere, to the same result (same threads: bitwise)
cp "$TMP/a/case_resolved.toml" "$TMP/again.toml"
"$EXE" run "$TMP/again.toml" --quiet --threads 2 --out "$TMP/again" > /dev/null 2>&1 || say "case_resolved.toml did not run"
for f in energy.csv series.csv front.csv wall.csv; do
  cmp -s "$TMP/a/$f" "$TMP/again/$f" || say "case_resolved.toml: $f differs from the first run's"
done

# again without --overwrite: refused (exit 2), nothing of the earlier run touched
run --out "$TMP/a" > /dev/null 2> "$TMP/err"; rc=$?
[ "$rc" = 2 ] || say "rerun into a used --out: exit $rc, expected 2"
grep -q -- "--overwrite" "$TMP/err" || { say "the refusal does not name --overwrite:"; cat "$TMP/err" >&2; }
cmp -s "$TMP/a/run.json" "$TMP/run.json.first" || say "the refused run changed run.json"

# --overwrite: the earlier outputs go, the user's own file stays
mkdir -p "$TMP/a/figures"; touch "$TMP/a/figures/old.png" "$TMP/a/notes.txt" "$TMP/a/fields/snap_00000999.h5.tmp"
run --out "$TMP/a" --overwrite > /dev/null 2>&1 || say "--overwrite run failed"
[ -e "$TMP/a/figures" ] && say "--overwrite left the earlier run's figures/"
[ -e "$TMP/a/fields/snap_00000999.h5.tmp" ] && say "--overwrite left a .tmp file"
[ -e "$TMP/a/notes.txt" ] || say "--overwrite removed a file that is not a run output"
grep -Eq '"status" *: *"completed"' "$TMP/a/run.json" || say "--overwrite run not completed"

# a full disk at each CSV: exit 1, run.json "failed" with the file and the reason, on stderr too
for f in energy.csv series.csv wall.csv front.csv; do
  d="$TMP/full-${f%.csv}"; mkdir -p "$d"; ln -s /dev/full "$d/$f"
  run --out "$d" > /dev/null 2> "$TMP/err"; rc=$?
  [ "$rc" = 1 ] || say "$f on a full disk: exit $rc, expected 1"
  grep -Eq '"status" *: *"failed"' "$d/run.json" || say "$f on a full disk: run.json not 'failed'"
  grep -q "$f: No space left on device" "$d/run.json" || { say "$f: run.json does not name the file and errno:"; grep message "$d/run.json" >&2; }
  grep -q "No space left on device" "$TMP/err" || say "$f: nothing on stderr"
done
# a write that fails at each HDF5 / index / checkpoint output (its final name taken by a
# directory, so the rename fails; the same path as a full disk in write-then-rename): exit 1,
# run.json "failed" naming the file, the CSV rows before it whole
for f in fields/snap_00000000.h5 fields/particles.xdmf series.h5 checkpoint; do
  d="$TMP/block-${f//\//-}"; mkdir -p "$d/$f/x"
  [ "$f" = checkpoint ] && { rm -r "$d/$f"; touch "$d/$f"; }  # a file where the directory goes
  run --out "$d" --set run.snapshot_interval_ns=1.0 --set run.checkpoint_interval_s=1e-6 > /dev/null 2> "$TMP/err"; rc=$?
  [ "$rc" = 1 ] || say "$f blocked: exit $rc, expected 1"
  grep -Eq '"status" *: *"failed"' "$d/run.json" || say "$f blocked: run.json not 'failed'"
  grep -q "$(basename "$f")" "$d/run.json" || { say "$f blocked: run.json does not name it:"; grep message "$d/run.json" >&2; }
  grep -q "failed: " "$TMP/err" || say "$f blocked: nothing on stderr"
done
[ "$fail" = 0 ] && echo "driver_outputs: PASS" || echo "driver_outputs: FAIL"
exit "$fail"
