#!/usr/bin/env python3
"""Percentage stiction time in the 30th cycle vs frequency ratio, ten friction levels.

    python scripts/study_fig7.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig7``; the values are in configs/fig7.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig7", *sys.argv[1:]], prog="study_fig7.py"))
