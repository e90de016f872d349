"""The exact scheme (scheme 4) through the FMU: against the exact piecewise solution
``dryfriction.references.exact`` (positions and the sequence of events), against an event-driven scipy
integration (helpers.event_driven) where the reference has no counterpart (chi = 0, inputs held
over communication steps), and the FMU's features (observables, FMU states, event log, h without
effect, bad input)."""

from __future__ import annotations

import math
import re
from collections.abc import Iterator

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from dryfriction.references.exact import ExactSolution, solve_exact
from dryfriction.drivers.oscillator import FMUError, OscillatorFMU2, Settings
from dryfriction.params import Oscillator
from dryfriction.analysis.validation import CASES

from helpers import event_driven, held_run


ND = Oscillator.from_nondimensional
EXACT = Settings(scheme="exact")
RTOL = 1e-10          # max |z - z_ref| over the motion's size (the bound)
EVENT_RTOL = 1e-8     # event times, in periods (a tangential touch is located to sqrt(rounding))
EVENT_RE = re.compile(r"t = ([-0-9.e+]+): (\w+ ?\w*) -> (\w+ ?\w*) at x = ([-0-9.e+]+)\.")
MODE = {"backward slip": -1, "stick": 0, "forward slip": 1}


@pytest.fixture(scope="module")
def fmu(fmu_path) -> Iterator[OscillatorFMU2]:
    with OscillatorFMU2(fmu_path, logging=True) as f:
        yield f


def _events(f: OscillatorFMU2, since: int) -> list[tuple[float, int, int, float]]:
    out = []
    for _, cat, msg in f.messages[since:]:
        m = EVENT_RE.match(msg) if cat == "logEvents" else None
        if m:
            out.append((float(m.group(1)), MODE[m.group(2)], MODE[m.group(3)], float(m.group(4))))
    return out


def _phases(mode0: int, events: list[tuple[float, int]], t_end: float, tol: float) -> list[tuple[float, int]]:
    """(start, mode) of each phase of positive length, consecutive equal modes merged."""
    starts = [(0.0, mode0)] + events
    out: list[tuple[float, int]] = []
    for i, (t, m) in enumerate(starts):
        t_next = starts[i + 1][0] if i + 1 < len(starts) else t_end
        if t_next - t <= tol:
            continue
        if out and out[-1][1] == m:
            continue
        out.append((t, m))
    return out


def _compare(f: OscillatorFMU2, p: Oscillator, periods: float = 30.0, per_period: int = 40) -> tuple[float, int]:
    """Run the FMU (exact) and the reference over `periods`: relative position error, events."""
    T = p.period
    t = np.linspace(0.0, periods * T, int(periods * per_period) + 1)
    n0 = len(f.messages)
    f.start(p, EXACT)
    mode0 = int(f.get(["mode"])["mode"])
    tr = f.trajectory(p, t, EXACT, outputs=("x", "v", "a", "mode"))
    ev = _events(f, n0)
    ref = solve_exact(p, float(t[-1]))
    x_ref, v_ref, a_ref, mode_ref = ref.evaluate(t)
    size = max(float(np.abs(x_ref).max()), p.P0 / p.k)
    err = float(np.abs(tr["x"] - x_ref).max()) / size
    # velocity and acceleration (the output a: the equation of motion, 0 while stuck) on their scales
    rate = p.w0 + p.omega
    assert float(np.abs(tr["v"] - v_ref).max()) <= RTOL * size * rate
    same = tr["mode"] == mode_ref
    if p.N * p.mu_s > 0:  # without friction the mode only names the sign of v (a touch of v = 0 may differ)
        assert same.mean() > 0.99
    assert float(np.abs(tr["a"] - a_ref)[same].max()) <= RTOL * size * rate**2
    tol = EVENT_RTOL * T
    got = _phases(mode0, [(e[0], e[2]) for e in ev], float(t[-1]), tol)
    want = _phases(ref.segments[0].mode, [(s.t0, s.mode) for s in ref.segments[1:]], float(t[-1]), tol)
    if p.N * p.mu_s > 0:
        assert [m for _, m in got] == [m for _, m in want], (got[:8], want[:8])
        dt = max((abs(a[0] - b[0]) for a, b in zip(got, want)), default=0.0)
        assert dt <= tol, dt
    # the event log's positions are the reference's at the same times
    if ev and p.N * p.mu_s > 0:
        xe = ref.evaluate(np.array([e[0] for e in ev]))[0]
        assert np.abs(np.array([e[3] for e in ev]) - xe).max() <= RTOL * size
    return err, len(ev)


@pytest.mark.parametrize("name", list(CASES))
def test_validation_cases_match_the_exact_solution(fmu: OscillatorFMU2, name: str) -> None:
    p, _ = CASES[name]
    err, n = _compare(fmu, p)
    assert err <= RTOL and n >= 30, (err, n)


@pytest.mark.parametrize("zeta", [0.0, 0.05, 1.0, 3.0])
@pytest.mark.parametrize("chi", [0.05, 0.7, 1.0, 2.0])
@pytest.mark.parametrize("lam", [0.5, 1.0, 2.0])
def test_grid_matches_the_exact_solution(fmu: OscillatorFMU2, zeta: float, chi: float, lam: float) -> None:
    p = ND(lam=lam, mu_s_sigma=0.3, chi=chi, zeta=zeta, z0=1.5, dz0=0.7, phi=0.3)
    err, _ = _compare(fmu, p)
    assert err <= RTOL, err


# friction and damping below 1e-9 are 0: Hypothesis draws literals of the package's modules (its
# local-constants pool: DBL_MIN, 1e-300, ...), and a friction of 1e-70 static deflections or a
# subnormal zeta is no physics (the mode at a touch of v = 0 is then a rounding matter, as without
# friction, and the Python reference's forced-response kernel overflows at a subnormal zeta)
def _tiny_is_zero(v: float) -> float:
    return 0.0 if v < 1e-9 else v


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(lam=st.floats(0.1, 3.0), mss=st.floats(0.0, 1.2).map(_tiny_is_zero), chi=st.floats(0.02, 2.5),
       zeta=st.floats(0.0, 3.0).map(_tiny_is_zero),
       z0=st.floats(-2.0, 2.0), dz0=st.floats(-2.0, 2.0), phi=st.floats(-math.pi, math.pi))
def test_random_parameters_match_the_exact_solution(fmu: OscillatorFMU2, lam: float, mss: float, chi: float,
                                                    zeta: float, z0: float, dz0: float, phi: float) -> None:
    p = ND(lam=lam, mu_s_sigma=mss, chi=chi, zeta=zeta, z0=z0, dz0=dz0, phi=phi)
    err, _ = _compare(fmu, p, periods=30.0, per_period=10)
    assert err <= RTOL, err


def test_tangential_touch_and_start_on_the_limit(fmu: OscillatorFMU2) -> None:
    # a forward slip whose velocity touches 0 with zero acceleration at t* = 1 (non-dimensional)
    lam, b, ts, th = 0.5, 0.2, 1.0, -math.pi / 3
    phi, H = th - lam * ts, 1.0 / (1.0 - lam * lam)
    A, B = math.cos(th) * (1.0 - H), lam * math.sin(th) * H
    z0 = math.cos(phi) * H + A * math.cos(-ts) + B * math.sin(-ts) - b
    dz0 = -lam * math.sin(phi) * H - A * math.sin(-ts) + B * math.cos(-ts)
    p = ND(lam=lam, mu_s_sigma=0.4, chi=0.5, z0=z0, dz0=dz0, phi=phi)
    n0 = len(fmu.messages)
    _compare(fmu, p, periods=10.0)
    first = _events(fmu, n0)[0]
    assert first[1:3] == (1, 0) and abs(first[0] * p.w0 - ts) < 1e-6
    # on the limit at t = 0: falling (stays stuck), rising with chi >= 1 (zero initial acceleration)
    for chi in (0.5, 1.0, 2.0):
        for phi0, sign in ((0.0, 1.0), (-math.pi / 2, -1.0)):
            q = ND(lam=0.5, mu_s_sigma=0.25, chi=chi, phi=phi0)
            zb = q.breakaway / q.P0
            q = ND(lam=0.5, mu_s_sigma=0.25, chi=chi, phi=phi0, z0=(1.0 - zb) if sign > 0 else -zb)
            err, n = _compare(fmu, q, periods=10.0)
            assert err <= RTOL and n >= 10


# ---------------------------------------------------- inputs held, against the event-driven reference


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_inputs_held_over_communication_steps(fmu: OscillatorFMU2, seed: int) -> None:
    rng = np.random.default_rng(seed)
    p = ND(lam=0.6, mu_s_sigma=0.4, chi=0.6 if seed != 3 else 0.0, zeta=0.05 * seed)
    T = p.period
    t = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 5.0 * T, 60)), [5.0 * T]])
    F_ext = rng.uniform(-0.5, 0.5, t.size) * p.P0
    N_ext = rng.uniform(-0.5, 1.0, t.size) * p.N
    x = held_run(fmu, p, EXACT, t, F_ext, N_ext)
    x_ref = event_driven(p, t, F_ext, N_ext)
    size = max(float(np.abs(x_ref).max()), p.P0 / p.k)
    err = float(np.abs(np.array(x) - x_ref).max()) / size
    assert err <= 1e-8, err


# ---------------------------------------------------------------- the FMU's features


def _ref_observables(ref: ExactSolution, t0: float, t1: float) -> tuple[float, float, float]:
    """Exact x_max, x_min and stuck time over [t0, t1]: x is monotone in each segment."""
    ts = [t0, t1] + [s.t0 for s in ref.segments if t0 < s.t0 < t1]
    x = ref.evaluate(np.array(ts))[0]
    stuck = sum(max(0.0, min(s.t1, t1) - max(s.t0, t0)) for s in ref.segments if s.mode == 0)
    return float(x.max()), float(x.min()), stuck


@pytest.mark.parametrize("name", ["stick-dominated", "chi-small", "heavy-friction"])
def test_observables_are_exact(fmu: OscillatorFMU2, name: str) -> None:
    p, _ = CASES[name]
    T = p.period
    obs = fmu.observables(p, t_stop=12.0 * T, t_obs_start=7.3 * T, t_obs_stop=11.6 * T, settings=EXACT)
    ref = solve_exact(p, 12.0 * T)
    xmax, xmin, stuck = _ref_observables(ref, 7.3 * T, 11.6 * T)
    size = max(abs(xmax), abs(xmin))
    assert abs(obs["x_max"] - xmax) <= RTOL * size and abs(obs["x_min"] - xmin) <= RTOL * size
    assert abs(obs["stick_fraction"] - stuck / (4.3 * T)) <= 1e-9
    n = sum(1 for s in ref.segments[1:] if 7.3 * T < s.t0 <= 11.6 * T)
    assert obs["transitions"] == n


def test_h_has_no_effect_and_states_continue_bit_for_bit(fmu: OscillatorFMU2) -> None:
    p, _ = CASES["chi-small"]
    t = np.linspace(0.0, 5.0 * p.period, 201)
    a = fmu.trajectory(p, t, Settings(scheme="exact", h=p.period / 1000))
    b = fmu.trajectory(p, t, Settings(scheme="exact", h=p.period / 37))
    for k in ("x", "v", "a", "F_friction", "mode"):
        assert np.array_equal(a[k], b[k]), k
    fmu.start(p, Settings(scheme="exact", observe=True))
    fmu.step_to(1.3 * p.period)
    t1 = fmu.time
    state = fmu.get_state()
    data = fmu.serialize_state(state)
    names = ["x", "v", "a", "F_friction", "x_max", "x_min", "stick_fraction", "E_friction"]

    def run() -> list[float]:
        vals = []
        for k in range(1, 40):
            fmu.step_to(t1 + 0.09 * k * p.period)
            vals.extend(fmu.get(names).values())
        return vals

    first = run()
    fmu.set_state(state)
    assert fmu.time == t1
    assert run() == first
    fmu.restore(data)
    assert run() == first
    state.free()


def test_switch_log_and_bad_input(fmu: OscillatorFMU2) -> None:
    p, _ = CASES["stick-dominated"]
    n0 = len(fmu.messages)
    fmu.trajectory(p, [0.0, 3.0 * p.period], EXACT)
    ev = _events(fmu, n0)
    ref = solve_exact(p, 3.0 * p.period)
    assert len(ev) == len(ref.segments) - 1
    for e, seg0, seg1 in zip(ev, ref.segments, ref.segments[1:]):
        assert (e[1], e[2]) == (seg0.mode, seg1.mode)
        assert abs(e[0] - seg1.t0) <= EVENT_RTOL * p.period
    fmu.start(Oscillator(**{**p.as_dict(), "k": 0.0}), EXACT)   # k = 0: tests/test_exact_free.py
    bad = Settings(scheme="exact", t_obs_start=1.0, t_obs_stop=0.5)
    with pytest.raises(FMUError, match="observation window is empty"):
        fmu.start(p, bad)


@pytest.mark.parametrize("kw", [
    dict(lam=1.0, z0=1.0, dz0=0.0, phi=0.0),        # at rest, zero force and zero force rate: moves at once
    dict(lam=1.0, z0=0.0, dz0=-3.46e-246, phi=1.0),  # a velocity below rounding against the force
    dict(lam=2.0, z0=0.0, dz0=0.0, phi=0.0),         # v touches 0 once per period
])
def test_without_friction_the_block_never_sticks(fmu: OscillatorFMU2, kw: dict) -> None:
    p = ND(mu_s_sigma=0.0, chi=1.0, **kw)
    err, n = _compare(fmu, p, periods=30.0, per_period=10)
    assert err <= RTOL and n >= 59
