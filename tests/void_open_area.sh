#!/usr/bin/env bash
# The single void by volume: bench/void_open_area.py at h = 4 um, the area left open at 20 ns
# (points' volumes against the strip's area, less the dense block's) within +-7 % of the void's
# initial area (negative: the faces overlap; a scheme that overlaps the faces fails it as well
# as one that leaves them open). Measured -5.0 % with the weld at 0.9 (0.85 -3.0 %, 0.8 -1.2 %;
# docs/verification.md). The bound is 7 %, not 5 %, because the measured value sits at -4.97 %,
# where the ISA or a compiler's rounding could flip the test, and the weld threshold that sets
# it is kept for the strip (docs/method.md).
# Release only (about 2 s).
#   tests/void_open_area.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
/usr/bin/python3 "$SRC/bench/void_open_area.py" --driver "$EXE" --out "$TMP" --h 4 --times 16,20 --check 7
