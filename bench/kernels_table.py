#!/usr/bin/env python3
"""Compact table of bench_kernels JSON results (Google Benchmark --benchmark_out format).

Usage: kernels_table.py RESULT.json [RESULT.json ...]   (one file per OMP thread count)

For every benchmark: median particle_steps_per_s per thread count (the "median" aggregate when
the run had repetitions, else the median of the individual runs), its spread across
repetitions (cv, when there were several), and the speed-up of the largest thread count over
the smallest. Then, for P2G, the colored/atomic and colored/serial ratios of those medians.
Standard library only.
"""
import json
import os
import re
import statistics
import sys

COUNTER = "particle_steps_per_s"


def thread_count(path, doc):
    ctx = doc.get("context", {})
    t = ctx.get("omp_max_threads")
    if t is not None:
        return int(t)
    m = re.search(r"-t(\d+)\.json$", path)
    return int(m.group(1)) if m else 0


def base_name(run_name):
    return run_name[: -len("/real_time")] if run_name.endswith("/real_time") else run_name


def load(path):
    with open(path) as f:
        doc = json.load(f)
    runs, aggs, errors = {}, {}, {}
    for b in doc.get("benchmarks", []):
        name = base_name(b.get("run_name", b["name"]))
        if b.get("error_occurred"):
            errors[name] = b.get("error_message", "error")
            continue
        if COUNTER not in b:
            continue
        if b.get("run_type") == "aggregate":
            aggs.setdefault(name, {})[b.get("aggregate_name")] = b
        else:
            runs.setdefault(name, []).append(b[COUNTER])
    out = {}
    for name in list(dict.fromkeys(list(runs) + list(aggs))):
        vals = runs.get(name, [])
        agg = aggs.get(name, {})
        if "median" in agg:
            med = agg["median"][COUNTER]
        elif vals:
            med = statistics.median(vals)
        else:
            continue
        cv = None
        if len(vals) >= 2:
            cv = statistics.stdev(vals) / statistics.mean(vals)
        elif "cv" in agg:
            cv = agg["cv"].get("real_time")  # cv of the time ~ cv of the rate
        reps = len(vals) if vals else agg.get("median", {}).get("repetitions", 1)
        out[name] = (med, cv, reps)
    for name, msg in errors.items():
        out.setdefault(name, (None, None, 0))
    return thread_count(path, doc), out, errors


def fmt_rate(v):
    return "-" if v is None else f"{v / 1e6:8.2f}"


def fmt_cv(cv):
    return "" if cv is None else f"±{100 * cv:.0f}%"


def main(paths):
    if not paths:
        print(__doc__)
        return 2
    data = {}
    errors = {}
    order = []
    for p in paths:
        t, res, err = load(p)
        data[t] = res
        for name in res:
            if name not in order:
                order.append(name)
        for name, msg in err.items():
            errors[(name, t)] = msg
    threads = sorted(data)
    if not order:
        print("no results with a particle_steps_per_s counter in: " + " ".join(paths))
        return 1

    w = max(len(n) for n in order)
    print(f"particle-steps/s [M/s], median over repetitions ({', '.join(os.path.basename(p) for p in paths)})")
    head = f"{'benchmark':<{w}}"
    for t in threads:
        head += f" | {t:>2} thr M/s  cv  "
    if len(threads) >= 2:
        head += f" | x{threads[-1]}/{threads[0]}"
    print(head)
    print("-" * len(head))
    for name in order:
        row = f"{name:<{w}}"
        meds = []
        for t in threads:
            med, cv, _ = data[t].get(name, (None, None, 0))
            meds.append(med)
            row += f" | {fmt_rate(med):>10} {fmt_cv(cv):>5}"
        if len(threads) >= 2:
            a, b = meds[0], meds[-1]
            row += f" | {b / a:6.2f}" if a and b else " |      -"
        print(row)

    # P2G ratios: colored vs atomic and serial, same shape and size, same thread count.
    keys = []
    for name in order:
        m = re.match(r"BM_P2G_Colored(<[^>]*>/\d+)$", name)
        if m:
            keys.append(m.group(1))
    if keys:
        print()
        kw = max(len(k) for k in keys + ["P2G <shape>/N"])
        cols = [(other, t, f"col/{abbr} {t}thr")
                for other, abbr in (("Atomic", "atom"), ("Serial", "ser")) for t in threads]
        head = f"{'P2G <shape>/N':<{kw}}" + "".join(f" | {label}" for _, _, label in cols)
        print(head)
        print("-" * len(head))
        for k in keys:
            row = f"{k:<{kw}}"
            for other, t, label in cols:
                c = data[t].get("BM_P2G_Colored" + k, (None,))[0]
                o = data[t].get(f"BM_P2G_{other}" + k, (None,))[0]
                row += f" | {c / o:>{len(label)}.2f}" if c and o else f" | {'-':>{len(label)}}"
            print(row)

    if errors:
        print()
        for (name, t), msg in errors.items():
            print(f"ERROR {name} ({t} thr): {msg}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
