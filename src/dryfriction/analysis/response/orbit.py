"""The orbit method: every periodic orbit at each frequency, the orbits of one frequency followed
to the next (the package's doc, dryfriction.analysis.response)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...drivers.oscillator import FMUError, OscillatorFMU2
from ...params import Oscillator
from ..orbits import ALIKE, DEFAULT_SPREAD, SAME, OrbitFollower, _auto_guesses, find_orbits, rest_interval, scales
from ..shooting import STABILITY_MARGIN, lagrange_weights, sweep
from .transient import default_settings

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
        x = v = ph = 0.0
        for w, (px, pv, pp) in zip(lagrange_weights([b.f for b in pts], f), [b.point for b in pts]):
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
    """The orbits at the frequency f: each branch followed (:func:`_follow`), else searched for
    (:func:`_search`)."""
    followed = _follow(inst, p, f, branches, cold, opts) if branches else None
    return followed if followed is not None else _search(inst, p, f, branches, opts)


def _follow(inst: OscillatorFMU2, p: Oscillator, f: float, branches: list[_Branch], cold: bool,
            opts: Mapping[str, Any]) -> list[_Branch] | None:
    """The orbits at the frequency f from the previous frequency's ``branches``: each followed
    (Newton from its predicted section state, :class:`dryfriction.analysis.orbits.OrbitFollower`), and
    with ``cold`` transients from the spread of initial conditions followed too
    (:func:`_transient_check`); None where a branch is lost, none is stable or K > 1."""
    K, T = opts["period"], p.period
    follow = opts["follower"]
    if not (K == 1 and branches):
        return None
    followed: list[_Branch] = []
    for b in branches:
        o = None
        if not b.orbit.stuck and b.orbit.period == 1:
            z, ph = b.guess(f)
            o = follow(p, z, ph * T)
            if o is None and b.history:
                # the prediction overshot (past a sharp resonance peak): from the orbit itself
                o = follow(p, (b.point[0], b.point[1]), b.point[2] * T)
        if o is None:
            return None
        followed.append(_Branch(o, f, T, b))
    _mirrors(p, f, followed, follow)
    if not any(_attracting(b.orbit, p) for b in followed):
        # the branch lost its stability (a fold, a symmetry-breaking pitchfork): the attractors from
        # the cold search's transients, followed (find_orbits where one cannot be)
        followed = _transient_check(inst, p, f, followed, opts)
        if not any(_attracting(b.orbit, p) for b in followed):
            return None
        followed.sort(key=lambda b: (not b.orbit.stable, not b.orbit.neutral, -b.orbit.amplitude))   # as find_orbits
    elif cold:
        followed = _transient_check(inst, p, f, followed, opts)
    if len(followed) == 1:
        return followed
    keep = {id(o) for o in _distinct([b.orbit for b in followed], p)}
    return [b for b in followed if id(b.orbit) in keep]


def _search(inst: OscillatorFMU2, p: Oscillator, f: float, branches: list[_Branch],
            opts: Mapping[str, Any]) -> list[_Branch]:
    """The orbits at the frequency f by find_orbits: from the previous orbits (``branches``), and
    without them or when none is stable from transients too; with no stable orbit of K periods, of
    2 K too."""
    K, T = opts["period"], p.period
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


#: a transient's end state within this scaled distance of the orbit Newton followed it to (from t = 0)
#: had settled on it: find_orbits' Newton from that end (at its own section) reaches the same orbit
SETTLED = 1e-6


def _settled_search(inst: OscillatorFMU2, p: Oscillator, f: float, opts: Mapping[str, Any]) -> list[_Branch] | None:
    """The orbits of a cold search without find_orbits' sampled cycles, where that gives what
    find_orbits gives: its transients (the same spread, the same length) each followed by Newton
    from t = 0 (:func:`_transient_check`) and each orbit's mirror image. None (find_orbits then) with
    K > 1, a block that can rest, a transient that cannot be followed or whose end is not within
    SETTLED of its orbit (Newton from an unsettled end at find_orbits' section may reach another
    orbit), or no steady state among them."""
    if opts["period"] != 1 or opts["transients"] <= 0 or rest_interval(p) is not None:
        return None
    follow, T = opts["follower"], p.period
    xs, w = scales(p)
    runs = opts["transient_runs"]
    runs.retarget(p)
    out: list[_Branch] = []

    def known(x: float, v: float) -> bool:
        a = (x / xs, v / (xs * w))
        tol = SAME * max(1.0, abs(a[0]), abs(a[1]))
        return any(abs(a[0] - b.orbit.x0 / xs) <= tol and abs(a[1] - b.orbit.v0 / (xs * w)) <= tol for b in out)

    ends: list[tuple[float, float]] = []
    for z in _auto_guesses(p, DEFAULT_SPREAD):
        runs.run(float(z[0]), float(z[1]), 0.0, opts["transients"] * T)
        x, v = runs.real[0], runs.real[1]
        a0, a1 = x / xs, v / (xs * w)
        # at an earlier transient's end (a stick phase forgets where it came from): followed already
        if any(max(abs(a0 - q0), abs(a1 - q1)) <= ALIKE * max(1.0, abs(q0), abs(q1)) for q0, q1 in ends):
            continue
        ends.append((a0, a1))
        o = follow(p, (x, v), 0.0)
        if o is None:
            return None
        b0, b1 = o.x0 / xs, o.v0 / (xs * w)
        if not max(abs(a0 - b0), abs(a1 - b1)) <= SETTLED * max(1.0, abs(b0), abs(b1)):
            return None
        if known(o.x0, o.v0):
            continue
        out.append(_Branch(o, f, T))
        image = follow(p, -o.section_state, o.section + 0.5 * T)
        if image is None:
            return None
        if not known(image.x0, image.v0):
            out.append(_Branch(image, f, T))
    if not any(_attracting(b.orbit, p) for b in out):
        return None
    out.sort(key=lambda b: (not b.orbit.stable, not b.orbit.neutral, -b.orbit.amplitude))   # as find_orbits
    keep = {id(o) for o in _distinct([b.orbit for b in out], p)}
    return [b for b in out if id(b.orbit) in keep]


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
    follow, T = opts["follower"], p.period
    xs, w = scales(p)
    out = list(found)

    def known(x: float, v: float) -> bool:
        a = (x / xs, v / (xs * w))
        tol = SAME * max(1.0, abs(a[0]), abs(a[1]))
        return any(abs(a[0] - b.orbit.x0 / xs) <= tol and abs(a[1] - b.orbit.v0 / (xs * w)) <= tol for b in out)

    runs = opts["transient_runs"]         # one set of value arrays for the sweep's cold searches
    runs.retarget(p)
    ends: list[tuple[float, float]] = []
    for z in _auto_guesses(p, DEFAULT_SPREAD):
        runs.run(float(z[0]), float(z[1]), 0.0, opts["transients"] * T)
        y = {"x": runs.real[0], "v": runs.real[1]}
        # an end state at an orbit known already (a transient that ended on it), or at an earlier
        # transient's end (a stick phase forgets where it came from): nothing new
        e = (y["x"] / xs, y["v"] / (xs * w))
        if known(y["x"], y["v"]) or any(max(abs(e[0] - q[0]), abs(e[1] - q[1])) <= ALIKE * max(1.0, abs(q[0]), abs(q[1]))
                                        for q in ends):
            continue
        ends.append(e)
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


def _at_rest_once(branches: list[_Branch]) -> list[_Branch]:
    """The branches with the block at rest (the interval of rest positions) once."""
    out, stuck = [], False
    for b in branches:
        if b.orbit.stuck:
            if stuck:
                continue
            stuck = True
        out.append(b)
    return out


def _orbit_chunk(fmu: str | bytes, base: Mapping[str, float], f_hz: np.ndarray,
                 opts: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """One Dask task (or the in-process sweep): every orbit at the frequencies f_hz in turn, the
    orbits of one frequency followed to the next."""
    import time

    from ..chaos.batch import fmu_for

    inst = fmu_for(fmu)
    t0 = time.process_time()
    checked = Oscillator(**{**base, "omega": 2.0 * math.pi * float(f_hz[0])})
    # the transients of the cold searches read x, v at their end
    opts = {**opts, "follower": OrbitFollower(inst), "transient_runs": inst.restarts(checked, default_settings(checked))}
    freqs = np.asarray(f_hz, dtype=float).tolist()
    table: list[list[tuple[float, ...]]] = [[] for _ in freqs]
    reasons = [""] * len(freqs)

    def at(f: float) -> Oscillator:
        # the oscillator at f: the checked one with omega replaced (f is checked finite and > 0 by
        # frequency_response; a new check per point would cost a fifth of the sweep)
        p = object.__new__(Oscillator)
        p.__dict__.update(checked.__dict__, omega=2.0 * math.pi * f)
        return p

    def warm(i: int, p: Oscillator, branches: list[_Branch]) -> list[_Branch] | None:
        found = _follow(inst, p, freqs[i], branches, i % opts["cold_every"] == 0, opts) if branches else None
        return None if found is None else _at_rest_once(found)

    def cold(i: int, p: Oscillator, branches: list[_Branch] | None) -> list[_Branch]:
        quick = None if branches else _settled_search(inst, p, freqs[i], opts)
        return _at_rest_once(quick if quick is not None else _search(inst, p, freqs[i], branches or [], opts))

    def record(i: int, p: Oscillator, branches: list[_Branch]) -> None:
        rows = []
        for b in branches:
            o = b.orbit
            lo, hi = o.rest_interval if o.rest_interval is not None else (math.nan, math.nan)
            rows.append((float(o.period), float(o.stable), o.mu_max, o.amplitude, o.offset, o.stick_fraction,
                         o.x0, o.v0, o.residual, float(o.neutral), lo, hi, float(_attracting(o, p))))
        table[i] = rows

    def failed(i: int, e: BaseException) -> None:
        # this frequency is not computed: its row says why, the sweep goes on
        reasons[i] = e.message if isinstance(e, FMUError) else str(e)

    sweep((at(f) for f in freqs), warm, cold, record, failed, (FMUError,))
    width = max([len(r) for r in table] + [1])
    pad = (math.nan,) * (len(ORBIT_COLUMNS) + 1)
    out = np.array([rows + [pad] * (width - len(rows)) for rows in table], dtype=float).reshape(
        len(f_hz), width, len(ORBIT_COLUMNS) + 1)
    return {"orbits": out, "reason": np.array(reasons, dtype=object), "cpu": np.array([time.process_time() - t0])}

