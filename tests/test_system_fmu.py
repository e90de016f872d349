"""The DryFrictionSystem FMUs (build/fmi3/DryFrictionSystem.fmu with n, nc set in Configuration Mode;
build/DryFrictionSystem.fmu, FMI 2.0 fixed at n = 2, nc = 1), on the friction engine's generic
instance, through fmpy: the same structure posed as a system gives the other FMUs' numbers (one DOF
and one contact: the FMI 3.0 oscillator; TwoMass's two masses and two contacts; a chain of three
blocks), for every scheme; every structure it cannot step is refused at initialisation in one
sentence naming the array and element or the test that fails; an FMU state restores and
round-trips; fmusim runs it to the end."""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

from dryfriction import System

ROOT = Path(__file__).resolve().parents[1]
BUILD = ROOT / "build"
SYS3 = Path(os.environ.get("DFO_SYSTEM_FMU3", BUILD / "fmi3" / "DryFrictionSystem.fmu"))
SYS2 = Path(os.environ.get("DFO_SYSTEM_FMU", BUILD / "DryFrictionSystem.fmu"))
OSC3 = Path(os.environ.get("DFO_FMU3", BUILD / "fmi3" / "DryFrictionOscillator.fmu"))
TM3 = Path(os.environ.get("DFO_TWO_MASS_FMU3", BUILD / "fmi3" / "TwoMass.fmu"))
CHAIN3 = Path(os.environ.get("DFO_CHAIN_FMU3", BUILD / "fmi3" / "DryFrictionChain.fmu"))
FMUSIM = Path(os.environ.get("FMUSIM", ROOT.parent / "shared" / "tools" / "fmusim" / "fmusim"))
SCHEMES = {"paper": 1, "consistent": 2, "located": 3}
INT_NAMES = ("scheme", "frictionUpdates", "friction_law")


class Fmu3:
    """One FMI 3.0 co-simulation instance of an FMU through fmpy, its log kept (messages)."""

    def __init__(self, path: Path, tmp: Path, sizes: dict[str, int] | None = None) -> None:
        self.md = read_model_description(str(path))
        self.dir = extract(str(path), unzipdir=str(tmp / f"{path.stem}-{id(self)}"))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []

        def log(env: Any, status: int, category: bytes, message: bytes) -> None:
            self.messages.append(message.decode())

        self.log = log  # (kept alive while the instance lives)
        self.s = FMU3Slave(guid=self.md.guid, unzipDirectory=self.dir,
                           modelIdentifier=self.md.coSimulation.modelIdentifier)
        self.s.instantiate(loggingOn=True, logMessage=log)
        self.sizes = dict(sizes or {})
        if sizes:
            self.s.enterConfigurationMode()
            self.s.setUInt64([self.vr[k] for k in sizes], list(sizes.values()))
            self.s.exitConfigurationMode()

    def set(self, values: dict[str, Any]) -> None:
        """Set parameters (scalars, or arrays as flat sequences; integers by name)."""
        for name, value in values.items():
            vals = list(np.ravel(value))
            if name in INT_NAMES:
                self.s.setInt64([self.vr[name]], [int(x) for x in vals])
            else:
                self.s.setFloat64([self.vr[name]], [float(x) for x in vals])

    def start(self, values: dict[str, Any]) -> None:
        self.s.enterInitializationMode(startTime=0.0)
        self.set(values)
        self.s.exitInitializationMode()

    def real(self, name: str, count: int = 1) -> np.ndarray:
        return np.array(self.s.getFloat64([self.vr[name]], nValues=count))

    def ints(self, name: str, count: int = 1) -> np.ndarray:
        return np.array(self.s.getInt32([self.vr[name]], nValues=count))

    def close(self) -> None:
        self.s.terminate()
        self.s.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


def run(f: Fmu3, times: np.ndarray, reals: list[tuple[str, int]], ints: list[tuple[str, int]]) -> np.ndarray:
    """The outputs (name, count) at the times (times[0] = 0, the instance initialised), one row each."""
    rows = []
    for k, t in enumerate(times):
        if k:
            f.s.doStep(times[k - 1], t - times[k - 1])
        row: list[float] = []
        for name, c in reals:
            row += list(f.real(name, c))
        for name, c in ints:
            row += [float(x) for x in f.ints(name, c)]
        rows.append(row)
    return np.array(rows)


def system(tmp: Path, n: int, nc: int, values: dict[str, Any], times: np.ndarray) -> np.ndarray:
    """x, v, f, mode of a system run at the times (FMI 3.0)."""
    f = Fmu3(SYS3, tmp, {"n": n, "nc": nc})
    try:
        f.start(values)
        return run(f, times, [("x", n), ("v", n), ("f", nc)], [("mode", nc)])
    finally:
        f.close()


def rel_diff(a: np.ndarray, b: np.ndarray) -> float:
    """The largest difference of the columns relative to each column's largest magnitude."""
    scale = np.maximum(np.max(np.abs(b), axis=0), 1e-300)
    return float(np.max(np.abs(a - b) / scale))


# --------------------------------------------------------------------- one DOF: the oscillator

OSC = {"m": 1.3, "k": 40.0, "c": 0.2, "P0": 1.0, "omega": 2.5, "phi": 0.0, "N": 1.5, "mu_s": 0.5, "chi": 0.7,
       "x0": 0.01, "v0": 0.0, "h": 1e-3, "alpha": -0.1}


def one_dof(p: dict[str, float], scheme: int) -> dict[str, Any]:
    """The oscillator's parameters p as the values of a system with one DOF and one rigid contact."""
    return {"M": [p["m"]], "K": [p["k"]], "C": [p["c"]], "F_c": [p["P0"]], "F_s": [0.0], "omega": p["omega"],
            "x0": [p["x0"]], "v0": [p["v0"]], "W": [1.0], "N": [p["N"]], "mu_s": [p["mu_s"]],
            "mu_k": [p["chi"] * p["mu_s"]], "h": p["h"], "alpha": p["alpha"], "scheme": scheme}


@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_one_dof_is_the_fmi3_oscillator(scheme: str, tmp_path: Path) -> None:
    times = np.arange(81) * 0.05
    o = Fmu3(OSC3, tmp_path)
    try:
        o.start({**OSC, "scheme": SCHEMES[scheme]})
        ref = run(o, times, [("x", 1), ("v", 1), ("F_friction", 1)], [("mode", 1)])
    finally:
        o.close()
    got = system(tmp_path, 1, 1, one_dof(OSC, SCHEMES[scheme]), times)
    assert np.array_equal(got[:, -1], ref[:, -1])  # the modes
    assert len(set(ref[:, -1])) == 3  # it sticks and slides both ways
    # the same engine over the same one-DOF operators (eng_one_dof.h): bit for bit
    assert got.tobytes() == ref.tobytes(), rel_diff(got, ref)


def test_one_dof_stribeck_is_the_fmi3_oscillator(tmp_path: Path) -> None:
    """The Stribeck law on one DOF (scheme located, the one that steps it): the oscillator's bits."""
    times = np.arange(81) * 0.05
    law = {"v_s": 0.03, "delta": 1.5}
    o = Fmu3(OSC3, tmp_path)
    try:
        o.start({**OSC, "scheme": SCHEMES["located"], "friction_law": 2, **law})
        ref = run(o, times, [("x", 1), ("v", 1), ("F_friction", 1)], [("mode", 1)])
    finally:
        o.close()
    got = system(tmp_path, 1, 1, {**one_dof(OSC, SCHEMES["located"]), "friction_law": [2], "v_s": [law["v_s"]],
                                  "delta": [law["delta"]]}, times)
    assert len(set(ref[:, -1])) == 3  # it sticks and slides both ways
    assert got.tobytes() == ref.tobytes(), rel_diff(got, ref)


# --------------------------------------------------------------------- TwoMass as a system

TM = {"m1": 1.0, "m2": 0.5, "k1": 100.0, "k2": 20.0, "k12": 50.0, "c1": 0.3, "c2": 0.0, "c12": 0.1, "P1": 3.0,
      "P2": 1.0, "omega": 5.0, "phi": 0.0, "N_g": 1.5, "mu_s_g": 0.4, "mu_k_g": 0.3, "N_c": 1.0, "mu_s_c": 0.3,
      "mu_k_c": 0.2, "x1_0": 0.0, "x2_0": 0.01, "v1_0": 0.0, "v2_0": 0.0, "h": 1e-3, "alpha": -0.1}


def two_mass_system(p: dict[str, float]) -> dict[str, Any]:
    """TwoMass's parameters as the system's M, C, K, W and contact arrays."""
    return {"M": [p["m1"], 0.0, 0.0, p["m2"]],
            "K": [p["k1"] + p["k12"], -p["k12"], -p["k12"], p["k2"] + p["k12"]],
            "C": [p["c1"] + p["c12"], -p["c12"], -p["c12"], p["c2"] + p["c12"]],
            "F_c": [p["P1"], p["P2"]], "F_s": [0.0, 0.0], "omega": p["omega"],
            "x0": [p["x1_0"], p["x2_0"]], "v0": [p["v1_0"], p["v2_0"]], "W": [1.0, 0.0, 1.0, -1.0],
            "N": [p["N_g"], p["N_c"]], "mu_s": [p["mu_s_g"], p["mu_s_c"]], "mu_k": [p["mu_k_g"], p["mu_k_c"]],
            "k_t": [0.0, 0.0], "h": p["h"], "alpha": p["alpha"]}


@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_two_mass_as_a_system_is_the_two_mass_fmu(scheme: str, tmp_path: Path) -> None:
    times = np.arange(61) * 0.05
    t = Fmu3(TM3, tmp_path)
    try:
        t.start({**TM, "scheme": SCHEMES[scheme]})
        ref = run(t, times, [("x1", 1), ("x2", 1), ("v1", 1), ("v2", 1), ("F_g", 1), ("F_c", 1)],
                  [("mode_g", 1), ("mode_c", 1)])
    finally:
        t.close()
    got = system(tmp_path, 2, 2, {**two_mass_system(TM), "scheme": SCHEMES[scheme]}, times)
    assert np.array_equal(got[:, -2:], ref[:, -2:])
    assert len({(int(a), int(b)) for a, b in ref[:, -2:]}) >= 3  # the run switches
    if scheme != "paper":
        assert got.tobytes() == ref.tobytes()  # measured: bit for bit (the same engine, dense 2 x 2 or n x n)
        return
    # paper: x, v bit for bit; a stuck contact's f is the force its step found (as the oscillator's and
    # the chain's F_friction), TwoMass's F_g, F_c the holding force at the state (eng_contact_forces,
    # the schemes whose stuck contacts rest): the same where the contact slides
    assert got[:, :4].tobytes() == ref[:, :4].tobytes()
    sliding = ref[:, -2:] != 0
    assert sliding.any() and (~sliding).any()
    assert np.array_equal(got[:, 4:6][sliding], ref[:, 4:6][sliding])
    limit = np.array([TM["N_g"] * TM["mu_s_g"], TM["N_c"] * TM["mu_s_c"]])
    assert np.all(np.abs(got[:, 4:6]) <= limit + 1e-15)


# --------------------------------------------------------------------- a chain of three blocks

CHAIN = {"m": [1.0, 0.8, 1.2], "k": [60.0, 40.0, 50.0], "c": [0.1, 0.0, 0.2], "P0": [1.5, 0.5, 1.0],
         "N": [1.0, 1.2, 0.8], "mu_s": [0.4, 0.3, 0.5], "chi": [0.7, 0.8, 0.6], "x0": [0.0, 0.01, -0.01],
         "k_end": 30.0, "c_end": 0.05, "omega": 4.0}


def chain_system(p: dict[str, Any]) -> dict[str, Any]:
    """The chain's springs, dampers and blocks as the system's tridiagonal K, C, diagonal M, W = I."""
    n = len(p["m"])

    def tri(left: list[float], end: float) -> np.ndarray:
        A = np.zeros((n, n))
        for i in range(n):
            right = left[i + 1] if i + 1 < n else end
            A[i, i] = left[i] + right
            if i + 1 < n:
                A[i, i + 1] = A[i + 1, i] = -left[i + 1]
        return A

    return {"M": np.diag(p["m"]), "K": tri(p["k"], p["k_end"]), "C": tri(p["c"], p["c_end"]), "F_c": p["P0"],
            "F_s": [0.0] * n, "omega": p["omega"], "x0": p["x0"], "v0": [0.0] * n, "W": np.eye(n), "N": p["N"],
            "mu_s": p["mu_s"], "mu_k": [a * b for a, b in zip(p["chi"], p["mu_s"])], "k_t": [0.0] * n}


@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_chain_of_three_as_a_system_is_the_chain_fmu(scheme: str, tmp_path: Path) -> None:
    times = np.arange(61) * 0.05
    c = Fmu3(CHAIN3, tmp_path, {"n": 3})
    try:
        c.start({**CHAIN, "h": 1e-3, "scheme": SCHEMES[scheme]})
        ref = run(c, times, [("x", 3), ("v", 3), ("F_friction", 3)], [("mode", 3)])
    finally:
        c.close()
    got = system(tmp_path, 3, 3, {**chain_system(CHAIN), "h": 1e-3, "scheme": SCHEMES[scheme]}, times)
    assert np.array_equal(got[:, -3:], ref[:, -3:])
    assert len({tuple(r) for r in ref[:, -3:]}) >= 4  # the blocks switch
    # not bit for bit: the chain's tridiagonal sweeps and box LCP against the dense Cholesky and
    # Lemke; measured 1.4e-13 (paper), 1.5e-13 (consistent), 1.4e-13 (located) of each output's
    # largest magnitude in x and v, the forces bit for bit
    assert rel_diff(got, ref) <= 1e-12, rel_diff(got, ref)


@pytest.mark.parametrize("scheme", ["consistent", "located"])
def test_inputs_changed_between_steps_are_the_chain_fmus(scheme: str, tmp_path: Path) -> None:
    """F_ext, N_ext and v_belt set at communication points (steps of a force, a normal force up and
    down, a belt starting under a block) move the system as the chain FMU moves its blocks."""
    times = np.arange(61) * 0.05

    def drive(f: Fmu3, names: tuple[str, str, str, str]) -> np.ndarray:
        rows = []
        for k, t in enumerate(times):
            if k:
                j = k - 1
                f.s.setFloat64([f.vr["F_ext"]], [0.0, 0.5 * (j >= 20), -0.3 * (j >= 35)])
                f.s.setFloat64([f.vr["N_ext"]], [0.2 * (j >= 10), 0.0, -0.1 * (j >= 40)])
                f.s.setFloat64([f.vr["v_belt"]], [0.0, 0.05 * (j >= 25), 0.0])
                f.s.doStep(times[k - 1], t - times[k - 1])
            rows.append(np.concatenate([f.real(names[0], 3), f.real(names[1], 3), f.real(names[2], 3),
                                        f.ints(names[3], 3)]))
        f.close()
        return np.array(rows)

    c = Fmu3(CHAIN3, tmp_path, {"n": 3})
    c.start({**CHAIN, "h": 1e-3, "scheme": SCHEMES[scheme]})
    ref = drive(c, ("x", "v", "F_friction", "mode"))
    f = Fmu3(SYS3, tmp_path, {"n": 3, "nc": 3})
    f.start({**chain_system(CHAIN), "h": 1e-3, "scheme": SCHEMES[scheme]})
    got = drive(f, ("x", "v", "f", "mode"))
    assert np.array_equal(got[:, -3:], ref[:, -3:])
    # measured: 1.4e-13 (consistent, located) of each output's largest magnitude
    assert rel_diff(got, ref) <= 1e-12, rel_diff(got, ref)


def test_without_contacts_it_is_the_modal_solution_to_second_order(tmp_path: Path) -> None:
    """nc = 0: a free linear structure (arrays of no element), x(1 s) against its modal solution:
    the error falls 4x per halving of h (Bossak's second order)."""
    M, K = np.diag([1.0, 2.0]), np.array([[40.0, -10.0], [-10.0, 30.0]])
    x0 = np.array([0.01, -0.02])
    w2, V = np.linalg.eig(np.linalg.solve(M, K))
    exact = V @ (np.linalg.solve(V, x0) * np.cos(np.sqrt(w2) * 1.0))
    errs = []
    for h in (1e-3, 5e-4):
        f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 0})
        try:
            f.start({"M": M, "K": K, "C": [0.0] * 4, "F_c": [0.0, 0.0], "x0": x0, "h": h})
            for k in range(10):
                f.s.doStep(k * 0.1, 0.1)
            errs.append(np.max(np.abs(f.real("x", 2) - exact)))
            assert f.real("E_friction")[0] == 0.0 and len(f.s.getFloat64([f.vr["f"]], nValues=0)) == 0
        finally:
            f.close()
    # measured: 1.0e-7 and 2.5e-8 (of |x| 0.02)
    assert errs[0] < 5e-7 and 3.5 < errs[0] / errs[1] < 4.5, errs


def test_early_return_ends_the_step_at_the_first_switch(tmp_path: Path) -> None:
    """FMI 3.0 with early return: a long step ends at the first stick/slip switch, logged at that time
    (logEvents), and stepping on from there continues the run."""
    md = read_model_description(str(SYS3))
    d = extract(str(SYS3), unzipdir=str(tmp_path / "early"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    messages: list[str] = []

    def log(env: Any, status: int, category: bytes, message: bytes) -> None:
        messages.append(message.decode())

    s = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier)
    s.instantiate(loggingOn=True, logMessage=log, earlyReturnAllowed=True)
    try:
        s.enterConfigurationMode()
        s.setUInt64([vr["n"], vr["nc"]], [2, 2])
        s.exitConfigurationMode()
        s.enterInitializationMode(startTime=0.0)
        for name, value in two_mass_system(TM).items():
            s.setFloat64([vr[name]], [float(x) for x in np.ravel(value)])
        s.exitInitializationMode()
        t, ends = 0.0, []
        while t < 2.0:
            _, _, early, t_last = s.doStep(t, 2.0 - t)
            if not early:
                break
            assert t_last > t
            t = t_last
            ends.append(t)
        switches = [float(m.split(":")[0][4:]) for m in messages if "switches from mode" in m]
        assert len(ends) >= 3 and ends == switches[:len(ends)]
    finally:
        s.terminate()
        s.freeInstance()


# --------------------------------------------------------------------- structures refused

VALID = {"M": [1.0, 0.0, 0.0, 2.0], "K": [100.0, -20.0, -20.0, 50.0], "C": [0.0] * 4, "F_c": [1.0, 0.0],
         "W": [1.0, 0.0], "N": [1.0], "mu_s": [0.4], "mu_k": [0.3], "k_t": [0.0], "h": 1e-3}

REFUSED = [
    ({"M": [1.0, 0.5, 0.4, 2.0]}, "M is not symmetric: M[2,1] = 0.40000000000000002 but M[1,2] = 0.5"),
    ({"M": [1.0, 2.0, 2.0, 1.0]}, "M is not positive definite (its Cholesky factorisation fails at row 2)"),
    ({"K": [100.0, 0.0, 0.0, -1e-6]}, "K has a negative eigenvalue beyond rounding (K + 1e-12 max|K| I is not positive definite)"),
    ({"C": [0.0, 1.0, 1.0, 0.0]}, "C has a negative eigenvalue beyond rounding (C + 1e-12 max|C| I is not positive definite)"),
    ({"K": [100.0, 1.0, 2.0, 50.0]}, "K is not symmetric: K[2,1] = 2 but K[1,2] = 1"),
    ({"W": [0.0, 0.0]}, "W row 1 is zero: contact 1 acts on no degree of freedom"),
]


@pytest.mark.parametrize("bad,sentence", REFUSED, ids=[s.split(":")[0].split(" (")[0] for _, s in REFUSED])
def test_a_bad_structure_is_refused_at_initialisation(bad: dict[str, Any], sentence: str, tmp_path: Path) -> None:
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
    try:
        f.s.enterInitializationMode(startTime=0.0)
        f.set({**VALID, **bad})
        with pytest.raises(FMICallException):
            f.s.exitInitializationMode()
        assert f.messages[-1] == f"fmi3ExitInitializationMode: {sentence}.", f.messages[-1]
    finally:
        f.s.freeInstance()
        shutil.rmtree(f.dir, ignore_errors=True)


def test_a_valid_structure_starts_and_within_rounding_is_symmetric(tmp_path: Path) -> None:
    """The same structure with M and K symmetric to 1e-15 (below the tolerance) and a K that is
    singular (a rigid-body mode) starts: the tests above refuse what they refuse for its reason."""
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
    try:
        f.start({**VALID, "M": [1.0, 1e-3, 1e-3 * (1 + 1e-15), 2.0], "K": [50.0, -50.0, -50.0, 50.0]})
        f.s.doStep(0.0, 0.1)
        assert np.all(np.isfinite(f.real("x", 2)))
    finally:
        f.close()


def test_a_moving_belt_under_the_paper_scheme_is_refused(tmp_path: Path) -> None:
    """As the chain: at initialisation, and at a step after v_belt was set (the state kept, a belt at
    rest again goes on)."""
    sentence = ("v_belt is set but the paper scheme has no moving belt (its stuck contacts creep with Bossak's "
                "acceleration); use scheme consistent or located.")
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
    try:
        f.s.enterInitializationMode(startTime=0.0)
        f.set({**VALID, "scheme": 1, "v_belt": [0.1]})
        with pytest.raises(FMICallException):
            f.s.exitInitializationMode()
        assert f.messages[-1] == f"fmi3ExitInitializationMode: {sentence}"
    finally:
        f.s.freeInstance()
        shutil.rmtree(f.dir, ignore_errors=True)
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
    try:
        f.start({**VALID, "scheme": 1})
        f.s.doStep(0.0, 0.1)
        x = f.real("x", 2)
        f.s.setFloat64([f.vr["v_belt"]], [0.1])
        with pytest.raises(FMICallException):
            f.s.doStep(0.1, 0.1)
        assert f.messages[-1] == f"fmi3DoStep: {sentence}" and np.array_equal(f.real("x", 2), x)
        f.s.setFloat64([f.vr["v_belt"]], [0.0])
        f.s.doStep(0.1, 0.1)
    finally:
        f.close()


@pytest.mark.parametrize("name,values,element", [
    ("K", [100.0, 0.0, 0.0, math.nan], "K[2,2]"), ("M", [1.0, math.inf, 0.0, 1.0], "M[1,2]"),
    ("N", [-1.0], "N[1]"), ("mu_s", [-0.1], "mu_s[1]"), ("mu_k", [math.nan], "mu_k[1]"), ("k_t", [-1.0], "k_t[1]")])
def test_a_non_finite_or_negative_element_is_refused_naming_it(name: str, values: list[float], element: str,
                                                                tmp_path: Path) -> None:
    """Ranges are checked when set (every element, nothing stored on refusal): the sentence names the element."""
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
    try:
        f.s.enterInitializationMode(startTime=0.0)
        f.set(VALID)
        with pytest.raises(FMICallException):
            f.set({name: values})
        assert f"{element} (value reference {f.vr[name]})" in f.messages[-1], f.messages[-1]
        f.s.exitInitializationMode()  # the valid values stayed
        assert np.array_equal(f.real(name, len(values)), np.ravel(VALID[name]))
    finally:
        f.close()


@pytest.mark.parametrize("name,value", [("n", 0), ("n", 1025), ("nc", 1025)])
def test_sizes_outside_their_range_are_refused(name: str, value: int, tmp_path: Path) -> None:
    f = Fmu3(SYS3, tmp_path)
    try:
        f.s.enterConfigurationMode()
        with pytest.raises(FMICallException):
            f.s.setUInt64([f.vr[name]], [value])
        lo = 1 if name == "n" else 0
        assert f.messages[-1] == (f"fmi3SetUInt64: invalid value {value} for {name} (value reference {f.vr[name]}); "
                                  f"valid range: in [{lo}, 1024].")
        f.s.exitConfigurationMode()
    finally:
        f.s.freeInstance()
        shutil.rmtree(f.dir, ignore_errors=True)


# --------------------------------------------------------------------- FMU states, FMI 2.0, fmusim

def test_fmu_state_rollback_and_serialisation_continue_bit_for_bit(tmp_path: Path) -> None:
    """A state taken mid-run and restored (also after a change of sizes in between: another
    instance's) continues to the bits of the run that never left it; a serialised state round-trips
    into another instance; a corrupted one is refused."""
    values = {**two_mass_system(TM), "scheme": 3}
    times = np.arange(21) * 0.07
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 2})
    g = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 2})
    try:
        f.start(values)
        for k in range(1, 11):
            f.s.doStep(times[k - 1], times[k] - times[k - 1])
        st = f.s.getFMUState()
        a = run(f, times[10:] - 0.0, [("x", 2), ("v", 2), ("f", 2), ("E_friction", 1)], [("mode", 2)])
        f.s.setFMUState(st)
        b = run(f, times[10:], [("x", 2), ("v", 2), ("f", 2), ("E_friction", 1)], [("mode", 2)])
        assert a.tobytes() == b.tobytes()
        blob = f.s.serializeFMUState(st)
        g.start(values)
        g.s.setFMUState(g.s.deserializeFMUState(blob))
        c = run(g, times[10:], [("x", 2), ("v", 2), ("f", 2), ("E_friction", 1)], [("mode", 2)])
        assert a.tobytes() == c.tobytes()
        bad = bytearray(blob)
        bad[len(bad) // 2] ^= 0x40
        with pytest.raises(FMICallException):
            g.s.deserializeFMUState(bytes(bad))
        f.s.freeFMUState(st)
    finally:
        f.close()
        g.close()


def test_fmi2_build_is_the_fmi3_bits_at_its_fixed_sizes(tmp_path: Path) -> None:
    """The FMI 2.0 FMU (n = 2, nc = 1 fixed by the build, elements M[1,1] ...) gives FMI 3.0's bits."""
    from fmpy.fmi2 import FMU2Slave

    values = {"M": [1.0, 0.2, 0.2, 0.5], "K": [150.0, -50.0, -50.0, 70.0], "C": [0.3, -0.1, -0.1, 0.1],
              "F_c": [3.0, 1.0], "F_s": [0.0, 0.5], "omega": 5.0, "x0": [0.0, 0.01], "W": [1.0, -1.0], "N": [1.0],
              "mu_s": [0.3], "mu_k": [0.2], "h": 1e-3}
    times = np.arange(31) * 0.05
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
    try:
        f.start(values)
        a = run(f, times, [("x", 2), ("v", 2), ("a", 2), ("f", 1)], [("mode", 1)])
    finally:
        f.close()
    md = read_model_description(str(SYS2))
    names = {v.name: v.valueReference for v in md.modelVariables}
    assert "M[2,1]" in names and "W[1,2]" in names and "n" not in names
    d = extract(str(SYS2), unzipdir=str(tmp_path / "sys2"))
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier)
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    for name, value in values.items():
        vals = list(np.ravel(value))
        if len(vals) == 1 and name in names:
            s.setReal([names[name]], vals)
            continue
        width = 2 if len(vals) == 4 or name == "W" else 0
        els = ([f"{name}[{i // width + 1},{i % width + 1}]" for i in range(len(vals))] if width
               else [f"{name}[{i + 1}]" for i in range(len(vals))])
        s.setReal([names[e] for e in els], vals)
    s.enterInitializationMode()
    s.exitInitializationMode()
    out = [names[e] for e in ("x[1]", "x[2]", "v[1]", "v[2]", "a[1]", "a[2]", "f[1]")]
    rows = []
    for k, t in enumerate(times):
        if k:
            s.doStep(times[k - 1], t - times[k - 1])
        rows.append(list(s.getReal(out)) + [float(s.getInteger([names["mode[1]"]])[0])])
    s.terminate()
    s.freeInstance()
    b = np.array(rows)
    assert a.tobytes() == b.tobytes()
    assert len(set(a[:, -1])) >= 2


@pytest.mark.skipif(not FMUSIM.is_file(), reason="fmusim not found (set FMUSIM)")
def test_fmusim_runs_it_to_the_end(tmp_path: Path) -> None:
    """fmusim (FMI 3.0) sets the sizes and the arrays by --start-value and runs the default experiment."""
    out = tmp_path / "out.csv"
    args = [str(FMUSIM), "--interface-type", "cs", "--output-interval", "0.01", "--output-file", str(out),
            "--start-value", "n", "3", "--start-value", "nc", "2", "--start-value", "h", "0.001",
            "--start-value", "M", "1 0 0 0 1 0 0 0 1", "--start-value", "K", "100 -50 0 -50 100 -50 0 -50 100",
            "--start-value", "W", "1 0 0 0 -1 1", "--start-value", "F_c", "2 0 1",
            "--start-value", "N", "1 0.5", "--start-value", "mu_s", "0.4 0.3", "--start-value", "mu_k", "0.3 0.2",
            str(SYS3)]
    r = subprocess.run(args, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = out.read_text().splitlines()
    head = [c.strip('"') for c in lines[0].split(",")]
    jac = ["dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0", "dx_ds0", "dv_ds0", "ds_dx0", "ds_dv0", "ds_ds0"]
    assert head == ["time", "E_friction", "x", "v", "a", "f", "s", "x_max", "x_min", "stick_fraction", *jac, "mode",
                    "transitions"]
    assert len(lines) == 1257 + 1
    last = lines[-1].split(",")
    assert float(last[0]) == pytest.approx(12.56, abs=1e-9)
    # the same run through fmpy with the same communication points: fmusim's numbers
    f = Fmu3(SYS3, tmp_path, {"n": 3, "nc": 2})
    try:
        f.start({"M": np.eye(3), "K": [100, -50, 0, -50, 100, -50, 0, -50, 100], "W": [1, 0, 0, 0, -1, 1],
                 "F_c": [2, 0, 1], "N": [1, 0.5], "mu_s": [0.4, 0.3], "mu_k": [0.3, 0.2], "h": 0.001})
        for k in range(1, 1257):
            f.s.doStep((k - 1) * 0.01, 0.01)
        x, mode, E = f.real("x", 3), f.ints("mode", 2), f.real("E_friction")[0]
        x_max, share = f.real("x_max", 3), f.real("stick_fraction", 2)
        transitions = f.ints("transitions", 2)
    finally:
        f.close()
    # the same numbers to the CSV's 16 digits (measured: 2.8e-17 in one element). (With h derived, not
    # a divisor of 0.01, every communication point ends a shortened step and the two hosts' rounding of
    # tc + dt differs: measured 1.1e-12 relative in x at the end.)
    assert np.allclose([float(v) for v in last[2].split()], x, rtol=1e-15, atol=0)
    assert [int(v) for v in last[19].split()] == list(mode) and float(last[1]) == pytest.approx(E, rel=1e-15)
    assert [int(v) for v in last[20].split()] == list(transitions) and min(transitions) > 0
    # the map's Jacobian is not computed without sensitivity = true: NaN (logged once), not a number
    assert all(v.strip().lower() == "nan" for v in last[10].split())
    assert np.allclose([float(v) for v in last[7].split()], x_max, rtol=1e-15, atol=0)
    assert np.allclose([float(v) for v in last[9].split()], share, rtol=1e-15, atol=0)
    assert last[6].split() == ["nan", "nan"]


FMUCHECK = Path(os.environ.get("FMUCHECK", ROOT.parent / "shared" / "tools" / "fmucheck" / "fmuCheck.linux64"))


@pytest.mark.skipif(not FMUCHECK.is_file(), reason="fmuCheck not found (set FMUCHECK)")
def test_the_compliance_checker_runs_the_fmi2_fmu_to_the_end(tmp_path: Path) -> None:
    """The FMU Compliance Checker with its default settings (the default experiment, the start values)
    on the FMI 2.0 FMU: no warning, no error, every output to the stop time, the same numbers as an
    fmpy FMI 3.0 run at the same communication points, bit for bit."""
    out, log = tmp_path / "out.csv", tmp_path / "log.txt"
    r = subprocess.run([str(FMUCHECK), "-o", str(out), "-e", str(log), str(SYS2)], capture_output=True, text=True,
                       timeout=120)
    text = log.read_text()
    assert r.returncode == 0 and "0 Warning(s)" in text and "0 Error(s)" in text, text
    lines = out.read_text().splitlines()
    head = [c.strip('"') for c in lines[0].split(",")]
    jac = [f"{name}[{i},{k}]" for name, a, b in (("dx_dx0", 2, 2), ("dx_dv0", 2, 2), ("dv_dx0", 2, 2),
                                                     ("dv_dv0", 2, 2), ("dx_ds0", 2, 1), ("dv_ds0", 2, 1),
                                                     ("ds_dx0", 1, 2), ("ds_dv0", 1, 2), ("ds_ds0", 1, 1))
           for i in range(1, a + 1) for k in range(1, b + 1)]
    # (the checker writes the matrices' names, M[1,2], unquoted: its header is compared as a line)
    assert lines[0].replace('"', "") == ",".join(
        ["time", "E_friction", "x[1]", "x[2]", "v[1]", "v[2]", "a[1]", "a[2]", "f[1]", "mode[1]", "s[1]",
         "x_max[1]", "x_max[2]", "x_min[1]", "x_min[2]", "stick_fraction[1]", *jac, "transitions[1]"]), head
    rows = [line.split(",") for line in lines[1:]]
    t = [float(row[0]) for row in rows]
    assert t[-1] == pytest.approx(12.56, abs=1e-12) and rows[-1][10] == "NAN"
    assert all(v == "NAN" for v in rows[-1][16:16 + len(jac)]) and len(rows[-1]) == 17 + len(jac)  # (sensitivity false)
    # the checker's communication points: its rows' times, and one it steps through without a row
    # (measured: 500 rows for 500 steps of 0.02512 s, none at 0.1256)
    dt = 12.56 / 500  # its default: 500 steps over the default experiment
    points = [t[0]]
    for a, b in zip(t[:-1], t[1:]):
        points += [a + dt, b] if b - a > 1.5 * dt else [b]
    assert len(points) == 501
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
    try:
        f.start({})
        for k in range(1, len(points)):
            f.s.doStep(points[k - 1], points[k] - points[k - 1])
        x = f.real("x", 2)
        obs = np.concatenate([f.real("x_max", 2), f.real("x_min", 2), f.real("stick_fraction", 1)])
        transitions = f.ints("transitions", 1)
    finally:
        f.close()
    assert np.array_equal([float(v) for v in rows[-1][2:4]], x)  # (the CSV's 17 digits round-trip)
    assert np.array_equal([float(v) for v in rows[-1][11:16]], obs)
    assert [int(rows[-1][-1])] == list(transitions) and transitions[0] > 0


def test_static_checks_of_both_fmus() -> None:
    """fmpy's validation and fmutool's check pass for both FMUs; the archives hold their sources and
    export the FMI functions only."""
    from fmpy.validation import validate_fmu

    exe = shutil.which("fmutool") or str(Path(sys.executable).with_name("fmutool"))
    for path, version, lib in ((SYS2, "2.0", BUILD / "DryFrictionSystem.so"),
                               (SYS3, "3.0", BUILD / "fmi3" / "lib" / "DryFrictionSystem.so")):
        assert validate_fmu(str(path)) == []
        r = subprocess.run([exe, "-input", str(path), "-check"], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0 and f"compliant with FMI-{version}" in r.stdout + r.stderr, r.stdout + r.stderr
        md = read_model_description(str(path))
        names = set(zipfile.ZipFile(path).namelist())
        for src in md.buildConfigurations[0].sourceFileSets[0].sourceFiles:
            assert f"sources/{src}" in names
        assert "sources/system_config.h" in names and md.coSimulation.canSerializeFMUstate
        if lib.is_file():
            out = subprocess.run(["nm", "-D", "--defined-only", str(lib)], capture_output=True, text=True).stdout
            exported = {line.split()[-1] for line in out.splitlines() if line.strip()}
            assert exported and all(e.startswith(f"fmi{version[0]}") for e in exported), exported


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no gcc")
@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
def test_the_listed_sources_rebuild_the_fmu(which: str, tmp_path: Path) -> None:
    """A plain C99 compile of the sources the description lists (sources/, its configuration header
    included) links a library with no undefined symbol."""
    path = SYS2 if which == "fmi2" else SYS3
    md = read_model_description(str(path))
    d = extract(str(path), unzipdir=str(tmp_path / which))
    files = [str(Path(d) / "sources" / f) for f in md.buildConfigurations[0].sourceFileSets[0].sourceFiles]
    r = subprocess.run(["gcc", "-std=c99", "-O0", "-shared", "-fPIC", "-I", str(Path(d) / "sources"), *files,
                        "-o", str(tmp_path / "rebuilt.so"), "-lm", "-Wl,--no-undefined"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr


def test_every_allocation_is_returned(tmp_path: Path) -> None:
    """Through the FMI 2.0 host's callbacks: a run, a state, a reset and a failed initialisation."""
    from fmi2_helpers import Inst

    d = extract(str(SYS2), unzipdir=str(tmp_path / "sys2"))
    i = Inst((d, read_model_description(str(SYS2))))
    s = i.s
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 0.3)
    st = s.getFMUstate()
    s.doStep(0.3, 0.3)
    s.setFMUstate(st)
    s.freeFMUstate(st)
    s.reset()
    s.setupExperiment(startTime=0.0)
    s.setReal([i.vr("W[1,1]")], [0.0])
    s.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.exitInitializationMode()
    assert "W row 1 is zero" in i.cb.last_error()
    assert i.cb.allocs > 0
    s.freeInstance()
    assert i.cb.allocs == i.cb.frees


# --------------------------------------------------------------------- start values, energy

def test_the_start_values_are_a_valid_structure_of_any_size(tmp_path: Path) -> None:
    """M = I, K = 100 I, C = 0, contact j on DOF j (W[j,j] = 1): the model description says so in both
    FMI versions, the FMU starts from them at its start sizes and after a change of sizes."""
    md3 = read_model_description(str(SYS3))
    starts = {v.name: v.start for v in md3.modelVariables}
    assert starts["M"].split() == ["1.0", "0.0", "0.0", "1.0"] and starts["W"].split() == ["1.0", "0.0"]
    assert starts["K"].split() == ["100.0", "0.0", "0.0", "100.0"]
    md2 = {v.name: v.start for v in read_model_description(str(SYS2)).modelVariables}
    assert (md2["M[1,2]"], md2["M[2,2]"], md2["W[1,1]"], md2["W[1,2]"]) == ("0.0", "1.0", "1.0", "0.0")
    for sizes in (None, {"n": 3, "nc": 2}):
        f = Fmu3(SYS3, tmp_path, sizes)
        n, nc = (2, 1) if sizes is None else (3, 2)
        try:
            f.s.enterInitializationMode(startTime=0.0)
            assert np.array_equal(f.real("M", n * n), np.eye(n).ravel())
            assert np.array_equal(f.real("K", n * n), 100 * np.eye(n).ravel())
            assert np.array_equal(f.real("W", nc * n), np.eye(nc, n).ravel())
            f.s.exitInitializationMode()
            f.s.doStep(0.0, 0.5)
            # F_c = 1 on every DOF against mu_s N = 0.4 held: the contacts' DOFs slide, each alone
            assert np.all(np.isfinite(f.real("x", n))) and f.real("h_used")[0] > 0
        finally:
            f.close()


@pytest.mark.parametrize("case", ["two_mass", "chain", "no time scale"])
def test_h_zero_derives_the_step_from_the_eigenvalues(case: str, tmp_path: Path) -> None:
    """h = 0: h_used is 1/1000 of 2 pi over sqrt(lambda_max(M^-1 K)) + lambda_max(M^-1 C) + omega (the
    eigenvalues by numpy here, by power iteration in the FMU), 1 ms without any time scale."""
    values = {"two_mass": two_mass_system(TM), "chain": chain_system(CHAIN),
              "no time scale": {"K": [0.0] * 4, "C": [0.0] * 4, "omega": 0.0}}[case]
    n = int(round(math.sqrt(len(np.ravel(values["K"])))))
    nc = len(values.get("N", [1.0]))
    f = Fmu3(SYS3, tmp_path, {"n": n, "nc": nc})
    try:
        f.start({**values, "h": 0.0})
        got = f.real("h_used")[0]
    finally:
        f.close()
    M = np.reshape(values.get("M", np.eye(n)), (n, n))
    K, C = (np.reshape(values[k], (n, n)) for k in ("K", "C"))
    rate = (math.sqrt(max(np.linalg.eigvals(np.linalg.solve(M, K)).real)) +
            max(np.linalg.eigvals(np.linalg.solve(M, C)).real) + values["omega"])
    want = 2 * math.pi / rate / 1000 if rate > 0 else 1e-3
    assert got == pytest.approx(want, rel=1e-8)


def test_the_generator_refuses_a_diagonal_start_of_a_vector(tmp_path: Path) -> None:
    src = ROOT / "fmu_src" / "models" / "system" / "modelDescription.xml"
    bad = src.read_text().replace('<DiagonalStart variable="W"', '<DiagonalStart variable="F_c"')
    (tmp_path / "md.xml").write_text(bad)
    r = subprocess.run([sys.executable, str(ROOT / "fmu_src" / "gen_model_vars.py"), str(tmp_path / "md.xml"),
                        str(tmp_path / "model_vars.h")], capture_output=True, text=True)
    assert r.returncode == 1 and "variable F_c: a DiagonalStart is for a Real matrix" in r.stderr


@pytest.mark.parametrize("scheme", ["consistent", "located"])
def test_friction_energy_closes_the_energy_balance(scheme: str, tmp_path: Path) -> None:
    """Over a run of TwoMass's structure with damping and stick-slip, the change of the mechanical
    energy 0.5 v'Mv + 0.5 x'Kx equals the work of the excitation minus the damping's dissipation
    (both integrated here from the outputs by the trapezoidal rule at every internal step) minus
    E_friction: to the schemes' error (second order in h, measured). The s output reads NaN, noted once."""
    p = two_mass_system(TM)
    M, K, C = (np.reshape(p[k], (2, 2)) for k in ("M", "K", "C"))
    h, T = TM["h"], 3.0
    steps = round(T / h)
    f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 2})
    try:
        f.start({**p, "scheme": SCHEMES[scheme]})
        X, V, E, t = [], [], [], np.arange(steps + 1) * h
        for k in range(steps + 1):
            if k:
                f.s.doStep(t[k - 1], h)
            X.append(f.real("x", 2))
            V.append(f.real("v", 2))
            E.append(f.real("E_friction")[0])
        assert np.all(np.isnan(f.real("s", 2))) and np.all(np.isnan(f.real("s", 2)))
        assert sum("variable s" in m for m in f.messages) == 1
    finally:
        f.close()
    X, V, E = np.array(X), np.array(V), np.array(E)
    P = np.outer(np.cos(TM["omega"] * t), p["F_c"])
    mech = 0.5 * np.einsum("ti,ij,tj->t", V, M, V) + 0.5 * np.einsum("ti,ij,tj->t", X, K, X)
    w_in = np.concatenate([[0.0], np.cumsum(0.5 * h * (np.sum(P[1:] * V[1:], 1) + np.sum(P[:-1] * V[:-1], 1)))])
    cv = np.einsum("ti,ij,tj->t", V, C, V)
    d = np.concatenate([[0.0], np.cumsum(0.5 * h * (cv[1:] + cv[:-1]))])
    assert E[0] == 0.0 and E[-1] > 0.1 * w_in.max()  # friction dissipates
    residual = mech - mech[0] - (w_in - d - E)
    # measured: 1.08e-5 (consistent), 1.14e-5 (located) of the input work's largest value, second
    # order in h (at h = 5e-4: 3.0e-6, 2.8e-6; at 2.5e-4: 8.5e-7, 7.0e-7; with alpha = 0 about the same)
    assert np.max(np.abs(residual)) <= 3e-5 * np.max(np.abs(w_in)), np.max(np.abs(residual)) / np.max(np.abs(w_in))
    # friction takes energy: E_friction never falls by more than the step's rounding of a reversal
    # (the step's force times its displacement; measured -1.7e-8 J at worst, against 0.29 J in all)
    assert np.diff(E).min() >= -1e-6 * E[-1]


@pytest.mark.parametrize("damping, backend", [("none", "modal"), ("rayleigh", "modal"), ("modal", "modal"),
                                              ("dashpot", "by dense Cholesky")])
def test_the_start_names_the_backend_of_the_solves(damping: str, backend: str, tmp_path: Path) -> None:
    """The start's event message names the solves' backend (system.h): modal where C is diagonal in
    the modal basis (C = 0, Rayleigh C = 0.1 M + 0.01 K, modal damping as System.with_modal_damping
    builds it: C's off-diagonal share at most 1e-12), by dense Cholesky for a dashpot 0.5 on one DOF
    (its share 1.8e-4 at h = 1 ms). (The two backends' trajectories: tests/c/test_system_modal.c; each
    against the event-driven reference: test_system_validation.py.)"""
    M, K = np.diag([1.0, 2.0, 1.5]), np.array([[40.0, -10.0, 0.0], [-10.0, 30.0, -5.0], [0.0, -5.0, 20.0]])
    C = {"none": np.zeros((3, 3)), "rayleigh": 0.1 * M + 0.01 * K,
         "modal": System(M=M, K=K).with_modal_damping(0.02).C,
         "dashpot": 0.1 * M + 0.01 * K + np.diag([0.5, 0.0, 0.0])}[damping]
    f = Fmu3(SYS3, tmp_path, {"n": 3, "nc": 1})
    try:
        f.start({"M": M, "K": K, "C": C, "F_c": [1.0, 0.0, 0.0], "F_s": [0.0] * 3, "x0": [0.0] * 3,
                 "v0": [0.0] * 3, "W": [[0.0, 1.0, -1.0]], "N": [1.0], "mu_s": [0.3], "mu_k": [0.25], "k_t": [0.0],
                 "omega": 3.0, "h": 1e-3})
        f.s.doStep(0.0, 0.1)
        start = [m for m in f.messages if m.startswith("start at t = ")]
    finally:
        f.close()
    assert len(start) == 1 and f"solves {backend} (C's off-diagonal share in the modal basis " in start[0], start
    share = float(start[0].split("modal basis ")[1].rstrip(").").split(")")[0])
    assert (share <= 1e-12) if backend == "modal" else (share >= 1e-4), start[0]
