"""Steady-state amplitude formulas of the undamped dry-friction oscillator (method.md section 5).

Both take the parameters from an Oscillator; `lam` (scalar or array) overrides p.lam.  Amplitudes
are returned in metres, nan where the formula does not apply.

Inman (Den Hartog's equivalent energy loss, stiction neglected):

    X = (P0 / k) sqrt(1 - (4 mu_k N / (pi P0))^2) / |1 - lambda^2|,   valid for 4 mu_k N < pi P0

Den Hartog (1931), exact non-stop steady state for zeta = 0, friction force F = mu_k N, r = lambda:

    X k / P0 = sqrt(V^2 - (F / P0)^2 U^2),   V = 1 / (1 - r^2),   U = tan(pi / (2 r)) / r

valid while the root is real and the block slides on at its turning points, k X r^2 > F_b.  At a
turning point the net applied force is P(t) - k x = k X r^2 (method.md; the phase follows from
sin(phi) = (F / P0) U / V, cos(phi) = -(X k / P0) / V when the half cycle starts at x = -X).
"""

from __future__ import annotations

import math
from typing import Optional, Union

import numpy as np

from ..params import Oscillator

__all__ = ["inman_amplitude", "den_hartog_amplitude", "den_hartog_state"]

ArrayLike = Union[float, np.ndarray]


def _ratio(p: Oscillator, lam: Optional[ArrayLike]) -> np.ndarray:
    return np.asarray(p.lam if lam is None else lam, dtype=float)


def _out(x: np.ndarray) -> ArrayLike:
    return float(x) if x.ndim == 0 else x


def inman_amplitude(p: Oscillator, lam: Optional[ArrayLike] = None) -> ArrayLike:
    """Inman's approximate steady-state amplitude, m (nan where 4 mu_k N >= pi P0)."""
    r = _ratio(p, lam)
    P0 = abs(p.P0)
    q = 4.0 * p.mu_k * p.N / (math.pi * P0) if P0 > 0 else math.inf
    if q >= 1.0:
        return _out(np.full(r.shape, np.nan))
    with np.errstate(divide="ignore"):
        x = (P0 / p.k) * math.sqrt(1.0 - q * q) / np.abs(1.0 - r * r)
    return _out(x)


def _den_hartog_nondim(p: Oscillator, r: np.ndarray) -> np.ndarray:
    """X k / P0 of Den Hartog's solution (nan where the root is not real or the block sticks)."""
    P0 = abs(p.P0)
    f = p.mu_k * p.N / P0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        V = 1.0 / (1.0 - r * r)
        U = np.tan(np.pi / (2.0 * r)) / r
        rad = V * V - (f * U) ** 2
        xh = np.where(rad >= 0.0, np.sqrt(np.where(rad >= 0.0, rad, 0.0)), np.nan)
        sticks = xh * r * r < p.breakaway / P0
    return np.where(sticks, np.nan, xh)


def den_hartog_amplitude(p: Oscillator, lam: Optional[ArrayLike] = None) -> ArrayLike:
    """Den Hartog's exact non-stop steady-state amplitude, m (nan where it does not hold).

    The stick check uses the breakaway limit F_b = max(mu_s, mu_k) N (= mu_s N for chi <= 1).
    """
    if p.P0 == 0:
        raise ValueError("Den Hartog's amplitude needs P0 != 0")
    r = _ratio(p, lam)
    return _out(_den_hartog_nondim(p, r) * abs(p.P0) / p.k)


def den_hartog_state(p: Oscillator) -> Oscillator:
    """p with x0, v0, phi set on Den Hartog's steady state at the turning point x = -X, v = 0
    (start of the forward half cycle), for P0 > 0 and omega > 0; ValueError where it does not
    hold."""
    if not (p.P0 > 0 and p.omega > 0):
        raise ValueError("den_hartog_state needs P0 > 0 and omega > 0")
    r = p.lam
    xh = float(_den_hartog_nondim(p, np.asarray(r)))
    if not math.isfinite(xh):
        raise ValueError(f"Den Hartog's non-stop solution does not hold at lambda = {r}")
    V = 1.0 / (1.0 - r * r)
    U = math.tan(math.pi / (2.0 * r)) / r
    f = p.mu_k * p.N / p.P0
    phi = math.atan2(f * U / V, -xh / V)
    return p.with_(x0=-xh * p.P0 / p.k, v0=0.0, phi=phi)
