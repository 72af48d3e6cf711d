#!/usr/bin/env bash
# Fresh Debian machine to first results: install what is missing, build Release, run
# cases/quickstart.toml, say where the results are.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_TARGET=shockmpm source "$ROOT/scripts/setup.sh"
cd "$ROOT"
"$BUILD_DIR/shockmpm" run cases/quickstart.toml --out out/quickstart --overwrite "$@"
echo "open out/quickstart/fields/particles.xdmf in ParaView; series in out/quickstart/*.csv, run summary in out/quickstart/run.json"
/usr/bin/python3 scripts/figures.py out/quickstart --time-ns 100 > /dev/null && echo "figures in out/quickstart/figures/"
