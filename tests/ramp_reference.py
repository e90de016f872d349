"""An event-driven reference for the oscillator with inputs that vary in time (tests/test_coupling_fmu.py):

    m x'' + c x' + k x = P0 cos(omega t + phi) + F_ext(t) + F,
    Coulomb friction F: sliding -s mu_k N(t), N(t) = max(N + N_ext(t), 0); stuck while
    |P + F_ext - k x| <= max(mu_s, mu_k) N(t).

It shares nothing with the FMU but the physics (method.md section 1): each slide by scipy's DOP853
(rtol 1e-12) stopped at its stop (s v = 0, direction -1); each stick phase ended at the first time
the static force leaves the limit, found on a grid of 400 points per phase and refined by brentq;
at a stop the rest rule (stick inside the limit, else slide along the static force). F_ext and
N_ext are callables of t (a ramp, or a smooth signal)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

Signal = Callable[[float], float]


def ramp_reference(p: dict[str, float], F_ext: Signal, N_ext: Signal, t_out: np.ndarray) -> np.ndarray:
    """x, v at the times t_out (increasing, from 0) as rows [x, v]."""
    m, k, c = p["m"], p["k"], p["c"]
    mu_k = p["chi"] * p["mu_s"]
    mu_b = max(p["mu_s"], mu_k)

    def P(t: float) -> float:
        return p["P0"] * math.cos(p["omega"] * t + p.get("phi", 0.0))

    def N(t: float) -> float:
        return max(p["N"] + N_ext(t), 0.0)

    def static(t: float, x: float) -> float:
        return P(t) + F_ext(t) - k * x

    t_end = float(t_out[-1])
    pieces: list[tuple[float, float, object]] = []  # (ta, tb, x(t), v(t) as a callable)
    t, x, v = 0.0, p["x0"], p["v0"]
    mode = int(np.sign(v))
    if mode == 0:
        S = static(t, x)
        mode = 0 if abs(S) <= mu_b * N(t) else int(np.sign(S))
    for _ in range(10000):
        if t >= t_end:
            break
        if mode == 0:
            def gap(s: float, x: float = x) -> float:
                return abs(static(s, x)) - mu_b * N(s)
            tb_max = min(t_end, t + 0.5)
            ts = np.linspace(t, tb_max, 401)
            gs = np.array([gap(s) for s in ts])
            idx = np.nonzero(gs[1:] > 0.0)[0]
            if idx.size == 0:
                pieces.append((t, tb_max, lambda s, x=x: (x, 0.0)))
                t = tb_max
                continue
            j = int(idx[0]) + 1
            tb = brentq(gap, ts[j - 1], ts[j], xtol=1e-15, rtol=1e-15) if gs[j - 1] <= 0.0 else ts[j - 1]
            pieces.append((t, tb, lambda s, x=x: (x, 0.0)))
            t, v = tb, 0.0
            mode = int(np.sign(static(t, x)))
            continue
        sgn = mode

        def rhs(tt: float, y: np.ndarray, s: int = sgn) -> list[float]:
            return [y[1], (P(tt) + F_ext(tt) - k * y[0] - c * y[1] - s * mu_k * N(tt)) / m]

        def stop(tt: float, y: np.ndarray, s: int = sgn) -> float:
            return s * y[1]
        stop.terminal, stop.direction = True, -1
        sol = solve_ivp(rhs, (t, t_end), [x, v], method="DOP853", rtol=1e-12, atol=1e-14, events=stop,
                        dense_output=True)
        te = float(sol.t_events[0][0]) if sol.status == 1 else t_end
        dense = sol.sol
        pieces.append((t, te, lambda s, d=dense: (float(d(s)[0]), float(d(s)[1]))))
        x = float(sol.y_events[0][0][0]) if sol.status == 1 else float(sol.y[0, -1])
        t, v = te, 0.0
        S = static(t, x)
        mode = 0 if abs(S) <= mu_b * N(t) else int(np.sign(S))
    out = np.empty((len(t_out), 2))
    for i, tq in enumerate(t_out):
        tq = float(tq)
        piece = next((pc for pc in pieces if pc[0] <= tq <= pc[1]), pieces[-1])
        out[i] = piece[2](tq)
    return out
