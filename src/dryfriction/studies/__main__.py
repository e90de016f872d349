"""``python -m dryfriction.studies <name> [options]``: see :func:`dryfriction.studies.main`."""

import sys

from . import main

if __name__ == "__main__":
    sys.exit(main(prog="python -m dryfriction.studies"))
