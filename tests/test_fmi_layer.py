"""The package's FMI 2.0 layer (dryfriction.fmi.fmi2) through OscillatorFMU2: statuses, errors (an
FMUError names the function, the status and the FMU's sentence), observables read without observe,
the batch runner's strict error, instances in threads. (FMU states: test_fmu_state.py; what
dryfriction.model reads from the XML: test_model_description.py; the Python range checks:
test_params.py.)"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from dryfriction.fmi import fmi2
from dryfriction.drivers.oscillator import FMUError, OBSERVABLE_OUTPUTS, OscillatorFMU2, Settings
from dryfriction.params import Oscillator
from dryfriction.sweep.runner import BatchRunner, PARAM_COLUMNS


# --------------------------------------------------------------------------- statuses, errors


def test_status_constants_are_fmi2s() -> None:
    assert (fmi2.OK, fmi2.WARNING, fmi2.DISCARD, fmi2.ERROR, fmi2.FATAL, fmi2.PENDING) == (0, 1, 2, 3, 4, 5)
    assert fmi2.STATUS_NAMES[fmi2.DISCARD] == "fmi2Discard"


@pytest.mark.min_versions
def test_check_accepts_ok_and_warning_and_raises_on_anything_else(fmu: OscillatorFMU2) -> None:
    inst = fmu.fmi
    assert inst.check("fmi2GetReal", fmi2.OK) == fmi2.OK
    assert inst.check("fmi2GetReal", fmi2.WARNING) == fmi2.WARNING
    for status in (fmi2.DISCARD, fmi2.ERROR, fmi2.FATAL, fmi2.PENDING):
        with pytest.raises(FMUError) as err:
            inst.check("fmi2DoStep", status, since=len(inst.messages))
        assert (err.value.function, err.value.status) == ("fmi2DoStep", status)
        assert str(err.value).startswith(f"fmi2DoStep returned {fmi2.STATUS_NAMES[status]}: ")


def test_a_failed_step_raises_with_the_fmus_sentence(fmu: OscillatorFMU2) -> None:
    """doStep that overflows: FMUError naming fmi2DoStep and fmi2Error with the FMU's sentence;
    reset recovers."""
    fmu.start(Oscillator(P0=1e307, N=0.0, omega=0.0, k=1e-100), Settings(h=1e-3))
    with pytest.raises(FMUError, match="non-finite") as err:
        fmu.step_to(1e6)
    assert (err.value.function, err.value.status) == ("fmi2DoStep", fmi2.ERROR)
    r = fmu.trajectory(Oscillator(), [0.0, 0.1], Settings(h=1e-3))
    assert math.isfinite(r["x"][-1]) and r["x"][-1] != 0.0


def test_observables_read_without_observe_are_not_an_error(fmu: OscillatorFMU2) -> None:
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
    row = dict(p.as_dict(), h=1e-3, alpha=-0.1, t_obs_start=0.0, t_obs_stop=1.0, t_stop=1.0, v_s=0.01, delta=1.0)
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


# --------------------------------------------------------------------------- threads


def _serial_run(fmu_path: Path, k: int) -> np.ndarray:
    with OscillatorFMU2(fmu_path) as f:
        p = Oscillator(omega=3.0 + 0.25 * k, x0=0.001 * (k % 7), chi=0.2 + 0.1 * k)
        st = Settings(h=7e-4, scheme=list(f.md.schemes)[k % 3])
        r = f.trajectory(p, np.arange(101) * 0.01, st)
        return np.column_stack([r[n] for n in ("x", "v", "a", "F_friction", "mode")])


def test_driver_instances_in_threads_match_serial_runs(fmu_path: Path) -> None:
    """The driver in 8 threads (each its own OscillatorFMU2: unzip, load, callbacks) gives the
    serial numbers bit for bit. (The FMU's own reentrancy, 32 C threads: tests/fmi_c.)"""
    serial = [_serial_run(fmu_path, k) for k in range(8)]
    with ThreadPoolExecutor(max_workers=8) as ex:
        parallel = list(ex.map(lambda k: _serial_run(fmu_path, k), range(8)))
    for k in range(8):
        assert np.array_equal(serial[k], parallel[k]), k
    assert len({a.tobytes() for a in serial}) == 8


# ---------------------------------------------------------------- the FMU's error, as an exception


def test_an_fmu_error_names_the_function_the_status_and_the_sentence(fmu: OscillatorFMU2) -> None:
    """The driver's error: the FMI function, its status and the FMU's logged sentence (the bad
    values themselves are the C API test's: tests/fmi_c/test_fmi_api.c, test_bad_values)."""
    fmu.reset()
    with pytest.raises(FMUError) as err:
        fmu.set({"m": 0.0})
    e = err.value
    assert (e.function, e.status) == ("fmi2SetReal", fmi2.ERROR)
    assert "variable m " in e.message and "valid range: in [1e-100, 1e+100]" in e.message, e.message
    assert str(e).startswith("fmi2SetReal returned fmi2Error: "), str(e)
    # the instance stays usable: a valid run after the rejected value
    r = fmu.trajectory(Oscillator(), [0.0, 0.5], Settings(h=1e-3))
    assert np.all(np.isfinite(r["x"])) and r["x"][-1] != 0.0
    # an error found at initialisation names that call
    with pytest.raises(FMUError, match="t_obs_stop must be >= t_obs_start") as err:
        fmu.start(Oscillator(), Settings(observe=True, t_obs_start=2.0, t_obs_stop=1.0))
    assert err.value.function == "fmi2ExitInitializationMode"
    fmu.reset()
