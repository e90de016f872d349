"""Largest Lyapunov exponent of the stroboscopic map by the two-trajectory method with periodic
renormalisation (Benettin et al. 1980).

From a point on the attractor (after a transient) a reference and a perturbed point d0 apart are
advanced by ``renorm`` periods from fresh starts (see :mod:`dryfriction.analysis.chaos.maps`); the
separation d (Euclidean in (z, z')) is logged, the perturbed point is put back at distance d0
along the new separation, and so on. The exponent per excitation period is the mean of ln(d / d0)
per period; per second it is that divided by T. The convergence estimate is the standard error of
the means of 10 consecutive blocks of the run (batch means), and the difference between the
estimates over the two halves of the run.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from .maps import StroboscopicMap

__all__ = ["LyapunovResult", "benettin"]

#: a separation below this (absolute, in z units) is at the level of rounding: the perturbation
#: collapsed (both points stuck at the same place); ln(d / d0) is then floored at ln(D_FLOOR / d0)
D_FLOOR = 1e-14
N_BLOCKS = 10


@dataclass
class LyapunovResult:
    """The largest Lyapunov exponent of a stroboscopic map, per period and per second, with its convergence
    estimates (batch-means standard error, second half minus first half) and the run's parameters."""
    lyapunov_per_period: float
    lyapunov_per_second: float
    stderr_per_period: float          # batch-means standard error (10 blocks)
    half_difference: float            # estimate over the 2nd half minus over the 1st half
    periods: int                      # periods measured (after the transient)
    transient: int
    renorm: int
    d0: float
    collapses: int                    # renormalisations where the separation fell below D_FLOOR
    period_s: float
    method: str
    strobe: np.ndarray = field(repr=False)     # reference (z, z') at every renormalisation, (n, 2)
    running: np.ndarray = field(repr=False)    # running estimate per period after each interval

    def as_json(self) -> dict[str, Any]:
        """The result as a JSON-ready dict (the stroboscopic record and the running estimate left out; the
        last point kept)."""
        d = {k: v for k, v in asdict(self).items() if k not in ("strobe", "running")}
        d["last_point"] = [float(x) for x in self.strobe[-1]]
        return d


def benettin(m: StroboscopicMap, z0: float, dz0: float, periods: int = 500, transient: int = 100,
             d0: float = 1e-8, renorm: int = 1, direction: tuple[float, float] = (1.0, 1.0)) -> LyapunovResult:
    """Largest Lyapunov exponent of the map ``m`` from (z0, dz0) (see the module docstring).

    ``periods`` is rounded down to a whole number of renormalisation intervals."""
    if periods < renorm or renorm < 1:
        raise ValueError(f"need periods >= renorm >= 1, got periods = {periods}, renorm = {renorm}")
    if not (0.0 < d0 < 1e-2):
        raise ValueError(f"the initial separation d0 must be in (0, 1e-2), not {d0}")
    n = periods // renorm
    z, dz = (m.advance(z0, dz0, transient) if transient > 0 else (z0, dz0))
    ex, ev = direction
    norm = math.hypot(ex, ev)
    ex, ev = ex / norm, ev / norm
    logs = np.empty(n)
    strobe = np.empty((n, 2))
    collapses = 0
    for i in range(n):
        zr, vr = m.advance(z, dz, renorm)
        zp, vp = m.advance(z + d0 * ex, dz + d0 * ev, renorm)
        ddz, ddv = zp - zr, vp - vr
        d = math.hypot(ddz, ddv)
        if not math.isfinite(d):
            raise RuntimeError(f"non-finite separation after {i * renorm} periods")
        if d < D_FLOOR:
            collapses += 1
            logs[i] = math.log(D_FLOOR / d0)
            ex, ev = 1.0 / math.sqrt(2.0), 1.0 / math.sqrt(2.0)
        else:
            logs[i] = math.log(d / d0)
            ex, ev = ddz / d, ddv / d
        z, dz = zr, vr
        strobe[i] = zr, vr
    per_interval = logs / renorm
    lam = float(per_interval.mean())
    nb = min(N_BLOCKS, n)
    blocks = np.array([b.mean() for b in np.array_split(per_interval, nb)])
    stderr = float(blocks.std(ddof=1) / math.sqrt(nb)) if nb > 1 else float("nan")
    h = n // 2
    half = float(per_interval[h:].mean() - per_interval[:h].mean()) if h else float("nan")
    running = np.cumsum(per_interval) / np.arange(1, n + 1)
    T = m.T
    return LyapunovResult(lam, lam / T, stderr, half, n * renorm, transient, renorm, d0, collapses, T,
                          m.label, strobe, running)
