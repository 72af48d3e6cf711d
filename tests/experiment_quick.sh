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
# 3 seeds; at h = 2 um this row is +4.7 % +- 5.4 %, 0.1 % from h = 4).
# Then the same row in 3D (--dim 3: a column periodic in x and z, spherical voids), as small as
# runs at all: h = 5 um, 3 void diameters across, a front run of 4 diameters (34 k particles,
# 179 steps at t = 0; 4 s on 1 thread). It checks the 3D path of the harness end to end (3D case,
# front fit, the band's bulk density over width x depth, swept porosity). Measured: seed 1
# -6.7 % (2.559 km/s); seeds 1-3 2.559, 2.941, 3.154 km/s, spread 10.4 % of their mean: a column
# this small holds 47-48 voids. TOL3 = 18 %: seed 1's error plus that spread. A lost frame change
# is -35 % and fails. Then the 2D row once more, stopped by SIGKILL after its first checkpoint
# and run again: the harness resumes it, and its Us is the uninterrupted run's to the last bit.
# Then a dry run with --seeds 2,3 plans those two seeds, and --compose joins hand-written
# reports of the 2D row (below). Release only.
#   tests/experiment_quick.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
ROW=3
TOL=12
TOL3=18
HARNESS=(/usr/bin/python3 "$SRC/bench/experiment_hugoniot.py" --data "$SRC/bench/data/porous_iron_hugoniot.csv"
         --driver "$EXE" --threads "${OMP_NUM_THREADS:-2}" --material iron)
"${HARNESS[@]}" --out "$TMP" --quick --rows "$ROW" --h 4 --check "$TOL"
rc=$?
"${HARNESS[@]}" --out "$TMP/3d" --quick --dim 3 --rows "$ROW" --h 5 --width-diameters 3 --front-diameters 4 --check "$TOL3" || rc=1
# A stopped run continues from its checkpoint: the 2D row again (checkpoints every 0.2 s, so
# another key), its driver killed after the first checkpoint; the harness run again resumes it.
"${HARNESS[@]}" --out "$TMP/stop" --quick --rows "$ROW" --h 4 --set run.checkpoint_interval_s=0.2 > /dev/null 2>&1 &
hp=$!
for _ in $(seq 1 1200); do compgen -G "$TMP/stop/runs/*/checkpoint/ckpt_*.bin" > /dev/null && break; sleep 0.05; done
pkill -KILL -f -- "--out $TMP/stop/runs/" || { echo "experiment_quick: no run to stop"; rc=1; }
wait "$hp" 2> /dev/null
"${HARNESS[@]}" --out "$TMP/stop" --quick --rows "$ROW" --h 4 --set run.checkpoint_interval_s=0.2 --check "$TOL" \
  > "$TMP/stop.log" 2>&1 || { cat "$TMP/stop.log"; rc=1; }
grep -q "resumed in" "$TMP/stop.log" && grep -q '"resumed": true' "$TMP/stop/experiment.json" ||
  { echo "experiment_quick: the stopped run was not resumed:"; cat "$TMP/stop.log"; rc=1; }
/usr/bin/python3 - "$TMP/experiment.json" "$TMP/stop/experiment.json" <<'PY' || rc=1
import json, sys
us = [json.load(open(f))["rows"][0]["by_h"]["4"]["runs"][0]["Us_km_s"] for f in sys.argv[1:]]
if us[0] != us[1]:
    sys.exit(f"experiment_quick: the resumed run's Us {us[1]!r} km/s differs from the uninterrupted {us[0]!r}")
PY
# --seeds as a list plans those seeds only (a dry run: nothing runs)
plan=$("${HARNESS[@]}" --out "$TMP/plan" --rows "$ROW" --h 4 --seeds 2,3 --dry-run 2>&1)
[ "$(echo "$plan" | grep -cE '^\| 3 \| [^|]+ \| [^|]+ \| 4 \| (2|3) \|')" = 2 ] && [ "$(echo "$plan" | grep -c '^| 3 |')" = 2 ] ||
  { echo "experiment_quick: --seeds 2,3 planned otherwise:"; echo "$plan"; rc=1; }
# --compose: reports of one experiment become one table. From the 2D run's report, three more of
# its row written by hand: seed 2 at h = 4 um (Us + 0.2 km/s), seed 1 at h = 4 um again (Us +
# 0.1: the later report's run replaces the first's) and seed 1 at h = 2 um (Us - 0.1). The
# composed row takes h = 2 um, the two seeds' mean at h = 4 um for its resolution change; a
# report of another dimension is refused, naming the key, and so is a run option beside it.
/usr/bin/python3 - "$TMP" /usr/bin/python3 "$SRC/bench/experiment_hugoniot.py" <<'PY' || rc=1
import json, math, subprocess, sys
tmp, harness = sys.argv[1], sys.argv[2:]
doc = json.load(open(f"{tmp}/experiment.json"))
run = doc["rows"][0]["by_h"]["4"]["runs"][0]
us = run["Us_km_s"]
paths = [f"{tmp}/experiment.json"]
for name, h, seed, du in (("b", "4", 2, 0.2), ("c", "4", 1, 0.1), ("d", "2", 1, -0.1)):
    d = json.loads(json.dumps(doc))
    d["rows"][0]["by_h"] = {h: {"runs": [dict(run, seed=seed, Us_km_s=us + du)]}}
    paths.append(f"{tmp}/{name}.json")
    json.dump(d, open(paths[-1], "w"))
p = subprocess.run(harness + ["--compose", *paths, "--out", f"{tmp}/composed"], capture_output=True, text=True)
if p.returncode != 0:
    sys.exit(f"experiment_quick: --compose failed: {p.stderr}")
r = json.load(open(f"{tmp}/composed/experiment.json"))["rows"][0]
want = {"engine_h_um": 2.0, "engine_Us_km_s": us - 0.1,
        "resolution_change_pct": 100 * abs(us + 0.15 - (us - 0.1)) / (us - 0.1)}
bad = [k for k, v in want.items() if not math.isclose(r[k], v, rel_tol=1e-12)]
if bad or [x["seed"] for x in r["by_h"]["4"]["runs"]] != [1, 2]:
    sys.exit(f"experiment_quick: --compose gave {[(k, r[k]) for k in want]}, seeds at 4 um "
             f"{[x['seed'] for x in r['by_h']['4']['runs']]}; expected {want}, seeds [1, 2]")
d = json.loads(json.dumps(doc)); d["dim"] = 3
json.dump(d, open(f"{tmp}/e.json", "w"))
p = subprocess.run(harness + ["--compose", paths[0], f"{tmp}/e.json", "--out", f"{tmp}/bad"], capture_output=True, text=True)
if p.returncode != 2 or "dim" not in p.stderr:
    sys.exit(f"experiment_quick: --compose of another dimension: exit {p.returncode}, {p.stderr!r}")
p = subprocess.run(harness + ["--compose", paths[0], "--rows", "3", "--out", f"{tmp}/bad"], capture_output=True, text=True)
if p.returncode != 2 or "--rows" not in p.stderr:
    sys.exit(f"experiment_quick: --compose with --rows: exit {p.returncode}, {p.stderr!r}")
PY
for f in experiment.json experiment.md experiment_us_up.png 3d/experiment.json composed/experiment.md; do
  [ -s "$TMP/$f" ] || { echo "experiment_quick: $f missing"; rc=1; }
done
[ "$rc" = 0 ] && echo "experiment_quick: PASS" || echo "experiment_quick: FAIL (exit $rc)"
exit $rc
