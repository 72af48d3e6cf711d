#!/usr/bin/env bash
# Smoke test of scripts/figures.py: build two small synthetic 2D shockmpm output directories
# (run.json, series.csv with 3 regions x 5 times, front/wall/energy CSVs, the second with
# freesurface.csv and gauges.csv instead of wall.csv, fields/particles.xdmf naming two HDF5
# snapshots, plus a stale snapshot it does not name) and a 3D one (positions x, y, z on layers
# 10 um apart in z, the 3D energy.csv columns), run the script on them and check that every
# expected PNG exists and is non-empty, that a figure whose inputs are missing is skipped, that the
# 3D maps take one layer of points about the mid-plane, and the exit statuses (0 written, 1
# nothing made, 2 bad arguments); then scripts/hot_spots.py on the 3D run (the band's target
# points counted, none above 1500 K). series.csv's columns are the engine's own: the headers of
# series.csv and the 2D energy.csv are read from a one-step run of the driver on the quick-start
# case; the 3D energy.csv header is that of a run of cases/quickstart3d.toml.
#
# usage: tests/figures_smoke.sh [SHOCKMPM [SOURCE_DIR]]   (default build/shockmpm of the source
#        tree; FIGURES_SMOKE_KEEP=1 keeps the temp directory)
set -euo pipefail
ROOT="${2:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}"
EXE="${1:-$ROOT/build/shockmpm}"
PY=/usr/bin/python3
SCRIPT="$ROOT/scripts/figures.py"

if ! "$PY" -c 'import numpy, h5py, matplotlib' 2>/dev/null; then
  echo "figures_smoke: $PY lacks numpy/h5py/matplotlib (apt-get install python3-numpy python3-h5py python3-matplotlib)" >&2
  exit 1
fi

TMP="$(mktemp -d "${TMPDIR:-/tmp}/figures_smoke.XXXXXX")"
if [ "${FIGURES_SMOKE_KEEP:-0}" = 1 ]; then
  echo "figures_smoke: keeping $TMP"
else
  trap 'rm -rf "$TMP"' EXIT
fi

# series.csv's header as the engine writes it (one step, no snapshots: well under a second)
if ! "$EXE" run "$ROOT/cases/quickstart.toml" --quiet --threads 1 --out "$TMP/engine" \
     --set run.max_steps=1 --set run.snapshot_interval_ns=0 >/dev/null 2>"$TMP/engine.err"; then
  cat "$TMP/engine.err" >&2
  echo "figures_smoke: $EXE did not run the quick-start case" >&2
  exit 1
fi
SERIES_HEADER="$(head -n 1 "$TMP/engine/series.csv")"
ENERGY_HEADER="$(head -n 1 "$TMP/engine/energy.csv")"
ENERGY_HEADER_3D="time_ns,kinetic_J,internal_J,total_J,momentum_x_kg_m_s,momentum_y_kg_m_s,momentum_z_kg_m_s,wall_removed_J,contact_removed_J,residual_J"

"$PY" - "$TMP" "$SERIES_HEADER" "$ENERGY_HEADER" "$ENERGY_HEADER_3D" <<'EOF'
import json, os, sys
import h5py
import numpy as np

def make(outdir, case, porosity, speed, with_T=True, with_wall=True, dim=2):
    rng = np.random.default_rng(7)
    os.makedirs(os.path.join(outdir, "fields"), exist_ok=True)
    run = {
        "case": case,
        "bodies": [{"name": "target", "porosity": porosity, "velocity_m_s": [0.0, -speed, 0.0][:dim],
                    "material": "al", "particles": 600}],
        "case_resolved": {"grid": {"cell_size_um": 20.0},
                          "bodies": [{"name": "target", "points_per_cell": 2}]},
        "particles": 700, "wall_seconds": 1.5,
    }
    if dim == 3:  # a column 200 um deep in z, points on the layers z = 5, 15, ..., 195 um
        run["case_resolved"]["grid"].update(dimension=3, z_range_um=[0.0, 200.0])
    json.dump(run, open(os.path.join(outdir, "run.json"), "w"), indent=1)

    times = [0.0, 100.0, 200.0, 300.0, 400.0]
    with open(os.path.join(outdir, "series.csv"), "w") as f:
        f.write(",".join(columns) + "\n")
        for t in times:
            for k, reg in enumerate(("I", "II", "III")):
                s = t / 400.0 / (1 + 0.3 * k) * speed / 1000.0
                value = {
                    "time_ns": f"{t}", "region": reg, "count": f"{300 - 80 * k}",
                    "P_mean_GPa": f"{20 * s:.4f}", "P_std_GPa": f"{5 * s:.4f}",
                    "T_mean_K": f"{300 + 150 * s:.3f}", "T_std_K": f"{40 * s:.3f}",
                    "rho_mean_gcc": f"{1.35 + 1.3 * s:.4f}", "rho_std_gcc": f"{0.2 * s:.4f}",
                    "Uy_mean_ms": f"{-speed * (1 - s):.2f}", "Uy_std_ms": f"{100 * s:.2f}",
                    "R2_mean_per_us2": f"{1e-3 + 2 * s:.5g}", "D2_mean_per_us2": f"{1e-3 + 5 * s:.5g}",
                    "S2_mean_per_us2": f"{1e-3 + 6 * s:.5g}",
                    "P_skew": "0.1", "P_kurt": "0.5", "T_skew": "0.2", "T_kurt": "1.0",
                    "rho_skew": "-0.3", "rho_kurt": "0.2", "Uy_skew": "0.0", "Uy_kurt": "0.4",
                    "R_mean_per_us": f"{(1e-3 + 2 * s) ** 0.5:.5g}", "D_mean_per_us": f"{(1e-3 + 5 * s) ** 0.5:.5g}",
                    "open_porosity": f"{porosity * max(0.0, 1 - 2 * s):.4f}",
                }
                # a column the engine adds later gets 0 until a figure reads it
                f.write(",".join(value.get(c, "0") for c in columns) + "\n")
    with open(os.path.join(outdir, "front.csv"), "w") as f:
        f.write("time_ns,front_y_um\n")
        for t in np.arange(0.0, 501.0, 20.0):
            f.write(f"{t},{1.5 * t}\n")
    if with_wall:
        with open(os.path.join(outdir, "wall.csv"), "w") as f:
            f.write("time_ns,wall_stress_GPa\n")
            for t in np.arange(0.0, 501.0, 10.0):
                f.write(f"{t},{20 + 2 * np.sin(t / 30)}\n")
    else:  # a plate with a free surface and two gauges instead of the wall
        with open(os.path.join(outdir, "freesurface.csv"), "w") as f:
            f.write("time_ns,body,u_fs_m_s\n")
            for t in np.arange(0.0, 501.0, 10.0):
                f.write(f"{t},target,{-speed if t < 300 else speed}\n")
        with open(os.path.join(outdir, "gauges.csv"), "w") as f:
            f.write("time_ns,gauge,x_um,y_um,vx_m_s,vy_m_s,sigma_xx_GPa,sigma_yy_GPa,sigma_xy_GPa,P_GPa,rho_g_cc,T_K\n")
            for t in np.arange(0.0, 501.0, 10.0):
                for g, y in (("g_0", 100.0), ("g_1", 200.0)):
                    p = 15.0 if 2 * y < t < 300 else 0.0
                    f.write(f"{t},{g},10,{y},0,{-speed},{-p},{-p},0,{p},2.7,300\n")
    columns_e, per = (energy_columns, "_per_m") if dim == 2 else (energy_columns_3d, "")
    with open(os.path.join(outdir, "energy.csv"), "w") as f:
        f.write(",".join(columns_e) + "\n")  # the engine's header
        for t in np.arange(0.0, 501.0, 20.0):
            ek = 100 * (1 - t / 1000)
            val = {"time_ns": t, f"kinetic_J{per}": ek, f"internal_J{per}": 100 - ek, f"total_J{per}": 100.0,
                   f"momentum_y_kg_m_s{per}": -0.2 * ek / 100}
            f.write(",".join(str(val.get(c, 0.0)) for c in columns_e) + "\n")

    def snapshot(step, t_ns, n=600 if dim == 2 else 6000):
        front = 1.5 * t_ns
        x = rng.uniform(0, 200e-6, n)
        y = rng.uniform(0, 1000e-6, n)
        z = (rng.integers(0, 20, n) + 0.5) * 10e-6 if dim == 3 else np.zeros(n)  # 3D: on layers
        vz = 50 * np.sin(2 * np.pi * x / 50e-6) if dim == 3 else np.zeros(n)
        behind = y * 1e6 < front
        p = np.where(behind, 20e9 + 4e9 * rng.standard_normal(n), 1e8 * rng.random(n))
        vx = np.where(behind, 200 * np.sin(2 * np.pi * y / 50e-6), 0.0)
        vy = np.where(behind, 150 * np.cos(2 * np.pi * x / 50e-6), -speed) + 20 * rng.standard_normal(n)
        # 100 points of a second body ("impactor", index 1) that the figures must leave out
        m = 100
        x = np.concatenate([x, rng.uniform(0, 200e-6, m)])
        y = np.concatenate([y, rng.uniform(-300e-6, -10e-6, m)])
        z = np.concatenate([z, rng.uniform(0, 200e-6, m) if dim == 3 else np.zeros(m)])
        body = np.concatenate([np.zeros(n), np.ones(m)])
        pad = lambda a, v: np.concatenate([a, np.full(m, v)])
        with h5py.File(os.path.join(outdir, "fields", f"snap_{step:08d}.h5"), "w") as f:
            g = f.create_group("particles")
            g.attrs["time"] = t_ns * 1e-9
            g.attrs["step"] = step
            g["position"] = np.stack([x, y, z][:dim], 1)
            g["velocity"] = np.stack([pad(vx, 0.0), pad(vy, 1000.0), pad(vz, 0.0)], 1)
            g["pressure"] = pad(p, 99e9)
            g["density"] = pad(np.where(behind, 2650 + 80 * rng.standard_normal(n), 1350.0), 9999.0)
            if with_T:
                g["temperature"] = pad(np.where(behind, 420 + 30 * rng.gamma(2.0, 1.0, n), 300.0), 9999.0)
            g["plastic_strain"] = np.zeros(n + m)
            g["stress_xx"] = -pad(p, 0.0)
            g["body"] = body
            g["id"] = np.arange(n + m, dtype=float)
            f.create_group("topology")["polyvertex"] = np.arange(n + m, dtype=np.int32)
        return f"snap_{step:08d}.h5", t_ns * 1e-9, n + m

    snaps = [snapshot(200, 200.0), snapshot(500, 500.0)]
    # a stale snapshot of an earlier run that particles.xdmf does not name: must be ignored
    with open(os.path.join(outdir, "fields", "snap_00099999.h5"), "wb") as f:
        f.write(b"not an HDF5 file")
    grids = ""
    for fname, t, n in snaps:
        grids += f"""      <Grid Name="{fname[:-3]}" GridType="Uniform">
        <Time Value="{t!r}"/>
        <Topology TopologyType="Polyvertex" NumberOfElements="{n}" NodesPerElement="1">
          <DataItem Dimensions="{n}" NumberType="Int" Precision="4" Format="HDF">{fname}:/topology/polyvertex</DataItem>
        </Topology>
        <Geometry GeometryType="{'XYZ'[:dim]}">
          <DataItem Dimensions="{n} {dim}" NumberType="Float" Precision="8" Format="HDF">{fname}:/particles/position</DataItem>
        </Geometry>
        <Attribute Name="pressure" AttributeType="Scalar" Center="Node">
          <DataItem Dimensions="{n}" NumberType="Float" Precision="8" Format="HDF">{fname}:/particles/pressure</DataItem>
        </Attribute>
      </Grid>
"""
    with open(os.path.join(outdir, "fields", "particles.xdmf"), "w") as f:
        f.write('<?xml version="1.0" ?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n<Xdmf Version="3.0">\n'
                '  <Domain>\n    <Grid Name="particles" GridType="Collection" CollectionType="Temporal">\n'
                + grids + "    </Grid>\n  </Domain>\n</Xdmf>\n")

tmp = sys.argv[1]
columns = sys.argv[2].strip().split(",")
energy_columns = sys.argv[3].strip().split(",")
energy_columns_3d = sys.argv[4].strip().split(",")
if not {"time_ns", "kinetic_J_per_m", "internal_J_per_m", "total_J_per_m"} <= set(energy_columns):
    sys.exit(f"figures_smoke: the engine's energy.csv header lacks the energy columns: {energy_columns}")
need = {"time_ns", "region", "P_mean_GPa", "P_std_GPa", "T_mean_K", "rho_mean_gcc", "Uy_mean_ms",
        "R2_mean_per_us2", "D2_mean_per_us2", "S2_mean_per_us2"}
if not need <= set(columns):
    sys.exit(f"figures_smoke: the engine's series.csv header lacks {sorted(need - set(columns))}: {columns}")
make(os.path.join(tmp, "a"), "smoke_a", 0.50, 1000.0)
make(os.path.join(tmp, "b"), "smoke_b", 0.41, 800.0, with_T=False, with_wall=False)
make(os.path.join(tmp, "c"), "smoke_3d", 0.50, 1000.0, dim=3)
os.makedirs(os.path.join(tmp, "empty"))
EOF

fail=0
check() {  # check FILE...: each exists and is non-empty
  for f in "$@"; do
    if [ -s "$f" ]; then echo "ok   $f"; else echo "MISSING $f" >&2; fail=1; fi
  done
}

echo "== --out and the other flags (the default run below overwrites these figures)"
set +e
"$PY" "$SCRIPT" "$TMP/a" "$TMP/b" --only compare,velocity,distributions --out "$TMP/cmp" --vel-frame lab --vel-bins 0 \
  --vel-x 20 180 --vel-y 400 600 --dist-times-ns 200 --dist-log --region-y 0 500 >/dev/null
rc=$?
set -e
[ "$rc" = 0 ] || { echo "figures.py --out exited $rc, expected 0" >&2; fail=1; }
check "$TMP/cmp/compare_means.png"

echo "== figures.py on two synthetic runs"
set +e
"$PY" "$SCRIPT" "$TMP/a" "$TMP/b" --time-ns 500 --region I >"$TMP/stdout" 2>"$TMP/stderr"
rc=$?
set -e
cat "$TMP/stdout" "$TMP/stderr"
[ "$rc" = 0 ] || { echo "figures.py exited $rc, expected 0" >&2; fail=1; }
A="$TMP/a/figures"
B="$TMP/b/figures"
check "$A"/{map_P,map_T,series_means,series_std,velocity_field,dissipation,distributions,history}.png \
      "$A"/compare_{means,std}.png \
      "$B"/{map_P,series_means,series_std,velocity_field,dissipation,distributions,history,freesurface}.png
if [ -e "$B/map_T.png" ]; then echo "map_T.png written for a run without temperature" >&2; fail=1; fi
grep -q "skip map_T.png" "$TMP/stderr" || { echo "no skip message for map_T.png" >&2; fail=1; }
grep -q "skip freesurface.png ($TMP/a): no freesurface.csv" "$TMP/stderr" || { echo "no skip message for freesurface.png" >&2; fail=1; }
n_written=$(grep -c '\.png$' "$TMP/stdout" || true)
[ "$n_written" = 18 ] || { echo "stdout names $n_written PNGs, expected 18" >&2; fail=1; }

echo "== figures.py on a synthetic 3D run"
set +e
"$PY" "$SCRIPT" "$TMP/c" --time-ns 500 >"$TMP/stdout3" 2>"$TMP/stderr3"
rc=$?
set -e
cat "$TMP/stdout3" "$TMP/stderr3"
[ "$rc" = 0 ] || { echo "figures.py (3D) exited $rc, expected 0" >&2; fail=1; }
C="$TMP/c/figures"
check "$C"/{map_P,map_T,series_means,series_std,velocity_field,dissipation,distributions,history}.png
n_written=$(grep -c '\.png$' "$TMP/stdout3" || true)
[ "$n_written" = 8 ] || { echo "3D: stdout names $n_written PNGs, expected 8" >&2; fail=1; }
if grep -v "skip freesurface.png" "$TMP/stderr3" | grep -q "skip\|energy.csv missing"; then
  echo "3D: a figure or the energy panel was skipped" >&2; fail=1
fi
# the maps' slice: the one layer of points nearest the mid-plane z = 100 um (z = 95 or 105 um)
"$PY" - "$SCRIPT" "$TMP/c" <<'EOF' || fail=1
import os, sys
import numpy as np
sys.path.insert(0, os.path.dirname(sys.argv[1]))
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
import figures
run = figures.Run(sys.argv[2])
d = run.load(run.nearest_snapshot(500.0)[1], ["pressure"])
s, lateral, text = figures.plane_slice(run, d, figures.parse_args([sys.argv[2]]))
z = s["z_um"]
ok = (lateral == "x" and np.ptp(z) < 1e-9 and abs(abs(z[0] - 100.0) - 5.0) < 1e-9
      and z.size == np.count_nonzero(np.isclose(d["z_um"], z[0])) and text == f"slice z = {z[0]:.1f} ± 5 µm")
print(("ok  " if ok else "BAD ") + f" 3D slice: {z.size} points, {text!r}, lateral axis {lateral}")
sys.exit(0 if ok else 1)
EOF
set +e  # the y-z plane
"$PY" "$SCRIPT" "$TMP/c" --time-ns 500 --only map,velocity --slice-axis x --slice-at-um 60 >/dev/null; rc=$?
set -e
[ "$rc" = 0 ] || { echo "figures.py (3D, --slice-axis x) exited $rc, expected 0" >&2; fail=1; }
check "$C"/{map_P,map_T,velocity_field}.png

echo "== hot_spots.py on the synthetic 3D run"
# the band's target points (the impactor's 9999 K points are not the target's): count and shares
"$PY" - "$TMP/c" "$ROOT/scripts/hot_spots.py" <<'EOF2' || fail=1
import glob, os, subprocess, sys
import h5py, numpy as np
out, script = sys.argv[1], sys.argv[2]
row = subprocess.run([sys.executable, script, out, "--time-ns", "500", "--band-um", "0", "100"], check=True,
                     capture_output=True, text=True).stdout.strip().splitlines()[-1].split("|")
with h5py.File(os.path.join(out, "fields", "snap_00000500.h5"), "r") as f:
    p = f["particles"]
    y = p["position"][:, 1] * 1e6
    n = int(np.sum((p["body"][...] == 0) & (y >= 0) & (y < 100)))
cells = [c.strip() for c in row[1:-1]]
ok = cells[1] == "500" and int(cells[2]) == n and cells[-2] == "0.0 %" and 300 <= float(cells[3]) <= 1000
print(("ok  " if ok else "BAD ") + f" hot_spots: {' | '.join(cells)} (band points {n})")
sys.exit(0 if ok else 1)
EOF2

echo "== exit statuses"
set +e
"$PY" "$SCRIPT" "$TMP/empty" >/dev/null 2>&1; rc_empty=$?
"$PY" "$SCRIPT" "$TMP/missing_dir" >/dev/null 2>&1; rc_missing=$?
"$PY" "$SCRIPT" "$TMP/a" --p-range 50 0 >/dev/null 2>&1; rc_bad=$?
"$PY" "$SCRIPT" >/dev/null 2>&1; rc_none=$?
set -e
[ "$rc_empty" = 1 ] || { echo "empty OUTDIR: exit $rc_empty, expected 1" >&2; fail=1; }
[ "$rc_missing" = 1 ] || { echo "missing OUTDIR: exit $rc_missing, expected 1" >&2; fail=1; }
[ "$rc_bad" = 2 ] || { echo "bad --p-range: exit $rc_bad, expected 2" >&2; fail=1; }
[ "$rc_none" = 2 ] || { echo "no OUTDIR: exit $rc_none, expected 2" >&2; fail=1; }

if [ "$fail" = 0 ]; then echo "figures_smoke: PASS"; else echo "figures_smoke: FAIL" >&2; fi
exit "$fail"
