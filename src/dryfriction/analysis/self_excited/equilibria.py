"""Steady sliding and its stability (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...drivers.oscillator import OscillatorFMU2
from .flow import _fmu, _Flow
from .problem import EQ_FD_STEP, NEUTRAL, BeltProblem


@dataclass
class Equilibrium:
    """Steady sliding: the block at rest at x_eq while the belt slides under it."""

    x_eq: float                      # m
    multipliers: np.ndarray          # of the flow over tau from the equilibrium (complex, |mu| descending)
    tau: float                       # s
    stable: bool                     # every |mu| < 1 - NEUTRAL
    neutral: bool                    # | |mu|max - 1 | <= NEUTRAL
    growth_rate: float               # ln |mu|max / tau, 1/s (< 0: disturbances decay)
    jacobian: str                    # "sensitivity" | "central differences"

    @property
    def mu_max(self) -> float:
        """The largest modulus of the equilibrium's multipliers (below 1: steady sliding is stable)."""
        return float(np.max(np.abs(self.multipliers)))


def _equilibrium(flow: _Flow, tau: float | None = None) -> Equilibrium:
    prob = flow.prob
    t = prob.natural_period if tau is None else float(tau)
    xe = prob.x_eq
    M = flow.jacobian(xe, 0.0, t, step=EQ_FD_STEP, richardson=True)
    mu = np.linalg.eigvals(M).astype(complex)
    mu = mu[np.argsort(-np.abs(mu))]
    mmax = float(np.abs(mu[0]))
    rate = math.log(mmax) / t if mmax > 0 else -math.inf
    return Equilibrium(x_eq=xe, multipliers=mu, tau=t, stable=bool(mmax < 1.0 - NEUTRAL),
                       neutral=bool(abs(mmax - 1.0) <= NEUTRAL), growth_rate=rate,
                       jacobian="sensitivity" if flow.exact else "central differences")


def equilibrium(prob: BeltProblem, tau: float | None = None, *, fmu: OscillatorFMU2 | None = None) -> Equilibrium:
    """Steady sliding of ``prob`` and its stability: the multipliers of the FMU's flow over ``tau``
    (default: one natural period) from (x_eq, 0)."""
    with _fmu(fmu) as f:
        return _equilibrium(_Flow(f, prob), tau)
