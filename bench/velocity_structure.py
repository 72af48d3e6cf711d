#!/usr/bin/env python3
"""Why the mean squares of the velocity gradient do not converge: velocity structure functions.

For runs of one case at several cell sizes (the output directories of bench/porous_convergence.py:
DIR/h4, DIR/h2, DIR/h1), takes the snapshot at --time-ns, the points of a band (--band y0,y1 in
um), and the second-order structure function of the velocity

  S2(r) = < |u(x + r e) - u(x)|^2 >   [(m/s)^2], averaged over e = x and e = y

on a pixel grid of the run's point spacing (each pixel the mean velocity of its points; pixels
without points, i.e. open space, are left out; periodic in x). A velocity field smooth at the
scale r has S2 ~ r^2, and then the mean square gradient S2(r) / r^2 tends to a limit as r (and
h) shrink; a rough one has S2 ~ r^zeta with zeta < 2, and the mean squares of its gradient grow as
h^(zeta - 2) when the grid resolves smaller scales. The script prints S2 at r = 1, 2, 4, ... um
for each h, the local slope zeta between successive r, and S2(r) / r^2 [1/us^2], beside the band's
<R^2> and <D^2> (series.csv at the same time).

  /usr/bin/python3 bench/velocity_structure.py DIR [--h 4,2,1] [--time-ns 200] [--band 50,150]

Writes a markdown table on stdout. Figures in docs/verification.md for the porous strip come from it.
"""
import argparse
import csv
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts"))
import figures  # noqa: E402  (the one reader of particles.xdmf)


def snapshot_at(run, t_ns):
    """(path, time [ns]) of the snapshot nearest to t_ns: scripts/figures.py's reading of
    fields/particles.xdmf."""
    try:
        t, path = figures.Run(run).nearest_snapshot(t_ns)
    except figures.Skip as e:
        sys.exit(f"error: {run}: {e}")
    return path, t


def series_row(run, t_ns, region):
    """series.csv's row of the region nearest to t_ns."""
    with open(os.path.join(run, "series.csv")) as f:
        rows = [r for r in csv.DictReader(f) if r.get("region") == region]
    if not rows:
        return None
    return min(rows, key=lambda r: abs(float(r["time_ns"]) - t_ns))


def pixel_field(x, y, u, x0, x1, y0, y1, pix):
    """Mean of u (n x 2) per pixel; NaN where a pixel holds no point."""
    nx = int(round((x1 - x0) / pix))
    ny = int(math.floor((y1 - y0) / pix))
    i = np.floor((x - x0) / pix).astype(int) % nx
    j = np.floor((y - y0) / pix).astype(int)
    keep = (j >= 0) & (j < ny)
    i, j, u = i[keep], j[keep], u[keep]
    s = np.zeros((ny, nx, 2))
    c = np.zeros((ny, nx))
    np.add.at(s, (j, i), u)
    np.add.at(c, (j, i), 1.0)
    with np.errstate(invalid="ignore"):
        f = s / c[:, :, None]
    f[c == 0] = np.nan
    return f


def structure(f, k):
    """S2 at a shift of k pixels: the mean over x (periodic) and y shifts of |du|^2."""
    vals = []
    dx = np.roll(f, -k, axis=1) - f
    vals.append(np.nansum(dx ** 2, axis=2)[~np.isnan(dx[:, :, 0])])
    if k < f.shape[0]:
        dy = f[k:] - f[:-k]
        vals.append(np.nansum(dy ** 2, axis=2)[~np.isnan(dy[:, :, 0])])
    v = np.concatenate(vals)
    return float(v.mean()) if v.size else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir", help="directory holding h4, h2, h1 (bench/porous_convergence.py --out)")
    ap.add_argument("--h", default="4,2,1", help="cell sizes [um] (subdirectories hH)")
    ap.add_argument("--time-ns", type=float, default=200.0)
    ap.add_argument("--band", default="50,150", help="y range of the band [um]")
    ap.add_argument("--region", default="III", help="series.csv region for <R^2>, <D^2>")
    ap.add_argument("--x-range", default="0,96", help="periodic x range [um]")
    a = ap.parse_args()
    hs = [float(v) for v in a.h.split(",")]
    y0, y1 = (float(v) for v in a.band.split(","))
    x0, x1 = (float(v) for v in a.x_range.split(","))
    rs = [0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0]
    table = {}
    for h in hs:
        run = os.path.join(a.dir, f"h{h:g}")
        path, t = snapshot_at(run, a.time_ns)
        with h5py.File(path, "r") as f:
            pos = f["particles/position"][:] * 1e6  # um
            vel = f["particles/velocity"][:]  # m/s
        band = (pos[:, 1] >= y0) & (pos[:, 1] < y1)
        pix = 0.5 * h  # the point spacing at 2 x 2 points per cell
        fld = pixel_field(pos[band, 0], pos[band, 1], vel[band, :2], x0, x1, y0, y1, pix)
        s2 = {}
        for r in rs:
            k = r / pix
            if r >= pix - 1e-9 and abs(k - round(k)) < 1e-9:
                s2[r] = structure(fld, int(round(k)))
        row = series_row(run, t, a.region)
        table[h] = (t, s2, row, float(np.nanstd(fld[:, :, 1])))

    print(f"Velocity structure function S2(r) = <|u(x+r) - u(x)|^2> in y = {y0:g}-{y1:g} um "
          f"(pixels of h/2, x and y shifts), snapshot nearest {a.time_ns:g} ns.\n")
    print("| h [um] | t [ns] | " + " | ".join(f"S2({r:g} um)" for r in rs) + " | U_y std [m/s] | <R^2> / <D^2> [1/us^2] |")
    print("|---" * (len(rs) + 4) + "|")
    for h in hs:
        t, s2, row, sd = table[h]
        cells = [f"{s2[r]:.0f}" if r in s2 else "" for r in rs]
        rd = f"{float(row['R2_mean_per_us2']):.1f} / {float(row['D2_mean_per_us2']):.1f}" if row and "R2_mean_per_us2" in row else ""
        print(f"| {h:g} | {t:.0f} | " + " | ".join(cells) + f" | {sd:.0f} | {rd} |")
    print("\nLocal slope zeta = dlog S2 / dlog r (2 for a smooth field):\n")
    print("| h [um] | " + " | ".join(f"{rs[i]:g}-{rs[i + 1]:g} um" for i in range(len(rs) - 1)) + " |")
    print("|---" * len(rs) + "|")
    for h in hs:
        s2 = table[h][1]
        cells = []
        for i in range(len(rs) - 1):
            r0, r1 = rs[i], rs[i + 1]
            cells.append(f"{math.log(s2[r1] / s2[r0]) / math.log(r1 / r0):.2f}" if r0 in s2 and r1 in s2 else "")
        print(f"| {h:g} | " + " | ".join(cells) + " |")
    print("\nS2(r) / r^2 [1/us^2] (the mean square gradient the scale r sees):\n")
    print("| h [um] | " + " | ".join(f"{r:g} um" for r in rs) + " |")
    print("|---" * (len(rs) + 1) + "|")
    for h in hs:
        s2 = table[h][1]
        print(f"| {h:g} | " + " | ".join(f"{s2[r] / r ** 2:.1f}" if r in s2 else "" for r in rs) + " |")


if __name__ == "__main__":
    main()
