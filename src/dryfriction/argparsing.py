"""The one argument parser of the package's commands and scripts: a bad argument is one readable
line (``prog: error: message``) and exit status 2, never a usage dump or a traceback.

    p = make_parser("dryfriction study", "...")           # error() raises UsageError
    p = make_parser("bench_sweep.py", "...", exit=True)   # error() prints the line and exits 2
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, NoReturn

__all__ = ["UsageError", "Parser", "make_parser", "EXIT_USAGE"]

EXIT_USAGE = 2


class UsageError(ValueError):
    """An invalid argument or configuration value: reported as one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    """argparse with a one-line error: raised as :class:`UsageError`, or (``exit_on_error``)
    printed as ``prog: error: message`` before exit status 2."""

    def __init__(self, *args: Any, exit_on_usage_error: bool = False, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.exit_on_usage_error = exit_on_usage_error

    def error(self, message: str) -> NoReturn:
        if self.exit_on_usage_error:
            sys.stderr.write(f"{self.prog}: error: {message}\n")
            raise SystemExit(EXIT_USAGE)
        raise UsageError(message)


def make_parser(prog: str, description: str | None = None, *, exit: bool = False, **kwargs: Any) -> Parser:
    """A :class:`Parser`; ``exit=True`` for scripts that end on a bad argument."""
    return Parser(prog=prog, description=description, exit_on_usage_error=exit, **kwargs)
