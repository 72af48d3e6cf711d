#!/usr/bin/python3
"""Sensitivity of the engine's porous shock speed to what is uncertain or absent in the model.

  /usr/bin/python3 bench/experiment_sensitivity.py [--rows 4,6] [--h 4] [--seeds 3]
      [--out DIR] [--driver build/shockmpm] [--threads 2] [--only NAME,NAME]

Runs bench/experiment_hugoniot.py once per variant below on the same rows of
bench/data/porous_iron_hugoniot.csv (default: rows 4 and 6, the two whose measured density behind
the shock is furthest below solid iron's, 7.38 and 6.62 g/cm^3), each into DIR/<variant>/, and
writes DIR/sensitivity.md and DIR/sensitivity.json: per variant and row the engine's Us (mean
+- sample standard deviation over the seeds), its error against the measured Us, and its change
against the base variant. Runs are cached per variant directory (a rerun only runs what
changed).

Variants (library iron otherwise; docs/validation.md says what each one tests):
  base          the library's iron, voids of radius 10 um, h as given
  yield_half    yield stress and hardening modulus x 0.5 (87.5 / 305 MPa)
  yield_double  yield stress and hardening modulus x 2 (350 / 1220 MPa): Johnson-Cook's rate
                factor 1 + C ln(rate / 1 s^-1) with Armco iron's C = 0.06 is 1.97 at 10^7 s^-1
  yield_x10     yield stress and hardening modulus x 10 (1750 / 6100 MPa): the flow stress with
                which static pore collapse (Carroll and Holt 1972: P = (2/3) Y ln(1/phi)) holds
                the porosity left in the measured material of rows 4 and 6 at their pressure
                (phi 0.06 at 3.7 GPa: Y = 2.0 GPa; 0.16 at 1.9 GPa: 1.5 GPa); not a value for
                iron, a test of whether strength alone can keep the pores open
  no_strength   `strength = "none"`: the hydrodynamic limit
  gamma_low, gamma_high  Grueneisen gamma0 1.4 and 2.2 instead of the library's 1.8: the
                thermal pressure of the hot compacted material, which sets how far below solid
                density it stays on the compacted Hugoniot (the shock heating enters the
                mechanics only through gamma; `heat_fraction` changes the temperature, not the
                motion)
  conduction    `solver.heat_conduction = true` (iron's conductivity, library entry)
  conduction_r20  conduction with voids of radius 20 um at twice the cell size: without
                conduction this run is the base run scaled by 2 in space and time (see
                scale_r20); with it, the pores' size enters through the diffusion length
  scale_r20     voids of radius 20 um at twice the cell size, no conduction: the model has no
                length or time scale of its own, so Us must equal the base's to round-off
  long          a front run of 40 void diameters instead of 15 (the end time and strip grow
                with it; the fit window is 0.3-0.95 of the end time): whether the front's speed
                still changes over the run
  wide          a strip 24 void diameters wide instead of 6: each sample holds 4 times the voids,
                so the seeds' spread (a small sample's porosity varies along y) should shrink
  visc_1e3, visc_1e4  a flow viscosity (`flow_viscosity_Pa_s`, flow stress Y + 3 eta rate_p) of
                1e3 and 1e4 Pa s: a pore-collapse time scale. No measured value for iron was
                found; the shear viscosities measured in shocked aluminium (perturbation decay:
                500 Pa s at 42 GPa, Liu et al. 2005, Chin. Phys. Lett. 22, 747; 1500, 2800 and
                3500 Pa s at 42, 78 and 101 GPa, Ma et al. 2011, Chin. Phys. B 20, 068301) are
                of order 1e3; 1e4 brackets them from above
  visc_1e3_long  1e3 Pa s and a front run of 40 void diameters: whether the compaction behind
                the front, spread out by the viscosity, settles within a longer run
  visc_1e4_r20  1e4 Pa s with voids of radius 20 um at twice the cell size: with a time scale
                in the model the void size matters (against visc_1e4; without one, scale_r20
                gives the base to round-off)
"""
import argparse
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HARNESS = os.path.join(ROOT, "bench", "experiment_hugoniot.py")

VARIANTS = [
    ("base", "library iron, r = 10 um", [], False),
    ("yield_half", "yield and hardening x 0.5", ["--set", "materials.sample.yield_stress_MPa=87.5",
                                                  "--set", "materials.sample.hardening_modulus_MPa=305.0"], False),
    ("yield_double", "yield and hardening x 2 (rate factor at 1e7/s)",
     ["--set", "materials.sample.yield_stress_MPa=350.0", "--set", "materials.sample.hardening_modulus_MPa=1220.0"],
     False),
    ("yield_x10", "yield and hardening x 10 (1750 / 6100 MPa)",
     ["--set", "materials.sample.yield_stress_MPa=1750.0", "--set", "materials.sample.hardening_modulus_MPa=6100.0"],
     False),
    ("no_strength", "no strength (hydrodynamic)", ["--set", 'materials.sample.strength="none"'], False),
    ("gamma_low", "Grueneisen gamma0 1.4", ["--set", "materials.sample.gruneisen_gamma=1.4"], False),
    ("gamma_high", "Grueneisen gamma0 2.2", ["--set", "materials.sample.gruneisen_gamma=2.2"], False),
    ("conduction", "heat conduction on", ["--set", "solver.heat_conduction=true"], False),
    ("conduction_r20", "heat conduction, r = 20 um at 2 h",
     ["--set", "solver.heat_conduction=true", "--void-radius-um", "20"], True),
    ("scale_r20", "r = 20 um at 2 h, no conduction", ["--void-radius-um", "20"], True),
    ("long", "front run of 40 void diameters", ["--front-diameters", "40"], False),
    ("wide", "strip 24 void diameters wide", ["--width-diameters", "24"], False),
    ("visc_1e3", "flow viscosity 1e3 Pa s", ["--set", "materials.sample.flow_viscosity_Pa_s=1000.0"], False),
    ("visc_1e4", "flow viscosity 1e4 Pa s", ["--set", "materials.sample.flow_viscosity_Pa_s=10000.0"], False),
    ("visc_1e3_long", "flow viscosity 1e3 Pa s, front run of 40 void diameters",
     ["--set", "materials.sample.flow_viscosity_Pa_s=1000.0", "--front-diameters", "40"], False),
    ("visc_1e4_r20", "flow viscosity 1e4 Pa s, r = 20 um at 2 h",
     ["--set", "materials.sample.flow_viscosity_Pa_s=10000.0", "--void-radius-um", "20"], True),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rows", default="4,6")
    ap.add_argument("--h", type=float, default=4.0, help="cell size [um] (the r = 20 um variants use 2 h)")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "sensitivity"))
    ap.add_argument("--driver", default=os.path.join(ROOT, "build", "shockmpm"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--only", default="", help="variants to run, comma-separated (default all)")
    a = ap.parse_args()
    names = [v[0] for v in VARIANTS]
    only = [x for x in a.only.split(",") if x]
    bad = [x for x in only if x not in names]
    if bad:
        print(f"error: --only {a.only}: unknown variant(s) {', '.join(bad)}; known: {', '.join(names)}",
              file=sys.stderr)
        return 2
    if not a.h > 0.0 or a.seeds < 1:
        print(f"error: --h {a.h:g} must be positive and --seeds {a.seeds} at least 1", file=sys.stderr)
        return 2
    os.makedirs(a.out, exist_ok=True)
    results, rc = {}, 0
    for name, what, extra, double_h in VARIANTS:
        if only and name not in only:
            continue
        h = 2.0 * a.h if double_h else a.h
        out = os.path.join(a.out, name)
        cmd = [sys.executable, HARNESS, "--rows", a.rows, "--h", f"{h:g}", "--seeds", str(a.seeds),
               "--out", out, "--driver", a.driver, "--threads", str(a.threads)] + extra
        print(f"== {name}: {what}", flush=True)
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        with open(os.path.join(a.out, name + ".log"), "w") as f:
            f.write(p.stdout)
        if p.returncode != 0:
            print(f"   {name}: the harness exited {p.returncode} (log: {name}.log)", flush=True)
            rc = 1
        try:
            doc = json.load(open(os.path.join(out, "experiment.json")))
        except (OSError, ValueError) as e:
            print(f"   {name}: no experiment.json: {e}", flush=True)
            rc = 1
            continue
        results[name] = {"what": what, "h_um": h, "args": extra, "rows": {
            str(r["index"]): {"Us_km_s": r.get("engine_Us_km_s"), "Us_sd_km_s": r.get("engine_Us_spread_km_s"),
                              "measured_Us_km_s": r["Us_km_s"], "error_pct": r.get("engine_error_pct"),
                              "compacted_Us_km_s": r.get("compacted_Us_km_s"), "m": r["m"], "up_km_s": r["up_km_s"],
                              "vs_swept_pct": r.get("engine_vs_swept_pct"),
                              "vs_swept_sd_pct": r.get("engine_vs_swept_spread_pct"),
                              "rho_bulk_behind_g_cm3": r.get("behind", {}).get("behind_rho_bulk_g_cm3"),
                              "measured_rho_g_cm3": r.get("rho_g_cm3"),
                              "Us_mass_balance_km_s": r.get("behind", {}).get("Us_mass_balance_km_s"),
                              "Uy_behind_m_s": r.get("behind", {}).get("behind_Uy_m_s"),
                              "T_behind_K": r.get("behind", {}).get("behind_T_K"),
                              "seeds": r.get("by_h", {}).get(f"{h:g}", {}).get("seeds_measured", 0)}
            for r in doc["rows"]}}
    rows = sorted({k for v in results.values() for k in v["rows"]}, key=int)
    base = results.get("base", {}).get("rows", {})

    def num(x, f):
        return "n/a" if x is None or not isinstance(x, (int, float)) or not math.isfinite(x) else f.format(x)
    lines = ["| variant | h [um] | " + " | ".join(
        f"row {k}: Us [km/s] (error; change against base; against the compacted Hugoniot at the swept "
        f"porosity)" for k in rows) + " |",
        "|---|---|" + "---|" * len(rows)]
    for name, v in results.items():
        cells = []
        for k in rows:
            x = v["rows"].get(k, {})
            us, b = x.get("Us_km_s"), base.get(k, {}).get("Us_km_s")
            ch = 100.0 * (us / b - 1.0) if isinstance(us, float) and isinstance(b, float) and b else None
            cells.append(f"{num(us, '{:.3f}')} +- {num(x.get('Us_sd_km_s'), '{:.3f}')} "
                         f"({num(x.get('error_pct'), '{:+.1f}')} %; {num(ch, '{:+.1f}')} %; "
                         f"{num(x.get('vs_swept_pct'), '{:+.1f}')} +- {num(x.get('vs_swept_sd_pct'), '{:.1f}')} %)")
        lines.append(f"| {name}: {v['what']} | {v['h_um']:g} | " + " | ".join(cells) + " |")
    # the state behind the front: bulk density (the measured one beside it), the shock speed that
    # mass balance gives from it, and the band's velocity in the wall frame (0 behind a steady front)
    lines += ["", "State behind the front (means over the seeds): bulk density [g/cm^3] (measured); Us from "
              "mass balance [km/s]; the band's velocity U_y in the wall frame [m/s] (0 behind a steady front; "
              "negative: still moving toward the wall).", "",
              "| variant | " + " | ".join(f"row {k}" for k in rows) + " |", "|---|" + "---|" * len(rows)]
    for name, v in results.items():
        cells = []
        for k in rows:
            x = v["rows"].get(k, {})
            cells.append(f"{num(x.get('rho_bulk_behind_g_cm3'), '{:.2f}')} ({num(x.get('measured_rho_g_cm3'), '{:.2f}')}); "
                         f"{num(x.get('Us_mass_balance_km_s'), '{:.3f}')}; {num(x.get('Uy_behind_m_s'), '{:.0f}')}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    meas = [f"row {k}: m {base.get(k, {}).get('m', 'n/a')}, up {base.get(k, {}).get('up_km_s', 'n/a')} km/s, "
            f"measured Us {base.get(k, {}).get('measured_Us_km_s', 'n/a')} km/s, compacted Hugoniot "
            f"{num(base.get(k, {}).get('compacted_Us_km_s'), '{:.3f}')} km/s" for k in rows]
    text = ("# Sensitivity of the porous iron shock speed\n\n"
            f"`{' '.join(['bench/experiment_sensitivity.py'] + sys.argv[1:])}`; seeds per variant and row: {a.seeds}.\n\n"
            + "\n".join("- " + m for m in meas) + "\n\n" + "\n".join(lines) + "\n")
    with open(os.path.join(a.out, "sensitivity.md"), "w") as f:
        f.write(text)
    with open(os.path.join(a.out, "sensitivity.json"), "w") as f:
        json.dump({"rows": rows, "seeds": a.seeds, "h_um": a.h, "variants": results}, f, indent=1)
    print(text)
    return rc


if __name__ == "__main__":
    sys.exit(main())
