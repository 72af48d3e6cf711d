#!/usr/bin/python3
"""bench/transit_speed.py on a synthetic run: a steady wave at Us = 2 km/s carrying a sample of
rho00 = 4000 kg/m^3 from rest to up = 1000 m/s under P = rho00 Us up = 8 GPa, its rise 10 ns
long at the gauges and 0.2 ns at the free surface. The foot, middle, gauge and momentum speeds
must all come out as 2 km/s (the foot within the rise: 0.08 ns of 300 ns). A second run whose
rise spreads (the foot at 2.5, the middle at 2.2 km/s) must report those, and the momentum speed
is unchanged.
  tests/transit_speed_check.py SOURCE_DIR"""
import json
import os
import subprocess
import sys
import tempfile

SRC = sys.argv[1]
L, RHO0, PHI, UP, US, RISE = 600.0, 8000.0, 0.5, 1000.0, 2.0, 10.0  # um, kg/m^3, -, m/s, km/s, ns


def make(d, us_foot, us_mid):
    os.makedirs(d)
    run = {"bodies": [{"name": "target", "material": "m", "porosity": PHI}],
           "case_resolved": {"bodies": [{"name": "target", "y_range_um": [0.0, L]}],
                             "materials": {"m": {"density_kg_m3": RHO0}}}}
    json.dump(run, open(os.path.join(d, "run.json"), "w"))
    t_foot, t_mid = L / us_foot, L / us_mid  # ns: the free surface's 10 % and 50 % of its final 2 up
    t_foot = min(t_foot, t_mid - 0.08)  # a steady wave: a rise of 0.2 ns
    with open(os.path.join(d, "freesurface.csv"), "w") as f:
        f.write("time_ns,body,u_fs_m_s\n")
        # linear rise through 10 % at t_foot and 50 % at t_mid, then flat at 2 up
        slope = 0.4 * 2 * UP / (t_mid - t_foot)
        t0 = t_foot - 0.1 * 2 * UP / slope
        for k in range(0, 4001):
            t = 0.1 * k
            f.write(f"{t},target,{min(max(0.0, slope * (t - t0)), 2 * UP)}\n")
    with open(os.path.join(d, "gauges.csv"), "w") as f:
        f.write("time_ns,gauge,x_um,y_um,vx_m_s,vy_m_s,sigma_xx_GPa,sigma_yy_GPa,sigma_xy_GPa,P_GPa,rho_g_cc,T_K\n")
        P = RHO0 * (1 - PHI) * US * 1e3 * UP * 1e-9  # GPa
        for k in range(0, 4001):
            t = 0.1 * k
            f.write(f"{t},drive,0,-100,0,{UP if t > 20 else 0},{-P},{-P if t > 20 else 0},0,{P},8,300\n")
            for j in range(12):
                y = 25.0 + 50.0 * j
                ta = y / us_mid  # the middle of the rise (up / 2) arrives at y / Us
                v = min(max(0.0, UP * (0.5 + (t - ta) / RISE)), UP)
                f.write(f"{t},depth_{j},0,{y},0,{v},0,0,0,0,8,300\n")


with tempfile.TemporaryDirectory() as tmp:
    make(os.path.join(tmp, "steady"), US, US)
    make(os.path.join(tmp, "spread"), 2.5, 2.2)
    out = subprocess.run(["/usr/bin/python3", os.path.join(SRC, "bench", "transit_speed.py"),
                          os.path.join(tmp, "steady"), os.path.join(tmp, "spread")],
                         capture_output=True, text=True)
    print(out.stdout + out.stderr)
    lines = {l.split("|")[1].strip(): [float(c) for c in l.split("|")[2:-1]] for l in out.stdout.splitlines()
             if l.startswith("| steady") or l.startswith("| spread")}
    want = {"steady": [8.0, 1000, 2000, 2.0, 2.0, 2.0, 2.0], "spread": [8.0, 1000, 2000, 2.5, 2.2, 2.2, 2.0]}
    bad = [(k, lines.get(k), w) for k, w in want.items()
           if k not in lines or any(abs(a - b) > 1e-3 * abs(b) + 1e-9 for a, b in zip(lines[k], w))]
    if out.returncode != 0 or bad:
        print(f"transit_speed_check: FAIL: {bad}")
        sys.exit(1)
print("transit_speed_check: PASS")
