#!/usr/bin/python3
"""Checks of bench/velocity_structure.py (the evidence that <D^2> follows the cell size).

Unit part, on synthetic pixel fields with a known structure function:
- a linear shear u = (a y, 0): x shifts see 0, y shifts (a r)^2, so S2(k) is their mean weighted by
  how many pairs each has, ((ny - k) / (2 ny - k)) (a k pix)^2, exactly; with a hole of empty pixels
  the pairs touching it are left out, and the y pairs' value is still (a r)^2;
- a wave periodic in x, u = (0, sin(2 pi x / Lx)): the x shift wraps around, S2 = 1 - cos(2 pi r / Lx)
  over the x pairs, 0 over the y pairs;
- pixel_field averages the points of a pixel, leaves empty pixels NaN and wraps x periodically.
End-to-end part (with a driver): the porous strip at h = 8 and 4 um to 20 ns, the script's tables
printed with numbers in them.

  /usr/bin/python3 tests/velocity_structure_check.py SOURCE_DIR [SHOCKMPM]
"""
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

SRC = sys.argv[1]
sys.path.insert(0, os.path.join(SRC, "bench"))
import velocity_structure as vs  # noqa: E402

fails = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        fails.append(what)


# pixel_field: two points in one pixel are averaged, x wraps, empty pixels are NaN
x = np.array([0.2, 0.7, 10.3, -0.6])  # the last wraps to the pixel at x in [9, 10)
y = np.array([0.5, 0.5, 0.5, 1.5])
u = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0], [7.0, 8.0]])
f = vs.pixel_field(x, y, u, 0.0, 10.0, 0.0, 3.0, 1.0)
check(f.shape == (3, 10, 2), "pixel_field shape (ny, nx, 2)")
check(np.allclose(f[0, 0], [3.0, 4.0]), "x = 0.2, 0.7 and 10.3 (wrapped) averaged in the first pixel")
check(np.allclose(f[1, 9], [7.0, 8.0]), "x = -0.6 wraps to the last column")
check(np.isnan(f[2, 4, 0]) and np.isnan(f[0, 5, 1]), "empty pixels are NaN")

# linear shear
ny, nx, pix, a = 40, 24, 0.5, 3.0
jj, ii = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
fld = np.zeros((ny, nx, 2))
fld[:, :, 0] = a * (jj + 0.5) * pix
for k in (1, 2, 4, 8):
    expect = (ny - k) / (2 * ny - k) * (a * k * pix) ** 2
    got = vs.structure(fld, k)
    check(abs(got - expect) <= 1e-12 * expect, f"shear S2(k = {k}) = {got:.6g}, exact {expect:.6g}")
# a hole: pairs touching it are dropped; over the y pairs that are left the value is still (a r)^2
hole = fld.copy()
hole[10:14, 5:9] = np.nan
k = 2
dy = hole[k:] - hole[:-k]
ny_pairs = int((~np.isnan(dy[:, :, 0])).sum())
nx_pairs = int((~np.isnan((np.roll(hole, -k, axis=1) - hole)[:, :, 0])).sum())
expect = ny_pairs * (a * k * pix) ** 2 / (ny_pairs + nx_pairs)
got = vs.structure(hole, k)
check(ny_pairs < (ny - k) * nx and abs(got - expect) <= 1e-12 * expect,
      f"shear with a hole: S2 = {got:.6g}, exact {expect:.6g} ({ny_pairs} y pairs, {nx_pairs} x pairs)")

# a wave periodic in x
Lx = nx * pix
wave = np.zeros((ny, nx, 2))
wave[:, :, 1] = np.sin(2 * math.pi * (ii + 0.5) * pix / Lx)
for k in (1, 3, 12, 23):
    r = k * pix
    expect = (1 - math.cos(2 * math.pi * r / Lx)) * ny * nx / (ny * nx + (ny - k) * nx)
    got = vs.structure(wave, k)
    check(abs(got - expect) <= 1e-12, f"periodic wave S2(k = {k}) = {got:.6g}, exact {expect:.6g}")

# end to end on real output
if len(sys.argv) > 2:
    exe = sys.argv[2]
    with tempfile.TemporaryDirectory() as tmp:
        for h in (8, 4):
            out = os.path.join(tmp, f"h{h}")
            subprocess.run([exe, "run", os.path.join(SRC, "cases/verify/porous_strip.toml"), "--out", out,
                            "--threads", "2", "--quiet", "--set", f"grid.cell_size_um={h}",
                            "--set", "run.end_time_ns=20", "--set", "run.snapshot_interval_ns=10",
                            "--set", "run.diagnostics_interval_ns=2"], check=True)
        r = subprocess.run([sys.executable, os.path.join(SRC, "bench/velocity_structure.py"), tmp,
                            "--h", "8,4", "--time-ns", "20", "--band", "400,500"],
                           capture_output=True, text=True)
        print(r.stdout)
        check(r.returncode == 0, f"velocity_structure.py exit status {r.returncode} {r.stderr.strip()}")
        rows = [l for l in r.stdout.splitlines() if l.startswith("| 8 |") or l.startswith("| 4 |")]
        check(len(rows) == 6, f"a row per h in each of the 3 tables ({len(rows)})")
        check(all("nan" not in l for l in rows), "no NaN in the tables")
        bad = subprocess.run([sys.executable, os.path.join(SRC, "bench/velocity_structure.py"),
                              os.path.join(tmp, "none"), "--h", "4"], capture_output=True, text=True)
        check(bad.returncode != 0 and "error" in bad.stderr, "a missing run directory is an error naming it")

print(f"{len(fails)} failed" if fails else "all passed")
sys.exit(1 if fails else 0)
