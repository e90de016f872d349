"""A chain of n blocks split into n oscillators (docs/coupling.md): block 1 with its wall spring
``k[0]``, ``c[0]`` and its harmonic force, the last block with the far wall's ``k_end``, ``c_end``
(0: free), the blocks between with no spring of their own (k = 0), and between blocks i and i+1 the
chain's ``k[i]``, ``c[i]`` as a :class:`SpringDamper` the master computes. The chain FMU with the
same parameters is the monolithic answer."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..params import Oscillator
from .coupling import SpringDamper

__all__ = ["split_chain", "split_chain2", "CHAIN_BLOCK_FIELDS"]

#: the per-block fields of the chain that are the oscillator's fields of the same name, with the
#: chain's defaults (dryfriction.references.chain.Chain.make)
CHAIN_BLOCK_FIELDS = {"m": 1.0, "P0": 0.0, "phi": 0.0, "N": 0.8, "mu_s": 0.5, "chi": 0.7, "x0": 0.0, "v0": 0.0}


def split_chain(params: Mapping[str, Any], n: int, names: Sequence[str] | None = None
                ) -> tuple[list[Oscillator], list[SpringDamper]]:
    """The n oscillators and the n - 1 coupling elements of the chain given by its parameters
    (``m``, ``k``, ``c``, ``P0``, ``phi``, ``N``, ``mu_s``, ``chi``, ``x0``, ``v0``: n values each or
    one for every block; ``omega``, ``k_end``, ``c_end``: scalars). ``names``: the instance names
    the elements join (default b1 ... bn)."""
    if not (isinstance(n, int) and n >= 2):
        raise ValueError(f"a split chain has n >= 2 blocks, not {n!r}")
    unknown = set(params) - set(CHAIN_BLOCK_FIELDS) - {"k", "c", "omega", "k_end", "c_end"}
    if unknown:
        raise ValueError(f"not parameters of the chain: {', '.join(sorted(unknown))}")
    labels = list(names) if names is not None else [f"b{i + 1}" for i in range(n)]
    if len(labels) != n:
        raise ValueError(f"{n} blocks need {n} names, not {len(labels)}")

    def per_block(name: str, default: float) -> np.ndarray:
        a = np.asarray(params.get(name, default), dtype=float)
        if a.ndim == 0:
            return np.full(n, float(a))
        if a.shape != (n,):
            raise ValueError(f"{name} needs {n} values (one per block) or one for every block, not {a.size}")
        return a

    omega = float(params.get("omega", 1.0))
    fields = {f: per_block(f, d) for f, d in CHAIN_BLOCK_FIELDS.items()}
    k, c = per_block("k", 1.0), per_block("c", 0.0)
    own_k = np.zeros(n)
    own_c = np.zeros(n)
    own_k[0], own_c[0] = k[0], c[0]
    own_k[-1] += float(params.get("k_end", 0.0))
    own_c[-1] += float(params.get("c_end", 0.0))
    blocks = [Oscillator(k=float(own_k[i]), c=float(own_c[i]), omega=omega,
                         **{f: float(v[i]) for f, v in fields.items()}) for i in range(n)]
    elements = [SpringDamper(labels[i - 1], labels[i], k=float(k[i]), c=float(c[i])) for i in range(1, n)]
    return blocks, elements


def split_chain2(params: Mapping[str, Any], names: tuple[str, str] = ("b1", "b2")
                 ) -> tuple[Oscillator, Oscillator, SpringDamper]:
    """The two-block chain split in two: block 1, block 2 and the element between them."""
    (b1, b2), (element,) = split_chain(params, 2, names)
    return b1, b2, element
