#!/usr/bin/python3
"""The simulated compaction wave against the fully compacted porous Hugoniot (issue 15, item 3).

Issue 14's strip (cases/verify/porous_strip.toml, voids of 10 um) with 14, 55 and 105 voids
(porosity about 0.09, 0.3 and 0.5) driven onto the wall at 500, 1000 and 2000 m/s. Per run:
the compaction front speed in the wall frame (front.csv, least squares over 0.5-0.95 of the run,
which ends when a front at the Hugoniot speed would have crossed 70 % of the strip, at most
200 ns) and the mean wall stress over the same window, against the fully compacted Rankine-Hugoniot
front and pressure for the run's achieved porosity (run.json compacted_hugoniot: no strength,
the material behind the front at rest and fully dense).

  /usr/bin/python3 bench/compaction_hugoniot.py [--h 4] [--out DIR] [--driver build/shockmpm]

Prints a markdown table (docs/accuracy.md, "Compaction against the porous Hugoniot").
"""
import argparse
import csv
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, default=4.0)
    ap.add_argument("--out", default="/tmp/compaction_hugoniot")
    ap.add_argument("--driver", default=os.path.join(ROOT, "build", "shockmpm"))
    a = ap.parse_args()
    print(f"Strip at h = {a.h:g} um; front and wall stress fitted over 0.5-0.95 of the run.\n")
    print("| voids | porosity | v [m/s] | front [m/s] | RH front | error | wall stress [GPa] | RH P | error | energy |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for count in (14, 55, 105):
        for v in (500.0, 1000.0, 2000.0):
            out = os.path.join(a.out, f"n{count}-v{v:g}-h{a.h:g}")
            sets = ["--set", f"grid.cell_size_um={a.h}", "--set", f"bodies.target.voids.count={count}",
                    "--set", f"bodies.target.velocity_m_s=[0.0, {-v}]"]
            case = os.path.join(ROOT, "cases", "verify", "porous_strip.toml")
            # the run ends before the front could reach the free top of the 500 um strip: at
            # 70 % of the strip at the compacted Hugoniot's speed (at most 200 ns)
            chk = subprocess.run([a.driver, "check", case] + sets, capture_output=True, text=True).stdout
            rh = [float(l.split("front ")[1].split(" m/s")[0]) for l in chk.splitlines() if "fully compacted" in l]
            if not rh:
                print(f"| {count} | | {v:g} | no fully compacted Hugoniot state (`check`) | | | | | | |", flush=True)
                continue
            t_end = min(200.0, 0.7 * 500e-6 / rh[0] * 1e9)
            cmd = [a.driver, "run", case, "--quiet", "--overwrite", "--out", out, "--set", f"run.end_time_ns={t_end:.1f}"]
            subprocess.run(cmd + sets, stdout=subprocess.DEVNULL)
            try:
                run = json.load(open(os.path.join(out, "run.json")))
                c = run["bodies"][0]["compacted_hugoniot"]
                fr = rows(os.path.join(out, "front.csv"))
                t = np.array([float(r["time_ns"]) for r in fr])
                y = np.array([float(r["front_y_um"]) for r in fr])
                sel = (t >= 0.5 * t_end) & (t <= 0.95 * t_end)
                front = float(np.polyfit(t[sel], y[sel], 1)[0]) * 1e3
                wl = rows(os.path.join(out, "wall.csv"))
                tw = np.array([float(r["time_ns"]) for r in wl])
                sw = np.array([float(r["wall_stress_GPa"]) for r in wl])
                wall = float(sw[(tw >= 0.5 * t_end) & (tw <= 0.95 * t_end)].mean())
                en = rows(os.path.join(out, "energy.csv"))
                e = float(en[-1]["residual_J_per_m"]) / float(en[0]["total_J_per_m"])
                rf, rp = c["front_speed_wall_frame_m_s"], c["P_Pa"] * 1e-9
                print(f"| {count} | {run['bodies'][0]['porosity']:.3f} | {v:g} | {front:.0f} | {rf:.0f} | "
                      f"{100 * (front / rf - 1):+.1f} % | {wall:.2f} | {rp:.2f} | {100 * (wall / rp - 1):+.1f} % | {e:+.1e} |",
                      flush=True)
            except (OSError, KeyError, ValueError, IndexError) as e:
                print(f"| {count} | | {v:g} | run failed: {e} | | | | | | |", flush=True)


if __name__ == "__main__":
    main()
