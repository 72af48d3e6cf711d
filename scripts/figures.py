#!/usr/bin/python3
"""Figures of shockmpm runs in the style of the reference study (Xu et al. 2010).

usage: scripts/figures.py OUTDIR [OUTDIR ...] [--time-ns T] [--region NAME] [options]

For each OUTDIR writes PNGs under OUTDIR/figures/:
  map_P.png, map_T.png   pressure and temperature of the target over the deformed configuration
                         at the snapshot nearest --time-ns (default 500 ns)
  series_means.png       regional means of P, T, rho, U_y against time (series.csv)
  series_std.png         their standard deviations
  velocity_field.png     velocity vectors of a window (default 200 x 200 um just behind the
                         compression front), in the window's mean-velocity frame or the lab frame
  dissipation.png        <R^2>, <D^2>, <S^2> against time, one panel per region
  distributions.png      histograms of rho, P, T, U_y in one region (--region, default I) at up to
                         three times, against Gaussians of the same mean and deviation
  history.png            compression front, wall stress and energy against time
  freesurface.png        free-surface velocity against time (freesurface.csv) and, with gauges.csv,
                         each gauge's pressure
With several OUTDIRs also compare_means.png and compare_std.png (region --region) in the first
OUTDIR's figures/ (or --out DIR).

A 3D run (positions x, y, z; y the impact axis) gives the same figures. The maps and the velocity
field show a slice: the points in a slab one point spacing thick across z (--slice-axis; x gives
the y-z plane) about the middle of the grid's z range (--slice-at-um), centred on the nearest
layer of points while some points keep their lattice's layers; the titles give the slab as
"slice z = Z ± H µm". The distributions take all the points of the region, over the whole depth
("all z" in the title). The energy panel of history.png is in J (a 2D run's in J per metre of
depth).

A figure whose inputs are missing is skipped with a message on stderr. The paths of the PNGs
written go to stdout. Exit status: 0 when at least one figure was written, 1 when none could be
made, 2 on bad arguments.

Only the snapshot files named in fields/particles.xdmf are read (the directory may hold stale
snapshots of earlier runs). Regions are those the engine used (run.json regions; its defaults
are the study's I 100-900 um, II 100-600 um, III 100-300 um of the target, scaled by the
target's height / 1000 um for a shorter target), else the case's, else the study's; y measured
from the impact plane y = 0 in the deformed configuration (as the engine's series.csv).
Map colour ranges: --p-range / --t-range, else the case's [figures] p_range / t_range, else the
1st-99th percentile of the shown snapshot (--ranges study: the study's 0-50 GPa and 300-500 K). Maps are drawn as images of pixels
one point spacing wide (the mean of the points in each), which shows no moire.
"""
import argparse
import csv
import json
import math
import os
import sys
import traceback
import xml.etree.ElementTree as ET

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

try:
    import h5py
except ImportError:  # snapshot figures are skipped; series figures still work
    h5py = None

DEFAULT_REGIONS = [("I", 100.0, 900.0), ("II", 100.0, 600.0), ("III", 100.0, 300.0)]
FIGURES = ("map", "series", "velocity", "dissipation", "distributions", "history", "freesurface", "compare")

# The four quantities the study follows: (series column stem, snapshot dataset, scale to the
# plotted unit, axis label).
QUANTITIES = [
    ("P", "pressure", 1e-9, "P [GPa]"),
    ("T", "temperature", 1.0, "T [K]"),
    ("rho", "density", 1e-3, r"$\rho$ [g/cm$^3$]"),
    ("Uy", "velocity_y", 1.0, r"$U_y$ [m/s]"),
]
SERIES_UNITS = {"P": "GPa", "T": "K", "rho": "gcc", "Uy": "ms"}


class Skip(Exception):
    """A figure cannot be made from what the directory holds."""


def note(msg):
    print(msg, file=sys.stderr)


# ----------------------------------------------------------------------------------------------
# Reading an output directory


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as e:
        note(f"warning: cannot read {path}: {e}")
        return None


def to_float(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return math.nan


def read_csv(path):
    """Columns of a CSV file as {name: list of strings}, or None when the file is absent/empty."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except FileNotFoundError:
        return None
    except (OSError, csv.Error, UnicodeDecodeError) as e:
        note(f"warning: cannot read {path}: {e}")
        return None
    if not rows:
        return None
    cols = {k.strip(): [] for k in rows[0].keys() if k is not None}
    for r in rows:
        for k, v in r.items():
            if k is not None and k.strip() in cols:
                cols[k.strip()].append(v.strip() if isinstance(v, str) else v)
    return cols


def numeric(cols, *names):
    """Float arrays of the named columns; Skip when one is missing."""
    out = []
    for n in names:
        if cols is None or n not in cols:
            raise Skip(f"no column {n}")
        out.append(np.array([to_float(v) for v in cols[n]]))
    return out


def read_series(outdir):
    """series.csv as {region: {column: array sorted by time}} in order of first appearance."""
    cols = read_csv(os.path.join(outdir, "series.csv"))
    if cols is None or "time_ns" not in cols or "region" not in cols:
        return None
    regions = list(dict.fromkeys(cols["region"]))
    t = np.array([to_float(v) for v in cols["time_ns"]])
    reg = np.array(cols["region"])
    out = {}
    for r in regions:
        sel = reg == r
        order = np.argsort(t[sel], kind="stable")
        out[r] = {k: np.array([to_float(v) for v in np.array(vals)[sel]])[order]
                  for k, vals in cols.items() if k != "region"}
    return out


class Run:
    """One output directory: run.json, the CSV series and the snapshots named in the XDMF file."""

    def __init__(self, outdir):
        self.dir = outdir
        self.name = os.path.basename(os.path.normpath(outdir))
        self.info = read_json(os.path.join(outdir, "run.json")) or {}
        self.case = self.info.get("case_resolved") or {}
        self._series = False
        self._snaps = None

    # --- metadata ---
    @property
    def case_name(self):
        return str(self.info.get("case") or self.name)

    def bodies(self):
        b = self.info.get("bodies")
        return b if isinstance(b, list) else []

    def target_index(self):
        for i, b in enumerate(self.bodies()):
            if isinstance(b, dict) and b.get("name") == "target":
                return i
        for i, b in enumerate(self.case.get("bodies") or []):
            if isinstance(b, dict) and b.get("name") == "target":
                return i
        return 0

    def target(self):
        b = self.bodies()
        i = self.target_index()
        return b[i] if i < len(b) and isinstance(b[i], dict) else {}

    def label(self):
        t = self.target()
        parts = [self.case_name]
        por = t.get("porosity")
        if por is None:  # the requested porosity, when run.json has no measured one
            cb = self.case.get("bodies") or []
            i = self.target_index()
            if i < len(cb) and isinstance(cb[i], dict) and isinstance(cb[i].get("voids"), dict):
                por = cb[i]["voids"].get("porosity")
        if isinstance(por, (int, float)):
            parts.append(rf"$\Delta$ = {por:.2f}")
        v = t.get("velocity_m_s")
        if isinstance(v, (list, tuple)) and v:
            parts.append(f"v = {math.hypot(*[to_float(x) for x in v[:3]]):.0f} m/s")
        return ", ".join(parts)

    def case_range(self, key):
        """Colour range of map `key` ("P" [GPa] or "T" [K]) set by the case's [figures], or None."""
        fig = self.case.get("figures")
        if not isinstance(fig, dict):
            return None
        names = {"P": (("p_range_GPa", 1.0), ("p_range_MPa", 1e-3), ("p_range_Pa", 1e-9)),
                 "T": (("t_range_K", 1.0),)}[key]
        for name, scale in names:
            try:
                lo, hi = (float(x) * scale for x in fig[name])
                return (lo, hi) if lo < hi else None
            except (KeyError, TypeError, ValueError):
                continue
        return None

    def regions(self):
        """[(name, y0_um, y1_um, x_range_um or None)]: the regions the engine used (run.json
        "regions"), else the case's, else the study's."""
        regs = self.info.get("regions") if isinstance(self.info.get("regions"), list) else None
        regs = regs or self.case.get("regions")
        out = []
        if isinstance(regs, list):
            for r in regs:
                try:
                    y0, y1 = (float(x) for x in r["y_range_um"])
                    xr = r.get("x_range_um")
                    xr = (float(xr[0]), float(xr[1])) if xr else None
                    out.append((str(r["name"]), y0, y1, xr))
                except (KeyError, TypeError, ValueError):
                    note(f"warning: {self.dir}: ignoring malformed region {r!r}")
        if not out:
            out = [(n, a, b, None) for n, a, b in DEFAULT_REGIONS]
        return out

    def region(self, name):
        for r in self.regions():
            if r[0] == name:
                return r
        raise Skip(f"no region {name!r} (regions: {', '.join(r[0] for r in self.regions())})")

    def spacing_um(self):
        """Point spacing of the target [um] from the case, or None."""
        try:
            h = float(self.case["grid"]["cell_size_um"])
            b = (self.case.get("bodies") or [])[self.target_index()]
            return h / float(b.get("points_per_cell", 2))
        except (KeyError, TypeError, ValueError, IndexError):
            return None

    # --- series ---
    def series(self):
        if self._series is False:
            self._series = read_series(self.dir)
        return self._series

    def csv(self, name):
        return read_csv(os.path.join(self.dir, name))

    # --- snapshots ---
    def snapshots(self):
        """[(time_ns, path)] of the snapshots listed in fields/particles.xdmf, sorted by time."""
        if self._snaps is not None:
            return self._snaps
        fields = os.path.join(self.dir, "fields")
        xdmf = os.path.join(fields, "particles.xdmf")
        snaps = {}
        if h5py is None:
            note("warning: h5py is not available; snapshot figures are skipped")
        elif not os.path.isfile(xdmf):
            note(f"note: {self.dir}: no fields/particles.xdmf, so no snapshots")
        else:
            try:
                root = ET.parse(xdmf).getroot()
            except (ET.ParseError, OSError) as e:
                note(f"warning: cannot parse {xdmf}: {e}")
                root = None
            if root is not None:
                for g in root.iter("Grid"):
                    if g.get("GridType", "Uniform") != "Uniform":
                        continue
                    tnode = g.find("Time")
                    t = to_float(tnode.get("Value")) * 1e9 if tnode is not None else math.nan
                    fname = None
                    for item in g.iter("DataItem"):
                        text = (item.text or "").strip()
                        if ":" in text:
                            fname = text.split(":", 1)[0].strip()
                            break
                    if not fname:
                        continue
                    path = fname if os.path.isabs(fname) else os.path.join(fields, fname)
                    if not os.path.isfile(path):
                        note(f"warning: {xdmf} names {fname}, which is missing")
                        continue
                    snaps[path] = t
        self._snaps = sorted(((t, p) for p, t in snaps.items()), key=lambda x: (x[0], x[1]))
        return self._snaps

    def nearest_snapshot(self, time_ns):
        snaps = self.snapshots()
        if not snaps:
            raise Skip("no snapshots listed in fields/particles.xdmf")
        return min(snaps, key=lambda s: abs(s[0] - time_ns) if not math.isnan(s[0]) else math.inf)

    def load(self, path, names, target_only=True):
        """Datasets of one snapshot: {'time_ns', 'x_um', 'y_um', 'z_um' (3D only), names...}, target
        body only; 'velocity_x', 'velocity_y', 'velocity_z' name the velocity's components."""
        try:
            with h5py.File(path, "r") as f:
                if "particles" not in f:
                    raise Skip(f"{os.path.basename(path)} has no /particles group")
                p = f["particles"]
                t = float(p.attrs.get("time", math.nan)) * 1e9
                if "position" not in p:
                    raise Skip(f"{os.path.basename(path)} has no position")
                pos = p["position"][...]
                sel = np.ones(len(pos), bool)
                if target_only and "body" in p:
                    sel = np.rint(p["body"][...]).astype(int) == self.target_index()
                out = {"time_ns": t, "x_um": pos[sel, 0] * 1e6, "y_um": pos[sel, 1] * 1e6,
                       "file": os.path.basename(path)}
                if pos.shape[1] > 2:
                    out["z_um"] = pos[sel, 2] * 1e6
                for n in names:
                    if n in ("velocity_x", "velocity_y", "velocity_z"):
                        if "velocity" in p and p["velocity"].shape[1] > "xyz".index(n[-1]):
                            out[n] = p["velocity"][:, "xyz".index(n[-1])][sel]
                    elif n in p:
                        out[n] = p[n][...][sel]
        except (OSError, KeyError) as e:
            raise Skip(f"cannot read {path}: {e}")
        if not np.any(sel):
            raise Skip(f"{os.path.basename(path)} holds no particle of body {self.target_index()}")
        return out


# ----------------------------------------------------------------------------------------------
# Helpers for the figures


def figdir(outdir):
    d = os.path.join(outdir, "figures")
    os.makedirs(d, exist_ok=True)
    return d


def save(fig, path, dpi):
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    print(path)
    return path


def series_col(sr, region, col):
    d = sr.get(region) or {}
    v = d.get(col)
    if v is None or not np.any(np.isfinite(v)):
        return None
    return v


def no_data(ax, text):
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="0.4")


def moments(v):
    v = np.asarray(v, float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan, math.nan, math.nan
    m = v.mean()
    s = v.std()
    if s <= 0:
        return m, s, math.nan, math.nan
    z = (v - m) / s
    return m, s, float(np.mean(z ** 3)), float(np.mean(z ** 4) - 3.0)


def figure_size(aspect, max_w=6.5, max_h=8.5, extra_w=2.0, extra_h=1.3):
    """Figure size [in] for an equal-aspect plot of height/width `aspect` with a colour bar."""
    if aspect > max_h / max_w:
        h, w = max_h, max(max_h / aspect, 1.5)
    else:
        w, h = max_w, max(max_w * aspect, 1.0)
    return w + extra_w, max(h + extra_h, 3.0)


def fit_markers(fig, ax, coll, spacing_um, n_points):
    """Resize the square markers of `coll` to one point spacing (a little more, so that a
    undeformed lattice shows no seams), measured on the laid-out axes."""
    fig.canvas.draw()  # runs the constrained layout: the axes have their final size now
    width_pt = ax.get_window_extent().width / fig.dpi * 72.0
    x0, x1 = ax.get_xlim()
    span = max(abs(x1 - x0), 1e-12)
    if not spacing_um:
        y0, y1 = ax.get_ylim()
        spacing_um = math.sqrt(span * abs(y1 - y0) / max(n_points, 1))
    d = 1.15 * spacing_um * width_pt / span
    coll.set_sizes([max(d * d, 0.02)])


STUDY_RANGES = {"P": (0.0, 50.0), "T": (300.0, 500.0)}  # the reference study's map colour ranges


def data_range(values):
    """Colour range from the data: the 1st to 99th percentile (a few hot spots or jets would
    otherwise take the whole scale); a constant field gets a small range about its value."""
    v = values[np.isfinite(values)]
    if v.size == 0:
        return (0.0, 1.0)
    lo, hi = (float(q) for q in np.percentile(v, [1.0, 99.0]))
    if not hi > lo:
        pad = max(abs(lo) * 1e-3, 1e-9)
        lo, hi = lo - pad, hi + pad
    return (lo, hi)


def pixel_map(ax, x, y, values, spacing_um, cmap, rng):
    """Draws a field of the points as an image of pixels one point spacing wide: each pixel the
    mean of the points in it, empty pixels (voids, outside) blank. Markers at one spacing drew
    moire streaks where compacted material packs the points closer than their lattice."""
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    if not spacing_um:
        spacing_um = math.sqrt(abs(x1 - x0) * abs(y1 - y0) / max(len(x), 1))
    nx = max(1, min(4000, int(round(abs(x1 - x0) / spacing_um))))
    ny = max(1, min(4000, int(round(abs(y1 - y0) / spacing_um))))
    edges = (np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1))
    ok = np.isfinite(values)
    count, _, _ = np.histogram2d(x[ok], y[ok], bins=edges)
    total, _, _ = np.histogram2d(x[ok], y[ok], bins=edges, weights=values[ok])
    # A deformed lattice leaves some pixels of the material without a point and puts two in
    # others: an empty pixel with at least 5 of its 8 neighbours filled is material, and gets
    # their mean (twice). Voids and free space, many pixels wide, stay blank.
    def neighbours(a):  # the 8 neighbours of every pixel, as arrays of a's shape (0 outside)
        p = np.pad(a, 1)
        return [p[1 + i:p.shape[0] - 1 + i, 1 + j:p.shape[1] - 1 + j]
                for i in (-1, 0, 1) for j in (-1, 0, 1) if i or j]

    for _ in range(2):
        filled = sum((c > 0).astype(int) for c in neighbours(count))
        nsum, ncnt = sum(neighbours(total)), sum(neighbours(count))
        hole = (count == 0) & (filled >= 5)
        total = np.where(hole, nsum / np.maximum(ncnt, 1), total)
        count = np.where(hole, 1.0, count)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    return ax.imshow(np.ma.masked_invalid(mean.T), origin="lower", extent=(x0, x1, y0, y1), cmap=cmap,
                     vmin=rng[0], vmax=rng[1], interpolation="nearest", aspect="equal")


def plane_slice(run, d, a):
    """The points of snapshot `d` (Run.load) that a map shows: all of a 2D snapshot; of a 3D one,
    those in a slab one point spacing thick across --slice-axis about --slice-at-um (default the
    middle of the grid's range on that axis). While a tenth or more of the points keep the layers
    of their lattice (ahead of the shock), the slab is centred on the layer nearest there: a slab
    edge on a layer would take two layers or none. Returns (points, the horizontal axis of the map, "x" or "z",
    the slab for titles "slice z = Z ± H µm", "" in 2D)."""
    if "z_um" not in d:
        return d, "x", ""
    axis = a.slice_axis
    c = d[f"{axis}_um"]
    h = run.spacing_um() or (np.ptp(d["x_um"]) * np.ptp(d["y_um"]) * np.ptp(d["z_um"]) / c.size) ** (1 / 3)
    at = a.slice_at_um
    if at is None:
        try:
            at = 0.5 * sum(float(v) for v in run.case["grid"][f"{axis}_range_um"])
        except (KeyError, TypeError, ValueError):
            at = 0.5 * (c.min() + c.max())
    phase = np.mean(np.exp(2j * np.pi * c / h))
    if abs(phase) > 0.1:  # the layers lie at offset + k h (a random cloud gives |phase| ~ n^-1/2)
        offset = np.angle(phase) / (2 * np.pi) * h
        at = offset + round((at - offset) / h) * h
    sel = (c >= at - 0.5 * h) & (c < at + 0.5 * h)
    text = f"slice {axis} = {at:.1f} ± {0.5 * h:.3g} µm"
    if not np.any(sel):
        raise Skip(f"no target particle in the {text}")
    return ({k: v[sel] if isinstance(v, np.ndarray) else v for k, v in d.items()},
            "z" if axis == "x" else "x", text)


# ----------------------------------------------------------------------------------------------
# Figures of one directory


def fig_maps(run, a):
    snap_t, path = run.nearest_snapshot(a.time_ns)
    d, lat, cut = plane_slice(run, run.load(path, ["pressure", "temperature"]), a)
    x, y = d[f"{lat}_um"], d["y_um"]
    cut = f", {cut}" if cut else ""
    pad = 0.02 * max(np.ptp(x), np.ptp(y), 1.0)
    xlim = (x.min() - pad, x.max() + pad)
    ylim = (min(0.0, y.min()) - pad, y.max() + pad)
    aspect = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    written = []
    for key, field, scale, unit, rng, title in (
        ("P", "pressure", 1e-9, "GPa", a.p_range, "Pressure"),
        ("T", "temperature", 1.0, "K", a.t_range, "Temperature"),
    ):
        name = f"map_{key}.png"
        if field not in d:
            note(f"skip {name} ({run.dir}): no '{field}' field in {d['file']} "
                 "(the scene does not track energy?)")
            continue
        fig, ax = plt.subplots(figsize=figure_size(aspect), constrained_layout=True)
        ax.set_aspect("equal")
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_facecolor("white")
        values = d[field] * scale
        rng = rng or run.case_range(key) or (STUDY_RANGES[key] if a.ranges == "study" else data_range(values))
        im = pixel_map(ax, x, y, values, run.spacing_um(), a.cmap, rng)
        cb = fig.colorbar(im, ax=ax, shrink=0.9, extend="both")
        cb.set_label(f"{key} [{unit}]")
        ax.set_xlabel(f"{lat} [µm]")
        ax.set_ylabel("y [µm] (impact plane at y = 0)")
        how = "study's range" if a.ranges == "study" and rng == STUDY_RANGES[key] else "colour range"
        ax.set_title(f"{title} of the target at t = {d['time_ns']:.0f} ns{cut} ({how} {rng[0]:.3g}-{rng[1]:.3g} {unit})"
                     f"\n{run.label()}", fontsize=10)
        written.append(save(fig, os.path.join(figdir(run.dir), name), a.dpi))
        if abs(snap_t - a.time_ns) > 0.05 * max(a.time_ns, 1.0):
            note(f"note: {name} ({run.dir}): nearest snapshot to {a.time_ns:g} ns is at {snap_t:.1f} ns")
    if not written:
        raise Skip("no pressure or temperature field")
    return written


def series_figure(run, stat, a):
    sr = run.series()
    if not sr:
        raise Skip("no series.csv (or it has no rows)")
    name = "series_means.png" if stat == "mean" else "series_std.png"
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True, constrained_layout=True)
    any_line = False
    for ax, (key, _, _, label) in zip(axes.flat, QUANTITIES):
        col = f"{key}_{stat}_{SERIES_UNITS[key]}"
        drawn = False
        for reg in sr:
            t = sr[reg].get("time_ns")
            v = series_col(sr, reg, col)
            if v is None or t is None:
                continue
            ax.plot(t, v, label=f"region {reg}", lw=1.4)
            drawn = True
        if not drawn:
            no_data(ax, f"no {col} in series.csv")
        any_line |= drawn
        what = "mean" if stat == "mean" else "standard deviation"
        ax.set_ylabel(("" if stat == "mean" else r"$\sigma$ of ") + label)
        ax.set_title(f"{label.split(' [')[0]} {what}", fontsize=10)
        ax.grid(alpha=0.3)
        if drawn:
            ax.legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t [ns]")
    if not any_line:
        plt.close(fig)
        raise Skip(f"series.csv has none of the {stat} columns")
    fig.suptitle(f"Regional {'means' if stat == 'mean' else 'standard deviations'} in the target: "
                 f"{run.label()}", fontsize=11)
    return [save(fig, os.path.join(figdir(run.dir), name), a.dpi)]


def fig_series(run, a):
    out = []
    for stat in ("mean", "std"):
        try:
            out += series_figure(run, stat, a)
        except Skip as e:
            note(f"skip series_{'means' if stat == 'mean' else 'std'}.png ({run.dir}): {e}")
    return out  # the reasons of any skip are printed above


def front_at(run, time_ns):
    cols = run.csv("front.csv")
    if cols is None:
        return None
    try:
        t, fy = numeric(cols, "time_ns", "front_y_um")
    except Skip:
        return None
    ok = np.isfinite(t) & np.isfinite(fy)
    if not np.any(ok):
        return None
    t, fy = t[ok], fy[ok]
    order = np.argsort(t)
    return float(np.interp(time_ns, t[order], fy[order]))


def fig_velocity(run, a):
    snap_t, path = run.nearest_snapshot(a.time_ns)
    d, lat, cut = plane_slice(run, run.load(path, ["velocity_x", "velocity_y", "velocity_z"]), a)
    if "velocity_y" not in d or f"velocity_{lat}" not in d:
        raise Skip(f"no velocity field in {d['file']}")
    x, y, vx, vy = d[f"{lat}_um"], d["y_um"], d[f"velocity_{lat}"], d["velocity_y"]
    cut = f", {cut}" if cut else ""
    t = d["time_ns"]
    how = ""
    if a.vel_x:
        x0, x1 = a.vel_x
    else:
        xc = 0.5 * (x.min() + x.max())
        half = min(100.0, 0.5 * np.ptp(x))
        x0, x1 = xc - half, xc + half
    if a.vel_y:
        y0, y1 = a.vel_y
    else:
        front = front_at(run, t)
        if front is None or not math.isfinite(front) or front <= 0:
            front = 0.5 * (y.min() + y.max())
            how = "\n(front.csv missing or empty: window at mid-height)"
        else:
            how = f"\n(compression front at y = {front:.0f} µm)"
        y1 = min(front, y.max())
        y0 = max(y1 - 200.0, min(0.0, y.min()))
        y1 = max(y1, y0 + min(200.0, np.ptp(y)))
    inside = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
    if not np.any(inside):
        raise Skip(f"no target particle in the window {lat} {x0:.0f}-{x1:.0f}, y {y0:.0f}-{y1:.0f} um{cut}")
    xs, ys, us, ws = x[inside], y[inside], vx[inside], vy[inside]
    if a.vel_frame == "window":
        mu, mw = us.mean(), ws.mean()
        frame = f"frame moving with the window's mean velocity ({mu:.0f}, {mw:.0f}) m/s"
    else:
        mu = mw = 0.0
        frame = "lab frame"
    us, ws = us - mu, ws - mw
    if a.vel_bins > 0:  # average over a grid of bins: one arrow per occupied bin
        nb = a.vel_bins
        ix = np.clip(((xs - x0) / (x1 - x0) * nb).astype(int), 0, nb - 1)
        iy = np.clip(((ys - y0) / (y1 - y0) * nb).astype(int), 0, nb - 1)
        k = iy * nb + ix
        cnt = np.bincount(k, minlength=nb * nb)
        occ = cnt > 0
        qx = (np.bincount(k, xs, nb * nb)[occ]) / cnt[occ]
        qy = (np.bincount(k, ys, nb * nb)[occ]) / cnt[occ]
        qu = (np.bincount(k, us, nb * nb)[occ]) / cnt[occ]
        qw = (np.bincount(k, ws, nb * nb)[occ]) / cnt[occ]
        sub = f"mean over {nb} x {nb} bins"
    else:  # every k-th particle
        stride = max(1, int(math.ceil(len(xs) / max(a.vel_max_arrows, 1))))
        qx, qy, qu, qw = xs[::stride], ys[::stride], us[::stride], ws[::stride]
        sub = f"every {stride}th particle" if stride > 1 else "every particle"
    speed = np.hypot(qu, qw)
    aspect = (y1 - y0) / max(x1 - x0, 1e-9)
    fig, ax = plt.subplots(figsize=figure_size(aspect, extra_h=1.6), constrained_layout=True)
    ax.set_aspect("equal")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    bg = ax.scatter(xs, ys, s=1, marker="s", linewidths=0, color="0.85", rasterized=True, zorder=0)
    q = ax.quiver(qx, qy, qu, qw, speed, cmap=a.cmap, angles="xy", pivot="middle", zorder=2)
    top = float(np.percentile(speed, 99)) if speed.size else 0.0
    if top > 0:
        q.set_clim(0.0, top)  # a few jets would otherwise take the whole colour range
    ref = float(np.percentile(speed, 90)) if speed.size else 0.0
    if ref > 0:
        mag = 10 ** math.floor(math.log10(ref))
        ref = round(ref / mag) * mag
        ax.quiverkey(q, 0.88, 1.02, ref, f"{ref:g} m/s", labelpos="W", coordinates="axes")
    cb = fig.colorbar(q, ax=ax, shrink=0.9, extend="max")
    cb.set_label("|u - <u>| [m/s]" if a.vel_frame == "window" else "|u| [m/s]")
    ax.set_xlabel(f"{lat} [µm]")
    ax.set_ylabel("y [µm]")
    ax.set_title(f"Velocity field at t = {t:.0f} ns{cut}, window {lat} {x0:.0f}-{x1:.0f} µm, y {y0:.0f}-{y1:.0f} µm"
                 f"{how}\n{frame}; {sub}\n{run.label()}", fontsize=9)
    fit_markers(fig, ax, bg, run.spacing_um(), len(xs))
    return [save(fig, os.path.join(figdir(run.dir), "velocity_field.png"), a.dpi)]


def fig_dissipation(run, a):
    sr = run.series()
    if not sr:
        raise Skip("no series.csv (or it has no rows)")
    cols = [("R2_mean_per_us2", r"$\langle R^2\rangle$ (vorticity)"),
            ("D2_mean_per_us2", r"$\langle D^2\rangle$ (divergence)"),
            ("S2_mean_per_us2", r"$\langle S^2\rangle$ (strain rate)")]
    regs = [r for r in sr if any(series_col(sr, r, c) is not None for c, _ in cols)]
    if not regs:
        raise Skip("series.csv has no R2/D2/S2 columns")
    n = len(regs)
    ncol = min(n, 3)
    nrow = int(math.ceil(n / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol + 0.5, 3.6 * nrow + 0.6), sharex=True,
                             sharey=True, squeeze=False, constrained_layout=True)
    vals = [series_col(sr, reg, c) for reg in regs for c, _ in cols]
    vals = np.concatenate([v[np.isfinite(v)] for v in vals if v is not None])
    # mean squares are >= 0: a log axis unless told otherwise (zeros, e.g. before the shock
    # arrives, are left out of it); linear if some value is negative
    positive = not a.dissipation_linear and vals.size > 0 and vals.min() >= 0 and vals.max() > 0
    if positive:
        floor = max(vals[vals > 0].min(), vals.max() * 1e-6)
    for ax, reg in zip(axes.flat, regs):
        t = sr[reg]["time_ns"]
        for (c, lab), style in zip(cols, ("-", "--", ":")):
            v = series_col(sr, reg, c)
            if v is not None:
                ax.plot(t, v, style, lw=1.5, label=lab)
        if positive:
            ax.set_yscale("log", nonpositive="mask")
            ax.set_ylim(floor * 0.5, vals.max() * 2.0)
        ax.set_title(f"region {reg}", fontsize=10)
        ax.grid(alpha=0.3, which="both" if positive else "major")
        ax.legend(fontsize=8)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel(r"mean square [$\mu$s$^{-2}$]")
    for ax in axes[-1]:
        ax.set_xlabel("t [ns]")
    fig.suptitle(f"Turbulent and volume dissipation measures: {run.label()}", fontsize=11)
    return [save(fig, os.path.join(figdir(run.dir), "dissipation.png"), a.dpi)]


def dist_times(run, a):
    snaps = run.snapshots()
    if not snaps:
        raise Skip("no snapshots listed in fields/particles.xdmf")
    if a.dist_times_ns:
        chosen = []
        for t in a.dist_times_ns:
            s = run.nearest_snapshot(t)
            if s not in chosen:
                chosen.append(s)
        return chosen[:3]
    later = [s for s in snaps if s[0] > 0] or snaps
    if len(later) <= 3:
        return later
    n = len(later)  # a third, two thirds and all of the run
    idx = sorted(set(max(0, int(round(n * k / 3.0)) - 1) for k in (1, 2, 3)))
    return [later[i] for i in idx]


def fig_distributions(run, a):
    if a.region_y:
        (y0, y1), xr = a.region_y, None
        name = where = f"band y = {y0:g}-{y1:g} µm"
    else:
        name, y0, y1, xr = run.region(a.region)
        where = f"region {name} (y = {y0:g}-{y1:g} µm)"
    data = []
    for t, path in dist_times(run, a):
        d = run.load(path, ["pressure", "temperature", "density", "velocity_y"])
        sel = (d["y_um"] >= y0) & (d["y_um"] <= y1)
        if xr:
            sel &= (d["x_um"] >= xr[0]) & (d["x_um"] <= xr[1])
        if np.count_nonzero(sel) < 2:
            note(f"note: distributions ({run.dir}): {where} holds {np.count_nonzero(sel)} "
                 f"particles at {d['time_ns']:.0f} ns; that time is left out")
            continue
        data.append((d["time_ns"], {k: v[sel] for k, v in d.items() if isinstance(v, np.ndarray)}))
    if not data:
        raise Skip(f"{where} is empty in the chosen snapshots")
    if "z_um" in data[0][1]:  # 3D: all the points of the region, not a slice
        where += ", all z"
    order = [2, 0, 1, 3]  # rho, P, T, U_y as in the study
    nrow = len(data)
    fig, axes = plt.subplots(nrow, 4, figsize=(16, 3.3 * nrow + 1.0), squeeze=False,
                             constrained_layout=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    q = a.dist_quantile
    for row, ((t, d), col) in enumerate(zip(data, colours)):
        for ax, qi in zip(axes[row], order):
            key, field, scale, label = QUANTITIES[qi]
            ax.set_title(f"{label.split(' [')[0]} at t = {t:.0f} ns", fontsize=10)
            ax.set_xlabel(label)
            if ax is axes[row][0]:
                ax.set_ylabel("probability density")
            if field not in d:
                no_data(ax, f"no {field} field")
                continue
            v = d[field] * scale
            v = v[np.isfinite(v)]
            m, sd, sk, ku = moments(v)
            if v.size < 2 or not sd > 0:
                ax.axvline(m, color=col, lw=1.5)
                no_data(ax, f"all {v.size} particles at {m:.4g}")
                continue
            # the range holds the central (100 - 2q) % of the points, so that a few wild particles
            # do not squeeze the distribution into one bin; the rest are counted, not drawn
            lo, hi = np.percentile(v, [q, 100.0 - q]) if q > 0 else (v.min(), v.max())
            if not hi > lo:
                lo, hi = m - 3 * sd, m + 3 * sd
            pad = 0.05 * (hi - lo)
            lo, hi = lo - pad, hi + pad
            outside = int(np.count_nonzero((v < lo) | (v > hi)))
            inside = v[(v >= lo) & (v <= hi)]
            # densities are normalised by all points, so the area drawn is the fraction inside
            w = np.full(inside.size, 1.0 / (v.size * (hi - lo) / a.dist_bins))
            dens, _, _ = ax.hist(inside, bins=a.dist_bins, range=(lo, hi), weights=w, histtype="stepfilled",
                                 color=col, alpha=0.35, ec=col, lw=1.2, label=f"N = {v.size}")
            g = np.linspace(lo, hi, 400)
            gauss = np.exp(-0.5 * ((g - m) / sd) ** 2) / (sd * math.sqrt(2 * math.pi))
            ax.plot(g, gauss, "k--", lw=1.0, label="Gaussian")
            txt = f"mean {m:.4g}\nstd {sd:.3g}\nskew {sk:+.2f}\nex. kurt {ku:+.2f}"
            if outside:
                txt += f"\n{outside} outside the axis"
            ax.text(0.02, 0.97, txt, transform=ax.transAxes, va="top", ha="left", fontsize=7.5,
                    bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.85))
            top = max(float(np.max(dens)) if dens.size else 0.0, float(gauss.max()))
            if a.dist_log:
                ax.set_yscale("log")
                ax.set_ylim(top * 1e-4, top * 30)  # the upper part holds the annotations
            else:
                hpeak = float(np.max(dens)) if dens.size else 0.0
                if not a.dist_no_clip and hpeak > 5.0 * gauss.max() and np.sort(dens)[-2] < 0.5 * hpeak:
                    # one spike (e.g. the unshocked particles of a band the front has not crossed
                    # yet) would flatten everything else: clip it and say so
                    top = max(np.sort(dens)[-2], float(gauss.max())) * 1.5
                    ax.text(0.98, 0.6, "tall bin clipped\n(--dist-no-clip)", transform=ax.transAxes,
                            ha="right", va="top", fontsize=7, color="0.35")
                ax.set_ylim(0, top * 1.45)  # the upper part holds the annotations
            ax.set_xlim(lo, hi)
            ax.legend(fontsize=7.5, loc="upper right")
    fig.suptitle(f"Distributions of the target particles in {where}, against Gaussians of the same mean "
                 f"and deviation: {run.label()}", fontsize=11)
    return [save(fig, os.path.join(figdir(run.dir), "distributions.png"), a.dpi)]


def fig_history(run, a):
    front, wall, energy = run.csv("front.csv"), run.csv("wall.csv"), run.csv("energy.csv")
    if front is None and wall is None and energy is None:
        raise Skip("no front.csv, wall.csv or energy.csv")
    fig, axes = plt.subplots(3, 1, figsize=(8, 9), sharex=True, constrained_layout=True)
    ax = axes[0]
    try:
        t, fy = numeric(front, "time_ns", "front_y_um")
        ax.plot(t, fy, lw=1.5)
    except Skip:
        no_data(ax, "front.csv missing or empty")
        note(f"note: history.png ({run.dir}): front.csv missing or empty, panel left empty")
    ax.set_ylabel("front y [µm]")
    ax.set_title("Leading edge of the compression wave in the target", fontsize=10)
    ax = axes[1]
    try:
        t, sw = numeric(wall, "time_ns", "wall_stress_GPa")
        ax.plot(t, sw, lw=1.0)
    except Skip:
        no_data(ax, "no wall.csv (no rigid wall in this scene)")
        note(f"note: history.png ({run.dir}): wall.csv missing or empty, panel left empty")
    ax.set_ylabel("wall stress [GPa]")
    ax.set_title("Normal stress on the rigid wall (compression positive)", fontsize=10)
    ax = axes[2]
    per_m = not (energy and "total_J" in energy)  # 2D: per unit depth [J/m]; 3D: the total [J]
    sfx, unit, title = ("_J_per_m", "J/m", "Energy per unit depth") if per_m else ("_J", "J", "Energy")
    try:
        t, ek, ei, et = numeric(energy, "time_ns", *(f"{k}{sfx}" for k in ("kinetic", "internal", "total")))
        ax.plot(t, ek, label="kinetic")
        ax.plot(t, ei, label="internal")
        ax.plot(t, et, "k", lw=1.5, label="total")
        if et.size and np.isfinite(et[0]) and et[0] != 0:
            drift = (et[np.isfinite(et)][-1] - et[0]) / abs(et[0])
            title += f" (drift of the total: {100 * drift:+.2f} %)"
        ax.legend(fontsize=8)
    except Skip:
        no_data(ax, "energy.csv missing or empty")
        note(f"note: history.png ({run.dir}): energy.csv missing or empty, panel left empty")
    ax.set_ylabel(f"energy [{unit}]")
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("t [ns]")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(run.label(), fontsize=11)
    return [save(fig, os.path.join(figdir(run.dir), "history.png"), a.dpi)]


def fig_free_surface(run, a):
    surface, gauges = run.csv("freesurface.csv"), run.csv("gauges.csv")
    if surface is None:
        raise Skip("no freesurface.csv (no body with record_free_surface)")
    panels = 2 if gauges is not None else 1
    fig, axes = plt.subplots(panels, 1, figsize=(8, 3.5 * panels), sharex=True, constrained_layout=True,
                             squeeze=False)
    t, u = numeric(surface, "time_ns", "u_fs_m_s")
    bodies = np.array(surface["body"])
    ax = axes[0][0]
    for b in dict.fromkeys(bodies):
        ax.plot(t[bodies == b], u[bodies == b], lw=1.5, label=b)
    ax.legend(fontsize=8)
    ax.set_ylabel("free-surface velocity [m/s]")
    ax.set_title("Mean y-velocity of the top row of points (what a VISAR records)", fontsize=10)
    if gauges is not None:
        t, p = numeric(gauges, "time_ns", "P_GPa")
        names = np.array(gauges["gauge"])
        ax = axes[1][0]
        for g in dict.fromkeys(names):
            ax.plot(t[names == g], p[names == g], lw=1.0, label=g)
        if len(set(names)) <= 10:
            ax.legend(fontsize=8)
        ax.set_ylabel("P [GPa]")
        ax.set_title("Pressure at the gauges (compression positive)", fontsize=10)
    axes[-1][0].set_xlabel("t [ns]")
    for row in axes:
        row[0].grid(alpha=0.3)
    fig.suptitle(run.label(), fontsize=11)
    return [save(fig, os.path.join(figdir(run.dir), "freesurface.png"), a.dpi)]


# ----------------------------------------------------------------------------------------------
# Comparison of several directories


def fig_compare(runs, a, stat):
    fname = "compare_means.png" if stat == "mean" else "compare_std.png"
    have = [(r, r.series()) for r in runs]
    have = [(r, sr) for r, sr in have if sr and a.region in sr]
    for r in runs:
        if not any(r is h[0] for h in have):
            note(f"note: {fname}: {r.dir} has no series.csv rows for region {a.region}; left out")
    if not have:
        raise Skip(f"no directory has series.csv rows for region {a.region}")
    labels = [r.label() for r, _ in have]
    if len(set(labels)) < len(labels):  # e.g. a convergence study: same case, other resolution
        labels = [f"{lab} [{r.name}]" for lab, (r, _) in zip(labels, have)]
    fig, axes = plt.subplots(2, 2, figsize=(10.5, 7.5), sharex=True, constrained_layout=True)
    for ax, (key, _, _, label) in zip(axes.flat, QUANTITIES):
        col = f"{key}_{stat}_{SERIES_UNITS[key]}"
        drawn = False
        for (r, sr), lab in zip(have, labels):
            v = series_col(sr, a.region, col)
            if v is None:
                continue
            ax.plot(sr[a.region]["time_ns"], v, lw=1.4, label=lab)
            drawn = True
        if drawn:
            ax.legend(fontsize=7.5)
        else:
            no_data(ax, f"no {col}")
        ax.set_ylabel(("" if stat == "mean" else r"$\sigma$ of ") + label)
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("t [ns]")
    what = "Mean" if stat == "mean" else "Standard deviation"
    fig.suptitle(f"{what} over region {a.region} of the target", fontsize=11)
    out = a.out or figdir(runs[0].dir)
    os.makedirs(out, exist_ok=True)
    return [save(fig, os.path.join(out, fname), a.dpi)]


# ----------------------------------------------------------------------------------------------


def parse_args(argv):
    ap = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], epilog="Figures: " + ", ".join(FIGURES))
    ap.add_argument("outdirs", nargs="+", metavar="OUTDIR", help="shockmpm output directories")
    ap.add_argument("--time-ns", type=float, default=500.0,
                    help="time of the maps and the velocity field (nearest snapshot) [ns]; default 500")
    ap.add_argument("--region", default="I", help="region of the distributions and the comparison; default I")
    ap.add_argument("--p-range", type=float, nargs=2, metavar=("LO", "HI"),
                    help="colour range of map_P [GPa] (default: the case's [figures] p_range, else the "
                         "1st to 99th percentile of the shown snapshot, or the --ranges preset)")
    ap.add_argument("--t-range", type=float, nargs=2, metavar=("LO", "HI"),
                    help="colour range of map_T [K] (default: as --p-range)")
    ap.add_argument("--ranges", choices=("data", "study"), default="data",
                    help="colour ranges of the maps not set by --p-range / --t-range: 'data' (1st-99th "
                         "percentile of the shown snapshot, default) or 'study' (the reference study's "
                         "0-50 GPa and 300-500 K)")
    ap.add_argument("--cmap", default="turbo", help="matplotlib colour map of maps and vectors; default turbo")
    ap.add_argument("--vel-x", type=float, nargs=2, metavar=("X0", "X1"),
                    help="x window of the velocity field [um] (z with --slice-axis x; default: 200 um "
                         "about the centre)")
    ap.add_argument("--vel-y", type=float, nargs=2, metavar=("Y0", "Y1"),
                    help="y window of the velocity field [um] (default: 200 um behind the front)")
    ap.add_argument("--slice-axis", choices=("z", "x"), default="z",
                    help="3D runs: axis across the slice of the maps and the velocity field; default z "
                         "(the x-y plane)")
    ap.add_argument("--slice-at-um", type=float, metavar="AT",
                    help="3D runs: position of the slice on --slice-axis [um] (default: the middle of "
                         "the grid's range)")
    ap.add_argument("--vel-frame", choices=("window", "lab"), default="window",
                    help="frame of the velocity vectors: the window's mean velocity (default), or the lab")
    ap.add_argument("--vel-bins", type=int, default=30,
                    help="average the velocity over N x N bins of the window (0: raw particles); default 30")
    ap.add_argument("--vel-max-arrows", type=int, default=2000,
                    help="with --vel-bins 0, draw at most this many particles' arrows; default 2000")
    ap.add_argument("--dist-times-ns", type=float, nargs="+", metavar="T",
                    help="up to 3 times of the distributions [ns] (default: 3 snapshots spread over "
                         "the run)")
    ap.add_argument("--dist-bins", type=int, default=40, help="histogram bins; default 40")
    ap.add_argument("--dissipation-linear", action="store_true",
                    help="linear axis for <R^2>, <D^2>, <S^2> (default: logarithmic)")
    ap.add_argument("--dist-log", action="store_true", help="logarithmic probability axis")
    ap.add_argument("--dist-quantile", type=float, default=0.5, metavar="Q",
                    help="histogram range: the Q-th to (100-Q)-th percentile of the points [%%] "
                         "(0: all points); default 0.5")
    ap.add_argument("--region-y", type=float, nargs=2, metavar=("Y0", "Y1"),
                    help="band of the distributions [um] instead of --region's (the series.csv "
                         "figures keep the regions the engine used)")
    ap.add_argument("--dist-no-clip", action="store_true",
                    help="do not clip a lone histogram spike (a bin over 5 x the Gaussian's peak and twice "
                         "the next bin)")
    ap.add_argument("--only", default=",".join(FIGURES),
                    help="comma-separated subset of the figures to make; default all")
    ap.add_argument("--out", help="directory of the comparison figures (default: FIRST/figures)")
    ap.add_argument("--dpi", type=int, default=150, help="resolution of the PNGs; default 150")
    ap.add_argument("--traceback", action="store_true", help="print tracebacks of unexpected errors")
    a = ap.parse_args(argv)
    for flag, rng in (("--p-range", a.p_range), ("--t-range", a.t_range), ("--vel-x", a.vel_x),
                      ("--vel-y", a.vel_y), ("--region-y", a.region_y)):
        if rng and not rng[0] < rng[1]:
            ap.error(f"{flag}: LO must be below HI")
    if a.dist_times_ns and len(a.dist_times_ns) > 3:
        ap.error("--dist-times-ns: at most 3 times")
    if not 0.0 <= a.dist_quantile < 50.0:
        ap.error("--dist-quantile must be in [0, 50)")
    if a.vel_bins < 0 or a.vel_max_arrows < 1 or a.dist_bins < 1 or a.dpi < 10:
        ap.error("--vel-bins must be >= 0, --vel-max-arrows and --dist-bins >= 1, --dpi >= 10")
    a.only = {s.strip() for s in a.only.split(",") if s.strip()}
    bad = a.only - set(FIGURES)
    if bad:
        ap.error(f"--only: unknown figure(s) {', '.join(sorted(bad))}; choose from {', '.join(FIGURES)}")
    try:
        plt.get_cmap(a.cmap)
    except ValueError:
        ap.error(f"--cmap: unknown colour map {a.cmap!r}")
    return a


def attempt(label, where, func, *args, verbose=False):
    try:
        return func(*args) or []
    except Skip as e:
        note(f"skip {label} ({where}): {e}")
    except Exception as e:  # a damaged file must not stop the other figures
        note(f"skip {label} ({where}): unexpected {type(e).__name__}: {e}")
        if verbose:
            traceback.print_exc()
    plt.close("all")
    return []


def main(argv=None):
    a = parse_args(sys.argv[1:] if argv is None else argv)
    written = []
    runs = []
    for od in a.outdirs:
        if not os.path.isdir(od):
            note(f"skip {od}: not a directory")
            continue
        run = Run(od)
        runs.append(run)
        if not os.path.isfile(os.path.join(od, "run.json")):
            note(f"note: {od}: no run.json; labels and regions fall back to defaults")
        jobs = [("map", "map_P.png/map_T.png", fig_maps),
                ("series", "series_means.png/series_std.png", fig_series),
                ("velocity", "velocity_field.png", fig_velocity),
                ("dissipation", "dissipation.png", fig_dissipation),
                ("distributions", "distributions.png", fig_distributions),
                ("history", "history.png", fig_history),
                ("freesurface", "freesurface.png", fig_free_surface)]
        for key, label, func in jobs:
            if key in a.only:
                written += attempt(label, od, func, run, a, verbose=a.traceback)
    if "compare" in a.only and len(runs) > 1:
        for stat in ("mean", "std"):
            name = "compare_means.png" if stat == "mean" else "compare_std.png"
            written += attempt(name, ", ".join(r.dir for r in runs), fig_compare, runs, a, stat,
                               verbose=a.traceback)
    if not written:
        note("no figure could be made")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
