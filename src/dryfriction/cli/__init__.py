"""The command line ``dryfriction COMMAND [options]``: validate, run, response, scenes, lyapunov,
chain, continuation, bifurcation, orbit, belt, system, study.

    dryfriction --help                      # the commands; 'dryfriction COMMAND --help' for one
    python -m dryfriction ...               # the same

One module of this package per command (:data:`COMMANDS`), each with one convention:
``add_parser(subparsers, parents)`` adds its subcommand(s) to the main parser (argparse only: the
module imports nothing heavy at its top, so that ``--help`` is immediate), ``run(args) -> int``
runs it and imports what it uses, and, for a command that does work of a size its arguments tell,
``work(args) -> (steps, what)`` estimates it before it starts (:mod:`dryfriction.budget`). No
command module imports another: what several share is in :mod:`.options` (the parser, the
oscillator's options) and :mod:`.output` (numbers as the commands print them); the process
(signals, result sets, FMU warnings) is :mod:`.console`.

Invalid arguments, an unusable FMU and an error the FMU reports end with one readable line on
stderr (``dryfriction: error: ...``) and exit status 2, before any work where they can be found
before it. Every warning an FMU logs is one line on stderr (``dryfriction: warning: ...``);
``--strict`` makes it an error. A command's files are written all or nothing, an unusable ``--out``
is refused before the work, and Ctrl-C prints one line and exits 130 (:mod:`.console`).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from importlib import import_module
from types import ModuleType

from .options import Parser, global_options, make_parser

__all__ = ["main", "build_parser", "command_work", "COMMANDS"]

#: command -> its module in this package (in the order of the help; one module may define two)
COMMANDS = {"validate": "validate", "run": "run", "response": "response", "scenes": "scenes",
            "lyapunov": "lyapunov", "chain": "chain", "continuation": "continuation",
            "bifurcation": "continuation", "orbit": "orbit", "belt": "belt", "system": "system",
            "study": "study"}


def _module(name: str) -> ModuleType:
    return import_module(f"{__name__}.{name}")


def build_parser() -> Parser:
    """The main parser with every command's subparser."""
    from .. import __version__

    p = make_parser("dryfriction", "Dry-friction oscillator FMU: validation, scenes and studies.",
                    parents=[global_options(False)])
    p.add_argument("--version", action="version", version=f"dryfriction {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND",
                           help="the command ('dryfriction COMMAND --help' for its options)")
    common = [global_options(True)]
    for name in dict.fromkeys(COMMANDS.values()):
        _module(name).add_parser(sub, common)
    return p


def command_work(args: argparse.Namespace) -> tuple[float, str] | None:
    """The estimated work (steps) of a parsed command and what it is made of; None for a command
    that does no bounded-size work of its own (``scenes``, ``validate``)."""
    work = getattr(_module(COMMANDS[args.command]), "work", None)
    return None if work is None else work(args)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` and return its exit status: 0, 1 (the system refused, e.g. a
    full disk, or the Dask workers were lost too often), 2 (bad input, an unusable FMU, an error the
    FMU reports, work above --max-work), 130 (interrupted), 141 (output into a closed pipe); every
    error one line ``dryfriction: error: ...`` (:func:`.console.guarded`). Without ``argv`` this is
    the program itself, the console script ``dryfriction`` (:func:`.console.main`, which exits)."""
    from .console import guarded

    if argv is None:
        from .console import main as program

        program(main)
    args_list = list(argv or [])
    return guarded(lambda: _run(args_list))


def _run(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    args.fmu = getattr(args, "fmu", None)
    args.max_work = getattr(args, "max_work", None)
    from ..budget import check_work

    est = command_work(args)  # the work estimated from the arguments, refused above --max-work
    if est is not None:
        check_work(est[0], est[1], args.max_work)
    if args.fmu is not None:
        from .options import check_fmu_option

        check_fmu_option(args.fmu, args.command)
    from .console import fmu_warnings_on_stderr

    with fmu_warnings_on_stderr("dryfriction", bool(getattr(args, "strict", False))):
        return int(_module(COMMANDS[args.command]).run(args))
