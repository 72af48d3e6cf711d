#!/usr/bin/env python3
"""Code-shape figures for engine/ and kernels/.

1. Functions longer than 80 lines: each function definition that ctags (universal-ctags)
   reports, from its first line to its end line, lambdas inside it included.
2. Hand-spelled component lines: a line counts when, with comments and string literals
   removed, it holds an identifier that names one axis component by hand: x, y, z, vx, vy,
   nx, ny, sx, sy, or a name that is a known field or key with an axis suffix or prefix (sxx,
   Lxy, Cyx, gmx, dvy, px, fy, x0, y0, xmin, ymax, xg, yg, dwx, wy, bx, by, gravity_x, x_range,
   periodic_x, length_y, tiles_x, ...: the regular expression AXIS below), unless it is indexed
   by an axis (x[d], xg[kDim]: d, e, r, c, a, k, K, D, kDim or kDim * kDim in the brackets). Loops over axes
   (pos(d), v[d]) do not count.

  python3 scripts/code_metrics.py           # both figures
  python3 scripts/code_metrics.py --list    # every counted component line and long function
"""
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DIRS = ["engine", "kernels"]
LIMIT = 80
AXIS = re.compile(
    r"\b(?:[xyz]|v[xyz]|n[xyz]|s[xy]|[xyz]0|[xyz]1|[xyz]g|[xyz]n|d?w[xyz]|b[xyz]|c[xyz]|e[xyz]|u[xyz]|"
    r"[xyz](?:min|max)|s[xyz][xyz]|[LCDWdm]?[xyz][xyz]|[LC][xyz][xyz]|[pfg]m?[xyz]|dv[xyz]|gm[xyz]|g[xyz]|"
    r"[a-z_]+_[xyz]|[xyz]_[a-z_]+|[a-z]+[xyz][xyz]p?|[a-z]+_[xyz][xyz])\b")


AXIS_INDEX = re.compile(r"\s*\[\s*(?:d|e|r|c|a|k|K|D|(?:kern::)?kDim(?:\s*\*\s*(?:kern::)?kDim)?)\s*\]")


def strip(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    text = re.sub(r"'(?:\\.|[^'\\])*'", "''", text)
    return text


def files():
    for d in DIRS:
        for f in sorted((ROOT / d).rglob("*")):
            if f.suffix in (".hpp", ".cpp", ".h"):
                yield f


def long_functions():
    out = subprocess.run(["ctags", "--c++-kinds=f", "--fields=+ne", "--sort=no", "-o", "-"] +
                         [str(f) for f in files()], capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        parts = line.split("\t")
        m = re.search(r"\bend:(\d+)", line)
        ln = re.search(r"\bline:(\d+)", line)
        if not m or not ln:
            continue
        start = int(ln.group(1))
        n = int(m.group(1)) - start + 1
        if n > LIMIT:
            rows.append((n, Path(parts[1]).relative_to(ROOT), parts[0], start))
    return sorted(rows, reverse=True)


def axis_lines():
    rows = []
    for f in files():
        for i, line in enumerate(strip(f.read_text()).splitlines(), 1):
            if any(not AXIS_INDEX.match(line, mt.end()) for mt in AXIS.finditer(line)):
                rows.append((f.relative_to(ROOT), i, line.strip()))
    return rows


def main():
    lst = "--list" in sys.argv
    longf = long_functions()
    ax = axis_lines()
    total = sum(len(strip(f.read_text()).splitlines()) for f in files())
    print(f"functions over {LIMIT} lines: {len(longf)}")
    for n, f, name, start in longf:
        print(f"  {n:4d}  {f}:{start}  {name}")
    print(f"hand-spelled component lines: {len(ax)} of {total} lines in {', '.join(DIRS)}")
    if lst:
        for f, i, line in ax:
            print(f"  {f}:{i}: {line}")


if __name__ == "__main__":
    main()
