#!/usr/bin/env python3
"""Frequency-response curves for several chi over a grid of initial conditions.

    python scripts/study_fig10_11.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig10_11``; the values are in configs/fig10_11.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig10_11", *sys.argv[1:]], prog="study_fig10_11.py"))
