"""``dryfriction study``: run a study of the registry (:mod:`dryfriction.studies`), list them, show
a study's effective configuration::

    dryfriction study list
    dryfriction study <name> [--quick] [--out DIR] [--workers N] [--scheduler ADDR]
                             [--set key=value ...] [--config FILE] [--fmu PATH]
    python -m dryfriction.studies <name> ...      # the same (main)

Exit status 0, 1 (the study failed), 2 (bad input or an error the FMU reports), 3 (stopped by
``--max-chunks``: run again to finish), 130 (interrupted; finished chunks are kept).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..studies import ALIASES, REGISTRY
from .options import add_max_work_argument, make_parser, path_arg

__all__ = ["add_parser", "run", "main", "add_arguments", "EXIT_STOPPED"]

EXIT_OK, EXIT_FAILED = 0, 1
#: a sweep stopped by ``--max-chunks`` (run again to finish)
EXIT_STOPPED = 3


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``study`` command to the main parser's subparsers ``sub``."""
    s = sub.add_parser("study", parents=parents, help="the paper's studies ('dryfriction study list')",
                       description="Reproduce a study of the paper (see 'list').")
    add_arguments(s, fmu=False)


def add_arguments(p: argparse.ArgumentParser, fmu: bool = True) -> argparse.ArgumentParser:
    """The study command's arguments (``fmu=False``: the caller's parser has a global ``--fmu``)."""
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    width = max(map(len, REGISTRY))
    p.epilog = "studies:\n" + "\n".join(f"  {n:{width}s}  {s.title}" for n, s in REGISTRY.items())
    p.add_argument("name", help="study name (fig2, fig3, ..., or list, all)")
    p.add_argument("--quick", action="store_true", help="small sizes (CI): the config's [quick] table")
    p.add_argument("--out", type=path_arg("--out"), default="results", metavar="DIR",
                   help="results root; files go to DIR/<study>/")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="Dask LocalCluster worker processes (default: all cores; 0: no Dask, this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDR",
                   help="address of an existing Dask scheduler (tcp://host:8786) instead of a LocalCluster")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                   help="override a config value, e.g. --set sweep.chi.num=20 (repeatable)")
    p.add_argument("--config", default=None, metavar="FILE", help="TOML file overriding the study's config")
    if fmu:
        p.add_argument("--fmu", default=None, metavar="PATH",
                       help="the FMU (default: $DFO_FMU, else the installed package's, else build/)")
    p.add_argument("--max-chunks", type=int, default=None, metavar="N",
                   help="stop after computing N new chunks (exit 3; run again to finish)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    if fmu:  # else the caller's parser has the global --max-work
        add_max_work_argument(p)
    p.add_argument("--show-config", action="store_true", help="print the effective config and exit")
    return p


def _parser(prog: str) -> argparse.ArgumentParser:
    return add_arguments(make_parser(prog, "Reproduce a study of the paper (see 'list')."))


def _list() -> str:
    """The studies as a table, its columns as wide as their longest entry."""
    rows = [("study", "figures", "title")] + [(n, ", ".join(s.figures), s.title) for n, s in REGISTRY.items()]
    w0, w1 = (max(len(r[i]) for r in rows) for i in (0, 1))
    lines = [f"{a:{w0}s}  {b:{w1}s}  {c}" for a, b, c in rows]
    lines.append("aliases: " + ", ".join(f"{a} -> {b}" for a, b in ALIASES.items()))
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None, prog: str = "dryfriction study") -> int:
    """``study <name> [options]``; returns the exit status (0 ok, 1 failed, 2 bad input or an error
    the FMU reports, 3 stopped, 130 interrupted). Errors are one line ``dryfriction: error: ...``
    (:func:`.console.guarded`), as from ``dryfriction study``."""
    from .console import guarded

    args_list = list(sys.argv[1:] if argv is None else argv)
    if args_list and args_list[0] in ("-h", "--help"):
        _parser(prog).print_help()
        return EXIT_OK

    def command() -> int:
        try:
            args = _parser(prog).parse_args(args_list)
        except SystemExit as e:  # --help anywhere
            return int(e.code or 0)
        return run(args, prog)

    return guarded(command)


def run(args: argparse.Namespace, prog: str = "dryfriction study") -> int:
    """Run the study command of parsed arguments (see :func:`add_arguments`); ``prog`` names the
    command in its help only. Bad input raises UsageError (one line, exit 2, reported by the
    caller: :func:`main`, ``dryfriction study``); an interrupt is KeyboardInterrupt (finished
    chunks are kept)."""
    from ..errors import FMUError
    from ..studies import OUTPUT_MARGIN, check_study, dump_toml, effective_config, resolve, run_study
    from ..studies.config import ConfigError
    from ..sweep.engine import SweepInterrupted
    from .console import PREFIX, interrupt_note, interrupted

    try:
        if args.name == "list":
            print(_list())
            return EXIT_OK
        names = list(REGISTRY) if args.name == "all" else [resolve(args.name)]
        if args.name == "all" and (args.sets or args.config):
            raise ConfigError("--set and --config apply to one study, not to 'all'")
        # check every study's config before any work starts
        cfgs = {n: effective_config(n, args.quick, args.config, args.sets) for n in names}
        if args.show_config:
            for n, cfg in cfgs.items():
                print(dump_toml(cfg, header=f"study {n}" + (" (--quick)" if args.quick else "")))
            return EXIT_OK
        # every study's work and output checked before the first starts
        total = 0.0
        for n, cfg in cfgs.items():
            total += check_study(n, cfg, Path(args.out) / n, getattr(args, "max_work", None)).out_bytes
        if len(names) > 1:
            from ..budget import check_writable

            check_writable(args.out, OUTPUT_MARGIN * total, "the results and chunks of all studies")
        fmu = getattr(args, "fmu", None)
        interrupt_note("finished chunks are kept, run again to resume")
        for n in names:
            print(f"== study {n}: {REGISTRY[n].title}", flush=True)
            run_study(n, quick=args.quick, out=args.out, workers=args.workers, scheduler=args.scheduler,
                      sets=args.sets, config_file=args.config, fmu=fmu, max_chunks=args.max_chunks,
                      progress=not args.no_progress, max_work=getattr(args, "max_work", None))
        return EXIT_OK
    except SweepInterrupted as e:
        print(f"{PREFIX}: {e}", file=sys.stderr)
        return EXIT_STOPPED
    except RuntimeError as e:
        if interrupted() or isinstance(e, FMUError):  # said by the caller: the interrupt, exit 2
            raise
        print(f"{PREFIX}: error: {e}", file=sys.stderr)
        return EXIT_FAILED
