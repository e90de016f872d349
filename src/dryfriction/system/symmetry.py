"""Cyclic symmetry of a structure under a travelling-wave excitation: a bladed disk of identical
sectors driven at one engine order, whose steady response is the same motion in every sector, each
sector a fixed share of the period later than the one before.

A :class:`CyclicSymmetry` says which degree of freedom (and contact) the motion of each one moves to
after ``T / sectors``: ``x_{dofs[i]}(t + T / sectors) = x_i(t)``. Where the structure (``M``, ``C``,
``K``, the contacts) is invariant under that relabelling and the excitation is too (the force on
``dofs[i]`` a share ``1 / sectors`` of the period after the force on ``i``), the periodic orbits
that share the symmetry solve ``z(T / sectors) = P z(0)``: a shooting over one sector's share of
the period (:func:`dryfriction.analysis.system_orbits.find_system_orbits`' ``symmetry``), ``sectors``
times fewer steps per map run and per Jacobian than over the period, with the period's multipliers the
``sectors``-th powers of that map's. The orbits it finds are orbits of the full structure (the
travelling wave); an orbit that breaks the symmetry (a localised or a standing response of a mistuned
or bifurcated disk) is not among them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import UsageError

if TYPE_CHECKING:
    from .structure import System as Structure  # (the annotations' name: the API reference links it)

__all__ = ["CyclicSymmetry", "SYMMETRY_TOL"]

#: relative tolerance of the invariance checks (of each array's largest entry)
SYMMETRY_TOL = 1e-9


def _permutation(name: str, value: Any, size: int) -> np.ndarray:
    a = np.asarray(value)
    if a.shape != (size,) or (size and not np.issubdtype(a.dtype, np.integer)):
        raise UsageError(f"CyclicSymmetry: {name} must be {size} integers (a permutation of 0 .. {size - 1}), "
                         f"not an array of shape {a.shape}")
    a = a.astype(np.int64)
    if size and not np.array_equal(np.sort(a), np.arange(size)):
        raise UsageError(f"CyclicSymmetry: {name} is not a permutation of 0 .. {size - 1}")
    a.setflags(write=False)
    return a


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    scale = max(float(np.max(np.abs(a), initial=0.0)), float(np.max(np.abs(b), initial=0.0)))
    return bool(np.all(np.abs(a - b) <= SYMMETRY_TOL * scale))


@dataclass(frozen=True)
class CyclicSymmetry:
    """The travelling-wave symmetry of a structure (module doc): after ``T / sectors`` the motion of
    degree of freedom ``i`` is that of ``dofs[i]``, contact ``j``'s that of ``contacts[j]``.
    ``sectors`` >= 2; ``dofs`` and ``contacts`` permutations that repeat after ``sectors``
    applications. :meth:`check` tells whether a structure has it; :meth:`of_sectors` finds it from
    each sector's degrees of freedom and contacts."""

    sectors: int
    dofs: np.ndarray
    contacts: np.ndarray

    def __post_init__(self) -> None:
        s = self.sectors
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 2:
            raise UsageError(f"CyclicSymmetry: sectors = {s!r}; valid: an integer >= 2")
        object.__setattr__(self, "sectors", int(s))
        dofs = _permutation("dofs", self.dofs, int(np.size(self.dofs)))
        contacts = _permutation("contacts", self.contacts, int(np.size(self.contacts)))
        for name, p in (("dofs", dofs), ("contacts", contacts)):
            if not np.array_equal(self.power(p, int(s)), np.arange(p.size)):
                raise UsageError(f"CyclicSymmetry: {name} applied {s} times is not the identity (the motion "
                                 "must come back to itself after a period)")
        object.__setattr__(self, "dofs", dofs)
        object.__setattr__(self, "contacts", contacts)

    def power(self, perm: np.ndarray, k: int) -> np.ndarray:
        """The relabelling ``perm`` (``dofs``, ``contacts`` or an index array built from them)
        applied k times."""
        q = np.arange(perm.size)
        for _ in range(k):
            q = perm[q]
        return q

    def orbits(self, perm: np.ndarray) -> np.ndarray:
        """``sectors`` x size: row k the permutation applied k times (row 0 the identity): the
        degrees of freedom (or contacts) whose motion each one takes over the period."""
        rows = [self.power(perm, k) for k in range(self.sectors)]
        return np.array(rows, dtype=np.int64).reshape(self.sectors, perm.size)

    def check(self, system: "Structure") -> None:
        """Raise dryfriction.UsageError naming the first array the symmetry does not leave
        unchanged (within SYMMETRY_TOL of its largest entry): the sizes, M, C, K, the contacts'
        rows, loads, coefficients, stiffnesses and laws, the excitation (F_c, F_s rotated by
        2 pi / sectors on the relabelled DOFs: the force on ``dofs[i]`` is the force on ``i`` a
        share ``1 / sectors`` of the period later)."""
        n, nc = system.n, system.nc
        p, q = self.dofs, self.contacts
        if p.size != n or q.size != nc:
            raise UsageError(f"CyclicSymmetry: {p.size} DOFs and {q.size} contacts, the structure has n = {n} "
                             f"and nc = {nc}")
        for name in ("M", "C", "K"):
            a = getattr(system, name)
            if not _close(a[np.ix_(p, p)], a):
                raise UsageError(f"CyclicSymmetry: {name} is not invariant under the relabelling "
                                 f"({name}[dofs[i], dofs[j]] != {name}[i, j])")
        W = system.W
        if nc and not _close(W[np.ix_(q, p)], W):
            raise UsageError("CyclicSymmetry: the contacts' rows W are not invariant (W[contacts[j], dofs[i]] != W[j, i])")
        for name in ("N", "mu_s", "mu_k", "k_t", "v_s", "delta", "friction_law"):
            a = np.asarray(getattr(system, name), dtype=float)
            if nc and not _close(a[q], a):
                raise UsageError(f"CyclicSymmetry: the contacts' {name} differ between contacts the symmetry maps "
                                 "onto each other")
        th = 2.0 * math.pi / self.sectors
        Fc, Fs = system.F_c, system.F_s
        # F_{dofs[i]}(t + T / sectors) = F_i(t) for every t: the two parts of the excitation
        if not (_close(Fc[p] * math.cos(th) + Fs[p] * math.sin(th), Fc)
                and _close(Fs[p] * math.cos(th) - Fc[p] * math.sin(th), Fs)):
            raise UsageError("CyclicSymmetry: the excitation is not a travelling wave of this symmetry (the force "
                             "on dofs[i] is not the force on i a share 1 / sectors of the period later)")

    @classmethod
    def of_sectors(cls, system: "Structure", sector_dofs: Sequence[Sequence[int]] | np.ndarray,
                   sector_contacts: Sequence[Sequence[int]] | np.ndarray = ()) -> "CyclicSymmetry":
        """The symmetry of ``system`` that moves each sector's motion to another sector's:
        ``sector_dofs[s]`` the degrees of freedom of sector s (each sector's in the same order),
        ``sector_contacts[s]`` its contacts (empty: none); the sector shift over ``T / sectors``
        (the travelling wave's direction and speed: an engine order's) is the first of 1 ..
        sectors - 1 that :meth:`check` accepts. Raises dryfriction.UsageError where the arrays
        are not a partition into equal sectors or no shift fits."""
        D = np.asarray(sector_dofs, dtype=np.int64)
        if D.ndim != 2 or D.shape[0] < 2:
            raise UsageError("CyclicSymmetry.of_sectors: sector_dofs must list the DOFs of each of at least 2 sectors")
        ns = D.shape[0]
        Cn = np.asarray(sector_contacts, dtype=np.int64).reshape(ns, -1) if np.size(sector_contacts) else \
            np.zeros((ns, 0), dtype=np.int64)
        n, nc = system.n, system.nc
        if not (np.array_equal(np.sort(D.ravel()), np.arange(n)) and np.array_equal(np.sort(Cn.ravel()), np.arange(nc))):
            raise UsageError(f"CyclicSymmetry.of_sectors: the sectors' DOFs must hold each of 0 .. {n - 1} once and "
                             f"their contacts each of 0 .. {nc - 1} once")
        why = ""
        for m in range(1, ns):
            dofs = np.empty(n, dtype=np.int64)
            dofs[D.ravel()] = np.roll(D, -m, axis=0).ravel()
            contacts = np.empty(nc, dtype=np.int64)
            contacts[Cn.ravel()] = np.roll(Cn, -m, axis=0).ravel()
            try:
                sym = cls(ns, dofs, contacts)
                sym.check(system)
            except UsageError as e:
                why = str(e)
                continue
            return sym
        raise UsageError(f"CyclicSymmetry.of_sectors: no sector shift is a symmetry of the structure and its "
                         f"excitation (the last tried: {why})")
