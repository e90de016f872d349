#!/usr/bin/env python3
"""Stick-slip fronts along a chain of 256 blocks, the first forced: the space-time image of the modes.

    python scripts/study_chain_waves.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study chain_waves``; the values are in configs/chain_waves.toml. The FMU is the FMI 3.0
chain (build/fmi3/DryFrictionChain.fmu).
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["chain_waves", *sys.argv[1:]], prog="study_chain_waves.py"))
