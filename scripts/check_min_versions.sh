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
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check uv
"$VENV/bin/python" -m uv pip install --quiet --python "$VENV/bin/python" --resolution lowest-direct -e ".[test]"
echo "check_min_versions: Python $("$VENV/bin/python" -c 'import sys; print(sys.version.split()[0])'), lowest direct dependencies:"
"$VENV/bin/python" -m uv pip freeze --python "$VENV/bin/python" \
  | grep -i -E '^(fmpy|numpy|scipy|matplotlib|tqdm|dask|distributed|xarray|h5netcdf|h5py|tomli.w|pytest|hypothesis|fmu.manipulation.toolbox|libcosimpy)==' \
  | tr '\n' ' '
echo
DFO_FMU="$FMU" MPLBACKEND=Agg "$VENV/bin/python" -m pytest -q -p no:cacheprovider -m min_versions
