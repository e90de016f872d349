"""Numbers and sentences as the commands print them (shared by several commands; no command
module imports another)."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["finite", "json_safe", "print_json", "percent", "rest_line"]


def finite(v: float) -> float | None:
    """``v`` as a JSON number, None (null) for NaN or an infinity."""
    return float(v) if math.isfinite(v) else None


def json_safe(x: Any) -> Any:
    """``x`` (floats, NumPy scalars, dicts, lists, tuples of them) with NaN and infinities as None."""
    import numpy as np

    if isinstance(x, float):
        return finite(x)
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, np.generic):
        return json_safe(x.item())
    return x


def print_json(obj: Any, indent: int | None = None) -> None:
    """``obj`` as JSON on stdout, one object (``indent``: pretty-printed)."""
    import json

    print(json.dumps(obj, indent=indent))


def percent(share: float) -> str:
    """A share in % with one decimal, more where that would read 0 or 100 of a share that is neither
    (a block stuck but for slides of 1e-4 of the cycle is not at rest)."""
    text = f"{100 * share:.1f}"
    digits = 1
    while 0.0 < share < 1.0 and text in ("0.0", "100.0") and digits < 12:
        digits += 1
        text = f"{100 * share:.{digits}f}"
    return text


def rest_line(rest: tuple[float, float], p: Any) -> str:
    """The sentence on the block at rest: the interval of its rest positions (``p``: the
    :class:`~dryfriction.params.Oscillator`)."""
    lo, hi = rest
    where = ("at any x (no spring)" if not math.isfinite(hi) else
             f"at any x in [{lo:.6g}, {hi:.6g}] m (|k x| <= F_b - |P0| = {p.breakaway - abs(p.P0):.4g} N)")
    return (f"the block at rest: P0 = {abs(p.P0):.4g} N within the breakaway force F_b = {p.breakaway:.4g} N, it "
            f"rests for good {where}; each rest position is a periodic orbit (multipliers 1 and 0: neutral), "
            "listed once, at the position the transient from x0, v0 reaches")
