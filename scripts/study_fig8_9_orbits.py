#!/usr/bin/env python3
"""The Fig. 8/9 band solved: branches of periodic orbits in chi over the scatter, bifurcations vs brute force.

    python scripts/study_fig8_9_orbits.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig8_9_orbits``; the values are in configs/fig8_9_orbits.toml (on top of configs/fig8_9.toml).
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig8_9_orbits", *sys.argv[1:]], prog="study_fig8_9_orbits.py"))
