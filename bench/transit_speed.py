#!/usr/bin/python3
"""Shock speed of a flyer-driven porous sample the way plate-impact experiments take it: from
transit times, and against the momentum the driver delivers.

  /usr/bin/python3 bench/transit_speed.py OUTDIR [OUTDIR ...] [--drive GAUGE] [--from-ns 40 --to-ns 200]

OUTDIR: a run of a case like cases/verify/porous_iron_free_surface.toml: a sample (the body
`target`, at rest, its bottom face at y0 and a free top at y1) struck from below by a flyer; the
target records its free surface (`record_free_surface`), a line of gauges named `depth_<k>`
follows points through it, and one gauge (--drive, default `drive`) sits in the dense flyer near
the impact face. Per run, with the sample's thickness L = y1 - y0 (its case) and rho00 (run.json:
the material's density times 1 - porosity):

  arrival    the free surface's velocity first exceeds 10 % / 50 % of its final value (mean over
             the last 20 % of the record; the first exceed time is linearly interpolated): the foot
             and the middle of the wave's rise reach the rear surface. Us = L / t (the wave starts
             at the impact face at t = 0).
  gauges     each depth gauge's arrival (v_y first above up / 2, up below) against its initial
             height: Us from a least-squares line over the gauges above 100 um from the face.
  momentum   the driving stress P and particle velocity up: the drive gauge's -sigma_yy and v_y,
             means over --from-ns to --to-ns (after the flyer's shock has passed the gauge and
             before its rear release returns). A wave that carries the sample from rest to up under
             P has Us = P / (rho00 up) by momentum conservation, whatever its shape: the speed at
             which mass enters the compacted state.

Where the wave's rise spreads as it runs, the foot arrives ahead of the middle, and both ahead of
the momentum Us; a steady wave gives one speed for all three (the foot ahead by its rise time
over the transit time). tests/transit_speed_check.py checks both cases on synthetic runs. Prints one Markdown row per run and
the mean and sample standard deviation over the runs.
"""
import argparse
import csv
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts"))
from study_summary import mean_sd  # noqa: E402  (mean and sample standard deviation of the finite values)


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def first_above(t, v, level):
    for i in range(1, len(t)):
        if v[i] > level >= v[i - 1]:
            return t[i - 1] + (level - v[i - 1]) / (v[i] - v[i - 1]) * (t[i] - t[i - 1])
    return math.nan


def body_of(run, name):
    for b in run["case_resolved"]["bodies"]:
        if b.get("name") == name:
            return b
    raise KeyError(f"no body named {name!r} in run.json")


def measure(out, drive, t0, t1):
    run = json.load(open(os.path.join(out, "run.json")))
    tb = body_of(run, "target")
    y0, y1 = tb["y_range_um"]
    L = y1 - y0
    info = next(b for b in run["bodies"] if b["name"] == "target")
    rho00 = float(run["case_resolved"]["materials"][info["material"]]["density_kg_m3"]) * (1.0 - float(info["porosity"]))
    fs = rows(os.path.join(out, "freesurface.csv"))
    t = [float(r["time_ns"]) for r in fs]
    u = [float(r["u_fs_m_s"]) for r in fs]
    n = max(1, len(u) // 5)
    u_final = sum(u[-n:]) / n
    g = rows(os.path.join(out, "gauges.csv"))
    dr = [r for r in g if r["gauge"] == drive and t0 <= float(r["time_ns"]) <= t1]
    if not dr:
        raise ValueError(f"gauge {drive!r} has no rows in {t0:g}-{t1:g} ns")
    P = sum(-float(r["sigma_yy_GPa"]) for r in dr) / len(dr) * 1e9
    up = sum(float(r["vy_m_s"]) for r in dr) / len(dr)
    pts = []
    names = sorted({r["gauge"] for r in g if r["gauge"].startswith("depth_")}, key=lambda s: int(s.split("_")[1]))
    for name in names:
        gg = [r for r in g if r["gauge"] == name]
        yi = float(gg[0]["y_um"]) - y0
        ta = first_above([float(r["time_ns"]) for r in gg], [float(r["vy_m_s"]) for r in gg], 0.5 * up)
        if yi > 100.0 and math.isfinite(ta):
            pts.append((ta, yi))
    us_g = math.nan
    if len(pts) >= 3:
        mt = sum(p[0] for p in pts) / len(pts)
        my = sum(p[1] for p in pts) / len(pts)
        us_g = sum((p[0] - mt) * (p[1] - my) for p in pts) / sum((p[0] - mt) ** 2 for p in pts)  # um/ns = km/s
    t10 = first_above(t, u, 0.1 * u_final)
    t50 = first_above(t, u, 0.5 * u_final)
    return {"run": out, "L_um": L, "rho00": rho00, "P_GPa": P * 1e-9, "up_m_s": up, "u_fs_final_m_s": u_final,
            "t10_ns": t10, "t50_ns": t50, "Us_foot": L / t10, "Us_mid": L / t50, "Us_gauges": us_g,
            "Us_momentum": P / (rho00 * up) * 1e-3, "gauges_used": len(pts)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--drive", default="drive", help="the flyer's gauge near the impact face")
    ap.add_argument("--from-ns", type=float, default=40.0)
    ap.add_argument("--to-ns", type=float, default=200.0)
    a = ap.parse_args()
    res = []
    for od in a.outdirs:
        try:
            res.append(measure(od, a.drive, a.from_ns, a.to_ns))
        except (OSError, KeyError, ValueError, IndexError, StopIteration, ZeroDivisionError) as e:
            print(f"{od}: {e}", file=sys.stderr)
    if not res:
        return 1
    cols = [("P_GPa", "P drive [GPa]", "{:.2f}"), ("up_m_s", "up [m/s]", "{:.0f}"),
            ("u_fs_final_m_s", "u_fs final [m/s]", "{:.0f}"), ("Us_foot", "Us foot (10 %) [km/s]", "{:.3f}"),
            ("Us_mid", "Us middle (50 %) [km/s]", "{:.3f}"), ("Us_gauges", "Us gauges [km/s]", "{:.3f}"),
            ("Us_momentum", "Us momentum P / (rho00 up) [km/s]", "{:.3f}")]
    print("| run | " + " | ".join(c[1] for c in cols) + " |")
    print("|---|" + "---|" * len(cols))
    for r in res:
        print(f"| {os.path.basename(os.path.normpath(r['run']))} | " + " | ".join(f.format(r[k]) for k, _, f in cols) + " |")
    if len(res) > 1:
        cells = []
        for k, _, f in cols:
            m, sd = mean_sd([r[k] for r in res])
            cells.append(f.format(m) + ("" if not math.isfinite(sd) else " +- " + f.format(sd)))
        print(f"| mean +- sd ({len(res)} runs) | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
