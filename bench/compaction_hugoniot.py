#!/usr/bin/python3
"""The simulated compaction wave against the fully compacted porous Hugoniot
(docs/model.md, "The fully compacted porous Hugoniot").

The convergence strip (cases/verify/porous_strip.toml, voids of 10 um) with 14, 55 and 105 voids
(porosity about 0.09, 0.3 and 0.5) driven onto the wall at 500, 1000 and 2000 m/s. Per run:
the compaction front speed in the wall frame (front.csv, least squares over 0.3-0.95 of the run,
which ends at 70 % of the time a front at the Hugoniot speed takes to meet the free top coming
down at v), the mean -sigma_yy behind the front (snapshots of the second half) and the mean wall
stress, against the fully compacted Rankine-Hugoniot front and pressure for the run's achieved
porosity (run.json compacted_hugoniot: no strength, the material behind the front at rest and
fully dense). The strip is --length-um high (the void count scales with it).

  /usr/bin/python3 bench/compaction_hugoniot.py [--h 4,2] [--length-um 500] [--width-um 96]
                   [--cases 0.5:2000,...] [--set KEY=VALUE ...] [--out DIR] [--driver build/shockmpm]

--width-um widens the strip (periodic sides; the void count scales with its area), --set passes
case overrides to every run (e.g. materials.al.yield_stress_MPa=0 for a material without strength).

Prints a markdown table (docs/accuracy.md).
"""
import argparse
import csv
import hashlib
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def profile_edges(out, v, dy):
    """Leading and trailing edge [um] of the wave in the last snapshot: where the mean U_y of the
    target (bins dy um high) first departs from -v by 5 % and by 95 %, scanning down from the top."""
    import glob
    import h5py
    snaps = sorted(glob.glob(os.path.join(out, "fields", "snap_*.h5")))
    if not snaps:
        return float("nan"), float("nan")
    with h5py.File(snaps[-1], "r") as f:
        y = f["particles/position"][:, 1] * 1e6
        uy = f["particles/velocity"][:, 1]
    bins = np.arange(0.0, y.max() + dy, dy)
    idx = np.digitize(y, bins)
    mean = np.array([uy[idx == k].mean() if np.any(idx == k) else np.nan for k in range(1, len(bins))])
    mid = 0.5 * (bins[1:] + bins[:-1])
    lead = trail = float("nan")
    for k in range(len(mean) - 1, -1, -1):  # from the top down
        if not np.isfinite(mean[k]):
            continue
        if np.isnan(lead) and mean[k] > -0.95 * v:
            lead = mid[k]
        if mean[k] > -0.05 * v:
            trail = mid[k]
            break
    return lead, trail


def stress_behind(out, t_front, y_front, t_end):
    """Mean -sigma_yy [GPa] and U_y [m/s] of the target's points between 0.1 and 0.8 of the
    front's height, over the snapshots of the second half of the run: the compacted state,
    averaged over its reverberation in space and time."""
    import glob
    import h5py
    s_all, u_all = [], []
    for snap in sorted(glob.glob(os.path.join(out, "fields", "snap_*.h5"))):
        with h5py.File(snap, "r") as f:
            t = f["particles"].attrs["time"] * 1e9
            if t < 0.5 * t_end:
                continue
            y = f["particles/position"][:, 1] * 1e6
            syy = f["particles/stress_yy"][:] * 1e-9
            uy = f["particles/velocity"][:, 1]
        yf = float(np.interp(t, t_front, y_front))
        m = (y >= 0.1 * yf) & (y <= 0.8 * yf)
        s_all.append(-syy[m].mean())
        u_all.append(uy[m].mean())
    return float(np.mean(s_all)), float(np.mean(u_all))


def swept_porosity(out, t, y, v, t1, t2, spacing):
    """Porosity of the material the front swept between t1 and t2 [ns]: the band of initial
    heights y0 = y_front(t) + v t (material ahead of the front falls at v), counted on the
    t = 0 snapshot's lattice (points of spacing `spacing` um; the voids' points are absent).
    A random sample's porosity varies along y (Poisson: +-0.03 in 200 um bands of the 384 um
    strip at 0.5), and near porosity 0.5 the compacted front moves 4 % per 0.01 of porosity. 2D or
    3D (the snapshot's position has 2 or 3 columns)."""
    import glob
    import h5py
    snaps = sorted(glob.glob(os.path.join(out, "fields", "snap_*.h5")))
    with h5py.File(snaps[0], "r") as f:
        if f["particles"].attrs["time"] > 0.0:
            return float("nan")
        p = f["particles/position"][:] * 1e6
    lo = float(np.interp(t1, t, y)) + v * t1 * 1e-3
    hi = float(np.interp(t2, t, y)) + v * t2 * 1e-3
    # the lateral extent: width along x (and z in 3D), one lattice spacing per site
    across = 1.0
    for a in [0] + list(range(2, p.shape[1])):
        xs = np.unique(np.round(p[:, a], 6))
        across *= xs.max() - xs.min() + spacing
    n = np.count_nonzero((p[:, 1] >= lo) & (p[:, 1] < hi))
    return 1.0 - n * spacing ** p.shape[1] / (across * (hi - lo))


def hugoniot_at(driver, case, sets, porosity):
    """The compacted Hugoniot (front [m/s], P [GPa]) at another porosity: `check` of the case with
    voids.porosity instead of its count or porosity line (the generator stops within one void of
    it)."""
    import tempfile
    text = open(case).read()
    text = "\n".join(f"porosity = {porosity:.5f}" if l.strip().startswith(("count =", "porosity =")) else l
                     for l in text.splitlines())
    with tempfile.NamedTemporaryFile("w", prefix=".compaction_hugoniot_", suffix=".toml", dir=os.path.dirname(case), delete=False) as f:
        f.write(text)
        tmp = f.name
    try:
        keep = [x for flag, kv in zip(sets[0::2], sets[1::2])  # ("--set", KEY=VALUE) pairs
                if not kv.startswith("bodies.target.voids.count") for x in (flag, kv)]
        chk = subprocess.run([driver, "check", tmp] + keep, capture_output=True, text=True)
    finally:
        os.unlink(tmp)
    for l in chk.stdout.splitlines():
        if "fully compacted" in l and "front " in l:
            return float(l.split("front ")[1].split(" m/s")[0]), float(l.split(" P ")[1].split(" GPa")[0])
    return float("nan"), float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", default="4", help="cell sizes [um], comma-separated")
    ap.add_argument("--length-um", type=float, default=500.0,
                    help="strip height [um]; the void count scales with it (same porosity)")
    ap.add_argument("--cases", default="",
                    help="only these porosity:speed pairs, e.g. 0.09:1000,0.5:2000 (porosity 0.09, 0.3, 0.5)")
    ap.add_argument("--width-um", type=float, default=96.0,
                    help="strip width [um]; the void count scales with it (same porosity)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a case override for every run (repeatable)")
    ap.add_argument("--out", default="/tmp/compaction_hugoniot")
    ap.add_argument("--driver", default=os.path.join(ROOT, "build", "shockmpm"))
    ap.add_argument("--no-run", action="store_true", help="analyse the runs already in --out")
    ap.add_argument("--check", type=float, default=0.0,
                    help="exit 1 unless every row's front, stress behind and wall stress are within this "
                         "many per cent of the Hugoniot's (and every run has a reference and completes)")
    a = ap.parse_args()
    L = a.length_um
    W = a.width_um
    if not W > 0.0 or abs(W / 4.0 - round(W / 4.0)) > 1e-9:
        sys.exit(f"error: --width-um {W:g}: must be a positive multiple of 4 um (the cell sizes divide it)")
    extra = []
    for kv in a.set:
        extra += ["--set", kv]
    tag = "" if not a.set else "-s" + hashlib.sha1("\n".join(a.set).encode()).hexdigest()[:8]
    counts = {0.09: 14, 0.3: 55, 0.5: 105}
    want = [(float(c.split(":")[0]), float(c.split(":")[1])) for c in a.cases.split(",") if c]
    print(f"Strip {W:g} um wide, {L:g} um high{' (' + ', '.join(a.set) + ')' if a.set else ''}. Front: least squares over 0.3-0.95 of the run. Wall: mean wall stress "
          "over the same window. Behind: mean -sigma_yy of the points between 0.1 and 0.8 of the "
          "front's height over the snapshots of the second half of the run (the compacted state, "
          "averaged over its reverberation), and their mean U_y. Against the fully compacted Rankine-Hugoniot front and P (no strength). Lead: the "
          "leading edge of the wave (U_y departs from -v by 5 %) minus the RH front position; width: "
          "from 5 % to 95 %.\n")
    print("| h [um] | porosity | v [m/s] | front [m/s] | RH front | error | behind [GPa] | RH P | error | "
          "U_y behind [m/s] | wall [GPa] | error | lead - RH [um] | width [um] | energy | swept porosity | "
          "RH front there | error | RH P there | behind error |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    failed = 0
    for h in [float(x) for x in a.h.split(",")]:
        for phi, count0 in counts.items():
            for v in (500.0, 1000.0, 2000.0):
                if want and not any(abs(phi - p) < 1e-9 and v == w for p, w in want):
                    continue
                count = int(round(count0 * L / 500.0 * W / 96.0))
                out = os.path.join(a.out, f"n{count}-v{v:g}-h{h:g}-L{L:g}" + (f"-W{W:g}" if W != 96.0 else "") + tag)
                sets = ["--set", f"grid.cell_size_um={h}", "--set", f"bodies.target.voids.count={count}",
                        "--set", f"bodies.target.velocity_m_s=[0.0, {-v}]",
                        "--set", f"bodies.target.y_range_um=[0.0, {L}]",
                        "--set", f"grid.y_range_um=[0.0, {L + 20.0 + (-L - 20.0) % h}]"]
                if W != 96.0:
                    sets += ["--set", f"grid.x_range_um=[0.0, {W:g}]", "--set", f"bodies.target.x_range_um=[0.0, {W:g}]"]
                sets += extra
                case = os.path.join(ROOT, "cases", "verify", "porous_strip.toml")
                # the run ends before the front meets the free top (which comes down at v): at 70 %
                # of the time a front at the compacted Hugoniot's speed takes to meet it
                chk = subprocess.run([a.driver, "check", case] + sets, capture_output=True, text=True)
                rh = [float(l.split("front ")[1].split(" m/s")[0]) for l in chk.stdout.splitlines()
                      if "fully compacted" in l]
                if not rh:
                    why = chk.stderr.strip() or "no fully compacted Hugoniot state (`check`)"
                    print(f"| {h:g} | {phi} | {v:g} | {why} | | | | | | | | | | | | | | | | |", flush=True)
                    failed += 1
                    continue
                t_end = 0.7 * L * 1e-6 / (rh[0] + v) * 1e9
                cmd = [a.driver, "run", case, "--quiet", "--overwrite", "--out", out,
                       "--set", f"run.end_time_ns={t_end:.1f}", "--set", f"run.snapshot_interval_ns={t_end / 8:.3f}"]
                if not a.no_run:
                    subprocess.run(cmd + sets, stdout=subprocess.DEVNULL)
                try:
                    run = json.load(open(os.path.join(out, "run.json")))
                    c = run["bodies"][0]["compacted_hugoniot"]
                    fr = rows(os.path.join(out, "front.csv"))
                    t = np.array([float(r["time_ns"]) for r in fr])
                    y = np.array([float(r["front_y_um"]) for r in fr])
                    sel = (t >= 0.3 * t_end) & (t <= 0.95 * t_end)
                    front = float(np.polyfit(t[sel], y[sel], 1)[0]) * 1e3
                    wl = rows(os.path.join(out, "wall.csv"))
                    tw = np.array([float(r["time_ns"]) for r in wl])
                    sw = np.array([float(r["wall_stress_GPa"]) for r in wl])
                    wall = float(sw[(tw >= 0.3 * t_end) & (tw <= 0.95 * t_end)].mean())
                    en = rows(os.path.join(out, "energy.csv"))
                    e = float(en[-1]["residual_J_per_m"]) / float(en[0]["total_J_per_m"])
                    rf, rp = c["front_speed_wall_frame_m_s"], c["P_Pa"] * 1e-9
                    phi_run = run["bodies"][0]["porosity"]
                    lead, trail = profile_edges(out, v, 2.0 * h)
                    behind, uy = stress_behind(out, t, y, t_end)
                    ts = t[sel]
                    phi_s = swept_porosity(out, t, y, v, ts[0], ts[-1], 0.5 * h)
                    rf_s, rp_s = hugoniot_at(a.driver, case, sets, phi_s) if np.isfinite(phi_s) else (float("nan"),) * 2
                    print(f"| {h:g} | {phi_run:.3f} | {v:g} | {front:.0f} | {rf:.0f} | {100 * (front / rf - 1):+.1f} % | "
                          f"{behind:.2f} | {rp:.2f} | {100 * (behind / rp - 1):+.1f} % | {uy:+.0f} | {wall:.2f} | "
                          f"{100 * (wall / rp - 1):+.1f} % | {lead - rf * t[-1] * 1e-3:+.0f} | {lead - trail:.0f} | {e:+.1e} | "
                          f"{phi_s:.3f} | {rf_s:.0f} | {100 * (front / rf_s - 1):+.1f} % | {rp_s:.2f} | {100 * (behind / rp_s - 1):+.1f} % |",
                          flush=True)
                    errs = [100 * abs(front / rf - 1), 100 * abs(behind / rp - 1), 100 * abs(wall / rp - 1)]
                    if a.check > 0 and (max(errs) > a.check or run["status"] != "completed"):
                        failed += 1
                except (OSError, KeyError, ValueError, IndexError, TypeError) as e:
                    print(f"| {h:g} | {phi} | {v:g} | run failed: {e} | | | | | | | | | | | | | | | | |", flush=True)
                    failed += 1
    if a.check > 0:
        print(f"\ncheck within {a.check:g} %: {'FAIL' if failed else 'PASS'} ({failed} rows failed)")
    return 1 if (a.check > 0 and failed) else 0


if __name__ == "__main__":
    sys.exit(main())
