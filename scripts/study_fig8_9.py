#!/usr/bin/env python3
"""Mean amplitude and asymmetry vs chi over a grid of initial conditions (bifurcation).

    python scripts/study_fig8_9.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig8_9``; the values are in configs/fig8_9.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig8_9", *sys.argv[1:]], prog="study_fig8_9.py"))
