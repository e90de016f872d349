"""``python -m dryfriction.studies <name> [options]``: the same as ``dryfriction study``
(:func:`dryfriction.cli.study.main`)."""

import sys

from ..cli.study import main

if __name__ == "__main__":
    sys.exit(main(prog="python -m dryfriction.studies"))
