#!/usr/bin/env python3
"""Area a collapsing void leaves open, by volume: cases/verify/void_collapse.toml.

Runs the single-void case and the same block without the void at each cell size (snapshots every
2 ns), then, at each snapshot time, takes the strip below a cut that lies between two lattice
rows in the undisturbed material above the shock (initially at --cut-um, falling at the impact
speed), and sets the open area = strip width x cut height - sum of the points' volumes below
the cut (V_p = m_p / rho_p). The dense run's value at the same time (the scheme's own volume
error in the shocked material) is subtracted, and the result is given in per cent of the void's
initial open area (the void as cut from the lattice, t = 0). Negative: the faces overlap.
test_porous measures the same collapse with rasterized point disks instead (voids.csv).

  /usr/bin/python3 bench/void_open_area.py [--h 4,2,1] [--times 12,16,20] [--out DIR]
      [--cut-um 150] [--driver build/shockmpm] [--no-run] [--check PCT] [--set KEY=VALUE ...]

--set passes a case override to every run (e.g. solver.shape="cubic"); the void-face keys
(contact.void_face*, e.g. contact.void_face_volume_fraction=0.9) go to the void run only: the
block without the void has no void faces, and the driver rejects them there.

--check PCT: exit 1 unless the open area at the last time is within +-PCT % at every h (the CI
test void_open_area: h = 4 um, 7 %; measured -5.0 %).

Writes a markdown table on stdout (docs/verification.md).
"""
import argparse
import os
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import figures  # noqa: E402  (the one reader of particles.xdmf)
CASE = os.path.join(ROOT, "cases", "verify", "void_collapse.toml")


def snapshots(run):
    """(time [ns], path) of every snapshot listed in particles.xdmf (scripts/figures.py reads it)."""
    return figures.Run(run).snapshots()


def open_area(run, times, cut0, v, width):
    """{time wanted: (snapshot time, open area [um^2])} below the falling cut, t = 0 included."""
    snaps = snapshots(run)
    with h5py.File(snaps[0][1], "r") as f:
        x0 = f["particles/position"][:, 0] * 1e6
        y0 = f["particles/position"][:, 1] * 1e6
        rho0 = float(f["particles/density"][:].max())  # every point starts at the material's rho0
    xs = np.unique(np.round(x0, 6))
    V0 = float(np.min(np.diff(xs))) ** 2  # the lattice cell of a point (um^2): mass = rho0 V0
    rows = np.unique(np.round(y0, 6))
    above = rows[rows > cut0]
    if len(above) < 2:
        sys.exit(f"error: no lattice rows above --cut-um {cut0:g} in {run}")
    cut_init = 0.5 * (above[0] + above[1])  # between two rows: no point straddles it
    res = {}
    for t_want in [0.0] + list(times):
        t, path = min(snaps, key=lambda s: abs(s[0] - t_want))
        with h5py.File(path, "r") as f:
            y = f["particles/position"][:, 1] * 1e6
            rho = f["particles/density"][:]
        cut = cut_init - v * t * 1e-3  # the undisturbed lattice falls at v
        res[t_want] = (t, width * cut - float(np.sum(rho0 / rho[y < cut])) * V0)
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--h", default="4,2,1", help="cell sizes [um]")
    ap.add_argument("--times", default="12,16,20", help="times [ns] (the void collapses by about 13 ns)")
    ap.add_argument("--out", default="/tmp/void_open_area")
    ap.add_argument("--cut-um", type=float, default=150.0,
                    help="initial height [um] above which the cut is placed (above the shock until 20 ns)")
    ap.add_argument("--driver", default=os.path.join(ROOT, "build", "shockmpm"))
    ap.add_argument("--no-run", action="store_true")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="case override for every run")
    ap.add_argument("--check", type=float, default=0.0, help="exit 1 unless |open| <= PCT %% at the last time")
    a = ap.parse_args()
    hs = [float(x) for x in a.h.split(",")]
    times = [float(x) for x in a.times.split(",")]
    # the dense block: the case without its [bodies.voids] table (the last table of the file)
    text = open(CASE).read()
    dense_case = os.path.join(a.out, "void_collapse_dense.toml")
    os.makedirs(a.out, exist_ok=True)
    with open(dense_case, "w") as f:
        # written outside cases/: name the library the void case finds next to it (cases/materials.toml)
        f.write(f'materials_file = "{os.path.join(os.path.dirname(os.path.dirname(CASE)), "materials.toml")}"\n')
        f.write(text.split("[bodies.voids]")[0])
    v, width = 1000.0, 64.0
    failed = 0
    print(f"Open area of the collapsed void, by volume, less the dense run's, in % of the void's initial "
          f"open area; times {a.times} ns.\n")
    print("| h [um] | initial [um^2] | " + " | ".join(f"{t:g} ns" for t in times) + " |")
    print("|---" * (len(times) + 2) + "|")
    for h in hs:
        runs = {}
        for name, case in (("void", CASE), ("dense", dense_case)):
            out = os.path.join(a.out, f"{name}-h{h:g}")
            if not a.no_run:
                subprocess.run([a.driver, "run", case, "--quiet", "--overwrite", "--out", out,
                                "--set", f"grid.cell_size_um={h}", "--set", "run.snapshot_interval_ns=2.0",
                                "--set", f"run.end_time_ns={max(times) + 1.0}"]
                               + [x for kv in a.set if name == "void" or not kv.startswith("contact.void_face")
                                  for x in ("--set", kv)],
                               check=True, stdout=subprocess.DEVNULL)
            runs[name] = open_area(out, times, a.cut_um, v, width)
        a0 = runs["void"][0.0][1] - runs["dense"][0.0][1]
        cells = [f"{100.0 * (runs['void'][t][1] - runs['dense'][t][1]) / a0:+.1f} %" for t in times]
        print(f"| {h:g} | {a0:.0f} | " + " | ".join(cells) + " |")
        last = 100.0 * (runs["void"][times[-1]][1] - runs["dense"][times[-1]][1]) / a0
        if a.check > 0.0 and not abs(last) <= a.check:
            failed += 1
    if a.check > 0.0:
        print(f"\ncheck |open| <= {a.check:g} % at {times[-1]:g} ns: {'FAIL' if failed else 'PASS'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
