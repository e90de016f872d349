"""The bench scripts' one timing helper: the best wall time of a few repeats."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TypeVar

R = TypeVar("R")


def timed(fn: Callable[[], R], repeats: int) -> tuple[float, R]:
    """(the least wall time of ``repeats`` calls of fn in seconds, the last call's result)."""
    if repeats < 1:
        raise ValueError(f"repeats must be at least 1, not {repeats}")
    best = math.inf
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out
