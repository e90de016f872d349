#!/usr/bin/env bash
# The main job, from a fresh clone: set up, build the FMU, validate it against the exact
# solution (prints errors and orders, writes results/validation.csv and results/validation.png).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/dryfriction validate --out results "$@"
