#!/usr/bin/env bash
# Check the declared minimum versions: a throw-away virtual environment gets the LOWEST versions
# pyproject.toml allows for the direct dependencies (uv's --resolution lowest-direct, test tools
# included), then the quick, representative subset of the tests (pytest -m min_versions) runs
# against the built FMU. A failure means a declared minimum is too low.
# Usage: bash scripts/check_min_versions.sh      (needs the FMU: bash scripts/setup.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
FMU=${DFO_FMU:-$PWD/build/DryFrictionOscillator.fmu}
if [ ! -f "$FMU" ]; then
  echo "check_min_versions: FMU not built: $FMU (run bash scripts/setup.sh)" >&2
  exit 2
fi
VENV=$(mktemp -d "${TMPDIR:-/tmp}/dfo-minversions.XXXXXX")
trap 'rm -rf "$VENV"' EXIT
"$PY" -m venv "$VENV"
# uv: .venv's (scripts/setup.sh installs it) where it is there, else one installed into the throw-away venv
if [ -x .venv/bin/python ] && .venv/bin/python -m uv --version >/dev/null 2>&1; then
  UV=(.venv/bin/python -m uv)
else
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check uv
  UV=("$VENV/bin/python" -m uv)
fi
"${UV[@]}" pip install --quiet --python "$VENV/bin/python" --resolution lowest-direct -e ".[test]"
echo "check_min_versions: Python $("$VENV/bin/python" -c 'import sys; print(sys.version.split()[0])'), lowest direct dependencies:"
"${UV[@]}" pip freeze --python "$VENV/bin/python" \
  | grep -i -E '^(fmpy|numpy|scipy|matplotlib|tqdm|dask|distributed|xarray|h5netcdf|h5py|tomli.w|pytest|hypothesis|fmu.manipulation.toolbox|libcosimpy)==' \
  | tr '\n' ' '
echo
# only the modules that hold the subset are collected
mapfile -t FILES < <(grep -l "min_versions" tests/test_*.py)
DFO_FMU="$FMU" MPLBACKEND=Agg "$VENV/bin/python" -m pytest -q -p no:cacheprovider -m min_versions "${FILES[@]}"
