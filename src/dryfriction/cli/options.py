"""The one argument parser of the package's commands and scripts: a bad argument is one readable
line (``prog: error: message``) and exit status 2, never a usage dump or a traceback; and the
options several commands share: ``--fmu --strict --max-work`` (:func:`global_options`), the
oscillator in physical units (:data:`PHYSICAL`, :func:`physical_options`,
:func:`~dryfriction.cli.options.physical`) or in the paper's non-dimensional form (:func:`nondim_options`).

    p = make_parser("dryfriction study", "...")           # error() raises UsageError
    p = make_parser("bench_sweep.py", "...", exit=True)   # error() prints the line and exits 2

This module imports only the standard library at its top: ``dryfriction --help`` builds every
command's parser.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

from ..errors import UsageError

__all__ = ["UsageError", "Parser", "make_parser", "number", "count", "path_arg", "EXIT_USAGE", "global_options",
           "add_max_work_argument", "SCHEMES", "DEFAULT_SCHEME", "PHYSICAL", "NONDIM", "physical_options",
           "nondim_options", "physical_given", "physical", "nondim_given", "one_form", "check_fmu_option"]

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


# ---- the options several commands share --------------------------------------------------------

def global_options(suppress: bool) -> argparse.ArgumentParser:
    """The options every command accepts, before or after its name (``--fmu``, ``--strict``,
    ``--max-work``). On the commands the default is SUPPRESS, so that a value given before the
    command's name is kept."""
    g = argparse.ArgumentParser(add_help=False)
    default = argparse.SUPPRESS if suppress else None
    g.add_argument("--fmu", type=Path, default=default,
                   help="path of the FMU (default: $DFO_FMU, else the installed package's, else build/)")
    g.add_argument("--strict", action="store_true", default=default,
                   help="a warning of the FMU (e.g. a step too coarse for the dynamics) is an error: exit 2")
    add_max_work_argument(g, default)
    return g


def add_max_work_argument(p: argparse.ArgumentParser, default: Any = None) -> None:
    """``--max-work STEPS`` on a parser (``default``: argparse.SUPPRESS on the commands, which share
    it with the main parser; :mod:`dryfriction.budget`)."""
    from ..budget import DEFAULT_MAX_WORK, EXACT_PERIOD_STEPS

    p.add_argument("--max-work", type=number("--max-work", 0.0, True), default=default, metavar="STEPS",
                   help=f"refuse work estimated above STEPS internal steps (default {DEFAULT_MAX_WORK:.0e}; "
                        f"an exact-scheme period counts {EXACT_PERIOD_STEPS:g})")


#: the FMU's integration schemes and its default one, as its model description has them
#: (:data:`dryfriction.drivers.oscillator.SCHEMES`; read here without opening the FMU, for the help)
SCHEMES = ("paper", "consistent", "located", "exact")
DEFAULT_SCHEME = "located"


#: the oscillator's parameters in physical units (SI), as ``dryfriction run`` & co. take them
PHYSICAL = ("m", "k", "c", "P0", "f", "omega", "N", "mu_s", "mu_k", "x0", "v0")
#: the paper's non-dimensional form
NONDIM = ("lam", "mu_s_sigma", "chi")


def physical_options(g: Any, required: bool, frequency: bool = True) -> None:
    """--m --k (--c | --zeta) --P0 (--f | --omega) --N --mu-s --mu-k --x0 --v0 (SI units) on the
    parser or group ``g``."""
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


def nondim_options(p: argparse.ArgumentParser, title: str, chi_lo_open: bool = False) -> Any:
    """The non-dimensional form (``--lam --mu-s-sigma --chi``, none of them required) in a new
    group named ``title`` of ``p``, returned; ``--chi`` > 0 with ``chi_lo_open``, else >= 0."""
    nd = p.add_argument_group(title)
    nd.add_argument("--lam", type=number("--lam", 0.0, True), default=None, help="frequency ratio omega / w0")
    nd.add_argument("--mu-s-sigma", type=number("--mu-s-sigma", 0.0), default=None, help="mu_s N / P0")
    nd.add_argument("--chi", type=number("--chi", 0.0, chi_lo_open), default=None, help="mu_k / mu_s")
    return nd


def physical_given(args: argparse.Namespace) -> bool:
    """Whether any option of the physical units was given (a nonzero value: 0 is no choice)."""
    return any(getattr(args, n, None) not in (None, 0.0) for n in PHYSICAL if n not in ("x0", "v0")) or \
        args.x0 != 0.0 or args.v0 != 0.0


def physical(args: argparse.Namespace, omega: float | None = None) -> Any:
    """The :class:`~dryfriction.params.Oscillator` of the physical options (``omega``: the frequency
    when the command gives it, not an option); UsageError, one line, when they do not make one."""
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


def nondim_given(args: argparse.Namespace, names: Sequence[str] = NONDIM) -> dict[str, float]:
    """The options of the non-dimensional form given (not None), by name."""
    return {n: getattr(args, n) for n in names if getattr(args, n) is not None}


def one_form(nondim: dict[str, float], first_physical: str | None = None) -> None:
    """Refuse (UsageError) physical units and the non-dimensional form given together."""
    if nondim:
        other = f" and --{first_physical.replace('_', '-')}" if first_physical else ""
        raise UsageError(f"give physical units or the non-dimensional form, not both "
                         f"(--{next(iter(nondim)).replace('_', '-')}{other})")


def check_fmu_option(path: Path, command: str) -> None:
    """An unusable ``--fmu`` refused before any work (one line): the oscillator's FMI 2.0 FMU for
    the oscillator's commands, any of the package's FMUs for a study (each study checks its own
    kind); the chain command checks its own."""
    from .. import paths

    if path.is_dir():
        raise UsageError(f"--fmu: {path} is a directory, not an FMU file")
    if not path.is_file():
        raise UsageError(f"--fmu: no such file: {path}")
    if command in ("chain", "system"):  # each checks its own kind
        return
    if command == "study":
        for kind in paths.KINDS:
            try:
                paths.check_fmu(path, kind)
                return
            except paths.FMUFileError:
                pass
    paths.check_fmu(path, paths.OSCILLATOR)
