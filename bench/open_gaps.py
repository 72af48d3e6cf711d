#!/usr/bin/env python3
"""Where the open volume behind a compaction front lies: in pores, or in gaps of about a cell.

For each run directory, in one snapshot (default the last; fields/snap_*.h5), the points of the
porous body (body 0) in a band behind the front: by default the experiment harness's band, 0.1 to
0.8 of the front's height at the snapshot's time (front.csv; bench/experiment_hugoniot.py BAND),
or --y LO,HI [um]. Prints one markdown row per run:

  open       1 - sum V / band volume: the band's volume that the points' own volumes
             (V = m / rho, equal masses: a lattice sample) leave empty (negative: overlap)
  uncovered  the share of the band's voxels that no point's ball covers, radius
             kCoverRadius V^(1/D) (0.75 in 2D, 0.92 in 3D: the engine's open-area measure,
             engine/diagnostics.hpp; openings narrower than about half a point spacing do not
             count); voxels of a quarter point spacing
  width      the uncovered space's local width [um], percentiles 50 / 90 / 99 over its voxels:
             twice a voxel's distance to the nearest covered voxel (Chebyshev distance, in
             voxels: at most the Euclidean one), so a slit's voxels read about its width and a
             pore's read less than its diameter
  <= 1 cell  the share of the uncovered voxels that lie in gaps at most one cell wide (distance
             to the nearest covered voxel at most h / 2)
  field > 0  the share of the band's points in a void-face field other than field 0 (the side
             below a void; docs/method.md): as cut, the points next to a void's upper side; a
             point joins field 0 once its void has closed and welded (contact.void_face_merge)

  /usr/bin/python3 bench/open_gaps.py RUN [RUN ...] [--snapshot NAME] [--band 0.1,0.8 | --y LO,HI]

Periodic along x (and z in 3D), as the harness's strips and columns. numpy and h5py only.
"""
import argparse
import csv
import glob
import json
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from experiment_hugoniot import BAND  # noqa: E402  (the harness's band behind the front)

COVER = {2: 0.75, 3: 0.92}  # engine/diagnostics.hpp kCoverRadius


def front_at(run_dir, t_ns):
    """The front's height [um] at t_ns, interpolated in front.csv."""
    with open(os.path.join(run_dir, "front.csv")) as f:
        rows = [r for r in csv.DictReader(f)]
    t = np.array([float(r["time_ns"]) for r in rows])
    y = np.array([float(r["front_y_um"]) for r in rows])
    ok = np.isfinite(t) & np.isfinite(y)
    if not ok.any():
        raise ValueError("front.csv holds no front")
    return float(np.interp(t_ns, t[ok], y[ok]))


def coverage(pos, rad, lo, shape, vox, periodic):
    """Boolean image of the voxels (shape, sides vox per axis, corner lo) whose centre lies in some
    point's ball (centres pos, radii rad); periodic axes wrap, the others end at the image."""
    D = len(shape)
    R = int(np.ceil(rad.max() / vox.min())) + 1
    M = 2 * R  # the margin: points up to R voxels outside, their balls R further
    pshape = tuple(n + 2 * M for n in shape)
    img = np.zeros(int(np.prod(pshape)), dtype=bool)
    idx = np.floor((pos - lo) / vox).astype(np.int64)
    frac = (idx + 0.5) * vox - (pos - lo)  # the point's own voxel centre, relative to the point
    keep = np.all((idx >= -R) & (idx < np.array(shape) + R), axis=1)
    idx, frac, rad = idx[keep] + M, frac[keep], rad[keep]
    strides = np.array([int(np.prod(pshape[a + 1:])) for a in range(D)], dtype=np.int64)
    base = idx @ strides
    reach = np.ceil(rad / vox.min()).astype(int) + 1  # each point's offsets, in voxels
    for r in np.unique(reach):  # the points by reach: the few large balls alone walk the wide offsets
        g = reach == r
        b, fr, r2 = base[g], frac[g], rad[g] ** 2
        rng = range(-r, r + 1)
        for off in np.array(np.meshgrid(*([rng] * D), indexing="ij")).reshape(D, -1).T:
            if np.sum(((np.abs(off) - 1.0).clip(0.0) * vox) ** 2) > r2.max():
                continue  # no ball of the group reaches this offset's voxel
            d = fr + off * vox
            hit = np.einsum("ij,ij->i", d, d) <= r2
            img[b[hit] + int(off @ strides)] = True
    img = img.reshape(pshape)
    for a in range(D):  # fold the margins back onto the image
        if periodic[a]:
            sl = [slice(None)] * D
            lo_m, hi_m, core_lo, core_hi = list(sl), list(sl), list(sl), list(sl)
            lo_m[a], hi_m[a] = slice(0, M), slice(M + shape[a], 2 * M + shape[a])
            core_hi[a], core_lo[a] = slice(shape[a], M + shape[a]), slice(M, 2 * M)
            img[tuple(core_hi)] |= img[tuple(lo_m)]
            img[tuple(core_lo)] |= img[tuple(hi_m)]
    return img[tuple(slice(M, M + n) for n in shape)]


def distance_to_cover(img, periodic):
    """Chebyshev distance [voxels] of every voxel to the nearest covered one (0 on covered
    voxels); beyond the non-periodic ends counts as covered."""
    dist = np.zeros(img.shape, dtype=np.int32)
    reached = img.copy()
    k = 0
    while not reached.all():
        k += 1
        grown = reached.copy()
        for a in range(img.ndim):
            for s in (1, -1):
                sh = np.roll(grown, s, axis=a)
                if not periodic[a]:
                    edge = [slice(None)] * img.ndim
                    edge[a] = slice(0, 1) if s == 1 else slice(-1, None)
                    sh[tuple(edge)] = True
                grown = grown | sh
        new = grown & ~reached
        dist[new] = k
        reached = grown
    return dist


def analyse(run_dir, snapshot, band, y_range):
    run = json.load(open(os.path.join(run_dir, "run.json")))
    grid = run["case_resolved"]["grid"]
    body = run["bodies"][0]
    D = 3 if "z_range_um" in grid else 2
    h = float(grid["cell_size_um"])
    spacing = h / float(run["case_resolved"]["bodies"][0].get("points_per_cell", 2))
    rho0 = float(run["case_resolved"]["materials"][body["material"]]["density_kg_m3"])
    size = float(body["volume_m3"] if D == 3 else body["area_m2"]) * (1e18 if D == 3 else 1e12)  # um^D
    mass_over_rho0 = size / int(body["particles"])  # a point's lattice volume [um^D]
    snaps = sorted(glob.glob(os.path.join(run_dir, "fields", "snap_*.h5")))
    path = os.path.join(run_dir, "fields", snapshot) if snapshot else (snaps[-1] if snaps else None)
    if not path or not os.path.exists(path):
        raise ValueError(f"no snapshot {snapshot or 'fields/snap_*.h5'}")
    with h5py.File(path, "r") as f:
        t = float(f["particles"].attrs["time"]) * 1e9
        pos = f["particles/position"][:, :D] * 1e6
        V = mass_over_rho0 * rho0 / f["particles/density"][:]
        mine = f["particles/body"][:] == 0
        field = f["particles/field"][:][mine] if "particles/field" in f else None
    pos, V = pos[mine], V[mine]
    if y_range:
        lo_y, hi_y = y_range
    else:
        yf = front_at(run_dir, t)
        lo_y, hi_y = band[0] * yf, band[1] * yf
    axes = [grid["x_range_um"], [lo_y, hi_y]] + ([grid["z_range_um"]] if D == 3 else [])
    lo = np.array([a[0] for a in axes], dtype=float)
    ext = np.array([a[1] - a[0] for a in axes], dtype=float)
    in_band = (pos[:, 1] >= lo_y) & (pos[:, 1] < hi_y)
    open_frac = 1.0 - float(V[in_band].sum()) / float(np.prod(ext))
    shape = tuple(max(1, int(round(e / (spacing / 4.0)))) for e in ext)
    vox = ext / np.array(shape)  # about a quarter point spacing along each axis
    periodic = [True, False] + ([True] if D == 3 else [])
    # balls capped at twice a lattice point's (a fractured point's debris can grow far larger)
    rad = np.minimum(COVER[D] * V ** (1.0 / D), 2.0 * COVER[D] * spacing)
    near = (pos[:, 1] >= lo_y - 2 * rad.max()) & (pos[:, 1] < hi_y + 2 * rad.max())
    img = coverage(pos[near], rad[near], lo, shape, vox, periodic)
    unc = ~img
    res = {"run": run_dir, "t_ns": t, "dim": D, "h_um": h, "band_um": (lo_y, hi_y),
           "open": open_frac, "uncovered": float(unc.mean()),
           "other_field": float(np.mean(field[in_band] > 0)) if field is not None and in_band.any() else None}
    if unc.any():
        w = 2.0 * distance_to_cover(img, periodic)[unc] * float(vox.mean())
        res["width_um"] = [float(np.percentile(w, q)) for q in (50, 90, 99)]
        res["within_cell"] = float(np.mean(w <= h))
    else:
        res["width_um"], res["within_cell"] = [0.0, 0.0, 0.0], 1.0
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", help="run directories (run.json, front.csv, fields/)")
    ap.add_argument("--snapshot", default="", help="snapshot file name in fields/ (default: the last)")
    ap.add_argument("--band", default=f"{BAND[0]},{BAND[1]}", help="the band [fractions of the front's height]")
    ap.add_argument("--y", default="", help="the band [um], LO,HI (instead of --band)")
    a = ap.parse_args()
    try:
        band = tuple(float(v) for v in a.band.split(","))
        y_range = tuple(float(v) for v in a.y.split(",")) if a.y else None
        if len(band) != 2 or not 0.0 <= band[0] < band[1] or (y_range and (len(y_range) != 2 or y_range[0] >= y_range[1])):
            raise ValueError
    except ValueError:
        sys.exit(f"error: --band {a.band!r} / --y {a.y!r}: two increasing numbers, LO,HI")
    print("| run | t [ns] | h [um] | band [um] | open | uncovered | width [um] 50 / 90 / 99 % | <= 1 cell | field > 0 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in a.runs:
        try:
            s = analyse(r, a.snapshot, band, y_range)
        except (OSError, KeyError, ValueError) as e:
            sys.exit(f"error: {r}: {e}")
        w = " / ".join(f"{v:.2f}" for v in s["width_um"])
        of = "n/a" if s["other_field"] is None else f"{100 * s['other_field']:.0f} %"
        print(f"| {r} | {s['t_ns']:.1f} | {s['h_um']:g} | {s['band_um'][0]:.0f}-{s['band_um'][1]:.0f} | "
              f"{100 * s['open']:.1f} % | {100 * s['uncovered']:.1f} % | {w} | {100 * s['within_cell']:.0f} % | {of} |",
              flush=True)


if __name__ == "__main__":
    main()
