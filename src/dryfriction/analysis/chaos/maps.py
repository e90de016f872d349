"""The stroboscopic (time-T) map of the oscillator, (z, z') at t = k T, through the FMU or the exact
solution.

Everything is non-dimensional (method.md (2)): z = k x / P0, z' = dz/dtau, tau = w0 t, T the
excitation period. A map is started *afresh* at each call of :meth:`FMUMap.advance`: the FMU is reset and
initialised at (z, z') with the excitation phase phi (a whole number of periods later the phase is
the same), so that two calls from nearby points differ only by their initial point and not by any
history the integrator carries (Bossak acceleration, caches). This is what the two-trajectory
Lyapunov method needs: with the Bossak schemes a continuous FMU run and one restarted from its own
state differ by about 1e-11 after a period, more than the initial separations used. The default
scheme is the FMU's ``exact`` one (closed form between events, about 1e-13; h has no effect);
``located`` and the first-order schemes stay selectable.

:class:`FMUMap` drives the FMU through the package's public API (``OscillatorFMU2.start``,
``step_to``, ``get``); :class:`ExactMap` stitches the closed-form phases of
:mod:`dryfriction.references.exact`, an independent reference.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ...references.exact import solve_exact
from ...drivers.oscillator import SCHEMES, OscillatorFMU2, Settings
from ...params import Oscillator

__all__ = ["Point", "StroboscopicMap", "FMUMap", "ExactMap", "NDParams", "DEFAULT_SCHEME", "check_scheme",
           "scheme_label", "scheme_names", "step_free"]

# reference SI scales (the non-dimensional results do not depend on them)
M_REF, K_REF, P0_REF, MU_S_REF = 1.0, 100.0, 1.0, 0.4

Point = tuple[float, float]


def scheme_names() -> list[str]:
    """The FMU's integration schemes (from the driver: a new scheme appears here when it lands)."""
    return list(SCHEMES)


#: the FMU scheme the chaos tools use unless told otherwise: the closed form between events (exact
#: to about 1e-13, the step h has no effect on it)
DEFAULT_SCHEME = "exact"


def step_free(scheme: str) -> bool:
    """True for the FMU's exact scheme, whose result does not depend on the step h."""
    return scheme == "exact"


def scheme_label(scheme: str, steps_per_period: int) -> str:
    """How a result names its scheme: ``FMU scheme exact`` or ``FMU scheme located, h = T/1000``."""
    return f"FMU scheme {scheme}" + ("" if step_free(scheme) else f", h = T/{int(steps_per_period)}")


def check_scheme(scheme: str) -> str:
    """The scheme name if the maps know it, else a ValueError naming the valid ones."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {', '.join(SCHEMES)}, not {scheme!r}")
    return scheme


@dataclass(frozen=True)
class NDParams:
    """Non-dimensional parameters of method.md (2)."""

    lam: float
    mu_s_sigma: float
    chi: float
    zeta: float = 0.0
    phi: float = 0.0

    @classmethod
    def from_mapping(cls, m: Mapping[str, float], **over: float) -> "NDParams":
        """Non-dimensional parameters from a mapping with the keys ``lam``, ``mu_s_sigma``, ``chi`` and
        optionally ``zeta``, ``phi``; keyword arguments override."""
        d = {k: float(m[k]) for k in ("lam", "mu_s_sigma", "chi", "zeta", "phi") if k in m}
        d.update({k: float(v) for k, v in over.items()})
        return cls(**d)

    def oscillator(self, z0: float = 0.0, dz0: float = 0.0) -> Oscillator:
        """The :class:`~dryfriction.params.Oscillator` of these parameters on the reference scales, starting
        at (z0, dz0)."""
        return Oscillator.from_nondimensional(lam=self.lam, mu_s_sigma=self.mu_s_sigma, chi=self.chi,
                                              zeta=self.zeta, z0=z0, dz0=dz0, phi=self.phi,
                                              m=M_REF, k=K_REF, P0=P0_REF, mu_s=MU_S_REF)

    @property
    def period_tau(self) -> float:
        """The excitation period in tau = w0 t: 2 pi / lambda."""
        return 2.0 * math.pi / self.lam


class StroboscopicMap(Protocol):
    """The time-T map of the oscillator in (z, z') = (k x / P0, dz/dtau): what the chaos tools iterate
    (:class:`FMUMap`, :class:`ExactMap`)."""
    nd: NDParams
    label: str
    T: float          # excitation period, s

    def advance(self, z: float, dz: float, periods: int = 1) -> Point:
        """The point (z, z') after ``periods`` excitation periods from (z, dz)."""

    def orbit(self, z0: float, dz0: float, transient: int, n: int) -> np.ndarray:
        """``n`` successive points of the map, one per period, after ``transient`` periods from (z0, dz0): an
        array of shape (n, 2)."""


class FMUMap:
    """The time-T map through one FMU instance (reset at every :meth:`FMUMap.advance`)."""

    def __init__(self, fmu: OscillatorFMU2, nd: NDParams, steps_per_period: int = 1000, scheme: str = DEFAULT_SCHEME,
                 alpha: float = -0.1) -> None:
        self.fmu, self.nd = fmu, nd
        self.scheme = check_scheme(scheme)
        self.steps_per_period = int(steps_per_period)
        p = nd.oscillator()
        self._p = p
        self.T = p.period
        self._xs, self._vs = p.P0 / p.k, p.P0 * p.w0 / p.k      # z = x / xs, z' = v / vs
        self.settings = Settings(h=self.T / self.steps_per_period, alpha=alpha, scheme=scheme)
        self.label = scheme_label(scheme, self.steps_per_period)

    @property
    def z_scale(self) -> float:
        """x (m) per unit of z."""
        return self._xs

    def start(self, z: float, dz: float) -> None:
        """Reset and initialise the FMU at (z, z') with phase phi (t = 0); step on with ``fmu.step_to``."""
        self.fmu.start(self._p.with_(x0=z * self._xs, v0=dz * self._vs), self.settings)

    def point(self) -> Point:
        """(z, z') of the FMU now."""
        g = self.fmu.get(("x", "v"))
        return g["x"] / self._xs, g["v"] / self._vs

    def advance(self, z: float, dz: float, periods: int = 1) -> Point:
        """(z, z') after ``periods`` periods from (z, z') at phase phi, from a fresh start."""
        self.start(z, dz)
        self.fmu.step_to(periods * self.T)
        return self.point()

    def orbit(self, z0: float, dz0: float, transient: int, n: int) -> np.ndarray:
        """Stroboscopic points k = transient .. transient + n - 1 of one continuous run, shape (n, 2)."""
        self.start(z0, dz0)
        out = np.empty((n, 2))
        for j in range(n):
            k = transient + j
            if k > 0:
                self.fmu.step_to(k * self.T)
            out[j] = self.point()
        return out


class ExactMap:
    """The time-T map of the exact piecewise solution (:func:`dryfriction.references.exact.solve_exact`)."""

    def __init__(self, nd: NDParams) -> None:
        self.nd = nd
        p = nd.oscillator()
        self._p = p
        self.T = p.period
        self._xs, self._vs = p.P0 / p.k, p.P0 * p.w0 / p.k
        self.label = "exact solution (dryfriction.references.exact)"

    def advance(self, z: float, dz: float, periods: int = 1) -> Point:
        """The point (z, z') after ``periods`` excitation periods from (z, dz), by the exact piecewise
        solution."""
        p = self._p.with_(x0=z * self._xs, v0=dz * self._vs)
        t = periods * self.T
        sol = solve_exact(p, t)
        x, v, _, _ = sol.evaluate(np.array([t]))
        return float(x[0]) / self._xs, float(v[0]) / self._vs

    def orbit(self, z0: float, dz0: float, transient: int, n: int) -> np.ndarray:
        """``n`` successive points of the map, one per period, after ``transient`` periods from (z0, dz0): an
        array of shape (n, 2)."""
        out = np.empty((n, 2))
        z, dz = z0, dz0
        if transient:
            z, dz = self.advance(z, dz, transient)
        for j in range(n):
            if j:
                z, dz = self.advance(z, dz, 1)
            out[j] = z, dz
        return out
