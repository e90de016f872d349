#!/usr/bin/env python3
"""Two blocks, the first forced: amplitude and stick share of each block against the frequency ratio.

    python scripts/study_chain2.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study chain2``; the values are in configs/chain2.toml. The FMU is the FMI 3.0
chain (build/fmi3/DryFrictionChain.fmu).
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["chain2", *sys.argv[1:]], prog="study_chain2.py"))
