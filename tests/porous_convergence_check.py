#!/usr/bin/python3
"""Checks of bench/porous_convergence.py's band measures on synthetic outputs (exact answers).

- bulk_density: a band's points' mass over its area, count x rho0 x (body area / points) over the
  grid's width x the band's height, in g/cc; nan when run.json lacks what it needs;
- zero_pressure_share: in the LAST snapshot (by name), of the band's points (the region's body, y
  inside its bounds by current position), the share at exactly zero pressure; nan without
  snapshots or without the region;
- open_split: in that snapshot, 1 - sum V / area and the fractured points' expansion past m / rho0
  over the area, past m / rho_zp(e) (the zero-pressure density of their energy) where the
  snapshot has energies and the material is Mie-Grueneisen.

  /usr/bin/python3 tests/porous_convergence_check.py SOURCE_DIR
"""
import json
import math
import os
import sys
import tempfile

import h5py
import numpy as np

SRC = sys.argv[1]
sys.path.insert(0, os.path.join(SRC, "bench"))
import porous_convergence as pc  # noqa: E402

fails = []


def check(cond, what):
    if not cond:
        fails.append(what)
        print("FAIL:", what)


run = {
    "bodies": [{"name": "target", "material": "al", "area_m2": 1e-10, "particles": 100}],
    "case_resolved": {"materials": {"al": {"density_kg_m3": 2700.0}}, "grid": {"x_range_um": [0.0, 10.0]}},
    "regions": [{"name": "III", "body": 0, "y_range_um": [0.0, 10.0]}],
}
# 25 points of mass 2700 x 1e-10 / 100 = 2.7e-9 kg/m over 10 x 10 um^2: 675 kg/m^3
b = pc.bulk_density(run, "III", 25.0)
check(abs(b - 0.675) < 1e-12, f"bulk density 0.675 g/cc, got {b}")
check(math.isnan(pc.bulk_density(run, "I", 25.0)), "bulk density of a missing region is nan")
check(math.isnan(pc.bulk_density({"bodies": []}, "III", 25.0)), "bulk density without a target is nan")


def snapshot(path, y_um, p, body, rho=None, sxy=None, energy=None):
    with h5py.File(path, "w") as f:
        n = len(y_um)
        pos = np.zeros((n, 2))
        pos[:, 1] = np.asarray(y_um) * 1e-6
        f["particles/position"] = pos
        f["particles/pressure"] = np.asarray(p, dtype=float)
        f["particles/body"] = np.asarray(body, dtype=np.uint8)
        if rho is not None:
            f["particles/density"] = np.asarray(rho, dtype=float)
            f["particles/stress_xx"] = -np.asarray(p, dtype=float)
            f["particles/stress_yy"] = -np.asarray(p, dtype=float)
            f["particles/stress_xy"] = np.asarray(sxy, dtype=float)
        if energy is not None:
            f["particles/energy"] = np.asarray(energy, dtype=float)


with tempfile.TemporaryDirectory() as d:
    check(math.isnan(pc.zero_pressure_share(d, run, "III")), "no snapshots: nan")
    os.makedirs(os.path.join(d, "fields"))
    # an earlier snapshot with no zero pressure at all: must not be the one read
    snapshot(os.path.join(d, "fields", "snap_00000002.h5"), [1, 2, 3], [1e9, 1e9, 1e9], [0, 0, 0])
    # the last one: in the band (body 0, 0 <= y <= 10 um) 4 points, 1 at zero P; outside it a
    # zero-P point above the band and one of another body
    snapshot(os.path.join(d, "fields", "snap_00000010.h5"), [1, 2, 5, 9, 12, 5],
             [0.0, 2e9, -1e8, 3e9, 0.0, 0.0], [0, 0, 0, 0, 0, 1])
    z = pc.zero_pressure_share(d, run, "III")
    check(abs(z - 0.25) < 1e-15, f"zero-P share 0.25, got {z}")
    check(math.isnan(pc.zero_pressure_share(d, run, "II")), "a missing region: nan")
    check(all(math.isnan(v) for v in pc.open_split(d, run, "III")), "open_split without densities: nan")
    # points of 2.7e-9 kg/m (m / rho0 = 1e-12 m^2); in the band: one at rho0 (V = 1e-12), one
    # compressed (rho 5400: 0.5e-12), one fractured at 1350 (V = 2e-12, 1e-12 of it crack) and
    # one at zero pressure but sheared (not fractured, V = 2e-12 counted whole); area 1e-10:
    # gaps 1 - 5.5e-12 / 1e-10 = 0.945, fractured 1e-12 / 1e-10 = 0.01
    snapshot(os.path.join(d, "fields", "snap_00000011.h5"), [1, 2, 5, 9, 12],
             [1e9, 2e9, 0.0, 0.0, 0.0], [0, 0, 0, 0, 0], rho=[2700, 5400, 1350, 1350, 100],
             sxy=[0.0, 0.0, 0.0, 1e6, 0.0])
    g, fr = pc.open_split(d, run, "III")
    check(abs(g - 0.945) < 1e-12, f"gaps 0.945, got {g}")
    check(abs(fr - 0.01) < 1e-12, f"fractured expansion 0.01, got {fr}")
    check(all(math.isnan(v) for v in pc.open_split(d, run, "II")), "open_split of a missing region: nan")
    # the same points with energies, the material Mie-Grueneisen (c0 = 3000 m/s, gamma0 = 2):
    # rho_zp = rho0 (1 - 2 e / c0^2); the fractured point at e = 2.25e5 J/kg has rho_zp = 0.95
    # rho0, so 1e-12 / 0.95 of its V = 2e-12 is solid; energies of the others do not matter.
    # Without energies, or another EOS, the cap stays m / rho0.
    snapshot(os.path.join(d, "fields", "snap_00000012.h5"), [1, 2, 5, 9, 12],
             [1e9, 2e9, 0.0, 0.0, 0.0], [0, 0, 0, 0, 0], rho=[2700, 5400, 1350, 1350, 100],
             sxy=[0.0, 0.0, 0.0, 1e6, 0.0], energy=[1e6, 1e6, 2.25e5, 1e6, 1e6])
    mg = json.loads(json.dumps(run))
    mg["case_resolved"]["materials"]["al"].update(
        {"eos": "mie_gruneisen", "bulk_sound_speed_m_s": 3000.0, "gruneisen_gamma": 2.0})
    g, fr = pc.open_split(d, mg, "III")
    check(abs(g - 0.945) < 1e-12, f"gaps with energies 0.945, got {g}")
    check(abs(fr - (2e-12 - 1e-12 / 0.95) / 1e-10) < 1e-12, f"fractured expansion past m / rho_zp, got {fr}")
    g, fr = pc.open_split(d, run, "III")
    check(abs(fr - 0.01) < 1e-12, f"fractured expansion without the EOS keys 0.01, got {fr}")
    # past e = c0^2 / gamma0 (4.5e6 J/kg here) no zero-pressure density: all of V is solid
    snapshot(os.path.join(d, "fields", "snap_00000013.h5"), [1, 2, 5, 9, 12],
             [1e9, 2e9, 0.0, 0.0, 0.0], [0, 0, 0, 0, 0], rho=[2700, 5400, 1350, 1350, 100],
             sxy=[0.0, 0.0, 0.0, 1e6, 0.0], energy=[1e6, 1e6, 6e6, 1e6, 1e6])
    g, fr = pc.open_split(d, mg, "III")
    check(abs(fr) < 1e-15, f"fractured point past the tension branch's reach holds all its V, got {fr}")

print("porous_convergence checks:", "FAILED " + "; ".join(fails) if fails else "all passed")
sys.exit(1 if fails else 0)
