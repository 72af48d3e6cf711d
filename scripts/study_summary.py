#!/usr/bin/python3
"""Summary table (markdown) of shockmpm study runs, one row per output directory.

usage: scripts/study_summary.py OUTDIR [OUTDIR ...] [--region I] [--times-ns 1200 1500] [--dir-names]
                                [--plateau-ns T0 T1]

An OUTDIR without a run.json whose subdirectories seed_<S>/ hold runs (scripts/sweep.sh --seeds)
is a seed ensemble: its row gives every number as the mean over the seeds and, after "+-", their
sample standard deviation (the spread of the random sample), and OUTDIR/series_ensemble.csv gets
every regional statistic of series.csv as mean and spread over the seeds (below).

Columns: porosity and impact speed (run.json); peak of the region's mean pressure and density
(series.csv); mean temperature of the region at the given times (nearest row); with --plateau-ns,
the means over T0-T1 of the region's mean P, T, rho and standard deviations of P and T
(docs/study.md's plateau values: region II, 1200-1800 ns); compression-front
speed and its attenuation (second / first, below); for each region the time the release from the
free top arrives (below); the run's particles and wall time.

Meeting time t_meet: the target (top y_top0, from run.json, falling at -v in the wall frame until
the compaction wave reaches it) has a free top; the compaction front of front.csv meets it at the
first record with front_y >= y_top0 - v t - 2 cells. After that front.csv no longer tracks a
compaction front: front_position (engine/diagnostics.cpp) scans rows from the top, and once the
top rows move (rebound of the released top, ejecta flying up) it would find the top of the plate
or of the ejecta, which moves up at 0.4-2.5 km/s; so it returns NaN there and the driver ends
front.csv: a completed run whose record stops early met the top at its last row.

Front speed: least-squares slope of front.csv, in the frame of the wall, over the first and the
second half of the record before t_meet (the whole record when the front never meets the top).

Release: the rarefaction from the free top starts at t_meet and runs down through the compacted
material, so it reaches the regions from above (I, top 900 um, before II, 600 um, before III,
300 um) and, once there, sets the material (at rest behind the front in this frame) moving up for
good. A region's release time is the first series.csv time t that is (1) at or after t_meet,
(2) at or after the release time of the region above it, and (3) from which the region's mean U_y
stays above +5 % of the impact speed for 100 ns, or to the end of the record if that comes sooner
but at least 30 ns after t. Reverberations (thin region III, 600-700 ns) and the fluctuations of
coarse-void runs (+-100 m/s with 20 um voids) fail (1) and (3). "n/a": no release within the
record (the front has not met the top, or the release has not reached the region by the end).
"""
import argparse
import csv
import glob
import json
import math
import os
import sys


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def slope(t, y):
    n = len(t)
    if n < 2:
        return float("nan")
    st, sy = sum(t), sum(y)
    stt = sum(a * a for a in t)
    sty = sum(a * b for a, b in zip(t, y))
    d = n * stt - st * st
    return (n * sty - st * sy) / d if d else float("nan")


# upper bounds of the engine's default regions (engine/scene.cpp) [um], for runs whose run.json
# predates its "regions" entry
REGION_TOP_UM = {"I": 900.0, "II": 600.0, "III": 300.0}
HOLD_NS, MIN_HOLD_NS = 100.0, 30.0


def meeting_time(run, body, v, ft, fy):
    """First front.csv time at which the front reaches the free top (None: never)."""
    cr = run.get("case_resolved", {})
    top0 = None
    for b in cr.get("bodies", []):
        if b.get("name") == body.get("name") and b.get("y_range_um"):
            top0 = b["y_range_um"][1]
    if top0 is None:
        return None
    tol = 2.0 * cr.get("grid", {}).get("cell_size_um", 4.0)
    t_meet = next((t for t, y in zip(ft, fy) if y >= top0 - v * t * 1e-3 - tol), None)
    # the driver ends front.csv when the wave reaches the far end: a record that
    # stops well before the run's end met the top at its last row
    t_end = run.get("end_time_s", 0.0) * 1e9
    if t_meet is None and run.get("status") == "completed" and len(ft) > 1 and ft[-1] < t_end - 3 * (ft[-1] - ft[-2]):
        t_meet = ft[-1]
    return t_meet


def release_time(t, uy, level, t_from):
    """First t >= t_from from which uy stays above level for HOLD_NS (or to the end, >= MIN_HOLD_NS)."""
    end = t[-1] if t else 0.0
    for i, ti in enumerate(t):
        if ti < t_from or uy[i] <= level:
            continue
        stop = min(ti + HOLD_NS, end)
        if stop - ti < MIN_HOLD_NS:
            return None
        if all(u > level for tj, u in zip(t[i:], uy[i:]) if tj <= stop):
            return ti
    return None


PLATEAU = [("P_mean_GPa", "P"), ("T_mean_K", "T"), ("rho_mean_gcc", "rho"), ("P_std_GPa", "std P"),
           ("T_std_K", "std T")]


def summarise(outdir, region, times, plateau=None):
    run = json.load(open(os.path.join(outdir, "run.json")))
    body = run["bodies"][0]
    for b in run["bodies"]:
        if b["name"] == "target":
            body = b
    v = abs(body["velocity_m_s"][1])
    series = read_csv(os.path.join(outdir, "series.csv"))
    regions = sorted({r["region"] for r in series})
    regions_seen = list(dict.fromkeys(r["region"] for r in series))
    rows = [r for r in series if r["region"] == region]
    out = {"case": run["case"], "porosity": body.get("porosity", 0.0), "v": v,
           "particles": run["particles"], "wall_min": run["wall_seconds"] / 60.0, "status": run["status"],
           "end_ns": run["end_time_s"] * 1e9}
    out["P_peak"] = max((float(r["P_mean_GPa"]) for r in rows), default=float("nan"))
    out["rho_peak"] = max((float(r["rho_mean_gcc"]) for r in rows), default=float("nan"))
    for t in times:
        near = min(rows, key=lambda r: abs(float(r["time_ns"]) - t), default=None)
        ok = near is not None and abs(float(near["time_ns"]) - t) < 0.05 * t
        out[f"T_{t:g}"] = float(near["T_mean_K"]) if ok else float("nan")
    if plateau:
        win = [r for r in rows if plateau[0] <= float(r["time_ns"]) <= plateau[1]]
        for col, _ in PLATEAU:
            out["plateau_" + col] = sum(float(r[col]) for r in win) / len(win) if win else float("nan")
    front = read_csv(os.path.join(outdir, "front.csv"))
    ft = [float(r["time_ns"]) for r in front]
    fy = [float(r["front_y_um"]) for r in front]
    t_meet = meeting_time(run, body, v, ft, fy)
    out["t_meet"] = t_meet
    n = sum(1 for t in ft if t_meet is None or t < t_meet)  # the compaction front's own record
    h = n // 2
    out["front1"] = slope(ft[:h], fy[:h]) * 1e3  # um/ns -> m/s
    out["front2"] = slope(ft[h:n], fy[h:n]) * 1e3
    out["atten"] = out["front2"] / out["front1"] if out["front1"] else float("nan")
    out["release"] = {}
    # from the top down: regions with a higher upper bound first (series order when unknown)
    tops = dict(REGION_TOP_UM)
    tops.update({r["name"]: r["y_range_um"][1] for r in run.get("regions", [])})  # run.json, newer runs
    order = sorted(regions, key=lambda g: (-tops.get(g, float("-inf")), regions_seen.index(g)))
    t_above = t_meet if front else 0.0
    for reg in order:
        rr = [r for r in series if r["region"] == reg]
        arr = None
        if t_above is not None and rr:
            arr = release_time([float(r["time_ns"]) for r in rr], [float(r["Uy_mean_ms"]) for r in rr],
                               0.05 * v, t_above)
        out["release"][reg] = arr
        t_above = arr
    return out, regions


def ensemble_members(outdir):
    """The seed runs of an ensemble directory (seed_<S>/run.json), in seed order; [] for a run."""
    if os.path.exists(os.path.join(outdir, "run.json")):
        return []
    dirs = [os.path.dirname(p) for p in glob.glob(os.path.join(outdir, "seed_*", "run.json"))]

    def seed_of(d):
        tail = os.path.basename(d)[len("seed_"):]
        return (0, int(tail), "") if tail.lstrip("-").isdigit() else (1, 0, tail)
    return sorted(dirs, key=seed_of)


def mean_sd(values):
    """Mean and sample standard deviation of the finite values (sd NaN for fewer than two)."""
    v = [x for x in values if x is not None and x == x]
    if not v:
        return float("nan"), float("nan")
    m = sum(v) / len(v)
    sd = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else float("nan")
    return m, sd


def interp(t, ts, ys):
    """Linear interpolation of (ts, ys) at t; NaN outside [ts[0], ts[-1]]."""
    if not ts or t < ts[0] - 1e-9 or t > ts[-1] + 1e-9:
        return float("nan")
    lo, hi = 0, len(ts) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if ts[mid] <= t:
            lo = mid
        else:
            hi = mid
    if ts[hi] == ts[lo]:
        return ys[lo]
    w = min(max((t - ts[lo]) / (ts[hi] - ts[lo]), 0.0), 1.0)
    return ys[lo] + w * (ys[hi] - ys[lo])


def write_series_ensemble(outdir, members):
    """OUTDIR/series_ensemble.csv: per region and time, every numeric series.csv column as
    <column>_mean and <column>_sd over the seeds. Rows are written at the first seed's times
    (the runs' steps differ, so their row times differ by up to a step; the other seeds are
    interpolated linearly), up to the earliest end of the seeds' records. n_seeds counts the
    seeds with a value there."""
    runs = [read_csv(os.path.join(d, "series.csv")) for d in members]
    if not runs or not runs[0]:
        return None
    cols = [c for c in runs[0][0].keys() if c not in ("time_ns", "region")]
    by_region = []
    for rows in runs:
        reg = {}
        for r in rows:
            reg.setdefault(r["region"], []).append(r)
        by_region.append(reg)
    t_end = min(float(rows[-1]["time_ns"]) for rows in runs if rows)
    path = os.path.join(outdir, "series_ensemble.csv")
    with open(path, "w") as f:
        f.write(",".join(["time_ns", "region", "n_seeds"] + [f"{c}_{k}" for c in cols for k in ("mean", "sd")]) + "\n")
        for region, rows0 in by_region[0].items():
            series = []
            for reg in by_region:
                rr = reg.get(region, [])
                ts = [float(r["time_ns"]) for r in rr]
                series.append((ts, {c: [float(r[c]) for r in rr] for c in cols}))
            for r0 in rows0:
                t = float(r0["time_ns"])
                if t > t_end + 1e-9:
                    break
                cells, n = [], 0
                for c in cols:
                    vals = [interp(t, ts, ys[c]) for ts, ys in series]
                    n = max(n, sum(1 for x in vals if x == x))
                    m, sd = mean_sd(vals)
                    cells += [f"{m:.8g}", f"{sd:.8g}"]
                f.write(",".join([f"{t:.8g}", region, str(n)] + cells) + "\n")
    return path


def aggregate(results):
    """One row from the rows of an ensemble's seeds: numbers as (mean, sd)."""
    out = {"seeds": len(results)}
    for k, v in results[0].items():
        if k == "release":
            out[k] = {g: mean_sd([r[k].get(g) for r in results]) for g in v}
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out[k] = mean_sd([r[k] for r in results])
        elif k == "t_meet":
            out[k] = mean_sd([r[k] for r in results])
        else:
            out[k] = v
    out["status"] = ", ".join(sorted({r["status"] for r in results}))
    return out


def fmt(x, f="{:.3g}"):
    if isinstance(x, tuple):  # an ensemble's (mean, sd)
        m, sd = x
        return fmt(m, f) + ("" if sd != sd else " +- " + fmt(sd, f))
    return "n/a" if x is None or x != x else f.format(x)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--region", default="I")
    ap.add_argument("--times-ns", nargs="+", type=float, default=[1200.0, 1500.0])
    ap.add_argument("--plateau-ns", nargs=2, type=float, metavar=("T0", "T1"),
                    help="add the region's means over T0-T1 [ns] of P, T, rho, std P, std T")
    ap.add_argument("--dir-names", action="store_true",
                    help="name each row by its output directory instead of its case (sweeps)")
    a = ap.parse_args()
    results = []
    regions = []
    for od in a.outdirs:
        members = ensemble_members(od)
        try:
            if members:
                seeds = [summarise(d, a.region, a.times_ns, a.plateau_ns) for d in members]
                r, regs = aggregate([x[0] for x in seeds]), seeds[0][1]
                write_series_ensemble(od, members)
            else:
                r, regs = summarise(od, a.region, a.times_ns, a.plateau_ns)
        except (OSError, KeyError, ValueError, json.JSONDecodeError) as e:
            print(f"skipping {od}: {e}", file=sys.stderr)
            continue
        if a.dir_names:
            r["case"] = os.path.basename(os.path.normpath(od))
        results.append(r)
        regions = regions or regs
    if not results:
        return 1
    head = (["case", "porosity", "v [m/s]", f"peak P {a.region} [GPa]", f"peak rho {a.region} [g/cc]"] +
            [f"T {a.region} at {t:g} ns [K]" for t in a.times_ns] +
            ([f"{lab} {a.region} {a.plateau_ns[0]:g}-{a.plateau_ns[1]:g} ns" for _, lab in PLATEAU]
             if a.plateau_ns else []) +
            ["front speed [m/s] (1st half)", "2nd half", "attenuation"] +
            [f"release at {g} [ns]" for g in regions] + ["particles", "run [min]", "status"])
    if any("seeds" in r for r in results):
        head.insert(1, "seeds")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in results:
        cells = [r["case"], fmt(r["porosity"], "{:.3f}"), fmt(r["v"], "{:.0f}"), fmt(r["P_peak"]),
                 fmt(r["rho_peak"])] + [fmt(r[f"T_{t:g}"], "{:.0f}") for t in a.times_ns] + \
                ([fmt(r["plateau_" + col], "{:.4g}") for col, _ in PLATEAU] if a.plateau_ns else []) + \
                [fmt(r["front1"], "{:.0f}"), fmt(r["front2"], "{:.0f}"), fmt(r["atten"], "{:.3f}")] + \
                [fmt(r["release"].get(g), "{:.0f}") for g in regions] + \
                [fmt(r["particles"], "{:.0f}"), fmt(r["wall_min"], "{:.1f}"), r["status"]]
        if "seeds" in head:
            cells.insert(1, str(r.get("seeds", 1)))
        print("| " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
