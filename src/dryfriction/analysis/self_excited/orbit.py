"""The periodic orbit: Newton shooting on R(v0, T), and the section map (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...drivers.oscillator import OscillatorFMU2
from ...roots import find_root
from .flow import _fmu, _Flow
from .problem import FD_STEP, STABILITY_MARGIN, TRIVIAL, BeltProblem
from .transients import transient


@dataclass
class BeltOrbit:
    """One periodic orbit of the autonomous belt oscillator (module doc)."""

    period: float                    # s
    v0: float                        # m/s: the velocity on the section x = x_eq
    x_eq: float                      # m: the section
    multipliers: np.ndarray          # (trivial, nontrivial), complex; with a stick phase (trace M, 0)
    stable: bool                     # |nontrivial| < 1 - STABILITY_MARGIN
    amplitude: float                 # (x_max - x_min) / 2 over the cycle, m (the FMU's observables)
    offset: float                    # (x_max + x_min) / 2, m
    x_max: float
    x_min: float
    stick_fraction: float            # share of the cycle stuck on the belt
    transitions: int                 # stick/slip mode changes per cycle (the FMU's count)
    residual: float                  # scaled (module doc)
    converged: bool
    reason: str = ""                 # why not converged ("" when converged)
    iterations: int = 0
    jacobian: str = ""               # "sensitivity" | "central differences"
    monodromy: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    section_multiplier: float = math.nan   # dP/dv0 of the section map (= the nontrivial one; NaN with a stick phase)

    @property
    def nontrivial(self) -> complex:
        """The orbit's nontrivial Floquet multiplier (the other one is 1, along the flow)."""
        return complex(self.multipliers[1])

    @property
    def sticks(self) -> bool:
        """Whether the orbit has a stick phase (it rides the belt for a while)."""
        return self.stick_fraction > 0.0


class _Orbit:
    """Newton on R(v0, T) for one problem (module doc)."""

    def __init__(self, flow: _Flow, tol: float, max_iter: int) -> None:
        self.flow, self.tol, self.max_iter = flow, tol, max_iter
        self.prob = flow.prob

    def fd_step(self, v0: float) -> float:
        """The differences' relative step: FD_STEP, smaller on an orbit that is slow on the section
        (|v0| << X w0: the map is steep there), at least 1e-3 FD_STEP."""
        return FD_STEP * min(1.0, max(abs(v0) / self.flow.V, 1e-3))

    def residual(self, v0: float, T: float, observe: bool = False) -> tuple[np.ndarray, dict[str, float]]:
        xe = self.prob.x_eq
        e = self.flow.end(xe, v0, T, observe)
        return np.array([(e["x"] - xe) / self.flow.X, (e["v"] - v0) / self.flow.V]), e

    def dR(self, v0: float, T: float, e: dict[str, float]) -> np.ndarray:
        """dR / d(v0, T), scaled."""
        X, V = self.flow.X, self.flow.V
        M = self.flow.jacobian(self.prob.x_eq, v0, T, e, columns=(1,), step=self.fd_step(v0))
        if int(e["mode"]) == 0:          # stuck at the end: rides the belt
            fx, fv = self.prob.v_belt, 0.0
        else:
            fx, fv = e["v"], self.prob.acceleration(e["x"], e["v"])
        return np.array([[M[0, 1] / X, fx / X], [(M[1, 1] - 1.0) / V, fv / V]])

    def solve(self, v0: float, T: float) -> BeltOrbit:
        d = -self.prob.direction
        r, e = self.residual(v0, T)
        nr = float(np.max(np.abs(r)))
        it = 0
        reason = ""
        while nr > self.tol:
            if it >= self.max_iter:
                reason = f"no convergence in {self.max_iter} Newton steps (residual {nr:.3g})"
                break
            try:
                A = self.dR(v0, T, e)
                step = np.linalg.solve(A, -r)
            except (np.linalg.LinAlgError, FloatingPointError) as exc:
                reason = f"the Newton step failed: {exc}"
                break
            dv, dT = float(step[0]), float(step[1])
            lam, ok = 1.0, False
            for _ in range(30):
                vn, Tn = v0 + lam * dv, T + lam * dT
                if Tn > 0.05 * T and d * vn > 0:
                    try:
                        rn, en = self.residual(vn, Tn)
                    except FloatingPointError:
                        rn, en = None, None
                    if rn is not None:
                        nrn = float(np.max(np.abs(rn)))
                        if nrn < (1.0 - 1e-4 * lam) * nr or nrn <= self.tol:
                            ok = True
                            break
                lam *= 0.5
            it += 1
            if not ok:
                reason = f"the line search found no decrease (residual {nr:.3g})"
                break
            v0, T, r, e, nr = vn, Tn, rn, en, nrn      # type: ignore[assignment]
        return self.finish(v0, T, nr, it, reason)

    def finish(self, v0: float, T: float, nr: float, it: int, reason: str) -> BeltOrbit:
        prob, flow = self.prob, self.flow
        _, e = self.residual(v0, T, observe=True)
        if not reason and abs(v0) < TRIVIAL * flow.V:
            reason = (f"Newton converged onto steady sliding (|v0| = {abs(v0):.3g} m/s on the section), not onto "
                      "an orbit")
        converged = not reason and nr <= self.tol
        xe = prob.x_eq
        try:
            M = flow.jacobian(xe, v0, T, e, step=self.fd_step(v0))
        except FloatingPointError:
            M = np.full((2, 2), np.nan)
        stick = e["stick_fraction"]
        sec = math.nan
        if stick > 0.0:
            mu = np.array([complex(np.trace(M)), 0j])
        elif np.all(np.isfinite(M)):
            ev = np.linalg.eigvals(M).astype(complex)
            i = int(np.argmin(np.abs(ev - 1.0)))
            mu = np.array([ev[i], ev[1 - i]])
            a = prob.acceleration(e["x"], e["v"])
            sec = float(M[1, 1] - a / e["v"] * M[0, 1]) if e["v"] != 0.0 else math.nan
        else:
            mu = np.full(2, np.nan, dtype=complex)
        stable = bool(converged and abs(mu[1]) < 1.0 - STABILITY_MARGIN)
        return BeltOrbit(period=T, v0=v0, x_eq=xe, multipliers=mu, stable=stable,
                         amplitude=(e["x_max"] - e["x_min"]) / 2.0, offset=(e["x_max"] + e["x_min"]) / 2.0,
                         x_max=e["x_max"], x_min=e["x_min"], stick_fraction=stick,
                         transitions=int(e["transitions"]), residual=nr, converged=converged, reason=reason,
                         iterations=it, jacobian="sensitivity" if flow.exact else "central differences",
                         monodromy=M, section_multiplier=sec)


def find_orbit(prob: BeltProblem, v0: float, T: float, *, fmu: OscillatorFMU2 | None = None,
               tol: float | None = None, max_iter: int = 30) -> BeltOrbit:
    """The periodic orbit through (x_eq, v0) near the period T by Newton shooting (module doc).
    ``tol``: the scaled residual (default 1e-12 with scheme exact, 1e-10 with located)."""
    t = (1e-12 if prob.scheme == "exact" else 1e-10) if tol is None else tol
    with _fmu(fmu) as f:
        return _Orbit(_Flow(f, prob), t, max_iter).solve(float(v0), float(T))


def section_map(prob: BeltProblem, v0: float, *, fmu: OscillatorFMU2 | None = None,
                samples: int = 512, periods: float = 3.0) -> tuple[float, float]:
    """(v1, t1): the velocity and the time of the next crossing of the section from (x_eq, v0), located
    by a sampled run and Brent's method (:func:`dryfriction.roots.find_root`) on x(t) - x_eq with the
    FMU's runs (a check of the multipliers by differences of this map)."""
    with _fmu(fmu) as f:
        flow = _Flow(f, prob)
        xe, d = prob.x_eq, -prob.direction
        T0 = prob.natural_period
        tr = transient(prob, xe, v0, periods, samples, fmu=f)
        later = tr.crossings[tr.crossings > 0.1 * T0]
        if later.size == 0:
            raise RuntimeError("no return to the section")
        dt = T0 / samples
        a, b = later[0] - 2 * dt, later[0] + 2 * dt

        def g(t: float) -> float:
            return d * (flow.end(xe, v0, t)["x"] - xe)

        t1 = find_root(g, a, b, xtol=1e-15, rtol=1e-15, maxiter=200)
        return flow.end(xe, v0, t1)["v"], t1
