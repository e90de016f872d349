#!/usr/bin/env python3
"""Fig. 10/11 as branches of periodic orbits in lambda, with stability, over the scatter.

    python scripts/study_fig10_11_orbits.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig10_11_orbits``; the values are in configs/fig10_11_orbits.toml (on top of configs/fig10_11.toml).
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig10_11_orbits", *sys.argv[1:]], prog="study_fig10_11_orbits.py"))
