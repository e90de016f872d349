#!/usr/bin/env bash
# Set up everything on a fresh machine (Python 3.11+, pip, gcc, cmake): a virtual environment in
# .venv with the package and its test tools, and the FMUs built by CMake into build/.
# The editable install compiles nothing (pyproject.toml: scikit-build-core puts src/ on sys.path);
# the package finds the FMUs in build/ (dryfriction.locate). A wheel with the FMUs inside:
# pip wheel . (see README.md, Development).
# Usage: bash scripts/setup.sh        (idempotent; later runs only rebuild what changed)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
rm -rf src/dryfriction.egg-info  # left by the former setuptools editable install
.venv/bin/python -m pip install --quiet --disable-pip-version-check -e ".[test]"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE="$PWD/.venv/bin/python" >/dev/null
cmake --build build -j"$(nproc)" >/dev/null
echo "setup: .venv ready (source .venv/bin/activate puts dryfriction on PATH), FMUs in build/ and build/fmi3/"
