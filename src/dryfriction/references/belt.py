"""Independent references for a block on a moving rough surface (a belt): the event-driven
stick/slip solution for Coulomb and Stribeck friction, and the closed-form stick-slip limit cycle of
the undamped, unforced Coulomb belt oscillator.

The model (one block; the FMU's)::

    m x'' + c x' + k x = P0 cos(omega t + phi) + F_ext + F,     v_rel = v - v_belt,
    stuck:   v = v_belt, while the force that keeps it so, |f|, f = P(t) + F_ext - c v_belt - k x,
             is within F_s = max(mu_s, mu_k) N,
    sliding: F = -sign(v_rel) N mu(|v_rel|),
             coulomb:  mu(u) = mu_k,    stribeck: mu(u) = mu_k + (mu_s - mu_k) exp(-(u / v_s)^delta).

``v_belt`` is piecewise constant: it may change at given times (as an FMU input changes at
communication points). A change while stuck does not jerk the block: it keeps its velocity and
slides (or stays stuck if the new belt speed equals it).

The solution is event-driven and uses none of the FMU's code: a stick phase is followed in closed
form (x = x_a + v_belt (t - t_a)) and ends at the first time |f| reaches F_s, found by steps that a
Lipschitz bound of f proves free of crossings, then Brent's method (dryfriction.roots); a slip phase is integrated by
scipy's DOP853 at a tight tolerance (rtol 1e-12 by default, steps of at most 1/256 of the shortest
period so that a brief excursion of v_rel past 0 is not stepped over) up to the event v_rel = 0,
where the rest rule decides: stick if |f| <= F_s, else slide the way f pushes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import solve_ivp

from ..roots import find_root

__all__ = ["Belt", "BeltRun", "LimitCycle", "simulate", "limit_cycle", "hopf_belt_speed"]

LAWS = ("coulomb", "stribeck")


@dataclass(frozen=True)
class Belt:
    """One block on a belt, SI units. ``mu_k`` is the kinetic coefficient (``chi mu_s``)."""

    m: float = 1.0
    k: float = 1.0
    c: float = 0.0
    N: float = 1.0
    mu_s: float = 0.5
    mu_k: float = 0.3
    P0: float = 0.0
    omega: float = 1.0
    phi: float = 0.0
    F_ext: float = 0.0
    x0: float = 0.0
    v0: float = 0.0
    law: str = "coulomb"
    v_s: float = 1.0
    delta: float = 1.0

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ValueError(f"law must be one of {LAWS}, not {self.law!r}")
        for name in ("m", "v_s", "delta"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, not {getattr(self, name)!r}")
        for name in ("k", "c", "N", "mu_s", "mu_k"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"{name} must be >= 0, not {getattr(self, name)!r}")

    def with_(self, **kw: float | str) -> "Belt":
        """A copy with the given fields changed."""
        return replace(self, **kw)  # type: ignore[arg-type]

    def mu(self, u: float) -> float:
        """The sliding coefficient at the relative speed u >= 0."""
        if self.law == "coulomb":
            return self.mu_k
        return self.mu_k + (self.mu_s - self.mu_k) * math.exp(-((u / self.v_s) ** self.delta))

    def dmu(self, u: float) -> float:
        """d mu / du at u > 0 (at u = 0 the right derivative; infinite for delta < 1)."""
        if self.law == "coulomb":
            return 0.0
        r = u / self.v_s
        if r == 0.0:
            return -(self.mu_s - self.mu_k) / self.v_s if self.delta == 1.0 else \
                (0.0 if self.delta > 1.0 else -math.inf)
        return -(self.mu_s - self.mu_k) * self.delta * r ** (self.delta - 1.0) / self.v_s * math.exp(-(r ** self.delta))

    @property
    def F_s(self) -> float:
        """The largest force a stuck block holds."""
        return max(self.mu_s, self.mu_k) * self.N

    def applied(self, t: float, x: float, v: float) -> float:
        """Every force but friction."""
        return self.P0 * math.cos(self.omega * t + self.phi) + self.F_ext - self.c * v - self.k * x


@dataclass
class BeltRun:
    """The reference's solution on a time grid, and its events."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    mode: np.ndarray                  # 0 stuck, +1 / -1 sliding with v_rel > 0 / < 0
    events: list[tuple[float, str]] = field(default_factory=list)  # (time, "stop" | "breakaway" | "reversal")

    def times(self, kind: str) -> np.ndarray:
        """The times of the run's events of one kind (``stick``, ``slip``, ...), s."""
        return np.array([t for t, k in self.events if k == kind])


Schedule = Sequence[tuple[float, float]]


def _belt_at(schedule: Schedule, v_belt: float, t: float) -> float:
    """The belt speed after every change at a time <= t."""
    for tc, vb in schedule:
        if tc <= t:
            v_belt = vb
    return v_belt


def simulate(b: Belt, t: Sequence[float], v_belt: float = 0.0, changes: Schedule = (),
             rtol: float = 1e-12, max_events: int = 100_000) -> BeltRun:
    """The motion from (x0, v0) at t[0] sampled at the increasing times ``t``; the belt moves at
    ``v_belt`` and then at ``vb`` from each ``(tc, vb)`` of ``changes`` (tc increasing, inside the
    span)."""
    grid = np.asarray(t, dtype=float)
    if grid.ndim != 1 or grid.size < 1 or np.any(np.diff(grid) <= 0):
        raise ValueError("t must be a one-dimensional increasing sequence")
    ch = [(float(tc), float(vb)) for tc, vb in changes if grid[0] < tc <= grid[-1]]
    xs, vs, ms = np.empty(grid.size), np.empty(grid.size), np.empty(grid.size, dtype=int)
    run = BeltRun(grid, xs, vs, ms)
    # the velocity and position scales (the absolute tolerance)
    scale_x = max(abs(b.x0), b.F_s / b.k if b.k > 0 else 0.0, abs(b.P0) / b.k if b.k > 0 else 0.0, 1e-300)
    w = math.sqrt(b.k / b.m) if b.k > 0 else max(b.omega, 1.0)
    atol = rtol * scale_x * np.array([1.0, w])
    # events are seen where v_rel changes sign between two steps: steps of at most 1/256 of the
    # shortest period (natural, excitation) see a crossing and its return unless they are closer
    max_step = 2.0 * math.pi / max(w, b.omega if b.P0 != 0 else 0.0) / 256.0
    ta, xa, va = float(grid[0]), float(b.x0), float(b.v0)
    vb = _belt_at(ch, v_belt, ta)
    mode = _decide(b, ta, xa, va, vb)
    i = 0                      # the next grid point to fill
    n_events = 0
    t_end = float(grid[-1])
    while True:
        # this phase ends at the next belt change or the end of the span, unless an event comes first
        t_lim = next((tc for tc, _ in ch if tc > ta), t_end)
        if mode == 0:
            tb, kind = _stick_end(b, ta, xa, vb, t_lim)
            while i < grid.size and grid[i] <= tb:
                xs[i], vs[i], ms[i] = xa + vb * (grid[i] - ta), vb, 0
                i += 1
            xb, vb_end = xa + vb * (tb - ta), vb
            va_next = vb_end
        else:
            s = mode

            def rhs(tt: float, y: np.ndarray) -> list[float]:
                u = abs(y[1] - vb)
                return [y[1], (b.applied(tt, y[0], y[1]) - s * b.N * b.mu(u)) / b.m]

            def stop(tt: float, y: np.ndarray) -> float:
                return y[1] - vb
            stop.terminal = True          # type: ignore[attr-defined]
            stop.direction = -s           # type: ignore[attr-defined]
            sol = solve_ivp(rhs, (ta, t_lim), [xa, va], method="DOP853", rtol=rtol, atol=atol,
                            events=stop, dense_output=True, max_step=max_step)
            if sol.status < 0:
                raise RuntimeError(f"the slip phase from t = {ta} failed: {sol.message}")
            if sol.t_events[0].size:
                tb, kind = float(sol.t_events[0][0]), "stop"
                xb, va_next = float(sol.y_events[0][0][0]), vb
            else:
                tb, kind = t_lim, "end"
                xb, va_next = float(sol.y[0, -1]), float(sol.y[1, -1])
            while i < grid.size and grid[i] <= tb:
                y = sol.sol(grid[i])
                xs[i], vs[i], ms[i] = y[0], y[1], s
                i += 1
        if tb >= t_end:
            break
        vb_new = _belt_at(ch, v_belt, tb)
        if kind == "breakaway":       # |f| reached F_s: it slides the way f pushes
            new_mode = 1 if b.applied(tb, xb, vb) > 0 else -1
        else:
            new_mode = _decide(b, tb, xb, va_next, vb_new)
        if mode == 0 and new_mode != 0:
            run.events.append((tb, "breakaway"))
        elif mode != 0 and new_mode == 0:
            run.events.append((tb, "stop"))
        elif mode != 0 and new_mode == -mode:
            run.events.append((tb, "reversal"))
        n_events += 1
        if n_events > max_events:
            raise RuntimeError(f"more than {max_events} events before t = {tb}")
        ta, xa, va, vb, mode = tb, xb, va_next, vb_new, new_mode
    while i < grid.size:        # the end point itself
        xs[i], vs[i], ms[i] = xb, va_next, mode
        i += 1
    return run


def _decide(b: Belt, t: float, x: float, v: float, vb: float) -> int:
    """The mode at (t, x, v) with the belt at vb: slide the way v_rel points; at v_rel = 0 stick if
    the holding force is within F_s, else slide the way the applied force pushes."""
    vr = v - vb
    if vr != 0.0:
        return 1 if vr > 0 else -1
    f = b.applied(t, x, vb)
    if abs(f) <= b.F_s:
        return 0
    return 1 if f > 0 else -1


def _stick_end(b: Belt, ta: float, xa: float, vb: float, t_lim: float) -> tuple[float, str]:
    """The breakaway time of a stick phase from (ta, xa) (or t_lim, "end"): the first t with
    |f(t)| = F_s, f(t) = P0 cos(omega t + phi) + F_ext - c vb - k (xa + vb (t - ta)); steps of
    (F_s - |f|) / L, L = |P0| omega + k |vb| bounding |f'|, cannot step over it."""
    L = abs(b.P0) * b.omega + b.k * abs(vb)

    def g(t: float) -> float:
        return abs(b.applied(t, xa + vb * (t - ta), vb)) - b.F_s

    t = ta
    if L == 0.0:
        return (t_lim, "end") if g(t) <= 0 else (t, "breakaway")
    tiny = 1e-15 * max(1.0, abs(t_lim))
    for _ in range(10_000_000):
        gt = g(t)
        if gt > 0:
            return t, "breakaway"
        d = max(-gt / L, tiny)
        if t + d >= t_lim:
            g_lim = g(t_lim)
            return (t_lim, "end") if g_lim <= 0 else (_crossing(g, t, t_lim, gt, g_lim), "breakaway")
        g_next = g(t + d)
        if g_next > 0:
            return _crossing(g, t, t + d, gt, g_next), "breakaway"
        t += d
    raise RuntimeError(f"the stick phase from t = {ta} did not end (a tangency?)")


def _crossing(g: Callable[[float], float], a: float, b: float, ga: float, gb: float) -> float:
    """The crossing of g from ga = g(a) <= 0 to gb = g(b) > 0, to rounding."""
    return find_root(g, a, b, fa=ga, fb=gb, xtol=1e-15 * max(1.0, abs(b)), rtol=4 * np.finfo(float).eps,
                     maxiter=500)


@dataclass(frozen=True)
class LimitCycle:
    """The stick-slip cycle of the undamped, unforced Coulomb belt oscillator (v_belt > 0)."""

    period: float
    t_stick: float
    t_slip: float
    x_max: float
    x_min: float
    x_stick_start: float          # where the block catches the belt (the stop)
    x_breakaway: float            # where it leaves it

    @property
    def stick_fraction(self) -> float:
        """The share of the period spent stuck (riding the belt)."""
        return self.t_stick / self.period

    @property
    def amplitude(self) -> float:
        """Half the peak-to-peak of x over the cycle, m."""
        return (self.x_max - self.x_min) / 2.0


def limit_cycle(m: float, k: float, N: float, mu_s: float, mu_k: float, v_belt: float) -> LimitCycle:
    """The closed-form stick-slip limit cycle of m x'' + k x = F on a belt at v_belt > 0 with Coulomb
    friction (c = 0, no excitation, mu_s > mu_k), F_s = mu_s N, F_k = mu_k N, w = sqrt(k / m):

    - stuck, the block rides the belt, x = x_c + v_belt t, until the spring holds F_s: x_b = F_s / k;
    - it slips back (v_rel < 0, F = +F_k): y = x - F_k / k is harmonic, starting at y0 = (F_s - F_k) / k
      with y' = v_belt, amplitude R = sqrt(y0^2 + (v_belt / w)^2), until y' = v_belt again, which is at
      y = -y0, after the phase pi + 2 alpha, alpha = atan2(v_belt / w, y0): t_slip = (pi + 2 alpha) / w;
    - there the holding force is k x = 2 F_k - F_s, within F_s: it sticks at x_c = (2 F_k - F_s) / k and
      rides to x_b in t_stick = 2 (F_s - F_k) / (k v_belt).

    The extremes are F_k / k +- R (the slip passes through both turning points of its harmonic)."""
    if not (m > 0 and k > 0 and N > 0 and v_belt > 0 and mu_s > mu_k >= 0):
        raise ValueError("limit_cycle needs m, k, N, v_belt > 0 and mu_s > mu_k >= 0")
    w = math.sqrt(k / m)
    Fs, Fk = mu_s * N, mu_k * N
    y0 = (Fs - Fk) / k
    R = math.hypot(y0, v_belt / w)
    alpha = math.atan2(v_belt / w, y0)
    t_slip = (math.pi + 2.0 * alpha) / w
    t_stick = 2.0 * (Fs - Fk) / (k * v_belt)
    return LimitCycle(period=t_stick + t_slip, t_stick=t_stick, t_slip=t_slip, x_max=Fk / k + R,
                      x_min=Fk / k - R, x_stick_start=(2.0 * Fk - Fs) / k, x_breakaway=Fs / k)


def hopf_belt_speed(c: float, N: float, mu_s: float, mu_k: float, v_s: float) -> float:
    """The belt speed below which steady sliding on a Stribeck law with delta = 1 is unstable: the
    linearised slide m dx'' + (c + N mu'(v_belt)) dx' + k dx = 0 loses its damping where
    c + N mu'(v_belt) = 0, mu'(u) = -(mu_s - mu_k) / v_s exp(-u / v_s): v* = v_s ln(N (mu_s - mu_k) / (c v_s)).
    NaN when steady sliding is stable at every belt speed (c v_s >= N (mu_s - mu_k))."""
    a = N * (mu_s - mu_k) / (c * v_s) if c > 0 else math.inf
    return v_s * math.log(a) if a > 1.0 else math.nan
