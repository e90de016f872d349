"""Model Exchange of the oscillator's and the chain's FMUs (FMI 2.0 and 3.0): the host integrates x and v.

What is asserted, against independent numbers:
- the descriptions declare <ModelExchange> beside an unchanged <CoSimulation>: the states, their
  derivatives, two event indicators (FMI 3.0: <ContinuousStateDerivative>, <EventIndicator>);
- the derivatives against the equation of motion written here (sliding: (P - k x - c v - mode mu_k
  N) / m; stuck: 0), the event indicators against the relative velocity and the breakaway margins
  mu_b N -+ F_static computed here, and the event update against the rest rule: a stop sets v to the
  belt's speed, sticks or reverses in one update (no iteration), a breakaway slides; right after
  every switch no indicator is 0 (the hysteresis); errors name the argument and its valid value;
- fmpy's CVode and Euler run to the end with the defaults; with CVode at relative tolerance 1e-10
  the five work-precision cases (bench/cases.py) over 20 periods stay within 1e-7 of the exact
  solution (dryfriction.references.exact) with exactly its switches, at the times it gives within
  the error the stuck position's error allows (1e-8 at relative tolerance 1e-12); the moving belt
  and Stribeck's law against the co-simulation schemes (exact, located at a fine step);
- the hosts fmusim (CVODE and Euler, both FMI versions) and the Compliance Checker's Model Exchange
  run: to the end, no warning, the events of the exact solution (fmusim's CVODE at 1e-10);
- the chain's likewise (FMI 3.0 with n set in Configuration Mode, dryfriction.drivers.chain_me): the
  derivatives against M a = P - K x - C v + F written here (stuck blocks held), the indicators against
  the relative velocities and each stuck block's margins, a breakaway, a stop and a reversal in one
  update each; CVode at 1e-10 and 1e-12 on stick-slip chains of 3 to 5 blocks against the event-driven
  reference (dryfriction.references.chain: x, switch count and times); the belts and Stribeck's law
  against co-simulation; fmpy's, fmusim's and the Compliance Checker's runs of the default chain;
- the FMIZoo friction pendulum (SpringFrictionPendulum1D: the Modelica Standard Library's
  MassWithStopAndFriction on a spring, dryfriction.drivers.modelica): the mapped FMU's friction force
  and acceleration at four speeds against the element's equations written here, its holding force
  and margins; Model Exchange (CVode 1e-10) and the located scheme against the event-driven reference
  (dryfriction.references.belt: s(8), the four reversals and the stick) and Dymola's published s(8).
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
import zipfile
from dataclasses import replace
from ctypes import POINTER, c_double, c_int, c_void_p
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model

from chain_cases import CASES as CHAIN_CASES
from dryfriction.drivers.chain import default_chain_fmu, default_chain_fmu3
from dryfriction.drivers.chain_me import chain_me_description, simulate_chain_me
from dryfriction.drivers.modelica import DYMOLA_S_AT_8, SpringFrictionPendulum
from dryfriction.drivers.oscillator import default_fmu_path
from dryfriction.drivers.oscillator3 import default_fmi3_path
from dryfriction.params import Oscillator
from dryfriction.references.belt import Belt, simulate as simulate_belt
from dryfriction.references.chain import Chain, solve_chain
from dryfriction.references.exact import solve_exact
from fmi2_helpers import Counting
from refcache import RefCache
from test_hosts import fmucheck, fmusim

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
from cases import CASES  # noqa: E402  (bench/cases.py: the work-precision cases)

DBL_MIN = sys.float_info.min
PERIODS = 20


def _fmu(version: int) -> Path:
    path = default_fmu_path() if version == 2 else default_fmi3_path()
    if not path.is_file():
        pytest.skip(f"did not run: {path} not built")
    return path


def _mode_changes(result: np.ndarray) -> tuple[np.ndarray, int]:
    """The times where fmpy's recorded mode changes (fmpy records both sides of every event), and how many."""
    idx = np.nonzero(np.diff(result["mode"]))[0] + 1
    return result["time"][idx], len(idx)


# --------------------------------------------------------------------------- the descriptions


@pytest.mark.parametrize("version", [2, 3])
def test_descriptions_declare_model_exchange(version: int) -> None:
    md = read_model_description(str(_fmu(version)))
    assert md.modelExchange is not None and md.coSimulation is not None
    assert md.modelExchange.modelIdentifier == md.coSimulation.modelIdentifier == "DryFrictionOscillator"
    assert [(d.variable.name, d.variable.derivative.name) for d in md.derivatives] == [("v", "x"), ("a", "v")]
    assert [u.variable.name for u in md.outputs][:3] == ["x", "v", "a"]
    if version == 2:
        assert md.numberOfEventIndicators == 2
    else:
        assert [e.variable.name for e in md.eventIndicators] == ["event_indicator_0", "event_indicator_1"]
    # co-simulation's capabilities are those it had
    cs = md.coSimulation
    assert cs.canHandleVariableCommunicationStepSize and cs.canGetAndSetFMUstate and cs.canSerializeFMUstate


def test_descriptions_are_valid() -> None:
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(_fmu(3))) == []
    assert validate_fmu(str(_fmu(2))) == []


# --------------------------------------------------------------------------- one instance, by hand


class Host:
    """What a host does with one Model Exchange instance ``f`` of nx states: read its arrays, handle
    an event (its update ``update`` once, no iteration); ``derivatives_fn`` reads the derivatives."""

    f: Any
    nx: int
    update: Any
    derivatives_fn: Any

    def event(self) -> tuple[Any, ...]:
        info = self.update()
        assert not info[0], "no event iteration"
        return info

    def arr(self, getter: Any, size: int | None = None) -> np.ndarray:
        a = np.zeros(self.nx if size is None else size)
        getter(a.ctypes.data_as(POINTER(c_double)), a.size)
        return a

    def states(self) -> np.ndarray:
        return self.arr(self.f.getContinuousStates)

    def derivatives(self) -> np.ndarray:
        return self.arr(self.derivatives_fn)

    def indicators(self) -> np.ndarray:
        return self.arr(self.f.getEventIndicators)

    def put(self, t: float, state: np.ndarray) -> None:
        self.f.setTime(t)
        self.f.setContinuousStates(state.ctypes.data_as(POINTER(c_double)), state.size)

    def switch(self) -> tuple[Any, ...]:
        """An event now: event mode, the update, back to continuous time."""
        self.f.enterEventMode()
        info = self.event()
        self.f.enterContinuousTimeMode()
        return info


class ME(Host):
    """One FMI 2.0 Model Exchange instance through fmpy's FMU2Model, with the counting logger."""

    def __init__(self, tmp: Path, **start: float) -> None:
        path = _fmu(2)
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        d = extract(str(path), unzipdir=str(tmp / "me"))
        self.cb = Counting()
        self.f = FMU2Model(guid=self.md.guid, unzipDirectory=d, modelIdentifier="DryFrictionOscillator",
                           instanceName="me")
        self.nx, self.update, self.derivatives_fn = 2, self.f.newDiscreteStates, self.f.getDerivatives
        self.f.instantiate(callbacks=self.cb.struct)
        self.f.setupExperiment(startTime=0.0)
        ints = {n: int(v) for n, v in start.items() if n in ("friction_law", "scheme")}  # Enumeration, Integer
        reals = {n: v for n, v in start.items() if n not in ints}
        if reals:
            self.f.setReal([self.vr[n] for n in reals], list(reals.values()))
        if ints:
            self.f.setInteger([self.vr[n] for n in ints], list(ints.values()))
        self.f.enterInitializationMode()
        self.f.exitInitializationMode()
        self.event()
        self.f.enterContinuousTimeMode()

    def set(self, t: float, x: float, v: float) -> None:
        self.put(t, np.array([x, v]))

    def mode(self) -> int:
        return self.f.getInteger([self.vr["mode"]])[0]


@pytest.fixture
def me(tmp_path: Path) -> Iterator[ME]:
    inst = ME(tmp_path)
    yield inst
    inst.f.terminate()
    inst.f.freeInstance()


def test_derivatives_indicators_and_switches_by_hand(me: ME) -> None:
    """The default oscillator (m 1, k 100, P0 1, omega 5, N 1, mu_s 0.4, chi 0.7): P(0) = 1 N > mu_s N
    at rest, so it starts sliding forward from v = 0, where the relative velocity is 0."""
    o = Oscillator()
    mu_k, Fb = o.chi * o.mu_s * o.N, o.mu_s * o.N

    def accel(t: float, x: float, v: float, mode: int) -> float:
        return (o.P0 * math.cos(o.omega * t + o.phi) - o.k * x - o.c * v - mode * mu_k) / o.m

    assert me.mode() == 1
    assert list(me.indicators()) == [DBL_MIN, 1.0]  # the hysteresis: not 0 right after the start of the slide
    assert list(me.derivatives()) == pytest.approx([0.0, accel(0.0, 0.0, 0.0, 1)], rel=1e-15)
    # sliding forward at t = 0.3: the derivatives and the relative velocity
    me.set(0.3, 0.004, 0.02)
    assert me.derivatives() == pytest.approx([0.02, accel(0.3, 0.004, 0.02, 1)], rel=1e-14)
    assert me.indicators()[0] == pytest.approx(0.02, rel=1e-15)
    # the velocity crossed 0 where the static force P - k x = 1 - 0.8 = 0.2 N is held: it sticks, v = 0
    me.set(0.0, 0.008, -1e-9)
    assert me.indicators()[0] < 0
    info = me.switch()
    assert info[3]  # valuesOfContinuousStatesChanged: v was set
    assert me.mode() == 0 and list(me.states()) == [0.008, 0.0]
    Fs = o.P0 - o.k * 0.008
    assert me.indicators() == pytest.approx([Fb - Fs, Fb + Fs], rel=1e-14)
    assert min(me.indicators()) > 0  # not 0 right after the stick
    assert list(me.derivatives()) == [0.0, 0.0]
    assert me.f.getReal([me.vr["F_friction"]])[0] == pytest.approx(-Fs, rel=1e-14)  # the holding force
    # stuck at x = 0.015 the static force is -0.5 N beyond -Fb: the backward margin is negative; the
    # update breaks away backward, x and v unchanged, the slide's indicator DBL_MIN
    me.set(0.0, 0.015, 0.0)
    assert me.indicators()[1] == pytest.approx(Fb + (o.P0 - o.k * 0.015), rel=1e-14) and me.indicators()[1] < 0
    me.switch()
    assert me.mode() == -1 and list(me.states()) == [0.015, 0.0]
    assert list(me.indicators()) == [DBL_MIN, 1.0]
    assert me.derivatives()[1] == pytest.approx(accel(0.0, 0.015, 0.0, -1), rel=1e-14)
    # a reversal: sliding backward, the velocity crossed 0 at x = 0, where the static force P - k x = 1 N
    # beyond Fb pushes forward: one update, forward slip from v = 0
    me.set(0.0, 0.0, 1e-9)
    assert me.indicators()[0] < 0
    info = me.switch()
    assert info[3] and me.mode() == 1 and list(me.states()) == [0.0, 0.0]
    assert list(me.indicators()) == [DBL_MIN, 1.0]
    # an event with nothing to switch changes nothing
    me.set(0.1, 0.001, 0.01)
    info = me.switch()
    assert not info[3] and me.mode() == 1 and list(me.states()) == [0.001, 0.01]
    # what Model Exchange does not compute reads NaN, with one sentence
    assert math.isnan(me.f.getReal([me.vr["x_max"]])[0])
    assert any("not computed in Model Exchange" in m for _, _, m in me.cb.messages)


def test_errors_name_the_argument(me: ME) -> None:
    z = np.zeros(3)
    with pytest.raises(FMICallException):
        me.f.getEventIndicators(z.ctypes.data_as(POINTER(c_double)), 3)
    assert "ni = 3" in me.cb.last_error() and "must be 2" in me.cb.last_error()
    with pytest.raises(FMICallException):
        me.f.getDerivatives(z.ctypes.data_as(POINTER(c_double)), 1)
    assert "nx = 1" in me.cb.last_error() and "must be 2" in me.cb.last_error()
    bad = np.array([0.0, math.nan])
    with pytest.raises(FMICallException):
        me.f.setContinuousStates(bad.ctypes.data_as(POINTER(c_double)), 2)
    assert "not finite" in me.cb.last_error()
    do_step = me.f.dll.fmi2DoStep  # not bound by FMU2Model
    do_step.argtypes, do_step.restype = [c_void_p, c_double, c_double, c_int], c_int
    assert do_step(me.f.component, 0.0, 0.01, 1) == 3  # fmi2Error
    assert "made for Model Exchange" in me.cb.last_error()


# --------------------------------------------------------------------------- hosts through fmpy


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("solver", ["CVode", "Euler"])
def test_fmpy_runs_to_the_end(version: int, solver: str) -> None:
    r = simulate_fmu(str(_fmu(version)), fmi_type="ModelExchange", solver=solver, output=["x", "v", "mode"])
    assert r["time"][-1] == pytest.approx(12.56, abs=1e-12)
    assert np.all(np.isfinite(r["x"])) and np.all(np.isfinite(r["v"]))
    times, n = _mode_changes(r)
    assert n > 0 and np.all(np.diff(times) > 0)  # one switch per event: never two at one time (no chattering)
    if solver == "CVode":  # default tolerance 1e-4: the exact solution's 29 switches, x within 1e-4
        ex = solve_exact(Oscillator(), 12.56)
        assert n == len(ex.switch_times()) == 29
        assert abs(r["x"][-1] - ex.evaluate(np.array([12.56]))[0][0]) < 1e-4


@pytest.fixture(scope="module")
def exact_cases() -> dict[str, Any]:
    return {c.name: solve_exact(c.oscillator, PERIODS * c.oscillator.period) for c in CASES}


def _me_case(case: Any, rtol: float, version: int = 2) -> np.ndarray:
    o = case.oscillator
    return simulate_fmu(str(_fmu(version)), fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol,
                        stop_time=PERIODS * o.period, output_interval=o.period / 100, start_values=o.as_dict(),
                        output=["x", "mode"])


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_cvode_accuracy_on_the_work_precision_cases(case: Any, exact_cases: dict[str, Any]) -> None:
    """CVode at 1e-10: x within 1e-7 of the exact solution over 20 periods, its switches exactly,
    their times within 3e-7: a breakaway's time error is the stuck position's error over the static
    force's rate, k dx / |dF/dt| (measured at most 1.3e-7 s, chi_near_0; at a stop the velocity's error
    over the deceleration, at most 1.7e-8 s). At 1e-12 every time is within 1e-8."""
    ex = exact_cases[case.name]
    sw = ex.switch_times()
    for rtol, t_tol in ((1e-10, 3e-7), (1e-12, 1e-8)):
        r = _me_case(case, rtol)
        t = r["time"]
        x_exact = ex.evaluate(np.minimum(t, ex.t_end))[0]
        assert np.max(np.abs(r["x"] - x_exact)) < (1e-7 if rtol == 1e-10 else 1e-9)
        times, n = _mode_changes(r)
        assert n == len(sw)
        assert np.max(np.abs(times - sw)) < t_tol


def test_fmi3_gives_fmi2s_numbers() -> None:
    case = CASES[0]
    r2, r3 = _me_case(case, 1e-10, 2), _me_case(case, 1e-10, 3)
    assert np.array_equal(r2["time"], r3["time"]) and np.array_equal(r2["x"], r3["x"])


def _against_cs(start: dict[str, float], t_end: float) -> tuple[float, int, int]:
    fmu = str(_fmu(2))
    me = simulate_fmu(fmu, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10, stop_time=t_end,
                      output_interval=0.01, start_values=start, output=["x", "mode"])
    cs = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=t_end, output_interval=0.01, start_values=start,
                      output=["x", "transitions"])
    t, first = np.unique(me["time"], return_index=True)  # the left side of each event
    x = np.interp(cs["time"], t, me["x"][first])
    return float(np.max(np.abs(x - cs["x"]))), _mode_changes(me)[1], int(cs["transitions"][-1])


@pytest.mark.parametrize("start", [
    {"scheme": 4, "v_belt": 0.05},
    {"scheme": 4, "v_belt": -0.05, "c": 0.1},
    {"scheme": 3, "h": 2e-5, "friction_law": 2, "v_belt": 0.05, "P0": 0.0, "v_s": 0.01},
    {"scheme": 3, "h": 2e-5, "friction_law": 2}],
    ids=["belt", "belt-backward-damped", "stribeck-belt-self-excited", "stribeck-forced"])
def test_belt_and_stribeck_against_cosimulation(start: dict[str, float]) -> None:
    """The moving belt and Stribeck's law as in co-simulation: against the exact scheme (Coulomb)
    within 1e-8, the located scheme at h = 2e-5 (Stribeck, second order: its own error ~1e-8) within
    1e-7, with the same number of switches."""
    err, n_me, n_cs = _against_cs(start, 4.0)
    assert n_me == n_cs > 0
    assert err < (1e-8 if start["scheme"] == 4 else 1e-7)


# --------------------------------------------------------------------------- the FMIZoo friction pendulum
# SpringFrictionPendulum1D (Dymola, SimulationX): MassWithStopAndFriction on a spring, mapped by
# dryfriction.drivers.modelica (docs/model_exchange.md, "The FMIZoo friction pendulum").

ZOO = SpringFrictionPendulum()
ZOO_T_END = 8.0


def test_pendulum_mapping_gives_the_modelica_forces(tmp_path: Path) -> None:
    """The mapped FMU's forces are the element's, read through the FMU: sliding forward at speeds
    1e-3 ... 2 m/s its F_friction is -(0.25 + 0.5 exp(-2 v)) and its acceleration the element's
    -(10 (s - 1) + f) / m, f = 0.05 v + 0.25 + 0.5 exp(-2 v) (viscous term in c, not in
    F_friction); stuck at s = 1.06 it holds 0.6 N with the breakaway margins 0.75 -+ (-0.6) N:
    our limit F_Coulomb + F_Stribeck, not the element's 1.001 times it."""
    start = ZOO.start_values()
    assert start["mu_s"] * start["N"] == 0.75 and start["chi"] * start["mu_s"] * start["N"] == 0.25
    assert (start["v_s"], start["delta"], start["F_ext"], start["c"]) == (0.5, 1.0, 10.0, 0.05)
    inst = ME(tmp_path, **start)
    try:
        assert inst.mode() == 1  # at rest at s = 0.5 the spring's 5 N > 0.75 N: a forward slide
        for s, v in [(0.6, 1e-3), (0.7, 0.1), (0.9, 0.5), (1.2, 2.0)]:
            inst.set(0.5, s, v)
            f_msl = 0.05 * v + 0.25 + 0.5 * math.exp(-2.0 * v)
            assert ZOO.friction(v) == pytest.approx(f_msl, rel=1e-15)
            assert inst.f.getReal([inst.vr["F_friction"]])[0] == pytest.approx(-(f_msl - 0.05 * v), rel=1e-14)
            assert inst.derivatives() == pytest.approx([v, -(10.0 * (s - 1.0) + f_msl)], rel=1e-14)
        inst.set(0.5, 1.06, -1e-12)  # the forward slide stops at s = 1.06: the spring pulls back 0.6 N
        inst.switch()
        assert inst.mode() == 0 and list(inst.states()) == [1.06, 0.0]
        assert inst.f.getReal([inst.vr["F_friction"]])[0] == pytest.approx(0.6, rel=1e-13)
        assert inst.indicators() == pytest.approx([0.75 + 0.6, 0.75 - 0.6], rel=1e-13)
    finally:
        inst.f.terminate()
        inst.f.freeInstance()


def test_pendulum_mapping_edges() -> None:
    """Without the Stribeck term (or with fexp = 0, where it is constant) the law is Coulomb's at
    F_Coulomb (+ F_Stribeck); without friction mu_s = 0; bad values and a motion that may reach the
    hard stops are refused in one line that names the value."""
    assert SpringFrictionPendulum(F_Stribeck=0.0).start_values() == {
        "m": 1.0, "k": 10.0, "c": 0.05, "P0": 0.0, "N": 1.0, "x0": 0.5, "v0": 0.0, "F_ext": 10.0,
        "mu_s": 0.25, "chi": 1.0}
    assert SpringFrictionPendulum(fexp=0.0).start_values()["mu_s"] == 0.75
    assert "friction_law" not in SpringFrictionPendulum(fexp=0.0).start_values()
    assert SpringFrictionPendulum(F_Coulomb=0.0, F_Stribeck=0.0).start_values()["mu_s"] == 0.0
    assert SpringFrictionPendulum(s0=-24.0).reaches_stops and not SpringFrictionPendulum().reaches_stops  # 1 + 25 > 25
    for kw, text in [({"m": 0.0}, "m must be > 0, not 0.0"), ({"F_Coulomb": -1.0}, "F_Coulomb must be >= 0"),
                     ({"s0": 30.0}, "s0 = 30.0 must lie strictly between smin = -25.0")]:
        with pytest.raises(ValueError, match=re.escape(text)):
            SpringFrictionPendulum(**kw)
    with pytest.raises(ValueError, match="may reach a hard stop"):
        SpringFrictionPendulum(s0=-24.0).start_values()


@pytest.fixture(scope="module")
def zoo_reference() -> Any:
    """The event-driven reference (dryfriction.references.belt: DOP853 at rtol 1e-12 between the
    events, none of the FMU's code) of the mapped pendulum over 8 s."""
    st = ZOO.start_values()
    b = Belt(m=st["m"], k=st["k"], c=st["c"], N=1.0, mu_s=0.75, mu_k=0.25, F_ext=st["F_ext"], x0=st["x0"],
             v0=st["v0"], law="stribeck", v_s=st["v_s"], delta=st["delta"])
    return simulate_belt(b, np.linspace(0.0, ZOO_T_END, 801))


def test_pendulum_model_exchange_and_cosimulation_against_dymola(zoo_reference: Any) -> None:
    """Our Model Exchange FMU under fmpy's CVode (rtol 1e-10) and the located co-simulation scheme
    (h = 2e-5; scheme exact takes Coulomb friction only) against the event-driven reference and
    each other: four reversals (0.99401, 1.98831, 2.98313, 3.97897 s) and the stop at 4.977132 s, stuck
    from then on at s = 1.0668709533 (measured: ME 3.6e-8 off, its switch times within 5.6e-9 s; CS 4e-10).

    Against the published Dymola s(8) = 1.06736 (DYMOLA_S_AT_8): 4.9e-4 m. The element's own
    conventions decide nothing here: the stops' static forces 4.254, 3.483, 2.664, 1.756 and 0.669 N
    lie at least 0.081 N from the band (0.75, 0.75075] N where its 0.1 % breakaway margin would stick
    a block ours slides on, its v_small plays no part at stops located at v = 0, and its Stribeck
    term is ours at v_s = 1 / fexp, delta = 1. The difference is the integration error at
    Dymola's FMU's default tolerance 1e-4: the stuck position carries the error of five swings
    (our own CVode at rtol 1e-4 ends 2.2e-3 off, at 1e-5 2.5e-4 off), so the bound is 1e-3
    (0.1 %); without the Stribeck term the block ends 0.114 m away, with v_s = 2 m/s 0.043 m."""
    ref = zoo_reference
    s_ref = ref.x[-1]
    stops = [t for t, _ in ref.events]
    assert [k for _, k in ref.events] == ["reversal"] * 4 + ["stop"] and ref.mode[-1] == 0
    # the conventions that differ, in numbers: every stop's static force far from the margin's band
    f_stop = np.abs(ZOO.c_spring * (np.interp(stops, ref.t, ref.x) - ZOO.s_rel0))
    assert np.min(np.abs(f_stop - ZOO.breakaway)) > 0.08 and ZOO.msl_breakaway - ZOO.breakaway == pytest.approx(7.5e-4)
    assert f_stop[-1] < ZOO.breakaway  # the last stop sticks by either rule
    fmu, start = str(_fmu(2)), ZOO.start_values()
    me = simulate_fmu(fmu, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10, stop_time=ZOO_T_END,
                      output_interval=0.01, start_values=start, output=["x", "v", "mode"])
    cs = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=ZOO_T_END, output_interval=0.01,
                      start_values={**start, "scheme": 3, "h": 2e-5}, output=["x", "mode", "transitions"])
    times, n = _mode_changes(me)
    assert n == 5 and np.max(np.abs(times - stops)) < 2e-8
    assert me["mode"][-1] == cs["mode"][-1] == 0 and cs["transitions"][-1] == 5
    assert abs(me["x"][-1] - s_ref) < 1e-7 and abs(cs["x"][-1] - s_ref) < 1e-8
    assert abs(me["x"][-1] - cs["x"][-1]) < 1e-7
    assert abs(me["x"][-1] - DYMOLA_S_AT_8) < 1e-3
    # the bound discriminates: a wrong mapping misses Dymola's value by far more
    for wrong in (replace(ZOO, F_Stribeck=0.0), replace(ZOO, fexp=0.5)):
        r = simulate_fmu(fmu, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                         stop_time=ZOO_T_END, start_values=wrong.start_values(), output=["x"])
        assert abs(r["x"][-1] - DYMOLA_S_AT_8) > 1e-2


# --------------------------------------------------------------------------- external hosts


def _csv(path: Path) -> dict[str, np.ndarray]:
    data = np.genfromtxt(path, delimiter=",", names=True)
    return {n: data[n] for n in data.dtype.names}


@pytest.mark.slow
@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("solver", ["cvode", "euler"])
def test_fmusim_model_exchange(version: int, solver: str, tmp_path: Path) -> None:
    out = tmp_path / "out.csv"
    args = [str(fmusim()), "--interface-type", "me", "--solver", solver, "--output-file", str(out)]
    if solver == "cvode":
        args += ["--tolerance", "1e-10"]
    r = subprocess.run(args + [str(_fmu(version))], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "[WARNING]" not in r.stdout + r.stderr and "[ERROR]" not in r.stdout + r.stderr
    d = _csv(out)
    assert d["time"][-1] == pytest.approx(12.56)
    if solver == "cvode":
        ex = solve_exact(Oscillator(), 12.56)
        assert np.count_nonzero(np.diff(d["mode"])) == len(ex.switch_times())
        assert abs(d["x"][-1] - ex.evaluate(np.array([12.56]))[0][0]) < 1e-8


def _fmucheck_me(fmu: Path, h: float, tmp_path: Path) -> Path:
    """The Compliance Checker's Model Exchange run of fmu to 12.56 s at the step h: no warning or
    error; its output file."""
    out, log = tmp_path / "out.csv", tmp_path / "log.txt"
    r = subprocess.run([str(fmucheck()), "-k", "me", "-h", repr(h), "-s", "12.56", "-o", str(out), "-e", str(log),
                        str(fmu)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    text = log.read_text() + r.stdout
    assert "0 warning(s) and error(s)" in text and "0 Error(s)" in text and "0 Warning(s)" in text
    return out


@pytest.mark.slow
def test_compliance_checker_model_exchange(tmp_path: Path) -> None:
    d = _csv(_fmucheck_me(_fmu(2), 0.01, tmp_path))
    assert d["time"][-1] == pytest.approx(12.56) and np.all(np.isfinite(d["x"]))


def test_fmu_state_in_model_exchange(me: ME) -> None:
    """An FMU state taken in continuous-time mode, serialised and restored, gives back the time, the
    states and the mode; the derivatives follow them."""
    me.set(0.0, 0.008, -1e-9)
    me.switch()  # stuck at x = 0.008
    me.set(0.25, 0.008, 0.0)
    d0 = me.derivatives()
    state = me.f.getFMUstate()
    blob = me.f.serializeFMUstate(state)
    me.set(0.0, 0.015, 0.0)
    me.switch()  # broke away backward
    assert me.mode() == -1
    restored = me.f.deSerializeFMUstate(blob)
    me.f.setFMUstate(restored)
    assert me.mode() == 0 and list(me.states()) == [0.008, 0.0]
    assert list(me.derivatives()) == list(d0) == [0.0, 0.0]
    assert me.indicators()[0] == pytest.approx(0.4 - (math.cos(5 * 0.25) - 0.8), rel=1e-13)
    me.f.freeFMUstate(state)
    me.f.freeFMUstate(restored)


# --------------------------------------------------------------------------- the chain


def _chain_fmu(version: int) -> Path:
    path = default_chain_fmu() if version == 2 else default_chain_fmu3()
    if not path.is_file():
        pytest.skip(f"did not run: {path} not built")
    return path


class ChainME(Host):
    """One FMI 3.0 Model Exchange instance of the chain through fmpy's FMU3Model, n set in
    Configuration Mode, the FMU's messages kept."""

    def __init__(self, tmp: Path, ch: Chain, **start: Any) -> None:
        from fmpy.fmi3 import FMU3Model
        path = _chain_fmu(3)
        self.n = n = ch.n
        self.md = chain_me_description(path, n)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []

        def log(env: Any, status: int, category: bytes, message: bytes) -> None:
            self.messages.append(message.decode())

        self.f = FMU3Model(guid=self.md.guid, unzipDirectory=extract(str(path), unzipdir=str(tmp / "chain-me")),
                           modelIdentifier="DryFrictionChain", instanceName="chain-me")
        self.nx, self.update = 2 * n, self.f.updateDiscreteStates
        self.derivatives_fn = self.f.getContinuousStateDerivatives
        self.f.instantiate(logMessage=log)
        self.f.enterConfigurationMode()
        self.f.setUInt64([self.vr["n"]], [n])
        self.f.exitConfigurationMode()
        self.start = {**ch.fmu_params(), **start}

    def init(self) -> None:
        """Initialisation with the parameters, the first event update, continuous-time mode."""
        for name, value in self.start.items():
            vals = value if isinstance(value, list) else [value]
            if isinstance(vals[0], int) and name in ("scheme", "friction_law"):
                self.f.setInt64([self.vr[name]], vals)
            else:
                self.f.setFloat64([self.vr[name]], [float(x) for x in vals])
        self.f.enterInitializationMode()
        self.f.exitInitializationMode()
        self.event()
        self.f.enterContinuousTimeMode()

    def set(self, t: float, x: Any, v: Any) -> None:
        self.put(t, np.concatenate([np.asarray(x, dtype=float), np.asarray(v, dtype=float)]))

    def mode(self) -> list[int]:
        return list(self.f.getInt32([self.vr["mode"]], nValues=self.n))

    def real(self, name: str) -> np.ndarray:
        return np.array(self.f.getFloat64([self.vr[name]], nValues=self.n))

    def free(self) -> None:
        self.f.freeInstance()


# the chain FMU's default parameters (2 blocks) as the reference's chain
DEFAULT_CHAIN = Chain.make(2, omega=5.0, k=100.0, P0=1.0, N=1.0, mu_s=0.4, chi=0.7)


def _chain_switches(modes: np.ndarray, ch: Chain) -> tuple[np.ndarray, int]:
    """The rows where the mode of a block with friction changes (fmpy records both sides of every
    event: one change per switch), and how many switches."""
    fr = np.asarray(ch.N) > 0
    changed = (np.diff(modes[:, fr], axis=0) != 0).sum(axis=1)
    return np.nonzero(changed)[0] + 1, int(changed.sum())


@pytest.mark.parametrize("version", [2, 3])
def test_chain_descriptions_declare_model_exchange(version: int) -> None:
    """The chain's states x, v per block, their derivatives v, a, two event indicators per block."""
    md = read_model_description(str(_chain_fmu(version)))
    assert md.modelExchange is not None and md.coSimulation is not None
    assert md.modelExchange.modelIdentifier == md.coSimulation.modelIdentifier == "DryFrictionChain"
    pairs = [(d.variable.name, d.variable.derivative.name) for d in md.derivatives]
    if version == 2:  # the build's n = 2, element by element
        assert pairs == [("v[1]", "x[1]"), ("v[2]", "x[2]"), ("a[1]", "v[1]"), ("a[2]", "v[2]")]
        assert md.numberOfEventIndicators == 4 and md.numberOfContinuousStates == 4
    else:
        assert pairs == [("v", "x"), ("a", "v")]
        assert [e.variable.name for e in md.eventIndicators] == ["event_indicator_0", "event_indicator_1"]
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(_chain_fmu(version))) == []


def test_chain_by_hand(tmp_path: Path) -> None:
    """Three blocks (different masses, springs, dampers, a wall spring): the derivatives against
    M a = P(t) - K x - C v + F written here (F: -mode mu_k N sliding; stuck blocks held, a = 0), the
    indicators against the relative velocities and the margins Fb -+ F_static, F_static = P - K x -
    C v of the block; a breakaway, a stop that sticks and a reversal, each in one update."""
    ch = Chain.make(3, omega=2.0, m=[1.0, 2.0, 1.5], k=[10.0, 20.0, 15.0], k_end=5.0, c=[0.1, 0.2, 0.3],
                    P0=[1.0, 0.5, 0.0], phi=[0.0, 0.3, 0.0], N=[1.0, 2.0, 1.5], mu_s=0.5, chi=0.7,
                    x0=[0.01, 0.02, 0.0], v0=[0.1, 0.0, 0.0])
    me = ChainME(tmp_path, ch)
    try:
        me.init()
        K, C = ch.matrices()
        Fb, mukN = ch.mu_s * ch.N, ch.chi * ch.mu_s * ch.N

        def static(t: float, x: np.ndarray, v: np.ndarray) -> np.ndarray:
            return ch.P0 * np.cos(ch.omega * t + ch.phi) - K @ x - C @ v

        def accel(t: float, x: np.ndarray, v: np.ndarray, mode: np.ndarray) -> np.ndarray:
            return np.where(mode == 0, 0.0, (static(t, x, v) - mode * mukN) / ch.m)

        x, v = np.array(ch.x0), np.array(ch.v0)
        Fs = static(0.0, x, v)
        assert np.all(np.abs(Fs[1:]) < Fb[1:])  # blocks 2 and 3 start at rest within their limits
        assert me.mode() == [1, 0, 0]
        assert me.derivatives() == pytest.approx(np.concatenate([v, accel(0.0, x, v, np.array([1, 0, 0]))]),
                                                 rel=1e-14, abs=1e-15)
        z = me.indicators()
        assert z == pytest.approx([0.1, Fb[1] - Fs[1], Fb[2] - Fs[2], 1.0, Fb[1] + Fs[1], Fb[2] + Fs[2]], rel=1e-14)
        assert me.real("F_friction") == pytest.approx([-mukN[0], -Fs[1], -Fs[2]], rel=1e-14)  # the holding forces
        # block 2 pulled beyond its forward limit (x[1] = -0.2: F_static about 7 N > Fb = 1 N): its margin is
        # negative, the update breaks it away forward, the states as they were, its indicator DBL_MIN (block 3
        # placed where its springs cancel: held)
        x = np.array([0.01, -0.2, -0.15])
        me.set(0.5, x, v)
        z = me.indicators()
        Fs = static(0.5, x, v)
        assert z[1] == pytest.approx(Fb[1] - Fs[1], rel=1e-14) and z[1] < 0
        info = me.switch()
        assert info[3]  # valuesOfContinuousStatesChanged: the derivatives jumped
        assert me.mode() == [1, 1, 0] and list(me.states()) == [*x, *v]
        assert me.indicators()[1] == DBL_MIN
        assert me.derivatives()[3:] == pytest.approx(accel(0.5, x, v, np.array([1, 1, 0])), rel=1e-14)
        # block 1's velocity crossed 0 where its static force is within the limit: it sticks, v = 0; block 2
        # slides on; one update
        x, v = np.array([0.01, 0.02, 0.0]), np.array([-1e-9, 0.3, 0.0])
        me.set(0.8, x, v)
        Fs = static(0.8, x, np.array([0.0, 0.3, 0.0]))
        assert abs(Fs[0]) < Fb[0] and me.indicators()[0] < 0
        info = me.switch()
        assert info[3] and me.mode() == [0, 1, 0] and list(me.states()) == [*x, 0.0, 0.3, 0.0]
        assert me.indicators()[[0, 3]] == pytest.approx([Fb[0] - Fs[0], Fb[0] + Fs[0]], rel=1e-14)
        assert me.derivatives()[3] == 0.0
        # a reversal: block 2 sliding forward stops where its static force drives it backward beyond the
        # limit (x[1] = 0.2; blocks 1 and 3 placed where their springs cancel, held): one update, slip
        # backward from v = 0
        x, v = np.array([0.4 / 3, 0.2, 0.15]), np.array([0.0, -1e-9, 0.0])
        me.set(0.8, x, v)
        assert np.all(np.abs(static(0.8, x, np.zeros(3))[[0, 2]]) < Fb[[0, 2]])
        assert me.indicators()[1] < 0
        info = me.switch()
        assert info[3] and me.mode() == [0, -1, 0] and me.states()[4] == 0.0
        assert me.indicators()[1] == DBL_MIN
        # an event with nothing to switch changes nothing
        info = me.switch()
        assert not info[3] and me.mode() == [0, -1, 0]
        # the host moves block 1's belt under it while it is stuck: the step ends in an event, the block
        # slides backward relative to its belt at its own speed
        me.f.setFloat64([me.vr["v_belt"]], [0.2, 0.0, 0.0])
        assert me.f.completedIntegratorStep()[0]  # enterEventMode
        me.switch()
        assert me.mode() == [-1, -1, 0] and me.states()[3] == 0.0
        assert me.indicators()[0] == pytest.approx(0.2, rel=1e-15)
        # a wrong size names the argument and its valid value
        with pytest.raises(FMICallException):
            me.arr(me.f.getContinuousStateDerivatives, 4)
        assert "nx = 4" in me.messages[-1] and "must be 6" in me.messages[-1]
        with pytest.raises(FMICallException):
            me.arr(me.f.getEventIndicators, 3)
        assert "ni = 3" in me.messages[-1] and "must be 6" in me.messages[-1]
        assert me.f.getNumberOfContinuousStates() == me.f.getNumberOfEventIndicators() == 6
        # the nominals: block i's static deflection F / K_i of the largest force F (here max(mu_s, mu_k) N
        # = 1 N of block 2), K_i its springs, and sqrt(K_i / m_i) times it
        K_i = np.array([30.0, 35.0, 20.0])
        F = max(np.max(np.abs(ch.P0)), np.max(Fb), np.max(K_i * np.abs(ch.x0)), np.max(np.sqrt(K_i * ch.m) * ch.v0))
        assert F == 1.0
        nominal = F / K_i
        assert me.arr(me.f.getNominalsOfContinuousStates) == pytest.approx(
            np.concatenate([nominal, np.sqrt(K_i / ch.m) * nominal]), rel=1e-15)
    finally:
        me.free()


def test_chain_fmu_state_in_model_exchange(tmp_path: Path) -> None:
    """An FMU state of the chain taken in continuous-time mode, serialised and restored after a
    switch, gives back the time, the states, the modes and the derivatives."""
    ch = Chain.make(3, omega=0.8, N=[0.6, 0.5, 0.4], P0=[1.0, 0.0, 0.3], x0=[0.0, 0.1, 0.0], v0=[0.2, 0.0, 0.0])
    me = ChainME(tmp_path, ch)
    try:
        me.init()
        me.set(0.3, [0.635, 0.3, 0.0], [0.1, 0.0, 0.0])
        modes, x, dx = me.mode(), me.states(), me.derivatives()
        state = me.f.getFMUState()
        blob = me.f.serializeFMUState(state)
        me.f.freeFMUState(state)
        me.set(0.3, [0.635, 0.3, 0.0], [-1e-9, 0.0, 0.0])  # block 1 stops and sticks
        me.switch()
        assert me.mode() != modes
        restored = me.f.deserializeFMUState(blob)
        me.f.setFMUState(restored)
        me.f.freeFMUState(restored)
        assert me.mode() == modes and np.array_equal(me.states(), x)
        assert np.array_equal(me.derivatives(), dx) and dx[3] != 0.0
    finally:
        me.free()


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("solver", ["CVode", "Euler"])
def test_chain_fmpy_runs_to_the_end(version: int, solver: str, refcache: RefCache) -> None:
    """The default chain (2 blocks, k 100, P0 1, omega 5, N 1, mu_s 0.4, chi 0.7) with fmpy's defaults:
    to the end; CVode with the reference's switches and x within 1e-4; Euler (fmpy's step 1e-3)
    within 1e-2. FMI 2.0 (the build's n = 2) and 3.0 give the same numbers."""
    kw = {"step_size": 1e-4, "output_interval": 1e-3} if solver == "Euler" else {}
    r = simulate_fmu(str(_chain_fmu(version)), fmi_type="ModelExchange", solver=solver, record_events=True, **kw)
    if version == 2:
        x = np.stack([r["x[1]"], r["x[2]"]], axis=1)
        modes = np.stack([r["mode[1]"], r["mode[2]"]], axis=1)
    else:
        x, modes = np.asarray(r["x"]), np.asarray(r["mode"])
    assert r["time"][-1] == pytest.approx(12.56, abs=1e-12) and np.all(np.isfinite(x))
    ch = DEFAULT_CHAIN
    ref = refcache.call(solve_chain, ch, 12.56)
    rows, n = _chain_switches(modes, ch)
    err = np.max(np.abs(x - ref.evaluate(r["time"])["x"]))
    if solver == "CVode":
        assert n == len(ref.events) == 41 and err < 1e-4
    else:
        assert err < 1e-2


def test_chain_fmi3_gives_fmi2s_numbers() -> None:
    """The default chain (n = 2) through both FMUs with CVode at 1e-10: the same times and x, bit for bit."""
    r2, r3 = (simulate_fmu(str(_chain_fmu(v)), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10)
              for v in (2, 3))
    assert np.array_equal(r2["time"], r3["time"])
    assert np.array_equal(np.stack([r2["x[1]"], r2["x[2]"]], axis=1), np.asarray(r3["x"]))


# the stick-slip cases of n = 3 ... 5 blocks: the coupled validation cases (tests/chain_cases.py) and two
# longer chains, all blocks with friction
CHAIN_ME_CASES = {
    **{name: ch for name, ch in CHAIN_CASES.items() if name != "friction-on-one"},
    "four-blocks": Chain.make(4, omega=0.6, k=[1.0, 2.0, 1.5, 1.0], m=[1.0, 0.5, 2.0, 1.0], N=[0.6, 0.3, 0.8, 0.4],
                              chi=0.6, P0=[1.0, 0.0, 0.0, 0.8], phi=[0.0, 0.0, 0.0, 2.0], c=0.02),
    "five-blocks": Chain.make(5, omega=0.4, N=[0.5, 0.7, 0.3, 0.6, 0.4], chi=[0.7, 0.5, 0.9, 0.6, 0.8],
                              P0=[0.0, 0.0, 1.2, 0.0, 0.0], k_end=1.0),
}


def _chain_accuracy(name: str, rtol: float, x_tol: float, t_tol: float, refcache: RefCache) -> None:
    """CVode at rtol over 10 excitation periods of CHAIN_ME_CASES[name] against the event-driven
    reference (solved once: conftest.refcache): every block's x within x_tol, exactly its switches,
    their times within t_tol."""
    ch = CHAIN_ME_CASES[name]
    t_end = 10 * ch.period
    ref = refcache.call(solve_chain, ch, t_end)
    r = simulate_chain_me(ch, t_end, _chain_fmu(3), relative_tolerance=rtol, output_interval=ch.period / 50,
                          record_events=True)
    x, modes = np.asarray(r["x"]), np.asarray(r["mode"])
    assert r["time"][-1] == pytest.approx(t_end)
    assert np.max(np.abs(x - ref.evaluate(r["time"])["x"])) < x_tol
    rows, n = _chain_switches(modes, ch)
    assert n == len(ref.events) > 20
    per_row = (np.diff(modes[:, np.asarray(ch.N) > 0], axis=0)[rows - 1] != 0).sum(axis=1)
    t_me, t_ref = np.repeat(r["time"][rows], per_row), np.array([e[0] for e in ref.events])
    assert np.max(np.abs(np.sort(t_me) - np.sort(t_ref))) < t_tol


@pytest.mark.parametrize("name", list(CHAIN_ME_CASES))
def test_chain_cvode_accuracy_against_the_reference(name: str, refcache: RefCache) -> None:
    """CVode at 1e-10 over 10 excitation periods: every block's x within 3e-7 of the event-driven
    reference (dryfriction.references.chain; measured 8.6e-9 ... 2.4e-7, the largest on the five
    blocks whose x reaches 3 m), exactly its switches (count), at its times within 3e-6 s: a
    breakaway's time error is the position's error over the static force's rate (measured at most
    1.1e-6 s, five-blocks)."""
    _chain_accuracy(name, 1e-10, 3e-7, 3e-6, refcache)


@pytest.mark.parametrize("name", list(CHAIN_ME_CASES))
def test_chain_cvode_accuracy_falls_with_the_tolerance(name: str, refcache: RefCache) -> None:
    """At 1e-12 every block's x within 1e-8 of the reference (measured at most 3.9e-9), the switch
    times within 1e-7 s."""
    _chain_accuracy(name, 1e-12, 1e-8, 1e-7, refcache)


@pytest.mark.parametrize("start", [
    {"v_belt": [0.05, -0.05, 0.1]},
    {"friction_law": 2, "v_s": [0.05] * 3},
    {"v_belt": [0.05, 0.0, 0.1], "friction_law": 2, "v_s": [0.05] * 3}],
    ids=["belts", "stribeck", "stribeck-belts"])
def test_chain_belt_and_stribeck_against_cosimulation(start: dict[str, Any]) -> None:
    """The moving belts and Stribeck's law as in co-simulation: three damped blocks over 2.5
    excitation periods, CVode at 1e-10 against the located scheme at h = 2e-5 (its own error ~1e-8)
    within 2e-7 (measured 2.6e-8 ... 5.2e-8), with the same number of switches."""
    from dryfriction.drivers.chain import ChainFMU3
    ch = Chain.make(3, omega=0.8, N=[0.6, 0.5, 0.4], chi=0.6, P0=[1.0, 0.0, 0.3], c=0.02)
    t_end = 2.5 * ch.period
    r = simulate_chain_me(ch, t_end, _chain_fmu(3), start=start, relative_tolerance=1e-10, output_interval=0.01,
                          record_events=True)
    t, first = np.unique(r["time"], return_index=True)  # the left side of each event
    x_me = np.asarray(r["x"])[first]
    inputs = {k: v for k, v in start.items() if k == "v_belt"}
    params = {**ch.fmu_params(), **{k: v for k, v in start.items() if k != "v_belt"}, "h": 2e-5}
    with ChainFMU3(n=3, params=params, fmu_path=_chain_fmu(3)) as cs:
        run = cs.run(t_stop=t_end, dt=0.01, inputs=inputs)
    x = np.stack([np.interp(run.t, t, x_me[:, i]) for i in range(3)], axis=1)
    assert np.max(np.abs(x - run.x)) < 2e-7
    n_me, n_cs = _chain_switches(np.asarray(r["mode"]), ch)[1], int(np.sum(np.diff(run.mode, axis=0) != 0))
    assert n_me == n_cs > 10


@pytest.mark.slow
@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("solver", ["cvode", "euler"])
def test_fmusim_chain_model_exchange(version: int, solver: str, tmp_path: Path, refcache: RefCache) -> None:
    """fmusim integrates the default chain (n = 2): to the end, no warning; CVODE at 1e-10 over its
    default 12.56 s with the reference's 41 switches and x within 1e-8; Euler at the step 1e-4 within
    1e-3 over the first 3 s (11 switches; at its default step, the description's 0.01, explicit
    Euler amplifies the chain's undamped modes, about 16 rad/s: a host's choice, not the FMU's)."""
    out = tmp_path / "out.csv"
    t_end = 12.56 if solver == "cvode" else 3.0
    args = [str(fmusim()), "--interface-type", "me", "--solver", solver, "--output-file", str(out)]
    args += ["--tolerance", "1e-10"] if solver == "cvode" else ["--output-interval", "1e-4", "--stop-time", "3.0"]
    r = subprocess.run(args + [str(_chain_fmu(version))], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "[WARNING]" not in r.stdout + r.stderr and "[ERROR]" not in r.stdout + r.stderr
    lines = out.read_text().splitlines()
    rows = [line.replace('"', "").replace(" ", ",").split(",") for line in lines[1:]]
    a = np.array(rows, dtype=float)  # time, x[1], x[2], v ..., mode[1], mode[2] (FMI 3.0: arrays space-separated)
    t, x, modes = a[:, 0], a[:, 1:3], a[:, -2:]
    assert t[-1] == pytest.approx(t_end, abs=2e-4)
    ch = DEFAULT_CHAIN
    ref = refcache.call(solve_chain, ch, t_end)
    err = np.max(np.abs(x - ref.evaluate(t)["x"]))
    if solver == "cvode":
        assert _chain_switches(modes, ch)[1] == len(ref.events) == 41 and err < 1e-8
    else:
        assert err < 1e-3


@pytest.mark.slow
def test_compliance_checker_chain_model_exchange(tmp_path: Path, refcache: RefCache) -> None:
    """The Compliance Checker's Model Exchange run of the FMI 2.0 chain (its explicit Euler at 1e-3):
    no warning or error, to the end, x within 1e-2 of the reference."""
    data = np.genfromtxt(_fmucheck_me(_chain_fmu(2), 0.001, tmp_path), delimiter=",", skip_header=1)
    t, x = data[:, 0], data[:, 1:3]
    assert t[-1] == pytest.approx(12.56)
    ref = refcache.call(solve_chain, DEFAULT_CHAIN, 12.56)
    assert np.max(np.abs(x - ref.evaluate(t)["x"])) < 1e-2
