#!/usr/bin/env bash
# The compaction wave at porosity 0.09 against the fully compacted porous Hugoniot (docs/model.md,
# "The fully compacted porous Hugoniot"): bench/compaction_hugoniot.py at h = 4 um on the 2000 um
# strip, 1000 and 2000 m/s; front speed, stress behind the front and wall stress within 3 %
# (measured: within 1.7 %, docs/accuracy.md). Release only (about 40 s on 2 threads).
#   tests/compaction_quick.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
/usr/bin/python3 "$SRC/bench/compaction_hugoniot.py" --driver "$EXE" --out "$TMP" --h 4 --length-um 2000 \
  --cases 0.09:1000,0.09:2000 --check 3
