#!/usr/bin/env bash
# Checkpoint and resume as a user meets them: a run killed by SIGKILL at a random
# moment (snapshots every 1 ns, so often mid-snapshot or mid-checkpoint) and resumed at another
# thread count ends with every output file byte for byte that of the uninterrupted run: CSV rows
# neither duplicated nor missing (gauges.csv and freesurface.csv too: the resumed run follows the
# same points), the same snapshots, XDMF index and series.h5. A SIGTERM writes a
# checkpoint; a damaged newest checkpoint is named and the one before it used; a completed run,
# a directory without checkpoints and a directory another run is writing are refused (exit 2).
# A 3D run resumes the same way (the engine taken from the checkpoint's case).
#   tests/driver_restart.sh SHOCKMPM SOURCE_DIR [WIDTH_UM]
# WIDTH_UM: the 2D runs' width (120 um; the sanitizer build, whose runs take 8-10 times as long,
# passes 40 from tests/CMakeLists.txt: the same checks in a third of the time).
set -uo pipefail
EXE="$1"; SRC="$2"; W="${3:-120}"
[[ $W =~ ^[1-9][0-9]*$ ]] || { echo "driver_restart.sh: WIDTH_UM = '$W': a whole number of um, at least 1" >&2; exit 2; }
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
fail=0
say() { echo "$*" >&2; fail=1; }
# the quick start, narrowed to W um (120: about 1.3 s on 2 threads) and 24 ns, with a line of
# gauges down its middle and the free surface of its top
CASE="$SRC/cases/quickstart.toml"
SET=(--set run.end_time_ns=24.0 --set run.snapshot_interval_ns=1.0 --set run.diagnostics_interval_ns=0.5
     --set "grid.x_range_um=[0.0, $W.0]" --set "bodies.0.x_range_um=[0.0, $W.0]"
     --set "gauges=[{name = \"g\", from_um = [$((W / 2)).0, 10.0], to_um = [$((W / 2)).0, 390.0], count = 5}]"
     --set bodies.target.record_free_surface=true)
"$EXE" run "$CASE" --out "$TMP/full" --quiet --threads 2 "${SET[@]}" || say "uninterrupted run failed"
for f in gauges.csv freesurface.csv; do
  [ "$(cat "$TMP/full/$f" 2> /dev/null | wc -l)" -gt 45 ] || say "the uninterrupted run wrote no rows of $f"
done
[ -d "$TMP/full/checkpoint" ] && say "a completed run left its checkpoints"
same_as_full() {  # every output of the uninterrupted run, byte for byte
  local d="$1" f
  for f in $(cd "$TMP/full" && find . -type f ! -name run.json ! -name case_resolved.toml | sort); do
    cmp -s "$TMP/full/$f" "$d/$f" || say "$d: $f differs from the uninterrupted run's"
  done
  # the case differs in run.checkpoint_interval_s only
  cmp -s <(grep -v checkpoint_interval_s "$TMP/full/case_resolved.toml") <(grep -v checkpoint_interval_s "$d/case_resolved.toml") ||
    say "$d: case_resolved.toml differs in more than run.checkpoint_interval_s"
  [ "$(cd "$TMP/full" && find . -type f | sort)" = "$(cd "$d" && find . -type f | sort)" ] ||
    say "$d: other files than the uninterrupted run's: $(cd "$d" && find . -type f | sort | tr '\n' ' ')"
}
wait_for() {  # wait_for FILE-GLOB: up to 60 s
  for _ in $(seq 1 1200); do compgen -G "$1" > /dev/null && return 0; sleep 0.05; done
  return 1
}

# 1. SIGKILL after the second checkpoint, at a random moment; resumed on 1 thread
"$EXE" run "$CASE" --out "$TMP/kill" --quiet --threads 2 "${SET[@]}" --set run.checkpoint_interval_s=0.2 &
pid=$!
wait_for "$TMP/kill/checkpoint/ckpt_*.bin" || say "no checkpoint within 60 s"
sleep 0.$((RANDOM % 4 + 2))
kill -KILL "$pid" 2> /dev/null || say "the run ended before SIGKILL (make it longer)"
wait "$pid" 2> /dev/null
"$EXE" resume "$TMP/kill" --quiet --threads 1 || say "resume after SIGKILL: exit $?"
same_as_full "$TMP/kill"
grep -q '"restarts"' "$TMP/kill/run.json" || say "run.json has no restarts entry"
grep -Eq '"status" *: *"completed"' "$TMP/kill/run.json" || say "resumed run.json not completed"

# 2. SIGTERM: a checkpoint at the stop; the newest damaged: the one before it is used
"$EXE" run "$CASE" --out "$TMP/term" --quiet --threads 2 "${SET[@]}" --set run.checkpoint_interval_s=0.2 \
  2> "$TMP/term.err" &
pid=$!
wait_for "$TMP/term/checkpoint/ckpt_*.bin" || say "no checkpoint within 60 s"
# a resume (or another run) into a directory a run is writing: refused, the run untouched
"$EXE" resume "$TMP/term" --quiet 2> "$TMP/busy.err"; rc=$?
[ "$rc" = 2 ] && grep -q "is in use by another shockmpm run" "$TMP/busy.err" || say "resume beside a running run: exit $rc, $(cat "$TMP/busy.err")"
"$EXE" run "$CASE" --out "$TMP/term" --overwrite --quiet "${SET[@]}" 2> "$TMP/busy.err"; rc=$?
[ "$rc" = 2 ] && grep -q "is in use by another shockmpm run" "$TMP/busy.err" || say "--overwrite beside a running run: exit $rc, $(cat "$TMP/busy.err")"
sleep 0.3
kill -TERM "$pid"
wait "$pid"; rc=$?
[ "$rc" = 3 ] || say "SIGTERM: exit $rc, expected 3"
grep -q "checkpoint written: continue with .shockmpm resume" "$TMP/term.err" || say "SIGTERM: no resume hint: $(cat "$TMP/term.err")"
n=$(ls "$TMP/term/checkpoint/" | grep -c '^ckpt_.*\.bin$')
[ "$n" = 2 ] || say "SIGTERM: $n checkpoints kept, expected the last two"
newest=$(ls "$TMP/term/checkpoint/"ckpt_*.bin | tail -1)
printf '\x7f' | dd of="$newest" bs=1 seek=100 conv=notrunc status=none
"$EXE" resume "$TMP/term" --quiet 2> "$TMP/resume.err" || say "resume after SIGTERM: exit $?"
grep -q "$(basename "$newest") is not a whole shockmpm checkpoint.*trying the one before" "$TMP/resume.err" ||
  say "damaged checkpoint not named: $(cat "$TMP/resume.err")"
same_as_full "$TMP/term"

# 3. refused: a completed run, a directory without checkpoints
"$EXE" resume "$TMP/full" 2> "$TMP/err"; rc=$?
[ "$rc" = 2 ] && grep -q "completed" "$TMP/err" || say "resume of a completed run: exit $rc, $(cat "$TMP/err")"
mkdir "$TMP/empty"
"$EXE" resume "$TMP/empty" 2> "$TMP/err"; rc=$?
[ "$rc" = 2 ] && grep -q "holds no checkpoint" "$TMP/err" || say "resume without checkpoint: exit $rc, $(cat "$TMP/err")"
# 4. a 3D run stopped by SIGTERM and resumed on another thread count: the driver takes the 3D
# engine from the checkpoint's case, and every CSV is that of the uninterrupted run
CASE3="$SRC/cases/verify/void_collapse_3d.toml"
# (narrowed to 32 x 32 um across, 20 000 points, 10 ns)
SET3=(--set run.end_time_ns=10.0 --set run.snapshot_interval_ns=2.0 --set run.checkpoint_interval_s=0.2
      --set 'grid.x_range_um=[0.0, 32.0]' --set 'grid.z_range_um=[0.0, 32.0]' --set 'bodies.0.x_range_um=[0.0, 32.0]'
      --set 'bodies.0.z_range_um=[0.0, 32.0]' --set 'bodies.0.voids.center_um=[16.0, 50.0, 16.0]')
"$EXE" run "$CASE3" --out "$TMP/full3" --quiet --threads 2 "${SET3[@]}" || say "3D run failed"
"$EXE" run "$CASE3" --out "$TMP/term3" --quiet --threads 2 "${SET3[@]}" 2> /dev/null &
pid=$!
wait_for "$TMP/term3/checkpoint/ckpt_*.bin" || say "3D: no checkpoint within 60 s"
kill -TERM "$pid"
wait "$pid"; rc=$?
[ "$rc" = 3 ] || say "3D SIGTERM: exit $rc, expected 3 (the run ended before the signal?)"
"$EXE" resume "$TMP/term3" --quiet --threads 1 || say "3D resume: exit $?"
for f in energy.csv series.csv front.csv wall.csv voids.csv; do
  cmp -s "$TMP/full3/$f" "$TMP/term3/$f" || say "3D: $f differs from the uninterrupted run's"
done
[ "$fail" = 0 ] && echo "driver_restart: PASS" || echo "driver_restart: FAIL"
exit "$fail"
