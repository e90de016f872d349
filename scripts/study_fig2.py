#!/usr/bin/env python3
"""FMU vs exact solution over the first cycle (z, z', z'').

    python scripts/study_fig2.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig2``; the values are in configs/fig2.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig2", *sys.argv[1:]], prog="study_fig2.py"))
