"""Self-excited stick-slip: periodic orbits of the autonomous belt oscillator (no excitation, a belt
at a constant speed), the stability of steady sliding, the Hopf belt speed located from the model
and the orbit branch continued in the belt speed (docs/self_excited.md).

    m x'' + c x' + k x = F_0 + F,   F the friction on v_rel = v - v_belt (coulomb or stribeck),

F_0 a constant force (the input F_ext; or P0 cos(phi) with omega = 0). Steady sliding is the
equilibrium x_eq = (F_0 + sign(v_belt) N mu(|v_belt|)) / k, v = 0.

**The orbit.** The period T is an unknown. The Poincare section is x = x_eq crossed with
sign(dx/dt) = -sign(v_belt), where the block always slides (it moves against the belt); the phase
condition is the section itself: the unknowns are the velocity v0 on it and T, the residual

    R(v0, T) = (x(T) - x_eq, v(T) - v0)        from (x_eq, v0) at t = 0,

with one run of the FMU (:class:`~dryfriction.drivers.oscillator.OscillatorFMU2`, the belt speed its input v_belt)
per evaluation. Newton on R with dR/dT = the vector field at the end, (v(T), a(T)), and dR/dv0 the
second column of the flow's Jacobian M = d(x, v)(T) / d(x, v)(0):

- scheme ``exact`` (coulomb): M is the FMU's own sensitivity (``sensitivity = true``: dx_dx0, ...);
- scheme ``located`` (coulomb or stribeck): M by central finite differences of the located map
  (steps of 1e-6 of the state's scales), said in the result (``jacobian``).

M's eigenvalues are the Floquet multipliers: the trivial one 1 (along the flow) and the nontrivial
one (the section map's derivative). A stick phase on the orbit makes M rank one (the block rides on
the belt whatever it started from): the nontrivial multiplier is then exactly 0 and the trivial one
trace(M). Converged when the scaled residual ``max(|R_x| / X, |R_v| / (X w0))`` is at most ``tol``
(X = mu_s N / k, the friction's deflection; w0 = sqrt(k / m)).

**Steady sliding** is stable when both multipliers of the flow over a fixed time tau (a natural
period) from the equilibrium are inside the unit circle (by more than NEUTRAL = 1e-6; within it of
the circle: neutral) (M by central differences with ``located``,
the sensitivity with ``exact``). With Stribeck friction (delta = 1) it loses stability at the Hopf
belt speed where c + N mu'(|v_belt|) = 0: :func:`locate_hopf` finds it from the model, by Brent's
method on ``ln |mu|max / tau`` (the growth rate of the equilibrium's flow) in the belt speed.

**The branch.** :func:`continue_orbits` follows the orbit in v_belt by pseudo-arclength
continuation in (v0, T, v_belt) (dR/dv_belt by central differences: the section moves with x_eq),
from stick-slip at low belt speed up to where the branch turns and on to where its amplitude vanishes
(the Hopf).
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import FMUError
from ..drivers.oscillator import OscillatorFMU2, Settings
from ..params import Oscillator

__all__ = ["BeltProblem", "BeltOrbit", "Equilibrium", "SelfExcited", "HopfPoint", "Branch", "BranchPoint",
           "LAWS", "SCHEMES", "equilibrium", "find_orbit", "self_excited", "locate_hopf", "continue_orbits",
           "transient", "section_map", "hopf_formula", "Transient"]

LAWS = {"coulomb": 1, "stribeck": 2}
SCHEMES = ("located", "exact")
#: an orbit (and steady sliding) is stable when its nontrivial multipliers have |mu| < 1 - STABILITY_MARGIN
STABILITY_MARGIN = 1e-9
#: steady sliding is neutral (neither stable nor unstable: e.g. undamped Coulomb, a centre) when its
#: largest |mu| is within this of 1 (the located scheme's own damping and the differences' error are
#: far smaller: 5e-8 over a period at 2000 steps)
NEUTRAL = 1e-6
#: a solution with |v0| under TRIVIAL V on the section is steady sliding itself (R vanishes there
#: for every T), not an orbit
TRIVIAL = 1e-6
#: the most samples of a transient (a slow belt's long stick phases)
MAX_SAMPLES = 200_000
#: internal steps per natural period by default (scheme located)
STEPS_PER_PERIOD = 2000
#: relative size of the central differences, of the state's scales X and X w0
FD_STEP = 1e-6
#: the same for the equilibrium's flow (smooth there: larger steps, less of the located scheme's
#: rounding, with Richardson's extrapolation of the steps d and d / 2)
EQ_FD_STEP = 1e-4
JACOBIAN = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")


@dataclass(frozen=True)
class BeltProblem:
    """The autonomous belt oscillator: ``oscillator`` gives m, k, c, N, mu_s, chi (mu_k = chi mu_s) and
    no excitation (P0 = 0, or omega = 0: then P0 cos(phi) is a constant force); the belt at
    ``v_belt`` (m/s, nonzero); the friction law with v_s (m/s) and delta; ``F_ext`` a constant force
    (N); the FMU's ``scheme`` (located or exact) and internal step ``h`` (s; None: the natural
    period / 2000)."""

    oscillator: Oscillator
    v_belt: float
    law: str = "coulomb"
    v_s: float = 0.01
    delta: float = 1.0
    F_ext: float = 0.0
    scheme: str = "located"
    h: float | None = None

    def __post_init__(self) -> None:
        p = self.oscillator
        if not isinstance(p, Oscillator):
            raise ValueError(f"oscillator must be an Oscillator, not {type(p).__name__}")
        if p.P0 != 0.0 and p.omega > 0.0:
            raise ValueError(f"the self-excited motion needs no excitation: P0 = 0 or omega = 0 (a constant force), "
                             f"not P0 = {p.P0:g} at omega = {p.omega:g}")
        if not p.k > 0:
            raise ValueError(f"k (stiffness) must be > 0 for a self-excited motion (a sliding equilibrium), "
                             f"not {p.k!r}")
        if not p.N > 0:
            raise ValueError(f"N (normal force) must be > 0 for a self-excited motion, not {p.N!r}")
        for name in ("v_belt", "v_s", "delta", "F_ext"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite real number, not {v!r}")
            object.__setattr__(self, name, float(v))
        if self.v_belt == 0.0:
            raise ValueError("v_belt (belt speed) must be nonzero: a belt at rest excites nothing")
        if self.law not in LAWS:
            raise ValueError(f"law (friction law) must be one of {', '.join(LAWS)}, not {self.law!r}")
        if not self.v_s > 0:
            raise ValueError(f"v_s (Stribeck velocity) must be > 0, not {self.v_s!r}")
        if self.law == "stribeck" and not self.delta >= 1.0:
            raise ValueError(f"delta (Stribeck exponent) must be >= 1, not {self.delta!r}")
        if self.scheme not in SCHEMES:
            raise ValueError(f"scheme must be one of {', '.join(SCHEMES)}, not {self.scheme!r}")
        if self.scheme == "exact" and self.law != "coulomb":
            raise ValueError("scheme exact supports law coulomb only (its closed form needs a constant kinetic "
                             "friction): use scheme located for stribeck")
        if self.h is not None and not (isinstance(self.h, (int, float)) and math.isfinite(self.h) and self.h > 0):
            raise ValueError(f"h (internal step) must be > 0 s (or None: the natural period / {STEPS_PER_PERIOD}), "
                             f"not {self.h!r}")

    def with_(self, **kw: Any) -> "BeltProblem":
        """A copy with the given fields changed."""
        return replace(self, **kw)

    # ---- the model ----
    @property
    def m(self) -> float:
        """The block's mass, kg."""
        return self.oscillator.m

    @property
    def w0(self) -> float:
        """The natural angular frequency sqrt(k / m), rad/s."""
        return self.oscillator.w0

    @property
    def natural_period(self) -> float:
        """The natural period 2 pi / w0, s."""
        return 2.0 * math.pi / self.w0

    @property
    def step(self) -> float:
        """The FMU's internal step h: the given one, or the natural period over the default number of steps
        per period."""
        return self.natural_period / STEPS_PER_PERIOD if self.h is None else float(self.h)

    @property
    def force(self) -> float:
        """The constant force F_0, N."""
        p = self.oscillator
        return self.F_ext + (p.P0 * math.cos(p.phi) if p.omega == 0.0 else 0.0)

    @property
    def mu_k(self) -> float:
        """The kinetic friction coefficient."""
        return self.oscillator.mu_k

    def mu(self, u: float) -> float:
        """The sliding coefficient at the relative speed u >= 0."""
        p = self.oscillator
        if self.law == "coulomb":
            return p.mu_k
        return p.mu_k + (p.mu_s - p.mu_k) * math.exp(-((u / self.v_s) ** self.delta))

    @property
    def direction(self) -> int:
        """sign(v_belt)."""
        return 1 if self.v_belt > 0 else -1

    @property
    def x_eq(self) -> float:
        """The steady sliding position, m."""
        p = self.oscillator
        return (self.force + self.direction * p.N * self.mu(abs(self.v_belt))) / p.k

    @property
    def scales(self) -> tuple[float, float]:
        """(X, V): X = max(mu_s, mu_k) N / k, V = X w0."""
        p = self.oscillator
        X = max(p.mu_s, p.mu_k) * p.N / p.k
        X = X if X > 0 else abs(self.v_belt) / self.w0
        return X, X * self.w0

    def acceleration(self, x: float, v: float) -> float:
        """The vector field's acceleration of a sliding block (v != v_belt), m/s^2."""
        p = self.oscillator
        vr = v - self.v_belt
        fr = -math.copysign(1.0, vr) * p.N * self.mu(abs(vr)) if vr != 0.0 else 0.0
        return (self.force - p.c * v - p.k * x + fr) / p.m

    def settings(self, sensitivity: bool = False, t_obs: float | None = None) -> Settings:
        """The FMU settings of a run of this problem (belt speed, friction law, step; the state's Jacobian
        when ``sensitivity``; the observables from ``t_obs`` on)."""
        extra: dict[str, Any] = {"v_belt": self.v_belt}
        if self.F_ext != 0.0:
            extra["F_ext"] = self.F_ext
        if sensitivity:
            extra["sensitivity"] = True
        st = Settings(h=self.step, scheme=self.scheme, friction_law=LAWS[self.law], v_s=self.v_s, delta=self.delta,
                      extra=extra)
        if t_obs is not None:
            st.observe, st.t_obs_start, st.t_obs_stop = True, 0.0, t_obs
        return st


class _Flow:
    """The FMU's flow of one problem: (x, v) at t = 0 -> the state at t = T (one doStep)."""

    def __init__(self, fmu: OscillatorFMU2, prob: BeltProblem) -> None:
        self.fmu, self.prob = fmu, prob
        self.exact = prob.scheme == "exact"
        self.X, self.V = prob.scales
        self.evaluations = 0

    def _osc(self, x: float, v: float) -> Oscillator:
        p = self.prob.oscillator
        q = object.__new__(Oscillator)          # a checked one with x0, v0 replaced (finite)
        q.__dict__.update(p.__dict__, x0=float(x), v0=float(v))
        return q

    def end(self, x: float, v: float, T: float, observe: bool = False) -> dict[str, float]:
        """x, v, mode at T (with ``observe``: x_max, x_min, stick_fraction, transitions over [0, T];
        with scheme exact: the sensitivities too)."""
        if not (math.isfinite(x) and math.isfinite(v) and math.isfinite(T) and T > 0):
            raise FloatingPointError(f"not a state and a period: x = {x}, v = {v}, T = {T}")
        f = self.fmu
        f.start(self._osc(x, v), self.prob.settings(self.exact, T if observe else None))
        f.step_to(T)
        names = ("x", "v", "mode") + (("x_max", "x_min", "stick_fraction", "transitions") if observe else ()) \
            + (JACOBIAN if self.exact else ())
        self.evaluations += 1
        return {k: float(val) for k, val in f.get(names).items()}

    def jacobian(self, x: float, v: float, T: float, end: dict[str, float] | None = None,
                 columns: Sequence[int] = (0, 1), step: float = FD_STEP, richardson: bool = False) -> np.ndarray:
        """M = d(x, v)(T) / d(x, v)(0): the FMU's sensitivity (exact) or central differences (located);
        only ``columns`` are computed with differences (the others NaN); ``richardson``: the
        differences of steps d and d / 2 combined, (4 M(d / 2) - M(d)) / 3 (error O(d^4))."""
        if self.exact:
            e = end if end is not None and "dx_dx0" in end else self.end(x, v, T)
            J = np.array([[e["dx_dx0"], e["dx_dv0"]], [e["dv_dx0"], e["dv_dv0"]]])
            if not np.all(np.isfinite(J)):
                raise FloatingPointError("the FMU's sensitivity is not available (NaN)")
            return J
        if richardson:
            fine = self.jacobian(x, v, T, None, columns, step / 2.0)
            return (4.0 * fine - self.jacobian(x, v, T, None, columns, step)) / 3.0
        J = np.full((2, 2), np.nan)
        for j in columns:
            d = step * (self.X if j == 0 else self.V)
            dz = (d, 0.0) if j == 0 else (0.0, d)
            a = self.end(x + dz[0], v + dz[1], T)
            b = self.end(x - dz[0], v - dz[1], T)
            J[:, j] = [(a["x"] - b["x"]) / (2 * d), (a["v"] - b["v"]) / (2 * d)]
        return J


# ---- steady sliding ------------------------------------------------------------------------------

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


class _fmu:
    """The given FMU, or one loaded for the call and closed after it."""

    def __init__(self, fmu: OscillatorFMU2 | None) -> None:
        self.given, self.fmu = fmu, fmu

    def __enter__(self) -> OscillatorFMU2:
        if self.fmu is None:
            self.fmu = OscillatorFMU2()
        return self.fmu

    def __exit__(self, *exc: Any) -> None:
        if self.given is None and self.fmu is not None:
            self.fmu.close()


# ---- the periodic orbit ----------------------------------------------------------------------------

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


# ---- transients and the guess -------------------------------------------------------------------------

@dataclass
class Transient:
    """A sampled run and its crossings of the section (x = x_eq against the belt)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    mode: np.ndarray
    crossings: np.ndarray            # times, s
    crossing_v: np.ndarray           # velocities there, m/s

    def window(self, fraction: float = 0.25) -> dict[str, float]:
        """Amplitude, offset, stick share and the mean period over the last ``fraction`` of the run."""
        i = self.t >= self.t[-1] - fraction * (self.t[-1] - self.t[0])
        x = self.x[i]
        c = self.crossings[self.crossings >= self.t[-1] - fraction * (self.t[-1] - self.t[0])]
        return {"amplitude": float(np.ptp(x) / 2.0), "offset": float((x.max() + x.min()) / 2.0),
                "stick_fraction": float(np.mean(self.mode[i] == 0)),
                "period": float(np.mean(np.diff(c))) if c.size > 1 else math.nan}


def transient(prob: BeltProblem, x0: float | None = None, v0: float | None = None, periods: float = 40.0,
              samples: int = 256, *, fmu: OscillatorFMU2 | None = None) -> Transient:
    """The motion over ``periods`` natural periods from (x0, v0) (default: riding on the belt at x_eq),
    ``samples`` per natural period (fewer, but at least 16, when that would be more than MAX_SAMPLES
    in all), with its section crossings (linear interpolation)."""
    xs = prob.x_eq if x0 is None else float(x0)
    vs = prob.v_belt if v0 is None else float(v0)
    T0 = prob.natural_period
    n = max(int(round(periods * min(samples, max(16, MAX_SAMPLES // max(periods, 1.0))))), 2)
    grid = np.linspace(0.0, periods * T0, n + 1)
    with _fmu(fmu) as f:
        q = object.__new__(Oscillator)
        q.__dict__.update(prob.oscillator.__dict__, x0=xs, v0=vs)
        tr = f.trajectory(q, grid, prob.settings(), ("x", "v", "mode"))
    x, v = tr["x"], tr["v"]
    d = -prob.direction
    g = x - prob.x_eq
    idx = np.nonzero((np.sign(g[:-1]) == -d) & (np.sign(g[1:]) != -d))[0]
    idx = idx[(tr["mode"][idx] != 0) & (tr["mode"][idx + 1] != 0)]
    w = g[idx] / (g[idx] - g[idx + 1])
    tc = grid[idx] + w * (grid[idx + 1] - grid[idx])
    vc = v[idx] + w * (v[idx + 1] - v[idx])
    return Transient(grid, x, v, tr["mode"], tc, vc)


# ---- the answer ---------------------------------------------------------------------------------------------

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


def hopf_formula(prob: BeltProblem) -> float:
    """The analytic Hopf belt speed (stribeck with delta = 1; NaN otherwise or when steady sliding is
    stable at every speed)."""
    if prob.law != "stribeck" or prob.delta != 1.0:
        return math.nan
    from ..references.belt import hopf_belt_speed

    p = prob.oscillator
    return hopf_belt_speed(p.c, p.N, p.mu_s, p.mu_k, prob.v_s)


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


def section_map(prob: BeltProblem, v0: float, *, fmu: OscillatorFMU2 | None = None,
                samples: int = 512, periods: float = 3.0) -> tuple[float, float]:
    """(v1, t1): the velocity and the time of the next crossing of the section from (x_eq, v0), located
    by a sampled run and Brent's method on x(t) - x_eq with the FMU's runs (a check of the
    multipliers by differences of this map)."""
    from scipy.optimize import brentq

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

        t1 = float(brentq(g, a, b, xtol=1e-15, rtol=1e-15, maxiter=200))
        return flow.end(xe, v0, t1)["v"], t1


# ---- the Hopf point ------------------------------------------------------------------------------------

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
    """The belt speed in [lo, hi] (same sign, ``|lo| < |hi|``) where steady sliding changes stability: its
    multipliers over tau = a quarter of the natural period (a complex pair near +-i there, well apart)
    followed over a scan of ``num`` speeds (geometric), then Brent's method on the growth rate
    ln |mu|max / tau. RuntimeError if no sign change, or if what crosses |mu| = 1 is not a complex
    pair (then it is not a Hopf point)."""
    from scipy.optimize import brentq

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
        v = float(brentq(rate, a, b, xtol=xtol, rtol=1e-15, maxiter=200))
        eq = _equilibrium(_Flow(f, prob.with_(v_belt=v)), tau)
        mu = eq.multipliers
        if not abs(mu[0].imag) > 1e-6:
            raise RuntimeError(f"steady sliding changes stability at v_belt = {v:.8g} m/s through a real multiplier "
                               f"({mu[0].real:.6g}), not a complex pair: not a Hopf point")
        return HopfPoint(v, hopf_formula(prob), (a, b), n[0] + 1, prob.step, mu, tau,
                         abs(cmath.phase(complex(mu[0]))) / tau)


# ---- the branch in v_belt -------------------------------------------------------------------------------

@dataclass
class BranchPoint:
    """One orbit on a branch in the belt speed: its period (s), v0 at the section, amplitude (m), stick share,
    multipliers, stability and residual."""
    v_belt: float
    period: float
    v0: float
    amplitude: float
    stick_fraction: float
    multipliers: np.ndarray
    stable: bool
    residual: float


@dataclass
class Branch:
    """The orbit branch continued in the belt speed: the stick-slip leg from low speed up to its
    turning point, then (``slip_leg``) the orbits that never stick, from there down to the Hopf."""

    points: list[BranchPoint]        # in order along the branch
    turning_points: list[float]      # belt speeds where the branch turns (v_belt's direction reverses)
    end: str                         # why it stopped
    end_v_belt: float                # the last belt speed
    grazing: float = math.nan        # the stick-slip leg's last belt speed, where its stick phase vanishes
    hopf: float = math.nan           # where the slip leg was seeded (the located Hopf), m/s

    def arrays(self) -> dict[str, np.ndarray]:
        """The branch's points as arrays by field (and the modulus of the nontrivial multiplier)."""
        keys = ("v_belt", "period", "v0", "amplitude", "stick_fraction", "stable", "residual")
        out = {k: np.array([getattr(p, k) for p in self.points], dtype=float) for k in keys}
        out["mu_nontrivial"] = np.array([abs(p.multipliers[1]) for p in self.points])
        return out

    @property
    def fold(self) -> float:
        """The largest belt speed of the branch (its turning point), m/s."""
        v = np.array([p.v_belt for p in self.points])
        return float(v[np.argmax(np.abs(v))]) if v.size else math.nan


class _Continuer:
    """Pseudo-arclength continuation of R(v0, T; v_belt) = 0 in y = (v0, T, v_belt), scaled by S."""

    def __init__(self, f: OscillatorFMU2, prob: BeltProblem, tol: float, ds: float, ds_min: float, ds_max: float,
                 v_range: tuple[float, float], progress: Callable[[BranchPoint], None] | None) -> None:
        self.f, self.prob, self.tol = f, prob, tol
        self.ds, self.ds_min, self.ds_max = ds, ds_min, ds_max
        self.X, self.V = prob.scales
        self.S = np.array([self.V, prob.natural_period, self.V])
        self.sgn = float(prob.direction)
        self.lo, self.hi = sorted(abs(v) for v in v_range)
        self.progress = progress

    def solver(self, vb: float) -> _Orbit:
        return _Orbit(_Flow(self.f, self.prob.with_(v_belt=float(vb))), self.tol, 30)

    def R(self, y: np.ndarray) -> tuple[np.ndarray, dict[str, float], _Orbit]:
        s = self.solver(y[2])
        r, e = s.residual(float(y[0]), float(y[1]))
        return r, e, s

    def J(self, y: np.ndarray, e: dict[str, float], s: _Orbit) -> np.ndarray:
        """dR / d(y / S): dR/dv0 and dR/dT of the solver, dR/dv_belt by central differences."""
        A = s.dR(float(y[0]), float(y[1]), e)
        d = FD_STEP * self.V
        rp, _, _ = self.R(y + np.array([0.0, 0.0, d]))
        rm, _, _ = self.R(y - np.array([0.0, 0.0, d]))
        return np.column_stack([A * self.S[:2], (rp - rm) / (2 * d) * self.S[2]])

    def valid(self, y: np.ndarray) -> bool:
        return bool(y[1] > 0 and -self.sgn * y[0] > 0 and y[2] * self.sgn > 0)

    def correct(self, yp: np.ndarray, row: np.ndarray) -> tuple[np.ndarray, float, dict[str, float], _Orbit] | None:
        """Newton on R(y) = 0 with row . (y - yp) / S = 0 (the arclength, or a coordinate fixed)."""
        yc = yp.copy()
        for _ in range(12):
            try:
                r, e, s = self.R(yc)
            except (FloatingPointError, FMUError):      # a predictor the FMU cannot run
                return None
            nr = float(np.max(np.abs(r)))
            if nr <= self.tol:
                return yc, nr, e, s
            A = np.vstack([self.J(yc, e, s), row])
            try:
                dy = np.linalg.solve(A, -np.concatenate([r, [float(row @ ((yc - yp) / self.S))]]))
            except np.linalg.LinAlgError:
                return None
            yc = yc + dy * self.S
            if not self.valid(yc):
                return None
        return None

    def point(self, y: np.ndarray, nr: float, report: bool = True) -> BranchPoint:
        o = self.solver(y[2]).finish(float(y[0]), float(y[1]), nr, 0, "")
        p = BranchPoint(float(y[2]), o.period, o.v0, o.amplitude, o.stick_fraction, o.multipliers, o.stable, nr)
        if report and self.progress:
            self.progress(p)
        return p

    def leg(self, y: np.ndarray, tan: np.ndarray, max_points: int, amplitude_min: float,
            accept: Callable[[BranchPoint], bool]) -> tuple[list[BranchPoint], list[float], str, np.ndarray]:
        """Points from y along tan until the amplitude falls under amplitude_min X, the belt speed
        leaves the range, max_points, or the corrector fails at the smallest step. A corrected point
        that ``accept`` refuses (the leg's kind of orbit: with a stick phase or without), or that is
        steady sliding itself (|v0| < TRIVIAL X w0), counts as a failed corrector: the step is halved
        (so a leg ends at its grazing, approached in ever smaller steps)."""
        pts: list[BranchPoint] = []
        turning: list[float] = []
        h, last_dir = self.ds, 0.0
        end = f"{max_points} points"
        while len(pts) < max_points:
            got = self.correct(y + h * tan * self.S, tan)
            if got is None:
                h *= 0.5
                if h < self.ds_min:
                    end = f"the corrector failed at the smallest step (v_belt {y[2]:.8g})"
                    break
                continue
            yc, nr, e, s = got
            cand = self.point(yc, nr, report=False)
            if abs(cand.v0) < TRIVIAL * self.V or not accept(cand):
                h *= 0.5
                if h < self.ds_min:
                    end = f"the next point is not on this leg at the smallest step (v_belt {y[2]:.8g})"
                    break
                continue
            tn = _null(self.J(yc, e, s))
            if tn @ ((yc - y) / self.S) < 0:                     # oriented along the secant
                tn = -tn
            d = float(np.sign(yc[2] - y[2]))
            if last_dir and d and d != last_dir:
                turning.append(float(y[2]))
            last_dir = d or last_dir
            y, tan = yc, tn
            pts.append(cand)
            if self.progress:
                self.progress(cand)
            h = min(h * 1.5, self.ds_max)
            if pts[-1].amplitude < amplitude_min * self.X:
                end = f"amplitude below {amplitude_min:g} X: the orbit shrinks onto the equilibrium (the Hopf)"
                break
            if not (self.lo <= abs(y[2]) <= self.hi):
                end = "left the belt speed range"
                break
        return pts, turning, end, y

    def seed_at_fixed_v0(self, v0: float, T: float, vb: float) -> tuple[np.ndarray, float] | None:
        """The orbit through (x_eq, v0) with T and v_belt the unknowns (Newton from T, vb)."""
        y = np.array([v0, T, vb])
        got = self.correct(y, np.array([1.0, 0.0, 0.0]))
        return None if got is None else (got[0], got[1])


#: how a leg ends at its edge (the sentences of _Continuer.leg)
EDGE = ("the corrector failed at the smallest step", "the next point is not on this leg")
#: the slip leg meets the stick-slip leg when its last belt speed is within MEET of the grazing (relative)
MEET = 1e-4


def continue_orbits(prob: BeltProblem, v_from: float, v_min: float, v_max: float, *,
                    fmu: OscillatorFMU2 | None = None, ds: float = 0.02, ds_min: float = 1e-5,
                    ds_max: float = 0.1, max_points: int = 200, amplitude_min: float = 2e-3,
                    slip_leg: bool = True, seed_amplitude: float = 0.02, tol: float | None = None,
                    progress: Callable[[BranchPoint], None] | None = None) -> Branch:
    """The orbit branch through the stable orbit at ``v_from`` (found by :func:`self_excited`), continued
    by pseudo-arclength towards larger |v_belt| while it stays in [v_min, v_max] (same sign), until it
    turns, its amplitude falls under ``amplitude_min`` X, or ``max_points``. Arclength in the scaled
    unknowns (v0 / V, T / T0, v_belt / V); ``ds`` its first step, halved on a failed corrector down to
    ``ds_min``, grown by 1.5 up to ``ds_max``.

    The stick-slip leg has no smooth fold (its nontrivial multiplier is 0): it ends where the catch
    of the belt becomes tangential (a grazing: beyond it the motion no longer reaches the belt's
    speed), ``grazing``, the last belt speed where the corrector still finds a stick-slip orbit (steps
    halved down to ``ds_min``). With Stribeck friction the branch turns there, with a corner, onto
    orbits that never stick; the corrector cannot turn that corner, so with ``slip_leg`` the other
    leg is continued from its other end instead: the Hopf located from the model (:func:`locate_hopf`
    in [v_min, grazing]), seeded by the orbit through (x_eq, v0) with |v0| = ``seed_amplitude`` V (T
    and v_belt solved for) and continued up to where it would stick; its points are appended in the
    order of the branch (from the corner down to the Hopf), and the grazing is a turning point when
    the legs meet there (within MEET). Without a Hopf in the range (Coulomb) the branch ends at the
    grazing."""
    t = (1e-12 if prob.scheme == "exact" else 1e-10) if tol is None else tol
    with _fmu(fmu) as f:
        se = self_excited(prob.with_(v_belt=v_from), fmu=f)
        if se.orbit is None or not se.orbit.converged:
            raise RuntimeError(f"no orbit at the start v_belt = {v_from:g}: {se.reason}")
        c = _Continuer(f, prob, t, ds, ds_min, ds_max, (v_min, v_max), progress)
        o = se.orbit
        y = np.array([o.v0, o.period, float(v_from)])
        r, e, s = c.R(y)
        first = c.point(y, float(np.max(np.abs(r))))
        tan = _null(c.J(y, e, s))
        if tan[2] * c.sgn < 0:
            tan = -tan
        sticks = first.stick_fraction > 0.0

        def same_kind(p: BranchPoint) -> bool:
            return (p.stick_fraction > 0.0) == sticks

        pts, turning, end, y = c.leg(y, tan, max_points - 1, amplitude_min, same_kind)
        pts.insert(0, first)
        grazing = math.nan
        if sticks and end.startswith(EDGE):          # the stick-slip orbits end there (the catch grazes)
            grazing = pts[-1].v_belt
        hopf = math.nan
        if slip_leg and math.isfinite(grazing):
            try:
                hp = locate_hopf(prob, v_min, grazing, fmu=f)
            except RuntimeError as exc:
                end += f"; no slip leg: {exc}"
            else:
                hopf = hp.v_belt
                seed = c.seed_at_fixed_v0(-c.sgn * seed_amplitude * c.V, prob.natural_period, hopf)
                if seed is None:
                    end += f"; no slip leg: no orbit with |v0| = {seed_amplitude:g} V near the Hopf {hopf:.6g}"
                else:
                    ys, nr = seed
                    r, e, s = c.R(ys)
                    p0 = c.point(ys, nr)
                    tan = _null(c.J(ys, e, s))
                    if tan[0] * -c.sgn < 0:               # towards larger |v0| (larger orbits)
                        tan = -tan

                    def slides(p: BranchPoint) -> bool:
                        return p.stick_fraction == 0.0

                    more, turn2, end2, _ = c.leg(ys, tan, max_points, 0.0, slides)
                    leg2 = [p0] + more
                    pts += leg2[::-1]
                    turning += turn2
                    meet = abs(leg2[-1].v_belt - grazing) <= MEET * abs(grazing)
                    if meet:
                        turning.append(grazing)
                    end = (f"the stick-slip leg ends at its grazing (v_belt {grazing:.8g}, {end}); the slip leg "
                           f"from the Hopf {hopf:.8g} up to v_belt {leg2[-1].v_belt:.8g} ({end2}); "
                           + ("they meet: the branch turns at the grazing" if meet else
                              "they do not meet: two branches"))
        return Branch(pts, turning, end, pts[-1].v_belt, grazing, hopf)


def _null(A: np.ndarray) -> np.ndarray:
    """The unit null vector of a 2 x 3 matrix."""
    _, _, vt = np.linalg.svd(A)
    v = vt[-1]
    return v / np.linalg.norm(v)
