#!/usr/bin/python3
"""Checks of bench/open_gaps.py on synthetic outputs with known answers.

A 2D square lattice (spacing 1 um: h = 2 um, 2 points per cell; 40 um wide, periodic in x; the
columns at x = 0, 1, ..., 39 um, so that the balls of the column at x = 0 reach across the seam)
from which columns of points are taken out:
- a slit 3 lattice columns wide (x = 10, 11, 12 um): open 3/40; the balls of radius 0.75 spacings leave
  2.5 um of it uncovered (6.25 % of the band), at most 2.5 um wide, and 80 % of its voxels in the
  part within one cell (2 um) of width;
- that slit plus a gap 8 columns wide across the periodic seam (x = 36 ... 39, 0 ... 3 um): open 11/40, uncovered
  (2.5 + 7.5) / 40, its widest voxels 7.5 um wide, and under half of the uncovered voxels within
  one cell of width;
- a band given in um (--y) and as fractions of the front's height (front.csv) reads the same
  points;
- the points of the columns x >= 20 um in field 1: their share of the band's points, 20 of the
  slit case's 37 columns.

  /usr/bin/python3 tests/open_gaps_check.py SOURCE_DIR
"""
import json
import os
import sys
import tempfile

import h5py
import numpy as np

SRC = sys.argv[1]
sys.path.insert(0, os.path.join(SRC, "bench"))
import open_gaps  # noqa: E402

fails = []


def check(cond, what):
    if not cond:
        fails.append(what)
        print("FAIL:", what)


def run_dir(d, removed):
    """A run directory: the lattice without the columns whose x centre lies in `removed`."""
    os.makedirs(os.path.join(d, "fields"))
    xs, ys = np.meshgrid(np.arange(40.0), np.arange(60) + 0.5, indexing="ij")
    keep = ~removed(xs.ravel())
    x, y = xs.ravel()[keep], ys.ravel()[keep]
    run = {"bodies": [{"name": "s", "material": "fe", "area_m2": 40e-12 * 60, "particles": 2400}],
           "case_resolved": {"materials": {"fe": {"density_kg_m3": 7850.0}},
                             "grid": {"cell_size_um": 2.0, "x_range_um": [0.0, 40.0], "y_range_um": [0.0, 60.0]},
                             "bodies": [{"points_per_cell": 2}]}}
    json.dump(run, open(os.path.join(d, "run.json"), "w"))
    with open(os.path.join(d, "front.csv"), "w") as f:
        f.write("time_ns,front_y_um\n0,50\n10,50\n")
    with h5py.File(os.path.join(d, "fields", "snap_00000000.h5"), "w") as f:
        f["particles/position"] = np.stack([x, y], 1) * 1e-6
        f["particles/density"] = np.full(len(x), 7850.0)
        f["particles/body"] = np.zeros(len(x), dtype=np.uint8)
        f["particles/field"] = (x >= 20).astype(np.uint8)
        f["particles"].attrs["time"] = 5e-9


with tempfile.TemporaryDirectory() as tmp:
    d = os.path.join(tmp, "slit")
    run_dir(d, lambda x: (x >= 10) & (x <= 12))
    s = open_gaps.analyse(d, "", (0.1, 0.8), (10.0, 40.0))
    check(abs(s["open"] - 3 / 40) < 1e-12, f"slit: open 0.075, got {s['open']}")
    check(abs(s["uncovered"] - 2.5 / 40) < 0.25 / 40, f"slit: uncovered 0.0625, got {s['uncovered']}")
    check(s["width_um"][2] <= 2.5 + 1e-9, f"slit: at most 2.5 um wide, got {s['width_um']}")
    check(abs(s["within_cell"] - 0.8) < 0.11, f"slit: 80 % within a cell, got {s['within_cell']}")
    check(abs(s["other_field"] - 20 / 37) < 1e-12, f"slit: field > 0 share 20/37, got {s['other_field']}")
    # the same band as fractions of the front's height (50 um at 5 ns)
    f = open_gaps.analyse(d, "", (0.2, 0.8), None)
    check(f["band_um"] == (10.0, 40.0) and f["open"] == s["open"], f"band from the front: {f['band_um']}")

    d = os.path.join(tmp, "seam")
    run_dir(d, lambda x: ((x >= 10) & (x <= 12)) | (x >= 36) | (x <= 3))
    s = open_gaps.analyse(d, "snap_00000000.h5", (0.1, 0.8), (10.0, 40.0))
    check(abs(s["open"] - 11 / 40) < 1e-12, f"seam: open 0.275, got {s['open']}")
    check(abs(s["uncovered"] - 10 / 40) < 0.5 / 40, f"seam: uncovered 0.25, got {s['uncovered']}")
    check(abs(s["width_um"][2] - 7.5) <= 0.5, f"seam: widest 7.5 um, got {s['width_um']}")
    check(s["within_cell"] < 0.5, f"seam: under half within a cell, got {s['within_cell']}")

print("open_gaps_check:", "FAIL" if fails else "PASS")
sys.exit(1 if fails else 0)
