#!/usr/bin/python3
"""Whole-run throughput harness: the standard scenes of cases/bench/ at about 1e5, 1e6 and 4e6
particles, with 1 and 2 threads, against this machine's measured roofs.

For every scene, size and thread count it runs `shockmpm run` for a fixed number of steps and
reads run.json: particle-steps/s, wall seconds per phase (sort, P2G, grid update, contact,
G2P, constitutive update, heat, diagnostics, output), resident bytes per particle, peak RSS.
In the same invocation it runs bench/machine_roofs (STREAM-like triad, FMA throughput) with 1 and
2 threads, and prints, per phase, the bytes and flops per particle-step of the kernel (the
model below) and the fraction of its roof the phase reaches:
    roof time per particle-step = max(bytes / triad bandwidth, flops / FMA throughput)
    fraction = roof time / measured time          (1.0: at the roof)

Usage (from the repository root, on a quiet machine: nothing else running):
    /usr/bin/python3 bench/throughput.py                          # everything, about 10 min
    /usr/bin/python3 bench/throughput.py --table bench/results/throughput-STAMP.json   # re-print
    /usr/bin/python3 bench/throughput.py --scenes dense_shock --sizes 1e6 --threads 2
Writes bench/results/throughput-STAMP.json (every run.json, the roofs) and -STAMP.md (tables),
and prints the tables. Builds build/ (Release) first unless --no-build.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# The one key that sets each scene's particle count, and its value for each size (the case
# files' comments list the same values).
SCENES = {
    "elastic_block": ("grid.cell_size_m", {"1e5": 0.0025, "1e6": 0.0008, "4e6": 0.0004}),
    "dense_shock": ("grid.cell_size_um", {"1e5": 4.0, "1e6": 1.25, "4e6": 0.625}),
    "porous_shock": ("grid.cell_size_um", {"1e5": 2.5, "1e6": 0.8, "4e6": 0.4}),
    "dense_shock_3d": ("grid.cell_size_um", {"1e5": 10.0, "1e6": 4.0, "4e6": 2.5}),
    "porous_shock_3d": ("grid.cell_size_um", {"1e5": 6.25, "1e6": 3.125, "4e6": 2.0}),
}
PHASES = ["sort", "p2g", "grid", "contact", "g2p", "constitutive", "heat", "diagnostics", "output"]
STEP_PHASES = PHASES[:7]  # the time step itself

# ---- the per-phase traffic and flop model ---------------------------------------------------
# Bytes: compulsory DRAM traffic per particle-step, each array streamed once per phase: 8 B per
# double read, 8 B per double written, and 8 B more for a write to an array the phase does not
# read (write-allocate). Grid arrays count per node and are divided by particles per node.
# Flops: hand counts of the kernels' arithmetic (kernels/transfer.hpp, constitutive.hpp),
# additions and multiplications, an FMA as two, a division or square root as one; shape
# function evaluation counted per axis. They are estimates to +-30 %, stated as such.
SHAPE_N = {"linear": 2, "ugimp": 3, "quadratic": 3, "cubic": 4}
SHAPE_EVAL_FLOPS = {"linear": 6, "ugimp": 30, "quadratic": 20, "cubic": 40}  # per axis


def traffic(phase, fields, cfg, nodes_per_particle, permute_every):
    """(bytes, flops) per particle-step of one phase, in D = 2 or 3 dimensions (3 when the
    particles carry a z coordinate). The counts are written for D axes: per-axis arrays and
    node values D, the stress D (D + 1) / 2 components, C and L D^2; the stencil N^D nodes.
    The hand counts of tensor arithmetic (the constitutive update) scale with D^2 / 4 from
    their 2D count. +-30 %, as in 2D."""
    has = set(fields)
    D = 3 if "z" in has else 2
    ax = "xyz"[:D]
    pos, vel = list(ax), ["v" + a for a in ax]
    stress = ["s" + a + a for a in ax] + ["s" + ax[r] + ax[c] for r in range(D) for c in range(r + 1, D)]
    affine = ["C" + r + c for r in ax for c in ax]
    apic = "Cxx" in has
    heat = apic and "e" in has       # the APIC gather heats the particles (transfer dissipation)
    flip = cfg["transfer"] == "flip"
    N = SHAPE_N[cfg["shape"]]
    nodes = N ** D
    ev = D * SHAPE_EVAL_FLOPS[cfg["shape"]]
    npp = nodes_per_particle
    ndouble = sum(1 for f in fields if f not in ("id", "body"))
    tensor = D * D / 4  # tensor arithmetic against its 2D count

    def rd(*names):
        return 8 * sum(1 for n in names if n in has)

    def rw(*names):
        return 16 * sum(1 for n in names if n in has)

    if phase == "sort":
        # keys from the coordinates (write key 4 B + allocate), histogram and stable scatter
        # (read key twice, write order 4 B + allocate), and every permute_every steps the
        # physical permutation of all arrays (read + write each, plus the id and body arrays)
        b = 8 * D + 8 + 8 + 8
        if permute_every > 0:
            b += (16 * ndouble + 8 + 2) / permute_every
        return b, 6 * D
    if phase == "p2g":
        # order index, x, v, m, V, stress, q, C; grid: clear 1 + 2 D arrays, then the tile
        # flush reads and writes them per node
        b = 4 + rd(*pos, *vel, "m", "V", *stress, "p", "q", *affine)
        b += npp * ((1 + 2 * D) * 8 + (1 + 2 * D) * 16)
        # per node: weight, affine, momentum, mass, gradient, force
        per_node = (D - 1) + (2 * D * D if apic else 0) + 2 * D + 2 + D * D + 2 * D * D + 2
        return b, ev + 15 * D + nodes * per_node
    if phase == "grid":
        # read m, p, f; write v (and dv for FLIP), write-allocate; with transfer heating also p
        # back (the scatter velocity p / m, in place)
        heat_g = apic and "e" in has
        return npp * ((1 + 2 * D) * 8 + (2 * D if flip else D) * 16 + (8 * D if heat_g else 0)), npp * 7 * D
    if phase == "contact":
        return npp * 2 * (4 * D * 8 + 2 * D * 16), npp * 30 * D
    if phase == "g2p":
        # reads x; writes x, v, C; heat: reads v, C, e too, and the scatter velocity (p holds
        # p / m after the grid update). L stays in the gather's block buffer
        # (kern::g2p_blocks; only its three measures are stored, for the steps the statistics read)
        b = D * 16 + D * (8 if (heat or flip) else 16)  # x rw, v
        b += rw(*affine) if heat else 16 * D * D * apic
        if heat:
            b += rw("e")
        b += npp * 8 * (D + (D if heat else 0) + (D if flip else 0))
        per_node = 1 + 2 * D + 2 * D * D + (2 * D * D if (apic and cfg["shape"] == "linear") else 0)
        if heat:
            per_node += 8 * D
        if flip:
            per_node += 2 * D
        flops = ev + 20 * D + nodes * per_node
        if cfg.get("scheme") == "musl":
            # MUSL: the velocity gather above, then a momentum remap (scatter of m v: reads x, v,
            # m, order; clears and adds p), grid velocity (reads m, p, writes v), and a second
            # gather for position and L (reads x, grid v; writes x; L into the block buffer)
            b += 4 + (2 * D + 1) * 8 + npp * (D * 8 + D * 16) + npp * ((1 + D) * 8 + D * 16)
            b += D * 16 + npp * 8 * D
            flops += 2 * ev + nodes * (1 + 2 * D) + npp * 4 * D + nodes * (1 + 2 * D + 2 * D * D)
        return b, flops
    if phase == "constitutive":
        # V rw, m read, stress rw, p rw, v read, optional e, epsp, wp rw, q write; L from the
        # gather's block buffer (in L2: not counted)
        b = rd("m", *vel) + rw("V", *stress, "p", "e", "epsp", "wp")
        b += rw("q")
        flops = 60 * tensor  # Jaumann trial, volume, rho, signal speed (one sqrt), max
        if "epsp" in has:
            flops += 25 * tensor  # von Mises and the return
        if "e" in has:
            flops += 40  # Mie-Grueneisen cold curve and the centred energy update
        if "q" in has:
            flops += 15 * tensor
        return b, flops
    if phase == "heat":
        return 0, 0
    return None, None  # diagnostics, output: not modelled


def run_one(binary, scene, key, value, steps, threads, workdir):
    out = Path(workdir) / f"{scene}-{value}-t{threads}"
    cmd = [str(binary), "run", str(ROOT / "cases" / "bench" / f"{scene}.toml"), "--out", str(out), "--overwrite", "--quiet",
           "--set", f"{key}={value}", "--set", f"run.max_steps={steps}"]
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    t0 = time.time()
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
    wall = time.time() - t0
    with open(out / "run.json") as f:
        r = json.load(f)
    r["process_wall_seconds"] = wall
    r["command"] = f"OMP_NUM_THREADS={threads} " + " ".join(cmd[:3] + cmd[5:]).replace(str(ROOT) + "/", "")
    return r


def roofs(binary_dir, threads):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    out = subprocess.run([str(binary_dir / "bench" / "machine_roofs")], check=True, env=env, capture_output=True,
                         text=True).stdout
    return json.loads(out)


def solver_cfg(run):
    """shape and transfer from the resolved case in run.json."""
    s = run["case_resolved"].get("solver", {})
    return {"shape": s.get("shape", "quadratic"), "transfer": s.get("transfer", "apic"),
            "scheme": s.get("scheme", "usl"), "permute_every": s.get("permute_every", 20)}


def tables(results, roof):
    lines = []
    lines.append("Machine roofs (bench/machine_roofs, best of 10): " + ", ".join(
        f"{t} thread{'s' if t > 1 else ''}: triad {roof[t]['triad_GB_s']:.1f} GB/s, FMA {roof[t]['fma_GFLOP_s']:.1f} GFLOP/s"
        for t in sorted(roof)))
    lines.append("")
    lines.append("| scene | particles | steps | M particle-steps/s, 1 thread | 2 threads | 2/1 | particle B/particle | "
                 "resident B/particle | peak RSS MiB | diagnostics + output % |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|")
    keyed = {}
    for r in results:
        keyed[(r["scene"], r["size"], r["threads"])] = r
    for (scene, size) in sorted({(r["scene"], r["size"]) for r in results}, key=lambda k: (k[0], float(k[1]))):
        r1, r2 = keyed.get((scene, size, 1)), keyed.get((scene, size, 2))
        r = r2 or r1
        v1 = r1["particle_steps_per_s"] * 1e-6 if r1 else float("nan")
        v2 = r2["particle_steps_per_s"] * 1e-6 if r2 else float("nan")
        ph = r["phase_seconds"]
        do = 100 * (ph["diagnostics"] + ph["output"]) / r["wall_seconds"]
        lines.append(f"| {scene} | {r['particles']:,} | {r['steps']} | {v1:.2f} | {v2:.2f} | {v2 / v1:.2f} | "
                     f"{r['particle_bytes_per_particle']:.0f} | {r['resident_bytes'] / r['particles']:.0f} | "
                     f"{r['peak_rss_bytes'] / 2**20:.0f} | {do:.1f} |")
    lines.append("")
    lines.append("The step alone (the sum of the step's phase times: no diagnostics, no output):")
    lines.append("")
    lines.append("| scene | particles | ns/p-step, 1 thread | 2 threads | 2/1 | M particle-steps/s, 2 threads |")
    lines.append("|---|---|---|---|---|---|")

    def step_ns(r):
        if r is None:
            return float("nan")
        return sum(t for ph, t in r["phase_seconds"].items() if ph in STEP_PHASES) / (r["particles"] * r["steps"]) * 1e9

    for (scene, size) in sorted({(r["scene"], r["size"]) for r in results}, key=lambda k: (k[0], float(k[1]))):
        r1, r2 = keyed.get((scene, size, 1)), keyed.get((scene, size, 2))
        a, b = step_ns(r1), step_ns(r2)
        lines.append(f"| {scene} | {(r2 or r1)['particles']:,} | {a:.1f} | {b:.1f} | {a / b:.2f} | {1e3 / b:.1f} |")
    lines.append("")
    lines.append("Per phase: ns per particle-step (measured), model bytes and flops per particle-step, and the "
                 "fraction of the roof reached (roof time / measured time).")
    lines.append("")
    lines.append("| scene | particles | threads | phase | ns/p-step | B/p-step | flop/p-step | bound | roof fraction |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for r in sorted(results, key=lambda r: (r["scene"], float(r["size"]), r["threads"])):
        n = r["particles"] * r["steps"]
        cfg = r["solver"]
        # the grid passes work on the occupied box of nodes (run.json active_nodes)
        npp = r.get("active_nodes", r["nodes"]) / r["particles"]
        R = roof[r["threads"]]
        for ph in PHASES:
            t = r["phase_seconds"].get(ph, 0.0)
            if t <= 0.0:
                continue
            ns = t / n * 1e9
            b, f = traffic(ph, r["particle_fields"], cfg, npp, cfg["permute_every"])
            if b is None:
                lines.append(f"| {r['scene']} | {r['particles']:,} | {r['threads']} | {ph} | {ns:.2f} | - | - | - | - |")
                continue
            tb = b / (R["triad_GB_s"] * 1e9) * 1e9
            tf = f / (R["fma_GFLOP_s"] * 1e9) * 1e9
            bound = "memory" if tb >= tf else "flops"
            lines.append(f"| {r['scene']} | {r['particles']:,} | {r['threads']} | {ph} | {ns:.2f} | {b:.0f} | {f:.0f} | "
                         f"{bound} | {max(tb, tf) / ns:.2f} |")
    return "\n".join(lines)


def measure(a, build, threads, work, results):
    """Runs every scene, size and thread count of the arguments; appends each run.json."""
    for scene in a.scenes.split(","):
        if scene not in SCENES:
            sys.exit(f"--scenes: unknown scene '{scene}' (allowed: {', '.join(SCENES)})")
        key, sizes = SCENES[scene]
        for size in a.sizes.split(","):
            if size not in sizes:
                sys.exit(f"--sizes: unknown size '{size}' (allowed: {', '.join(sizes)})")
            value = sizes[size]
            for t in threads:
                # particles from the first run; steps from the budget
                n_est = float(size)
                steps = int(min(300, max(20, a.particle_steps / n_est)))
                print(f"== {scene} {size} ({key}={value}), {t} thread(s), {steps} steps", file=sys.stderr, flush=True)
                r = run_one(build / "shockmpm", scene, key, value, steps, t, work)
                if r["status"] != "completed":
                    sys.exit(f"{scene} {size}: run {r['status']}: {r['message']}")
                if not a.keep:
                    shutil.rmtree(Path(work) / f"{scene}-{value}-t{t}")
                r.update(scene=scene, size=size, solver=solver_cfg(r))
                print(f"   {r['particles']:,} particles, {r['particle_steps_per_s'] * 1e-6:.2f} M particle-steps/s",
                      file=sys.stderr, flush=True)
                results.append(r)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default=",".join(SCENES), help="comma-separated, from " + ", ".join(SCENES))
    ap.add_argument("--sizes", default="1e5,1e6,4e6", help="comma-separated, from 1e5, 1e6, 4e6")
    ap.add_argument("--threads", default="1,2", help="comma-separated thread counts")
    ap.add_argument("--particle-steps", type=float, default=2e8,
                    help="particle-steps per run: steps = this / particles, within [20, 300] (default 2e8)")
    ap.add_argument("--build-dir", default=str(ROOT / "build"))
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--keep", help="keep the runs' output directories here (default: a temporary directory)")
    ap.add_argument("--table", help="only re-print the tables of an earlier bench/results/throughput-*.json")
    a = ap.parse_args()
    if a.table:
        with open(a.table) as f:
            d = json.load(f)
        for r in d["runs"]:
            # files written before the scheme was recorded: the scenes as in cases/bench
            r["solver"].setdefault("scheme", "musl" if r["scene"] == "elastic_block" else "usl")
        print(tables(d["runs"], {int(k): v for k, v in d["roofs"].items()}))
        return
    build = Path(a.build_dir)
    if not a.no_build:
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release"], check=True,
                       stdout=subprocess.DEVNULL)
        subprocess.run(["cmake", "--build", str(build), "--target", "shockmpm", "machine_roofs", "-j", "2"], check=True,
                       stdout=subprocess.DEVNULL)
    threads = [int(t) for t in a.threads.split(",")]
    roof = {t: roofs(build, t) for t in threads}
    results = []
    # each run's output goes once its run.json is read (a 4e6 run writes about 1 GB of
    # snapshots), unless --keep; after a failure the runs so far stay for inspection
    work = a.keep or tempfile.mkdtemp(prefix="smpm-throughput-")
    done = False
    try:
        measure(a, build, threads, work, results)
        done = True
    finally:
        if not a.keep:
            if done:
                shutil.rmtree(work, ignore_errors=True)
            else:
                print(f"(the runs so far are kept in {work})", file=sys.stderr)
    text = tables(results, roof)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    outdir = ROOT / "bench" / "results"
    outdir.mkdir(parents=True, exist_ok=True)
    for r in results:
        r.pop("case_resolved", None)
    with open(outdir / f"throughput-{stamp}.json", "w") as f:
        json.dump({"roofs": roof, "runs": results}, f, indent=1)
    with open(outdir / f"throughput-{stamp}.md", "w") as f:
        f.write(text + "\n")
    print(text)
    print(f"\n(bench/results/throughput-{stamp}.json, .md)", file=sys.stderr)


if __name__ == "__main__":
    main()
