"""Attractors from stroboscopic points: period detection and a catalogue that labels runs by the
attractor they reach (identified, with a tolerance, from their points after the transient)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["period_of", "Attractor", "Catalogue", "NONPERIODIC"]

#: period reported for stroboscopic points that repeat with no period up to ``max_period``
NONPERIODIC = 0


def period_of(points: np.ndarray, tol: float = 1e-6, max_period: int = 8) -> int:
    """Smallest p <= max_period with |P[k + p] - P[k]| <= tol (max norm) for every k of the tail
    ``points`` (shape (n, 2), n > 2 max_period advised); 0 (:data:`NONPERIODIC`) if none."""
    P = np.asarray(points, dtype=float)
    n = P.shape[0]
    for p in range(1, min(max_period, n - 1) + 1):
        if np.max(np.abs(P[p:] - P[:-p])) <= tol:
            return p
    return NONPERIODIC


@dataclass
class Attractor:
    """A periodic orbit (its p stroboscopic points) or the class of non-periodic motions."""

    period: int
    points: np.ndarray                # (p, 2) for a periodic orbit; the last points seen otherwise
    count: int = 0

    def describe(self) -> str:
        """The attractor in words: ``non-periodic``, or its period and the z of its points."""
        if self.period == NONPERIODIC:
            return "non-periodic"
        zs = ", ".join(f"{z:+.3f}" for z in np.sort(self.points[:, 0]))
        return f"period {self.period} (z = {zs})"


@dataclass
class Catalogue:
    """Attractors met so far; :meth:`label` returns the index of the one a tail of points is on.

    Two periodic tails are the same attractor when they have the same period and every point of
    one lies within ``tol`` (max norm) of a point of the other. All non-periodic tails form one
    class (chaotic motion, or a transient longer than the run)."""

    tol: float = 1e-4
    max_period: int = 8
    attractors: list[Attractor] = field(default_factory=list)

    def label(self, tail: np.ndarray, period_tol: float | None = None) -> int:
        """The index of the attractor the tail of an orbit (rows of (z, z')) settled on, adding it to the
        catalogue when it is new; -1 when the tail is not finite."""
        tail = np.asarray(tail, dtype=float)
        if not np.all(np.isfinite(tail)):
            return -1
        p = period_of(tail, self.tol if period_tol is None else period_tol, self.max_period)
        pts = tail[-p:] if p else tail[-1:]
        for i, a in enumerate(self.attractors):
            if a.period != p:
                continue
            if p == NONPERIODIC or _same_set(a.points, pts, self.tol):
                a.count += 1
                return i
        self.attractors.append(Attractor(p, pts.copy(), 1))
        return len(self.attractors) - 1

    def canonical(self) -> np.ndarray:
        """Relabelling old -> new that orders the attractors by period (non-periodic last), then by
        the mean z of their points; apply it with ``mapping[labels]`` (label -1 stays -1)."""
        key = [((a.period if a.period else 10**6), float(a.points[:, 0].mean()) if a.period else 0.0)
               for a in self.attractors]
        order = sorted(range(len(key)), key=lambda i: key[i])
        mapping = np.empty(len(order) + 1, dtype=int)
        for new, old in enumerate(order):
            mapping[old] = new
        mapping[-1] = -1
        self.attractors = [self.attractors[i] for i in order]
        return mapping


def _same_set(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    if a.shape != b.shape:
        return False
    d = np.max(np.abs(a[:, None, :] - b[None, :, :]), axis=2)
    return bool(np.all(d.min(axis=1) <= tol) and np.all(d.min(axis=0) <= tol))
