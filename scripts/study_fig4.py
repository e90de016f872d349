#!/usr/bin/env python3
"""Four steady-state cycles below and above resonance.

    python scripts/study_fig4.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
        [--set key=value ...] [--config FILE] [--fmu PATH]

The same as ``dryfriction study fig4``; the values are in configs/fig4.toml.
"""

import sys

from dryfriction.studies import main

if __name__ == "__main__":
    sys.exit(main(["fig4", *sys.argv[1:]], prog="study_fig4.py"))
