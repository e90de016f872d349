"""The exact Jacobian of the state inside the oscillator FMU (parameter `sensitivity`, local variables
dx_dx0, dx_dv0, dv_dx0, dv_dv0; scheme exact): against exp(A t) without friction (scipy.linalg.expm),
against a central finite-difference Jacobian of the FMU's own map with stick-slip, rank one over a
stick phase, the identity after a state restore, and not computed (NaN, one sentence) otherwise; read
by value reference with the bits it read as an output, recorded by a host only when asked."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from scipy.linalg import expm

from dryfriction.drivers.oscillator3 import default_fmi3_path
from dryfriction.drivers.oscillator import default_fmu_path
from fmi2_helpers import Inst, fmi2Warning

EXACT, LOCATED = 4, 3
JAC = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")


def start(i: Inst, p: dict[str, float], scheme: int = EXACT, sensitivity: bool = True, t0: float = 0.0) -> int:
    s = i.s
    s.setupExperiment(startTime=t0)
    s.setReal([i.vr(k) for k in p], list(p.values()))
    s.setInteger([i.vr("scheme")], [scheme])
    s.setBoolean([i.vr("sensitivity")], [sensitivity])
    s.enterInitializationMode()
    return s.exitInitializationMode()


def jac(i: Inst) -> np.ndarray:
    return np.array(i.s.getReal([i.vr(n) for n in JAC])).reshape(2, 2)


def state(i: Inst) -> np.ndarray:
    return np.array(i.s.getReal([i.vr("x"), i.vr("v")]))


def mode(i: Inst) -> int:
    return int(i.s.getInteger([i.vr("mode")])[0])


def run(unzipped: tuple[str, object], p: dict[str, float], t_end: float, n: int = 1) -> tuple[np.ndarray, np.ndarray, int]:
    """(x, v) at t_end, the Jacobian there and the mode, in n equal communication steps."""
    i = Inst(unzipped)
    try:
        start(i, p)
        for j in range(n):
            i.s.doStep(j * t_end / n, t_end / n)
        return state(i), jac(i), mode(i)
    finally:
        i.free()


def fd_jacobian(unzipped: tuple[str, object], p: dict[str, float], t_end: float, eps: float) -> np.ndarray:
    """Central differences of the FMU's own map (x0, v0) -> (x, v)(t_end)."""
    J = np.zeros((2, 2))
    for col, name in enumerate(("x0", "v0")):
        plus = dict(p, **{name: p[name] + eps})
        minus = dict(p, **{name: p[name] - eps})
        J[:, col] = (run(unzipped, plus, t_end)[0] - run(unzipped, minus, t_end)[0]) / (2.0 * eps)
    return J


def expm_reference(m: float, k: float, c: float, t: float) -> np.ndarray:
    """exp(A t), A = [[0, 1], [-k/m, -c/m]], by scipy's expm over short spans (one expm of a long t
    loses some 1e-13 to its own scaling and squaring) and exact powers of the span's matrix."""
    A = np.array([[0.0, 1.0], [-k / m, -c / m]])
    rate = math.sqrt(k / m) + c / m
    n = max(1, math.ceil(t * rate))
    E = np.linalg.matrix_power(expm(A * (t / n)), n)
    return E


def rel(a: np.ndarray, b: np.ndarray, w: float = 1.0) -> float:
    """The largest difference over the largest entry, of the Jacobians made dimensionless with the
    rate w (x in units of v / w: entries diag(1, 1/w) J diag(1, w)), so that an entry in 1/s is not
    compared with one in s."""
    D, Di = np.diag([1.0, 1.0 / w]), np.diag([1.0, w])
    a, b = D @ a @ Di, D @ b @ Di
    return float(np.abs(a - b).max() / np.abs(b).max())


# ---- no friction: exp(A t) ------------------------------------------------------------------------

@pytest.mark.parametrize("m, k, c", [(1.0, 1.0, 0.0), (1.3, 2.0, 0.1), (2.0, 50.0, 3.0), (0.5, 2000.0, 0.3),
                                     (1.0, 4.0, 4.5), (1.0, 4.0, 4.0), (1.0, 0.0, 0.7), (1.0, 0.0, 0.0)])
def test_no_friction_is_exp_of_a_t(unzipped: tuple[str, object], m: float, k: float, c: float) -> None:
    """N = 0: the Jacobian after t is exp(A t), under-, critically and over-damped, k = 0 (exact_free)
    too, over one call of many periods and over many communication steps."""
    w0 = math.sqrt(k / m) if k > 0 else 1.0
    T = 2.0 * math.pi / w0
    p = dict(m=m, k=k, c=c, N=0.0, P0=1.0, omega=1.1 * w0, x0=0.1, v0=0.2)
    zeta = c / (2.0 * math.sqrt(k * m)) if k > 0 else 0.0
    # many periods, unless heavy damping leaves nothing to compare (1e-162 after 60 periods at zeta = 1,
    # where the reference's own powers lose 3e-11 and the FMU's closed form 2e-13)
    long = 60.3 if zeta < 0.5 else 6.3
    for periods, steps in ((0.37, 1), (3.0, 1), (long, 1), (long, 97)):
        t = periods * T
        _, J, _ = run(unzipped, p, t, steps)
        E = expm_reference(m, k, c, t)
        assert rel(J, E, w0) < 1e-12, (periods, steps, J, E)


# ---- stick-slip: a finite-difference Jacobian of the FMU's own map --------------------------------

STICK_SLIP = [
    # (name, parameters, end times in excitation periods): mu_s > mu_k (chi 0.7, 0.3) and mu_s = mu_k,
    # stops with stick phases and reversals on the way; each end time lies inside a slide, away
    # from a stick phase (where the map is not differentiable in v: a state with v != 0 is not stuck)
    ("chi 0.7", dict(m=1.0, k=1.0, c=0.05, N=0.4, mu_s=1.0, chi=0.7, P0=1.0, omega=0.5, x0=0.3, v0=0.5),
     (3.3, 5.7, 10.1)),
    ("chi 1", dict(m=1.0, k=1.0, c=0.05, N=0.4, mu_s=1.0, chi=1.0, P0=1.0, omega=0.5, x0=0.3, v0=0.5), (3.3,)),
    ("chi 0.3", dict(m=1.0, k=1.0, c=0.05, N=0.4, mu_s=1.0, chi=0.3, P0=1.0, omega=0.5, x0=0.3, v0=0.5), (3.3,)),
    ("reversals", dict(m=0.5, k=2000.0, c=0.3, N=20.0, mu_s=0.3, chi=0.7, P0=10.0, omega=2 * math.pi * 13,
                       x0=0.01, v0=0.3), (4.2, 7.6)),
    ("undamped", dict(m=1.0, k=1.0, c=0.0, N=0.2, mu_s=0.5, chi=0.8, P0=1.0, omega=1.7, x0=-0.2, v0=0.4),
     (2.35, 6.6)),
    ("no spring", dict(m=1.0, k=0.0, c=0.2, N=0.1, mu_s=1.0, chi=0.7, P0=1.0, omega=2.0, x0=0.0, v0=0.3),
     (2.3, 4.6)),
]


@pytest.mark.parametrize("name, p, periods", STICK_SLIP, ids=[c[0] for c in STICK_SLIP])
def test_stick_slip_agrees_with_finite_differences(unzipped: tuple[str, object], name: str, p: dict[str, float],
                                                   periods: tuple[float, ...]) -> None:
    T = 2.0 * math.pi / p["omega"]
    for q in periods:
        t = q * T
        y, J, md = run(unzipped, p, t)
        assert md != 0, f"{name}: t = {q} T ends stuck; choose an end time inside a slide"
        scale = max(abs(y[0]), 1e-3)
        J1 = fd_jacobian(unzipped, p, t, 1e-6 * scale)
        J2 = fd_jacobian(unzipped, p, t, 2e-6 * scale)
        assert rel(J1, J2) < 1e-6, f"{name}: the map is not smooth at t = {q} T (an event nearby)"
        assert rel(J, J1) < 1e-6, (name, q, J, J1)


def test_events_on_the_way(unzipped: tuple[str, object]) -> None:
    """The stick-slip cases do pass through stick phases (rank one on the way) and reversals."""
    p = STICK_SLIP[0][1]
    T = 2.0 * math.pi / p["omega"]
    i = Inst(unzipped, logging=True)
    try:
        start(i, p)
        i.s.setDebugLogging(True, ["logEvents"])
        i.s.doStep(0.0, 3.3 * T)
    finally:
        i.free()
    events = [m for _, c, m in i.cb.messages if c == "logEvents" and "->" in m]
    assert any("slip -> stick" in m for m in events) and any("stick -> " in m for m in events)


# ---- rank one over a stick phase ------------------------------------------------------------------

def test_stick_phase_is_rank_one(unzipped: tuple[str, object]) -> None:
    """While stuck the v row is exactly 0 (det exactly 0); after the breakaway the map stays rank one
    (det below 1e-14 of the squared norm), and x's row follows x at the stop."""
    p = STICK_SLIP[0][1]
    T = 2.0 * math.pi / p["omega"]
    i = Inst(unzipped)
    try:
        start(i, p)
        assert np.array_equal(jac(i), np.eye(2))
        dt, t, stuck, slid_after = T / 200, 0.0, 0, 0
        for _ in range(1200):
            i.s.doStep(t, dt)
            t += dt
            J = jac(i)
            if mode(i) == 0:
                stuck += 1
                assert J[1, 0] == 0.0 and J[1, 1] == 0.0
                assert np.linalg.det(J) == 0.0
                assert np.abs(J[0]).max() > 0.0
            elif stuck:
                slid_after += 1
                assert abs(np.linalg.det(J)) <= 1e-14 * np.abs(J).max() ** 2
        assert stuck > 10 and slid_after > 10
    finally:
        i.free()


# ---- state restore --------------------------------------------------------------------------------

def test_identity_after_restore_and_continues(unzipped: tuple[str, object]) -> None:
    """After fmi2SetFMUstate (also of a serialised state) the Jacobian is the identity, and after a
    further step it is that of a fresh run started from the restored state at the restored time."""
    p = STICK_SLIP[0][1]
    T = 2.0 * math.pi / p["omega"]
    t_r, t_e = 3.3 * T, 5.7 * T
    i = Inst(unzipped)
    try:
        start(i, p)
        i.s.doStep(0.0, t_r)
        assert mode(i) != 0
        y_r = state(i)
        st = i.s.getFMUstate()
        data = i.s.serializeFMUstate(st)
        i.s.doStep(t_r, t_e - t_r)
        assert not np.allclose(jac(i), np.eye(2))
        i.s.setFMUstate(st)
        assert np.array_equal(jac(i), np.eye(2))
        assert np.array_equal(state(i), y_r)
        i.s.doStep(t_r, t_e - t_r)
        J_cont = jac(i)
        i.s.doStep(t_e, T)
        st2 = i.s.deSerializeFMUstate(data)
        i.s.setFMUstate(st2)
        assert np.array_equal(jac(i), np.eye(2))
        i.s.doStep(t_r, t_e - t_r)
        assert np.array_equal(jac(i), J_cont)
        i.s.freeFMUstate(st)
        i.s.freeFMUstate(st2)
    finally:
        i.free()
    fresh = Inst(unzipped)
    try:
        start(fresh, dict(p, x0=float(y_r[0]), v0=float(y_r[1])), t0=t_r)
        fresh.s.doStep(t_r, t_e - t_r)
        J_fresh = jac(fresh)
    finally:
        fresh.free()
    assert rel(J_cont, J_fresh) < 1e-12
    assert not np.allclose(J_cont, 0.0)


# ---- not computed ---------------------------------------------------------------------------------

def not_computed_messages(i: Inst) -> list[str]:
    return [m for _, c, m in i.cb.messages if c == "logNotComputed"]


def test_not_computed_with_scheme_located(unzipped: tuple[str, object]) -> None:
    """sensitivity = true with scheme located: a warning at initialisation naming the scheme, the four
    outputs NaN with status OK and one logNotComputed sentence; x, v as without sensitivity."""
    p = STICK_SLIP[0][1]
    i = Inst(unzipped)
    try:
        assert start(i, p, scheme=LOCATED) == fmi2Warning
        warnings = [m for st, _, m in i.cb.messages if st == fmi2Warning]
        assert len(warnings) == 1 and "scheme located" in warnings[0] and "sensitivity" in warnings[0]
        i.s.doStep(0.0, 1.0)
        y = state(i)
        for _ in range(3):
            assert np.isnan(jac(i)).all()
        msgs = not_computed_messages(i)
        assert len(msgs) == 1 and "scheme located" in msgs[0] and "dx_dx0" in msgs[0]
        assert not i.s.getInteger([i.vr("effects")])[0] & 64
    finally:
        i.free()
    j = Inst(unzipped)
    try:
        assert start(j, p, scheme=LOCATED, sensitivity=False) == 0
        j.s.doStep(0.0, 1.0)
        assert np.array_equal(state(j), y)
    finally:
        j.free()


def test_not_computed_while_off(unzipped: tuple[str, object]) -> None:
    """sensitivity false (the default) with scheme exact: NaN, one sentence; the effect bit is clear,
    and set with sensitivity on; x, v bit for bit the same either way."""
    p = STICK_SLIP[0][1]
    out = {}
    for on in (False, True):
        i = Inst(unzipped)
        try:
            assert start(i, p, sensitivity=on) == 0
            i.s.doStep(0.0, 37.0)
            out[on] = state(i)
            assert bool(i.s.getInteger([i.vr("effects")])[0] & 64) == on
            J = jac(i)
            if on:
                assert np.isfinite(J).all() and not_computed_messages(i) == []
            else:
                assert np.isnan(J).all()
                msgs = not_computed_messages(i)
                assert len(msgs) == 1 and "sensitivity is false" in msgs[0]
        finally:
            i.free()
    assert np.array_equal(out[False], out[True])


# ---- FMI 3.0 ----------------------------------------------------------------------------------------

def test_fmi3_gives_the_same_jacobian_and_restores_to_identity(unzipped: tuple[str, object]) -> None:
    """The FMI 3.0 FMU (same description, same core) gives the FMI 2.0 Jacobian bit for bit, also
    with events landed on (early return at every switch); fmi3SetFMUState resets it to the identity."""
    from dryfriction.drivers.oscillator3 import OscillatorFMU3

    p = STICK_SLIP[0][1]
    T = 2.0 * math.pi / p["omega"]
    _, J2, _ = run(unzipped, p, 3.3 * T)
    with OscillatorFMU3(params={**p, "scheme": EXACT, "sensitivity": True}) as fmu:
        fmu.do_step(3.3 * T)
        J3 = np.array([fmu.get(list(JAC))[n] for n in JAC]).reshape(2, 2)
        state = fmu.slave.getFMUState()
        fmu.do_step(T)
        fmu.slave.setFMUState(state)
        assert np.array_equal(np.array([fmu.get(list(JAC))[n] for n in JAC]), [1.0, 0.0, 0.0, 1.0])
        fmu.slave.freeFMUState(state)
    assert np.array_equal(J3, J2)
    with OscillatorFMU3(params={**p, "scheme": EXACT, "sensitivity": True}, early_return=True) as fmu:
        returns = 0
        while fmu.time < 3.3 * T:
            _, early = fmu.do_step(3.3 * T - fmu.time)
            returns += early
        J3e = np.array([fmu.get(list(JAC))[n] for n in JAC]).reshape(2, 2)
    assert returns > 3
    assert rel(J3e, J2) < 1e-9


# ---- local variables: read by value reference, recorded by a host only when asked -----------------

#: (x, v, dx_dx0, dx_dv0, dv_dx0, dv_dv0) as float.hex at the last end time of each STICK_SLIP case
#: (three equal communication steps), read by value reference from the FMI 2.0 build in which the four
#: were outputs: making them local variables moved no bit
_PINNED = """
chi 0.7: 0x1.4196b5766e0eap+0 -0x1.a3645b94eaad0p-6
    0x1.2720977bd25f2p-7 -0x1.68699e4479226p-9 -0x1.9f21b09cb4758p-8 0x1.faf68bbbe8f72p-10
chi 1: 0x1.9380ada828cf6p-2 -0x1.9988b10bd7a5ap-1
    0x1.bff7b072da944p-10 -0x1.56f2262f85281p-7 0x1.3c0e7c0814a4cp-11 -0x1.e3eb9d08a8582p-9
chi 0.3: 0x1.627c0963bc90ep-3 -0x1.c1fac7b099e6fp-1
    -0x1.93cdd02c7f34fp-8 -0x1.fea531f1af21ap-6 -0x1.cd8496d1a5b50p-9 -0x1.23d097e98703ap-6
reversals: 0x1.532d488f9d1aap-9 -0x1.bb82f6b612e45p-2
    0x1.5ee59dc292ed2p-5 -0x1.5a08e58bdcc90p-15 0x1.1ddcaae4be450p+0 0x1.ce053d87aae30p-6
undamped: 0x1.9a2ea4c89cdd4p-2 -0x1.7f64d50081172p-2
    0x1.73de1513afddfp-2 -0x1.6f90af12d8038p-2 0x1.416eb3ba5d8f3p-2 0x1.8557ccf68d2dep-2
no spring: 0x1.2459cad191addp+0 -0x1.66544f3287c95p-2
    0x1.0000000000000p+0 0x1.cbcb7c9c5f12ap+1 0x0.0p+0 0x1.f21f0c1f2a20fp-7
"""


def _pinned(text: str) -> dict[str, list[str]]:
    """Case name -> its six values as float.hex: a line `name: x v`, then an indented line with the
    Jacobian's entries row by row."""
    out: dict[str, list[str]] = {}
    name = ""
    for line in text.strip().splitlines():
        if not line.startswith(" "):
            name, line = line.split(":")
        out.setdefault(name, []).extend(line.split())
    return out


PINNED = _pinned(_PINNED)


@pytest.mark.parametrize("name, p, periods", STICK_SLIP, ids=[c[0] for c in STICK_SLIP])
def test_local_jacobian_reads_the_bits_it_read_as_an_output(unzipped: tuple[str, object], name: str,
                                                            p: dict[str, float], periods: tuple[float, ...]) -> None:
    T = 2.0 * math.pi / p["omega"]
    y, J, _ = run(unzipped, p, periods[-1] * T, 3)
    assert [float(v).hex() for v in (*y, *J.ravel())] == list(PINNED[name]), name


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_a_host_records_the_jacobian_only_when_asked(unzipped: tuple[str, object], version: str) -> None:
    """fmpy's simulate_fmu records the outputs by default: the four local variables are not among its
    columns (they were four NaN columns), with sensitivity on or off; asked for by name, it records
    them, the same bits as a run that reads them by value reference."""
    path = str(default_fmu_path() if version == "2.0" else default_fmi3_path())
    md = read_model_description(path)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    sens = {"scheme": EXACT, "sensitivity": True}
    for start_values in ({}, sens):
        res = simulate_fmu(path, stop_time=1.0, output_interval=0.125, start_values=start_values)
        assert len(res.dtype.names) == 1 + len(outputs) and set(res.dtype.names) == {"time", *outputs}
        assert not set(res.dtype.names) & set(JAC)
    res = simulate_fmu(path, stop_time=2.0, output_interval=0.125, start_values=sens, output=["x", *JAC])
    assert list(res.dtype.names) == ["time", "x", *JAC]
    assert np.array_equal([res[n][0] for n in JAC], [1.0, 0.0, 0.0, 1.0])  # the identity at the start
    _, J, _ = run(unzipped, {}, 2.0, 16)  # the FMU's default parameters, the same communication points
    assert np.array_equal([res[n][-1] for n in JAC], J.ravel())
    assert not np.array_equal(J, np.eye(2))
