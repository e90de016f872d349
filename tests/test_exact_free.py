"""The exact scheme at k = 0 (fmu_src/exact_free.c): a free mass on a rough support, through the FMU,
against the independent 40-digit reference of tests/free_reference.py (mpmath closed form, sampled
event search): c = 0 and c > 0, chi < 1, = 1, > 1 and 0, with and without F_ext, stick-slip and pure
slides, inputs held over communication steps, one long doStep against many, the event list, the
observables; and the located scheme at k = 0 (second order against the same reference)."""

from __future__ import annotations

import math
import re
import time

import numpy as np
import pytest

from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator
from free_reference import reference_for, solved_reference
from refcache import RefCache

EXACT = Settings(scheme="exact")
TOL = 1e-12            # max error over the motion's size, exact scheme
EVENT_RE = re.compile(r"t = ([-0-9.e+]+): (\w+ ?\w*) -> (\w+ ?\w*) at x = ([-0-9.e+]+)\.")
MODE = {"backward slip": -1, "stick": 0, "forward slip": 1}


def free(**kw: float) -> Oscillator:
    base = dict(m=1.0, k=0.0, c=0.0, P0=1.0, omega=1.0, phi=0.0, N=1.0, mu_s=0.4, chi=0.7, x0=0.0, v0=0.0)
    return Oscillator(**{**base, **kw})


# name: (oscillator, F_ext)
CASES = {
    "c=0 chi=0.7 stick-slip": (free(), 0.0),
    "c>0 chi=0.7 stick-slip": (free(c=0.3), 0.0),
    "c=0 chi=1": (free(chi=1.0), 0.0),
    "c>0 chi=1": (free(c=0.2, chi=1.0), 0.0),
    "c=0 chi=1.5 (breakaway at zero acceleration)": (free(chi=1.5, mu_s=0.3), 0.0),
    "c>0 chi=1.5": (free(c=0.5, chi=1.5, mu_s=0.3), 0.0),
    "c=0 chi=0 (no kinetic friction)": (free(chi=0.0), 0.0),
    "c>0 chi=0": (free(c=0.1, chi=0.0), 0.0),
    "c=0 F_ext drift with sticks": (free(), 0.3),
    "c>0 F_ext drift with sticks": (free(c=0.4, chi=0.5), -0.35),
    "c=0 F_ext pure slide": (free(), 2.0),
    "c>0 F_ext pure slide": (free(c=0.3), 2.0),
    "c>0 heavy damping": (free(c=20.0, P0=3.0), 0.0),
    "c=0 no friction": (free(N=0.0, v0=0.3), 0.0),
    "c>0 no friction": (free(c=0.2, N=0.0, v0=-0.5, x0=1.0), 0.4),
    "phase, start in motion, other units": (free(m=2.5, c=0.05, P0=-4.0, omega=3.0, phi=1.3, N=3.0, chi=0.6,
                                                  v0=-0.7, x0=0.2), 0.5),
    "slow excitation, tiny damping": (free(c=1e-9, omega=0.05, mu_s=0.2), 0.0),
}


@pytest.fixture(scope="module")
def fmu(fmu_path):
    with OscillatorFMU2(fmu_path, logging=True) as f:
        yield f


def _settings(F_ext: float, **kw) -> Settings:
    return Settings(scheme=kw.pop("scheme", "exact"), extra={"F_ext": F_ext} if F_ext else {}, **kw)


def _events(f: OscillatorFMU2, since: int) -> list[tuple[float, int, int]]:
    out = []
    for _, cat, msg in f.messages[since:]:
        m = EVENT_RE.match(msg) if cat == "logEvents" else None
        if m:
            out.append((float(m.group(1)), MODE[m.group(2)], MODE[m.group(3)]))
    return out


def _errors(tr: dict, ref, t: np.ndarray) -> tuple[float, float, np.ndarray]:
    xr, vr, mr = ref.evaluate(t)
    xr, vr = np.array(xr), np.array(vr)
    ex = float(np.abs(tr["x"] - xr).max()) / max(float(np.abs(xr).max()), 1e-300)
    ev = float(np.abs(tr["v"] - vr).max()) / max(float(np.abs(vr).max()), 1e-300)
    return ex, ev, np.array(mr)


# the heavily damped case takes about 9 s (a long slide sampled per damping time): slow
@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n == "c>0 heavy damping" else n
                                  for n in CASES])
def test_against_the_40_digit_reference(fmu: OscillatorFMU2, name: str, refcache: RefCache) -> None:
    p, F = CASES[name]
    T = p.period
    t = np.linspace(0.0, 12.0 * T, 481)
    n0 = len(fmu.messages)
    tr = fmu.trajectory(p, t, _settings(F), outputs=("x", "v", "a", "mode"))
    ev_fmu = _events(fmu, n0)
    ref = refcache.call(solved_reference, p, F, t[-1])
    ex, ev, mr = _errors(tr, ref, t)
    print(f"{name}: x {ex:.2e}, v {ev:.2e}, {len(ref.segments)} phases")
    assert ex <= TOL and ev <= TOL, (ex, ev)
    if p.N * p.mu_s > 0:
        # the same phases: every event at the same time, from and to the same modes
        ev_ref = ref.events()
        assert [(a, b) for _, a, b in ev_fmu] == [(a, b) for _, a, b in ev_ref]
        assert max((abs(a[0] - b[0]) for a, b in zip(ev_fmu, ev_ref)), default=0.0) <= 1e-9 * T
        # the same mode at every sample (but those within rounding of an event: chi = 0 reverses on t = n pi)
        near = np.zeros(t.size, bool)
        for te, _, _ in ev_ref:
            near |= np.abs(t - te) <= 1e-12 * T
        assert np.array_equal(tr["mode"][~near], mr[~near])
        # while stuck the output a is 0; sliding, it is the equation of motion's
        stuck = tr["mode"] == 0
        assert np.all(tr["a"][stuck] == 0.0) and np.all(tr["v"][stuck] == 0.0)


def test_a_stop_needs_no_sign_change_and_a_slide_from_rest_at_zero_acceleration(fmu: OscillatorFMU2,
                                                                                refcache: RefCache) -> None:
    """A touch: sliding forward with F_ext = mu_k N (f0 = 0, c = 0), v = v0 + (sin t - sin 0) / omega
    only touches 0 at t = 3 pi / 2 (v0 = 1 / omega): the block stops there (the touch is within
    rounding) and sticks, |P + F_ext| = mu_k N < mu_s N, until the force reaches mu_s N."""
    p = free(v0=1.0, chi=0.5)
    F = p.chi * p.mu_s * p.N
    n0 = len(fmu.messages)
    t = np.linspace(0.0, 3.0 * p.period, 121)
    tr = fmu.trajectory(p, t, _settings(F), outputs=("x", "v", "mode"))
    ev = _events(fmu, n0)
    assert ev[0][1:] == (1, 0) and abs(ev[0][0] - 1.5 * math.pi) <= 1e-6
    ref = refcache.call(solved_reference, p, F, t[-1])
    ex, evv, mr = _errors(tr, ref, t)
    assert ex <= TOL and np.array_equal(tr["mode"], mr)


def test_inputs_held_over_communication_steps(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    rng = np.random.default_rng(7)
    p = free(c=0.15, chi=0.8)
    T = p.period
    t = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 6.0 * T, 40)), [6.0 * T]])
    F = rng.uniform(-0.8, 0.8, t.size)
    fmu.start(p, EXACT)
    x, v = [float(fmu.get(["x"])["x"])], [0.0]
    for i in range(t.size - 1):
        fmu.set({"F_ext": float(F[i])})
        fmu.step_to(float(t[i + 1]))
        o = fmu.get(["x", "v"])
        x.append(o["x"])
        v.append(o["v"])
    ref = refcache.call(solved_reference, p, 0.0, t[-1], schedule=list(zip(t[:-1], F[:-1])))
    xr, vr, _ = ref.evaluate(t)
    err = float(np.abs(np.array(x) - np.array(xr)).max()) / float(np.abs(xr).max())
    assert err <= TOL, err


def test_one_long_dostep_equals_many_and_h_has_no_effect(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    """One doStep over n periods, n doSteps of a period, h: the same motion, within rounding. (The
    stop times are doubles: each event's rounding, ulp(t) / 4, shifts the later motion by that much,
    and a free mass keeps the resulting offset of x: 3e-13 after 200 periods.)"""
    p, F = CASES["c>0 chi=0.7 stick-slip"]
    T = p.period
    for n, with_ref in ((50, True), (200, False)):
        fmu.start(p, _settings(F))
        fmu.step_to(n * T)
        one = fmu.get(["x", "v", "mode"])
        t = np.arange(n + 1) * T
        many = fmu.trajectory(p, t, _settings(F), outputs=("x", "v", "mode"))
        coarse = fmu.trajectory(p, t[::10], _settings(F, h=0.37), outputs=("x", "v", "mode"))
        size = float(np.abs(many["x"]).max())
        assert abs(one["x"] - many["x"][-1]) <= TOL * size and one["mode"] == many["mode"][-1]
        assert float(np.abs(coarse["x"] - many["x"][::10]).max()) <= TOL * size
        if with_ref:
            ref = refcache.call(solved_reference, p, F, t[-1])
            xr, _, _ = ref.evaluate([t[-1]])
            assert abs(one["x"] - xr[0]) <= TOL * size and abs(many["x"][-1] - xr[0]) <= TOL * size


def test_a_long_slide_costs_a_few_evaluations(fmu: OscillatorFMU2) -> None:
    """10^6 periods of sliding in one doStep (damped, drifting under F_ext): no event, exact."""
    p, F = CASES["c>0 F_ext pure slide"]
    t_end = 1e6 * p.period
    fmu.start(p, _settings(F))
    t0 = time.perf_counter()
    fmu.step_to(t_end)
    dt = time.perf_counter() - t0
    o = fmu.get(["x", "v", "mode"])
    # the force beyond friction all along (P0 + mu_k N < F_ext): one slide from rest, in closed form
    assert abs(p.P0) + p.mu_k * p.N < F
    ref = reference_for(p, F)
    x, v, _ = ref.slide(1, 0, ref.x0, ref.v0, ref.F_default)
    xr, vr = [float(x(t_end))], [float(v(t_end))]
    assert o["mode"] == 1
    assert abs(o["x"] - xr[0]) <= TOL * abs(xr[0]) and abs(o["v"] - vr[0]) <= TOL * abs(vr[0])
    assert dt < 0.05, dt


@pytest.mark.slow
def test_observables(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    p, F = CASES["c=0 F_ext drift with sticks"]
    T = p.period
    w0, w1 = 2.3 * T, 9.1 * T
    o = fmu.observables(p, 10.0 * T, w0, w1, settings=_settings(F))
    ref = refcache.call(solved_reference, p, F, 10.0 * T)
    tt = np.linspace(w0, w1, 20001)
    xr, _, mr = ref.evaluate(tt)
    stuck = sum(float(min(s.t1, w1) - max(s.t0, w0)) for s in ref.segments if s.mode == 0 and s.t1 > w0 and s.t0 < w1)
    size = max(abs(min(xr)), abs(max(xr)))
    # the extremes: sampled, plus the stops (x is monotone in a slide)
    stops = [float(s.x0) for s in ref.segments if w0 <= s.t0 <= w1]
    assert abs(o["x_max"] - max([*xr, *stops])) <= 1e-10 * size
    assert abs(o["x_min"] - min([*xr, *stops])) <= 1e-10 * size
    assert abs(o["stick_fraction"] - stuck / (w1 - w0)) <= 1e-9
    assert o["transitions"] == sum(1 for e in ref.events() if w0 < e[0] <= w1)


# ---------------------------------------------------------------- the other schemes at k = 0


def test_located_scheme_is_second_order_at_k0(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    p, F = CASES["c>0 chi=0.7 stick-slip"]
    T = p.period
    t = np.linspace(0.0, 10.0 * T, 201)
    ref = refcache.call(solved_reference, p, F, t[-1])
    xr = np.array(ref.evaluate(t)[0])
    size = float(np.abs(xr).max())
    errs = []
    for div in (400, 800, 1600):
        tr = fmu.trajectory(p, t, Settings(scheme="located", h=T / div), outputs=("x",))
        errs.append(float(np.abs(tr["x"] - xr).max()) / size)
    ratios = [a / b for a, b in zip(errs, errs[1:])]
    print("located at k = 0:", errs, ratios)
    assert all(3.6 <= r <= 4.4 for r in ratios), (errs, ratios)
    assert errs[-1] <= 1e-4


@pytest.mark.parametrize("scheme, tol", [("paper", 5e-2), ("consistent", 5e-2), ("located", 1e-5)])
def test_the_bossak_schemes_run_at_k0(fmu: OscillatorFMU2, scheme: str, tol: float, refcache: RefCache) -> None:
    """They accept k = 0 and converge there (paper and consistent at first order, docs/schemes.md)."""
    p, F = CASES["c=0 chi=0.7 stick-slip"]
    T = p.period
    t = np.linspace(0.0, 5.0 * T, 51)
    tr = fmu.trajectory(p, t, Settings(scheme=scheme, h=T / 2000), outputs=("x",))
    ref = refcache.call(solved_reference, p, F, t[-1])
    xr = np.array(ref.evaluate(t)[0])
    err = float(np.abs(tr["x"] - xr).max()) / float(np.abs(xr).max())
    print(f"{scheme} at k = 0, h = T/2000: {err:.2e}")
    assert err <= tol
