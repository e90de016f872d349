"""What the block does on the belt: self_excited (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...drivers.oscillator import OscillatorFMU2
from .equilibria import Equilibrium, _equilibrium
from .flow import _fmu, _Flow
from .hopf import hopf_formula
from .orbit import BeltOrbit, _Orbit
from .problem import BeltProblem
from .transients import transient


@dataclass
class SelfExcited:
    """What the block does on the belt: ``motion`` is "stick-slip" (a stable orbit with a stick phase),
    "slip orbit" (a stable orbit that never sticks), "steady sliding" (no stable orbit found, the
    equilibrium stable) or "not converged" (the reason says why)."""

    problem: BeltProblem
    motion: str
    orbit: BeltOrbit | None
    equilibrium: Equilibrium
    reason: str = ""
    hopf_formula: float = math.nan   # v* = v_s ln(N (mu_s - mu_k) / (c v_s)) (stribeck, delta = 1)


def self_excited(prob: BeltProblem, *, fmu: OscillatorFMU2 | None = None, periods: float = 40.0,
                 guess: tuple[float, float] | None = None, tol: float | None = None) -> SelfExcited:
    """The self-excited motion of ``prob``: the equilibrium's stability, then the orbit from a guess
    (v0, T) or from a transient of ``periods`` natural periods (at least five estimated stick-slip
    cycles) that starts riding on the belt at x_eq (a stick-slip orbit passes there). A transient
    that decays (successive crossings slower by more than 1e-3) while the equilibrium is stable is
    steady sliding; otherwise Newton from its last crossing."""
    with _fmu(fmu) as f:
        flow = _Flow(f, prob)
        eq = _equilibrium(flow)
        vstar = hopf_formula(prob)
        t = (1e-12 if prob.scheme == "exact" else 1e-10) if tol is None else tol
        solver = _Orbit(flow, t, 30)
        if guess is None:
            # at least 5 cycles of stick-slip: a natural period and the ride from the catch to the
            # breakaway, at most about 2 (F_s - N min(mu_s, mu_k)) / (k |v_belt|) (Coulomb's cycle with
            # the smallest kinetic friction)
            p = prob.oscillator
            ride = 2.0 * abs(p.mu_s - p.mu_k) * p.N / (p.k * abs(prob.v_belt))
            periods = max(periods, 5.0 * (1.0 + ride / prob.natural_period))
            tr = transient(prob, periods=periods, fmu=f)
            X, V = prob.scales
            amp = tr.window()["amplitude"]
            cv = np.abs(tr.crossing_v)
            decays = cv.size < 3 or cv[-1] < (1.0 - 1e-3) * cv[-2] or amp < 1e-9 * X
            if decays and eq.stable:
                return SelfExcited(prob, "steady sliding", None, eq,
                                   "the motion from riding on the belt decays to steady sliding; the equilibrium is "
                                   "stable", vstar)
            if cv.size < 3:
                return SelfExcited(prob, "not converged", None, eq,
                                   f"the transient of {periods:g} natural periods crossed the section fewer than 3 "
                                   "times and the equilibrium is unstable", vstar)
            guess = (float(tr.crossing_v[-1]), float(tr.crossings[-1] - tr.crossings[-2]))
        orbit = solver.solve(*guess)
        if not orbit.converged:
            return SelfExcited(prob, "not converged", orbit, eq, orbit.reason, vstar)
        if not orbit.stable:
            motion = "steady sliding" if eq.stable else "not converged"
            return SelfExcited(prob, motion, orbit, eq, "the orbit found is unstable" +
                               ("; the equilibrium is stable" if eq.stable else ""), vstar)
        return SelfExcited(prob, "stick-slip" if orbit.sticks else "slip orbit", orbit, eq, "", vstar)
