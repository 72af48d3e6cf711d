#!/usr/bin/python3
"""The engine against measured porous Hugoniots: one run per row of a data file, seed and cell size.

  /usr/bin/python3 bench/experiment_hugoniot.py [--data bench/data/porous_iron_hugoniot.csv]
      [--out DIR] [--dim 2|3] [--h 4,2] [--seeds 3 | --seeds 2,3] [--void-radius-um 10] [--material iron]
      [--rows 0,3] [--coarse-rows 8] [--set KEY=VALUE ...] [--driver build/shockmpm] [--threads 2]
      [--quick] [--check PCT] [--dry-run]
  /usr/bin/python3 bench/experiment_hugoniot.py --compose A/experiment.json B/experiment.json ... --out DIR

The data file: CSV, comment lines start with '#', columns
  m            distention rho_solid / rho00 [-] (porosity 1 - 1/m)
  rho00_g_cm3  initial bulk density [g/cm^3]
  up_km_s      particle velocity behind the shock [km/s]
  Us_km_s      shock velocity [km/s]
  P_GPa        pressure behind the shock [GPa] (rho00 Us up)
  rho_g_cm3    density behind the shock [g/cm^3] (rho00 Us / (Us - up))
  source       where the row comes from (text)
Any file with these columns runs; a missing column or a bad value is an error naming it.

Per row, seed (1..N for --seeds N, or the seeds a comma-separated --seeds lists) and cell size
(--h), a case is written to DIR/cases/ and run:
  sample   a strip periodic in x (width 6 void diameters, --width-diameters, rounded up to a
           multiple of every h; --dim 3: a column periodic in x and z, that width along both, with
           spherical voids instead of cylindrical ones) on a frictionless (slip) wall at y = 0,
           which holds the normal velocity at zero, pulling as well as pushing, as the symmetry
           plane does; free top; moving at -up onto the wall; porosity 1 - 1/m of the
           material's dense density (random overlapping voids of --void-radius-um,
           `voids.porosity`, seed = the seed number), points_per_cell 2, quadratic APIC, USL,
           cfl 0.3, artificial viscosity on (as cases/verify/porous_strip.toml). The material
           is `[materials.sample] base = "<--material>"` from the repository's
           cases/materials.toml; --set overrides reach it as materials.sample.KEY=VALUE. Where
           the library's dense density differs from the row's rho00 x m by more than 0.1 %, the
           outputs say so (the porosity follows m; the engine's rho00 is then rho0 / m, not the
           row's).
  frames   the wall is the symmetry plane of a symmetric impact: in the wall frame the unshocked
           sample moves at -up (towards the wall), the shocked material is at rest and the front
           runs up at U (front.csv). The experiment's frame is the unshocked sample's: add +up
           to every velocity. There the unshocked sample is at rest, the shocked material moves
           at +up (the way the shock runs) and the front at Us = U + up. The same holds for the
           fully compacted Hugoniot: Us_c = run.json compacted_hugoniot.front_speed_wall_frame_m_s
           + up (its Us_m_s, checked equal).
  size     per row, once (every seed and h of a row run the same strip and end time): `check` of
           the case at the coarsest h gives the compacted Hugoniot's wall-frame front speed U_c;
           the end time is the time a front at U_c takes to run FRONT = 15 void diameters
           (--front-diameters), t_end = FRONT / U_c; the strip is high enough that a front 1.5x
           as fast (the measured fronts of bench/data/porous_iron_hugoniot.csv run at up to 1.32x
           U_c in the wall frame, distention 2.91 at 0.646 km/s) stays 2 void diameters below the
           free top, which comes down at up: height = 1.5 FRONT + up t_end + 4 r (rounded up to a
           multiple of every h).
  measure  front speed U: least squares of front.csv (in rows of h from the top, where the mean
           v_y first differs from -up by up/2) over 0.3-0.95 of t_end, cut where the front comes
           within 2 void diameters of the free top (the window used is in experiment.json);
           Us = U + up. The front is fitted, not the momentum the wall takes up: the compacted
           slab behind the front rings between the wall and the front (in the iron rows at
           h = 4 um its mean velocity swings by up to about 0.2 up over tens of ns), which moves
           the front by a few um but the slab's momentum by a large part of what the front takes
           in over one swing. Behind the front: the points between 0.1 and 0.8 of the front's
           height, over the snapshots of the second half of the run (the shocked state, averaged
           over its ringing): mean -sigma_yy (the longitudinal stress, what rho00 Us up
           measures) and mean pressure [GPa], bulk density (their mass over the band's area: pores
           left open count) and the points' own mean density [g/cm^3], mean U_y [m/s] (0 in the
           wall frame when the state is the shocked one) and T [K]. The jump conditions with the
           engine's Us give P = rho00 Us up and rho = rho00 Us / (Us - up), as the rows do; and
           mass conservation with the bulk density behind gives Us = up rho_b / (rho_b - rho00),
           equal to the fitted Us for a steady single front.
  swept    the porosity of the material the front swept over the fit window, counted on the
           t = 0 snapshot (bench/compaction_hugoniot.py, swept_porosity), and the compacted
           Hugoniot's Us there (`check` at that porosity): a strip's random sample has a porosity
           that varies along y by a few hundredths, and the compacted front's speed changes by
           several per cent per hundredth at high porosity. The engine's Us against it is the
           model's departure from full compaction with that scatter taken out.
  per row  at each h the engine's Us as mean and spread (sample standard deviation) over seeds;
           the resolution change |Us(h1) - Us(h2)| / Us(h2) between the two finest h (converged
           when within 3 %); errors (engine / measured - 1) of the finest h's mean and of the
           compacted Hugoniot's Us (mean over the finest h's seeds: each sample's own porosity);
           the engine against the compacted Hugoniot at the swept porosity (mean and spread of the
           seeds' ratios).

Outputs: DIR/experiment.json (per row all of the above, every run, the command line and the
driver's git commit from a run.json provenance), DIR/experiment.md (the table, then the mean and
the worst |Us error| of the engine and of the compacted Hugoniot), DIR/experiment_us_up.png (Us
against up: measured points, the engine with error bars, the compacted Hugoniot; one colour per
distention). Runs are cached under DIR/runs/<key> (key: the case text, the overrides and the
driver binary's hash): a rerun only runs what changed. A run that was stopped (the harness
killed, SIGTERM, a full disk) and left a checkpoint continues from it (`shockmpm resume`, bitwise
the uninterrupted run) instead of starting again; where no checkpoint can be resumed it runs
from the start. A long experiment should run a copy of the driver (--driver): a rebuilt driver
has another hash, so its runs have other keys. A failed run is reported, the rest go on, and the
exit status is 1.

--coarse-rows LIST: rows run at the coarsest h only, for a row whose finest-h runs cost too much
(the engine's Us of such a row is from the coarsest h, no resolution change is given, and the
table says so). --quick: one row (the first, or the first of --rows), one seed, the coarsest h. --check PCT: exit 1
when a row's |Us error| against its measured Us exceeds PCT per cent (tests/experiment_quick.sh).
--dry-run: print the planned runs (strip, end time, particles, steps, cached or resumable) and run
nothing.

--compose JSON ...: run nothing; write one report (the three outputs above) into --out from the
experiment.json of several runs of the harness on one experiment (the same data file, dimension,
material, overrides and void radius; another is an error naming the key): rows run at another
cell or with more seeds in a later run join the table. No option but --out applies (another is
an error). Per row, h and seed the run of the last
report that has one counts; a row's engine Us is from its finest h with runs, its resolution
change against the next coarser h with runs. The report lists its sources' commands.
"""
import argparse
import csv
import glob
import hashlib
import json
import math
import os
import re
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compaction_hugoniot  # noqa: E402  (swept_porosity, hugoniot_at)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MATERIALS = os.path.join(ROOT, "cases", "materials.toml")
COLUMNS = ["m", "rho00_g_cm3", "up_km_s", "Us_km_s", "P_GPa", "rho_g_cm3", "source"]
CONVERGED_PCT = 3.0          # the second-resolution criterion
FAST = 1.5                   # the fastest wall-frame front the strip's height allows, over U_c
TOP_GAP_DIAMETERS = 2.0      # the fit stops where the front comes this close to the free top
WINDOW = (0.3, 0.95)         # fit window [fractions of t_end]
BAND = (0.1, 0.8)            # the shocked band [fractions of the front's height]
DENSITY_NOTE_PCT = 0.1       # library rho0 against rho00 x m (the rows' rounding is under 0.05 %)


class DataError(Exception):
    pass


def read_data(path):
    """The data rows as dicts of floats (source: text). Raises DataError naming the file, line and
    column of a missing column or a bad value."""
    try:
        with open(path, newline="") as f:
            lines = [(n, l) for n, l in enumerate(f, 1) if l.strip() and not l.lstrip().startswith("#")]
    except OSError as e:
        raise DataError(f"{path}: cannot read the data file ({e.strerror})")
    if not lines:
        raise DataError(f"{path}: no header line (only comments or empty)")
    reader = csv.reader([l for _, l in lines])
    header = [c.strip() for c in next(reader)]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise DataError(f"{path} line {lines[0][0]}: missing column(s) {', '.join(missing)} "
                        f"(needs {', '.join(COLUMNS)}; has {', '.join(header)})")
    rows = []
    for (n, _), vals in zip(lines[1:], reader):
        if len(vals) != len(header):
            raise DataError(f"{path} line {n}: {len(vals)} values for {len(header)} columns")
        rec = dict(zip(header, [v.strip() for v in vals]))
        row = {"line": n, "source": rec["source"]}
        for c in COLUMNS[:-1]:
            try:
                x = float(rec[c])
            except ValueError:
                raise DataError(f"{path} line {n}: column {c} = {rec[c]!r} is not a number")
            if not math.isfinite(x):
                raise DataError(f"{path} line {n}: column {c} = {rec[c]!r} is not finite")
            row[c] = x
        for c, ok, why in (("m", row["m"] >= 1.0, "a distention is at least 1"),
                           ("rho00_g_cm3", row["rho00_g_cm3"] > 0.0, "must be positive"),
                           ("up_km_s", row["up_km_s"] > 0.0, "must be positive"),
                           ("Us_km_s", row["Us_km_s"] > row["up_km_s"], "must exceed up_km_s")):
            if not ok:
                raise DataError(f"{path} line {n}: column {c} = {rec[c]!r}: {why}")
        rows.append(row)
    if not rows:
        raise DataError(f"{path}: no data rows")
    return rows


def seed_text(doc):
    """"3 seed(s)" for seeds 1..3, else the seeds by number (older reports: the count)."""
    seeds = doc.get("seed_list") or list(range(1, doc["seeds"] + 1))
    return f"{len(seeds)} seed(s)" if seeds == list(range(1, len(seeds) + 1)) else \
        f"{len(seeds)} seed(s): {', '.join(map(str, seeds))}"


def parse_list(text, kind, name):
    try:
        vals = [kind(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise DataError(f"{name} {text!r}: expected a comma-separated list of numbers")
    if not vals:
        raise DataError(f"{name} {text!r}: empty")
    return vals


def common_step(hs):
    """The smallest multiple of the largest h [um] that every h divides (geometry shared by all
    resolutions)."""
    H = max(hs)
    for k in range(1, 65):
        if all(abs(k * H / h - round(k * H / h)) < 1e-9 for h in hs):
            return k * H
    raise DataError(f"--h {','.join(f'{h:g}' for h in hs)}: no common multiple of the cell sizes "
                    "within 64 x the largest")


def round_up(x, step):
    return math.ceil(x / step - 1e-9) * step


def geometry(dim):
    return "3D, spherical voids" if dim == 3 else "2D plane strain, cylindrical voids"


def toml_num(x):
    return repr(float(x))


def case_text(row, idx, a, h, seed, width, height, t_end):
    phi = 1.0 - 1.0 / row["m"]
    top = round_up(height + 20.0, h)
    voids = ""
    if phi > 0.0:
        voids = (f"\n[bodies.voids]\nradius_um = {toml_num(a.void_radius_um)}\n"
                 f"porosity = {phi:.6f}   # 1 - 1/m, m = {row['m']:g}\nseed = {seed}\n")
    w = toml_num(width)
    v = -row['up_km_s'] * 1e3
    if a.dim == 3:  # a column periodic in x and z, square across; spherical voids
        what = "A column periodic in x and z"
        grid = (f"dimension = 3\ncell_size_um = {toml_num(h)}\nx_range_um = [0.0, {w}]\n"
                f"y_range_um = [0.0, {toml_num(top)}]\nz_range_um = [0.0, {w}]\nperiodic_x = true\nperiodic_z = true")
        body = (f'shape = "box"\nmaterial = "sample"\nx_range_um = [0.0, {w}]\ny_range_um = [0.0, {toml_num(height)}]\n'
                f"z_range_um = [0.0, {w}]\nvelocity_m_s = [0.0, {v!r}, 0.0]")
    else:
        what = "A strip periodic in x"
        grid = (f"cell_size_um = {toml_num(h)}\nx_range_um = [0.0, {w}]\ny_range_um = [0.0, {toml_num(top)}]\n"
                "periodic_x = true")
        body = (f'material = "sample"\nx_range_um = [0.0, {w}]\ny_range_um = [0.0, {toml_num(height)}]\n'
                f"velocity_m_s = [0.0, {v!r}]")
    return f"""# bench/experiment_hugoniot.py: data row {idx} ({os.path.basename(a.data)} line {row['line']}:
# m {row['m']:g}, up {row['up_km_s']:g} km/s, measured Us {row['Us_km_s']:g} km/s; {row['source']}),
# h {h:g} um, seed {seed}. {what}, porous sample moving at -up onto the slip wall
# at y = 0 (the symmetry plane of a symmetric impact), free top.
materials_file = "{MATERIALS}"

[run]
end_time_ns = {t_end:.3f}
snapshot_interval_ns = {t_end / 8.0:.4f}
diagnostics_interval_ns = {t_end / 250.0:.4f}

[grid]
{grid}

[solver]
shape = "quadratic"
transfer = "apic"
scheme = "usl"
cfl = 0.3
artificial_viscosity = true

[walls]
bottom = "slip"

[materials.sample]
base = "{a.material}"

[[bodies]]
name = "target"
{body}
points_per_cell = 2
{voids}"""


def set_args(a):
    out = []
    for kv in a.set:
        out += ["--set", kv]
    return out


def driver_check(a, path):
    """`check` of a case: (the compacted Hugoniot's wall-frame front [m/s], the dense one's for a
    sample without voids, or nan; particles; steps; stderr)."""
    chk = subprocess.run([a.driver, "check", path] + set_args(a), capture_output=True, text=True)
    front, dense, parts, steps = math.nan, math.nan, 0, 0
    for l in chk.stdout.splitlines():
        if "fully compacted" in l and "front " in l:
            front = float(l.split("front ")[1].split(" m/s")[0])
        md = re.search(r"stopped from ([0-9.eE+-]+) m/s \(dense Hugoniot\): Us ([0-9.eE+-]+) m/s", l)
        if md:
            dense = float(md.group(2)) - float(md.group(1))  # a dense sample (m = 1): its own front
        mp = re.match(r"\s*particles\s+(\d+)", l)
        if mp:
            parts = int(mp.group(1))
        ms = re.search(r"about (\d+) steps", l)
        if ms:
            steps = int(ms.group(1))
    if not math.isfinite(front):
        front = dense
    return front, parts, steps, (chk.stderr.strip() if chk.returncode else "")


def size_row(a, row, idx, width):
    """(height [um], t_end [ns], U_c [m/s]) of a row's strip, from `check` at the coarsest h."""
    r, up = a.void_radius_um, row["up_km_s"]  # km/s = um/ns
    front = a.front_diameters * 2.0 * r
    path = os.path.join(a.out, "cases", f"row{idx}-sizing.toml")
    t_guess = 100.0
    with open(path, "w") as f:
        f.write(case_text(row, idx, a, max(a.hs), 1, width, round_up(front * FAST + 4 * r, a.step), t_guess))
    uc, _, _, err = driver_check(a, path)
    if not math.isfinite(uc) or uc <= 0.0:
        raise DataError(f"row {idx}: no fully compacted Hugoniot from `{a.driver} check {path}`"
                        + (f": {err}" if err else ""))
    t_end = front / (uc * 1e-3)
    height = round_up(FAST * front + up * t_end + 4.0 * r, a.step)
    return height, t_end, uc


_DRIVER_HASH = {}


def run_key(driver, text, sets):
    if driver not in _DRIVER_HASH:
        with open(driver, "rb") as f:
            _DRIVER_HASH[driver] = hashlib.sha1(f.read()).hexdigest()
    return hashlib.sha1((_DRIVER_HASH[driver] + "|" + text + "|" + "|".join(sets)).encode()).hexdigest()[:16]


def completed(out):
    try:
        return json.load(open(os.path.join(out, "run.json"))).get("status") == "completed"
    except (OSError, ValueError):
        return False


def resumable(out):
    """A run directory that a stopped run left with a checkpoint (`shockmpm resume` can continue it)."""
    return not completed(out) and bool(glob.glob(os.path.join(out, "checkpoint", "ckpt_*.bin")))


def execute(a, path, out, sets):
    """Runs one case into out: continues a stopped run from its checkpoint, else runs it from the start.
    Returns the finished process and "resumed" or "ran"."""
    if resumable(out):
        p = subprocess.run([a.driver, "resume", out, "--quiet", "--threads", str(a.threads)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if p.returncode == 0:
            return p, "resumed"
        print(f"{out}: `shockmpm resume` failed (exit {p.returncode}: "
              f"{(p.stderr.strip().splitlines() or [''])[-1]}); running it from the start", flush=True)
    cmd = [a.driver, "run", path, "--quiet", "--overwrite", "--out", out, "--threads", str(a.threads)] + sets
    return subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True), "ran"


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def measure(out, up_km_s, t_end, height, r, case_path, driver, sets):
    """The run's front and state behind it (see the module's docstring). Raises on a run that
    cannot be measured, with the reason."""
    run = json.load(open(os.path.join(out, "run.json")))
    if run.get("status") != "completed":
        raise ValueError(f"run status {run.get('status')!r}: {run.get('message', '')}")
    if float(run["end_time_s"]) * 1e9 < 0.999 * t_end:
        raise ValueError(f"the run stopped at {float(run['end_time_s']) * 1e9:.1f} ns of {t_end:.1f} ns: "
                         f"{run.get('message', '')}")
    body = run["bodies"][0]
    c = body.get("compacted_hugoniot")
    if c is None and "dense_hugoniot" in body and float(body["porosity"]) == 0.0:
        d = body["dense_hugoniot"]  # no voids (m = 1): the compacted Hugoniot is the dense one
        c = {"front_speed_wall_frame_m_s": float(d["Us_m_s"]) - float(d["up_m_s"]), "Us_m_s": d["Us_m_s"],
             "P_Pa": d["P_Pa"], "rho_kg_m3": d["rho_kg_m3"]}
    mat = run["case_resolved"]["materials"][body["material"]]
    rho0 = float(mat["density_kg_m3"])
    up = up_km_s * 1e3
    fr = read_csv(os.path.join(out, "front.csv"))
    t = np.array([float(x["time_ns"]) for x in fr])
    y = np.array([float(x["front_y_um"]) for x in fr])
    ok = np.isfinite(t) & np.isfinite(y)
    t, y = t[ok], y[ok]
    top = height - up_km_s * t  # the free top [um], coming down at up
    sel = (t >= WINDOW[0] * t_end) & (t <= WINDOW[1] * t_end)
    cut = sel & (y > top - TOP_GAP_DIAMETERS * 2.0 * r)
    sel &= ~cut
    if sel.sum() < 5:
        raise ValueError(f"{int(sel.sum())} front.csv rows in the fit window (need 5)"
                         + (" (the front reached the free top: strip too short)" if cut.any() else ""))
    (slope, icpt), cov = np.polyfit(t[sel], y[sel], 1, cov=True)
    U = float(slope) * 1e3  # um/ns -> m/s
    res = {"front_wall_frame_m_s": U, "front_fit_std_m_s": float(math.sqrt(cov[0][0])) * 1e3,
           "Us_km_s": (U + up) * 1e-3,
           "window_ns": [float(t[sel][0]), float(t[sel][-1])],
           "window_front_um": [float(y[sel][0]), float(y[sel][-1])],
           "window_cut_at_top": bool(cut.any()),
           "porosity": float(body["porosity"]), "voids": int(body.get("voids", 0)),
           "particles": int(run["particles"]), "steps": int(run["steps"]),
           "wall_seconds": float(run["wall_seconds"]), "threads": int(run.get("threads", 0)),
           "rho0_library_g_cm3": rho0 * 1e-3,
           "git_commit": run.get("provenance", {}).get("git_commit", ""),
           "git_dirty": run.get("provenance", {}).get("git_dirty", "")}
    res["m_sample"] = 1.0 / (1.0 - res["porosity"])
    rho00 = rho0 * (1.0 - res["porosity"])
    res["rho00_engine_g_cm3"] = rho00 * 1e-3
    Us = U + up
    res["P_jump_GPa"] = rho00 * Us * up * 1e-9
    res["rho_jump_g_cm3"] = rho00 * Us / U * 1e-3 if U > 0 else math.nan
    if c is not None:
        res["compacted_front_wall_frame_m_s"] = float(c["front_speed_wall_frame_m_s"])
        res["compacted_Us_km_s"] = (float(c["front_speed_wall_frame_m_s"]) + up) * 1e-3
        if abs(float(c["Us_m_s"]) - (float(c["front_speed_wall_frame_m_s"]) + up)) > 1e-6 * float(c["Us_m_s"]) + 1e-3:
            raise ValueError("run.json compacted_hugoniot: Us_m_s is not front_speed_wall_frame_m_s + up")
        res["compacted_P_GPa"] = float(c["P_Pa"]) * 1e-9
        res["compacted_rho_g_cm3"] = float(c["rho_kg_m3"]) * 1e-3
    # the porosity of the material the front swept over the fit window (a random sample's
    # porosity varies along y; the compacted front's speed depends steeply on it at high
    # porosity) and the compacted Hugoniot there: the engine's Us against it is the model's
    # departure from full compaction without the sample's own scatter
    spacing = float(run["case_resolved"]["grid"]["cell_size_um"]) / float(
        run["case_resolved"]["bodies"][0].get("points_per_cell", 2))
    phi_sw = compaction_hugoniot.swept_porosity(out, t, y, up_km_s * 1e3, res["window_ns"][0], res["window_ns"][1],
                                                spacing) if res["porosity"] > 0.0 else 0.0
    res["swept_porosity"] = phi_sw
    res["compacted_swept_Us_km_s"] = math.nan
    if res["porosity"] > 0.0 and math.isfinite(phi_sw) and 0.0 < phi_sw < 1.0:
        front_sw, _ = compaction_hugoniot.hugoniot_at(driver, case_path, sets, phi_sw)
        res["compacted_swept_Us_km_s"] = (front_sw + up) * 1e-3
    elif c is not None:
        res["compacted_swept_Us_km_s"] = res["compacted_Us_km_s"]
    # the shocked band, over the snapshots of the second half
    import h5py
    grid = run["case_resolved"]["grid"]
    across = 1.0  # the band's extent across the impact direction [m]: width (2D) or width x depth (3D)
    for k in ("x_range_um", "z_range_um") if "z_range_um" in grid else ("x_range_um",):
        across *= (grid[k][1] - grid[k][0]) * 1e-6
    size = float(body["volume_m3"] if "volume_m3" in body else body["area_m2"])
    mass = rho0 * size / int(body["particles"])  # per point [kg/m in 2D, kg in 3D]: a lattice sample
    acc = {k: [] for k in ("P_long_GPa", "p_GPa", "rho_bulk_g_cm3", "rho_points_g_cm3", "Uy_m_s", "T_K")}
    for snap in sorted(glob.glob(os.path.join(out, "fields", "snap_*.h5"))):
        with h5py.File(snap, "r") as f:
            ts = float(f["particles"].attrs["time"]) * 1e9
            if ts < 0.5 * t_end:
                continue
            yy = f["particles/position"][:, 1] * 1e6
            yf = float(np.interp(ts, t, y))
            lo, hi = BAND[0] * yf, BAND[1] * yf
            m = (yy >= lo) & (yy <= hi) & (f["particles/body"][:] == 0)
            if m.sum() < 10:
                continue
            acc["P_long_GPa"].append(-float(f["particles/stress_yy"][:][m].mean()) * 1e-9)
            acc["p_GPa"].append(float(f["particles/pressure"][:][m].mean()) * 1e-9)
            acc["rho_points_g_cm3"].append(float(f["particles/density"][:][m].mean()) * 1e-3)
            acc["rho_bulk_g_cm3"].append(int(m.sum()) * mass / (across * (hi - lo) * 1e-6) * 1e-3)
            acc["Uy_m_s"].append(float(f["particles/velocity"][:, 1][m].mean()))
            acc["T_K"].append(float(f["particles/temperature"][:][m].mean()))
    res["behind_snapshots"] = len(acc["P_long_GPa"])
    for k, v in acc.items():
        res["behind_" + k] = float(np.mean(v)) if v else math.nan
    # the Us that mass conservation gives for the bulk density behind (a steady wave, the material
    # behind at rest): Us = up rho_b / (rho_b - rho00); it equals the fitted Us only for a steady
    # single front
    rb = res["behind_rho_bulk_g_cm3"] * 1e3
    res["Us_mass_balance_km_s"] = up * rb / (rb - rho00) * 1e-3 if rb > rho00 else math.nan
    # and momentum: the stress behind carries the sample from rest to up, P = rho00 Us up
    res["Us_momentum_km_s"] = res["behind_P_long_GPa"] * 1e9 / (rho00 * up) * 1e-3
    return res


def mean_std(xs):
    xs = [x for x in xs if x is not None and math.isfinite(x)]
    if not xs:
        return math.nan, math.nan
    return float(np.mean(xs)), (float(np.std(xs, ddof=1)) if len(xs) > 1 else math.nan)


def fmt(x, f="{:.3f}"):
    return "n/a" if x is None or not math.isfinite(x) else f.format(x)


def pct(x):
    return "n/a" if x is None or not math.isfinite(x) else f"{x:+.1f} %"


def clean(o):
    """JSON without NaN (null instead)."""
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, dict):
        return {k: clean(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [clean(v) for v in o]
    return o


def finish_rows(rows_out, cells):
    """Per row of rows_out: at each h the seeds' mean and spread of Us, of the compacted Hugoniot's
    Us and of the engine against the swept porosity; at the row's reported h (cells(rec) ->
    (h, (h1, h2) or None), the pair for the resolution change) the engine's Us, its errors and the
    state behind the front. Returns the summary over the rows (mean and worst |Us error|) and the
    runs' (git commit, dirty) pairs in order of first appearance."""
    commits = []
    for rec in rows_out:
        for hh in rec["by_h"].values():
            us = [x["Us_km_s"] for x in hh["runs"]]
            hh["Us_km_s_mean"], hh["Us_km_s_std"] = mean_std(us)
            hh["compacted_Us_km_s_mean"], _ = mean_std([x.get("compacted_Us_km_s", math.nan) for x in hh["runs"]])
            hh["seeds_measured"] = len(us)
            hh["vs_swept_pct_mean"], hh["vs_swept_pct_std"] = mean_std(
                [100.0 * (x["Us_km_s"] / x["compacted_swept_Us_km_s"] - 1.0) for x in hh["runs"]
                 if math.isfinite(x.get("compacted_swept_Us_km_s", math.nan))])
            for x in hh["runs"]:
                if (x["git_commit"], x["git_dirty"]) not in commits:
                    commits.append((x["git_commit"], x["git_dirty"]))
        h_row, pair = cells(rec)
        fine = rec["by_h"].get(f"{h_row:g}", {"runs": []})
        ok = bool(fine["runs"])
        rec["engine_h_um"] = h_row
        rec["engine_Us_km_s"] = fine.get("Us_km_s_mean", math.nan) if ok else math.nan
        rec["engine_Us_spread_km_s"] = fine.get("Us_km_s_std", math.nan) if ok else math.nan
        rec["compacted_Us_km_s"] = fine.get("compacted_Us_km_s_mean", math.nan) if ok else math.nan
        rec["engine_error_pct"] = 100.0 * (rec["engine_Us_km_s"] / rec["Us_km_s"] - 1.0)
        rec["engine_vs_swept_pct"] = fine.get("vs_swept_pct_mean", math.nan) if ok else math.nan
        rec["engine_vs_swept_spread_pct"] = fine.get("vs_swept_pct_std", math.nan) if ok else math.nan
        rec["compacted_error_pct"] = 100.0 * (rec["compacted_Us_km_s"] / rec["Us_km_s"] - 1.0)
        rec["resolution_change_pct"] = math.nan
        if pair:
            u1 = rec["by_h"].get(f"{pair[0]:g}", {}).get("Us_km_s_mean", math.nan)
            u2 = rec["engine_Us_km_s"]
            rec["resolution_change_pct"] = 100.0 * abs(u1 - u2) / u2
            rec["resolution_h_um"] = list(pair)
        keys = ["Us_mass_balance_km_s", "Us_momentum_km_s", "P_jump_GPa", "rho_jump_g_cm3", "behind_P_long_GPa", "behind_p_GPa", "behind_rho_bulk_g_cm3",
                "behind_rho_points_g_cm3", "behind_Uy_m_s", "behind_T_K", "compacted_P_GPa", "compacted_rho_g_cm3",
                "porosity", "swept_porosity", "compacted_swept_Us_km_s", "rho0_library_g_cm3", "rho00_engine_g_cm3"]
        rec["behind"] = {k: mean_std([x.get(k, math.nan) for x in fine["runs"]])[0] for k in keys}
        rho_lib = rec["behind"]["rho0_library_g_cm3"]
        if math.isfinite(rho_lib):
            want = rec["rho00_g_cm3"] * rec["m"]
            if abs(rho_lib / want - 1.0) * 100.0 > DENSITY_NOTE_PCT:
                rec["density_note"] = (f"the library's dense density {rho_lib:.4f} g/cm^3 differs from the row's "
                                       f"rho00 x m = {want:.4f} g/cm^3 ({100 * (rho_lib / want - 1):+.1f} %); the "
                                       f"sample's porosity follows m, its rho00 is {rho_lib / rec['m']:.4f} g/cm^3")
    done = [x for x in rows_out if not x["failed_runs"] and math.isfinite(x["engine_error_pct"])]
    eng = [abs(x["engine_error_pct"]) for x in done]
    cmp_ = [abs(x["compacted_error_pct"]) for x in done if math.isfinite(x["compacted_error_pct"])]
    return {
        "rows_complete": len(done),
        "engine_mean_abs_error_pct": float(np.mean(eng)) if eng else math.nan,
        "engine_worst_abs_error_pct": max(eng) if eng else math.nan,
        "engine_worst_row": max(done, key=lambda x: abs(x["engine_error_pct"]))["index"] if done else None,
        "compacted_mean_abs_error_pct": float(np.mean(cmp_)) if cmp_ else math.nan,
        "compacted_worst_abs_error_pct": max(cmp_) if cmp_ else math.nan,
        "compacted_worst_row": max(done, key=lambda x: abs(x["compacted_error_pct"]))["index"] if cmp_ else None,
    }, commits


def reported_h(doc):
    """The cell of most rows' engine Us [um] (ties: the finer); --coarse-rows and composed reports
    have rows at other cells, which the table and the chart mark."""
    by_h = {}
    for r in doc["rows"]:
        if r.get("engine_h_um") is not None:
            by_h.setdefault(r["engine_h_um"], []).append(str(r["index"]))
    return (max(by_h, key=lambda h: (len(by_h[h]), -h)) if by_h else doc["h_um"][-1]), by_h


def write_markdown(path, doc):
    hs = doc["h_um"]
    main_h = reported_h(doc)[0]
    fine = f"{main_h:.3g}"
    L = []
    L.append("# Porous Hugoniot: engine against measurements\n")
    L.append(f"Data: `{doc['data']}`; material `{doc['material']}`"
             + (f" with {', '.join('`' + s + '`' for s in doc['sets'])}" if doc["sets"] else "")
             + f"; voids of radius {doc['void_radius_um']:g} um; h = {', '.join(f'{h:g}' for h in hs)} um; "
             f"{seed_text(doc)}; {geometry(doc['dim'])}. Engine commit {doc['git_commit'] or 'n/a'}"
             + (" (dirty)" if doc.get("git_dirty") == "true" else "") + ".\n")
    L.append(f"Command: `{doc['command']}`\n")
    if doc.get("sources"):
        L.append("Composed of these reports (per row, h and seed the run of the last report that has one; "
                 "a row's engine Us from its finest h):\n")
        for src in doc["sources"]:
            L.append(f"- `{src['report']}`: `{src['command']}` (engine {src['git_commit'][:7] or 'n/a'}"
                     + (", dirty" if src.get("git_dirty") == "true" else "") + ")")
        L.append("")
    L.append(f"Us in the frame of the unshocked sample (the wall-frame front speed + up). Engine Us: mean "
             f"+- sample standard deviation over seeds at h = {fine} um; resolution change "
             f"|Us(h1) - Us(h2)| / Us(h2) between the row's two finest h (converged within {CONVERGED_PCT:g} %: "
             f"yes / no); compacted: the fully compacted Rankine-Hugoniot Us of the same EOS at each "
             f"sample's porosity (no strength, fully dense behind the front). Errors: model / measured - 1. "
             f"Engine against swept: each run's Us against the compacted Hugoniot at the porosity of the "
             f"material its front swept over the fit window (mean +- std over seeds): the engine's departure "
             f"from full compaction with the random sample's own scatter taken out.\n")
    L.append("| row | m | up [km/s] | measured Us [km/s] | engine Us [km/s] | resolution change | "
             "compacted Us [km/s] | engine error | compacted error | engine against swept |")
    L.append("|---|---|---|---|---|---|---|---|---|---|")
    for r in doc["rows"]:
        res = r["resolution_change_pct"]
        pair = r.get("resolution_h_um")
        rc = "n/a" if res is None else f"{res:.1f} % ({'yes' if res <= CONVERGED_PCT else 'no'}" + (
            f"; h {pair[0]:.3g} -> {pair[1]:.3g} um)" if pair and f"{pair[1]:.3g}" != fine else ")")
        spread = r["engine_Us_spread_km_s"]
        eng = fmt(r["engine_Us_km_s"]) + ("" if spread is None else f" +- {spread:.3f}")
        if r.get("engine_h_um") is not None and math.isfinite(r["engine_h_um"]) and f"{r['engine_h_um']:.3g}" != fine:
            eng += f" (h = {r['engine_h_um']:.3g} um)"
        L.append(f"| {r['index']} | {r['m']:g} | {r['up_km_s']:g} | {r['Us_km_s']:g} | {eng} | {rc} | "
                 f"{fmt(r['compacted_Us_km_s'])} | {pct(r['engine_error_pct'])} | {pct(r['compacted_error_pct'])} | "
                 f"{pct(r.get('engine_vs_swept_pct'))}"
                 + ("" if r.get("engine_vs_swept_spread_pct") is None else f" +- {r['engine_vs_swept_spread_pct']:.1f} %")
                 + " |")
    s = doc["summary"]
    L.append("")
    L.append(f"Mean |Us error|: engine {fmt(s['engine_mean_abs_error_pct'], '{:.1f} %')}, compacted Hugoniot "
             f"{fmt(s['compacted_mean_abs_error_pct'], '{:.1f} %')}. Worst: engine "
             f"{fmt(s['engine_worst_abs_error_pct'], '{:.1f} %')} (row {s['engine_worst_row']}), compacted "
             f"{fmt(s['compacted_worst_abs_error_pct'], '{:.1f} %')} (row {s['compacted_worst_row']}). "
             f"Rows with every run measured: {s['rows_complete']} of {len(doc['rows'])}.\n")
    L.append(f"State behind the front at h = {fine} um (a row marked with another h above: at that h; seed means): "
             "measured P and rho from the row; the "
             "engine's from the jump conditions with its Us (P = rho00 Us up, rho = rho00 Us / (Us - up)) and "
             "measured behind the front (longitudinal stress -sigma_yy; bulk density with the pores left open, "
             "and the points' own density); the compacted Hugoniot's. Us from rho bulk behind: "
             "up rho_b / (rho_b - rho00), what mass conservation gives for that density (a steady single "
             "front, the material behind at rest): where it differs from the fitted Us, the wave is not one "
             "steady front over the fit window. Us from -sigma_yy behind: P / (rho00 up), what momentum "
             "conservation gives for that stress.\n")
    L.append("| row | P measured [GPa] | P jump | -sigma_yy behind | P compacted | "
             "rho measured [g/cm^3] | rho jump | rho bulk behind | rho of the points | rho compacted | "
             "Us from rho bulk behind [km/s] | Us from -sigma_yy behind [km/s] | porosity (target / sample) |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in doc["rows"]:
        b = r["behind"]
        L.append(f"| {r['index']} | {r['P_GPa']:g} | {fmt(b['P_jump_GPa'], '{:.2f}')} | "
                 f"{fmt(b['behind_P_long_GPa'], '{:.2f}')} | {fmt(b['compacted_P_GPa'], '{:.2f}')} | "
                 f"{r['rho_g_cm3']:g} | {fmt(b['rho_jump_g_cm3'])} | {fmt(b['behind_rho_bulk_g_cm3'])} | "
                 f"{fmt(b['behind_rho_points_g_cm3'])} | {fmt(b['compacted_rho_g_cm3'])} | "
                 f"{fmt(b['Us_mass_balance_km_s'])} | {fmt(b['Us_momentum_km_s'])} | "
                 f"{r['porosity_target']:.4f} / {fmt(b['porosity'], '{:.4f}')} |")
    strips = [f"row {r['index']} {r['strip']['width_um']:g} x {r['strip']['height_um']:g}, {r['strip']['end_time_ns']:.0f}"
              for r in doc["rows"] if r.get("strip")]
    if strips:
        L.append("")
        L.append(f"Strips (width x height [um], end time [ns]; voids of radius {doc['void_radius_um']:g} um, front fit "
                 f"over {doc['fit_window_fraction_of_end_time'][0]:g}-{doc['fit_window_fraction_of_end_time'][1]:g} of "
                 "the end time): " + "; ".join(strips) + ".")
    notes = [r for r in doc["rows"] if r.get("density_note")]
    fails = [(r["index"], f) for r in doc["rows"] for f in r["failed_runs"]]
    cuts = [r["index"] for r in doc["rows"] if any(x.get("window_cut_at_top") for hh in r["by_h"].values() for x in hh["runs"])]
    if notes or fails or cuts:
        L.append("")
    for r in notes:
        L.append(f"- row {r['index']}: {r['density_note']}")
    for i in cuts:
        L.append(f"- row {i}: the fit window was cut where the front came within {TOP_GAP_DIAMETERS:g} void "
                 "diameters of the free top (faster than the strip was sized for)")
    for i, f in fails:
        L.append(f"- row {i}: run failed: {f}")
    with open(path, "w") as f:
        f.write("\n".join(L) + "\n")


def write_chart(path, doc):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    ms = sorted({r["m"] for r in doc["rows"]})
    cmap = plt.get_cmap("viridis")
    handles = []
    for k, m in enumerate(ms):
        col = cmap(k / max(1, len(ms) - 1) * 0.9)
        rs = sorted((r for r in doc["rows"] if r["m"] == m), key=lambda r: r["up_km_s"])
        ax.plot([r["up_km_s"] for r in rs], [r["Us_km_s"] for r in rs], "o", color=col, ms=7)
        eu = [(r["up_km_s"], r["engine_Us_km_s"], r["engine_Us_spread_km_s"] or 0.0) for r in rs
              if r["engine_Us_km_s"] is not None]
        if eu:
            ax.errorbar([e[0] for e in eu], [e[1] for e in eu], yerr=[e[2] for e in eu], fmt="s", mfc="none",
                        color=col, ms=8, capsize=3)
        cu = [(r["up_km_s"], r["compacted_Us_km_s"]) for r in rs if r["compacted_Us_km_s"] is not None]
        if cu:
            ax.plot([c[0] for c in cu], [c[1] for c in cu], "x--", color=col, lw=0.8, ms=7)
        handles.append(Line2D([], [], color=col, lw=6, label=f"m = {m:g}"))
    handles += [Line2D([], [], color="k", marker="o", ls="none", label="measured"),
                Line2D([], [], color="k", marker="s", mfc="none", ls="none",
                       label=f"engine (mean +- std over {doc['seeds']} seed(s))"),
                Line2D([], [], color="k", marker="x", ls="--", lw=0.8, label="fully compacted Hugoniot")]
    ax.set_xlabel("particle velocity up [km/s]")
    ax.set_ylabel("shock velocity Us [km/s]")
    # the cell of most rows, and the rows at another (--coarse-rows, or a composed table)
    main_h, by_h = reported_h(doc)
    others = "; ".join(f"row{'s' if len(v) > 1 else ''} {', '.join(v)}: {h:.3g} um"
                       for h, v in sorted(by_h.items()) if h != main_h)
    ax.set_title(f"{doc['material']}, {geometry(doc['dim'])}, r = {doc['void_radius_um']:g} um, "
                 f"h = {main_h:.3g} um" + (f" ({others})" if others else ""), fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(handles=handles, fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# What reports must share to compose: the same measured data, sample rules and material.
COMPOSE_MATCH = ("data", "dim", "material", "sets", "void_radius_um", "fit_window_fraction_of_end_time",
                 "behind_band_fraction_of_front")


def compose(paths, command):
    """One report from several experiment.json of one experiment (--compose): per row, h and seed
    the run of the last report that has one; a row's engine Us from its finest h with runs, the
    resolution change against the next coarser h with runs. Returns the doc."""
    docs = []
    for p in paths:
        try:
            with open(p) as f:
                d = json.load(f)
        except (OSError, ValueError) as e:
            raise DataError(f"--compose {p}: {e}")
        missing = [k for k in ("rows", "command", "h_um") + COMPOSE_MATCH if k not in d]
        if missing:
            raise DataError(f"--compose {p}: no {', '.join(missing)}: not a report of this harness (experiment.json)")
        docs.append((p, d))
    p0, d0 = docs[0]
    for p, d in docs[1:]:
        for k in COMPOSE_MATCH:
            if d[k] != d0[k]:
                raise DataError(f"--compose {p}: {k} is {d[k]!r} where {p0} has {d0[k]!r}: only reports of one "
                                "experiment compose")
    rows, strips = {}, {}
    for p, d in docs:
        for r in d["rows"]:
            rec = rows.setdefault(r["index"], {"index": r["index"], **{k: r[k] for k in COLUMNS},
                                               "data_line": r["data_line"], "porosity_target": r["porosity_target"],
                                               "by_h": {}, "failed_runs": []})
            for k in COLUMNS:
                if r[k] != rec[k]:
                    raise DataError(f"--compose {p}: row {r['index']} has {k} = {r[k]!r} where an earlier report "
                                    f"has {rec[k]!r}")
            for h, hh in r["by_h"].items():
                if not hh["runs"]:
                    continue
                runs = {x["seed"]: x for x in rec["by_h"].get(h, {"runs": []})["runs"]}
                for x in hh["runs"]:
                    runs[x["seed"]] = {**x, "report": p}
                rec["by_h"][h] = {"runs": [runs[k] for k in sorted(runs)]}
                strips[(r["index"], h)] = r.get("strip")
    rows_out = [rows[i] for i in sorted(rows)]

    def cells(rec):  # the finest h with runs, and the next coarser one
        hs = sorted((float(h) for h in rec["by_h"]), reverse=True)
        if not hs:
            return math.nan, None
        return hs[-1], (hs[-2], hs[-1]) if len(hs) >= 2 else None

    summary, commits = finish_rows(rows_out, cells)
    for rec in rows_out:
        if strips.get((rec["index"], f"{rec['engine_h_um']:g}")):
            rec["strip"] = strips[(rec["index"], f"{rec['engine_h_um']:g}")]
    seeds = sorted({x["seed"] for rec in rows_out for hh in rec["by_h"].values() for x in hh["runs"]})
    return {"command": command, "data": d0["data"],
            "driver": ", ".join(dict.fromkeys(d.get("driver", "") for _, d in docs)),
            "driver_sha1": ", ".join(dict.fromkeys(d.get("driver_sha1", "") for _, d in docs)),
            "git_commit": ", ".join(c[:7] + (" (dirty)" if dirty == "true" else "") for c, dirty in commits if c),
            "git_dirty": "", "dim": d0["dim"], "material": d0["material"], "sets": d0["sets"],
            "void_radius_um": d0["void_radius_um"],
            "h_um": sorted({float(h) for rec in rows_out for h in rec["by_h"]}, reverse=True),
            "seeds": len(seeds), "seed_list": seeds, "threads": d0.get("threads"), "quick": False,
            "frame": d0.get("frame"), "fit_window_fraction_of_end_time": d0["fit_window_fraction_of_end_time"],
            "behind_band_fraction_of_front": d0["behind_band_fraction_of_front"],
            "sources": [{"report": p, "command": d["command"], "git_commit": d.get("git_commit", ""),
                         "git_dirty": d.get("git_dirty", "")} for p, d in docs],
            "rows": rows_out, "summary": summary}


def write_outputs(out, doc):
    """DIR/experiment.json, experiment.md and experiment_us_up.png; prints the table. False when
    the chart failed (the table and the JSON are written first, so that it loses nothing else)."""
    doc = clean(doc)
    with open(os.path.join(out, "experiment.json"), "w") as f:
        json.dump(doc, f, indent=1)
    write_markdown(os.path.join(out, "experiment.md"), doc)
    ok = True
    try:
        write_chart(os.path.join(out, "experiment_us_up.png"), doc)
    except Exception as e:  # a chart failure must not lose the table
        print(f"chart failed: {e}", file=sys.stderr)
        ok = False
    print(open(os.path.join(out, "experiment.md")).read())
    print(f"Wrote {os.path.join(out, 'experiment.json')}, experiment.md, experiment_us_up.png")
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=os.path.join(ROOT, "bench", "data", "porous_iron_hugoniot.csv"),
                    help="the measured rows (CSV; columns: " + ", ".join(COLUMNS) + ")")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "experiment"), help="output directory")
    ap.add_argument("--dim", type=int, default=2,
                    help="2: a strip in plane strain, cylindrical voids; 3: a square column, spherical voids")
    ap.add_argument("--h", default="4,2", help="cell sizes [um], comma-separated (the last, finest, is reported)")
    ap.add_argument("--seeds", default="3",
                    help="void seeds per row and h: N (seeds 1..N) or a comma-separated list (e.g. 2,3)")
    ap.add_argument("--void-radius-um", type=float, default=10.0, help="void radius [um]")
    ap.add_argument("--front-diameters", type=float, default=15.0,
                    help="the compacted front's run [void diameters] that sets the end time")
    ap.add_argument("--width-diameters", type=float, default=6.0,
                    help="strip width [void diameters] (at least 10 cells of the coarsest h)")
    ap.add_argument("--material", default="iron", help="base entry of cases/materials.toml")
    ap.add_argument("--rows", default="", help="data rows to run, 0-based, comma-separated (default all)")
    ap.add_argument("--coarse-rows", default="",
                    help="rows run at the coarsest h only (their engine Us is from it; the table says so)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a case override for every run, e.g. materials.sample.yield_stress_MPa=300 (repeatable)")
    ap.add_argument("--driver", default=os.path.join(ROOT, "build", "shockmpm"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="one row, one seed, the coarsest h")
    ap.add_argument("--check", type=float, default=0.0, metavar="PCT",
                    help="exit 1 when a row's |Us error| against its measured Us exceeds PCT per cent")
    ap.add_argument("--dry-run", action="store_true", help="print the planned runs, run nothing")
    ap.add_argument("--compose", nargs="+", metavar="JSON",
                    help="run nothing: one report in --out from these experiment.json of one experiment")
    a = ap.parse_args()
    command = " ".join([os.path.relpath(sys.argv[0], os.getcwd()) if os.path.exists(sys.argv[0]) else sys.argv[0]]
                       + sys.argv[1:])
    if a.compose:
        try:
            given = [k for k in vars(a) if k not in ("compose", "out") and getattr(a, k) != ap.get_default(k)]
            if given:
                raise DataError(f"--compose runs nothing and takes only --out: --{given[0].replace('_', '-')} "
                                "does not apply")
            doc = compose(a.compose, command)
        except DataError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        os.makedirs(a.out, exist_ok=True)
        return 0 if write_outputs(a.out, doc) else 1
    try:
        if a.dim not in (2, 3):
            raise DataError(f"--dim {a.dim}: 2 (plane strain, cylindrical voids) or 3 (spherical voids)")
        a.hs = sorted(parse_list(a.h, float, "--h"), reverse=True)
        if any(not h > 0.0 for h in a.hs):
            raise DataError(f"--h {a.h}: cell sizes must be positive [um]")
        seeds = parse_list(a.seeds, int, "--seeds")
        a.seed_list = seeds if "," in a.seeds else list(range(1, seeds[0] + 1))
        if not a.seed_list or min(a.seed_list) < 1 or len(set(a.seed_list)) != len(a.seed_list):
            raise DataError(f"--seeds {a.seeds}: a count of at least 1, or distinct seeds of at least 1")
        a.seeds = len(a.seed_list)
        if not a.void_radius_um > 0.0:
            raise DataError(f"--void-radius-um {a.void_radius_um:g}: must be positive")
        if not a.width_diameters > 0.0:
            raise DataError(f"--width-diameters {a.width_diameters:g}: must be positive")
        if not a.front_diameters > 0.0:
            raise DataError(f"--front-diameters {a.front_diameters:g}: must be positive")
        if a.threads < 1:
            raise DataError(f"--threads {a.threads}: at least 1")
        for kv in a.set:
            if "=" not in kv or not kv.split("=", 1)[0].strip():
                raise DataError(f"--set {kv!r}: expected KEY=VALUE")
        if not (os.path.isfile(a.driver) and os.access(a.driver, os.X_OK)):
            raise DataError(f"--driver {a.driver}: not an executable file (build it: cmake --build build)")
        data = read_data(a.data)
        idx = list(range(len(data)))
        if a.rows:
            idx = parse_list(a.rows, int, "--rows")
            bad = [i for i in idx if not 0 <= i < len(data)]
            if bad:
                raise DataError(f"--rows {a.rows}: row(s) {', '.join(map(str, bad))} not in {a.data} "
                                f"({len(data)} rows, 0-based)")
        a.coarse_rows = parse_list(a.coarse_rows, int, "--coarse-rows") if a.coarse_rows else []
        bad = [i for i in a.coarse_rows if i not in idx]
        if bad:
            raise DataError(f"--coarse-rows {','.join(map(str, a.coarse_rows))}: row(s) "
                            f"{', '.join(map(str, bad))} are not among the rows run")
        if a.quick:
            idx, a.hs, a.seeds, a.seed_list = idx[:1], a.hs[:1], 1, a.seed_list[:1]
        a.step = common_step(a.hs)
    except DataError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    a.driver = os.path.abspath(a.driver)
    a.out = os.path.abspath(a.out)
    os.makedirs(os.path.join(a.out, "cases"), exist_ok=True)
    os.makedirs(os.path.join(a.out, "runs"), exist_ok=True)
    r = a.void_radius_um
    width = round_up(max(a.width_diameters * 2.0 * r, 10.0 * max(a.hs)), a.step)
    sets = set_args(a)

    # plan: the strip of every row, then the runs
    plan, rows_out, failed = [], [], []
    for i in idx:
        row = data[i]
        rec = {"index": i, **{k: row[k] for k in COLUMNS}, "data_line": row["line"],
               "porosity_target": 1.0 - 1.0 / row["m"], "by_h": {}, "failed_runs": []}
        rows_out.append(rec)
        try:
            height, t_end, uc = size_row(a, row, i, width)
        except DataError as e:
            print(f"row {i}: {e}", flush=True)
            rec["failed_runs"].append(str(e))
            failed.append(f"row {i}: sizing")
            continue
        rec["strip"] = {"width_um": width, "height_um": height, "end_time_ns": t_end,
                        "width_diameters": a.width_diameters,
                        "compacted_front_wall_frame_m_s_sizing": uc, "front_diameters": a.front_diameters}
        for h in a.hs:
            if i in a.coarse_rows and h != a.hs[0]:
                continue
            rec["by_h"][f"{h:g}"] = {"runs": []}
            for seed in a.seed_list:
                text = case_text(row, i, a, h, seed, width, height, t_end)
                path = os.path.join(a.out, "cases", f"row{i}-h{h:g}-seed{seed}.toml")
                with open(path, "w") as f:
                    f.write(text)
                key = run_key(a.driver, text, sets)
                plan.append((rec, row, h, seed, path, os.path.join(a.out, "runs", key), height, t_end))
    if a.dry_run:
        print("| row | m | up [km/s] | h [um] | seed | strip [um] | end [ns] | particles | steps | cached |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        tot = 0
        for rec, row, h, seed, path, out, height, t_end in plan:
            _, parts, steps, err = driver_check(a, path)
            tot += parts * steps
            print(f"| {rec['index']} | {row['m']:g} | {row['up_km_s']:g} | {h:g} | {seed} | {width:g} x {height:g} | "
                  f"{t_end:.0f} | {parts} | {steps} | {'yes' if completed(out) else 'resumes' if resumable(out) else 'no'} |" + (f" {err}" if err else ""))
        print(f"\n{len(plan)} runs, {tot:.3g} particle-steps")
        return 1 if failed else 0

    n = len(plan)
    for k, (rec, row, h, seed, path, out, height, t_end) in enumerate(plan, 1):
        label = f"[{k}/{n}] row {rec['index']} (m {row['m']:g}, up {row['up_km_s']:g} km/s) h {h:g} um seed {seed}"
        cached = completed(out)
        t0 = time.time()
        how = "cached"
        if not cached:
            p, how = execute(a, path, out, sets)
            if p.returncode != 0 and p.stderr.strip():
                with open(os.path.join(a.out, "runs", os.path.basename(out) + ".stderr"), "w") as f:
                    f.write(p.stderr)
        try:
            res = measure(out, row["up_km_s"], t_end, height, r, path, a.driver, sets)
        except (OSError, KeyError, ValueError, IndexError, TypeError, ZeroDivisionError) as e:
            why = str(e)
            if not cached:
                stderr_file = os.path.join(a.out, "runs", os.path.basename(out) + ".stderr")
                if os.path.exists(stderr_file):
                    why += " (driver: " + open(stderr_file).read().strip().splitlines()[-1] + ")"
            print(f"{label}: FAILED: {why} ({out})", flush=True)
            rec["failed_runs"].append(f"h {h:g} um seed {seed}: {why}")
            failed.append(label)
            continue
        res.update({"seed": seed, "case": os.path.relpath(path, a.out), "dir": os.path.relpath(out, a.out),
                    "cached": cached, "resumed": how == "resumed"})
        rec["by_h"][f"{h:g}"]["runs"].append(res)
        print(f"{label}: {'cached' if cached else f'{how} in {time.time() - t0:.1f} s'}, Us {res['Us_km_s']:.3f} km/s "
              f"(measured {row['Us_km_s']:g}, compacted {fmt(res.get('compacted_Us_km_s', math.nan))}), "
              f"porosity {res['porosity']:.4f}", flush=True)

    # per row: the finest h, a coarse row's coarsest
    def cells(rec):
        if rec["index"] in a.coarse_rows:
            return a.hs[0], None
        return a.hs[-1], (a.hs[-2], a.hs[-1]) if len(a.hs) >= 2 else None
    summary, commits = finish_rows(rows_out, cells)
    commit = next((c for c, _ in commits if c), "")
    dirty = next((d for _, d in commits if d), "")
    doc = {"command": command, "data": os.path.relpath(os.path.abspath(a.data), ROOT) if os.path.abspath(a.data).startswith(ROOT + os.sep) else a.data,
           "driver": os.path.relpath(a.driver, ROOT) if a.driver.startswith(ROOT + os.sep) else os.path.basename(a.driver),
           "driver_sha1": _DRIVER_HASH.get(a.driver, ""), "git_commit": commit,
           "git_dirty": dirty, "dim": a.dim, "material": a.material, "sets": a.set,
           "void_radius_um": r, "h_um": a.hs, "seeds": a.seeds, "seed_list": a.seed_list, "threads": a.threads, "quick": a.quick,
           "frame": "Us = wall-frame front speed + up: in the wall frame (the symmetry plane of a symmetric "
                    "impact) the unshocked sample moves at -up and the shocked material is at rest; adding +up "
                    "gives the frame of the unshocked sample, where the shocked material moves at +up",
           "fit_window_fraction_of_end_time": list(WINDOW), "behind_band_fraction_of_front": list(BAND),
           "rows": rows_out, "summary": summary}
    if not write_outputs(a.out, doc):
        failed.append("chart")
    rc = 0
    if failed:
        print(f"{len(failed)} failure(s): " + "; ".join(failed))
        rc = 1
    if a.check > 0.0:
        bad = [x for x in rows_out if not (abs(x["engine_error_pct"]) <= a.check)]  # nan fails
        for x in bad:
            print(f"check: row {x['index']}: |Us error| {fmt(abs(x['engine_error_pct']), '{:.1f}')} % > {a.check:g} %")
        print(f"check within {a.check:g} %: {'FAIL' if bad else 'PASS'}")
        rc = 1 if bad else rc
    return rc


if __name__ == "__main__":
    sys.exit(main())
