#!/usr/bin/env python3
"""Time histories, phase portraits and diverging nearby initial conditions (sub-harmonic zone).

    python scripts/study_fig12_14.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig12_14``; the values are in configs/fig12_14.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig12_14", *sys.argv[1:]], prog="study_fig12_14.py"))
