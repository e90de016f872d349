"""The Python side of the DryFrictionSystem FMU's friction law per contact and its observables:
Contact(law="stribeck", v_s, delta) and its refusals, the TOML keys, System.start_values(), the
written FMU (FMI 3.0 and 2.0) with Stribeck contacts, and the driver's x_max, x_min and
stick_fraction (SystemRun, ``dryfriction system run --json``), against the chain's own driver with
Stribeck blocks, the event-driven reference and the FMU read through fmpy."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from dryfriction import Contact, System
from dryfriction.cli import main
from dryfriction.drivers.chain import ChainFMU3
from dryfriction.drivers.system import SystemFMU3, run, trajectory
from dryfriction.errors import UsageError
from dryfriction.references.system import simulate
from dryfriction.system.fmu import write_fmu
from dryfriction.system.spec import loads
from test_system_features import reference_observables, two_contacts
from test_system_fmu import SYS3, Fmu3

CHAIN = dict(m=[1.0, 0.8, 1.2], k=[60.0, 40.0, 50.0], c=[0.1, 0.0, 0.2], P0=[1.5, 0.5, 1.0], N=[1.0, 1.2, 0.8],
             mu_s=[0.4, 0.3, 0.5], chi=[0.7, 0.8, 0.6], x0=[0.0, 0.01, -0.01], k_end=30.0, c_end=0.05, omega=4.0)
V_S, DELTA = [0.05, 0.02, 0.1], [1.0, 2.0, 1.5]


def stribeck_chain(h: float = 1e-3) -> System:
    """The chain of three blocks as a system, every contact with the Stribeck law."""
    s = System.from_chain(**CHAIN, h=h, scheme="located")
    contacts = [Contact(dof=c.dof, N=c.N, mu_s=c.mu_s, mu_k=c.mu_k, law="stribeck", v_s=v, delta=d)
                for c, v, d in zip(s.contacts, V_S, DELTA)]
    return s.replace(contacts=contacts)


# --------------------------------------------------------------------- the law through the driver

def test_stribeck_contacts_through_the_driver_are_the_chains_driver() -> None:
    sys = stribeck_chain()
    times = np.arange(61) * 0.05
    got = trajectory(sys, times)
    with ChainFMU3(n=3) as chain:
        ref = chain.run(3.0, 0.05, {**CHAIN, "h": 1e-3, "alpha": sys.alpha, "scheme": "located",
                                    "friction_law": 2, "v_s": V_S, "delta": DELTA})
        coulomb = chain.run(3.0, 0.05, {**CHAIN, "h": 1e-3, "alpha": sys.alpha, "scheme": "located"})
    assert np.allclose(ref.t, got.t, rtol=0, atol=1e-12)
    assert np.array_equal(got.mode, ref.mode)
    assert len({tuple(r) for r in ref.mode}) >= 4  # the blocks switch
    # the chain's tridiagonal sweeps against the dense Cholesky and Lemke (the FMU-level test
    # measured 8.3e-13 of x, 1.6e-12 of v, 1.8e-12 of the friction force, relative to each's largest)
    for mine, theirs in ((got.x, ref.x), (got.v, ref.v), (got.f, ref.F_friction)):
        scale = np.max(np.abs(theirs), axis=0)
        assert np.max(np.abs(mine - theirs) / scale) <= 1e-11
    # the law matters: Coulomb's motion is another
    assert np.max(np.abs(coulomb.x - ref.x)) > 1e-3 * np.max(np.abs(ref.x))


def test_start_values_carry_the_law_per_contact() -> None:
    s = System(M=np.eye(2), K=100 * np.eye(2), contacts=[Contact(dof=0, N=1.0, mu_s=0.4, mu_k=0.3, law="stribeck",
                                                                 v_s=0.03, delta=1.5),
                                                         Contact(dof=1, N=1.0, mu_s=0.4)])
    sv = s.start_values()
    assert sv["friction_law"] == [2, 1] and sv["v_s"] == [0.03, 0.01] and sv["delta"] == [1.5, 1.0]
    assert s != s.replace(contacts=[Contact(dof=0, N=1.0, mu_s=0.4, mu_k=0.3, v_s=0.03, delta=1.5),
                                    s.contacts[1]])


# --------------------------------------------------------------------- the refusals

@pytest.mark.parametrize("kw, sentence", [
    (dict(law="stribeck", k_t=50.0), "a Jenkins element (k_t = 50.0 > 0) takes the Coulomb law only"),
    (dict(law="stribeck", delta=0.5), "law = stribeck supports delta >= 1 only, not 0.5"),
    (dict(law="stribeck", v_s=0.0), "v_s = 0.0 is not > 0"),
    (dict(v_s=-1.0), "v_s = -1.0 is not > 0"),
    (dict(delta=0.0), "delta = 0.0 is out of range; valid range: > 0"),
    (dict(law="dahl"), "law = 'dahl' is not offered; valid: coulomb, stribeck"),
])
def test_a_contact_the_engine_cannot_step_is_refused(kw: dict, sentence: str) -> None:
    with pytest.raises(UsageError) as e:
        Contact(dof=0, N=1.0, mu_s=0.4, **kw)
    assert sentence in str(e.value)


def test_stribeck_needs_scheme_located_and_the_reference_refuses_it() -> None:
    c = Contact(dof=0, N=1.0, mu_s=0.4, mu_k=0.3, law="stribeck")
    with pytest.raises(UsageError, match=r"contacts\[0\]: law = stribeck needs scheme located .* not scheme paper"):
        System(M=[[1.0]], K=[[100.0]], contacts=[c], scheme="paper")
    with pytest.raises(ValueError, match=r"contacts\[0\] has the Stribeck law, which this reference does not model"):
        simulate(System(M=[[1.0]], K=[[100.0]], contacts=[c]), 1.0)


def test_stribeck_and_jenkins_in_one_structure_are_accepted_by_the_system_and_the_fmu(tmp_path: Path) -> None:
    """A rigid Stribeck contact beside a Jenkins element: the System keeps each contact's law and
    stiffness, and the FMU initialised from its start values steps it (the slider's position read
    for the Jenkins element, NaN for the rigid contact)."""
    strib = Contact(dof=0, N=1.0, mu_s=0.4, mu_k=0.3, law="stribeck")
    jenk = Contact(dof=1, N=1.0, mu_s=0.4, k_t=50.0)
    sys = System(M=np.eye(2), K=100 * np.eye(2), contacts=[strib, jenk], F_c=[2.0, 2.0], omega=3.0)
    v = sys.start_values()
    assert v["friction_law"] == [2, 1] and v["k_t"] == [0.0, 50.0]
    v.pop("n")
    v.pop("nc")
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 2})
    try:
        f.start(v)
        f.s.doStep(0.0, 0.5)
        s = f.real("s", 2)
        assert math.isnan(s[0]) and math.isfinite(s[1]) and all(math.isfinite(a) for a in f.real("x", 2))
    finally:
        try:
            f.close()
        except Exception:
            pass


# --------------------------------------------------------------------- the TOML keys

SPEC = """
[structure]
M = [[1.0, 0.0], [0.0, 2.0]]
K = [[150.0, -50.0], [-50.0, 50.0]]
[excitation]
omega = 6.0
F_c = [1.0, 0.0]
[[contact]]
dof = 0
N = 2.0
mu_s = 0.4
mu_k = 0.25
law = "stribeck"
v_s = 0.04
delta = 2.0
[[contact]]
between = [1, 0]
N = 1.0
mu_s = 0.3
[run]
h = 5e-4
"""


def test_the_spec_with_a_stribeck_contact_round_trips() -> None:
    s = loads(SPEC)
    built = System(M=[[1.0, 0.0], [0.0, 2.0]], K=[[150.0, -50.0], [-50.0, 50.0]], F_c=[1.0, 0.0], omega=6.0, h=5e-4,
                   contacts=[Contact(dof=0, N=2.0, mu_s=0.4, mu_k=0.25, law="stribeck", v_s=0.04, delta=2.0),
                             Contact(between=(1, 0), N=1.0, mu_s=0.3)])
    assert s == built
    assert s.contacts[0].law == "stribeck" and (s.contacts[0].v_s, s.contacts[0].delta) == (0.04, 2.0)
    assert s.friction_law.tolist() == [2, 1]
    with pytest.raises(UsageError, match=r"\[\[contact\]\] number 0 \(0-based\): Contact: law = stribeck supports "
                                         r"delta >= 1 only"):
        loads(SPEC.replace("delta = 2.0", "delta = 0.5"))
    with pytest.raises(UsageError, match="law = stribeck needs scheme located"):
        loads(SPEC + 'scheme = "consistent"\n')


# --------------------------------------------------------------------- the written FMU

def test_a_written_fmu_with_stribeck_contacts_is_the_prebuilt_run(tmp_path: Path) -> None:
    sys = loads(SPEC)
    path = write_fmu(sys, tmp_path / "Strib.fmu")
    res = simulate_fmu(str(path), stop_time=2.0, output_interval=0.01, output=["x", "f", "mode"])  # no values set
    ref = run(sys, 2.0, 0.01)  # the prebuilt FMU, the values set by the driver
    assert np.array_equal(np.asarray(res["x"]).reshape(ref.x.shape), ref.x)  # bit for bit
    assert np.array_equal(np.asarray(res["f"]).reshape(ref.f.shape), ref.f)
    assert np.array_equal(np.asarray(res["mode"]).reshape(ref.mode.shape), ref.mode)
    assert 0 in ref.mode[:, 0] and np.any(ref.mode[:, 0] != 0)  # the Stribeck contact sticks and slips
    # and the law is carried: the same structure with Coulomb contacts moves otherwise
    coul = run(sys.replace(contacts=[Contact(dof=0, N=2.0, mu_s=0.4, mu_k=0.25), sys.contacts[1]]), 2.0, 0.01)
    assert np.max(np.abs(coul.x - ref.x)) > 1e-3 * np.max(np.abs(ref.x))


def test_a_written_fmi2_fmu_with_a_stribeck_contact_is_the_prebuilt_run(tmp_path: Path) -> None:
    M = np.array([[2.0, 0.3], [0.3, 1.0]])
    K = np.array([[300.0, -100.0], [-100.0, 100.0]])
    s = System(M=M, K=K, C=0.01 * K, contacts=[Contact(between=(0, 1), N=1.0, mu_s=0.4, mu_k=0.3, law="stribeck",
                                                       v_s=0.05, delta=1.5)],
               F_c=[2.0, 0.5], omega=9.0, x0=[0.001, 0.0], h=2e-4)
    path = write_fmu(s, tmp_path / "Two.fmu", fmi=2)
    res = simulate_fmu(str(path), stop_time=1.0, output_interval=0.01, output=["x[1]", "x[2]", "f[1]"])
    ref = run(s, 1.0, 0.01)
    assert np.array_equal(np.column_stack([res["x[1]"], res["x[2]"]]), ref.x)  # bit for bit
    assert np.array_equal(res["f[1]"], ref.f[:, 0])


# --------------------------------------------------------------------- the observables

def test_the_drivers_observables_are_the_references_and_the_fmus() -> None:
    sys = two_contacts()
    w0, w1 = 1.5, 4.5
    for t_end in (3.0, 5.0):  # mid-window, and the window closed
        got = run(sys, t_end, 0.25, t_obs_start=w0, t_obs_stop=w1)
        ref = reference_observables(sys, w0, w1, t_end)
        assert np.all((ref[4:6] > 0.05) & (ref[4:6] < 0.95)), ref  # both contacts stick and slide
        assert got.transitions.tolist() == ref[6:].tolist()  # each contact's mode changes in the window
        ref = ref[:6]
        mine = np.concatenate([got.x_max, got.x_min, got.stick_fraction])
        # the FMU-level test's tolerances: x to 2e-5 of the largest |x| (second order at h = 5e-4 and
        # the step-end sampling), the stuck shares to 5e-5 (the located switch times)
        assert np.max(np.abs(mine[:4] - ref[:4])) <= 2e-5 * np.max(np.abs(ref[:4])), (mine, ref)
        assert np.max(np.abs(mine[4:] - ref[4:])) <= 5e-5, (mine, ref)
        # the output times inside the window bound the extremes from inside
        inside = (got.t >= w0) & (got.t <= w1)
        assert np.all(got.x_max >= got.x[inside].max(axis=0)) and np.all(got.x_min <= got.x[inside].min(axis=0))


def test_the_drivers_observables_are_the_fmus_through_fmpy(tmp_path: Path) -> None:
    sys = loads(SPEC)  # a Stribeck contact and a Coulomb one
    got = run(sys, 2.0, 0.1, t_obs_start=0.5)
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 2})
    try:
        f.start({k: v for k, v in sys.start_values().items() if k not in ("n", "nc")} | {"t_obs_start": 0.5})
        for a in np.arange(20) * 0.1:
            f.s.doStep(a, 0.1)
        want = [f.real("x_max", 2), f.real("x_min", 2), f.real("stick_fraction", 2)]
    finally:
        f.close()
    for mine, theirs in zip((got.x_max, got.x_min, got.stick_fraction), want):
        assert np.array_equal(mine, theirs)
    assert np.all(got.x_max > got.x_min) and np.all((got.stick_fraction > 0) & (got.stick_fraction < 1))


def test_observe_false_gives_nan_and_a_bad_window_is_refused() -> None:
    sys = two_contacts()
    off = run(sys, 1.0, 0.1, observe=False)
    assert np.all(np.isnan(off.x_max)) and np.all(np.isnan(off.x_min)) and np.all(np.isnan(off.stick_fraction))
    on = run(sys, 1.0, 0.1)
    assert np.array_equal(on.x, off.x)  # observing does not change the motion
    # the default window is the run: the start is a sample, so x_max >= x0
    assert np.all(on.x_max >= sys.x0) and np.all(on.x_min <= sys.x0) and np.all(np.isfinite(on.stick_fraction))
    with SystemFMU3(sys) as fmu, pytest.raises(ValueError, match=r"t_obs_stop >= t_obs_start"):
        fmu.run(1.0, 0.1, t_obs_start=2.0, t_obs_stop=1.0)


def test_the_command_prints_the_observables(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC, encoding="utf-8")
    assert main(["system", "run", str(spec), "--t-end", "1.0", "--dt", "0.1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    ref = run(loads(SPEC), 1.0, 0.1)
    assert out["x_max"] == ref.x_max.tolist() and out["x_min"] == ref.x_min.tolist()
    assert out["stick_fraction"] == ref.stick_fraction.tolist()
    assert out["transitions"] == ref.transitions.tolist() and min(out["transitions"]) >= 0
