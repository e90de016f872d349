"""python -m dryfriction: the command line (:func:`dryfriction.cli.main`)."""

from .cli import main

main()
