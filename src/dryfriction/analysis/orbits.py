"""Periodic orbits of the excited oscillator by Newton shooting on the exact stroboscopic map
(docs/orbits.md).

The map P^K: (x, v) at the section time t_s -> (x, v) at t_s + K T, T = 2 pi / omega, is the FMU's
scheme ``exact`` run in one ``doStep`` through :class:`~dryfriction.drivers.oscillator.OscillatorFMU2`; its 2 x 2
Jacobian is the FMU's own (``sensitivity = true``: the linear flow of each slide and the saltation
matrix of each event), never a finite difference. Newton: solve (J - I) dz = -r, r = P^K(z) - z, with
a backtracking line search on the scaled residual; converged when the residual is at most ``tol``
(default 1e-12) relative: ``|S^-1 r|_inf / max(1, |S^-1 z|_inf)`` with S = diag(x_s, x_s w) the
problem's own scales (:func:`scales`: the static deflection |P0| / k and w0 below the natural
frequency, the forced motion |P0| / (m omega^2) and omega above it and without a spring), then
while the Newton step itself is above ``tol`` (a multiplier near 1) up to two more steps. A converged
state that creeps (x moves over its cycle by more than 1e-3 of its motion) is not an orbit.

Section rule: the map is not differentiable in v inside a stick phase, so the section t_s is taken in
the middle of the longest slide of the guess's cycle (re-chosen if the converged orbit moved a stick
phase onto it), or, where the slides are shorter than the cycle's samples, of its longest stick
phase (Newton then solves for the stuck position); the state at t = 0 mod K T is then read from a run
of the converged orbit. The block at rest (|P0| within the breakaway force) is one orbit: a member of
the interval of rest positions :func:`rest_interval`, its Jacobian the FMU's over a period, rank one,
multipliers exactly 1 (along the interval: ``neutral``) and 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..drivers.oscillator import OscillatorFMU2, Restarts, Settings
from ..params import Oscillator
from .shooting import STABILITY_MARGIN, Newton, OrbitRecord, _roots2, classify, multipliers, newton

__all__ = ["Orbit", "OrbitFollower", "find_orbits", "follow_orbit", "stroboscopic_map", "scales", "rest_interval",
           "neutral_margin", "STABILITY_MARGIN"]

JACOBIAN = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")
#: samples per excitation period of the cycle runs (section choice, events, stick share of the cycle)
SAMPLES = 512
#: scaled distance under which two converged states are the same orbit
SAME = 1e-7
#: scaled distance under which the end states of two transients are one guess (solved once)
ALIKE = 1e-10
#: Newton's iterates must stay within BOUND times the frictionless harmonic amplitude (plus the
#: static deflections of the excitation and of friction), else the solve is reported as diverged
BOUND = 1e3
#: the frictionless amplification k X / P0 the bound assumes at most (zeta >= 5e-7 at resonance)
MAX_AMPLIFICATION = 1e6
#: Newton steps at most after the residual is within tol, while the step itself is not (a multiplier
#: near 1: the residual then understates the distance to the orbit)
POLISH = 2


@dataclass
class Orbit(OrbitRecord):
    """One periodic orbit of K excitation periods (``period``), its state at t = 0 mod K T. Read as
    ``orbit.x0`` or ``orbit["x0"]``; ``orbit.mu_max`` the largest |multiplier|."""

    period: int
    x0: float                        # m, at t = 0 mod K T
    v0: float                        # m/s
    z0: float                        # k x0 / P0 (static deflections; NaN without a spring)
    zdot0: float                     # dz/dtau, tau = w0 t: k v0 / (P0 w0) (NaN without a spring)
    multipliers: np.ndarray          # eigenvalues of the K-period Jacobian (complex, |mu| descending)
    stable: bool                     # every |mu| < 1 - STABILITY_MARGIN
    residual: float                  # the scaled Newton residual at the section (see the module's doc)
    amplitude: float                 # (x_max - x_min) / 2 over the cycle, m (the FMU's observables)
    offset: float                    # (x_max + x_min) / 2, m
    stick_fraction: float            # share of the cycle stuck (the FMU's observable)
    events: dict[str, int]           # per cycle: stops, breakaways, reversals, transitions (FMU's count)
    converged: bool
    reason: str = ""                 # why not converged ("" when converged)
    section: float = 0.0             # the section time t_s in [0, K T) the Newton solve used, s
    jacobian: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))  # at the section
    section_state: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))  # (x, v) at the section
    iterations: int = 0
    stuck: bool = False              # never slides (stuck for good)
    neutral: bool = False            # a multiplier exactly 1 along a continuum of orbits, the other < 1: a
    #                                  steady state but not an isolated one (the block at rest, a member of
    #                                  rest_interval; without a spring, one of a family shifted in x)
    rest_interval: tuple[float, float] | None = None   # the block at rest: every x (m) it can rest at


def rest_interval(p: Oscillator) -> tuple[float, float] | None:
    """The positions x (m) where the block rests for good, or None when there are none: stuck at x
    (v = 0) the friction force holds P(t) - k x for every t while |P0 cos(omega t + phi) - k x| <= F_b,
    F_b = max(mu_s, mu_k) N the breakaway force (method.md section 1; a tangential touch of the limit
    keeps it stuck), i.e. for all t exactly when |k x| <= F_b - |P0|. So the block at rest is a
    closed interval [-(F_b - |P0|) / k, (F_b - |P0|) / k] when |P0| <= F_b (the single point 0 at
    |P0| = F_b), the whole line without a spring (k = 0), and empty when |P0| > F_b (the excitation
    breaks any rest). Every member is a periodic orbit of period 1 (damping plays no part: v = 0)."""
    margin = p.breakaway - abs(p.P0)
    if not margin >= 0.0:
        return None
    if p.k == 0.0:
        return (-math.inf, math.inf)
    h = margin / p.k
    return (-h, h)


#: x_s is at least this share of the static deflection |P0| / k: the exact scheme computes positions in
#: static deflections (rounding about 1.4e-14 of one), so a tolerance of 1e-12 in x_s stays above it
RESOLVED = 1e-2


def scales(p: Oscillator) -> tuple[float, float]:
    """(x_s, w): the position and rate scales of the residual (module doc): the excitation's
    deflection against the larger of the spring and the inertia at omega, x_s = |P0| / max(k, m omega^2),
    and w = max(w0, omega). Below the natural frequency (lambda <= 1) the static deflection |P0| / k
    and w0; above it |P0| / (m omega^2) and omega, the size of the forced motion there (at lambda = 10
    a hundredth of the static deflection), but at least RESOLVED static deflections (lambda > 10: the
    FMU resolves no finer); without a spring (k = 0) the amplitude of the free mass under the
    excitation and omega."""
    P0 = abs(p.P0)
    inertia = p.m * p.omega ** 2
    if p.k >= inertia:
        return P0 / p.k, p.w0
    return max(P0 / inertia, RESOLVED * P0 / p.k) if p.k > 0 else P0 / inertia, p.omega


class _Map:
    """The stroboscopic map P^K of one oscillator through one FMU instance (reset per evaluation,
    through the FMU driver's :class:`~dryfriction.drivers.oscillator.Restarts`: start's calls with the value arrays
    built once)."""

    #: the outputs of an evaluation: the state, the Jacobian (and the observables, see _ObservingMap)
    names: tuple[str, ...] = ("x", "v") + JACOBIAN

    def __init__(self, fmu: OscillatorFMU2, p: Oscillator, K: int, samples: int = SAMPLES) -> None:
        self.fmu, self.p, self.K, self.samples = fmu, p, K, samples
        self.T = p.period
        self.xs, self.w = scales(p)
        self.settings = Settings(scheme="exact", extra={"sensitivity": True})
        self.evaluations = 0
        self._runs: Restarts | None = None      # made at the first evaluation
        self.final = True                       # the last evaluation was a final one

    def retarget(self, p: Oscillator, xs_w: tuple[float, float] | None = None) -> None:
        """The same map of another oscillator (the same K and settings; ``xs_w``: its scales if known)."""
        self.p, self.T = p, p.period
        self.xs, self.w = scales(p) if xs_w is None else xs_w
        if self._runs is not None:
            self._runs.retarget(p)

    def scaled(self, z: np.ndarray) -> np.ndarray:
        return np.array([z[0] / self.xs, z[1] / (self.xs * self.w)])

    def at(self, z: np.ndarray) -> Oscillator:
        """The oscillator started from z: a copy of the checked one with x0, v0 replaced (any finite
        state is valid: no new check, which costs more than the FMU's run of a period)."""
        x, v = float(z[0]), float(z[1])
        if not (math.isfinite(x) and math.isfinite(v)):
            return self.p.with_(x0=x, v0=v)        # the check names the non-finite value
        q = object.__new__(type(self.p))
        q.__dict__.update(self.p.__dict__, x0=x, v0=v)
        return q

    #: Integer outputs read besides the mode
    ints: tuple[str, ...] = ()

    def _mid(self, t_s: float, t_end: float, KT: float) -> float | None:
        """An intermediate stop of the run from t_s to t_end = t_s + KT (none: the map reads only the end)."""
        return None

    def eval(self, x: float, v: float, t_s: float,
             final: bool = True) -> tuple[float, float, float, float, float, float, int]:
        """(P^K(z), its Jacobian's entries row by row, the mode at the end) as plain floats, for the
        state z = (x, v) at the section time t_s (``final`` False: an evaluation unlikely to be the
        converged one, which may leave out what only the converged one needs)."""
        if not (math.isfinite(x) and math.isfinite(v)):
            self.p.with_(x0=x, v0=v)               # raises: the check names the non-finite value
        runs = self._runs
        if runs is None:
            runs = self._runs = self.fmu.restarts(self.p, self.settings, self.names, ("mode",) + self.ints)
        KT = self.K * self.T
        t_end = t_s + KT
        mid = self._mid(t_s, t_end, KT)
        runs.run(x, v, t_s, t_end, mid if final else None)
        self.final = final or mid is None        # without a stop to make, every run is a final one
        self.evaluations += 1
        r = runs.real
        return r[0], r[1], r[2], r[3], r[4], r[5], runs.int[0]

    def __call__(self, z: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray, int]:
        """(P^K(z), its Jacobian, the mode at the end) for the state z at the section time t_s."""
        px, pv, a, b, c, d, md = self.eval(float(z[0]), float(z[1]), t_s)
        return np.array([px, pv]), np.array([[a, b], [c, d]]), md

    def cycle(self, z: np.ndarray, t_s: float, periods: int | None = None) -> dict[str, np.ndarray | float]:
        """A sampled run of ``periods`` (default K) periods from z at t_s, with the FMU's observables
        over it; the grid holds every multiple of T in (t_s, t_s + periods T]."""
        n = self.K if periods is None else periods
        T = self.T
        t_end = t_s + n * T
        grid = np.linspace(t_s, t_end, n * self.samples + 1)
        marks = T * np.arange(math.floor(t_s / T) + 1, math.floor(t_end / T + 1e-12) + 1)
        grid = np.unique(np.concatenate([grid, marks]))
        grid = grid[np.concatenate([[True], np.diff(grid) > 1e-12 * max(T, t_end)])]
        st = Settings(scheme="exact", observe=True, t_obs_start=t_s, t_obs_stop=t_end)
        res = self.fmu.trajectory(self.at(z), grid, st, ("x", "v", "mode"))
        obs = self.fmu.get(("x_max", "x_min", "stick_fraction", "transitions"))
        res.update({k: float(v) for k, v in obs.items()})
        res["marks"] = marks
        return res


def stroboscopic_map(oscillator: Oscillator, z: Sequence[float], t_s: float = 0.0, period: int = 1,
                     fmu: OscillatorFMU2 | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """(P^K(z), its exact Jacobian, the mode at the end) of the state z = (x, v) at the section time t_s."""
    own = fmu is None
    f = OscillatorFMU2() if own else fmu
    try:
        return _Map(f, oscillator, period)(np.asarray(z, dtype=float), t_s)
    finally:
        if own:
            f.close()


def _events(mode: np.ndarray) -> dict[str, int]:
    """Stops, breakaways and reversals in the sampled modes of a cycle (a phase shorter than a sample
    may be missed; ``transitions`` is the FMU's own count of mode changes)."""
    m = mode.astype(int)
    prev, nxt = m[:-1], m[1:]
    stops = int(np.sum((prev != 0) & (nxt == 0)))
    breaks = int(np.sum((prev == 0) & (nxt != 0)))
    revs = int(np.sum((prev != 0) & (nxt != 0) & (prev != nxt)))
    return {"stops": stops, "breakaways": breaks, "reversals": revs}


def _slide_section(t: np.ndarray, mode: np.ndarray, t_from: float, span: float, stuck: bool = False) -> float | None:
    """The middle of the longest run of sliding samples of a cycle (cyclic), as a time in
    [t_from, t_from + span); None if it never slides. ``stuck``: of the longest run of stuck samples
    instead (None if it never sticks)."""
    slide = (mode == 0) if stuck else (mode != 0)
    if not slide.any():
        return None
    if slide.all():               # slides all the time: any section will do (NaN: keep it)
        return float("nan")
    n = slide.size - 1            # the last sample is the first one again (one cycle)
    s = slide[:n]
    k0 = int(np.argmin(s))        # start the scan at a stuck sample
    best, best_len, run_start, run = 0, 0, 0, 0
    for j in range(1, n + 1):
        i = (k0 + j) % n
        if s[i]:
            if run == 0:
                run_start = j
            run += 1
            if run > best_len:
                best_len, best = run, run_start
        else:
            run = 0
    mid = (k0 + best + (best_len - 1) / 2.0) % n
    lo = int(math.floor(mid))
    frac = mid - lo
    ts = t[lo] + frac * (t[lo + 1] - t[lo]) if lo + 1 < t.size else t[lo]
    return float(t_from + ((ts - t_from) % span))


class _Solver:
    def __init__(self, fmu: OscillatorFMU2, p: Oscillator, K: int, tol: float, max_iter: int,
                 samples: int = SAMPLES, map_: "_Map | None" = None) -> None:
        self.map = _Map(fmu, p, K, samples) if map_ is None else map_
        self.K, self.tol, self.max_iter = K, tol, max_iter
        self._slide_runs: Restarts | None = None    # slides_throughout's runs (made at its first call)
        self.retarget(p)

    def retarget(self, p: Oscillator) -> None:
        """The same solver for another oscillator (its map moved along)."""
        self.p = p
        self.KT = self.K * p.period
        xs, w = scales(p)
        if self.map.p is not p:
            self.map.retarget(p, (xs, w))
        if self._slide_runs is not None:
            self._slide_runs.retarget(p)
        # friction only takes energy: an orbit stays within the frictionless harmonic amplitude (a
        # generous multiple of it bounds Newton's iterates). Undamped at resonance X is infinite, or
        # huge where omega hits w0 up to rounding: the amplification k X / P0 is capped at
        # MAX_AMPLIFICATION (else Newton "converges" on the unbounded growth, relative to a huge state)
        den = math.hypot(p.k - p.m * p.omega ** 2, p.c * p.omega)
        X = abs(p.P0) / den if den > 0 else math.inf
        # the static deflections of the excitation and of friction too (an orbit may stick at an offset
        # of that size: far beyond X where the inertia sets x_s, lambda >> 1)
        static = (abs(p.P0) + p.breakaway) / p.k if p.k > 0 else 0.0
        self.bound = BOUND * (1.0 + min(X / xs, MAX_AMPLIFICATION) + static / xs)

    def slides_throughout(self, z: np.ndarray, t_s: float) -> bool:
        """Whether the run of K periods from z at t_s never sticks (the FMU's stuck time over it is
        0 and it ends sliding): one run with the observables instead of a sampled cycle."""
        x, v = float(z[0]), float(z[1])
        if not (math.isfinite(x) and math.isfinite(v)):
            return False
        runs = self._slide_runs
        if runs is None:
            runs = self._slide_runs = self.map.fmu.restarts(self.p, Settings(scheme="exact", observe=True),
                                                            ("stick_fraction",), ("mode",))
        runs.run(x, v, t_s, t_s + self.KT)
        return runs.real[0] == 0.0 and runs.int[0] != 0

    def _residual(self, z0: float, z1: float, p0: float, p1: float) -> float:
        # plain floats, the max by comparisons (as max(): the first argument unless a later is larger)
        xs, xw = self.map.xs, self.map.xs * self.map.w
        r, e = abs(p0 - z0) / xs, abs(p1 - z1) / xw
        if e > r:
            r = e
        s, e = abs(z0) / xs, abs(z1) / xw
        if not s > 1.0:
            s = 1.0
        if e > s:
            s = e
        return r / s

    # ---- the oscillator's ShootingMap (dryfriction.analysis.shooting): plain floats, a 2 x 2 system ----
    #: (a trial state the FMU refuses is an error of the point: the sweep reports it)
    refused: tuple[type[BaseException], ...] = ()

    def evaluate(self, z: Sequence[float], t_s: float, final: bool,
                 jacobian: bool = True) -> tuple[tuple[float, float], tuple[float, float, float, float], int]:
        """(P^K(z), its Jacobian's entries row by row, the mode at the end), plain floats (the
        Jacobian always: two more columns cost next to nothing)."""
        px, pv, a, b, c, d, md = self.map.eval(z[0], z[1], t_s, final)
        return (px, pv), (a, b, c, d), md

    @staticmethod
    def expensive_jacobian() -> bool:
        """No: the oscillator's Jacobian comes with the run."""
        return False

    def residual(self, z: Sequence[float], Pz: Sequence[float]) -> float:
        """The scaled residual of z (module doc)."""
        return self._residual(float(z[0]), float(z[1]), float(Pz[0]), float(Pz[1]))

    def step(self, z: Sequence[float], Pz: Sequence[float],
             J: Sequence[float]) -> tuple[tuple[float, float] | None, str]:
        """The Newton step: (J - I) dz = -(P(z) - z) by Cramer's rule."""
        a, b, c, d = J[0] - 1.0, J[1], J[2], J[3] - 1.0
        if not (math.isfinite(a) and math.isfinite(b) and math.isfinite(c) and math.isfinite(d)):
            return None, "the FMU's Jacobian is not available (NaN: e.g. a tangential breakaway)"
        det = a * d - b * c
        if det == 0.0 or not math.isfinite(det):
            return None, "J - I is singular (a multiplier 1: a fold or a family of orbits)"
        r0, r1 = z[0] - Pz[0], z[1] - Pz[1]
        return ((d * r0 - b * r1) / det, (a * r1 - c * r0) / det), ""

    @staticmethod
    def move(z: Sequence[float], dz: Sequence[float], lam: float) -> tuple[float, float]:
        """z + lam dz."""
        return z[0] + lam * dz[0], z[1] + lam * dz[1]

    def step_size(self, z: Sequence[float], dz: Sequence[float]) -> float:
        """The scaled step, relative to the scaled state (at least 1)."""
        xs, xw = self.map.xs, self.map.xs * self.map.w
        return max(abs(dz[0]) / xs, abs(dz[1]) / xw) / max(1.0, abs(z[0]) / xs, abs(z[1]) / xw)

    def outside(self, z: Sequence[float], first: bool) -> str:
        """Why z is beyond the bound on Newton's iterates ("" if it is not)."""
        xs, xw = self.map.xs, self.map.xs * self.map.w
        if first:
            if max(abs(z[0]) / xs, abs(z[1]) / xw) > self.bound:
                return f"the guess is beyond the bound of {BOUND:g} times the frictionless amplitude"
        elif abs(z[0]) / xs > self.bound or abs(z[1]) / xw > self.bound:
            return f"Newton diverged: the state left the bound of {BOUND:g} times the frictionless amplitude"
        return ""

    def solve(self, x: float, v: float, t_s: float) -> Newton[tuple[float, float], tuple[float, float, float, float], int]:
        """Newton shooting from the state (x, v) at the section time t_s (:func:`~dryfriction.analysis.shooting.newton`
        with POLISH steps; its ``aux`` the mode at the end)."""
        return newton(self, (x, v), t_s, self.tol, self.max_iter, polish=POLISH)

    def newton(self, z: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray, float, int, str, int]:
        """(z, J, residual, iterations, reason, mode at the end) of :meth:`solve` as arrays."""
        n = self.solve(float(z[0]), float(z[1]), t_s)
        return np.array(n.z), np.array(n.J).reshape(2, 2), n.residual, n.iterations, n.reason, n.aux


def _check(p: Oscillator, K: int) -> None:
    if not (isinstance(K, int) and K >= 1):
        raise ValueError(f"period must be an integer >= 1 (excitation periods), not {K!r}")
    if not (p.omega > 0 and p.P0 != 0):
        raise NotImplementedError(
            "find_orbits needs an excitation (omega > 0, P0 != 0): the self-excited orbits of the autonomous "
            "system (no excitation, on a moving belt, the period an unknown) are dryfriction.analysis.self_excited's "
            "find_orbit (or: dryfriction belt)")


def _auto_guesses(p: Oscillator, spread: Sequence[tuple[float, float]]) -> list[np.ndarray]:
    xs, w = scales(p)
    # the frictionless harmonic amplitude sets the spread of the initial conditions
    den = math.hypot(p.k - p.m * p.omega ** 2, p.c * p.omega)   # 0: undamped at resonance
    X = abs(p.P0) / den if den > 0 else math.inf
    X = X if math.isfinite(X) and X > 0 else xs
    return [np.array([a * X, b * X * w]) for a, b in spread]


DEFAULT_SPREAD = ((0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.3, -0.7), (2.0, 0.0))


def find_orbits(oscillator: Oscillator, period: int = 1,
                guesses: Iterable[Sequence[float]] | None = None, *,
                fmu: OscillatorFMU2 | None = None,
                transients: int = 60,
                spread: Sequence[tuple[float, float]] = DEFAULT_SPREAD,
                symmetry: Any = True,
                tol: float = 1e-12,
                max_iter: int = 40,
                keep_failed: bool = False,
                samples: int = SAMPLES, **system_options: Any) -> list[Orbit]:
    """Every distinct periodic orbit of ``period`` (K) excitation periods found by Newton shooting on
    the exact stroboscopic map (module doc), from:

    - the end states of transients of ``transients`` K-periods from the initial conditions ``spread``
      (x0, v0 in units of the frictionless harmonic amplitude X and X w) at t = 0 (the attractors),
    - ``guesses``: states (x0, v0) at t = 0 mod K T, in m and m/s,
    - with ``symmetry``: the image of each orbit found, (x, v)(t) -> -(x, v)(t + T/2) (the system is
      symmetric under the excitation's half-period shift).

    Orbits are distinct when their cycles differ (a cycle shifted by whole periods is the same orbit);
    a K-orbit whose minimal period is a divisor j of K is reported once, with ``period = j`` and the
    multipliers of P^j. Orbits that did not converge are dropped unless ``keep_failed`` (then listed
    with ``converged = False`` and the reason). Stable orbits first, then by amplitude.

    ``samples``: samples per period of the cycle runs (the section choice and the sampled ``events``;
    fewer is faster, the amplitude, offset and stick share are the FMU's observables whatever it is).

    ``fmu``: an :class:`OscillatorFMU2` to use (else one is loaded and closed). Every
    DryFrictionWarning the FMU emits reaches the caller.

    Returns
    -------
    list of Orbit
        The orbits, stable ones first, each with its state at t = 0 (m, m/s), multipliers, amplitude,
        offset (m) and stick share.

    Raises
    ------
    ValueError
        A ``period`` that is not an integer >= 1.
    dryfriction.FMUCallError
        The FMU refuses the oscillator's values (its sentence names the variable).

    Examples
    --------
    >>> from dryfriction import Oscillator, find_orbits
    >>> p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.4)
    >>> orbits = find_orbits(p)
    >>> [(o.period, o.stable) for o in orbits]     # a mirror pair of stable period-1 orbits
    [(1, True), (1, True)]

    A structure (:class:`~dryfriction.system.structure.System`) in place of the oscillator: its orbits on the located
    scheme's map (:func:`dryfriction.analysis.system_orbits.find_system_orbits`, which takes the
    keywords ``guesses``, ``transients``, ``tol``, ``max_iter``, ``keep_failed`` and its own;
    ``symmetry`` there a :class:`~dryfriction.system.symmetry.CyclicSymmetry`, not the mirror switch).
    """
    from ..system.structure import System

    if isinstance(oscillator, System):
        from .system_orbits import find_system_orbits

        extra = {"transients": transients if transients != 60 else 40, "tol": tol if tol != 1e-12 else 1e-8,
                 "max_iter": max_iter if max_iter != 40 else 30, "keep_failed": keep_failed, **system_options}
        if fmu is not None:  # (a SystemFMU3: find_system_orbits checks it)
            extra["fmu"] = fmu
        if not isinstance(symmetry, bool):  # (a structure's cyclic symmetry; the mirror switch is the oscillator's)
            extra["symmetry"] = symmetry
        return find_system_orbits(oscillator, period, guesses, **extra)  # type: ignore[return-value]
    if system_options:
        raise TypeError(f"find_orbits: {', '.join(system_options)} apply to a dryfriction.System only")
    if not isinstance(symmetry, bool):
        raise TypeError(f"find_orbits: an oscillator's symmetry is True or False (its mirror orbits), not "
                        f"{type(symmetry).__name__} (a CyclicSymmetry is a structure's)")
    p = oscillator
    _check(p, period)
    own = fmu is None
    f = OscillatorFMU2() if own else fmu
    try:
        return _find(f, p, period, guesses, transients, spread, symmetry, tol, max_iter, keep_failed, samples)
    finally:
        if own:
            f.close()


def _find(f: OscillatorFMU2, p: Oscillator, K: int, guesses: Iterable[Sequence[float]] | None,
          transients: int, spread: Sequence[tuple[float, float]], symmetry: bool, tol: float, max_iter: int,
          keep_failed: bool, samples: int = SAMPLES) -> list[Orbit]:
    sol = _Solver(f, p, K, tol, max_iter, samples)
    KT = K * p.period
    # (state, time) guesses: the attractors at t = transients K T, the given ones at t = 0
    todo: list[tuple[np.ndarray, float, bool]] = []
    starts = _auto_guesses(p, spread)
    if transients > 0 and starts:
        runs = f.restarts(p, Settings(scheme="exact"))     # reads x, v at the end
        ends: list[np.ndarray] = []
        for z in starts:
            runs.run(float(z[0]), float(z[1]), 0.0, transients * KT)
            end = np.array(runs.real)
            # transients that ended in the same state (a stick phase forgets where it came from) give
            # the same orbit: solved once
            se = sol.map.scaled(end)
            if any(np.max(np.abs(se - e)) <= ALIKE * max(1.0, float(np.max(np.abs(e)))) for e in ends):
                continue
            ends.append(se)
            todo.append((end, 0.0, False))
    else:
        todo.extend((z, 0.0, False) for z in starts)
    for g in guesses or ():
        todo.append((np.asarray(g, dtype=float), 0.0, True))
    rest = rest_interval(p)
    # the block at rest: one orbit for the whole interval of rest positions (members reached by the
    # guesses are not listed again)
    found: list[Orbit] = [] if rest is None else [_rest_orbit(f, sol, rest, max(transients, REST_PERIODS) * K)]
    cycles: list[np.ndarray] = []        # scaled states of each found orbit at the K marks
    failed: list[Orbit] = []

    def seen(z: np.ndarray, t_s: float) -> bool:
        # a converged state of an orbit found already: its states at the K marks from one run
        # (no sampled cycle; the comparison's tolerance SAME is far above the runs' rounding)
        if not cycles:
            return False
        T = p.period
        marks = T * np.arange(math.floor(t_s / T) + 1, math.floor((t_s + KT) / T + 1e-12) + 1)
        grid = np.concatenate([[t_s], marks[marks > t_s]])
        run = f.trajectory(sol.map.at(z), grid, Settings(scheme="exact"), ("x", "v"))
        sm = np.array([sol.map.scaled(np.array([x, v])) for x, v in zip(run["x"][1:], run["v"][1:])])
        return any(_same(sm, c) for c in cycles)

    while todo:
        z, t_g, given = todo.pop(0)
        orbit, marks, halfway = _solve(sol, z, t_g, seen)
        if orbit is None:
            continue
        if not orbit.converged:
            if keep_failed and given:
                failed.append(orbit)
            continue
        if orbit.stuck and rest is not None:
            continue                     # a member of the rest interval, reported once
        sm = np.array([sol.map.scaled(m) for m in marks])
        if any(_same(sm, c) for c in cycles):
            continue
        # minimal period: the state comes back after j < K periods (j divides K)
        j = next((j for j in range(1, K) if K % j == 0 and
                  np.max(np.abs(sm[j - 1] - sm[-1])) <= SAME * max(1.0, np.max(np.abs(sm[-1])))), K)
        cycles.append(sm)
        if j < K:
            sub = _Solver(f, p, j, tol, max_iter, samples)
            o2, _, _ = _solve(sub, np.array([orbit.x0, orbit.v0]), 0.0)
            if o2 is not None and o2.converged:
                found.append(o2)
            continue
        found.append(orbit)
        if symmetry and halfway is not None:
            todo.insert(0, (-halfway[0], halfway[1], False))
    found.sort(key=lambda o: (not o.stable, not o.neutral, -o.amplitude))
    return found + failed


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the cycles with the scaled states a, b at the K period marks are one orbit (b is a
    at some shift of whole periods)."""
    if a.shape != b.shape:
        return False
    tol = SAME * max(1.0, float(np.max(np.abs(a))))
    return any(np.max(np.abs(np.roll(a, s, axis=0) - b)) <= tol for s in range(a.shape[0]))


def _solve(sol: _Solver, z: np.ndarray, t_g: float,
           seen: Callable[[np.ndarray, float], bool] | None = None) -> tuple[Orbit | None, list[np.ndarray],
                                                                             tuple[np.ndarray, float] | None]:
    """Solve from the guess z at time t_g: (the orbit, its states at the K period marks, the state and
    time half a period after the section, for the symmetry image); (None, [], None) when ``seen``
    tells that the converged state (z, t_s) is of an orbit known already (no cycle run for it)."""
    K, KT = sol.K, sol.KT
    m = sol.map
    t_s = t_g
    reason = ""
    for attempt in range(4):
        in_stick = False        # the section in a stick phase (the slides are shorter than the samples)
        if attempt == 0 and sol.slides_throughout(z, t_s):
            t_new: float | None = math.nan      # any section will do: no sampled cycle needed
        else:
            cyc = m.cycle(z, t_s)
            t_new = _slide_section(cyc["t"], cyc["mode"], 0.0, KT)
            if (t_new is None or attempt >= 2) and cyc["stick_fraction"] < 1.0:
                # it slides (the FMU's stuck time says so) between samples, or the orbit came out stuck
                # at the slide's section twice: solve in the longest stick phase instead, where the
                # map is the scalar one of the stuck states (x, 0) (its Jacobian's v column is 0)
                t_stick = _slide_section(cyc["t"], cyc["mode"], 0.0, KT, stuck=True)
                if t_stick is not None:          # NaN: every sample stuck, the guess's section will do
                    t_new, in_stick = (t_s % KT if math.isnan(t_stick) else t_stick), True
        if t_new is None:           # never slides over the cycle: a stuck orbit (or stuck for now)
            Pz, J, md = m(z, t_s)
            r = sol.residual(z, Pz)
            if r <= sol.tol:
                return _stuck_orbit(sol, z, t_s, J, r), [z] * K, None
            reason = f"the guess sticks over a whole cycle but is not periodic (residual {r:.3g})"
            z, t_s = Pz, t_s      # go on from where it is
            continue
        if not math.isnan(t_new) and abs(t_new - (t_s % KT)) > 1e-12 * KT:
            # move the guess to the new section along its own run
            i = int(np.argmin(np.abs(((cyc["t"] - t_s) % KT) - ((t_new - t_s) % KT))))
            z, t_s = np.array([cyc["x"][i], cyc["v"][i]]), float(cyc["t"][i] % KT)
        elif math.isnan(t_new):
            t_s = t_s % KT
        if in_stick:
            z = np.array([z[0], 0.0])            # stuck there (the sample's v is 0 already)
        zc, J, r, it, reason, md = sol.newton(z, t_s)
        if reason:
            return _failed(sol, zc, t_s, J, r, it, reason), [], None
        if md == 0 and not (in_stick and zc[1] == 0.0):    # a stick phase came onto the section: choose it again
            z = zc
            reason = "the converged orbit is stuck at every section tried"
            continue
        if seen is not None and seen(zc, t_s):
            return None, [], None
        return _finish(sol, zc, t_s, J, r, it)
    return _failed(sol, z, t_s, np.full((2, 2), np.nan), math.nan, 0, reason), [], None


#: a converged state whose x moves over its cycle by more than this share of its peak-to-peak motion is
#: not an orbit but a creep (within tol only because the motion is tiny against the static deflection:
#: e.g. a block creeping onto the edge of the interval of rest positions, a breakaway per period)
CREEP = 1e-3


def _creeps(drift: float, x_max: float, x_min: float) -> bool:
    return drift > CREEP * (x_max - x_min)


def _creep_reason(drift: float, x_max: float, x_min: float) -> str:
    return (f"not periodic: x moves by {drift:.3g} m per cycle, more than {CREEP:g} of its peak-to-peak "
            f"{x_max - x_min:.3g} m (a creep, e.g. onto the edge of the interval of rest positions)")


def _stability(mu: Iterable[complex], p: Oscillator) -> tuple[bool, bool]:
    """(neutral, stable) of the multipliers mu: neutral with a multiplier 1 (within
    :func:`neutral_margin`) and the other inside the unit circle, one of a family of orbits shifted
    in x (without a spring; or with one too weak against the inertia for the FMU to tell the family's
    members apart); stable when not neutral and every |mu| < 1 - STABILITY_MARGIN."""
    one, inside = classify(mu, neutral_margin(p))
    neutral = one and inside
    return neutral, inside and not one


#: the exact scheme's relative rounding of positions, in its unit the static deflection |P0| / k
ROUNDING = 64 * 2.0 ** -52


def neutral_margin(p: Oscillator) -> float:
    """How close to 1 a multiplier must be to count as 1: STABILITY_MARGIN, or where the inertia
    dwarfs the spring (lambda >> 1) the FMU's resolution of the motion, ROUNDING lambda^2 (it
    computes positions in static deflections, |P0| / k, the motion is |P0| / (m omega^2): at lambda
    4.4e4 its members drift by 4e-8 of their offset per period, below the rounding of the map)."""
    ratio = p.m * p.omega ** 2 / p.k if p.k > 0 else 0.0
    return max(STABILITY_MARGIN, ROUNDING * ratio)


def _nondim(p: Oscillator, x: float, v: float) -> tuple[float, float]:
    if p.k > 0:
        return p.k * x / p.P0, p.k * v / (p.P0 * p.w0)
    return math.nan, math.nan


def _finish(sol: _Solver, z: np.ndarray, t_s: float, J: np.ndarray, r: float,
            it: int) -> tuple[Orbit, list[np.ndarray], tuple[np.ndarray, float] | None]:
    p, K, KT, T = sol.p, sol.K, sol.KT, sol.p.period
    cyc = sol.map.cycle(z, t_s)
    if cyc["stick_fraction"] >= 1.0:             # Newton stepped into the interval of rest positions
        return _stuck_orbit(sol, z, t_s, J, r), [z] * K, None
    drift = abs(float(cyc["x"][-1]) - float(z[0]))
    if _creeps(drift, cyc["x_max"], cyc["x_min"]):
        return _failed(sol, z, t_s, J, r, it, _creep_reason(drift, cyc["x_max"], cyc["x_min"])), [], None
    t = cyc["t"]
    marks = [np.array([cyc["x"][i], cyc["v"][i]]) for i in (int(np.argmin(np.abs(t - tm))) for tm in cyc["marks"])]
    # the state at t = 0 mod K T: at the multiple of K T in (t_s, t_s + K T]
    i0 = int(np.argmin(np.abs(t - KT * math.floor((t_s + KT) / KT + 1e-12))))
    x0, v0 = float(cyc["x"][i0]), float(cyc["v"][i0])
    events = _events(cyc["mode"])
    events["transitions"] = int(cyc["transitions"])
    # with a stick phase on the cycle J has rank one (the FMU sets its v row to 0 there)
    mu = multipliers(J, float(cyc["stick_fraction"]) > 0.0 or events["stops"] > 0)
    z0, zd0 = _nondim(p, x0, v0)
    xmax, xmin = float(cyc["x_max"]), float(cyc["x_min"])
    neutral, stable = _stability(mu, p)
    orbit = Orbit(period=K, x0=x0, v0=v0, z0=z0, zdot0=zd0, multipliers=mu, neutral=neutral, stable=stable, residual=r,
                  amplitude=(xmax - xmin) / 2.0, offset=(xmax + xmin) / 2.0,
                  stick_fraction=float(cyc["stick_fraction"]), events=events, converged=True, section=t_s,
                  jacobian=J, section_state=np.array(z, dtype=float), iterations=it)
    ih = int(np.argmin(np.abs(t - (t_s + T / 2.0))))
    halfway = (np.array([cyc["x"][ih], cyc["v"][ih]]), float(t[ih] - T / 2.0))
    # the image starts at t_s (time t[ih] - T/2 = t_s up to the grid): -(x, v)(t_s + T/2)
    return orbit, marks, (halfway[0], t_s)


def _stuck_orbit(sol: _Solver, z: np.ndarray, t_s: float, J: np.ndarray, r: float) -> Orbit:
    p = sol.p
    mu = multipliers(J, True)
    x0 = float(z[0])
    z0, zd0 = _nondim(p, x0, 0.0)
    return Orbit(period=1, x0=x0, v0=0.0, z0=z0, zdot0=zd0, multipliers=mu, stable=False, residual=r,
                 amplitude=0.0, offset=x0, stick_fraction=1.0,
                 events={"stops": 0, "breakaways": 0, "reversals": 0, "transitions": 0}, converged=True,
                 section=t_s, jacobian=J, section_state=np.array([x0, 0.0]), stuck=True, neutral=True,
                 rest_interval=rest_interval(p))


#: the transient from the oscillator's initial state that finds where the block comes to rest runs at
#: least this many excitation periods
REST_PERIODS = 60


def _rest_orbit(f: OscillatorFMU2, sol: _Solver, rest: tuple[float, float], periods: int) -> Orbit:
    """The block at rest (``rest``: :func:`rest_interval`): the rest position the transient from the
    oscillator's initial state (x0, v0) reaches (``periods`` excitation periods of the FMU, as the
    transient method runs; it is at rest for good once stuck inside the interval at a period mark),
    else the point of the interval nearest to where that transient ended (it creeps onto the
    interval's edge, a breakaway per period, or moves on another orbit), 1e-12 of the half-width
    inside the edge (on the edge the force touches the limit once per period, which rounding may
    read as a breakaway); its map over one period evaluated by the FMU (residual, Jacobian
    [[1, 0], [0, 0]]: multipliers exactly 1, along the interval, and 0). Neutrally stable:
    ``neutral``, not ``stable``."""
    p = sol.p
    lo, hi = rest
    runs = f.restarts(p, Settings(scheme="exact"), ("x", "v"), ("mode",))
    runs.run(p.x0, p.v0, 0.0, periods * p.period)
    x, v = runs.real
    if not (runs.int[0] == 0 and v == 0.0 and lo <= x <= hi):
        x = min(max(x, lo * (1.0 - 1e-12)), hi * (1.0 - 1e-12))    # lo = -hi (or -inf, inf without a spring)
    z = np.array([x, 0.0])
    Pz, J, _ = _Map(f, p, 1)(z, 0.0)
    orbit = _stuck_orbit(sol, z, 0.0, J, sol.residual(z, Pz))
    orbit.rest_interval = rest
    return orbit


def _failed(sol: _Solver, z: np.ndarray, t_s: float, J: np.ndarray, r: float, it: int, reason: str) -> Orbit:
    p = sol.p
    z0, zd0 = _nondim(p, float(z[0]), float(z[1]))
    mu = multipliers(J)
    return Orbit(period=sol.K, x0=float(z[0]), v0=float(z[1]), z0=z0, zdot0=zd0, multipliers=mu, stable=False,
                 residual=r, amplitude=math.nan, offset=math.nan, stick_fraction=math.nan, events={},
                 converged=False, reason=reason, section=t_s, jacobian=J, iterations=it)


# ---- following an orbit to a nearby parameter (the frequency response's warm start) ---------------

class _ObservingMap(_Map):
    """P^K with the FMU's observables of the same run and the state at the period mark inside it: the
    last evaluation is the orbit's cycle once Newton has converged (no separate cycle run). One per
    FMU instance, moved to each new oscillator by :meth:`retarget` (no new Settings per point)."""

    names = ("x", "v") + JACOBIAN + ("x_max", "x_min", "stick_fraction")
    ints = ("transitions",)

    def __init__(self, fmu: OscillatorFMU2, p: Oscillator, K: int) -> None:
        super().__init__(fmu, p, K)
        self.settings = Settings(scheme="exact", observe=True, extra={"sensitivity": True})
        self.last: dict[str, float] = {}

    def _mid(self, t_s: float, t_end: float, KT: float) -> float | None:
        mark = KT * math.floor(t_end / KT + 1e-12)          # the multiple of K T in (t_s, t_s + K T]
        return mark if mark < t_end - 1e-12 * KT else None

    @property
    def end(self) -> tuple[float, float]:
        """(x, v) at the end of the last evaluation."""
        assert self._runs is not None
        return self._runs.real[0], self._runs.real[1]

    def observed(self) -> dict[str, float]:
        """The last evaluation's observables and its state x0, v0 at the period mark (the last
        evaluation a ``final`` one: it stopped at the mark)."""
        runs = self._runs
        assert runs is not None and self.final
        r = runs.real
        mid = runs.mid if runs.mid is not None else (r[0], r[1])
        return {"x_max": r[6], "x_min": r[7], "stick_fraction": r[8], "transitions": runs.int[1],
                "x0": mid[0], "v0": mid[1]}


class OrbitFollower:
    """:func:`follow_orbit` through one FMU instance, point after point (a sweep): one map, one
    solver and one set of value arrays for all of them (moved to each new oscillator)."""

    def __init__(self, fmu: OscillatorFMU2, tol: float = 1e-12, max_iter: int = 40) -> None:
        self.fmu, self.tol, self.max_iter = fmu, tol, max_iter
        self.map: _ObservingMap | None = None
        self._sol: _Solver | None = None

    def __call__(self, oscillator: Oscillator, state: Sequence[float], section: float) -> Orbit | None:
        p = oscillator
        sol = self._sol
        if sol is None or sol.p is not p:       # checked once per oscillator (a sweep follows several orbits of one)
            _check(p, 1)
        if sol is None:
            self.map = _ObservingMap(self.fmu, p, 1)
            sol = self._sol = _Solver(self.fmu, p, 1, self.tol, self.max_iter, map_=self.map)
        elif sol.p is not p:
            sol.retarget(p)
        m = sol.map
        t_s = float(section) % p.period
        n = sol.solve(float(state[0]), float(state[1]), t_s)
        (x, v), J = n.z, n.J
        if n.reason or (n.aux == 0 and not (float(state[1]) == 0.0 and v == 0.0)):   # stuck at a slide's section
            return None
        if not m.final:             # the guess was periodic already: run it again with the stop at the mark
            m.eval(x, v, t_s)
        y = m.last = m.observed()
        stick = y["stick_fraction"]
        if stick >= 1.0 or _creeps(abs(m.end[0] - x), y["x_max"], y["x_min"]):
            return None                 # at rest for good, or creeping onto a rest position: find_orbits
        a, b, c, d = J
        jac = np.array(((a, b), (c, d)))
        # as multipliers(jac, stick > 0, closed=True), on plain floats (classified as Python complex numbers:
        # the same arithmetic, without numpy's scalars)
        if stick > 0.0:                                   # rank one: exactly trace(J) and 0
            mus: list[complex] | np.ndarray = [complex(a + d), 0j]
        elif math.isfinite(a) and math.isfinite(b) and math.isfinite(c) and math.isfinite(d):
            mus = _roots2(a, b, c, d)
        else:
            mus = multipliers(jac)
        mu = np.array(mus)
        neutral, stable = _stability(mus, p)
        x0, v0 = y["x0"], y["v0"]
        z0, zd0 = _nondim(p, x0, v0)
        xmax, xmin = y["x_max"], y["x_min"]
        return Orbit(period=1, x0=x0, v0=v0, z0=z0, zdot0=zd0, multipliers=mu, neutral=neutral, stable=stable,
                     residual=n.residual, amplitude=(xmax - xmin) / 2.0, offset=(xmax + xmin) / 2.0,
                     stick_fraction=stick, events={"transitions": y["transitions"]}, converged=True, section=t_s,
                     jacobian=jac, section_state=np.array([x, v]), iterations=n.iterations)


def follow_orbit(oscillator: Oscillator, state: Sequence[float], section: float, *, fmu: OscillatorFMU2,
                 tol: float = 1e-12, max_iter: int = 40) -> Orbit | None:
    """The period-1 orbit of ``oscillator`` near the state (x, v) at the section time ``section`` (a
    nearby orbit's section state at the same phase of the excitation, e.g. the previous frequency's
    of a sweep): Newton shooting as :func:`find_orbits`, without its cycle runs (the converged
    evaluation's own observables give the amplitude, offset and stick share, its stop at t = T the
    state x0, v0). None when Newton does not converge or the converged orbit is stuck at the section
    (then :func:`find_orbits` chooses a section), unless the section is a stick phase already (a
    stuck state v = 0 given, as find_orbits' section where the slides are shorter than its samples:
    Newton then solves for the stuck position, the Jacobian's v column being 0), or when it is at rest
    for good or creeps (then None too). ``events`` holds only the FMU's count of mode changes
    (``transitions``; stops, breakaways and reversals need find_orbits' sampled cycle). The
    multipliers: with a stick phase exactly trace(J) and 0, else the roots of the characteristic
    polynomial of J. For a sweep, :class:`OrbitFollower` does the same with less set-up per point."""
    return OrbitFollower(fmu, tol, max_iter)(oscillator, state, section)
