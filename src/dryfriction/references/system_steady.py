"""The steady state of a structure with friction contacts by long runs of the event-driven
reference (:mod:`dryfriction.references.system`), independent of the engine and of every FMU.

The reference motion is run from the system's initial state (x0, v0; the Jenkins sliders relaxed)
for P periods of the excitation, T = 2 pi / omega, and the stroboscopic map's change over each
period is measured on the state z = (x, v / omega, s) (the Jenkins sliders' positions s) at the
times k T, relative to the motion's scale (the largest |x| or |v / omega| of the last period):

    d_k = max |z(k T) - z((k - 1) T)| / scale.

The approach to the steady state is geometric, d_k ~ rho^k: rho is the log-linear fit of the
changes that still fall (above 100 times the noise floor, the median of the last eight), and the
state's remaining distance to the periodic orbit is estimated as d_P rho / (1 - rho), or d_P / (1 -
rho) once d_P is at the floor. The run is converged when that estimate is below ``tol``; if not, it
is run again from the start (the reference cannot resume a Jenkins slider's state) for the periods
the measured rate says are still needed (with a margin; twice as many without a rate), up to
``max_periods``. An unconverged answer is never silent: :attr:`SteadyState.converged` is False, the
last change and the estimate say by how much, and ``strict=True`` raises instead.

The amplitude of each degree of freedom is half its peak to peak over the last period, (max -
min) / 2, the extremes found on ``samples`` points of the reference's dense solution and refined
by a bounded scalar search around the sampled extremes (the dense output is of the integration's
accuracy, rtol 1e-12 by default).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np
from scipy.optimize import minimize_scalar

from ..system.structure import System
from .system import RTOL, SystemSolution, simulate

__all__ = ["SteadyState", "steady_state", "SteadyStateNotConverged"]


class SteadyStateNotConverged(RuntimeError):
    """The long run did not reach the requested tolerance within ``max_periods`` (strict mode)."""


@dataclass(frozen=True)
class SteadyState:
    """A long run's steady state (see the module docstring).

    ``amplitude``, ``x_max``, ``x_min`` (n): the last period's half peak-to-peak and extremes per
    degree of freedom; ``x0``, ``v0`` (n), ``s0`` (nc, NaN for a rigid contact): the state at the
    last period's start, t = (periods - 1) T; ``periods`` the periods run; ``change`` the last
    period's change of the stroboscopic state (relative, d_P); ``rate`` the estimated contraction
    per period rho; ``error_estimate`` the estimated remaining distance to the periodic orbit
    (relative); ``converged`` whether it is below ``tol``; ``changes`` every period's d_k."""

    amplitude: np.ndarray
    x_max: np.ndarray
    x_min: np.ndarray
    x0: np.ndarray
    v0: np.ndarray
    s0: np.ndarray
    periods: int
    change: float
    rate: float
    error_estimate: float
    tol: float
    converged: bool
    changes: np.ndarray
    period: float

    def __str__(self) -> str:
        state = "converged" if self.converged else "NOT converged"
        return (f"steady state {state} after {self.periods} periods: last change {self.change:.3g}, rate "
                f"{self.rate:.4g}, estimated error {self.error_estimate:.3g} (tol {self.tol:.3g}); amplitude "
                f"{np.array2string(self.amplitude, precision=10)}")


def _states(sol: SystemSolution, t: Any) -> np.ndarray:
    """The reference's state rows (x, v, the sliders' s, E_friction) at the times t (len(t) x
    (2n + nj + 1)), straight from the phases' dense solutions (no forces evaluated)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    starts = np.array([p.t0 for p in sol.phases])
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(sol.phases) - 1)
    Y = np.empty((t.size, sol.phases[0].y0.size))
    for i in np.unique(idx):
        sel = np.flatnonzero(idx == i)
        ph = sol.phases[int(i)]
        Y[sel] = ph.y0 if ph.sol is None else ph.sol(np.clip(t[sel], ph.t0, ph.t1)).T
    return Y


def _extremes(sol: SystemSolution, n: int, t0: float, t1: float, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Each DOF's max and min of x on [t0, t1]: sampled, then refined around the sampled extreme."""
    t = np.linspace(t0, t1, samples + 1)
    x = _states(sol, t)[:, :n]
    hi = np.empty(n)
    lo = np.empty(n)
    dt = t[1] - t[0]
    for i in range(n):
        for sign, out in ((1.0, hi), (-1.0, lo)):
            k = int(np.argmax(sign * x[:, i]))
            a, b = max(t0, t[k] - dt), min(t1, t[k] + dt)
            best = sign * x[k, i]
            if b > a:
                r = minimize_scalar(lambda tt: -sign * float(_states(sol, tt)[0, i]), bounds=(a, b),
                                    method="bounded", options={"xatol": 1e-13 * max(abs(t1), 1.0)})
                best = max(best, -float(r.fun))
            out[i] = sign * best
    return hi, lo


def _measure(sol: SystemSolution, n: int, P: int, T: float, omega: float) -> tuple[np.ndarray, ...]:
    """The stroboscopic states x, v, s (the sliders') at k T, k = 0..P, and the changes d_k."""
    Y = _states(sol, np.arange(P + 1) * T)
    x, v, s = Y[:, :n], Y[:, n:2 * n], Y[:, 2 * n:-1]
    z = np.concatenate([x, v / omega, s], axis=1)
    scale = max(float(np.max(np.abs(x[-2:]))), float(np.max(np.abs(v[-2:]))) / omega, 1e-300)
    d = np.max(np.abs(np.diff(z, axis=0)), axis=1) / scale
    return x, v, s, d


def _rate(d: np.ndarray) -> tuple[float, float]:
    """The contraction per period rho and the estimated remaining distance to the periodic orbit.

    rho: the log-linear fit of d_k over the periods where the change still falls (d_k above 100
    times the floor, the median of the last eight changes: the integration's noise); the estimate
    d_P rho / (1 - rho), or, once d_P is at the floor, d_P / (1 - rho) (the floor's own error
    summed over the periods it takes to decay). rho = 1 (no estimate: the estimate is d_P) with
    fewer than four falling changes."""
    d = np.asarray(d, dtype=float)
    floor = float(np.median(d[-8:])) if d.size else 0.0
    last = float(d[-1]) if d.size else math.inf
    falling = np.flatnonzero(d > 100.0 * floor)
    if falling.size >= 4 and np.all(d[falling] > 0):
        slope = np.polyfit(falling.astype(float), np.log(d[falling]), 1)[0]
        rho = float(min(np.exp(slope), 1.0))
    else:
        m = max(2, d.size // 4)
        tail = d[-m:]
        tail = tail[tail > 0]
        rho = float(min(np.exp(np.mean(np.diff(np.log(tail)))), 1.0)) if tail.size >= 2 else 1.0
    if rho >= 1.0:
        return 1.0, last
    at_floor = falling.size >= 4 and last <= 100.0 * floor
    return rho, (last / (1.0 - rho) if at_floor else last * rho / (1.0 - rho))


def steady_state(system: System, *, tol: float = 1e-9, periods: int = 64, max_periods: int = 4096,
                 samples: int = 2048, rtol: float = RTOL, strict: bool = False,
                 F_ext: Optional[Sequence[float]] = None, v_belt: Optional[Sequence[float]] = None,
                 **simulate_options: Any) -> SteadyState:
    """The steady state of ``system`` under its excitation by long runs of the event-driven
    reference (see the module docstring): ``periods`` periods first (default 64), doubled until the
    estimated distance to the periodic orbit is below ``tol`` (relative; default 1e-9) or
    ``max_periods`` would be passed. ``samples`` points of the last period locate the extremes;
    ``rtol`` the reference's integration tolerance; ``F_ext``, ``v_belt`` and ``simulate_options``
    go to :func:`dryfriction.references.system.simulate`.

    Returns a :class:`SteadyState` (``converged`` False when the tolerance was not reached, with the
    last change and the estimate; ``strict=True`` raises :class:`SteadyStateNotConverged` then).
    Raises ValueError for a system without excitation frequency (omega = 0) or a tolerance, a
    number of periods or of samples out of range."""
    if not system.omega > 0:
        raise ValueError(f"steady_state: the system's omega is {system.omega!r}; a steady state needs omega > 0")
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"steady_state: tol = {tol!r}; valid range: > 0")
    if not (isinstance(periods, int) and 2 <= periods <= max_periods):
        raise ValueError(f"steady_state: periods = {periods!r}; valid range: an integer 2 to max_periods "
                         f"({max_periods!r})")
    if not (isinstance(samples, int) and samples >= 16):
        raise ValueError(f"steady_state: samples = {samples!r}; valid range: an integer >= 16")
    T = 2.0 * math.pi / system.omega
    jidx = np.flatnonzero(np.asarray(system.k_t) > 0)
    n = system.n
    P = periods
    while True:
        res = simulate(system, P * T, t_eval=[0.0, P * T], F_ext=F_ext, v_belt=v_belt, rtol=rtol, **simulate_options)
        sol = res.solution
        x, v, sj, d = _measure(sol, n, P, T, system.omega)
        rho, estimate = _rate(d)
        change = float(d[-1])
        converged = estimate < tol
        if converged or P >= max_periods:
            break
        more = 2 * P                       # the periods still needed at the measured rate, with a margin
        if 0.0 < rho < 1.0 and estimate > 0.0:
            more = P + int(math.ceil(1.25 * math.log(tol / estimate) / math.log(rho))) + 8
        P = int(min(max_periods, max(more, P + 8)))
    x_max, x_min = _extremes(sol, n, (P - 1) * T, P * T, samples)
    s = np.full(system.nc, np.nan)
    s[jidx] = sj[-2]
    out = SteadyState(amplitude=0.5 * (x_max - x_min), x_max=x_max, x_min=x_min, x0=x[-2].copy(), v0=v[-2].copy(),
                      s0=s, periods=P, change=change, rate=rho, error_estimate=float(estimate), tol=tol,
                      converged=bool(converged), changes=d, period=T)
    if strict and not converged:
        raise SteadyStateNotConverged(str(out))
    return out
