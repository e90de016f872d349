#!/usr/bin/env python3
"""Steady-state frequency response from rest vs Inman and Den Hartog.

    python scripts/study_fig3.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig3``; the values are in configs/fig3.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig3", *sys.argv[1:]], prog="study_fig3.py"))
