"""The methods a user would pick instead of the FMU, written with scipy.

1. ``event_driven``: the switching model. Every slip phase is one ``solve_ivp`` call with the
   kinetic friction force of its direction and a terminal event at ``x' = 0``; at the stop the block
   sticks if the static force ``|P(t) - k x|`` is inside the breakaway limit, else it slides on in
   the direction of that force. Every stick phase is one ``solve_ivp`` call on the frozen state with
   terminal events where ``P(t) - k x`` reaches ``+/- F_b`` (``max_step = T/20`` so that an
   excursion of the force beyond the limit cannot be stepped over). The solver is restarted at
   every event, as the textbook recipe does. Methods: RK45, DOP853, Radau at several tolerances.

2. ``smoothed``: one ``solve_ivp`` call on a regularised (tanh-smoothed, Stribeck-shaped)
   friction law without events,

       F(v) = -N tanh(v/eps) [mu_k + (mu_b - mu_k) exp(-(v/v_s)^2)],
       mu_b = max(mu_s, mu_k),   v_s = sqrt(eps v_scale),

   which tends to Coulomb's law with the static peak ``mu_b N`` as the width ``eps -> 0``: the
   Stribeck velocity ``v_s`` shrinks with ``eps`` but more slowly, so the peak of the law tends to
   ``mu_b N`` (with ``v_s`` a fixed multiple of ``eps`` the peak stays short of it and the error has
   a floor). A stuck block creeps with ``|v| ~ eps``. With ``chi = 1`` it is the plain tanh law.
   Methods: Radau and LSODA (both given the analytic Jacobian) at several widths.

Both work in SI units with ``atol = rtol * (x_scale, v_scale)``, ``x_scale = P0/k`` and
``v_scale = w0 P0 / k``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from dryfriction.params import Oscillator

MAX_PHASES = 100_000


class PeerError(RuntimeError):
    """A peer run failed (solver failure or too many phases)."""


@dataclass
class PeerRun:
    """Result of one peer run: the phases (each a dense-output callable on [t0, t1] or a frozen
    position), the number of right-hand-side evaluations and of solver steps."""

    phases: list[tuple[float, float, Callable[[np.ndarray], np.ndarray] | float]] = field(default_factory=list)
    nfev: int = 0
    steps: int = 0
    events: int = 0

    def x(self, t: np.ndarray) -> np.ndarray:
        """Position at the sample times t (needs dense output)."""
        t = np.asarray(t, dtype=float)
        out = np.full(t.shape, np.nan)
        starts = np.array([ph[0] for ph in self.phases])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.phases) - 1)
        for i in np.unique(idx):
            sel = idx == i
            t0, t1, sol = self.phases[i]
            if callable(sol):
                out[sel] = sol(np.clip(t[sel], t0, t1))[0]
            else:
                out[sel] = sol
        return out


def _scales(p: Oscillator) -> tuple[float, float]:
    xs = abs(p.P0) / p.k if p.k > 0 else 1.0
    return xs, xs * math.sqrt(p.k / p.m)


def event_driven(p: Oscillator, t_end: float, method: str, rtol: float, dense: bool = True) -> PeerRun:
    """The switching model, restarted at every stop and breakaway (see the module docstring)."""
    m, k, c, P0, w, phi = p.m, p.k, p.c, p.P0, p.omega, p.phi
    muk_N = p.mu_k * p.N
    Fb = p.breakaway
    xs, vs = _scales(p)
    atol = np.array([rtol * xs, rtol * vs])
    T = p.period
    run = PeerRun()

    def P(t: float) -> float:
        return P0 * math.cos(w * t + phi)

    def slip_rhs(s: int) -> Callable[[float, np.ndarray], list[float]]:
        fs = s * muk_N

        def f(t: float, y: np.ndarray) -> list[float]:
            return [y[1], (P0 * math.cos(w * t + phi) - c * y[1] - k * y[0] - fs) / m]

        return f

    def stop_event(s: int) -> Callable[[float, np.ndarray], float]:
        def g(t: float, y: np.ndarray) -> float:
            return s * y[1]

        g.terminal = True  # type: ignore[attr-defined]
        g.direction = -1  # type: ignore[attr-defined]
        return g

    def stick_rhs(t: float, y: np.ndarray) -> list[float]:
        return [0.0, 0.0]

    t, x, v = 0.0, p.x0, p.v0
    if v == 0.0:
        S = P(0.0) - k * x
        mode = 0 if abs(S) <= Fb else (1 if S > 0 else -1)
    else:
        mode = 1 if v > 0 else -1
    while t < t_end:
        if len(run.phases) >= MAX_PHASES:
            raise PeerError(f"{method}: more than {MAX_PHASES} phases before t = {t_end}")
        if mode == 0:
            x_stuck = x

            def up(tt: float, y: np.ndarray, xf: float = x_stuck) -> float:
                return P0 * math.cos(w * tt + phi) - k * xf - Fb

            def down(tt: float, y: np.ndarray, xf: float = x_stuck) -> float:
                return P0 * math.cos(w * tt + phi) - k * xf + Fb

            up.terminal = down.terminal = True  # type: ignore[attr-defined]
            up.direction, down.direction = 1, -1  # type: ignore[attr-defined]
            sol = solve_ivp(stick_rhs, (t, t_end), [x, 0.0], method=method, rtol=rtol, atol=atol,
                            events=(up, down), max_step=T / 20)
            if sol.status < 0:
                raise PeerError(f"{method} failed in a stick phase at t = {t}: {sol.message}")
            run.nfev += sol.nfev
            run.steps += sol.t.size - 1
            t1 = float(sol.t[-1])
            run.phases.append((t, t1, x_stuck))
            t, v = t1, 0.0
            if sol.status == 1:  # breakaway
                run.events += 1
                mode = 1 if sol.t_events[0].size else -1
        else:
            s = mode
            sol = solve_ivp(slip_rhs(s), (t, t_end), [x, v], method=method, rtol=rtol, atol=atol,
                            events=stop_event(s), dense_output=dense)
            if sol.status < 0:
                raise PeerError(f"{method} failed in a slip phase at t = {t}: {sol.message}")
            run.nfev += sol.nfev
            run.steps += sol.t.size - 1
            t1 = float(sol.t[-1])
            run.phases.append((t, t1, sol.sol if dense else float(sol.y[0, -1])))
            x, v = float(sol.y[0, -1]), float(sol.y[1, -1])
            t = t1
            if sol.status == 1:  # stop: stick or slide on along the static force
                run.events += 1
                v = 0.0
                S = P(t) - k * x
                mode = 0 if abs(S) <= Fb else (1 if S > 0 else -1)
    return run


def smoothed_law(p: Oscillator, eps_rel: float) -> Callable[[np.ndarray], np.ndarray]:
    """The regularised friction force F(v) of the module docstring, vectorised (for plots/tests)."""
    _, vs = _scales(p)
    eps, v_s = eps_rel * vs, math.sqrt(eps_rel) * vs
    N, muk = p.N, p.mu_k
    dmu = max(p.mu_s, muk) - muk

    def F(v: np.ndarray) -> np.ndarray:
        return -N * np.tanh(v / eps) * (muk + dmu * np.exp(-(v / v_s) ** 2))

    return F


def smoothed(p: Oscillator, t_end: float, method: str, eps_rel: float, rtol: float, dense: bool = True) -> PeerRun:
    """One solve_ivp call on the smoothed law; eps = eps_rel * v_scale, v_s = sqrt(eps_rel) * v_scale."""
    m, k, c, P0, w, phi = p.m, p.k, p.c, p.P0, p.omega, p.phi
    xs, vs = _scales(p)
    eps, v_s = eps_rel * vs, math.sqrt(eps_rel) * vs
    N, muk = p.N, p.mu_k
    dmu = max(p.mu_s, muk) - muk
    tanh, exp = math.tanh, math.exp

    def f(t: float, y: np.ndarray) -> list[float]:
        v = y[1]
        F = -N * tanh(v / eps) * (muk + dmu * exp(-(v / v_s) ** 2))
        return [v, (P0 * math.cos(w * t + phi) - c * v - k * y[0] + F) / m]

    def jac(t: float, y: np.ndarray) -> list[list[float]]:
        v = y[1]
        th = tanh(v / eps)
        g = exp(-(v / v_s) ** 2)
        dF = -N * ((1.0 - th * th) / eps * (muk + dmu * g) - th * dmu * g * 2.0 * v / (v_s * v_s))
        return [[0.0, 1.0], [-k / m, (dF - c) / m]]

    atol = np.array([rtol * xs, rtol * vs])
    sol = solve_ivp(f, (0.0, t_end), [p.x0, p.v0], method=method, rtol=rtol, atol=atol, jac=jac,
                    dense_output=dense)
    if sol.status < 0:
        raise PeerError(f"smoothed {method} (eps {eps_rel:g}) failed: {sol.message}")
    run = PeerRun(nfev=sol.nfev, steps=sol.t.size - 1)
    run.phases.append((0.0, float(sol.t[-1]), sol.sol if dense else float(sol.y[0, -1])))
    return run


@dataclass(frozen=True)
class PeerSetting:
    """One peer configuration: family 'event' or 'smoothed', solver, tolerance, width."""

    family: str
    method: str
    rtol: float
    eps_rel: float = float("nan")

    @property
    def label(self) -> str:
        if self.family == "event":
            return f"event {self.method}"
        return f"tanh {self.method}"

    @property
    def setting(self) -> str:
        if self.family == "event":
            return f"rtol={self.rtol:.0e}"
        return f"eps={self.eps_rel:.0e}*v_scale rtol={self.rtol:.0e}"

    def run(self, p: Oscillator, t_end: float, dense: bool = True) -> PeerRun:
        if self.family == "event":
            return event_driven(p, t_end, self.method, self.rtol, dense)
        return smoothed(p, t_end, self.method, self.eps_rel, self.rtol, dense)


def peer_settings(quick: bool) -> list[PeerSetting]:
    """The tolerances and widths of the study (fewer with quick)."""
    if quick:
        ev = {"RK45": (1e-5, 1e-8), "DOP853": (1e-6, 1e-10), "Radau": (1e-4, 1e-6)}
        widths = (1e-2, 1e-3)
    else:
        ev = {"RK45": (1e-4, 1e-6, 1e-8, 1e-10), "DOP853": (1e-5, 1e-7, 1e-9, 1e-11, 1e-13),
              "Radau": (1e-4, 1e-6, 1e-8, 1e-10)}
        widths = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
    out = [PeerSetting("event", mth, tol) for mth, tols in ev.items() for tol in tols]
    for mth in ("Radau", "LSODA"):
        for wdt in widths:
            # the smoothing error is about eps: solve a little tighter than that, not needlessly tight
            out.append(PeerSetting("smoothed", mth, float(np.clip(wdt * 1e-2, 1e-10, 1e-4)), wdt))
    return out
