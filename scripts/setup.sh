#!/usr/bin/env bash
# Set up everything on a fresh machine (Python 3.11+, pip, gcc, cmake): a virtual environment in
# .venv with the package, its test tools and its docs tools (uv pip install -e ".[test,docs]"), and
# the FMUs built by CMake into build/.
# The editable install compiles nothing (pyproject.toml: scikit-build-core puts src/ on sys.path);
# the package finds the FMUs in build/ (dryfriction.paths). A wheel with the FMUs inside:
# pip wheel . (docs/getting_started.md).
# Usage: bash scripts/setup.sh        (idempotent; later runs only rebuild what changed)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
rm -rf src/dryfriction.egg-info  # a setuptools editable install's metadata would shadow this one
# uv (installed into .venv by pip) installs the package and its tools from its cache
# (~/.cache/uv): seconds once the wheels are there, where pip downloads them all again; pip does the
# install if uv cannot be had.
if .venv/bin/python -m uv --version >/dev/null 2>&1 ||
   .venv/bin/python -m pip install --quiet --disable-pip-version-check uv >/dev/null 2>&1; then
  .venv/bin/python -m uv pip install --quiet --python .venv/bin/python -e ".[test,docs]"
else
  .venv/bin/python -m pip install --quiet --disable-pip-version-check -e ".[test,docs]"
fi
# Where the environment forbids writing bytecode (PYTHONDONTWRITEBYTECODE), every Python process would
# compile numpy, scipy, xarray, dask and the package again at each import (about 1 s a process: the
# CLI, the Dask workers, the tests' subprocesses); compiled once here instead (what pip does by default).
if [ -n "${PYTHONDONTWRITEBYTECODE:-}" ]; then
  .venv/bin/python -m compileall -q -j 0 .venv/lib/python*/site-packages src >/dev/null 2>&1 || true
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE="$PWD/.venv/bin/python" >/dev/null
cmake --build build -j"$(nproc)" >/dev/null
echo "setup: .venv ready (source .venv/bin/activate puts dryfriction on PATH), FMUs in build/ and build/fmi3/"
