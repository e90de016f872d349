"""Steady states that are steady, and the frequency response of an oscillator in physical units.

Two methods (``frequency_response(..., method=...)``, ``dryfriction response --method``):

``orbit`` (the default with the exact scheme): the steady states are the periodic orbits of
:func:`dryfriction.analysis.orbits.find_orbits` (Newton shooting on the exact stroboscopic map, the Floquet
multipliers from the FMU's own Jacobian): every orbit found at each frequency, stable or not, along
a dimension ``orbit`` (padded NaN). Each orbit of one frequency is followed to the next (Newton from
a polynomial prediction of its state at its section, :class:`dryfriction.analysis.orbits.OrbitFollower`, no
sampled cycle runs); :func:`~dryfriction.analysis.orbits.find_orbits` from transients at the first frequency
and wherever the followed orbits include no stable one (a bifurcation of the branch followed; with
no stable orbit of K periods, of 2 K too: a period doubling);
every :data:`COLD_EVERY` frequencies the transients of that search are followed too (a branch born
away from the ones followed).

``transient``: :func:`steady_state` runs the FMU from the initial conditions for n = ``min_periods``,
2 n, 4 n, ... excitation periods (one ``doStep`` each, the in-FMU observables over the last half of
the run, so that successive runs observe successive, adjacent windows [n/2, n] T and [n, 2n] T).
It stops when the error left in the last window, estimated from the last three windows, is within
the tolerance:

    e_A <= tol A_j,   e_o <= tol A_j,   |s_j - s_{j-1}| <= tol_stick

(A the amplitude, half the peak-to-peak of x over the window, m; o the offset, the window's
mid-range, m; s the share of the window spent stuck). The estimate fits the decay of a transient to
the last three windows: a window's amplitude is taken as A_inf + B u^(2^j) (a free vibration
decaying geometrically in time, each window starting at twice the time of the one before), so that
with the differences d_j = A_j - A_{j-1} and q = d_j / d_{j-1} = u (u + 1) the error left is
e = |d_j| u^2 / (1 - u^2), times the safety factor :data:`SAFETY`. A change that does not shrink
(|q| >= 2: u >= 1, e.g. a free vibration that decays slowly against the run) is never converged,
however small it is. Without friction (mu_k N = 0) the decay rate is known, zeta w0, and the larger
of the two estimates is used. ``tol`` thus bounds the estimated error of the amplitude, not the
change between two windows. ``converged = False`` is reported with the last window's values when
``max_periods`` is reached first. A window covers many periods, so period-n motions and slow beats
are compared as wholes. An undamped oscillator excited at its resonance with 4 mu_k N < pi P0 never
converges (the amplitude grows by (pi P0 - 4 mu_k N) / k per period): it is reported so, never as
a steady amplitude.

:func:`frequency_response` does either for a list of frequencies in Hz (in this process, or on Dask
workers for long sweeps) and returns an xarray Dataset with units; :func:`plot_response` draws it
with Den Hartog's and Inman's amplitudes where they apply and the stick share below.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..budget import check_memory, check_work
from ..drivers.oscillator import FMUError, OscillatorFMU2, Settings
from .orbits import SAME, STABILITY_MARGIN, find_orbits, scales
from ..params import Oscillator

__all__ = ["SteadyState", "steady_state", "frequency_response", "plot_response", "TOL", "TOL_STICK",
           "MIN_PERIODS", "MAX_PERIODS", "METHODS", "default_settings", "remaining_error", "response_work"]

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


# ---- frequency response ---------------------------------------------------------------------------

def _chunk(fmu: str | bytes, base: Mapping[str, float], f_hz: np.ndarray, opts: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """One Dask task (or an in-process chunk): steady states at the frequencies f_hz."""
    import time

    from .chaos.batch import fmu_for

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


#: the orbit method's cold search (transients from several initial conditions) every this many
#: frequencies, besides the first and wherever the warm start finds no stable orbit
COLD_EVERY = 100
#: samples per period of the orbit method's cycle runs (section choice; amplitudes, offsets and stick
#: shares are the FMU's observables, exact whatever this is)
ORBIT_SAMPLES = 32
#: columns of the orbit method's table per (frequency, orbit)
ORBIT_COLUMNS = ("period", "stable", "mu_max", "amplitude_m", "offset_m", "stick_fraction", "x0_m", "v0_m_per_s",
                 "residual", "neutral", "rest_from_m", "rest_to_m")
#: the columns of ORBIT_COLUMNS that are booleans (the Dataset's bool variables)
ORBIT_FLAGS = ("stable", "neutral")
METHODS = ("orbit", "transient")


class _Branch:
    """One orbit of the previous frequencies (f, period T) with up to three before it on the same
    branch: a polynomial predictor (cubic through four points, else through the points there are) of
    its section state and phase at the next frequency (cubic rather than quadratic: about a third
    fewer second Newton steps along a sweep, docs/performance.md)."""

    __slots__ = ("orbit", "f", "T", "history", "point")

    def __init__(self, orbit: Any, f: float, T: float, before: "_Branch | None" = None) -> None:
        self.orbit, self.f, self.T = orbit, f, T
        hist = [] if before is None else [before, *before.history[:2]]
        self.history = [b for b in hist if b.f != f]
        z = orbit.section_state
        self.point = (float(z[0]), float(z[1]), orbit.section / T)

    def guess(self, f: float) -> tuple[tuple[float, float], float]:
        """(state, section phase in periods) predicted at the frequency f."""
        pts = [self, *self.history]
        ph0 = self.point[2]
        for b in self.history:
            if abs(b.point[2] - ph0) > 0.25:
                pts = pts[:1]                   # the section was chosen again: no extrapolation
                break
        fs = [b.f for b in pts]
        x = v = ph = 0.0
        for bi in pts:                          # Lagrange weights of the points at f
            w, fi = 1.0, bi.f
            for fj in fs:
                if fj != fi:                    # the points' frequencies differ (history)
                    w *= (f - fj) / (fi - fj)
            px, pv, pp = bi.point
            x += w * px
            v += w * pv
            ph += w * pp
        return (x, v), ph


def _attracting(o: Any, p: Oscillator) -> bool:
    """A steady state: a stable orbit, the block at rest (``neutral``: one of the interval of rest
    positions); without a spring (every orbit one of a family shifted in x, a multiplier exactly 1,
    ``stable`` false) one whose other multiplier is inside the unit circle."""
    if o.stable or o.neutral:
        return True
    if p.k > 0 or o.stuck:
        return False
    mu = sorted(abs(complex(m)) for m in o.multipliers)
    return len(mu) == 2 and mu[0] < 1.0 - STABILITY_MARGIN


def _distinct(orbits: list[Any], p: Oscillator) -> list[Any]:
    """Orbits of period 1 whose states at t = 0 differ (scaled, as find_orbits tells orbits apart);
    the members of a family shifted in x (without a spring, or neutral: a spring too weak to tell them
    apart) are one (x0 - offset and v0 compared)."""
    if len(orbits) < 2:
        return list(orbits)
    xs, w = scales(p)
    out: list[Any] = []
    seen: list[tuple[float, float]] = []
    for o in orbits:
        x = o.x0 - o.offset if (p.k == 0 or o.neutral) and math.isfinite(o.offset) else o.x0
        a0, a1 = x / xs, o.v0 / (xs * w)
        tol = SAME * max(1.0, abs(a0), abs(a1))
        if o.period == 1 and any(max(abs(a0 - q0), abs(a1 - q1)) <= tol for q0, q1 in seen):
            continue
        seen.append((a0, a1))
        out.append(o)
    return out


def _orbits_at(inst: OscillatorFMU2, p: Oscillator, f: float, branches: list[_Branch], cold: bool,
               opts: Mapping[str, Any]) -> list[_Branch]:
    """The orbits at the frequency f: each branch followed (Newton from its predicted section state,
    :class:`dryfriction.analysis.orbits.OrbitFollower`), and with ``cold`` transients from the spread of
    initial conditions followed too (:func:`_transient_check`); where a branch is lost (or K > 1),
    find_orbits from the previous orbits; without branches or when none is stable, find_orbits from
    transients too."""
    K, T = opts["period"], p.period
    follow = opts["follower"]
    if K == 1 and branches:
        followed: list[_Branch] = []
        for b in branches:
            o = None
            if not b.orbit.stuck and b.orbit.period == 1:
                z, ph = b.guess(f)
                o = follow(p, z, ph * T)
            if o is None:
                break
            followed.append(_Branch(o, f, T, b))
        else:
            _mirrors(p, f, followed, follow)
            if any(_attracting(b.orbit, p) for b in followed):
                if cold:
                    followed = _transient_check(inst, p, f, followed, opts)
                if len(followed) == 1:
                    return followed
                keep = {id(o) for o in _distinct([b.orbit for b in followed], p)}
                return [b for b in followed if id(b.orbit) in keep]
    guesses = [(b.orbit.x0, b.orbit.v0) for b in branches]
    kw = {"period": K, "guesses": guesses, "fmu": inst, "samples": ORBIT_SAMPLES}
    orbits = find_orbits(p, transients=0, spread=(), **kw) if branches else []
    if not branches or not any(_attracting(o, p) for o in orbits):
        orbits = find_orbits(p, transients=opts["transients"], **kw)
    if not any(_attracting(o, p) for o in orbits):
        # no stable orbit of K periods: the attractor may have doubled its period (reported with
        # its minimal period, the unstable K-orbits kept)
        kw["period"] = 2 * K
        more = find_orbits(p, transients=opts["transients"], **kw)
        orbits = orbits + [o for o in more if o.period != K]
    return [_Branch(o, f, T) for o in _distinct(orbits, p)]


def _mirrors(p: Oscillator, f: float, followed: list[_Branch], follow: Any) -> None:
    """Add the mirror image (x, v)(t) -> -(x, v)(t + T/2) of each asymmetric orbit followed whose
    image is not among them (a symmetric orbit followed through a symmetry-breaking pitchfork comes
    out as one of the pair)."""
    T = p.period
    for b in list(followed):
        o = b.orbit
        if o.period != 1 or not abs(o.offset) > 1e-9 * o.amplitude:
            continue
        tol = 1e-7 * o.amplitude
        if any(abs(q.orbit.offset + o.offset) <= tol and abs(q.orbit.amplitude - o.amplitude) <= tol for q in followed):
            continue
        image = follow(p, -o.section_state, o.section + 0.5 * T)
        if image is not None:
            followed.append(_Branch(image, f, T))


def _transient_check(inst: OscillatorFMU2, p: Oscillator, f: float, found: list[_Branch],
                     opts: Mapping[str, Any]) -> list[_Branch]:
    """The cold search of a sweep's later frequencies, cheap: the end states of find_orbits'
    transients (its spread of initial conditions), each followed by Newton from t = 0 (as a
    section), find_orbits for one that cannot be; a new orbit's mirror image (the state -z half a
    period later) followed too."""
    from .orbits import _auto_guesses, DEFAULT_SPREAD

    follow, T = opts["follower"], p.period
    xs, w = scales(p)
    out = list(found)

    def known(x: float, v: float) -> bool:
        a = (x / xs, v / (xs * w))
        tol = SAME * max(1.0, abs(a[0]), abs(a[1]))
        return any(abs(a[0] - b.orbit.x0 / xs) <= tol and abs(a[1] - b.orbit.v0 / (xs * w)) <= tol for b in out)

    runs = opts["transient_runs"]         # one set of value arrays for the sweep's cold searches
    runs.retarget(p)
    for z in _auto_guesses(p, DEFAULT_SPREAD):
        runs.run(float(z[0]), float(z[1]), 0.0, opts["transients"] * T)
        y = {"x": runs.real[0], "v": runs.real[1]}
        o = follow(p, (y["x"], y["v"]), 0.0)
        if o is None:
            new = [q for q in find_orbits(p, guesses=[(y["x"], y["v"])], transients=0, spread=(), fmu=inst,
                                          samples=ORBIT_SAMPLES) if not known(q.x0, q.v0)]
            out.extend(_Branch(q, f, T) for q in new)
            continue
        if known(o.x0, o.v0):
            continue
        out.append(_Branch(o, f, T))
        image = follow(p, -o.section_state, o.section + 0.5 * T)
        if image is not None and not known(image.x0, image.v0):
            out.append(_Branch(image, f, T))
    return out


def _orbit_chunk(fmu: str | bytes, base: Mapping[str, float], f_hz: np.ndarray,
                 opts: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """One Dask task (or the in-process sweep): every orbit at the frequencies f_hz in turn, the
    orbits of one frequency followed to the next."""
    import time

    from .chaos.batch import fmu_for

    from .orbits import OrbitFollower

    inst = fmu_for(fmu)
    t0 = time.process_time()
    table: list[list[tuple[float, ...]]] = []
    reasons: list[str] = []
    branches: list[_Branch] = []
    checked = Oscillator(**{**base, "omega": 2.0 * math.pi * float(f_hz[0])})
    # the transients of the cold searches read x, v at their end
    opts = {**opts, "follower": OrbitFollower(inst), "transient_runs": inst.restarts(checked, default_settings(checked))}
    for i, f in enumerate(np.asarray(f_hz, dtype=float).tolist()):
        # the oscillator at f: the checked one with omega replaced (f is checked finite and > 0 by
        # frequency_response; a new check per point would cost a fifth of the sweep)
        p = object.__new__(Oscillator)
        p.__dict__.update(checked.__dict__, omega=2.0 * math.pi * f)
        try:
            branches = _orbits_at(inst, p, f, branches, not branches or i % opts["cold_every"] == 0, opts)
        except FMUError as e:   # this frequency is not computed: its row says why, the sweep goes on
            table.append([])
            reasons.append(e.message)
            branches = []
            continue
        rows, kept, stuck = [], [], False
        for b in branches:
            o = b.orbit
            if o.stuck:        # the interval of rest positions: reported once
                if stuck:
                    continue
                stuck = True
            kept.append(b)
            lo, hi = o.rest_interval if o.rest_interval is not None else (math.nan, math.nan)
            rows.append((float(o.period), float(o.stable), o.mu_max, o.amplitude, o.offset, o.stick_fraction,
                         o.x0, o.v0, o.residual, float(o.neutral), lo, hi, float(_attracting(o, p))))
        branches = kept
        table.append(rows)
        reasons.append("")
    width = max([len(r) for r in table] + [1])
    pad = (math.nan,) * (len(ORBIT_COLUMNS) + 1)
    out = np.array([rows + [pad] * (width - len(rows)) for rows in table], dtype=float).reshape(
        len(f_hz), width, len(ORBIT_COLUMNS) + 1)
    return {"orbits": out, "reason": np.array(reasons, dtype=object), "cpu": np.array([time.process_time() - t0])}


def frequency_response(p: Oscillator, f_hz: Sequence[float] | np.ndarray, *, method: str | None = None,
                       tol: float = TOL, min_periods: int = MIN_PERIODS, max_periods: int = MAX_PERIODS,
                       scheme: str | None = None, h: float = 0.0, period: int = 1, transients: int = 60,
                       cold_every: int = COLD_EVERY, workers: int = 0, progress: bool = False,
                       fmu_path: str | os.PathLike[str] | None = None, max_work: float | None = None) -> Any:
    """Steady states of ``p`` at the excitation frequencies ``f_hz`` (Hz), as an xarray Dataset
    (dimension ``f_hz``; attributes: the oscillator and the settings, with units).

    ``method`` ``"orbit"`` (the default, unless a Bossak ``scheme`` is asked for: the orbits need the
    exact scheme's Jacobian): every periodic orbit of ``period`` excitation periods found
    (:func:`dryfriction.analysis.orbits.find_orbits`; the previous frequency's orbits are the next one's
    guesses, ``transients`` the length of the cold searches' transients, ``cold_every`` their
    spacing in frequencies besides the first one and where no stable orbit is found), along a second dimension
    ``orbit``: period, stable, neutral, mu_max, amplitude_m, offset_m, stick_fraction, x0_m,
    v0_m_per_s, residual, rest_from_m, rest_to_m (the block at rest: one orbit, amplitude 0, ``neutral``,
    with the interval of its rest positions); ``n_orbits`` and ``converged`` (at least one stable orbit,
    or the block at rest) per frequency. The padding of ``orbit`` (fewer orbits than the widest
    frequency's) is the bool mask ``has_orbit``: the numbers are NaN there and the bool variables
    ``stable``, ``neutral`` False (they stay bool: NaN would make them floats, None objects, which NetCDF
    cannot hold).

    ``method`` ``"transient"``: :func:`steady_state` (variables amplitude_m, offset_m, stick_fraction,
    converged, periods, change, error).

    Both: reason, den_hartog_m, inman_m. A frequency the FMU cannot compute gets NaN values,
    ``converged`` False and the FMU's sentence in ``reason``; the other frequencies go on.

    ``scheme`` None: exact (also at k = 0). ``workers`` > 0 runs
    the frequencies on a Dask LocalCluster of that many processes (for long sweeps), streamed in
    chunks of at most :data:`MAX_CHUNK` frequencies.

    The work is estimated before it starts (:func:`response_work`, in steps,
    :mod:`dryfriction.budget`) and refused (:class:`~dryfriction.budget.WorkBoundError`) above
    ``max_work`` (default :data:`~dryfriction.budget.DEFAULT_MAX_WORK`), as is a table too large for
    half this machine's memory.

    Returns
    -------
    xarray.Dataset
        The steady states by frequency (and by orbit for ``method="orbit"``), SI units, the units and
        the settings in the attributes.

    Raises
    ------
    ValueError
        An unknown ``method``, a Bossak ``scheme`` with ``method="orbit"``, a ``period`` or
        ``cold_every`` that is not an integer >= 1.
    dryfriction.budget.WorkBoundError
        The estimated work is above ``max_work`` (a :class:`~dryfriction.errors.UsageError`).
    dryfriction.FMUFileError
        No usable oscillator FMU at ``fmu_path`` (or found by :mod:`dryfriction.paths`).

    Examples
    --------
    >>> from dryfriction import Oscillator, frequency_response
    >>> block = Oscillator.physical(m=0.5, k=2000, zeta=0.003, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2)
    >>> ds = frequency_response(block, [5, 10, 15])         # Hz
    >>> round(float(ds.amplitude_m.sel(f_hz=10).max()), 4)   # m, one stable orbit
    0.2356
    """
    import xarray as xr

    from .chaos.batch import map_chunks
    from .. import paths
    from ..references.steady import den_hartog_amplitude, inman_amplitude

    f = _frequencies(f_hz)
    if method is None:
        method = "orbit" if scheme in (None, "exact") else "transient"
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, not {method!r}")
    if method == "orbit" and scheme not in (None, "exact"):
        raise ValueError(f"the orbit method needs the exact scheme (its Jacobian), not scheme {scheme!r}: "
                         "use method='transient' for the Bossak schemes")
    if not (isinstance(period, int) and period >= 1):
        raise ValueError(f"period must be an integer >= 1 (excitation periods), not {period!r}")
    if method == "orbit" and not (isinstance(cold_every, int) and cold_every >= 1):
        raise ValueError(f"cold_every must be an integer >= 1 (frequencies), not {cold_every!r}")
    work, what = response_work(p, f.size, method, period=period, transients=transients, cold_every=cold_every,
                               max_periods=max_periods, scheme=scheme, h=h)
    check_work(work, what, max_work, option="max_work")
    check_memory(f.size * RESPONSE_BYTES, f"{f.size:,} frequencies", "fewer frequencies")
    path = paths.fmu_path(paths.OSCILLATOR, fmu_path)
    base = {k: v for k, v in p.as_dict().items() if k != "omega"}
    if method == "orbit":
        opts: dict[str, Any] = {"period": period, "transients": transients, "cold_every": cold_every}
        per_chunk = min(math.ceil(f.size / max(1, 2 * workers)), MAX_CHUNK) if workers else f.size
        task: Any = _orbit_chunk
    else:
        opts = {"tol": tol, "min_periods": min_periods, "max_periods": max_periods, "scheme": scheme, "h": h}
        per_chunk = max(1, min(16, math.ceil(f.size / max(1, 4 * workers)))) if workers else max(1, min(8, f.size))
        task = _chunk
    # streamed: each task built when it is submitted, from a slice of the frequencies
    chunks = ((base, f[i:i + per_chunk], opts) for i in range(0, f.size, per_chunk))
    results, _ = map_chunks(task, path, chunks, workers=workers, progress=progress, desc="response",
                            total=-(-f.size // per_chunk))
    reason = np.concatenate([r["reason"] for r in results]).astype(str)
    lam = 2.0 * math.pi * f / p.w0 if p.k > 0 else np.full(f.shape, np.inf)
    applies = p.k > 0 and p.c == 0 and p.P0 != 0
    dh = np.asarray(den_hartog_amplitude(p, lam), dtype=float) if applies else np.full(f.shape, np.nan)
    inm = np.asarray(inman_amplitude(p, lam), dtype=float) if applies else np.full(f.shape, np.nan)
    common = {
        "reason": ("f_hz", reason, {"long_name": "why the point was not computed (the FMU's sentence; "
                                                 "empty where it was)"}),
        "den_hartog_m": ("f_hz", dh, {"units": "m", "long_name": "Den Hartog (zeta = 0, non-stop), exact"}),
        "inman_m": ("f_hz", inm, {"units": "m", "long_name": "Inman (equivalent viscous damping), approximate"}),
    }
    attrs = {**{f"param_{k}": v for k, v in p.as_dict().items() if k != "omega"},
             "param_mu_k": p.mu_k, "param_zeta": p.zeta, "natural_frequency_hz": p.f_n_hz,
             "units": "SI: m, kg, N, s, Hz", "method": method, "scheme": scheme or "exact",
             "never_converges": never_converges_note(p)}
    coords = {"f_hz": ("f_hz", f, {"units": "Hz", "long_name": "excitation frequency"})}
    if method == "orbit":
        width = max(r["orbits"].shape[1] for r in results)
        tab = np.concatenate([np.pad(r["orbits"], ((0, 0), (0, width - r["orbits"].shape[1]), (0, 0)),
                                     constant_values=np.nan) for r in results], axis=0)
        col = {n: tab[:, :, i] for i, n in enumerate(ORBIT_COLUMNS + ("attracting",))}
        # a bool stays a bool: the padding (no orbit) is the mask has_orbit, the flags False there (NaN
        # would make them floats, None objects, which NetCDF cannot hold)
        has = np.isfinite(col["period"])
        n_orbits = np.sum(has, axis=1)
        flag = {n: has & (col[n] == 1.0) for n in ORBIT_FLAGS + ("attracting",)}
        dims = ("f_hz", "orbit")
        ds = xr.Dataset(
            {
                "has_orbit": (dims, has, {"long_name": "an orbit at this index (False: padding, every variable "
                                                       "NaN or False there)"}),
                "period": (dims, col["period"], {"units": "excitation periods", "long_name": "period K of the orbit"}),
                "stable": (dims, flag["stable"], {
                    "long_name": "stable: every |multiplier| < 1 (False for an unstable or neutral orbit, and where "
                                 "has_orbit is False)"}),
                "neutral": (dims, flag["neutral"], {
                    "long_name": "neutrally stable: a multiplier exactly 1 along a continuum of orbits, the other "
                                 "inside the unit circle (the block at rest; a family shifted in x)"}),
                "mu_max": (dims, col["mu_max"], {"units": "1", "long_name": "largest |Floquet multiplier|"}),
                "amplitude_m": (dims, col["amplitude_m"], {"units": "m",
                                                           "long_name": "amplitude, half peak-to-peak of x over the orbit"}),
                "offset_m": (dims, col["offset_m"], {"units": "m", "long_name": "offset, (x_max + x_min) / 2"}),
                "stick_fraction": (dims, col["stick_fraction"], {"units": "1", "long_name": "share of the orbit stuck"}),
                "x0_m": (dims, col["x0_m"], {"units": "m", "long_name": "x at t = 0 mod K T"}),
                "v0_m_per_s": (dims, col["v0_m_per_s"], {"units": "m/s", "long_name": "v at t = 0 mod K T"}),
                "residual": (dims, col["residual"], {"units": "1", "long_name": "scaled Newton residual"}),
                "rest_from_m": (dims, col["rest_from_m"], {"units": "m", "long_name": "the block at rest: the lowest "
                                                                     "rest position, -(F_b - |P0|) / k (NaN for "
                                                                     "other orbits)"}),
                "rest_to_m": (dims, col["rest_to_m"], {"units": "m", "long_name": "the block at rest: the highest rest "
                                                                 "position, (F_b - |P0|) / k"}),
                "n_orbits": ("f_hz", n_orbits, {"units": "1", "long_name": "orbits found"}),
                "converged": ("f_hz", np.any(flag["attracting"], axis=1),
                              {"long_name": "a stable orbit was found (a steady state; the block at rest "
                                            "counts, neutral; without a spring: one attracting but for its neutral "
                                            "shift in x)"}),
                **common,
            },
            coords={**coords, "orbit": ("orbit", np.arange(width), {"long_name": "orbit index (stable first, "
                                                                                  "then neutral, then by amplitude)"})},
            attrs={**attrs, "period": period, "transients": transients, "cold_every": cold_every},
        )
        return ds
    rows = np.concatenate([r["rows"] for r in results], axis=0)
    ds = xr.Dataset(
        {
            "amplitude_m": ("f_hz", rows[:, 0], {"units": "m", "long_name": "amplitude, half peak-to-peak of x"}),
            "offset_m": ("f_hz", rows[:, 1], {"units": "m", "long_name": "offset, (x_max + x_min) / 2"}),
            "stick_fraction": ("f_hz", rows[:, 2], {"units": "1", "long_name": "share of the window stuck"}),
            "converged": ("f_hz", rows[:, 3].astype(bool),
                          {"long_name": f"estimated error of the last window within {tol:g} (relative)"}),
            "periods": ("f_hz", rows[:, 4], {"units": "1", "long_name": "excitation periods run"}),
            "change": ("f_hz", rows[:, 5], {"units": "1", "long_name": "relative amplitude change, last two windows"}),
            "error": ("f_hz", rows[:, 6], {"units": "1", "long_name": "estimated relative error left in the last "
                                                                      "window"}),
            **common,
        },
        coords=coords,
        attrs={**attrs, "tol": tol, "tol_stick": TOL_STICK, "min_periods": min_periods, "max_periods": max_periods},
    )
    return ds


#: frequencies of one Dask task of the orbit method at most (a worker's memory and a lost
#: worker's redo stay small)
MAX_CHUNK = 2000
#: bytes the response holds per frequency in this process (the results of the tasks and the
#: Dataset; measured: 2.56 GB for 10^6 frequencies of the orbit method)
RESPONSE_BYTES = 3000
#: steps (:mod:`dryfriction.budget`) one frequency of the orbit method counts, besides its cold
#: searches: Newton from the predicted orbits, their multipliers, the cycle run (measured: 183
#: microseconds per frequency over 10^6 frequencies, about 12,000 Bossak steps)
ORBIT_FREQUENCY_STEPS = 12000.0


def response_work(p: Oscillator, n: int, method: str, *, period: int = 1, transients: int = 60,
                  cold_every: int = COLD_EVERY, max_periods: int = MAX_PERIODS, scheme: str | None = None,
                  h: float = 0.0) -> tuple[float, str]:
    """The estimated work of :func:`frequency_response` over ``n`` frequencies, in steps
    (:mod:`dryfriction.budget`), and what it is made of: the orbit method's Newton periods and
    cold searches (transients from each of the spread's initial conditions at the first frequency
    and every ``cold_every``); the transient method's bound, 2 ``max_periods`` periods per
    frequency (32 + 64 + ... up to the limit)."""
    from ..budget import BOSSAK_PERIOD_STEPS, EXACT_PERIOD_STEPS, fmt
    from .orbits import DEFAULT_SPREAD

    if method == "orbit":
        cold = len(DEFAULT_SPREAD) * (transients + 10) * period * EXACT_PERIOD_STEPS
        per = ORBIT_FREQUENCY_STEPS * period + cold / cold_every
        return n * per + cold, f"{n:,} frequencies x about {fmt(per)} steps"
    if scheme in (None, "exact"):
        steps = EXACT_PERIOD_STEPS
    elif h > 0:
        steps = max(p.period / h, 1.0)
    else:
        steps = BOSSAK_PERIOD_STEPS
    periods = 2.0 * max_periods
    return n * periods * steps, f"{n:,} frequencies x up to {fmt(periods)} periods x {fmt(steps)} steps"


def _frequencies(f_hz: Any) -> np.ndarray:
    """The frequencies as a 1-D float array, checked: numbers (not strings, not booleans), finite,
    > 0, at least one."""
    if isinstance(f_hz, (str, bytes)):
        raise ValueError(f"the frequencies must be numbers in Hz, not the string {f_hz!r}")
    arr = np.asarray(f_hz)
    if arr.dtype.kind not in "iuf" or isinstance(f_hz, (list, tuple)):
        items = (x.item() if isinstance(x, np.generic) else x
                 for x in (f_hz if isinstance(f_hz, (list, tuple)) else np.ravel(arr)))
        ok = object()
        bad = next((x for x in items if isinstance(x, (str, bytes, bool)) or not isinstance(x, (int, float))), ok)
        if bad is not ok or arr.size == 0 and arr.dtype.kind not in "iufO":
            what = f"{type(bad).__name__} {bad!r}" if bad is not ok else f"{arr.dtype} values"
            raise ValueError(f"the frequencies must be numbers in Hz, not {what}")
    f = np.asarray(arr, dtype=float)
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("the frequencies must be a non-empty list of finite values > 0 Hz")
    return f


def never_converges_note(p: Oscillator) -> str:
    """A sentence when the oscillator has an unbounded resonance (c = 0, 4 mu_k N < pi P0), else ''."""
    if p.c == 0 and p.k > 0 and 4.0 * p.mu_k * p.N < math.pi * abs(p.P0):
        return (f"undamped with 4 mu_k N = {4 * p.mu_k * p.N:.4g} N < pi P0 = {math.pi * abs(p.P0):.4g} N: "
                f"at the natural frequency {p.f_n_hz:.6g} Hz the amplitude grows without bound "
                "(never converges)")
    return ""


def plot_response(ds: Any, path: str | os.PathLike[str]) -> Path:
    """PNG: amplitude (m) vs f (Hz) with Den Hartog's and Inman's curves where they apply, and the
    stick share below; the orbit method: every orbit, stable ones filled on solid lines, unstable
    ones hollow on dashed lines; the transient method: unconverged points drawn hollow and labelled."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..atomic import atomic_path

    f = ds["f_hz"].values
    amp = ds["amplitude_m"].values
    conv = ds["converged"].values.astype(bool)
    orbit = ds.attrs.get("method") == "orbit"
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    if orbit:   # every orbit: stable (and neutral: at rest) filled on solid lines, unstable hollow on dashed ones
        has = ds["has_orbit"].values
        st = ds["stable"].values | ds["neutral"].values
        un = has & ~st
        for j in range(amp.shape[1]):
            a = amp[:, j]
            ax.plot(f, np.where(st[:, j], a, np.nan), "-", color="C0", lw=1, zorder=1)
            ax.plot(f, np.where(un[:, j], a, np.nan), "--", color="C3", lw=1, zorder=1)
        ff = np.broadcast_to(f[:, None], amp.shape)
        ax.plot(ff[st], amp[st], "o", ms=4, color="C0", label="stable orbit (or at rest)", zorder=3)
        if un.any():
            ax.plot(ff[un], amp[un], "o", ms=5, mfc="none", mec="C3", mew=1.2,
                    label="unstable orbit", zorder=3)
    else:
        ax.plot(f, amp, "-", color="0.6", lw=1, zorder=1)
        ax.plot(f[conv], amp[conv], "o", ms=5, color="C0", label="FMU steady state (converged)", zorder=3)
        if (~conv).any():
            ax.plot(f[~conv], amp[~conv], "o", ms=6, mfc="none", mec="C3", mew=1.5,
                    label="not converged (last window)", zorder=3)
    if np.isfinite(ds["den_hartog_m"].values).any():
        ax.plot(f, ds["den_hartog_m"].values, "--", color="k", lw=1.3, label="Den Hartog (exact, non-stop, zeta = 0)")
    if np.isfinite(ds["inman_m"].values).any():
        ax.plot(f, ds["inman_m"].values, ":", color="C2", lw=1.6, label="Inman (approximate, stiction neglected)")
    fn = float(ds.attrs.get("natural_frequency_hz", np.nan))
    for a in (ax, bx):
        if f.min() <= fn <= f.max():
            a.axvline(fn, color="0.5", lw=0.8, ls="-.")
    if f.min() <= fn <= f.max():
        ax.text(fn, ax.get_ylim()[1] * 0.97, f" natural frequency {fn:.4g} Hz", va="top", fontsize=8, color="0.3")
    ax.set_ylabel("amplitude X (half peak-to-peak of x), m")
    ax.set_title(f"steady-state frequency response: m = {ds.attrs['param_m']:g} kg, k = {ds.attrs['param_k']:g} N/m, "
                 f"zeta = {ds.attrs['param_zeta']:.3g},\nP0 = {ds.attrs['param_P0']:g} N, N = {ds.attrs['param_N']:g} N, "
                 f"mu_s = {ds.attrs['param_mu_s']:g}, mu_k = {ds.attrs['param_mu_k']:.3g}", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    if orbit:
        sf = np.where(ds["stable"].values | ds["neutral"].values, ds["stick_fraction"].values, np.nan)
        for j in range(sf.shape[1]):
            bx.plot(f, 100 * sf[:, j], "s-", ms=3, color="C1", label="stuck share of the stable orbits" if j == 0 else None)
    else:
        bx.plot(f, 100 * ds["stick_fraction"].values, "s-", ms=4, color="C1", label="stuck share of the window")
    bx.set_ylabel("stuck, % of time")
    bx.set_xlabel("excitation frequency f, Hz")
    bx.set_ylim(-5, 105)
    bx.grid(alpha=0.3)
    bx.legend(fontsize=8, loc="best")
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return out


def with_omega(p: Oscillator, f_hz: float) -> Oscillator:
    """The oscillator driven at ``f_hz`` Hz instead (omega = 2 pi f)."""
    return replace(p, omega=2.0 * math.pi * f_hz)
