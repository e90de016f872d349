"""python -m dryfriction: the command line (dryfriction.console, then dryfriction.cli)."""

from .console import main

main()
