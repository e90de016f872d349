"""The shooting machinery that the oscillator's orbits (:mod:`dryfriction.analysis.orbits`) and a
structure's (:mod:`dryfriction.analysis.system_orbits`) share: what an orbit record reads like, Newton
with a backtracking line search on a stroboscopic map, the Floquet multipliers and the stability
they tell, and the frequency response's loop (docs/orbits.md, docs/system_orbits.md).

Each model supplies a :class:`ShootingMap`: its map P^K at a section time with the Jacobian (the
FMU's own), its scaled residual, its Newton step (the oscillator's 2 x 2 solve on plain floats, a
structure's minimum-norm step in its scaled unknowns), its constraints on a state (a structure's
sliders) and its bound on Newton's iterates. Newton (:func:`newton`) solves P^K(z) = z:

- a step dz from (J - I) dz = -(P^K(z) - z), from the model;
- a backtracking line search: z + lam dz, lam = 1, 1/2, 1/4 ..., accepted when the scaled residual
  falls, by the share ``armijo`` lam of itself at least (or is within ``tol``); where the model's
  Jacobian costs several map runs, the trials run without it and the accepted state's is computed
  after (the same iterates, a fraction of the cost);
- converged when the residual is at most ``tol``; then, while the Newton step is itself above ``tol``
  (a multiplier near 1: the residual understates the distance to the orbit), up to ``polish`` more
  steps.

Along a frequency response each point starts from its branch's last orbits extrapolated to its
frequency (:func:`extrapolate`, :func:`lagrange_weights`: the Lagrange polynomial through up to four
of them).

No module here imports a model: the models import this one.
"""

from __future__ import annotations

import cmath
import sys
from collections.abc import Callable, Iterable, Sequence
from typing import Any, Generic, Protocol, TypeVar

import numpy as np

__all__ = ["STABILITY_MARGIN", "OrbitRecord", "ShootingMap", "Newton", "newton", "multipliers", "classify",
           "sweep", "progress_bar", "extrapolate", "lagrange_weights"]

#: an orbit is stable when every |mu| < 1 - STABILITY_MARGIN (a neutral orbit's multipliers 1 aside)
STABILITY_MARGIN = 1e-9

_Z = TypeVar("_Z")      # a model's state: the oscillator's (x, v) floats, a structure's array
_J = TypeVar("_J")      # a model's Jacobian: the oscillator's four floats, a structure's matrix
_A = TypeVar("_A")      # what else an evaluation returns: the mode at the end, the observables


class OrbitRecord:
    """What every orbit record (:class:`~dryfriction.analysis.orbits.Orbit`,
    :class:`~dryfriction.analysis.system_orbits.SystemOrbit`: dataclasses) reads like: its fields as
    attributes or by name, and the largest multiplier's modulus. Their common fields: ``period``,
    ``multipliers`` (|mu| descending), ``stable``, ``neutral``, ``residual``, ``converged``, ``reason``,
    ``section``, ``section_state``, ``jacobian``, ``iterations``, ``amplitude``, ``offset``,
    ``stick_fraction``, ``x0``, ``v0``."""

    __dataclass_fields__: dict[str, Any]
    multipliers: np.ndarray

    def __getitem__(self, name: str) -> Any:
        """``orbit["x0"]``: the field ``name`` (KeyError for an unknown one)."""
        if name not in self.__dataclass_fields__:
            raise KeyError(f"{type(self).__name__} has no field {name!r}; "
                           f"fields: {', '.join(self.__dataclass_fields__)}")
        return getattr(self, name)

    @property
    def mu_max(self) -> float:
        """The largest multiplier's modulus (NaN without multipliers)."""
        mu = self.multipliers
        return float(np.max(np.abs(mu))) if mu.size else float("nan")


def multipliers(J: np.ndarray, rank_one: bool = False, closed: bool = False) -> np.ndarray:
    """The eigenvalues of the map's Jacobian J (complex), |mu| descending (ties in their order); NaN
    where J is not finite. ``rank_one``: J has rank one (a stick phase on the oscillator's cycle sets
    its v row to 0): exactly trace(J) and 0. ``closed`` and a 2 x 2 J: the roots of its
    characteristic polynomial (a tenth of LAPACK's cost; they may differ in the last bits)."""
    J = np.asarray(J, dtype=float)
    if rank_one:
        return np.array([complex(np.trace(J)), 0j] + [0j] * (J.shape[0] - 2))
    if not np.all(np.isfinite(J)):
        return np.full(J.shape[0], np.nan, dtype=complex)
    if closed and J.shape == (2, 2):
        return np.array(_roots2(float(J[0, 0]), float(J[0, 1]), float(J[1, 0]), float(J[1, 1])))
    mu = np.linalg.eigvals(J).astype(complex)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def _roots2(a: float, b: float, c: float, d: float) -> list[complex]:
    """The eigenvalues of [[a, b], [c, d]], |mu| descending."""
    tr, det = a + d, a * d - b * c
    root = cmath.sqrt(complex(tr * tr / 4.0 - det))
    mu = [tr / 2.0 + root, tr / 2.0 - root]
    return mu if not abs(mu[1]) > abs(mu[0]) else mu[::-1]


def classify(mu: Iterable[complex], one: float, margin: float = STABILITY_MARGIN) -> tuple[bool, bool]:
    """(a multiplier 1, the others inside): whether some multiplier is within ``one`` of 1 (a
    continuum of orbits: neutral directions), and whether every other one has |mu| < 1 - ``margin``
    (a NaN multiplier is not inside)."""
    has_one, inside, lim = False, True, 1.0 - margin
    for m in mu:
        if abs(m - 1.0) <= one:
            has_one = True
        elif not abs(m) < lim:
            inside = False
    return has_one, inside


class ShootingMap(Protocol[_Z, _J, _A]):
    """What a model supplies to :func:`newton`: its stroboscopic map at a section time, in its own
    representation of a state z, of the map's Jacobian and of what else an evaluation returns."""

    #: exceptions of a trial evaluation that only shorten the line search's step (a state the FMU refuses)
    refused: tuple[type[BaseException], ...]

    def evaluate(self, z: _Z, t_s: float, final: bool, jacobian: bool = True) -> tuple[_Z, _J, _A]:
        """(P^K(z), its Jacobian, the rest) for the state z at the section time t_s (``final``
        False: an evaluation unlikely to be the converged one; ``jacobian`` False: the Jacobian may
        be left out, not computed)."""
        ...

    def expensive_jacobian(self) -> bool:
        """Whether the map's Jacobian costs several runs of the map (a large structure): the line
        search then tries states without it and computes it at the accepted one only."""
        ...

    def residual(self, z: _Z, Pz: _Z) -> float:
        """The scaled residual of z (its image Pz), relative to the size of z."""
        ...

    def step(self, z: _Z, Pz: _Z, J: _J) -> tuple[_Z | None, str]:
        """(the Newton step dz, ""), or (None, why there is none)."""
        ...

    def move(self, z: _Z, dz: _Z, lam: float) -> _Z:
        """z + lam dz (within the model's constraints)."""
        ...

    def step_size(self, z: _Z, dz: _Z) -> float:
        """The scaled size of the step dz, relative to the size of z."""
        ...

    def outside(self, z: _Z, first: bool) -> str:
        """Why z is beyond the bound on Newton's iterates ("" when it is not; ``first``: the guess)."""
        ...


class Newton(Generic[_Z, _J, _A]):
    """The result of :func:`newton`: the last state z, its image Pz, the Jacobian J there, the rest
    of its evaluation, the scaled residual, the Newton steps taken and why it did not converge ("")."""

    __slots__ = ("z", "Pz", "J", "aux", "residual", "iterations", "reason")

    def __init__(self, z: _Z, Pz: _Z, J: _J, aux: _A, residual: float, iterations: int, reason: str) -> None:
        self.z, self.Pz, self.J, self.aux = z, Pz, J, aux
        self.residual, self.iterations, self.reason = residual, iterations, reason


def newton(m: ShootingMap[_Z, _J, _A], z: _Z, t_s: float, tol: float, max_iter: int, *, halvings: int = 30,
           armijo: float = 1e-4, polish: int = 0, first: tuple[_Z, _J, _A] | None = None) -> Newton[_Z, _J, _A]:
    """Newton on P^K(z) = z from z at the section time t_s with a backtracking line search (module
    doc): at most ``max_iter`` steps, ``halvings`` halvings of a step, ``polish`` steps after the
    residual is within ``tol`` while the step is not. ``first``: the evaluation of z if made already."""
    Pz, J, aux = m.evaluate(z, t_s, False) if first is None else first   # the guess: rarely converged already
    res = m.residual
    r = res(z, Pz)
    it = 0
    why = m.outside(z, True)
    if why:
        return Newton(z, Pz, J, aux, r, it, why)
    while r > tol:
        if it >= max_iter:
            return Newton(z, Pz, J, aux, r, it, f"no convergence in {max_iter} Newton steps (residual {r:.3g})")
        dz, why = m.step(z, Pz, J)
        if dz is None:
            return Newton(z, Pz, J, aux, r, it, why)
        lam = 1.0
        lazy = m.expensive_jacobian()
        for _ in range(halvings):
            zt = m.move(z, dz, lam)
            try:
                Pt, Jt, at = m.evaluate(zt, t_s, True, jacobian=not lazy)
            except m.refused:
                lam *= 0.5
                continue
            rt = res(zt, Pt)
            if rt < (1.0 - armijo * lam) * r or rt <= tol:
                break
            lam *= 0.5
        else:
            return Newton(z, Pz, J, aux, r, it + 1, f"the line search found no decrease of the residual {r:.3g} "
                                                    "(a non-smooth point)")
        if lazy:  # the accepted state's Jacobian (the next step's, or the converged orbit's)
            Pt, Jt, at = m.evaluate(zt, t_s, True)
        it += 1
        z, Pz, J, aux, r = zt, Pt, Jt, at, rt
        why = m.outside(z, False)
        if why:
            return Newton(z, Pz, J, aux, r, it, why)
    for _ in range(polish):
        # r <= tol, but the distance left to the fixed point is the Newton step, about r / |1 - mu|:
        # far more than r where a multiplier is near 1 (a slow creep, e.g. the oscillator at lambda
        # 1e-6, or onto the edge of its interval of rest positions): step on while the step is above tol
        dz, _ = m.step(z, Pz, J)
        if dz is None or not m.step_size(z, dz) > tol:
            break
        zt = m.move(z, dz, 1.0)
        lazy = m.expensive_jacobian()
        Pt, Jt, at = m.evaluate(zt, t_s, True, jacobian=not lazy)
        rt = res(zt, Pt)
        if not rt <= tol:
            m.evaluate(z, t_s, True, jacobian=not lazy)  # the map's last evaluation is the state kept (its observables)
            break
        if lazy:
            Pt, Jt, at = m.evaluate(zt, t_s, True)
        it += 1
        z, Pz, J, aux, r = zt, Pt, Jt, at, rt
    return Newton(z, Pz, J, aux, r, it, "")


_P = TypeVar("_P")      # a point of a sweep: an oscillator, a structure
_S = TypeVar("_S")      # what a point's solve returns: its orbits, its orbit


def sweep(points: Iterable[_P], warm: Callable[[int, _P, _S], _S | None], cold: Callable[[int, _P, _S | None], _S],
          record: Callable[[int, _P, _S], None], failed: Callable[[int, BaseException], None],
          errors: tuple[type[BaseException], ...], progress: Callable[[int], None] | None = None) -> None:
    """The frequency response's loop: at each point (in order) its steady states from the previous
    point's (``warm``: None where it cannot follow them), else from a fresh search (``cold``, also at
    the first point and after a point that failed); ``record`` the point's result (its index, the
    point, what its solve returned), ``failed`` the
    error of a point where one of ``errors`` was raised (the sweep goes on, the next point cold);
    ``progress`` called with each index done."""
    prev: _S | None = None
    for i, p in enumerate(points):
        try:
            found = warm(i, p, prev) if prev is not None else None
            if found is None:
                found = cold(i, p, prev)
        except errors as e:
            failed(i, e)
            prev = None
        else:
            record(i, p, found)
            prev = found
        if progress is not None:
            progress(i)


def lagrange_weights(at: Sequence[float], p: float) -> list[float]:
    """The weights of the Lagrange polynomial through points at the parameters ``at`` (distinct) at
    the parameter ``p``: the point predicted there is sum_i w_i y_i (plain floats: the oscillator's
    response sums its two-number states with them)."""
    out = []
    for ai in at:
        w = 1.0
        for aj in at:
            if aj != ai:
                w *= (p - aj) / (ai - aj)
        out.append(w)
    return out


def extrapolate(at: Sequence[float], points: Sequence[Any], p: float) -> np.ndarray:
    """The Lagrange polynomial through the points (``points[i]`` at the parameter ``at[i]``, the
    parameters distinct; each a number or an array of one shape) at the parameter ``p``: a branch's
    next point predicted from its last ones (a sweep's predictor; :func:`lagrange_weights`)."""
    out = np.zeros(np.shape(points[0]))
    for w, yi in zip(lagrange_weights(at, p), points, strict=True):
        out = out + w * np.asarray(yi, dtype=float)
    return out


def progress_bar(total: int, on: bool, desc: str = "response") -> Callable[[int], None]:
    """A progress line on stderr (``on``; else nothing): call with the index done, -1 at the end."""
    if not on:
        return lambda i: None

    def bar(i: int) -> None:
        if i < 0:
            sys.stderr.write("\n")
            return
        done = i + 1
        width = 30
        fill = int(width * done / total)
        sys.stderr.write(f"\r{desc} [{'#' * fill}{'.' * (width - fill)}] {done}/{total}")
        sys.stderr.flush()

    return bar
