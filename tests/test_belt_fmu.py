"""The oscillator FMU on a moving belt, with Coulomb and Stribeck friction (input v_belt, parameters
friction_law, v_s, delta; docs/belt.md), against the independent references of
dryfriction.references.belt (event-driven stick/slip with DOP853 at rtol 1e-12, and the closed-form
limit cycle of the undamped, unforced Coulomb belt oscillator), none of which uses the FMU's code.

Asserted: the located scheme's error and its second order (halving h divides it by 4 +- 15 %) on
forced, damped cases of both laws, also with v_belt changed at communication points; the closed-form
limit cycle (period, extremes, stick share) to second order; Stribeck's self-excited stick-slip below
the Hopf belt speed and steady sliding above it; the paper and consistent schemes on a belt; the
errors (v_s, delta, v_belt NaN, stribeck outside scheme located, stribeck with scheme exact,
derivatives of v_belt); FMI 3.0 bit for bit FMI 2.0; the FMU state round trip with a belt."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from dryfriction.references.belt import Belt, hopf_belt_speed, limit_cycle, simulate
from fmi3_helpers import FMI2Run, assert_fmi3_equals_fmi2_on_belt

OUT = ["x", "v", "a", "F_friction", "mode", "x_max", "x_min", "stick_fraction", "transitions", "E_friction",
       "effects"]
BASE = dict(m=1.0, k=1.0, c=0.05, P0=0.2, omega=0.7, N=1.0, mu_s=0.5, chi=0.6, x0=0.0, v0=0.0, scheme=3)
REF = Belt(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=0.5, mu_k=0.3, P0=0.2, omega=0.7)
STRIBECK = dict(friction_law=2, v_s=0.1, delta=1.0)
CHANGES = [(10.0, 0.1), (20.0, -0.2)]  # (time, new v_belt) at communication points


def run(params: dict, v_belt: float | None, t_end: float, dt: float,
        changes: list[tuple[float, float]] = ()) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """x, v at the communication points k dt of the FMI 2.0 FMU; v_belt (None: never set) changed at
    the given points."""
    r = FMI2Run(params if v_belt is None else dict(params, v_belt=v_belt))
    try:
        vr = r.vars["v_belt"].valueReference
        n = int(round(t_end / dt))
        t, x, v = np.arange(n + 1) * dt, [r.get(["x"])[0]], [r.get(["v"])[0]]
        for i in range(n):
            for tc, vb in changes:
                if abs(tc - i * dt) < 1e-9:
                    r.slave.setReal([vr], [vb])
            r.slave.doStep(i * dt, dt)
            xi, vi = r.get(["x", "v"])
            x.append(xi)
            v.append(vi)
        return t, np.array(x), np.array(v), dict(zip(OUT, r.get(OUT)))
    finally:
        r.close()


def errors(params: dict, ref: Belt, v_belt: float, changes, h: float) -> tuple[float, float]:
    t, x, v, _ = run(dict(params, h=h), v_belt, 30.0, 0.1, changes)
    b = simulate(ref, t, v_belt=v_belt, changes=changes)
    return float(np.max(np.abs(x - b.x))), float(np.max(np.abs(v - b.v)))


# measured max |x - x_ref| (h = 2e-3, 1e-3): 7.32e-7, 1.83e-7; 8.50e-7, 2.13e-7; 1.63e-6, 4.12e-7;
# 3.68e-7, 9.20e-8 (ratios 4.00, 4.00, 3.96, 4.00; v alike)
CASES = {
    "coulomb, belt changed twice": (BASE, REF, 0.3, CHANGES),
    "stribeck, belt changed twice": (dict(BASE, **STRIBECK), REF.with_(law="stribeck", v_s=0.1), 0.3, CHANGES),
    "stribeck, delta 2, damped, belt reversed": (dict(BASE, chi=0.4, delta=2.0, friction_law=2, v_s=0.05, c=0.2, P0=0.5),
                                        REF.with_(mu_k=0.2, law="stribeck", v_s=0.05, delta=2.0, c=0.2, P0=0.5),
                                        -0.25, [(15.0, 0.4)]),
    "coulomb, chi > 1": (dict(BASE, chi=1.2), REF.with_(mu_k=0.6), 0.15, [(12.0, 0.0)]),
}


@pytest.mark.parametrize("name", list(CASES))
def test_located_second_order_against_the_event_driven_reference(name: str) -> None:
    params, ref, vb, changes = CASES[name]
    e1 = errors(params, ref, vb, changes, 2e-3)
    e2 = errors(params, ref, vb, changes, 1e-3)
    for a, b in zip(e1, e2):
        assert b < 1e-6, (name, e1, e2)
        assert 4.0 / 1.15 < a / b < 4.0 * 1.15, (name, e1, e2)


def cycle_observables(h: float) -> tuple[dict, float]:
    """The undamped, unforced Coulomb belt oscillator started where it catches the belt: four periods."""
    lc = limit_cycle(1.0, 1.0, 1.0, 0.5, 0.3, 0.2)
    params = dict(BASE, c=0.0, P0=0.0, x0=lc.x_stick_start, v0=0.2, h=h, t_obs_start=0.0)
    r = FMI2Run(dict(params, v_belt=0.2))
    try:
        T = 4 * lc.period + 0.5 * lc.t_stick  # four cycles, and half a stick phase
        r.slave.doStep(0.0, T)
        return dict(zip(OUT, r.get(OUT))), lc
    finally:
        r.close()


def test_closed_form_limit_cycle_located_second_order() -> None:
    errs = []
    for h in (2e-3, 1e-3):
        o, lc = cycle_observables(h)
        T = 4 * lc.period + 0.5 * lc.t_stick
        e = [abs(o["x_max"] - lc.x_max), abs(o["x_min"] - lc.x_min), abs(o["stick_fraction"] - 4.5 * lc.t_stick / T),
             abs(o["x"] - (lc.x_stick_start + 0.1 * lc.t_stick)) + abs(o["v"] - 0.2)]
        assert o["transitions"] == 8  # four periods: a breakaway and a stop each
        assert o["mode"] == 0
        errs.append(e)
    # measured (h = 2e-3 / 1e-3): x_max 8.8e-9 / 1.1e-9, x_min 9.4e-9 / 3.3e-9 (sampled at the steps' ends:
    # within a h^2 / 2 of the turning point, not a clean order), stick share 3.10e-7 / 7.76e-8, final
    # state 1.73e-6 / 4.32e-7 (ratios 4.00)
    for h, e in zip((2e-3, 1e-3), errs):
        assert e[0] < 0.01 * h * h and e[1] < 0.01 * h * h, errs
    for a, b in list(zip(*errs))[2:]:
        assert b < 1e-6, errs
        assert 4.0 / 1.1 < a / b < 4.0 * 1.1, errs


def test_stribeck_hopf_belt_speed() -> None:
    """delta = 1: steady sliding loses stability below v* = v_s ln(N (mu_s - mu_k) / (c v_s))."""
    c, v_s = 0.1, 0.1
    v_star = hopf_belt_speed(c, 1.0, 0.5, 0.3, v_s)
    assert v_star == pytest.approx(0.1 * math.log(20.0), rel=1e-15)
    ref = REF.with_(c=c, P0=0.0, law="stribeck", v_s=v_s)
    amp = {}
    for vb in (0.8 * v_star, 1.2 * v_star):
        x_eq = ref.N * ref.mu(vb) / ref.k  # steady sliding: v = 0, v_rel = -vb, F = +N mu(vb)
        params = dict(BASE, c=c, P0=0.0, x0=x_eq + 0.01, h=1e-3, t_obs_start=150.0, **STRIBECK)
        t, x, v, o = run(params, vb, 200.0, 1.0)
        amp[vb] = (o["x_max"] - o["x_min"]) / 2, o["stick_fraction"]
    below, above = amp[0.8 * v_star], amp[1.2 * v_star]
    # measured: 0.8 v*: amplitude 0.338, stick share 0.236; 1.2 v*: amplitude 3.2e-4 (from 0.01), no stick
    assert below[1] > 0.1 and below[0] > 0.2, amp   # self-excited stick-slip
    assert above[1] == 0.0 and above[0] < 1e-3, amp   # the perturbation of 0.01 decays


@pytest.mark.parametrize("scheme", [1, 2])
def test_paper_and_consistent_on_a_belt(scheme: int) -> None:
    """First-order schemes on a belt (coulomb), h = 1e-3: measured 9.69e-5 (paper), 9.70e-5 (consistent)."""
    t, x, v, _ = run(dict(BASE, scheme=scheme, h=1e-3), 0.3, 30.0, 0.1, CHANGES)
    b = simulate(REF, t, v_belt=0.3, changes=CHANGES)
    assert np.max(np.abs(x - b.x)) < 3e-4


def test_effects_and_no_belt_unchanged() -> None:
    """The effect bits; a v_belt of 0 never set is the fixed support (the bits of a run without it)."""
    t, x0, v0, o0 = run(dict(BASE, h=1e-3), None, 5.0, 0.1)
    assert not (int(o0["effects"]) & (128 | 256))
    r = FMI2Run(dict(BASE, h=1e-3))
    try:
        r.slave.doStep(0.0, 5.0)
        assert r.get(["x", "v"]) == [x0[-1], v0[-1]]
        assert not (int(r.get(["effects"])[0]) & 128)
    finally:
        r.close()
    _, _, _, o = run(dict(BASE, h=1e-3, **STRIBECK), 0.3, 1.0, 0.1)
    assert int(o["effects"]) & 128 and int(o["effects"]) & 256


def failure_messages(params: dict) -> list[str]:
    """The messages of an FMI 2.0 run whose set-up (setting the values, leaving initialisation) must fail."""
    r = FMI2Run.__new__(FMI2Run)
    try:
        FMI2Run.__init__(r, params, log_events=True)
    except FMICallException:
        r.slave.freeInstance()
        return r.messages
    r.close()
    raise AssertionError(f"{params} accepted")


@pytest.mark.parametrize("params, words", [
    (dict(v_s=0.0), ("v_s", "valid range")),
    (dict(delta=-1.0), ("delta", "valid range")),
    (dict(v_belt=math.nan), ("v_belt", "finite")),
    (dict(friction_law=2, scheme=4), ("scheme exact supports friction_law = coulomb only",)),
    (dict(friction_law=2, scheme=1), ("friction_law = stribeck needs scheme located",)),
    (dict(friction_law=3), ("friction_law",)),
    (dict(friction_law=2, delta=0.5), ("supports delta >= 1 only",)),
])
def test_bad_values_rejected_with_a_sentence(params: dict, words: tuple[str, ...]) -> None:
    msgs = [m for m in failure_messages(dict(BASE, **params)) if " " in m]
    assert msgs and msgs[-1].endswith("."), msgs
    for w in words:
        assert w in msgs[-1], (w, msgs)


def test_v_belt_derivatives_refused() -> None:
    r = FMI2Run(dict(BASE, h=1e-3, v_belt=0.1))
    try:
        with pytest.raises(FMICallException):
            r.slave.setRealInputDerivatives([r.vars["v_belt"].valueReference], [1], [0.5])
        assert any("input derivatives of v_belt" in m for m in r.messages), r.messages
    finally:
        r.close()


def test_fmi3_bit_for_bit_fmi2_with_belt_and_stribeck() -> None:
    for extra in ({}, STRIBECK):
        assert_fmi3_equals_fmi2_on_belt(dict(BASE, h=1e-3, observe=True, v_belt=0.3, **extra), OUT)


def test_fmu_state_round_trip_with_belt() -> None:
    params = dict(BASE, h=1e-3, v_belt=0.3, **STRIBECK)
    r = FMI2Run(params)
    try:
        r.slave.doStep(0.0, 3.0)
        state = r.slave.serializeFMUstate(r.slave.getFMUstate())
        r.slave.doStep(3.0, 4.0)
        first = r.get(OUT)
        r.slave.setFMUstate(r.slave.deSerializeFMUstate(state))
        r.slave.doStep(3.0, 4.0)
        assert np.array_equal(np.asarray(r.get(OUT), float).view(np.int64), np.asarray(first, float).view(np.int64))
    finally:
        r.close()


def test_directional_derivative_with_respect_to_v_belt() -> None:
    """Sliding with Stribeck: dF_friction / dv_belt = N mu'(|v - v_belt|), da = that / m, against a
    central difference of the outputs (read without a step); coulomb sliding: 0."""
    for extra, nonzero in ((STRIBECK, True), ({}, False)):
        r = FMI2Run(dict(BASE, h=1e-3, v_belt=0.3, **extra))
        try:
            t = 0.0
            while r.get(["mode"])[0] == 0 or t < 1.0:  # into a slide
                r.slave.doStep(t, 0.05)
                t += 0.05
            vr = {n: r.vars[n].valueReference for n in ("a", "F_friction", "v_belt")}
            mode, vel = r.get(["mode", "v"])
            assert mode != 0
            J = r.slave.getDirectionalDerivative([vr["a"], vr["F_friction"]], [vr["v_belt"]], [1.0])
            eps, fd = 1e-6, []
            for d in (eps, -eps):
                r.slave.setReal([vr["v_belt"]], [0.3 + d])
                fd.append(np.array(r.get(["a", "F_friction"])))
            r.slave.setReal([vr["v_belt"]], [0.3])
            num = (fd[0] - fd[1]) / (2 * eps)
            if nonzero:
                mu1 = REF.with_(law="stribeck", v_s=0.1).dmu(abs(vel - 0.3))
                assert J[1] == pytest.approx(mu1, rel=1e-12) and J[0] == pytest.approx(mu1, rel=1e-12)
                assert np.allclose(J, num, rtol=1e-6, atol=0), (J, num)
            else:
                assert list(J) == [0.0, 0.0] and np.all(num == 0.0)
        finally:
            r.close()


@pytest.mark.parametrize("extra", [{}, STRIBECK], ids=["coulomb", "stribeck"])
def test_belt_with_F_ext_input_derivatives_second_order(extra: dict) -> None:
    """F_ext given with its first derivative at every communication point (a sine), on a belt: the
    located scheme converges at second order to its h = 1.25e-4 run (measured x errors at h = 2e-3,
    1e-3, 5e-4: coulomb 1.81e-6, 4.48e-7, 1.07e-7; stribeck 8.99e-7, 2.22e-7, 5.28e-8; ratios 4.05, 4.20)."""
    def xs(h: float) -> np.ndarray:
        r = FMI2Run(dict(BASE, h=h, v_belt=0.3, **extra))
        try:
            vr, out = r.vars["F_ext"].valueReference, []
            for i in range(300):
                t = i * 0.1
                r.slave.setReal([vr], [0.02 * math.sin(0.1 * t)])
                r.slave.setRealInputDerivatives([vr], [1], [0.002 * math.cos(0.1 * t)])
                r.slave.doStep(t, 0.1)
                out.append(r.get(["x"])[0])
            return np.array(out)
        finally:
            r.close()
    ref = xs(1.25e-4)
    e = [float(np.abs(xs(h) - ref).max()) for h in (2e-3, 1e-3, 5e-4)]
    assert e[1] < 5e-7, e
    for a, b in zip(e, e[1:]):
        assert 3.5 < a / b < 4.6, e
