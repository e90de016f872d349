"""python -m dryfriction: the command line (dryfriction.cli)."""

from .cli import main

raise SystemExit(main())
