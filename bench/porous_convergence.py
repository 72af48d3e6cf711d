#!/usr/bin/env python3
"""Speed against error for porous runs: a case at several cell sizes, one table.

Runs the driver on a case (default cases/verify/porous_strip.toml, the convergence strip) at each cell
size, then tabulates per run, for the region (default III) at the last series.csv time:

  front    compaction-front speed in the wall frame [m/s]: least squares of front.csv over the
           fit window (default 100-190 ns)
  P        mean pressure [GPa]; rho the points' mean density [g/cc]; open the band's open
           porosity (series.csv open_porosity, 1 - sum V / band area)
  bulk     the band's bulk density [g/cc]: its points' mass over its area (count x the target's
           mass per point, rho0 x area / points: equal masses, a lattice sample; the grid's
           width, periodic sides)
  zero-P   share of the region's points at exactly zero pressure (fractured: stress-free) in the
           last snapshot (fields/snap_*.h5; needs h5py; nan without snapshots); the region by
           the points' current y, bounds from run.json
  (gaps + fractured)  the open porosity's two parts in that snapshot: space no point's volume
           covers, and the expansion of fractured points past the zero-pressure density of their
           energy (open_split)
  energy   (total - initial) / initial from energy.csv; residual likewise
  cost     particle-steps and wall seconds (run.json)

and, with three or more cell sizes, the Richardson limit of the front speed from the three finest
(observed order p from the three, any ratio of cell sizes; richardson()) and each run's error against it, plus the fully
compacted Rankine-Hugoniot front from run.json (compacted_hugoniot).

  /usr/bin/python3 bench/porous_convergence.py [--h 4,2,1] [--set KEY=VALUE ...] [--out DIR]
      [--case FILE] [--region III] [--window 100,190] [--driver build/shockmpm] [--reuse] [--check]

--reuse tabulates existing outputs in DIR without running. --check exits 1 unless the first
(coarsest) run meets the figures one run must show (open porosity under 2 %, zero-P share under
5 %, front within 5 % of the compacted Hugoniot, energy within 1e-8; ctest strip_closure). Output: a markdown table on stdout.
Figures in docs/verification.md for the porous strip come from this script.
"""
import argparse
import csv
import glob
import json
import math
import os
import subprocess
import sys

import numpy as np


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def front_speed(outdir, window):
    rows = read_csv(os.path.join(outdir, "front.csv"))
    t = np.array([float(r["time_ns"]) for r in rows])
    y = np.array([float(r["front_y_um"]) for r in rows])
    sel = (t >= window[0]) & (t <= window[1])
    if sel.sum() < 3:
        return math.nan
    return float(np.polyfit(t[sel], y[sel], 1)[0]) * 1e3  # um/ns -> m/s


def last_band(outdir, run, region):
    """The region's points in the last snapshot (fields/snap_*.h5, by name; the region by the points'
    body and current y, bounds from run.json): a dict of arrays (density, pressure, stress_*, and
    energy where the snapshot has it), or None without snapshots, h5py or the region."""
    snaps = sorted(glob.glob(os.path.join(outdir, "fields", "snap_*.h5")))
    reg = next((r for r in run.get("regions", []) if r["name"] == region), None)
    if not snaps or reg is None:
        return None
    try:
        import h5py
    except ImportError:
        return None
    with h5py.File(snaps[-1], "r") as f:
        y = f["particles/position"][:, 1] * 1e6  # m -> um
        sel = (f["particles/body"][:] == reg["body"]) & (y >= reg["y_range_um"][0]) & (y <= reg["y_range_um"][1])
        names = ["pressure", "density", "stress_xx", "stress_yy", "stress_xy", "stress_zz", "stress_xz",
                 "stress_yz", "energy"]
        return {k: f["particles/" + k][:][sel] for k in names if "particles/" + k in f}


def zero_pressure_share(outdir, run, region):
    """Share of the region's points with p == 0 in the last snapshot, or nan."""
    band = last_band(outdir, run, region)
    if band is None:
        return math.nan
    p = band["pressure"]
    return float(np.count_nonzero(p == 0.0)) / max(1, len(p))


def zero_pressure_density(run, energy, rho0):
    """Density [kg/m^3] at which intact target material of specific internal energy `energy`
    [J/kg] has zero pressure: Mie-Grueneisen's tension branch rho0 (1 - gamma0 rho0 e / (rho0
    c0^2)), rho0 for e <= 0 (kernels/constitutive.hpp, zero_pressure_density); rho0 for another
    EOS or without energies."""
    try:
        body = next(b for b in run["bodies"] if b["name"] == "target")
        mat = run["case_resolved"]["materials"][body["material"]]
    except (KeyError, StopIteration):
        return rho0
    if energy is None or mat.get("eos") != "mie_gruneisen":
        return rho0
    c0, g0 = mat["bulk_sound_speed_m_s"], mat["gruneisen_gamma"]
    return rho0 * (1.0 - g0 * np.maximum(energy, 0.0) / (c0 * c0))


def open_split(outdir, run, region):
    """The band's open porosity in two parts, fractions of its area, from the last snapshot:
    (gaps, fractured): gaps = 1 - sum V / area, the space no point's volume V = m / rho covers
    (negative where points overlap); fractured = sum over fractured points (zero pressure and zero
    stress, the engine's test) of V - min(V, m / rho_zp), the expansion of cracked points past the
    density intact material of their energy has at zero pressure (zero_pressure_density; their
    thermal expansion is solid), which series.csv's open_porosity counts as void too
    (engine/diagnostics.cpp, solid_volume). Their sum is that open_porosity at the snapshot's
    time. Equal point masses (a lattice sample) as in bulk_density; (nan, nan) without what it
    needs."""
    band, geom = last_band(outdir, run, region), band_geometry(run, region)
    if band is None or geom is None or "density" not in band or "stress_xy" not in band:
        return math.nan, math.nan
    m, area, rho0 = geom
    V = m / band["density"]
    fr = band["pressure"] == 0.0
    for k in ("stress_xx", "stress_yy", "stress_xy", "stress_xz", "stress_yz"):  # zz: -P in 2D, not 0
        if k in band:
            fr &= band[k] == 0.0
    rho_zp = zero_pressure_density(run, band.get("energy"), rho0)
    rz = np.broadcast_to(rho_zp, V.shape)[fr]
    # no zero-pressure density (e past c0^2 / gamma0): the point holds all its V, as in the engine
    cap = np.where(rz > 0.0, m / np.where(rz > 0.0, rz, 1.0), V[fr])
    excess = float(np.sum(V[fr] - np.minimum(V[fr], cap)))
    return 1.0 - float(V.sum()) / area, excess / area


def band_geometry(run, region):
    """(mass per point [kg/m in 2D, kg in 3D], band size [m^2 per unit depth in 2D, m^3 in 3D],
    rho0 [kg/m^3]) of the target's region from run.json: equal point masses (a lattice sample),
    the grid's width along x (and z in 3D; periodic sides); None without what it needs."""
    try:
        body = next(b for b in run["bodies"] if b["name"] == "target")
        rho0 = run["case_resolved"]["materials"][body["material"]]["density_kg_m3"]
        reg = next(r for r in run["regions"] if r["name"] == region)
        grid = run["case_resolved"]["grid"]
    except (KeyError, StopIteration):
        return None
    size = (reg["y_range_um"][1] - reg["y_range_um"][0]) * 1e-6
    for k in ("x_range_um", "z_range_um"):
        if k in grid:
            size *= (grid[k][1] - grid[k][0]) * 1e-6
    m = rho0 * body.get("area_m2", body.get("volume_m3", math.nan)) / body["particles"]
    return m, size, rho0


def bulk_density(run, region, count):
    """Mass of the region's points over its area [g/cc] (equal point masses, periodic width), or nan."""
    geom = band_geometry(run, region)
    if geom is None:
        return math.nan
    m, area, _ = geom
    return count * m / area / 1000.0


def swept_hugoniot(outdir, run, window, driver):
    """(porosity, compacted Hugoniot front [m/s]) of the material the front swept over the fit
    window (bench/compaction_hugoniot.py: a random sample's porosity varies along y, and a 96 um
    strip's by several points), from the run's t = 0 snapshot; nans without it or h5py."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    try:
        import compaction_hugoniot as ch
        rows = read_csv(os.path.join(outdir, "front.csv"))
        t = np.array([float(r["time_ns"]) for r in rows])
        y = np.array([float(r["front_y_um"]) for r in rows])
        body = run["case_resolved"]["bodies"][0]
        v = abs(float(body["velocity_m_s"][1]))
        spacing = float(run["case_resolved"]["grid"]["cell_size_um"]) / float(body.get("points_per_cell", 2))
        phi = ch.swept_porosity(outdir, t, y, v, window[0], window[1], spacing)
        if not math.isfinite(phi):
            return math.nan, math.nan
        us, _ = ch.hugoniot_at(driver, os.path.join(outdir, "case_resolved.toml"), [], phi)
        return phi, us
    except (ImportError, OSError, KeyError, IndexError, ValueError):
        return math.nan, math.nan


def summarise(outdir, region, window, driver=None):
    run = json.load(open(os.path.join(outdir, "run.json")))
    series = [r for r in read_csv(os.path.join(outdir, "series.csv")) if r["region"] == region]
    last = series[-1]
    energy = read_csv(os.path.join(outdir, "energy.csv"))
    unit = "J_per_m" if "total_J_per_m" in energy[0] else "J"  # 2D: per unit depth; 3D: whole
    e0, e1 = float(energy[0]["total_" + unit]), float(energy[-1]["total_" + unit])
    res = float(energy[-1].get("residual_" + unit, "nan"))
    comp = next((b.get("compacted_hugoniot", {}) for b in run.get("bodies", []) if "compacted_hugoniot" in b), {})
    phi, swept_rh = swept_hugoniot(outdir, run, window, driver) if driver else (math.nan, math.nan)
    return {
        "swept_porosity": phi,
        "swept_rh": swept_rh,
        "h_um": run["case_resolved"]["grid"].get("cell_size_um", math.nan),
        "front": front_speed(outdir, window),
        "P": float(last["P_mean_GPa"]),
        "rho": float(last["rho_mean_gcc"]),
        "bulk": bulk_density(run, region, float(last["count"])),
        "open": float(last.get("open_porosity", "nan")),
        "R2": float(last["R2_mean_per_us2"]),
        "D2": float(last["D2_mean_per_us2"]),
        "zeroP": zero_pressure_share(outdir, run, region),
        "split": open_split(outdir, run, region),
        "energy": (e1 - e0) / e0,
        "residual": res / e0,
        "particle_steps": run["particles"] * run["steps"],
        "wall_s": run["wall_seconds"],
        "time_ns": float(last["time_ns"]),
        "rh_front": comp.get("front_speed_wall_frame_m_s", math.nan),
        "status": run.get("status", "?"),
    }


def richardson(hs, vals):
    """Richardson limit and observed order p of three values at cell sizes h1 > h2 > h3 (any
    ratios): f(h) = f0 + C h^p through the three points, p from (f1 - f2) / (f2 - f3) =
    (h1^p - h2^p) / (h2^p - h3^p) by bisection on 0.05-8. (nan, nan) where the differences do
    not shrink monotonically."""
    (h1, f1), (h2, f2), (h3, f3) = sorted(zip(hs, vals), key=lambda t: -t[0])
    d1, d2 = f1 - f2, f2 - f3
    if d1 == 0 or d2 == 0 or d1 / d2 <= 0:
        return math.nan, math.nan
    ratio = d1 / d2
    g = lambda p: (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p) - ratio
    lo, hi = 0.05, 8.0
    if g(lo) * g(hi) > 0:
        return math.nan, math.nan
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if g(lo) * g(mid) <= 0:
            hi = mid
        else:
            lo = mid
    p = 0.5 * (lo + hi)
    return f3 - d2 * h3 ** p / (h2 ** p - h3 ** p), p


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--case", default=os.path.join(root, "cases/verify/porous_strip.toml"))
    ap.add_argument("--h", default="4,2,1", help="cell sizes [um], coarse to fine")
    ap.add_argument("--set", action="append", default=[], help="driver --set, repeatable")
    ap.add_argument("--out", default="out/porous_convergence")
    ap.add_argument("--region", default="III")
    ap.add_argument("--window", default="100,190", help="front fit window [ns]")
    ap.add_argument("--driver", default=os.path.join(root, "build/shockmpm"))
    ap.add_argument("--reuse", action="store_true", help="tabulate existing outputs, run nothing")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 unless the first (coarsest) run meets the figures one run must show: "
                         "open porosity under 2 %%, under 5 %% of the band at zero pressure, front within 5 %% "
                         "of the fully compacted Rankine-Hugoniot front, energy within 1e-8")
    ap.add_argument("--check-trend", action="store_true",
                    help="exit 1 unless, from each cell size to the next finer one, the front's distance to the "
                         "compacted Hugoniot at the swept porosity and the open porosity both shrink, and every "
                         "run's energy is within 1e-8 (the quick form where one run cannot meet --check)")
    a = ap.parse_args()
    hs = [float(x) for x in a.h.split(",")]
    window = [float(x) for x in a.window.split(",")]
    rows = []
    for h in hs:
        outdir = os.path.join(a.out, f"h{h:g}")
        if not a.reuse:
            cmd = [a.driver, "run", a.case, "--quiet", "--overwrite", "--out", outdir, "--set", f"grid.cell_size_um={h}"]
            for s in a.set:
                cmd += ["--set", s]
            print("running:", " ".join(cmd), file=sys.stderr, flush=True)
            if subprocess.run(cmd).returncode != 0:
                print(f"run at h = {h} um did not complete (see {outdir}/run.json)", file=sys.stderr)
        try:
            rows.append(summarise(outdir, a.region, window, a.driver))
        except (OSError, KeyError, ValueError, IndexError) as e:
            print(f"cannot read {outdir}: {e}", file=sys.stderr)
    if not rows:
        sys.exit(1)
    limit = math.nan
    if len(rows) >= 3:
        limit, p = richardson([r["h_um"] for r in rows[-3:]], [r["front"] for r in rows[-3:]])
        if math.isfinite(limit):
            print(f"Richardson: observed order {p:.2f}, limit {limit:.0f} m/s", file=sys.stderr)
    rh = rows[0]["rh_front"]
    print(f"Front over {window[0]:g}-{window[1]:g} ns; region {a.region} at {rows[0]['time_ns']:g} ns. "
          f"Richardson limit of the front: {limit:.0f} m/s; fully compacted Rankine-Hugoniot front: {rh:.0f} m/s "
          f"at the nominal porosity, {rows[-1]['swept_rh']:.0f} m/s at the porosity the finest run's front swept "
          f"({rows[-1]['swept_porosity']:.3f}).")
    print()
    print("| h [um] | front [m/s] | vs limit | vs RH | vs swept RH | P [GPa] | rho points / bulk [g/cc] | open porosity (gaps + fractured) | <R^2> / <D^2> [1/us^2] "
          "| zero-P | energy | particle-steps | wall [s] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        vl = (r["front"] / limit - 1) * 100 if math.isfinite(limit) else math.nan
        vr = (r["front"] / rh - 1) * 100 if math.isfinite(rh) else math.nan
        vs = (r["front"] / r["swept_rh"] - 1) * 100
        print(f"| {r['h_um']:g} | {r['front']:.0f} | {vl:+.1f} % | {vr:+.1f} % | {vs:+.1f} % | {r['P']:.2f} | {r['rho']:.3f} / {r['bulk']:.3f} "
              f"| {r['open'] * 100:.1f} % ({r['split'][0] * 100:.1f} + {r['split'][1] * 100:.1f}) | {r['R2']:.1f} / {r['D2']:.1f} | {r['zeroP'] * 100:.1f} % | {r['energy'] * 100:+.2g} % "
              f"| {r['particle_steps']:.3g} | {r['wall_s']:.1f} |")
    if a.check:
        r = rows[0]
        # the Hugoniot at the porosity the front swept where the snapshot gives it, else the nominal
        ref = r["swept_rh"] if math.isfinite(r["swept_rh"]) else rh
        refname = "swept" if math.isfinite(r["swept_rh"]) else "nominal"
        checks = [("open porosity", r["open"], abs(r["open"]) < 0.02, "within 0.02"),
                  ("zero-pressure share", r["zeroP"], r["zeroP"] < 0.05, "< 0.05"),
                  (f"front / compacted Hugoniot front ({refname} porosity) - 1", r["front"] / ref - 1,
                   abs(r["front"] / ref - 1) < 0.05, "within 0.05"),
                  ("energy change", r["energy"], abs(r["energy"]) < 1e-8, "within 1e-8")]
        bad = [c for c in checks if not c[2]]
        for name, v, ok, bound in checks:
            print(f"check h = {r['h_um']:g} um: {name} {v:.4g} ({bound}): {'ok' if ok else 'FAILED'}")
        if bad:
            sys.exit(1)
    if a.check_trend:
        ok = len(rows) == len(hs) and len(rows) >= 2
        if not ok:
            print("check trend: a run is missing: FAILED")
        for r in rows:
            good = abs(r["energy"]) < 1e-8
            ok &= good
            print(f"check h = {r['h_um']:g} um: energy change {r['energy']:.3g} (within 1e-8): {'ok' if good else 'FAILED'}")
        for r0, r1 in zip(rows, rows[1:]):
            for name, v0, v1 in (("|front / swept Hugoniot front - 1|", abs(r0["front"] / r0["swept_rh"] - 1),
                                  abs(r1["front"] / r1["swept_rh"] - 1)),
                                 ("|open porosity|", abs(r0["open"]), abs(r1["open"]))):
                good = v1 < v0
                ok &= good
                print(f"check h = {r0['h_um']:g} -> {r1['h_um']:g} um: {name} {v0:.4g} -> {v1:.4g} (shrinks): "
                      f"{'ok' if good else 'FAILED'}")
        if not ok:
            sys.exit(1)


if __name__ == "__main__":
    main()
