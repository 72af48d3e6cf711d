#!/usr/bin/python3
"""Hot spots: the temperature distribution of the target's points in a band along the impact
axis at one snapshot, as percentiles and as the shares of points above thresholds (docs/study.md,
"What 3D changes"). Every point counts once, in 2D and in 3D (all z).

usage: scripts/hot_spots.py OUTDIR [OUTDIR ...] --time-ns 600 --band-um 100 300
       [--percentiles 50 90 99 99.9] [--above-K 1500 3000]

Prints one Markdown row per output directory: the snapshot's time, the points in the band, the
percentiles [K] and the shares above each threshold [%]. The snapshot is the one nearest to
--time-ns (scripts/figures.py's choice).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from figures import Run  # noqa: E402


def band_temperatures(outdir, time_ns, band_um):
    run = Run(outdir)
    t, path = run.nearest_snapshot(time_ns)
    d = run.load(path, ["temperature"])
    sel = (d["y_um"] >= band_um[0]) & (d["y_um"] < band_um[1])
    return d["time_ns"], d["temperature"][sel]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--time-ns", type=float, required=True)
    ap.add_argument("--band-um", type=float, nargs=2, required=True, metavar=("LO", "HI"))
    ap.add_argument("--percentiles", type=float, nargs="+", default=[50, 90, 99, 99.9])
    ap.add_argument("--above-K", type=float, nargs="+", default=[1500, 3000])
    a = ap.parse_args()
    head = ["run", "time [ns]", "points"] + [f"T p{q:g} [K]" for q in a.percentiles] + \
        [f"above {k:g} K" for k in a.above_K]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for out in a.outdirs:
        t, T = band_temperatures(out, a.time_ns, a.band_um)
        if T.size == 0:
            print(f"{out}: no points in the band {a.band_um[0]:g}-{a.band_um[1]:g} um", file=sys.stderr)
            continue
        cells = [os.path.basename(os.path.normpath(out)), f"{t:.0f}", f"{T.size}"]
        cells += [f"{v:.0f}" for v in np.percentile(T, a.percentiles)]
        cells += [f"{100.0 * np.mean(T > k):.1f} %" for k in a.above_K]
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
