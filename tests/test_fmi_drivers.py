"""The four drivers (OscillatorFMU2, OscillatorFMU3, ChainFMU2, ChainFMU3) on the package's one FMI
layer (dryfriction.fmi): the same x(t) as fmpy's simulate_fmu (the independent host) on the same
FMU, the former names are the same objects, run(t_stop, dt, ...) and do_step(dt) everywhere, the
chain's fast path equals its slow path bit for bit, FMU states through the shared driver, and the
one model-description reader (arrays, structural parameters, the effect table of both versions)."""

from __future__ import annotations

import inspect
import math
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from dryfriction import model, paths
from dryfriction.drivers.chain import ChainFMU2, ChainFMU3
from dryfriction.drivers.base import Driver
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.drivers.oscillator3 import OscillatorFMU3
from dryfriction.params import Oscillator

ROOT = Path(__file__).resolve().parents[1]
P = Oscillator()  # the model's start values: stick-slip with stops, breakaways and reversals
T = P.period
H = T / 400
DT = T / 40
T_STOP = 3 * T
DRIVERS = (OscillatorFMU2, OscillatorFMU3, ChainFMU2, ChainFMU3)


def close_to(a: np.ndarray, b: np.ndarray) -> None:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, (a.shape, b.shape)
    scale = max(1.0, float(np.max(np.abs(b))))
    assert float(np.max(np.abs(a - b))) <= 1e-12 * scale, float(np.max(np.abs(a - b)))


@pytest.fixture(scope="module")
def fmu3_path() -> Path:
    return paths.fmu_path(paths.OSCILLATOR3)


# ------------------------------------------------------------------ the same numbers as fmpy's host

def test_oscillator_fmu2_equals_simulate_fmu(fmu_path: Path) -> None:
    ref = simulate_fmu(str(fmu_path), stop_time=T_STOP, output_interval=DT, start_values={"h": H},
                       output=["x", "mode"])
    with OscillatorFMU2(fmu_path) as f:
        f.start(P, Settings(h=H))
        run = f.run(T_STOP, DT, ("x", "mode"))
    assert (run["mode"] == 0).any() and (run["mode"] != 0).any()
    close_to(run.time, ref["time"])
    close_to(run["x"], ref["x"])
    assert np.array_equal(run["mode"], ref["mode"])


def test_oscillator_fmu3_equals_simulate_fmu(fmu3_path: Path) -> None:
    ref = simulate_fmu(str(fmu3_path), stop_time=T_STOP, output_interval=DT, start_values={"h": H},
                       output=["x", "mode"])
    with OscillatorFMU3({"h": H}, fmu_path=fmu3_path) as f:
        run = f.run(T_STOP, DT, ("x", "mode"))
    assert (run["mode"] == 0).any() and (run["mode"] != 0).any()
    close_to(run.time, ref["time"])
    close_to(run["x"], ref["x"])


def test_chain_fmu2_equals_simulate_fmu(chain_fmu2: Path) -> None:
    with ChainFMU2(fmu_path=chain_fmu2) as f:
        n = f.n
        run = f.run(T_STOP, DT)  # the FMU's start values, as simulate_fmu uses them
    names = [f"x[{i}]" for i in range(1, n + 1)]
    ref = simulate_fmu(str(chain_fmu2), stop_time=T_STOP, output_interval=DT, output=names)
    assert np.max(np.abs(run.x)) > 1e-4  # it moves
    close_to(run.t, ref["time"])
    close_to(run.x, np.column_stack([ref[k] for k in names]))


def test_chain_fmu3_equals_simulate_fmu(chain_fmu3: Path) -> None:
    n = int(model.from_fmu(chain_fmu3).var("n").start)  # simulate_fmu cannot set n: its start value
    ref = simulate_fmu(str(chain_fmu3), stop_time=T_STOP, output_interval=DT, output=["x", "mode"])
    with ChainFMU3(n, fmu_path=chain_fmu3) as f:
        run = f.run(T_STOP, DT)
    assert np.max(np.abs(run.x)) > 1e-4
    close_to(run.t, ref["time"])
    close_to(run.x, ref["x"])
    assert np.array_equal(run.mode, ref["mode"])


# ------------------------------------------------------------------ the path functions, uniform signatures

def test_the_path_functions_are_thin_wrappers_of_fmu_path() -> None:
    """The drivers' default FMU paths are :func:`dryfriction.paths.fmu_path` of their kind (the
    former paths and names of the drivers: tests/test_layout.py)."""
    from dryfriction.drivers import chain, oscillator, oscillator3

    assert oscillator3.default_fmi3_path() == paths.fmu_path(paths.OSCILLATOR3)
    assert chain.default_chain_fmu3() == paths.fmu_path(paths.CHAIN3)
    assert chain.default_chain_fmu() == paths.fmu_path(paths.CHAIN)
    assert oscillator.default_fmu_path() == paths.fmu_path(paths.OSCILLATOR)


@pytest.mark.parametrize("cls", DRIVERS)
def test_run_and_do_step_have_the_same_signature(cls: type) -> None:
    assert issubclass(cls, Driver)
    run = list(inspect.signature(cls.run).parameters)
    assert run[:3] == ["self", "t_stop", "dt"], run
    step = list(inspect.signature(cls.do_step).parameters)
    assert step[:2] == ["self", "dt"], step
    for name in ("get", "set", "get_state", "set_state", "serialize_state", "restore", "close", "__enter__",
                 "__exit__"):
        assert callable(getattr(cls, name)), name
    assert cls.KIND in paths.KINDS


def test_do_step_dt_and_the_former_do_step_t_dt_agree(fmu: OscillatorFMU2) -> None:
    """OscillatorFMU2.do_step(dt) steps from the current time; do_step(t, dt) (the former
    signature, t the current communication point) gives the same bits."""
    def x_after(legacy: bool) -> list[float]:
        fmu.start(P, Settings(h=H))
        xs = []
        for k in range(40):
            if legacy:
                fmu.do_step(k * DT, DT)
            else:
                fmu.do_step(DT)
            xs.append(fmu.get("x"))
        return xs

    a, b = x_after(False), x_after(True)
    assert a == b and len(set(a)) > 10
    assert fmu.time == pytest.approx(40 * DT, rel=1e-14)


def test_chain_do_step_and_step_to(chain_fmu3: Path) -> None:
    with ChainFMU3(3, fmu_path=chain_fmu3) as f:
        ref = f.run(20 * DT, DT, {"h": H})
        f.start({"h": H})
        for k in range(1, 21):
            f.step_to(float(ref.t[k]))
        assert np.array_equal(f.get("x"), ref.x[-1])
        with pytest.raises(ValueError, match="dt must be a finite number > 0"):
            f.do_step(0.0)


# ------------------------------------------------------------------ the fast path is the slow path

@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
def test_chain_fast_path_equals_the_slow_path_bit_for_bit(which: str, chain_fmu2: Path, chain_fmu3: Path) -> None:
    """run(): every point's outputs read by one typed call per type into preallocated rows (the
    layer's bulk_get); the slow path: step_to and a checked get by name per output (ctypes arrays
    built per call). The same bits."""
    params = {"h": H, "omega": 0.9, "N": 0.7, "chi": 0.6, "v0": 0.1}
    make = (lambda: ChainFMU2(fmu_path=chain_fmu2)) if which == "fmi2" else (lambda: ChainFMU3(4, fmu_path=chain_fmu3))
    with make() as f:
        fast = f.run(6 * T, DT, params)
        f.start(params)
        rows: dict[str, list[np.ndarray]] = {k: [np.asarray(f.get(k))] for k in ("x", "v", "a", "F_friction", "mode")}
        for t in fast.t[1:]:
            f.step_to(float(t))
            for k in rows:
                rows[k].append(np.asarray(f.get(k)))
    assert (fast.mode == 0).any() and (fast.mode != 0).any()
    for k, r in rows.items():
        slow = np.array(r)
        got = getattr(fast, k)
        assert slow.shape == got.shape, k
        if k == "mode":
            assert np.array_equal(slow, got), k
        else:
            assert np.array_equal(slow.view(np.int64), np.ascontiguousarray(got).view(np.int64)), k


# ------------------------------------------------------------------ FMU states through the driver

@pytest.mark.parametrize("cls", DRIVERS)
def test_state_save_restore_and_bytes_through_every_driver(cls: type, fmu_path: Path, fmu3_path: Path,
                                                           chain_fmu2: Path, chain_fmu3: Path) -> None:
    def make() -> Driver:
        if cls is OscillatorFMU2:
            f = OscillatorFMU2(fmu_path)
            f.start(P, Settings(h=H))
            return f
        if cls is OscillatorFMU3:
            return OscillatorFMU3({"h": H}, fmu_path=fmu3_path)
        f = ChainFMU2(fmu_path=chain_fmu2) if cls is ChainFMU2 else ChainFMU3(3, fmu_path=chain_fmu3)
        f.start({"h": H})
        return f

    def advance(f: Driver, k: int) -> list[np.ndarray]:
        out = []
        for _ in range(k):
            f.do_step(DT)
            out.append(np.asarray(f.get("x"), dtype=float))
        return out

    with make() as f:
        advance(f, 7)
        t1 = f.time
        with f.get_state() as st:
            data = f.serialize_state(st)
            a = advance(f, 12)
            f.set_state(st)
            assert f.time == t1  # the driver's time follows the state
            b = advance(f, 12)
        assert np.array_equal(np.array(a), np.array(b))
        with make() as g:  # another instance: the bytes carry the whole run
            g.restore(data)
            assert g.time == t1
            assert np.array_equal(np.array(advance(g, 12)), np.array(a))


# ------------------------------------------------------------------ one model-description reader

def test_the_reader_reads_both_chains_arrays_and_the_structural_parameter(chain_fmu2: Path, chain_fmu3: Path) -> None:
    import zipfile
    from xml.etree import ElementTree as ET

    md3 = model.from_fmu(chain_fmu3)
    root = ET.fromstring(zipfile.ZipFile(chain_fmu3).read("modelDescription.xml"))
    n_el = root.find("ModelVariables/UInt64[@name='n']")
    assert n_el is not None
    n = md3.var("n")
    assert md3.fmi_version == "3.0" and md3.structural_parameters() == ("n",)
    assert (n.type, n.min, n.max, n.start) == ("UInt64", int(n_el.get("min")), int(n_el.get("max")), int(n_el.get("start")))
    assert md3.var("m").dimension == "n" and md3.var("m").call_type == "Float64"
    assert md3.var("scheme").call_type == "Int64" and md3.var("mode").call_type == "Int32"
    assert md3.var("h_used").dimension is None
    assert md3.arrays()["x"] == ("x",)
    md2 = model.from_fmu(chain_fmu2)
    n2 = len(md2.arrays()["m"])
    assert md2.structural_parameters() == ()
    assert md2.arrays()["F_ext"] == tuple(f"F_ext[{i}]" for i in range(1, n2 + 1))
    assert set(md2.arrays()) == set(md3.arrays())
    assert md2.schemes == md3.schemes
    sources = sorted(ROOT.glob("fmu_src/**/chain/modelDescription.xml"))
    if sources:  # the chain's source description: dimension="n"
        src = model.from_xml(sources[0])
        assert src.var("n").causality == "structuralParameter" and src.var("x").dimension == "n"
        assert set(src.arrays()) == set(md3.arrays())


def test_both_oscillator_descriptions_give_the_same_variables_and_effects(fmu_path: Path, fmu3_path: Path) -> None:
    md2, md3 = model.from_fmu(fmu_path), model.from_fmu(fmu3_path)
    assert md2.effects == md3.effects and md2.effects and md2.effects_variable == md3.effects_variable == "effects"
    assert md2.schemes == md3.schemes and md2.guid == md3.guid
    names3 = [n for n in md3.variables if n != "time"]
    assert names3 == list(md2.variables)
    for name in names3:
        a, b = md2.var(name), md3.var(name)
        assert (a.vr, a.causality, a.unit, a.zero) == (b.vr, b.causality, b.unit, b.zero), name
        assert a.start == b.start or (isinstance(a.start, float) and math.isclose(a.start, b.start)), name
        assert a.is_real == b.is_real, name
    # the same range sentence from either description
    for name, value in (("m", 0.0), ("alpha", 0.1), ("frictionUpdates", 101), ("h", math.nan)):
        with pytest.raises(ValueError) as e2:
            md2.check(name, value)
        with pytest.raises(ValueError) as e3:
            md3.check(name, value)
        assert str(e2.value) == str(e3.value)
