"""``dryfriction scenes``: the scenes ``dryfriction run --scene`` runs, one line each."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``scenes`` command to the main parser's subparsers ``sub``."""
    sub.add_parser("scenes", parents=parents, help="list the scenes")


def run(args: argparse.Namespace) -> int:
    """Print every scene with what it does; the exit status."""
    from ..drivers.scenes import SCENES

    for s in SCENES.values():
        print(f"{s.name:11s} {s.description}")
    return 0
