#!/usr/bin/python3
"""Summary table (markdown) of shockmpm study runs, one row per output directory.

usage: scripts/study_summary.py OUTDIR [OUTDIR ...] [--region I] [--times-ns 1200 1500]

Columns: porosity and impact speed (run.json); peak of the region's mean pressure and density
(series.csv); mean temperature of the region at the given times (nearest row); compression-front
speed (least-squares slope of front.csv over the first and the second half of the front's
record, in the frame of the wall) and its attenuation (second / first); for each region the time
the release from the free top arrives, taken as the first time after the region's peak pressure
at which its mean U_y exceeds +5 % of the impact speed (the material behind the front is at rest
in this frame; the release sets it moving up); the run's particles and wall time.
"""
import argparse
import csv
import json
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


def summarise(outdir, region, times):
    run = json.load(open(os.path.join(outdir, "run.json")))
    body = run["bodies"][0]
    for b in run["bodies"]:
        if b["name"] == "target":
            body = b
    v = abs(body["velocity_m_s"][1])
    series = read_csv(os.path.join(outdir, "series.csv"))
    regions = sorted({r["region"] for r in series})
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
    front = read_csv(os.path.join(outdir, "front.csv"))
    ft = [float(r["time_ns"]) for r in front]
    fy = [float(r["front_y_um"]) for r in front]
    h = len(ft) // 2
    out["front1"] = slope(ft[:h], fy[:h]) * 1e3  # um/ns -> m/s
    out["front2"] = slope(ft[h:], fy[h:]) * 1e3
    out["atten"] = out["front2"] / out["front1"] if out["front1"] else float("nan")
    out["release"] = {}
    for reg in regions:
        rr = [r for r in series if r["region"] == reg]
        if not rr:
            continue
        k = max(range(len(rr)), key=lambda i: float(rr[i]["P_mean_GPa"]))
        arr = next((float(r["time_ns"]) for r in rr[k:] if float(r["Uy_mean_ms"]) > 0.05 * v), None)
        out["release"][reg] = arr
    return out, regions


def fmt(x, f="{:.3g}"):
    return "n/a" if x is None or x != x else f.format(x)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--region", default="I")
    ap.add_argument("--times-ns", nargs="+", type=float, default=[1200.0, 1500.0])
    a = ap.parse_args()
    results = []
    regions = []
    for od in a.outdirs:
        try:
            r, regs = summarise(od, a.region, a.times_ns)
        except (OSError, KeyError, ValueError, json.JSONDecodeError) as e:
            print(f"skipping {od}: {e}", file=sys.stderr)
            continue
        results.append(r)
        regions = regions or regs
    if not results:
        return 1
    head = (["case", "porosity", "v [m/s]", f"peak P {a.region} [GPa]", f"peak rho {a.region} [g/cc]"] +
            [f"T {a.region} at {t:g} ns [K]" for t in a.times_ns] +
            ["front speed [m/s] (1st half)", "2nd half", "attenuation"] +
            [f"release at {g} [ns]" for g in regions] + ["particles", "run [min]", "status"])
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in results:
        cells = [r["case"], fmt(r["porosity"], "{:.3f}"), fmt(r["v"], "{:.0f}"), fmt(r["P_peak"]),
                 fmt(r["rho_peak"])] + [fmt(r[f"T_{t:g}"], "{:.0f}") for t in a.times_ns] + \
                [fmt(r["front1"], "{:.0f}"), fmt(r["front2"], "{:.0f}"), fmt(r["atten"], "{:.3f}")] + \
                [fmt(r["release"].get(g), "{:.0f}") for g in regions] + \
                [str(r["particles"]), fmt(r["wall_min"], "{:.1f}"), r["status"]]
        print("| " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
