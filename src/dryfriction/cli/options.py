"""The one argument parser of the package's commands and scripts: a bad argument is one readable
line (``prog: error: message``) and exit status 2, never a usage dump or a traceback.

    p = make_parser("dryfriction study", "...")           # error() raises UsageError
    p = make_parser("bench_sweep.py", "...", exit=True)   # error() prints the line and exits 2
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

from ..errors import UsageError

__all__ = ["UsageError", "Parser", "make_parser", "number", "count", "path_arg", "EXIT_USAGE"]

EXIT_USAGE = 2


class Parser(argparse.ArgumentParser):
    """argparse with a one-line error: raised as :class:`UsageError`, or (``exit_on_error``)
    printed as ``prog: error: message`` before exit status 2. An option it does not know is
    reported first, with the closest valid one (``unknown option --f-strat; did you mean
    --f-start?``), before a missing required option or any other error it causes."""

    def __init__(self, *args: Any, exit_on_usage_error: bool = False, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.exit_on_usage_error = exit_on_usage_error

    def parse_known_args(self, args: Sequence[str] | None = None,  # type: ignore[override]
                         namespace: argparse.Namespace | None = None) -> tuple[argparse.Namespace, list[str]]:
        """Parse the arguments, first refusing an unknown option with the closest valid one named."""
        arg_list = list(sys.argv[1:] if args is None else args)
        self._refuse_unknown(arg_list)     # first: argparse would report a missing option instead
        return super().parse_known_args(arg_list, namespace)

    def _unknown(self, args: Sequence[str]) -> str | None:
        """The first option in ``args`` this parser does not know (before ``--``), or None."""
        longs = [o for o in self._option_string_actions if o.startswith("--")]
        commands = {c for a in self._actions if isinstance(a, argparse._SubParsersAction) for c in a.choices}
        for a in args:
            if a == "--" or a in commands:   # the rest is the subcommand's (its parser checks it)
                return None
            if len(a) < 2 or a[0] not in self.prefix_chars or self._negative_number_matcher.match(a) or " " in a:
                continue
            name = a.split("=", 1)[0]
            if name in self._option_string_actions:
                continue
            if self.allow_abbrev and name.startswith("--") and any(o.startswith(name) for o in longs):
                continue                 # an abbreviation argparse takes (or reports as ambiguous)
            return name
        return None

    def _refuse_unknown(self, args: Sequence[str]) -> None:
        import difflib

        name = self._unknown(args)
        if name is None:
            return
        # compared without the dashes, which every option shares
        known = {o.lstrip(self.prefix_chars): o for o in self._option_string_actions}
        close = difflib.get_close_matches(name.lstrip(self.prefix_chars), list(known), n=1, cutoff=0.6)
        hint = f"; did you mean {known[close[0]]}?" if close else f" ({self.prog} --help lists the options)"
        self.error(f"unknown option {name}{hint}")

    def error(self, message: str) -> NoReturn:
        # argparse's "argument --m: --m must be > 0, not -1": the option is named once
        """Report a usage error in one line: a :class:`~dryfriction.errors.UsageError`, or the line on stderr
        and exit status 2."""
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


def path_arg(name: str, what: str = "folder") -> Callable[[str], Path]:
    """An argparse type: a path that names something (``''`` is refused: it would mean the
    current folder without a word)."""
    def conv(text: str) -> Path:
        if not text.strip():
            raise argparse.ArgumentTypeError(f"{name} must name a {what}, not {text!r}")
        return Path(text)

    return conv
