"""``dryfriction validate``: the FMU against the exact solution, its errors and orders of
convergence, ``results/validation.{csv,png}`` (:func:`dryfriction.analysis.report.validate`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .options import path_arg

__all__ = ["add_parser", "run"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``validate`` command to the main parser's subparsers ``sub``."""
    v = sub.add_parser("validate", parents=parents,
                       help="FMU against the exact solution: errors, orders, results/validation.png")
    v.add_argument("--out", type=path_arg("--out"), default=Path("results"), help="output folder (default: results)")
    v.add_argument("--quick", action="store_true", help="two cases, three step sizes")


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction validate``; the exit status."""
    from ..analysis.report import validate
    from .console import check_output_folder

    check_output_folder(args.out)
    print(validate(args.out, quick=args.quick, fmu_path=args.fmu, progress=sys.stderr.isatty()))
    return 0
