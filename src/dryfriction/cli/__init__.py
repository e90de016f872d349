"""The command line ``dryfriction`` (the console script and ``python -m dryfriction``).

``main()`` without arguments is the program: the signal handlers first
(:func:`dryfriction.cli.console.main`), then the command; ``main(argv)`` runs the command line
``argv`` and returns its exit status (:func:`dryfriction.cli.main.main`). Importing the package
imports nothing heavy: a command's modules are imported when it runs.
"""

from __future__ import annotations

import sys
import types
from collections.abc import Sequence

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` and return its exit status; without ``argv`` the program
    itself (the console script), which exits."""
    if argv is None:
        from .console import main as program

        program()
    from .main import main as run

    return run(argv)


class _Package(types.ModuleType):
    """``dryfriction.cli.main`` stays the function above once the submodule ``main`` is imported
    (importing a submodule binds it on its package; the submodule is ``sys.modules[...]``)."""

    def __setattr__(self, name: str, value: object) -> None:
        if name == "main" and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
