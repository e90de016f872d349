"""FMU states of the oscillator: get / set / serialise / deserialise through the package's driver bit
for bit, states left open freed with their instance, and forged serialised states (checksum-valid,
impossible contents: fmi2_helpers.forge) refused, or at least never a hang.

The FMU-state tests in C: tests/fmi_c/test_fmi_api.c (round trips, truncated or corrupted
buffers, foreign pointers), tests/fmi_c/test_instance_core.c (the core's copy and serialiser),
tests/fmi3_c/chain_fmu.c (the chain's states, FMI 2.0 and 3.0); resumed runs on every platform:
tests/platforms."""

from __future__ import annotations

import math
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from dryfriction.drivers.oscillator import FMUError, OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from fmi2_helpers import HEADER, Inst, deserialise_raw, fmi2Error, forge, serialised


def test_state_round_trip_through_the_driver_is_bit_exact(fmu: OscillatorFMU2) -> None:
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
    with OscillatorFMU2(fmu.path) as other:
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
    f = OscillatorFMU2(fmu_path)
    f.start(Oscillator(), Settings(h=1e-3))
    states = [f.get_state() for _ in range(3)]
    f.close()
    assert all(s.freed for s in states)


@pytest.mark.parametrize("field,index,value", [("m", 0, -1.0), ("k", 1, math.nan), ("h", 11, 0.0),
                                                ("alpha", 12, 0.5)])
def test_forged_state_with_bad_parameter_rejected(inst: Inst, field: str, index: int, value: float) -> None:
    """A state with a valid checksum but an impossible parameter (the parameters are the first
    doubles of the payload) is rejected with a sentence."""
    data = serialised(inst)
    assert struct.unpack_from("<d", data, HEADER + 11 * 8)[0] == 7e-4  # layout check: h
    rc, st_ = deserialise_raw(inst, forge(data, HEADER + 8 * index, struct.pack("<d", value)))
    assert rc == fmi2Error and not st_
    assert "rejected" in inst.cb.last_error()


FORGED_DERIVED_H = textwrap.dedent("""
    import struct, sys
    sys.path.insert(0, {testdir!r})
    import fmi2_helpers as t
    from fmpy import extract, read_model_description
    import tempfile
    from dryfriction.drivers.oscillator import default_fmu_path
    path = str(default_fmu_path())
    md = read_model_description(path)
    d = extract(path, unzipdir=tempfile.mkdtemp())
    i = t.Inst((d, md))
    data = t.serialised(i)
    hb = struct.pack("<d", 7e-4)
    first = data.find(hb)
    second = data.find(hb, first + 1)   # the model's copy of the parameters holds h again
    assert first == t.HEADER + 88 and second > first, (first, second)
    rc, st = t.deserialise_raw(i, t.forge(data, second, struct.pack("<d", {value!r})))
    if rc == 0:
        i.s.setFMUstate(st)
        try:
            i.s.doStep(0.1, 0.1)
        except Exception:
            pass
    print("returned", rc)
""")


@pytest.mark.parametrize("value", [0.0, -1.0])
def test_forged_state_with_inconsistent_derived_step_does_not_hang(value: float) -> None:
    """A checksum-valid state whose derived model copy holds h = 0 (or < 0) while the parameter
    h is valid: deserialisation must reject it or doStep must return; it must not hang (run in a
    child process with a 10 s limit)."""
    code = FORGED_DERIVED_H.format(testdir=str(Path(__file__).parent), value=value)
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=10)
    except subprocess.TimeoutExpired:
        pytest.fail(f"fmi2DoStep hung after fmi2DeSerializeFMUstate accepted a state with the derived h = {value}")
    assert r.returncode == 0 and "returned" in r.stdout, r.stderr
