"""The Hopf belt speed, from the model and from the formula (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np

from ...drivers.oscillator import OscillatorFMU2
from ...roots import find_root
from .equilibria import _equilibrium
from .flow import _fmu, _Flow
from .problem import BeltProblem


def hopf_formula(prob: BeltProblem) -> float:
    """The analytic Hopf belt speed (stribeck with delta = 1; NaN otherwise or when steady sliding is
    stable at every speed)."""
    if prob.law != "stribeck" or prob.delta != 1.0:
        return math.nan
    from ...references.belt import hopf_belt_speed

    p = prob.oscillator
    return hopf_belt_speed(p.c, p.N, p.mu_s, p.mu_k, prob.v_s)


@dataclass
class HopfPoint:
    """Where steady sliding loses stability as the belt speed falls."""

    v_belt: float                    # located from the model, m/s
    formula: float                   # the analytic v* (stribeck, delta = 1), NaN otherwise
    bracket: tuple[float, float]     # the scan's interval with the sign change
    evaluations: int
    h: float                         # the FMU's internal step
    multipliers: np.ndarray          # steady sliding's over tau at the located speed (a complex pair on |mu| = 1)
    tau: float                       # s
    frequency: float                 # |arg mu| / tau there, rad/s (the frequency the orbits are born with)

    @property
    def relative_error(self) -> float:
        """The located belt speed's relative distance from the formula's, c + N mu'(v_belt) = 0."""
        return abs(self.v_belt - self.formula) / abs(self.formula)


def locate_hopf(prob: BeltProblem, lo: float, hi: float, *, num: int = 12, fmu: OscillatorFMU2 | None = None,
                xtol: float = 1e-13) -> HopfPoint:
    """The belt speed in [lo, hi] (same sign, |lo| < |hi|) where steady sliding changes stability: its
    multipliers over tau = a quarter of the natural period (a complex pair near +-i there, well apart)
    followed over a scan of ``num`` speeds (geometric), then Brent's method
    (:func:`dryfriction.roots.find_root`, from the scan's two speeds around the sign change) on the
    growth rate ln |mu|max / tau. RuntimeError if no sign change, or if what crosses |mu| = 1 is not a
    complex pair (then it is not a Hopf point)."""
    if not (lo * hi > 0 and abs(lo) < abs(hi)):
        raise ValueError(f"locate_hopf needs 0 < |lo| < |hi| with one sign, not lo = {lo}, hi = {hi}")
    with _fmu(fmu) as f:
        n = [0]

        tau = prob.natural_period / 4.0

        def rate(vb: float) -> float:
            n[0] += 1
            return _equilibrium(_Flow(f, prob.with_(v_belt=float(vb))), tau).growth_rate

        s = math.copysign(1.0, lo)
        speeds = s * np.geomspace(abs(lo), abs(hi), num)
        rates = [rate(v) for v in speeds]
        k = next((i for i in range(num - 1) if rates[i] > 0 >= rates[i + 1] or rates[i] <= 0 < rates[i + 1]), None)
        if k is None:
            raise RuntimeError(f"steady sliding does not change stability between {lo:g} and {hi:g} m/s "
                               f"(growth rates {rates[0]:.3g} ... {rates[-1]:.3g} 1/s)")
        a, b = float(speeds[k]), float(speeds[k + 1])
        v = find_root(rate, a, b, fa=rates[k], fb=rates[k + 1], xtol=xtol, rtol=1e-15, maxiter=200)
        eq = _equilibrium(_Flow(f, prob.with_(v_belt=v)), tau)
        mu = eq.multipliers
        if not abs(mu[0].imag) > 1e-6:
            raise RuntimeError(f"steady sliding changes stability at v_belt = {v:.8g} m/s through a real multiplier "
                               f"({mu[0].real:.6g}), not a complex pair: not a Hopf point")
        return HopfPoint(v, hopf_formula(prob), (a, b), n[0] + 1, prob.step, mu, tau,
                         abs(cmath.phase(complex(mu[0]))) / tau)
