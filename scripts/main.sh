#!/usr/bin/env bash
# The main job, from a fresh clone: set up, build the FMUs, validate the oscillator against the exact
# solution (prints errors and orders, writes results/validation.csv and results/validation.png)
# and the chain (FMI 3.0, n = 3) against its event-driven reference on four coupled cases
# (results/chain_validation.csv and .png).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/dryfriction validate --out results "$@"
.venv/bin/python scripts/plot_chain_validation.py --out results/chain_validation.png
