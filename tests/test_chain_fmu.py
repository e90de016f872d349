"""The chain's FMUs (FMI 3.0 build/fmi3/DryFrictionChain.fmu with n set in Configuration Mode, FMI
2.0 build/DryFrictionChain.fmu with its built n) driven by dryfriction.drivers.chain, against independent
numbers: the oscillator FMU (n = 1), each other (n = 2), the C chain's own driver
(tests/c/chain_driver: the same physics, so the same bits), the event-driven reference
(dryfriction.references.chain: the errors and orders of docs/chain.md), the energy balance from the
outputs, fmpy's and the FMU Manipulation Toolbox's checks and the FMU's errors for bad input.
(Elsewhere: the command, test_cli_chain.py; libcosim, test_hosts.py; held inputs, test_inputs.py.)"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from dryfriction.errors import FMUCallError
from dryfriction.drivers.chain import ChainFMU3, ChainFMU2, ChainRun
from dryfriction.diagnostics import DryFrictionWarning
from dryfriction.references.chain import Chain
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from chain_cases import CASES, PERIODS, chain_params, run_driver
from helpers import assert_rounding_apart


def fmu_run(ch: Chain, t_end: float, h: float, dt: float, chain_fmu3: Path, **kw) -> ChainRun:
    with ChainFMU3(ch.n, fmu_path=chain_fmu3) as f:
        return f.run(t_end, dt, chain_params(ch, h, **kw))


# ---- n = 1 is the oscillator ------------------------------------------------------------------

ONE_BLOCK = [dict(m=1.0, k=1.0, c=0.0, P0=1.0, omega=0.5, N=0.8, mu_s=0.5, chi=0.7, x0=0.0, v0=0.0),
             dict(m=2.0, k=3.0, c=0.2, P0=1.5, omega=1.1, N=0.6, mu_s=0.4, chi=1.4, x0=0.3, v0=-0.2),
             dict(m=1.0, k=100.0, c=0.0, P0=1.0, omega=5.0, N=1.0, mu_s=0.4, chi=0.3, x0=0.0, v0=0.0)]


@pytest.mark.parametrize("case", range(len(ONE_BLOCK)))
@pytest.mark.parametrize("scheme", ["located", "consistent", "paper"])
def test_n1_is_the_oscillator_fmu_to_rounding(case: int, scheme: str, chain_fmu3: Path, fmu: OscillatorFMU2) -> None:
    """One block of the FMI 3.0 chain gives the oscillator FMU's mode at every communication point
    (phi = 0; docs/chain.md says why a phase rounds apart), in every scheme, and its x, v, a and
    F_friction to rounding (helpers.CHAIN_N1_REL: the oscillator steps through the friction engine,
    the chain through its own stepper, their arithmetic ordered otherwise)."""
    b = ONE_BLOCK[case]
    p = Oscillator(phi=0.0, **b)
    T = p.period
    h, dt = T / 500, T / 50
    with ChainFMU3(1, fmu_path=chain_fmu3) as f:
        run = f.run(6 * T, dt, {**b, "phi": 0.0, "h": h, "alpha": -0.1, "scheme": scheme})
    ref = fmu.trajectory(p, run.t, Settings(h=h, alpha=-0.1, scheme=scheme))
    assert (run.mode == 0).any() and (run.mode != 0).any()
    assert np.array_equal(run.mode[:, 0], ref["mode"])
    for k in ("x", "v", "a", "F_friction"):
        assert_rounding_apart(getattr(run, k)[:, 0], ref[k], k)
    stuck = run.mode[:, 0] == 0
    Fb = max(b["mu_s"], b["chi"] * b["mu_s"]) * b["N"]
    assert np.all(np.abs(run.F_friction[stuck, 0]) <= Fb * (1 + 1e-12))


# ---- FMI 2.0 == FMI 3.0 ---------------------------------------------------------------------------

def test_fmi2_and_fmi3_chains_give_the_same_bits(chain_fmu2: Path, chain_fmu3: Path) -> None:
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        n = f2.n
        ch = Chain.make(n, omega=0.6, k_end=0.5, c=0.05, N=np.linspace(0.3, 0.6, n), chi=0.8,
                        P0=np.linspace(1.0, 0.4, n), phi=np.linspace(0.0, 1.0, n), v0=0.1)
        T = ch.period
        a = f2.run(8 * T, T / 70, chain_params(ch, T / 600))
    b = fmu_run(ch, 8 * T, T / 600, T / 70, chain_fmu3)
    assert (a.mode == 0).any() and (a.mode != 0).any()
    assert np.array_equal(a.t, b.t)
    for k in ("x", "v", "a", "F_friction", "mode"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k


# ---- the FMU against the C chain and the reference ----------------------------------------------

@pytest.mark.parametrize("n", [1, 3, 8])
def test_fmi3_chain_equals_the_c_driver(n: int, chain_fmu3: Path) -> None:
    """fmpy's FMU3Slave with n set in Configuration Mode: the C chain's numbers (chain_driver), bit
    for bit, for n = 1, 3, 8."""
    ch = Chain.make(n, omega=0.7, k_end=1.5, c_end=0.1, c=0.05, N=np.linspace(0.8, 1.2, n),
                    P0=np.where(np.arange(n) % 2 == 0, 1.0, 0.3), phi=0.2 * np.arange(n),
                    x0=np.linspace(0.1, -0.1, n), v0=0.2)
    T = ch.period
    dt = T / 100
    run = fmu_run(ch, 500 * dt, T / 400, dt, chain_fmu3)  # the driver's points k dt
    drv = run_driver(ch, 500 * dt, T / 400, dt=dt)
    assert run.x.shape == (501, n) and np.array_equal(run.t, drv["t"])
    assert (run.mode == 0).any() and (run.mode != 0).any()
    for k, d in (("x", "x"), ("v", "v"), ("F_friction", "F"), ("mode", "mode")):
        assert np.array_equal(getattr(run, k), drv[d]), k


# docs/chain.md, "Validation of the C chain": located, T/400 ... T/3200
DOC_ERRORS = {"stick-dominated": (2.27e-4, 5.66e-5, 1.41e-5, 3.54e-6),
              "friction-on-one": (2.74e-3, 6.86e-4, 1.71e-4, 4.29e-5),
              "chi-mixed": (7.20e-3, 1.81e-3, 4.54e-4, 1.14e-4),
              "damped-walled": (1.60e-4, 3.99e-5, 9.98e-6, 2.50e-6)}


@pytest.mark.parametrize("case", list(DOC_ERRORS))
def test_located_error_against_the_reference(case: str, refs: dict, chain_fmu3: Path) -> None:
    """Through the FMU, max |x - x_ref| over 10 periods is the error docs/chain.md reports (3
    digits) and falls 4x per halving of h."""
    ch, ref = CASES[case], refs[case]
    T = ch.period
    errs = []
    for ppp in (400, 800, 1600, 3200):
        run = fmu_run(ch, PERIODS * T, T / ppp, T / 100, chain_fmu3)
        errs.append(float(np.max(np.abs(run.x - ref.evaluate(run.t)["x"]))))
    e = np.array(errs)
    np.testing.assert_allclose(e, DOC_ERRORS[case], rtol=6e-3)
    ratios = e[:-1] / e[1:]
    assert np.all((ratios > 3.6) & (ratios < 4.4)), ratios


def test_located_second_order_with_random_communication_steps(refs: dict, chain_fmu3: Path) -> None:
    """Communication steps drawn in [0.1 h, 3 h] through fmi3DoStep: still 4x per halving."""
    ch = CASES["chi-mixed"]
    T = ch.period
    rng = np.random.default_rng(7)
    errs = []
    with ChainFMU3(ch.n, fmu_path=chain_fmu3) as f:
        for ppp in (400, 800, 1600):
            h = T / ppp
            f.start(chain_params(ch, h))
            ts, xs = [0.0], [f.outputs()["x"]]
            while f.time < PERIODS * T:
                f.step_to(min(f.time + h * rng.uniform(0.1, 3.0), PERIODS * T))
                ts.append(f.time)
                xs.append(f.outputs()["x"])
            errs.append(float(np.max(np.abs(np.array(xs) - refs["chi-mixed"].evaluate(ts)["x"]))))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 3.4) & (ratios < 4.6)), (errs, ratios)


def test_energy_balance_from_the_outputs(chain_fmu3: Path) -> None:
    """E - E0 = W_applied + W_friction - D_damping with the works integrated (trapezoid) from the
    outputs at every internal step: the residual is O(h^2)."""
    ch = CASES["damped-walled"]
    K, C = ch.matrices()
    T = ch.period
    res = []
    for ppp in (200, 400, 800):
        h = T / ppp
        r = fmu_run(ch, 3 * T, h, h, chain_fmu3)
        P = np.cos(ch.omega * r.t[:, None] + ch.phi[None, :]) * ch.P0[None, :]
        E = 0.5 * np.einsum("ij,j,ij->i", r.v, ch.m, r.v) + 0.5 * np.einsum("ij,jk,ik->i", r.x, K, r.x)
        power = np.einsum("ij,ij->i", P + r.F_friction, r.v) - np.einsum("ij,jk,ik->i", r.v, C, r.v)
        work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(r.t))])
        res.append(np.max(np.abs(E - E[0] - work)))
    ratios = np.array(res[:-1]) / np.array(res[1:])
    assert np.all((ratios > 3.3) & (ratios < 4.7)), (res, ratios)
    assert res[-1] < 1e-3


# ---- FMI checks ---------------------------------------------------------------------------------

@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
def test_fmpy_validate_and_fmu_info(which: str, chain_fmu2: Path, chain_fmu3: Path) -> None:
    from fmpy.util import fmu_info
    from fmpy.validation import validate_fmu

    path = chain_fmu2 if which == "fmi2" else chain_fmu3
    assert validate_fmu(str(path)) == []
    info = fmu_info(str(path))
    assert "DryFrictionChain" in info and "Co-Simulation" in info
    assert ("2.0" if which == "fmi2" else "3.0") in info


@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
def test_fmutool_check_reports_compliant(which: str, chain_fmu2: Path, chain_fmu3: Path) -> None:
    exe = shutil.which("fmutool") or str(Path(sys.executable).with_name("fmutool"))
    path = chain_fmu2 if which == "fmi2" else chain_fmu3
    r = subprocess.run([exe, "-input", str(path), "-check"], capture_output=True, text=True, timeout=120)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert f"compliant with FMI-{2 if which == 'fmi2' else 3}.0" in out, out
    assert "No semantic error" in out, out
    assert "ERROR" not in out, out


def test_structured_names_and_dimensions(chain_fmu2: Path, chain_fmu3: Path) -> None:
    """FMI 2.0: m[1] ... x[n] for every array; FMI 3.0: each array one variable of dimension n
    (the structural parameter n, UInt64, start 2, min 1, max >= 4096)."""
    import zipfile
    from xml.etree import ElementTree as ET

    from fmpy import read_model_description

    md3 = read_model_description(str(chain_fmu3))
    v3 = {v.name: v for v in md3.modelVariables}
    n = v3["n"]
    assert n.type == "UInt64" and n.causality == "structuralParameter" and int(n.start) == 2
    xml = ET.fromstring(zipfile.ZipFile(chain_fmu3).read("modelDescription.xml"))
    n_el = xml.find("ModelVariables/UInt64[@name='n']")
    assert n_el is not None and int(n_el.get("min")) == 1 and int(n_el.get("max")) >= 4096
    for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0", "F_ext", "N_ext", "x", "v", "a",
                 "F_friction", "mode"):
        dims = v3[name].dimensions
        assert len(dims) == 1 and dims[0].valueReference == n.valueReference, name
    for name in ("k_end", "c_end", "omega", "h", "alpha", "scheme"):
        assert not v3[name].dimensions, name
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        names = set(f2.md.variables)
        for name in ("m", "x0", "F_ext", "x", "mode"):
            assert {f"{name}[{i}]" for i in range(1, f2.n + 1)} <= names, name
            assert f"{name}[{f2.n + 1}]" not in names


# ---- bad input ------------------------------------------------------------------------------------

@pytest.mark.parametrize("n", [0, 5000])
def test_n_outside_its_range_is_the_fmus_error(n: int, chain_fmu3: Path) -> None:
    with ChainFMU3(n, fmu_path=chain_fmu3) as f:
        with pytest.raises(FMUCallError, match=rf"invalid value {n} for n .*valid range: in \[1, 4096\]"):
            f.run(1.0, 0.1)
        f.set_n(4)  # the instance recovers: reset, Configuration Mode again
        assert f.run(1.0, 0.1).x.shape == (11, 4)


def test_bad_array_values_name_the_element(chain_fmu3: Path, chain_fmu2: Path) -> None:
    m = [1.0, 1.0, -1.0]
    with ChainFMU3(3, fmu_path=chain_fmu3) as f:
        with pytest.raises(FMUCallError, match=r"invalid value -1 for m\[3\]"):
            f.run(1.0, 0.1, {"m": m})
        # the instance stays usable
        assert f.run(1.0, 0.1, {"m": 1.0}).x.shape == (11, 3)
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        bad = [1.0] * (f2.n - 1) + [-1.0]
        with pytest.raises(FMUCallError, match=rf"invalid value -1 for m\[{f2.n}\]"):
            f2.run(1.0, 0.1, {"m": bad})


def test_wrong_array_length(chain_fmu3: Path) -> None:
    """The driver names the parameter and n; the FMU itself refuses a wrong nValues."""
    with ChainFMU3(3, fmu_path=chain_fmu3) as f:
        with pytest.raises(ValueError, match=r"m needs 3 values \(one per block, n = 3\)"):
            f.run(1.0, 0.1, {"m": [1.0, 2.0]})
        f._begin(0.0)  # Configuration Mode (n = 3), then Initialization Mode
        with pytest.raises(FMUCallError, match=r"nValues = 2, but the variables given hold 3 values: m \(3\)"):
            f.set_raw("m", [1.0, 2.0])


# ---- the docs' example ---------------------------------------------------------------------------

def test_the_docs_chain_example() -> None:
    """The chain example of docs/chain.md runs as printed and prints what its comment says."""
    import contextlib
    import io
    import re

    readme = (Path(__file__).resolve().parents[1] / "docs" / "chain.md").read_text()
    block = re.search(r"```python\n(from dryfriction import ChainFMU3\n.*?)```", readme, re.S)
    assert block is not None
    code = block.group(1)
    assert len(code.strip().splitlines()) == 5
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        exec(compile(code, "docs/chain.md", "exec"), {})
    shown = re.search(r"print\(run.stick_share\(\).round\(2\)\).*# (\[[0-9. ]+\])", readme)
    assert shown is not None
    printed = [float(x) for x in buf.getvalue().strip(" []\n").split()]
    assert printed == [float(x) for x in shown.group(1).strip("[]").split()]


@pytest.mark.parametrize("which", ["fmi3", "fmi2"])
def test_a_step_that_does_not_resolve_the_dynamics_is_a_warning(which: str, chain_fmu2: Path, chain_fmu3: Path) -> None:
    """Stiff springs (k = 1e5 on unit masses: periods down to about 10 ms) with h = 1 ms:
    fewer than 20 steps per shortest period, the FMU's warning names h and the step to choose; the
    run still runs. k = 1e3 resolves it: no warning."""
    import warnings

    def run(k: float) -> tuple[list[str], int]:
        params = {"k": k, "h": 1e-3}
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if which == "fmi3":
                with ChainFMU3(3, fmu_path=chain_fmu3) as f:
                    r = f.run(0.05, 0.01, params)
            else:
                with ChainFMU2(fmu_path=chain_fmu2) as f:
                    r = f.run(0.05, 0.01, params)
        assert np.all(np.isfinite(r.x))
        return [str(w.message) for w in caught if issubclass(w.category, DryFrictionWarning)], r.x.shape[1]

    said, n = run(1e5)
    # Gershgorin's bound of max eig M^-1 K with a free right end: 4k for n >= 3, 3k for n = 2
    T_min = 2 * np.pi / np.sqrt((4.0 if n >= 3 else 3.0) * 1e5)
    assert len(said) == 1 and "h = 0.001 s takes only" in said[0], said
    assert f"Choose h <= {T_min / 1000:.6g} s" in said[0], (said, T_min)
    assert run(1e3)[0] == []


def test_h_zero_derives_the_step_from_the_dynamics(chain_fmu2: Path, chain_fmu3: Path) -> None:
    """h = 0 (the start value): h_used is 1/1000 of the chain's shortest period (Gershgorin's bound
    of its fastest natural frequency; here the springs: 2 pi / sqrt(4 k / m) for n = 3 with a free
    end, 2 pi / sqrt(3 k / m) for n = 2), the same in both FMUs for the same n, and the run is the
    run with that h set explicitly, bit for bit."""
    params = {"k": 50.0, "m": 2.0, "omega": 1.5, "mu_s": 0.3, "chi": 0.7, "N": 1.0, "P0": 1.0}
    with ChainFMU3(3, fmu_path=chain_fmu3) as f:
        derived = f.run(3.0, 0.05, {**params, "h": 0.0})
        h3 = float(f.get("h_used"))
        explicit = f.run(3.0, 0.05, {**params, "h": h3})
        assert float(f.get("h_used")) == h3
    assert h3 == pytest.approx(2 * np.pi / np.sqrt(4 * 50.0 / 2.0) / 1000, rel=1e-15)
    assert (derived.mode == 0).any() and (derived.mode != 0).any()
    for k in ("x", "v", "a", "F_friction", "mode"):
        assert np.array_equal(getattr(derived, k), getattr(explicit, k)), k
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        f2.run(0.1, 0.05, {**params, "h": 0.0})
        n2, h2 = f2.n, float(f2.get("h_used"))
    g = 4.0 if n2 >= 3 else 3.0
    assert h2 == pytest.approx(2 * np.pi / np.sqrt(g * 50.0 / 2.0) / 1000, rel=1e-15)
