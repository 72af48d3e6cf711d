#!/usr/bin/python3
"""A study case at two resolutions: the coarse run's error against the fine one (the study's
error bars, docs/study.md).

usage: scripts/study_resolution.py COARSE FINE [--times-ns T ...] [--window-ns 50] [--fit-from-ns 200]
       [--initial DIR [--driver build/shockmpm]] [--markdown]

COARSE and FINE are output directories of the same case (e.g. h = 4 and h = 2 um; only the
record both have is compared, so FINE may be a shorter run or one stopped early).

- front speed: least-squares slope of front.csv (wall frame, m/s) over the same window in both,
  from --fit-from-ns to the end of the common record or to the coarse run's meeting time with the
  free top, whichever comes first (scripts/study_summary.py's t_meet);
- regional quantities (series.csv): the mean over --window-ns ending at each time of --times-ns
  (default: the end of the common record and 60 % of it, rounded down to 50 ns), in each region
  the compaction front has passed (front_y at the window's start above the region's top, in both
  runs): means and standard deviations of P, T, rho, U_y, <|R|>, <|D|>, <R^2>, <D^2>, and the
  open porosity.
- with --initial DIR (a run of the same case with a t = 0 snapshot, any resolution, e.g.
  `shockmpm run CASE --out DIR --set run.end_time_ns=1`): the porosity each run's front swept in
  the fit window and the fully compacted Hugoniot's front speed there
  (bench/compaction_hugoniot.py's swept_porosity and hugoniot_at; a random sample's porosity
  varies along y, docs/accuracy.md).
The difference is printed as (coarse - fine) / fine, except U_y's (over the impact speed) and the
open porosity's (absolute, in points of porosity); the open porosity counts a fractured point's
solid at most its volume at zero pressure, m / rho_zp(e) (engine/diagnostics.cpp), so that bands
with blown-up debris do not read far below 0.
"""
import argparse
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "bench"))
from study_summary import meeting_time, read_csv, slope  # noqa: E402

QUANTITIES = [  # (series.csv column, label, kind of difference)
    ("P_mean_GPa", "mean P [GPa]", "rel"),
    ("T_mean_K", "mean T [K]", "rel"),
    ("rho_mean_gcc", "mean rho [g/cc]", "rel"),
    ("Uy_mean_ms", "mean U_y [m/s]", "over_v"),
    ("P_std_GPa", "std P [GPa]", "rel"),
    ("T_std_K", "std T [K]", "rel"),
    ("rho_std_gcc", "std rho [g/cc]", "rel"),
    ("Uy_std_ms", "std U_y [m/s]", "rel"),
    ("R_mean_per_us", "<abs R> [1/us]", "rel"),
    ("D_mean_per_us", "<abs D> [1/us]", "rel"),
    ("R2_mean_per_us2", "<R^2> [1/us^2]", "rel"),
    ("D2_mean_per_us2", "<D^2> [1/us^2]", "rel"),
    ("open_porosity", "open porosity", "abs"),
]


def load(outdir):
    run = json.load(open(os.path.join(outdir, "run.json")))
    body = run["bodies"][0]
    v = abs(body["velocity_m_s"][1])
    front = [(float(r["time_ns"]), float(r["front_y_um"])) for r in read_csv(os.path.join(outdir, "front.csv"))]
    series = read_csv(os.path.join(outdir, "series.csv"))
    ft = [t for t, _ in front]
    fy = [y for _, y in front]
    return {"dir": outdir, "run": run, "v": v, "ft": ft, "fy": fy, "series": series,
            "t_meet": meeting_time(run, body, v, ft, fy),
            "t_end": max(ft) if ft else 0.0,
            "cell_um": run["case_resolved"]["grid"]["cell_size_um"] if "case_resolved" in run else float("nan"),
            "regions": {r["name"]: r["y_range_um"] for r in run.get("regions", [])}}


def front_at(r, t):
    """front_y [um] at the last record at or before t."""
    y = float("nan")
    for tt, yy in zip(r["ft"], r["fy"]):
        if tt > t + 1e-9:
            break
        y = yy
    return y


def fit(r, t0, t1):
    pts = [(t, y) for t, y in zip(r["ft"], r["fy"]) if t0 <= t <= t1]
    return slope([p[0] for p in pts], [p[1] for p in pts]) * 1e3  # um/ns -> m/s


def window_mean(r, region, col, t0, t1):
    vals = [float(x[col]) for x in r["series"] if x["region"] == region and t0 <= float(x["time_ns"]) <= t1
            and col in x and x[col] not in ("", None)]
    return sum(vals) / len(vals) if vals else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("coarse")
    ap.add_argument("fine")
    ap.add_argument("--times-ns", nargs="+", type=float)
    ap.add_argument("--window-ns", type=float, default=50.0)
    ap.add_argument("--fit-from-ns", type=float, default=200.0)
    ap.add_argument("--initial", help="a run of the case with a t = 0 snapshot: swept porosity and its Hugoniot")
    ap.add_argument("--driver", default=os.path.join(os.path.dirname(HERE), "build", "shockmpm"))
    ap.add_argument("--markdown", action="store_true", help="one markdown table instead of text")
    a = ap.parse_args()
    c, f = load(a.coarse), load(a.fine)
    if abs(c["v"] - f["v"]) > 1e-9:
        sys.exit(f"the two runs have different impact speeds ({c['v']} and {f['v']} m/s): not one case")
    t_common = min(c["t_end"], f["t_end"])
    t_fit_end = t_common if c["t_meet"] is None else min(t_common, c["t_meet"])
    if f["t_meet"] is not None:
        t_fit_end = min(t_fit_end, f["t_meet"])
    if t_fit_end <= a.fit_from_ns + 50.0:
        sys.exit(f"common record ends at {t_fit_end:.0f} ns: too short for a front fit from {a.fit_from_ns:.0f} ns")
    times = a.times_ns or sorted({math.floor(0.6 * t_common / 50.0) * 50.0, math.floor(t_common / 10.0) * 10.0})
    uc, uf = fit(c, a.fit_from_ns, t_fit_end), fit(f, a.fit_from_ns, t_fit_end)
    v = c["v"]
    print(f"coarse {c['dir']} (h = {c['cell_um']} um, record to {c['t_end']:.0f} ns), "
          f"fine {f['dir']} (h = {f['cell_um']} um, to {f['t_end']:.0f} ns); impact {v:.0f} m/s")
    rows = [("front speed (wall frame) [m/s]", f"{a.fit_from_ns:.0f}-{t_fit_end:.0f} ns", "all", uc, uf,
             (uc - uf) / uf)]
    if a.initial:
        import compaction_hugoniot as ch
        ini = json.load(open(os.path.join(a.initial, "run.json")))
        g = ini["case_resolved"]["grid"]["cell_size_um"]
        ppc = ini["case_resolved"]["bodies"][0].get("points_per_cell", 2)
        phis, rhs = [], []
        for r in (c, f):
            phi = ch.swept_porosity(a.initial, r["ft"], r["fy"], v, a.fit_from_ns, t_fit_end, g / ppc)
            us, _ = ch.hugoniot_at(a.driver, os.path.join(a.initial, "case_resolved.toml"), [], phi)
            phis.append(phi)
            rhs.append(us)
        rows.append(("swept porosity", f"{a.fit_from_ns:.0f}-{t_fit_end:.0f} ns", "all", phis[0], phis[1],
                     float("nan")))
        rows.append(("compacted Hugoniot front there [m/s]", "", "all", rhs[0], rhs[1], (rhs[0] - rhs[1]) / rhs[1]))
        rows.append(("front against that Hugoniot [%]", "", "all", 100 * (uc / rhs[0] - 1), 100 * (uf / rhs[1] - 1),
                     float("nan")))
    for t in times:
        t0 = t - a.window_ns
        for reg in sorted(c["regions"], key=lambda n: c["regions"][n][1]):
            top = c["regions"][reg][1]
            if not (front_at(c, t0) >= top and front_at(f, t0) >= top):
                continue
            for col, label, kind in QUANTITIES:
                xc, xf = window_mean(c, reg, col, t0, t), window_mean(f, reg, col, t0, t)
                if kind == "rel":
                    d = (xc - xf) / xf if xf else float("nan")
                elif kind == "over_v":
                    d = (xc - xf) / v
                else:
                    d = xc - xf
                rows.append((label, f"{t0:.0f}-{t:.0f} ns", reg, xc, xf, d))
    if a.markdown:
        print("| quantity | window | region | coarse | fine | coarse against fine |")
        print("|---|---|---|---|---|---|")
        for label, win, reg, xc, xf, d in rows:
            print(f"| {label} | {win} | {reg} | {xc:.4g} | {xf:.4g} | {'' if math.isnan(d) else f'{d * 100:+.1f} %'} |")
    else:
        for label, win, reg, xc, xf, d in rows:
            print(f"{label:36s} {win:>14s} {reg:>4s} {xc:12.4g} {xf:12.4g} " + ("" if math.isnan(d) else f"{d * 100:+8.1f} %"))
    if len(rows) == 1:
        print("no region is compacted in both runs at the times asked (front_y below the region's top)")


if __name__ == "__main__":
    main()
