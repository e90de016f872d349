"""FMI 3.0 events: early return lands on every stick/slip switch; the switch times against the
exact solution (located scheme: second order, measured below); event mode's left and right limits
against the exact solution; fmpy's simulate_fmu with early_return_allowed / use_event_mode records
samples at the switches; the intermediate update's early-return request. (fmi3UpdateDiscreteStates'
rules and FMU states in event mode: test_fmi3_api.py.)"""

from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy import simulate_fmu

from dryfriction.references.exact import solve_exact
from dryfriction.drivers.oscillator3 import OscillatorFMU3
from dryfriction.params import Oscillator

from fmi3_helpers import DT, FMU2, FMU3, fmi2_switches, kinds, scheme_names, schemes


P = Oscillator()  # stick-slip with reversals, stops and breakaways
T = 2 * math.pi / P.omega
T_END = 4 * T


@pytest.fixture(scope="module")
def exact():
    return solve_exact(P, T_END)


def early_return_run(scheme: int, h: float, event_mode: bool = False):
    with OscillatorFMU3({"scheme": scheme, "h": h}, early_return=True, event_mode=event_mode) as fmu:
        return fmu.run(T_END, DT, outputs=("x", "v", "mode"))


# An early return lands on a switch by stepping again from the step's start to the switch time: the
# located root of that shorter run agrees with the plain run's to a few ulps of t (measured: up to 8
# with the derived default step).
LANDING_ULPS = 16


def ulps(t: np.ndarray) -> np.ndarray:
    return np.spacing(np.abs(t))


@pytest.mark.parametrize("scheme", schemes())
def test_early_return_lands_on_every_switch(scheme: int) -> None:
    """Every switch the FMI 2.0 FMU's event log reports on the same host grid is an early return,
    at its time (to a few ulps), with the same modes."""
    h = T / 1000
    ref = fmi2_switches({"scheme": scheme, "h": h}, T_END, DT)
    run = early_return_run(scheme, h)
    assert len(ref) >= 10
    assert [(a, b) for _, a, b in ref] == [(s.mode_before, s.mode_after) for s in run.switches]
    t_ref = np.array([t for t, _, _ in ref])
    assert np.all(np.abs(run.switch_times - t_ref) <= LANDING_ULPS * ulps(t_ref)), np.abs(run.switch_times - t_ref).max()
    # the samples: the mode changes only at the switches, and every switch is a sample
    changed = run.time[1:][np.diff(run.values["mode"]) != 0]
    np.testing.assert_array_equal(changed, run.switch_times)


def switch_error(scheme: int, h: float, exact) -> float:
    run = early_return_run(scheme, h)
    t_ex = exact.switch_times()
    assert len(run.switches) == len(t_ex), (len(run.switches), len(t_ex))
    m = exact.modes()
    assert [(s.mode_before, s.mode_after) for s in run.switches] == list(zip(m[:-1], m[1:]))
    return float(np.max(np.abs(run.switch_times - t_ex)))


def test_located_switch_times_against_exact_second_order(exact) -> None:
    """Measured: max |t_switch - t_exact| over the 12 switches of 4 periods = 1.20e-3 s at h = T/100,
    1.26e-5 s at h = T/1000 (1.0e-5 T), 1.27e-7 s at h = T/10^4: order 2.0."""
    located = next(v for v, n in scheme_names().items() if n == "located")
    e = [switch_error(located, T / n, exact) for n in (100, 1000, 10000)]
    assert e[1] < 2e-5
    orders = np.log10(np.array(e[:-1]) / np.array(e[1:]))
    assert np.all((orders > 1.8) & (orders < 2.3)), (e, orders)
    # the run holds every kind of switch (switch_error checked the modes of each against the exact ones)
    assert set(kinds(list(zip(exact.modes()[:-1], exact.modes()[1:])))) == {"reversal", "stop", "breakaway"}


def test_exact_scheme_switch_times_if_present(exact) -> None:
    names = scheme_names()
    if "exact" not in names.values():
        pytest.skip("no exact scheme in the Scheme enumeration of this build")
    scheme = next(v for v, n in names.items() if n == "exact")
    assert switch_error(scheme, T / 1000, exact) < 1e-9


def test_event_mode_limits_against_exact(exact) -> None:
    """Left limits (the old mode, its friction force and acceleration) before
    fmi3UpdateDiscreteStates, right limits after it, against the exact solution at its switch."""
    located = next(v for v, n in scheme_names().items() if n == "located")
    run = early_return_run(located, T / 1000, event_mode=True)
    t_ex, m = exact.switch_times(), exact.modes()
    assert len(run.switches) == len(t_ex)
    muk_N, Fb = P.mu_k * P.N, max(P.mu_s, P.mu_k) * P.N
    seen = set()
    for sw, te, before, after in zip(run.switches, t_ex, m[:-1], m[1:]):
        assert (sw.mode_before, sw.mode_after) == (before, after)
        seen.add(sw.kind)
        _, _, a_right_ex, _ = exact.evaluate(np.array([te]))
        _, _, a_left_ex, _ = exact.evaluate(np.array([te - 1e-9]))
        if before != 0:  # sliding up to the switch: kinetic friction, the slide's acceleration
            assert sw.F_left == pytest.approx(-before * muk_N, rel=1e-14)
            assert sw.a_left == pytest.approx(a_left_ex[0], abs=1e-3)
        else:  # stuck up to a breakaway: the static force at the limit, at rest
            assert sw.F_left == pytest.approx(-after * Fb, rel=1e-9)
            assert sw.a_left == 0.0
        if after != 0:  # sliding from the switch (breakaway: the force jumps to the kinetic value)
            assert sw.F_right == pytest.approx(-after * muk_N, rel=1e-14)
            assert sw.a_right == pytest.approx(a_right_ex[0], abs=1e-3)
        else:  # a stop: the static force holds the block
            assert sw.F_right == pytest.approx(exact.friction(np.array([te]))[0], abs=1e-3)
            assert abs(sw.F_right) <= Fb
            assert sw.a_right == 0.0
    assert seen == {"reversal", "stop", "breakaway"}


@pytest.mark.min_versions
def test_simulate_fmu_early_return_records_the_switches() -> None:
    ref = fmi2_switches({}, T_END, DT)
    out = simulate_fmu(str(FMU3), stop_time=T_END, output_interval=DT, early_return_allowed=True,
                       output=["x", "mode"])
    t, mode = out["time"], out["mode"]
    changed = t[1:][np.diff(mode) != 0]
    t_ref = np.array([s[0] for s in ref])
    assert len(changed) == len(t_ref)
    assert np.all(np.abs(changed - t_ref) <= LANDING_ULPS * ulps(t_ref))
    assert len(t) == math.ceil(T_END / DT) + 1 + len(t_ref)  # the grid, the stop time, one sample per switch


@pytest.mark.min_versions
def test_simulate_fmu_event_mode_records_left_and_right_limits() -> None:
    ref = fmi2_switches({}, T_END, DT)
    out = simulate_fmu(str(FMU3), stop_time=T_END, output_interval=DT, early_return_allowed=True,
                       use_event_mode=True, output=["mode", "F_friction"])
    t = out["time"]
    twice = t[1:][np.diff(t) == 0]  # a sample before and one after each event
    t_ref = np.array([s[0] for s in ref])
    assert len(twice) == len(t_ref)
    assert np.all(np.abs(twice - t_ref) <= LANDING_ULPS * ulps(t_ref))
    i = np.nonzero(np.diff(t) == 0)[0]
    assert list(zip(out["mode"][i], out["mode"][i + 1])) == [(a, b) for _, a, b in ref]


def test_event_mode_without_early_return_is_plain_stepping() -> None:
    """Documented choice: without early return, events are handled inside the step (FMI 2.0's
    outputs), and fmi3DoStep never asks for event handling."""
    o3 = simulate_fmu(str(FMU3), stop_time=T_END, output_interval=DT, use_event_mode=True, output=["x", "mode"])
    o2 = simulate_fmu(str(FMU2), stop_time=T_END, output_interval=DT, output=["x", "mode"])
    np.testing.assert_array_equal(o3["x"], o2["x"])
    np.testing.assert_array_equal(o3["mode"], o2["mode"])


def test_intermediate_update_early_return_request_honoured() -> None:
    """With early return allowed and a callback, the step goes on through the switches until the
    callback requests the return: here at the second switch."""
    calls: list[tuple[float, bool]] = []
    # h = DT / 100: the reference's communication points fall on the internal grid, so that its steps
    # are the one long step's steps
    grid = {"h": DT / 100}
    fmu = OscillatorFMU3(grid, early_return=True, intermediate=lambda t, can: calls.append((t, can)) or len(calls) == 2)
    try:
        event, early = fmu.do_step(T_END / 2)
        assert early and not event
        assert len(calls) == 2 and all(can for _, can in calls)
        assert fmu.time == calls[1][0]
        ref = fmi2_switches(grid, T_END, DT)
        assert abs(calls[0][0] - ref[0][0]) <= 4 * np.spacing(ref[0][0])
        assert abs(calls[1][0] - ref[1][0]) <= 4 * np.spacing(ref[1][0])
    finally:
        fmu.close()
