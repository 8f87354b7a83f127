#!/bin/sh
# Install DOLFINx 0.5.2 (Debian python3-dolfinx, system python3, separate from the project venv)
# and run the solidshell <-> DOLFINx cross-check (docs/fenicsx.md).
#   sh verification/fenicsx/install_and_run.sh [OUT_DIR] [crosscheck options, e.g. --quick]
# Needs root (apt-get) and network; takes a few minutes to install, ~1 h to run on 2 busy cores.
set -e
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
OUT=${1:-$ROOT/verification/out/fenicsx}
[ $# -gt 0 ] && shift
if ! /usr/bin/python3 -c "import dolfinx" 2>/dev/null; then
    apt-get update
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3-dolfinx
fi
PY=${SOLIDSHELL_PYTHON:-$ROOT/.venv/bin/python}
[ -x "$PY" ] || PY=/work/main/.venv/bin/python
cd "$ROOT"
exec "$PY" -m verification.fenicsx.crosscheck --out "$OUT" "$@"
