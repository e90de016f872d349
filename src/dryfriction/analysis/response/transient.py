"""The transient method: run the FMU until the error left in the last window is within the
tolerance (the package's doc, dryfriction.analysis.response)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from ...drivers.oscillator import FMUError, OscillatorFMU2, Settings
from ...params import Oscillator

#: relative agreement of successive windows (amplitude and offset, relative to the amplitude)
TOL = 1e-3
#: absolute agreement of the stick share of successive windows
TOL_STICK = 0.01
#: first run length and the period limit (excitation periods)
MIN_PERIODS = 32
MAX_PERIODS = 8192
#: the estimated error left in a window is this multiple of the fitted geometric decay's
SAFETY = 2.0
#: the initial deviation from the steady state is taken as at most |x0, v0 / omega| + SPAN (A + |o|)
SPAN = 3.0
#: differences of windows at this share of the amplitude are round-off (the error is then that; the
#: flow's estimate never reads below it)
ROUNDOFF = 1e-13


@dataclass(frozen=True)
class SteadyState:
    """The steady state of one oscillator (SI units)."""

    amplitude: float        # half the peak-to-peak of x over the last window, m
    offset: float           # mid-range (x_max + x_min) / 2 over the last window, m
    x_max: float            # m
    x_min: float            # m
    stick_fraction: float   # share of the last window spent stuck
    converged: bool         # the estimated error of the last window is within tol
    periods: float          # excitation periods run (the last run)
    change: float           # relative change of the amplitude between the last two windows
    error: float = math.nan  # estimated error left in the last window, relative to its amplitude

    def as_dict(self) -> dict[str, Any]:
        """The steady state as a dict of its fields."""
        return asdict(self)


def default_settings(p: Oscillator) -> Settings:
    """The exact scheme (closed form, h has no effect), with a spring or without (k = 0: a free
    mass on a rough support, exact_free.c)."""
    return Settings(h=0.0, scheme="exact")


def remaining_error(d_prev: float, d_last: float, floor: float = 0.0) -> float:
    """The error left in the last of three windows whose amplitudes differ by d_prev, then d_last
    (module doc: A_j = A_inf + B u^(2^j), e = |d_last| u^2 / (1 - u^2), u (u + 1) = |q|); inf when
    the differences do not shrink; |d_last| when it is at the round-off ``floor``."""
    a, b = abs(d_prev), abs(d_last)
    if b <= floor:
        return b
    if a == 0.0:
        return math.inf
    q = b / a
    if q >= 2.0:
        return math.inf
    u = 0.5 * (math.sqrt(1.0 + 4.0 * q) - 1.0)
    return b * u * u / (1.0 - u * u)


def _viscous_error(p: Oscillator, d_last: float, n: float) -> float:
    """Without friction: the error left after the last window from the known decay rate zeta w0 of
    the free vibration (window start at n T / 2, the one before at n T / 4)."""
    sigma = p.c / (2.0 * p.m)
    t = 0.25 * n * p.period
    if sigma * t <= 0.0:
        return math.inf if d_last != 0.0 else 0.0
    u2 = math.exp(-sigma * t)          # B u^4 / B u^2: the decay from one window start to the next
    return abs(d_last) * u2 / (1.0 - u2)


JACOBIAN = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")


def _flow_error(p: Oscillator, J: np.ndarray, dev: float) -> float:
    """The deviation from the steady state left after the flow whose Jacobian (since the start) is
    J, from an initial deviation ``dev`` (in m; velocities scaled by the excitation's omega): the
    2-norm of the scaled J times dev. Without a spring the position is neutral (the steady states are
    a family shifted in x, the amplitude the same): the velocity's row only."""
    w = p.omega
    Js = np.array([[J[0, 0], J[0, 1] * w], [J[1, 0] / w, J[1, 1]]])
    if p.k == 0:
        Js = Js[1:]
    return float(np.linalg.norm(Js, 2)) * dev


def steady_state(fmu: OscillatorFMU2, p: Oscillator, *, tol: float = TOL, tol_stick: float = TOL_STICK,
                 min_periods: int = MIN_PERIODS, max_periods: int = MAX_PERIODS,
                 settings: Settings | None = None) -> SteadyState:
    """Run until the estimated error of the last window is within tol (see the module docstring);
    needs omega > 0."""
    if not p.omega > 0:
        raise ValueError(f"a steady state needs an excitation: omega must be > 0, not {p.omega!r}")
    if not (tol > 0 and tol_stick > 0):
        raise ValueError("tol and tol_stick must be > 0")
    if not (2 <= min_periods <= max_periods):
        raise ValueError(f"need 2 <= min_periods <= max_periods, not {min_periods}, {max_periods}")
    st = settings or default_settings(p)
    flow = st.scheme == "exact"
    if flow:
        st = replace(st, extra={**st.extra, "sensitivity": True})
    T = p.period
    frictionless = p.N * p.mu_k == 0.0
    start = math.hypot(p.x0, p.v0 / p.omega)
    hist: list[tuple[float, float, float]] = []
    J_prev: np.ndarray | None = None
    n = float(min_periods)
    while True:
        o = fmu.observables(p, n * T, 0.5 * n * T, settings=st)
        amp, off = 0.5 * (o["x_max"] - o["x_min"]), 0.5 * (o["x_max"] + o["x_min"])
        stick = float(o["stick_fraction"])
        hist.append((amp, off, stick))
        J = None
        if flow:
            y = fmu.get(JACOBIAN)
            J = np.array([y[k] for k in JACOBIAN], dtype=float).reshape(2, 2)
        change = error = math.inf
        converged = False
        scale = max(amp, 1e-300)
        if len(hist) >= 2:
            a1, o1, s1 = hist[-2]
            change = abs(amp - a1) / scale
            agree = change <= tol and (abs(off - o1) <= tol * scale) and abs(stick - s1) <= tol_stick
            if J_prev is not None and np.all(np.isfinite(J_prev)):
                # the flow's own decay: the deviation left at the window's start (the previous run's end)
                dev = start + SPAN * (amp + abs(off))
                error = SAFETY * _flow_error(p, J_prev, dev) / scale + ROUNDOFF
            elif len(hist) >= 3:
                a0, o0, _ = hist[-3]
                floor = ROUNDOFF * max(abs(amp), abs(off), 1e-300)
                e_amp = remaining_error(a1 - a0, amp - a1, floor)
                e_off = remaining_error(o1 - o0, off - o1, floor) if p.k > 0 else 0.0
                if frictionless:
                    e_amp = max(e_amp, _viscous_error(p, amp - a1, n))
                    e_off = max(e_off, _viscous_error(p, off - o1, n)) if p.k > 0 else 0.0
                error = SAFETY * max(e_amp, e_off) / scale
            converged = agree and error <= tol
        if amp == 0.0 and len(hist) >= 2 and hist[-2][0] == 0.0:
            converged, change, error = True, 0.0, 0.0      # stuck for good: nothing moves
        if converged or 2 * n > max_periods:
            return SteadyState(amp, off, float(o["x_max"]), float(o["x_min"]), stick, converged, n, change, error)
        J_prev = J
        n *= 2


def _chunk(fmu: str | bytes, base: Mapping[str, float], f_hz: np.ndarray, opts: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """One Dask task (or an in-process chunk): steady states at the frequencies f_hz."""
    import time

    from ..chaos.batch import fmu_for

    inst = fmu_for(fmu)
    t0 = time.process_time()
    rows, reasons = [], []
    for f in f_hz:
        p = Oscillator(**{**base, "omega": 2.0 * math.pi * float(f)})
        st = Settings(h=opts["h"], scheme=opts["scheme"]) if opts["scheme"] else default_settings(p)
        try:
            s = steady_state(inst, p, tol=opts["tol"], min_periods=opts["min_periods"],
                             max_periods=opts["max_periods"], settings=st)
        except FMUError as e:  # this frequency is not computed: its row says why, the sweep goes on
            rows.append((math.nan, math.nan, math.nan, 0.0, math.nan, math.nan, math.nan))
            reasons.append(e.message)
            continue
        rows.append((s.amplitude, s.offset, s.stick_fraction, float(s.converged), s.periods, s.change, s.error))
        reasons.append("")
    out = np.array(rows, dtype=float).reshape(len(f_hz), 7)
    return {"rows": out, "reason": np.array(reasons, dtype=object), "cpu": np.array([time.process_time() - t0])}

