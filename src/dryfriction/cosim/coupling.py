"""What joins the units of a :class:`~dryfriction.cosim.system.System`: a connection (an input set
from an output, times a gain) and the coupling elements the master computes itself (a
:class:`SpringDamper` between two blocks). Every coupling here is linear in the outputs, so the
system's inputs are ``u = G y`` with one matrix ``G`` (:func:`coupling_matrix`), which the master
uses for the values, their time derivatives and the interface-Jacobian correction alike."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Connection", "SpringDamper", "split", "coupling_matrix"]


def split(port: str) -> tuple[str, str]:
    """``"b1.x"`` -> ``("b1", "x")`` (split at the first dot)."""
    unit, sep, var = port.partition(".")
    if not sep or not unit or not var:
        raise ValueError(f"a port is 'instance.variable', not {port!r}")
    return unit, var


@dataclass(frozen=True)
class Connection:
    """``target = gain * source`` (``"a.x"`` -> ``"b.F_ext"``); several into one input add up."""

    source: str
    target: str
    gain: float = 1.0

    def terms(self) -> list[tuple[str, str, float]]:
        """(input port, output port, coefficient) of every term."""
        if not math.isfinite(self.gain):
            raise ValueError(f"the gain of {self.source} -> {self.target} must be finite, not {self.gain!r}")
        return [(self.target, self.source, float(self.gain))]


@dataclass(frozen=True)
class SpringDamper:
    """A spring ``k`` and damper ``c`` between blocks ``a`` and ``b`` (instance names), computed by
    the master: ``F = k (x_b - x_a) + c (v_b - v_a)`` on ``a`` and ``-F`` on ``b``, through each
    block's ``force`` input (default ``F_ext``); ``x`` and ``v`` name the blocks' position and
    velocity outputs. Each name is one for both blocks or a pair (``x=("x[2]", "x")``: a chain's
    last block and an oscillator)."""

    a: str
    b: str
    k: float
    c: float = 0.0
    x: str | tuple[str, str] = "x"
    v: str | tuple[str, str] = "v"
    force: str | tuple[str, str] = "F_ext"

    def terms(self) -> list[tuple[str, str, float]]:
        """The element's terms (unit, variable, coefficient), its values checked (ValueError for a negative or
        non-finite k or c)."""
        for name, val in (("k", self.k), ("c", self.c)):
            if not (math.isfinite(val) and val >= 0):
                raise ValueError(f"SpringDamper({self.a}, {self.b}): {name} must be a finite number >= 0, not {val!r}")
        a, b = self.a, self.b
        (xa, xb), (va, vb), (fa, fb) = (_pair(n) for n in (self.x, self.v, self.force))
        out = []
        for sign, target in ((1.0, f"{a}.{fa}"), (-1.0, f"{b}.{fb}")):
            out += [(target, f"{b}.{xb}", sign * self.k), (target, f"{a}.{xa}", -sign * self.k)]
            if self.c:
                out += [(target, f"{b}.{vb}", sign * self.c), (target, f"{a}.{va}", -sign * self.c)]
        return out


def _pair(name: str | tuple[str, str]) -> tuple[str, str]:
    if isinstance(name, str):
        return name, name
    a, b = name
    return str(a), str(b)


def coupling_matrix(elements: list[Connection | SpringDamper]) -> tuple[list[str], list[str], np.ndarray]:
    """The inputs (ports, in order of appearance), the outputs they are computed from, and ``G``
    [inputs, outputs] with ``u = G y``."""
    terms = [t for e in elements for t in e.terms()]
    inputs = list(dict.fromkeys(t[0] for t in terms))
    outputs = list(dict.fromkeys(t[1] for t in terms))
    G = np.zeros((len(inputs), len(outputs)))
    iu = {p: i for i, p in enumerate(inputs)}
    iy = {p: j for j, p in enumerate(outputs)}
    for target, source, coef in terms:
        G[iu[target], iy[source]] += coef
    return inputs, outputs, G
