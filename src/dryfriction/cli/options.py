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
from typing import TYPE_CHECKING, Any, NoReturn

from ..budget import DEFAULT_MAX_WORK, EXACT_PERIOD_STEPS, check_work, continuation_work, fmt
from ..errors import UsageError

if TYPE_CHECKING:
    from ..params import Oscillator

__all__ = ["UsageError", "Parser", "make_parser", "number", "count", "path_arg", "EXIT_USAGE", "PHYSICAL",
           "add_max_work_argument", "command_work", "check_command"]

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


#: the physical options (their argparse dests) of the commands that take an oscillator in SI units
PHYSICAL = ("m", "k", "c", "P0", "f", "omega", "N", "mu_s", "mu_k", "x0", "v0")


def _physical_options(g: Any, required: bool, frequency: bool = True) -> None:
    """--m --k (--c | --zeta) --P0 (--f | --omega) --N --mu-s --mu-k --x0 --v0 (SI units)."""
    req = " (required)" if required else ""
    g.add_argument("--m", type=number("--m", 0.0, True), required=required, help=f"mass, kg{req}")
    g.add_argument("--k", type=number("--k", 0.0), required=required, help=f"stiffness, N/m{req}")
    g.add_argument("--c", type=number("--c", 0.0), default=None, help="viscous damping, N s/m (or --zeta)")
    if required:
        g.add_argument("--zeta", type=number("--zeta", 0.0), default=None,
                       help="damping ratio c / (2 sqrt(k m)) (or --c; default 0)")
    g.add_argument("--P0", type=number("--P0"), required=required, help=f"excitation amplitude, N{req}")
    if frequency:
        g.add_argument("--f", type=number("--f", 0.0), default=None, help="excitation frequency, Hz (or --omega)")
        g.add_argument("--omega", type=number("--omega", 0.0), default=None, help="excitation frequency, rad/s")
    g.add_argument("--N", type=number("--N", 0.0), required=required, help=f"normal force, N{req}")
    g.add_argument("--mu-s", type=number("--mu-s", 0.0), required=required, help=f"static friction coefficient{req}")
    g.add_argument("--mu-k", type=number("--mu-k", 0.0), default=None,
                   help="kinetic friction coefficient (default: mu_s)")
    g.add_argument("--x0", type=number("--x0"), default=0.0, help="initial position, m (default 0)")
    g.add_argument("--v0", type=number("--v0"), default=0.0, help="initial velocity, m/s (default 0)")


def _physical(args: argparse.Namespace, omega: float | None = None) -> Oscillator:
    """The oscillator the physical options of ``args`` give (--f or --omega, or ``omega``)."""
    from ..params import Oscillator

    if args.c is not None and args.zeta is not None:
        raise UsageError("give the damping as --c or --zeta, not both")
    f = getattr(args, "f", None)
    om = getattr(args, "omega", None) if omega is None else omega
    if f is not None and om is not None:
        raise UsageError("give the excitation frequency as --f (Hz) or --omega (rad/s), not both")
    if f is None and om is None:
        raise UsageError("the excitation frequency is missing: --f HZ or --omega RAD_PER_S")
    missing = [o for o, v in (("--m", args.m), ("--k", args.k), ("--P0", args.P0), ("--N", args.N),
                              ("--mu-s", args.mu_s)) if v is None]
    if missing:
        raise UsageError(f"physical units need {', '.join(missing)} too")
    try:
        return Oscillator.physical(m=args.m, k=args.k, c=args.c, zeta=args.zeta, P0=args.P0, f=f, omega=om,
                                   N=args.N, mu_s=args.mu_s, mu_k=args.mu_k, x0=args.x0, v0=args.v0)
    except ValueError as e:
        raise UsageError(str(e)) from None


# ---- the work bound of a command (dryfriction.budget) ------------------------------------------

def add_max_work_argument(p: object, default: object = None) -> None:
    """``--max-work STEPS`` on a command's parser (``default``: argparse.SUPPRESS on subcommands
    that share it with the main parser)."""
    p.add_argument("--max-work", type=number("--max-work", 0.0, True), default=default, metavar="STEPS",  # type: ignore[attr-defined]
                   help=f"refuse work estimated above STEPS internal steps (default {DEFAULT_MAX_WORK:.0e}; "
                        f"an exact-scheme period counts {EXACT_PERIOD_STEPS:g})")


def _steps_per_period(args: object, default: float) -> float:
    """A command's steps per excitation period: the exact scheme's count, ``--steps-per-period``."""
    if str(getattr(args, "scheme", "") or "") == "exact":
        return EXACT_PERIOD_STEPS
    return float(getattr(args, "steps_per_period", None) or default)


def command_work(args: object) -> tuple[float, str] | None:
    """The estimated work (steps) of a parsed command and what it is made of; None for a command
    that does no bounded-size work of its own (``scenes``, ``validate``)."""
    a: object = args
    cmd = getattr(a, "command", None)
    g = lambda name, default=None: getattr(a, name, default) if getattr(a, name, None) is not None else default  # noqa: E731
    if cmd == "response":
        from ..params import Oscillator
        from ..analysis.response import response_work

        num = int(g("num", 41))
        method = g("method") or ("orbit" if g("scheme") in (None, "exact") else "transient")
        p = Oscillator(m=1.0, k=1.0, omega=1.0)
        return response_work(p, num, method, period=int(g("period", 1)), max_periods=int(g("max_periods", 8192)),
                             scheme=g("scheme"))
    if cmd == "run":
        spp = EXACT_PERIOD_STEPS if g("scheme") == "exact" else float(g("steps_per_period", 1000))
        periods = float(g("periods", 30.0)) + 1.0
        return periods * spp, f"{fmt(periods)} periods x {fmt(spp)} steps"
    if cmd == "lyapunov":
        spp = EXACT_PERIOD_STEPS if g("exact", False) else _steps_per_period(a, 1000)
        periods = 2.0 * (int(g("periods", 500)) + int(g("transient", 100)))
        return periods * spp, f"2 runs x {fmt(periods / 2)} periods x {fmt(spp)} steps"
    if cmd == "orbit":
        from ..analysis.orbits import DEFAULT_SPREAD

        n = len(DEFAULT_SPREAD)
        periods = n * (int(g("transients", 60)) + 10) * int(g("period", 1))
        return periods * EXACT_PERIOD_STEPS, f"{n} searches x {fmt(periods / n)} periods x {EXACT_PERIOD_STEPS:g} steps"
    if cmd == "continuation":
        return continuation_work(int(g("max_points", 400)), int(g("max_branches", 8)), int(g("period", 1)))
    if cmd == "bifurcation":
        quick = bool(g("quick", False))
        values = int(g("values", 16 if quick else 80))
        ics = int(g("ics", 5 if quick else 11)) ** 2
        runs = values * ics
        periods = int(g("periods", 30)) + 1
        return runs * periods * 1000.0, f"{fmt(runs)} runs x {periods} periods x 1,000 steps"
    if cmd == "belt":
        spp = EXACT_PERIOD_STEPS if g("scheme") == "exact" else float(g("steps_per_period", 2000))
        periods = float(g("periods", 40.0)) * 3.0   # the transient, the orbit's search and its cycle
        return periods * spp, f"about {fmt(periods)} periods x {fmt(spp)} steps"
    if cmd == "chain":
        n = int(g("n", 2) or 2)
        t_end, dt = float(g("t_end", 20.0)), float(g("dt", 0.05))
        h = None
        for item in g("sets", []) or []:
            name, _, text = str(item).partition("=")
            if name.strip() == "h":
                try:
                    h = float(text)
                except ValueError:
                    h = None
        per_dt = max(dt / h, 1.0) if h and h > 0 else 100.0
        steps = t_end / dt * per_dt * n
        return steps, f"{n} blocks x {fmt(t_end / dt)} communication steps x {fmt(per_dt)} internal steps"
    return None


def check_command(args: object) -> None:
    """Refuse a parsed command whose estimated work exceeds ``--max-work`` (before any work)."""
    est = command_work(args)
    if est is not None:
        check_work(est[0], est[1], getattr(args, "max_work", None))
