#!/usr/bin/env bash
# The quick form of the 3D column's convergence (docs/verification.md): cases/verify/porous_strip_3d.toml
# narrowed to 40 x 40 um across (106 spheres of 10 um, porosity 0.50) and run to 150 ns at h = 5
# and 4 um. No run this cheap meets the one-run check of the 2D strip (tests/strip_closure.sh):
# the full column needs h = 3.125 um for that (docs/method.md, "Void faces in 3D"). So this checks
# the direction: from h = 5 to 4 um the front's distance to the compacted Hugoniot at the swept
# porosity shrinks (measured 32.9 -> 19.8 %) and so does band III's open porosity (9.0 -> 5.2 %);
# energy within 1e-8 in both runs (5e-12). About 20 s on 2 threads; Release only.
#   tests/strip_trend_3d.sh SHOCKMPM SOURCE_DIR
set -uo pipefail
EXE="$1"; SRC="$2"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
/usr/bin/python3 "$SRC/bench/porous_convergence.py" --driver "$EXE" --out "$TMP" \
  --case "$SRC/cases/verify/porous_strip_3d.toml" --h 5,4 --window 60,140 --check-trend \
  --set 'grid.x_range_um=[0.0,40.0]' --set 'grid.z_range_um=[0.0,40.0]' \
  --set 'bodies.0.x_range_um=[0.0,40.0]' --set 'bodies.0.z_range_um=[0.0,40.0]' \
  --set bodies.0.voids.count=106 --set run.end_time_ns=150 --set run.snapshot_interval_ns=150
