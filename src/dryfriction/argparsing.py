"""The one argument parser of the package's commands and scripts: a bad argument is one readable
line (``prog: error: message``) and exit status 2, never a usage dump or a traceback.

    p = make_parser("dryfriction study", "...")           # error() raises UsageError
    p = make_parser("bench_sweep.py", "...", exit=True)   # error() prints the line and exits 2
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from typing import Any, NoReturn

__all__ = ["UsageError", "Parser", "make_parser", "number", "count", "EXIT_USAGE"]

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
        # argparse's "argument --m: --m must be > 0, not -1": the option is named once
        head, sep, rest = message.partition(": ")
        if sep and head.startswith("argument ") and rest.startswith(head[len("argument "):].split("/")[0] + " "):
            message = rest
        if self.exit_on_usage_error:
            sys.stderr.write(f"{self.prog}: error: {message}\n")
            raise SystemExit(EXIT_USAGE)
        raise UsageError(message)


def make_parser(prog: str, description: str | None = None, *, exit: bool = False, **kwargs: Any) -> Parser:
    """A :class:`Parser`; ``exit=True`` for scripts that end on a bad argument."""
    return Parser(prog=prog, description=description, exit_on_usage_error=exit, **kwargs)


def number(name: str, lo: float | None = None, lo_open: bool = False,
           hi: float | None = None) -> Callable[[str], float]:
    """An argparse type: a finite float, >= lo (> lo when lo_open) and < hi where given; the error
    names the option and the valid range."""
    def conv(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, not {text!r}") from None
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{name} must be finite, not {text}")
        if lo is not None and (v <= lo if lo_open else v < lo):
            raise argparse.ArgumentTypeError(f"{name} must be {'>' if lo_open else '>='} {lo:g}, not {text}")
        if hi is not None and v >= hi:
            raise argparse.ArgumentTypeError(f"{name} must be < {hi:g}, not {text}")
        return v

    return conv


def count(name: str, lo: int = 1) -> Callable[[str], int]:
    """An argparse type: a whole number >= lo."""
    def conv(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a whole number, not {text!r}") from None
        if v < lo:
            raise argparse.ArgumentTypeError(f"{name} must be >= {lo}, not {text}")
        return v

    return conv
