"""The package's one FMI layer (dryfriction.fmi2) and the model description it is driven by
(dryfriction.model): statuses, errors, FMU states through OscillatorFMU, instances in threads,
and the names, ranges, schemes and effect bits read from modelDescription.xml."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from dryfriction import fmi2, model
from dryfriction.fmu import OBSERVABLE_OUTPUTS, FMUError, OscillatorFMU, Settings
from dryfriction.params import Oscillator
from dryfriction.sweep.runner import PARAM_COLUMNS, BatchRunner

REPO_XML = Path(__file__).resolve().parents[1] / "modelDescription.xml"


# --------------------------------------------------------------------------- statuses, errors


def test_status_constants_are_fmi2s() -> None:
    assert (fmi2.OK, fmi2.WARNING, fmi2.DISCARD, fmi2.ERROR, fmi2.FATAL, fmi2.PENDING) == (0, 1, 2, 3, 4, 5)
    assert fmi2.STATUS_NAMES[fmi2.DISCARD] == "fmi2Discard"


@pytest.mark.min_versions
def test_check_accepts_ok_and_warning_and_raises_on_anything_else(fmu: OscillatorFMU) -> None:
    inst = fmu.fmi
    assert inst.check("fmi2GetReal", fmi2.OK) == fmi2.OK
    assert inst.check("fmi2GetReal", fmi2.WARNING) == fmi2.WARNING
    for status in (fmi2.DISCARD, fmi2.ERROR, fmi2.FATAL, fmi2.PENDING):
        with pytest.raises(FMUError) as err:
            inst.check("fmi2DoStep", status, since=len(inst.messages))
        assert (err.value.function, err.value.status) == ("fmi2DoStep", status)
        assert str(err.value).startswith(f"fmi2DoStep returned {fmi2.STATUS_NAMES[status]}: ")


def test_a_failed_step_raises_with_the_fmus_sentence(fmu: OscillatorFMU) -> None:
    """doStep that overflows: FMUError naming fmi2DoStep and fmi2Error with the FMU's sentence;
    reset recovers."""
    fmu.start(Oscillator(P0=1e307, N=0.0, omega=0.0, k=1e-300), Settings(h=1e-3))
    with pytest.raises(FMUError, match="non-finite") as err:
        fmu.step_to(1e6)
    assert (err.value.function, err.value.status) == ("fmi2DoStep", fmi2.ERROR)
    r = fmu.trajectory(Oscillator(), [0.0, 0.1], Settings(h=1e-3))
    assert math.isfinite(r["x"][-1]) and r["x"][-1] != 0.0


def test_observables_read_without_observe_are_not_an_error(fmu: OscillatorFMU) -> None:
    """The FMU answers a read of the observables with observe off (the driver's default) by fmi2OK
    and NaN (transitions -1), not a number that looks like a result; the driver itself never asks
    (trajectory refuses the request)."""
    fmu.start(Oscillator(), Settings(h=1e-3))
    fmu.step_to(0.1)
    got = fmu.get(list(OBSERVABLE_OUTPUTS))
    assert got["transitions"] == -1
    assert all(math.isnan(v) for k, v in got.items() if k != "transitions"), got
    with pytest.raises(ValueError, match="observe=True"):
        fmu.trajectory(Oscillator(), [0.0, 0.1], Settings(h=1e-3), outputs=("x", "x_max"))
    r = fmu.trajectory(Oscillator(), [0.0, 0.1], Settings(h=1e-3, observe=True), outputs=("x", "x_max"))
    assert r["x_max"][-1] >= r["x"][-1]


def test_batch_runner_strict_error_names_the_run_and_the_call(fmu_path: Path) -> None:
    p = Oscillator()
    row = dict(p.as_dict(), h=1e-3, alpha=-0.1, t_obs_start=0.0, t_obs_stop=1.0, t_stop=1.0)
    table = np.array([[row[c] for c in PARAM_COLUMNS]] * 2)
    table[1, PARAM_COLUMNS.index("alpha")] = 0.5
    r = BatchRunner(str(fmu_path))
    try:
        out = r.run(table)
        assert out[0, -1] == 0.0 and out[1, -1] == 1.0 and np.isnan(out[1, 0])
        with pytest.raises(FMUError, match="run 1: .*variable alpha") as err:
            r.run(table, strict=True)
        assert err.value.function == "fmi2SetReal"
        assert len(r.fmu.messages) == 0  # nothing accumulates over a sweep
    finally:
        r.close()


# --------------------------------------------------------------------------- FMU states


def test_state_round_trip_through_the_driver_is_bit_exact(fmu: OscillatorFMU) -> None:
    p = Oscillator(x0=0.004, chi=0.5)
    st = Settings(h=7e-4, observe=True)
    t = 37 * 0.0123 + np.arange(201) * 0.01
    fmu.start(p, st)
    fmu.step_to(t[0])
    with fmu.get_state() as state:
        outs = ("x", "v", "a", "F_friction", "mode", "E_friction", "stick_fraction", "transitions")

        def run() -> np.ndarray:
            rows = []
            for k in range(1, t.size):
                fmu.step_to(t[k])
                rows.append(list(fmu.get(outs).values()))
            return np.array(rows)

        a = run()
        fmu.set_state(state)
        assert fmu.time == t[0]  # the driver's time follows the state
        b = run()
        assert np.array_equal(a, b)
        data = fmu.serialize_state(state)
    assert state.freed
    # into another instance that was only instantiated: the state carries the whole setup
    with OscillatorFMU(fmu.path) as other:
        other.restore(data)
        assert other.time == t[0]
        assert other.serialize_state() == data
        other.step_to(t[1])
        assert np.array_equal(list(other.get(outs).values()), a[0])
    with pytest.raises(FMUError) as err:
        fmu.deserialize_state(data[:-1])
    assert err.value.function == "fmi2DeSerializeFMUstate"
    with pytest.raises(ValueError, match="freed"):
        fmu.set_state(state)


def test_states_left_open_are_freed_with_the_instance(fmu_path: Path) -> None:
    f = OscillatorFMU(fmu_path)
    f.start(Oscillator(), Settings(h=1e-3))
    states = [f.get_state() for _ in range(3)]
    f.close()
    assert all(s.freed for s in states)


# --------------------------------------------------------------------------- threads


def _serial_run(fmu_path: Path, k: int) -> np.ndarray:
    with OscillatorFMU(fmu_path) as f:
        p = Oscillator(omega=3.0 + 0.25 * k, x0=0.001 * (k % 7), chi=0.2 + 0.1 * k)
        st = Settings(h=7e-4, scheme=list(f.md.schemes)[k % 3])
        r = f.trajectory(p, np.arange(101) * 0.01, st)
        return np.column_stack([r[n] for n in ("x", "v", "a", "F_friction", "mode")])


def test_driver_instances_in_threads_match_serial_runs(fmu_path: Path) -> None:
    """The driver in 8 threads (each its own OscillatorFMU: unzip, load, callbacks) gives the
    serial numbers bit for bit. (The FMU's own reentrancy, 32 C threads: tests/fmi_c.)"""
    serial = [_serial_run(fmu_path, k) for k in range(8)]
    with ThreadPoolExecutor(max_workers=8) as ex:
        parallel = list(ex.map(lambda k: _serial_run(fmu_path, k), range(8)))
    for k in range(8):
        assert np.array_equal(serial[k], parallel[k]), k
    assert len({a.tobytes() for a in serial}) == 8


# --------------------------------------------------------------------------- the model description


@pytest.mark.min_versions
def test_model_module_reads_what_the_xml_declares() -> None:
    md = model.from_xml(REPO_XML)
    root = ET.parse(REPO_XML).getroot()
    svs = root.findall("ModelVariables/ScalarVariable")
    assert list(md.variables) == [sv.get("name") for sv in svs]
    for sv in svs:
        v = md.var(sv.get("name"))
        assert v.vr == int(sv.get("valueReference")) and v.causality == sv.get("causality")
        el = next(iter(sv))
        assert v.type == el.tag and v.unit == el.get("unit")
        if el.get("min") is not None:
            assert v.min == float(el.get("min"))
    items = root.findall("TypeDefinitions/SimpleType[@name='Scheme']/Enumeration/Item")
    assert md.schemes == {i.get("name"): int(i.get("value")) for i in items}
    bits = root.findall("VendorAnnotations/Tool[@name='dryfriction']/Effects/Effect")
    assert [(e.bit, e.name) for e in md.effects] == [(int(b.get("bit")), b.get("name")) for b in bits]
    assert md.effects_variable == "effects"
    # the package's defaults are the declared starts (h: None, period / 1000, by design; observe:
    # off unless a run reads the observables, by design, the FMU's own start being true)
    p, st = Oscillator(), Settings()
    assert md.parameter_starts()["observe"] is True and st.observe is False
    for name, start in md.parameter_starts().items():
        if name in ("h", "observe"):
            continue
        value = getattr(p, name) if hasattr(p, name) else getattr(st, name)
        if name == "scheme":
            value = md.schemes[value]
        assert value == start, name
    assert PARAM_COLUMNS[:-1] == tuple(n for n in md.names("parameter") if md.var(n).type == "Real")


def test_fmus_own_description_equals_the_repositorys(fmu: OscillatorFMU) -> None:
    assert fmu.md == model.from_xml(REPO_XML)


@pytest.mark.parametrize("name,value,valid", [
    ("m", 0.0, "> 0"), ("k", -1.0, ">= 0"), ("alpha", 0.1, "in [-0.333333, 0]"), ("alpha", -0.34, "in [-0.3"),
    ("h", math.nan, "finite"), ("P0", math.inf, "finite"), ("frictionUpdates", 101, "in [0, 100]"),
    ("scheme", "fast", "one of paper, consistent, located, exact"), ("scheme", 5, "one of paper"),
])
def test_python_values_are_checked_against_the_declared_range(name: str, value: object, valid: str) -> None:
    md = model.default()
    with pytest.raises(ValueError, match=f"invalid value .* for variable {name}; valid range: ") as err:
        md.check(name, value)
    assert valid in str(err.value), str(err.value)


@pytest.mark.parametrize("name,value", [("m", 1e-300), ("alpha", -1 / 3), ("alpha", 0.0), ("frictionUpdates", 0),
                                        ("scheme", "paper"), ("scheme", 3), ("observe", True), ("x0", -5.0)])
def test_valid_python_values_pass(name: str, value: object) -> None:
    model.default().check(name, value)


def test_effects_are_named_by_the_vendor_annotation(fmu: OscillatorFMU) -> None:
    fmu.start(Oscillator(c=0.5, chi=1.0), Settings(h=1e-3, observe=True))
    mask = int(fmu.get(["effects"])["effects"])
    assert fmu.effects() == [e.name for e in fmu.md.effects if mask & e.bit]
    assert set(fmu.effects()) == {"friction", "damping", "observables"}
