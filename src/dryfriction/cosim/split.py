"""The two-block chain split in two (docs/coupling.md): block 1 with its wall spring ``k[0]``,
``c[0]`` and the harmonic force, block 2 with the far wall's ``k_end``, ``c_end`` (0 for a free
block), and between them the chain's ``k[1]``, ``c[1]`` as a :class:`SpringDamper` the master
computes. The chain FMU at n = 2 with the same parameters is the monolithic answer."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..params import Oscillator
from .coupling import SpringDamper

__all__ = ["split_chain2", "CHAIN2_BLOCK_FIELDS"]

#: the per-block fields of the chain that are the oscillator's fields of the same name
CHAIN2_BLOCK_FIELDS = ("m", "P0", "phi", "N", "mu_s", "chi", "x0", "v0")


def split_chain2(params: Mapping[str, Any], names: tuple[str, str] = ("b1", "b2")
                 ) -> tuple[Oscillator, Oscillator, SpringDamper]:
    """The oscillators of blocks 1 and 2 and the coupling element of a two-block chain given by
    the chain's parameters (``m``, ``k``, ``c``, ``P0``, ``phi``, ``N``, ``mu_s``, ``chi``, ``x0``,
    ``v0``: two values each or one for both; ``omega``, ``k_end``, ``c_end``: scalars)."""
    unknown = set(params) - set(CHAIN2_BLOCK_FIELDS) - {"k", "c", "omega", "k_end", "c_end"}
    if unknown:
        raise ValueError(f"not parameters of the two-block chain: {', '.join(sorted(unknown))}")

    def pair(name: str, default: float) -> np.ndarray:
        a = np.broadcast_to(np.asarray(params.get(name, default), dtype=float), (2,))
        return a

    omega = float(params.get("omega", 1.0))
    fields = {f: pair(f, d) for f, d in zip(CHAIN2_BLOCK_FIELDS, (1.0, 0.0, 0.0, 0.8, 0.5, 0.7, 0.0, 0.0))}
    k, c = pair("k", 1.0), pair("c", 0.0)
    b1 = Oscillator(k=float(k[0]), c=float(c[0]), omega=omega, **{f: float(v[0]) for f, v in fields.items()})
    b2 = Oscillator(k=float(params.get("k_end", 0.0)), c=float(params.get("c_end", 0.0)), omega=omega,
                    **{f: float(v[1]) for f, v in fields.items()})
    return b1, b2, SpringDamper(names[0], names[1], k=float(k[1]), c=float(c[1]))
