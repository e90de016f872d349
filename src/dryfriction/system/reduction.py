"""Component mode synthesis of a structure with friction contacts (Craig-Bampton): the finite-element
model reduced to its contact DOFs and a few fixed-interface modes, as harmonic-balance tools and
their users reduce a blade or a beam before they solve it.

A finite-element mesh has modes far above the ones a response excites (a 24-DOF beam: 84 to
206,000 rad/s). The located scheme resolves the fastest one (a step with ``rate h > 10`` falls back
to the consistent scheme's first order and loses the map's Jacobian), so the step the full mesh
needs is set by modes that do not take part. The reduction keeps the physics the friction sees:

    x = T q,   T = [[I, 0], [Psi, Phi_k]],   Psi = -K_ii^-1 K_ib,

``b`` the boundary DOFs (by default every DOF a contact's row touches, so each contact is a
boundary coordinate exactly), ``i`` the others, ``Phi_k`` the first ``modes`` mass-normalised modes
of the interior with the boundary held. ``M_r = T' M T``, ``C_r = T' C T``, ``K_r = T' K T``,
``F_r = T' F``, contact rows ``W T``, the initial state the M-orthogonal projection
``q = (T' M T)^-1 T' M x``. The static response is exact (the constraint modes ``Psi``); the
reduced modes converge to the full ones from above as ``modes`` grows (the beam with 8 modes: the
first frequency within 1.4e-8, the fastest 17,700 rad/s instead of 206,000).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import UsageError
from .structure import System

__all__ = ["Reduction", "craig_bampton"]


@dataclass(frozen=True)
class Reduction:
    """A structure reduced by :func:`craig_bampton`: ``system`` the reduced one (its coordinates
    ``q``: the boundary DOFs' displacements, then the modal amplitudes), ``T`` the basis (n x r,
    ``x = T q``), ``boundary`` and ``interior`` the full model's DOF indices, ``frequencies`` the
    kept fixed-interface modes' (rad/s)."""

    system: System
    T: np.ndarray
    boundary: tuple[int, ...]
    interior: tuple[int, ...]
    frequencies: np.ndarray

    def expand(self, q: np.ndarray) -> np.ndarray:
        """The full model's DOFs from reduced coordinates: ``T q`` (q of shape (r,) or (..., r), real or
        complex)."""
        return np.asarray(q) @ self.T.T

    def coordinate(self, dof: int) -> int:
        """The reduced coordinate that is the full model's boundary DOF ``dof`` (UsageError for an
        interior DOF: its motion is ``T[dof] @ q``, :meth:`expand`)."""
        if dof not in self.boundary:
            raise UsageError(f"dof = {dof} is not a boundary DOF of the reduction (boundary: "
                             f"{', '.join(map(str, self.boundary))}); its motion is T[dof] @ q (Reduction.expand)")
        return self.boundary.index(dof)


def craig_bampton(system: System, modes: int, boundary: Sequence[int] | None = None) -> Reduction:
    """``system`` reduced to its ``boundary`` DOFs (default: every DOF a contact's row touches) and
    its first ``modes`` fixed-interface modes (module docstring). The contacts keep their friction;
    their rows become ``w T`` (a boundary DOF's contact: that coordinate). The run's settings (h,
    scheme, alpha, omega) are kept; h = 0 lets the FMU derive the step from the reduced dynamics.

    Raises UsageError for ``modes`` outside 0 to the interior's size, a boundary index out of range
    or repeated, an empty boundary, or an interior that the boundary does not hold (K_ii singular:
    a free part of the structure)."""
    n = system.n
    if boundary is None:
        b = sorted({int(i) for i in np.flatnonzero(np.any(system.W != 0.0, axis=0))})
    else:
        b = [int(i) for i in boundary]
        if len(set(b)) != len(b):
            raise UsageError(f"boundary {list(boundary)} repeats a DOF")
        for i in b:
            if not 0 <= i < n:
                raise UsageError(f"boundary DOF {i} is out of range; valid: 0 to {n - 1}")
        b = sorted(b)
    if not b:
        raise UsageError("the reduction needs at least one boundary DOF (the structure has no contact: give boundary=)")
    interior = [i for i in range(n) if i not in set(b)]
    k = int(modes)
    if not 0 <= k <= len(interior):
        raise UsageError(f"modes = {modes!r} is out of range; valid: 0 to {len(interior)} (the interior DOFs)")
    M, K, C = system.M, system.K, system.C
    ii, ib = np.ix_(interior, interior), np.ix_(interior, b)
    Kii = K[ii]
    from scipy.linalg import eigh

    lam, phi = eigh(Kii, M[ii])
    if interior and not lam[0] > 1e-12 * max(float(np.max(np.abs(lam))), 1e-300):
        raise UsageError("the boundary does not hold the interior (K_ii is singular: a part of the structure is "
                         "free when the boundary DOFs are held); add DOFs of that part to the boundary")
    r = len(b) + k
    T = np.zeros((n, r))
    T[b, np.arange(len(b))] = 1.0
    if interior:
        T[np.ix_(interior, range(len(b)))] = -np.linalg.solve(Kii, K[ib])
        T[np.ix_(interior, range(len(b), r))] = phi[:, :k]

    def congruent(A: np.ndarray) -> np.ndarray:
        R = T.T @ A @ T
        return 0.5 * (R + R.T)

    Mr = congruent(M)
    MT = M @ T

    def project(x: np.ndarray) -> np.ndarray:
        return np.linalg.solve(Mr, MT.T @ x)

    contacts = []
    for c, w in zip(system.contacts, system.W @ T):
        nz = np.flatnonzero(w)
        if nz.size == 1 and w[nz[0]] == 1.0:
            contacts.append(dataclasses.replace(c, dof=int(nz[0]), between=None, w=None))
        else:
            contacts.append(dataclasses.replace(c, dof=None, between=None, w=tuple(float(v) for v in w)))
    reduced = System(M=Mr, K=congruent(K), C=congruent(C), contacts=contacts, F_c=T.T @ system.F_c,
                     F_s=T.T @ system.F_s, omega=system.omega, x0=project(system.x0), v0=project(system.v0),
                     h=system.h, scheme=system.scheme, alpha=system.alpha)
    return Reduction(reduced, T, tuple(b), tuple(interior), np.sqrt(np.maximum(lam[:k], 0.0)))

