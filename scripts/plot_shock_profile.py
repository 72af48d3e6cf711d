#!/usr/bin/python3
"""Pressure, density and temperature profiles along y of a dense-impact run against the exact
Hugoniot plateau and shock position (docs/verification.md).

usage: scripts/plot_shock_profile.py OUTDIR [OUTDIR ...] [--png FILE]

Reads OUTDIR/run.json (the exact state is in bodies[0].dense_hugoniot, computed by the code from
its own EOS) and the last snapshot in OUTDIR/fields/. Row means over cells of the grid.
"""
import argparse
import glob
import json
import os

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def profile(outdir):
    run = json.load(open(os.path.join(outdir, "run.json")))
    snap = sorted(glob.glob(os.path.join(outdir, "fields", "snap_*.h5")))[-1]
    with h5py.File(snap, "r") as f:
        p = f["particles"]
        t = float(p.attrs["time"])
        y = p["position"][:, 1]
        P = p["pressure"][:]
        rho = p["density"][:]
        T = p["temperature"][:] if "temperature" in p else None
    h = run["case_resolved"]["grid"].get("cell_size_um", 0) * 1e-6 or run["case_resolved"]["grid"]["cell_size_m"]
    bins = np.arange(0, y.max() + h, h)
    idx = np.digitize(y, bins) - 1
    cnt = np.bincount(idx, minlength=len(bins))
    mean = lambda v: np.bincount(idx, weights=v, minlength=len(bins)) / np.maximum(cnt, 1)
    yc = (bins + 0.5 * h)[cnt > 0]
    body = run["bodies"][0]
    return dict(t=t, y=yc, P=mean(P)[cnt > 0], rho=mean(rho)[cnt > 0],
                T=None if T is None else mean(T)[cnt > 0], exact=body["dense_hugoniot"],
                v=abs(body["velocity_m_s"][1]), h=h, name=os.path.basename(os.path.normpath(outdir)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--png", default=None, help="output file (default OUTDIR/figures/shock_profile.png)")
    a = ap.parse_args()
    fig, axes = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for od in a.outdirs:
        r = profile(od)
        ex = r["exact"]
        y_shock = (ex["Us_m_s"] - r["v"]) * r["t"]  # lab frame: the shock runs up at Us - v
        lab = f"{r['name']}, h = {r['h'] * 1e6:g} um"
        axes[0].plot(r["y"] * 1e6, r["P"] * 1e-9, label=lab)
        axes[1].plot(r["y"] * 1e6, r["rho"], label=lab)
        if r["T"] is not None:
            axes[2].plot(r["y"] * 1e6, r["T"], label=lab)
        for ax, val in ((axes[0], ex["P_Pa"] * 1e-9), (axes[1], ex["rho_kg_m3"]), (axes[2], ex["T_K"])):
            ax.plot([0, y_shock * 1e6, y_shock * 1e6], [val, val, ax.get_ylim()[0] if ax is axes[2] else 0],
                    "k--", lw=1)
    axes[0].set_ylabel("P [GPa]")
    axes[1].set_ylabel("rho [kg/m^3]")
    axes[2].set_ylabel("T [K]")
    axes[2].set_xlabel("y [um] (wall at 0)")
    axes[0].set_title(f"dense Al on a rigid wall at t = {r['t'] * 1e9:.0f} ns; dashed: exact Hugoniot state and shock position")
    axes[0].title.set_fontsize(9)
    axes[1].set_ylim(bottom=2650)
    axes[2].set_ylim(bottom=280)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    png = a.png or os.path.join(a.outdirs[0], "figures", "shock_profile.png")
    os.makedirs(os.path.dirname(os.path.abspath(png)), exist_ok=True)
    fig.savefig(png, dpi=120)
    print(png)


if __name__ == "__main__":
    main()
