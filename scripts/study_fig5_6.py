#!/usr/bin/env python3
"""Unbounded growth at resonance (4 mu_k N < pi P0) and beating near it.

    python scripts/study_fig5_6.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig5_6``; the values are in configs/fig5_6.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig5_6", *sys.argv[1:]], prog="study_fig5_6.py"))
