"""The exact scheme (scheme = exact) on a moving belt with Coulomb friction (docs/belt.md), against
references that use none of the FMU's code: the closed-form stick-slip limit cycle of the undamped,
unforced belt oscillator (dryfriction.references.belt.limit_cycle) at several scales and in both belt
directions, FMI 2.0 and 3.0; the event-driven reference (belt_reference.simulate: closed-form stick
phases, DOP853 at rtol 1e-12) with damping, forcing, belt changes at communication points, chi > 1
and k = 0, events included; one long doStep against many short ones; the sensitivity outputs against
central finite differences; stribeck still refused with exact."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from dryfriction.references.belt import Belt, limit_cycle, simulate
from dryfriction.drivers.oscillator3 import OscillatorFMU3
from fmi3_helpers import FMI2Run, assert_fmi3_equals_fmi2_on_belt, kinds
from refcache import RefCache

EXACT = 4
OUT = ["x", "v", "a", "F_friction", "mode", "x_max", "x_min", "stick_fraction", "transitions", "E_friction"]
JAC = ["dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0"]
BASE = dict(m=1.0, k=1.0, c=0.05, P0=0.2, omega=0.7, N=1.0, mu_s=0.5, chi=0.6, x0=0.0, v0=0.0, scheme=EXACT)
REF = Belt(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=0.5, mu_k=0.3, P0=0.2, omega=0.7)


# ---- the closed-form limit cycle ---------------------------------------------------------------------

def cycle_params(m: float, k: float, N: float, ratio: float, sign: int) -> tuple[dict, object, float, float]:
    """The undamped, unforced belt oscillator (mu_s 0.5, mu_k 0.3) with the belt at sign * ratio times
    the speed d w0 of the stick band (d = (mu_s - mu_k) N / k), started where the block catches the belt;
    mirrored (x -> -x) for a belt moving backwards. Returns the FMU's parameters, the cycle, the belt
    speed and the slide's amplitude R (the length scale)."""
    w0, d = math.sqrt(k / m), 0.2 * N / k
    vb = ratio * d * w0
    lc = limit_cycle(m, k, N, 0.5, 0.3, vb)
    R = lc.amplitude
    p = dict(m=m, k=k, c=0.0, P0=0.0, omega=1.0, N=N, mu_s=0.5, chi=0.6, x0=sign * lc.x_stick_start, v0=sign * vb,
             scheme=EXACT, observe=True, t_obs_start=0.0, v_belt=sign * vb)
    return p, lc, sign * vb, R


SCALES = {"unit": (1.0, 1.0, 1.0), "m 1e-3": (1e-3, 1.0, 1.0), "k 1e3": (1.0, 1e3, 1.0), "N 1e-3": (1.0, 1.0, 1e-3),
          "all": (1e3, 1e-3, 1e3)}
RATIOS = {"slow belt": 1e-3, "belt 1": 1.0, "fast belt": 1e3}
# FMI 2.0 at every scale, belt speed and direction; FMI 3.0 (which gives FMI 2.0's bits, test_fmi3_same_bits)
# at the unit scale for every belt speed and at every scale for the unit belt speed
CYCLES = [pytest.param(fmi, sc, ra, sign, id=f"fmi{fmi}-{sc}-{ra}-{'forward' if sign > 0 else 'backward'}")
          for fmi in (2, 3) for sc in SCALES for ra in RATIOS for sign in (1, -1)
          if fmi == 2 or sc == "unit" or ra == "belt 1"]


@pytest.mark.parametrize("fmi, scale_name, ratio_name, sign", CYCLES)
def test_limit_cycle_closed_form(fmi: int, scale_name: str, ratio_name: str, sign: int) -> None:
    """Five cycles and half a stick phase in one doStep: the state at the end, the extremes, the stick
    share and the transitions within 1e-12 (relative to the slide's amplitude, resp. absolute for the
    share)."""
    p, lc, vb, R = cycle_params(*SCALES[scale_name], RATIOS[ratio_name], sign)
    K = 5
    T = K * lc.period + 0.5 * lc.t_stick
    if fmi == 2:
        r = FMI2Run(p)
        try:
            r.slave.doStep(0.0, T)
            o = dict(zip(OUT, r.get(OUT)))
        finally:
            r.close()
    else:
        f = OscillatorFMU3(p)
        try:
            f.do_step(T)
            o = f.get(OUT)
        finally:
            f.close()
    x_end = sign * (lc.x_stick_start + abs(vb) * 0.5 * lc.t_stick)
    assert abs(o["x"] - x_end) <= 1e-12 * R, (o["x"], x_end, R)
    assert o["v"] == vb and o["mode"] == 0 and o["a"] == 0.0
    x_max, x_min = (lc.x_max, lc.x_min) if sign > 0 else (-lc.x_min, -lc.x_max)
    assert abs(o["x_max"] - x_max) <= 1e-12 * R and abs(o["x_min"] - x_min) <= 1e-12 * R, (o, x_max, x_min)
    assert abs(o["stick_fraction"] - (K + 0.5) * lc.t_stick / T) <= 1e-12, (o, lc)
    assert o["transitions"] == 2 * K
    # the friction's work on the relative motion: per cycle mu_k N times the belt's travel during the
    # slide plus the block's way back from the breakaway to the stop
    back = lc.x_breakaway - lc.x_stick_start
    assert o["E_friction"] == pytest.approx(K * 0.3 * p["N"] * (abs(vb) * lc.t_slip + back), rel=1e-12)


def test_limit_cycle_period_and_stick_time_from_the_events() -> None:
    """The switch times the event log reports: breakaways at t_stick + j T, stops at (j + 1) T (the
    period and the stick time per cycle), at the slow, unit and fast belt."""
    for ratio in (1e-3, 1.0, 1e3):
        p, lc, vb, R = cycle_params(1.0, 1.0, 1.0, ratio, 1)
        r = FMI2Run(p, log_events=True)
        try:
            r.slave.doStep(0.0, 6 * lc.period + 0.5 * lc.t_stick)
            sw = r.switches
        finally:
            r.close()
        assert [(a, b) for _, a, b in sw] == [(0, -1), (-1, 0)] * 6
        t = np.array([s[0] for s in sw])
        expect = np.array([[lc.t_stick + j * lc.period, (j + 1) * lc.period] for j in range(6)]).ravel()
        assert np.max(np.abs(t - expect)) <= 1e-12 * 6 * lc.period, (ratio, t - expect)


# ---- the event-driven reference --------------------------------------------------------------------

def run(params: dict, v_belt: float, t_end: float, dt: float, changes=()) -> tuple[np.ndarray, np.ndarray,
                                                                                    np.ndarray, list]:
    """x, v at the communication points of the FMI 2.0 FMU and its switches; v_belt changed at the
    given points."""
    r = FMI2Run(dict(params, v_belt=v_belt), log_events=True)
    try:
        vr = r.vars["v_belt"].valueReference
        n = int(round(t_end / dt))
        x, v = [r.get(["x"])[0]], [r.get(["v"])[0]]
        for i in range(n):
            for tc, vb in changes:
                if abs(tc - i * dt) < 1e-9:
                    r.slave.setReal([vr], [vb])
            r.slave.doStep(i * dt, dt)
            xi, vi = r.get(["x", "v"])
            x.append(xi)
            v.append(vi)
        return np.arange(n + 1) * dt, np.array(x), np.array(v), list(r.switches)
    finally:
        r.close()


# measured max |x - x_ref|, |v - v_ref|: 3.1e-15, 2.9e-15; 2.3e-15, 2.4e-15; 1.2e-14, 1.4e-15; 6.8e-15, 1.0e-14;
# event times within 2e-14
CASES = {
    "damped, forced, belt changed twice": (BASE, REF, 0.3, [(10.0, 0.1), (20.0, -0.2)]),
    "chi > 1, belt stopped": (dict(BASE, chi=1.2), REF.with_(mu_k=0.6), 0.15, [(12.0, 0.0)]),
    "k = 0, belt reversed": (dict(BASE, k=0.0, c=0.3, x0=1.0), REF.with_(k=0.0, c=0.3, x0=1.0), 0.3,
                             [(10.0, -0.1), (20.0, 0.2)]),
    "k = 0, forced: turns inside slides": (dict(BASE, k=0.0, c=0.3, x0=1.0, P0=1.0, omega=1.0, N=0.2),
                                           REF.with_(k=0.0, c=0.3, x0=1.0, P0=1.0, omega=1.0, N=0.2), 0.1, []),
    "undamped, forced, backward belt": (dict(BASE, c=0.0, P0=0.6, omega=1.3), REF.with_(c=0.0, P0=0.6, omega=1.3),
                                        -0.25, [(15.0, 0.4)]),
    "heavy damping, F_ext": (dict(BASE, c=1.5, F_ext=0.1, P0=0.4), REF.with_(c=1.5, F_ext=0.1, P0=0.4), 0.2,
                             [(8.0, 0.5), (16.0, 0.05)]),
}


@pytest.mark.parametrize("name", [n if i == 0 else pytest.param(n, marks=pytest.mark.slow)
                                  for i, n in enumerate(CASES)])  # (the reference on 30001 points: 1.5-4.5 s each)
def test_extremes_against_the_reference_on_a_fine_grid(name: str, refcache: RefCache) -> None:
    """x_max, x_min over [5, 30] (observe): at least the largest (least) x of the reference on a grid of
    1e-3 s, and within the grid's reach of it (the turning points inside slides are found: x is not
    monotone in a slide on a belt)."""
    params, ref, vb, changes = CASES[name]
    p = dict(params, v_belt=vb, observe=True, t_obs_start=5.0)
    r = FMI2Run(p)
    try:
        vr, t = r.vars["v_belt"].valueReference, 0.0
        for tc, v in list(changes) + [(30.0, None)]:
            r.slave.doStep(t, tc - t)
            t = tc
            if v is not None:
                r.slave.setReal([vr], [v])
        x_max, x_min = r.get(["x_max", "x_min"])
    finally:
        r.close()
    grid = np.linspace(0.0, 30.0, 30001)
    b = refcache.call(simulate, ref, grid, v_belt=vb, changes=changes)
    w = grid >= 5.0
    xs, vs, ms = b.x[w], b.v[w], b.mode[w]
    reach = 1e-3 * np.abs(vs).max()  # (x moves at most by this between two grid points: a turning point lies within)
    assert -1e-10 <= x_max - xs.max() <= reach and -1e-10 <= xs.min() - x_min <= reach, (x_max, xs.max(), x_min,
                                                                                        xs.min())
    # a turning point inside a slide: the reference's v changes sign while v - v_belt keeps it
    turns = np.sum((np.sign(vs[1:]) != np.sign(vs[:-1])) & (ms[1:] != 0) & (ms[1:] == ms[:-1]))
    assert turns > 0, name


@pytest.mark.parametrize("name", list(CASES))
def test_against_the_event_driven_reference(name: str, refcache: RefCache) -> None:
    params, ref, vb, changes = CASES[name]
    t, x, v, sw = run(params, vb, 30.0, 0.1, changes)
    b = refcache.call(simulate, ref, t, v_belt=vb, changes=changes)
    assert np.max(np.abs(x - b.x)) < 1e-10 and np.max(np.abs(v - b.v)) < 1e-10, name
    assert kinds([(a, c) for _, a, c in sw]) == [k for _, k in b.events], (sw, b.events)
    assert len(sw) >= 4  # events happen
    assert np.max(np.abs(np.array([s[0] for s in sw]) - np.array([e[0] for e in b.events]))) < 1e-9


def test_long_stick_phase_with_a_brief_crossing(refcache: RefCache) -> None:
    """A slow belt (0.002) drags the stuck block's holding force 0.05 cos(3 t) + 0.3 - 0.002 t down over
    some 180 excitation periods until one trough of the excitation dips past -F_s: one doStep of 400 s
    finds that breakaway (and the slides after it) at the reference's times."""
    p = dict(BASE, c=0.0, P0=0.05, omega=3.0, x0=-0.3, v0=0.002)
    ref = REF.with_(c=0.0, P0=0.05, omega=3.0, x0=-0.3, v0=0.002)
    r = FMI2Run(dict(p, v_belt=0.002), log_events=True)
    try:
        r.slave.doStep(0.0, 400.0)
        x, v = r.get(["x", "v"])
        sw = list(r.switches)
    finally:
        r.close()
    b = refcache.call(simulate, ref, [0.0, 400.0], v_belt=0.002)
    assert sw and sw[0][1] == 0 and 300.0 < sw[0][0] < 400.0, sw
    assert kinds([(a, c) for _, a, c in sw]) == [k_ for _, k_ in b.events]
    assert np.max(np.abs(np.array([q[0] for q in sw]) - np.array([e[0] for e in b.events]))) < 1e-9
    # the crossing lies near a trough of the excitation: cos(3 t_b) close to -1
    assert math.cos(3.0 * sw[0][0]) < -0.9
    assert abs(x - b.x[-1]) < 1e-10 and abs(v - b.v[-1]) < 1e-10


def test_fmi3_same_bits() -> None:
    """FMI 3.0 gives FMI 2.0's bits with a belt changed at communication points."""
    assert_fmi3_equals_fmi2_on_belt(dict(BASE, observe=True, v_belt=0.3), OUT)


# ---- input derivatives on a belt -------------------------------------------------------------------

@dataclass(frozen=True)
class RampBelt(Belt):
    """The reference's block with F_ext + F1 t instead of F_ext (a ramp). ``P0`` is only the reference's
    bound of the force's rate (|P0| omega bounds it: set to P_true + |F1| / omega); the excitation is
    P_true cos(omega t + phi)."""

    F1: float = 0.0
    P_true: float = 0.0

    def applied(self, t: float, x: float, v: float) -> float:
        return (self.P_true * math.cos(self.omega * t + self.phi) + self.F_ext + self.F1 * t - self.c * v
                - self.k * x)


@pytest.mark.parametrize("k", [1.0, 0.0], ids=["spring", "no spring"])
def test_F_ext_ramp_on_a_belt(k: float, refcache: RefCache) -> None:
    """F_ext = 0.05 + 0.01 t given at every communication point with its derivative (so the FMU's
    polynomial is the ramp itself), on a belt changed once: against the reference with that ramp."""
    F0, F1, vb, dt = 0.05, 0.01, 0.3, 0.1
    x0 = 1.0 if k == 0.0 else 0.0
    r = FMI2Run(dict(BASE, k=k, x0=x0, v_belt=vb, observe=True), log_events=True)
    try:
        vr, vbr = r.vars["F_ext"].valueReference, r.vars["v_belt"].valueReference
        xs, vs = [], []
        for i in range(300):
            t = i * dt
            if i == 150:
                r.slave.setReal([vbr], [-0.1])
            r.slave.setReal([vr], [F0 + F1 * t])
            r.slave.setRealInputDerivatives([vr], [1], [F1])
            r.slave.doStep(t, dt)
            x, v = r.get(["x", "v"])
            xs.append(x)
            vs.append(v)
        sw = list(r.switches)
    finally:
        r.close()
    ref = RampBelt(m=1.0, k=k, c=0.05, N=1.0, mu_s=0.5, mu_k=0.3, P0=0.2 + F1 / 0.7, omega=0.7, F_ext=F0, F1=F1,
                   P_true=0.2, x0=x0)
    grid = np.arange(301) * dt
    b = refcache.call(simulate, ref, grid, v_belt=vb, changes=[(15.0, -0.1)])
    assert np.max(np.abs(np.array(xs) - b.x[1:])) < 1e-10 and np.max(np.abs(np.array(vs) - b.v[1:])) < 1e-10
    assert kinds([(a, c) for _, a, c in sw]) == [k_ for _, k_ in b.events] and len(sw) >= 3, (sw, b.events)


def test_extremes_without_spring_with_a_normal_force_ramp() -> None:
    """k = 0 on a belt, N_ext falling through 0 (the friction ends at t = 12: the slide's pieces) and F_ext
    rising, both given with their derivatives at every communication point of 0.1: x_max, x_min over
    [2, 20] against the x of the same run sampled every 1e-3 (at least each sample, within the sampling's
    reach; x turns inside the slides)."""
    def run(dt: float, observe: bool) -> tuple[np.ndarray, list[float]]:
        r = FMI2Run(dict(BASE, k=0.0, c=0.3, x0=1.0, P0=1.0, omega=1.0, N=0.6, v_belt=0.1, observe=observe,
                         t_obs_start=2.0, t_obs_stop=20.0))
        try:
            vF, vN = r.vars["F_ext"].valueReference, r.vars["N_ext"].valueReference
            xs = []
            n = int(round(20.0 / dt))
            for i in range(n):
                t = i * dt
                r.slave.setReal([vF, vN], [0.02 * t, -0.05 * t])
                r.slave.setRealInputDerivatives([vF, vN], [1, 1], [0.02, -0.05])
                r.slave.doStep(t, dt)
                xs.append(r.get(["x"])[0])
            return np.array(xs), (r.get(["x_max", "x_min"]) if observe else [])
        finally:
            r.close()
    _, (x_max, x_min) = run(0.1, True)
    xs, _ = run(1e-3, False)
    w = xs[1999:]  # t in [2, 20]
    assert -1e-10 <= x_max - w.max() <= 1e-5 and -1e-10 <= w.min() - x_min <= 1e-5, (x_max, w.max(), x_min, w.min())
    assert np.any(np.diff(np.sign(np.diff(w))) != 0)  # x turns


def test_fmu_state_round_trip_on_a_belt() -> None:
    r = FMI2Run(dict(BASE, observe=True, v_belt=0.3))
    try:
        r.slave.doStep(0.0, 3.0)
        state = r.slave.serializeFMUstate(r.slave.getFMUstate())
        r.slave.setReal([r.vars["v_belt"].valueReference], [-0.1])
        r.slave.doStep(3.0, 4.0)
        first = r.get(OUT)
        r.slave.setFMUstate(r.slave.deSerializeFMUstate(state))
        r.slave.setReal([r.vars["v_belt"].valueReference], [-0.1])
        r.slave.doStep(3.0, 4.0)
        assert np.array_equal(np.asarray(r.get(OUT), float).view(np.int64),
                              np.asarray(first, float).view(np.int64))
    finally:
        r.close()


# ---- one long doStep, many short ones ---------------------------------------------------------------

LONG = [
    # (name, ratio of the belt speed to d w0, damping, forcing amplitude): the limit cycle (its stick
    # phases make it super-stable: an error does not grow), and a fast belt on which the damped, forced
    # block never catches the belt again (one slide of 50 cycles)
    ("limit cycle, slow belt", 1e-2, 0.0, 0.0),
    ("limit cycle, belt 1", 1.0, 0.0, 0.0),
    ("limit cycle, fast belt", 1e2, 0.0, 0.0),
    ("damped limit cycle", 1.0, 0.05, 0.0),
    ("fast belt, damped and forced: one slide", 1e2, 0.02, 0.05),
]


@pytest.mark.parametrize("name, ratio, c, P0", LONG, ids=[c[0] for c in LONG])
def test_long_do_step_equals_short_ones(name: str, ratio: float, c: float, P0: float) -> None:
    """One doStep of 50 cycles against the same 50 cycles in 997 steps: the same state and observables
    within 1e-12 (relative to the slide's amplitude)."""
    p, lc, vb, R = cycle_params(1.0, 1.0, 1.0, ratio, 1)
    p = dict(p, c=c, P0=P0, omega=0.9)
    T = 50 * lc.period + 0.5 * lc.t_stick  # (not on a stop)
    outs = []
    for n in (1, 997):
        r = FMI2Run(p)
        try:
            for i in range(n):
                r.slave.doStep(i * T / n, (i + 1) * T / n - i * T / n)
            outs.append(dict(zip(OUT, r.get(OUT))))
        finally:
            r.close()
    a, b = outs
    for key in ("x", "x_max", "x_min"):
        assert abs(a[key] - b[key]) <= 1e-12 * R, (key, a, b)
    assert abs(a["v"] - b["v"]) <= 1e-12 * R * math.sqrt(p["k"] / p["m"]), (a, b)
    assert a["transitions"] == b["transitions"]
    assert (a["transitions"] == 1) if P0 > 0 else (a["transitions"] >= 100)
    assert abs(a["stick_fraction"] - b["stick_fraction"]) <= 1e-12
    assert a["E_friction"] == pytest.approx(b["E_friction"], rel=1e-12)


# ---- the sensitivity outputs ------------------------------------------------------------------------

def end_state(p: dict, vb: float, t_end: float, changes=()) -> tuple[np.ndarray, np.ndarray, int]:
    r = FMI2Run(dict(p, v_belt=vb, sensitivity=True))
    try:
        t, vr = 0.0, r.vars["v_belt"].valueReference
        for tc, v in list(changes) + [(t_end, None)]:
            if tc > t:
                r.slave.doStep(t, tc - t)
                t = tc
            if v is not None:
                r.slave.setReal([vr], [v])
        x, v_, md = r.get(["x", "v", "mode"])
        return np.array([x, v_]), np.array(r.get(JAC)).reshape(2, 2), int(md)
    finally:
        r.close()


def fd(p: dict, vb: float, t_end: float, eps: float, changes=()) -> np.ndarray:
    J = np.zeros((2, 2))
    for col, name in enumerate(("x0", "v0")):
        hi = end_state(dict(p, **{name: p[name] + eps}), vb, t_end, changes)[0]
        lo = end_state(dict(p, **{name: p[name] - eps}), vb, t_end, changes)[0]
        J[:, col] = (hi - lo) / (2.0 * eps)
    return J


SENS = [
    # (name, parameters, belt, end times, belt changes): each end time inside a slide
    ("slide only", dict(BASE, c=0.1, P0=0.3, omega=1.3, x0=0.2, v0=0.1), 1.5, (7.3, 23.1), ()),
    ("stick phases", dict(BASE, x0=0.1, v0=0.6), 0.3, (12.0, 28.5), ()),
    ("stick phases, undamped, chi > 1", dict(BASE, c=0.0, chi=1.2, P0=0.5, omega=1.1, x0=0.2, v0=0.1), -0.2,
     (6.0, 18.0), ()),
    ("belt changed while stuck", dict(BASE, x0=0.1, v0=0.6), 0.3, (26.5,), ((12.0, 0.1), (20.0, -0.2))),
    ("no spring, stick phases", dict(BASE, k=0.0, c=0.2, N=1.5, P0=1.0, omega=2.0, x0=0.0, v0=0.5), 0.3, (3.5, 14.5),
     ()),
]


@pytest.mark.parametrize("name, p, vb, times, changes", SENS, ids=[c[0] for c in SENS])
def test_sensitivity_against_finite_differences(name: str, p: dict, vb: float, times: tuple[float, ...],
                                                changes) -> None:
    for t_end in times:
        y, J, md = end_state(p, vb, t_end, changes)
        assert md != 0, f"{name}: t = {t_end} ends stuck; choose an end time inside a slide"
        J1 = fd(p, vb, t_end, 1e-6, changes)
        J2 = fd(p, vb, t_end, 2e-6, changes)
        scale = np.abs(J1).max()
        assert np.abs(J1 - J2).max() < 1e-6 * scale, f"{name}: an event near t = {t_end}"
        assert np.abs(J - J1).max() < 1e-6 * scale, (name, t_end, J, J1)


def test_sensitivity_cases_pass_through_stick_phases() -> None:
    """The stick cases do stick on the way (rank one there: the v row is 0, the x row kept)."""
    for name, p, vb, times, changes in SENS[1:3]:
        r = FMI2Run(dict(p, v_belt=vb, sensitivity=True))
        try:
            t, seen = 0.0, False
            while t < times[0]:
                r.slave.doStep(t, 0.05)
                t += 0.05
                if r.get(["mode"])[0] == 0:
                    J = r.get(JAC)
                    assert J[2] == 0.0 and J[3] == 0.0 and (J[0] != 0.0 or J[1] != 0.0), (name, t, J)
                    seen = True
            assert seen, name
        finally:
            r.close()


# ---- refusals -------------------------------------------------------------------------------------

def test_stribeck_with_exact_still_refused() -> None:
    r = FMI2Run.__new__(FMI2Run)
    with pytest.raises(FMICallException):
        FMI2Run.__init__(r, dict(BASE, friction_law=2, v_belt=0.3), log_events=True)
    r.slave.freeInstance()
    msgs = [m for m in r.messages if " " in m]
    assert msgs and "scheme exact supports friction_law = coulomb only" in msgs[-1] and msgs[-1].endswith(".")
