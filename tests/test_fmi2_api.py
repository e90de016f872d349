"""Misuse of the FMI 2.0 API, through fmpy's FMU2Slave (and its raw ctypes functions where fmpy
hides the call): every case returns fmi2Error (or fmi2Discard) with a logged sentence that names the
variable / value / range, and the process and the instance keep working.

Also: forged serialised states (checksum-valid, impossible contents) and steps that must not hang.
Checked once, in the C API tests (tests/fmi_c) and not again here: every invalid parameter value,
NULL instances and arrays, instantiate rejections, overflow, FMU-state round trips, truncated or corrupted serialised states, foreign state pointers, 32
instances in parallel threads, 10^4 instantiate/free cycles. The package's own driver
(OscillatorFMU: errors, states, threads) is tested in test_fmi_layer.py.
"""

from __future__ import annotations

import ctypes
import math
import shutil
import struct
import subprocess
import sys
import tempfile
import textwrap
from collections.abc import Iterator
import threading
from ctypes import byref, c_int, c_size_t, c_void_p
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException, calloc, free
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2FMUstate,
)

from dryfriction.fmu import default_fmu_path

fmi2OK, fmi2Warning, fmi2Discard, fmi2Error = 0, 1, 2, 3
fmi2LastSuccessfulTime = 2


# --------------------------------------------------------------------------- plumbing


@pytest.fixture(scope="module")
def unzipped() -> Iterator[tuple[str, object]]:
    path = default_fmu_path()
    assert path.is_file(), f"FMU not found: {path} (build it, or set DFO_FMU)"
    md = read_model_description(str(path))
    d = extract(str(path), unzipdir=tempfile.mkdtemp(prefix="dfo-misuse-"))
    yield d, md
    shutil.rmtree(d, ignore_errors=True)


class Counting:
    """fmi2CallbackFunctions with a logger that keeps the messages and allocate/free counters."""

    def __init__(self) -> None:
        self.messages: list[tuple[int, str, str]] = []
        self.allocs = 0
        self.frees = 0
        self.struct = fmi2CallbackFunctions()
        self.struct.logger = fmi2CallbackLoggerTYPE(self._log)
        self.struct.allocateMemory = fmi2CallbackAllocateMemoryTYPE(self._alloc)
        self.struct.freeMemory = fmi2CallbackFreeMemoryTYPE(self._free)

    def _log(self, env: object, name: bytes, status: int, category: bytes, message: bytes) -> None:
        self.messages.append((status, category.decode(), message.decode(errors="replace")))

    def _alloc(self, n: int, size: int) -> int:
        self.allocs += 1
        return calloc(n, size)

    def _free(self, ptr: object) -> None:
        if ptr:
            self.frees += 1
        free(ptr)

    def last_error(self) -> str:
        errs = [m for s, _, m in self.messages if s >= fmi2Error]
        return errs[-1] if errs else ""


_LOAD_LOCK = threading.Lock()


class Inst:
    """One FMU2Slave instance with counting callbacks; vr(name) by variable name."""

    def __init__(self, unzipped: tuple[str, object], name: str = "misuse", logging: bool = False) -> None:
        d, md = unzipped
        self.md = md
        self.vars = {v.name: v for v in md.modelVariables}
        self.cb = Counting()
        # fmpy's loader changes the process's working directory while it loads the library: not
        # thread-safe, so loading is serialised; instantiating and stepping run in parallel
        with _LOAD_LOCK:
            self.s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                               instanceName=name)
        self.s.instantiate(callbacks=self.cb.struct, loggingOn=logging)

    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def init(self, h: float = 1e-3, **reals: float) -> None:
        s = self.s
        s.setupExperiment(startTime=0.0)
        s.setReal([self.vr("h")], [h])
        if reals:
            s.setReal([self.vr(n) for n in reals], list(reals.values()))
        s.enterInitializationMode()
        s.exitInitializationMode()

    def expect_error(self, fn: object, *args: object, contains: tuple[str, ...] = ()) -> str:
        """fn(*args) must fail (fmi2Error/Discard) and log a sentence containing every string."""
        n = len(self.cb.messages)
        with pytest.raises(FMICallException) as ei:
            fn(*args)
        assert ei.value.status in (fmi2Discard, fmi2Error)
        msgs = [m for s, _, m in self.cb.messages[n:] if s >= fmi2Discard]
        assert msgs, f"{getattr(fn, '__name__', fn)} failed without a logged sentence"
        msg = msgs[-1]
        for part in contains:
            assert part in msg, f"{part!r} not in {msg!r}"
        assert msg.endswith("."), f"not a sentence: {msg!r}"
        return msg

    def raw(self, fname: str, *args: object) -> int:
        """Call an fmi2 function of the library directly (no fmpy status check)."""
        f = getattr(self.s.dll, fname)
        return f(*args)

    def free(self) -> None:
        self.s.freeInstance()


@pytest.fixture
def inst(unzipped: tuple[str, object]) -> Iterator[Inst]:
    i = Inst(unzipped)
    yield i
    i.free()
    assert i.cb.allocs == i.cb.frees, f"{i.cb.allocs} allocations, {i.cb.frees} frees"


def still_usable(i: Inst) -> None:
    """After fmi2Reset the instance runs a valid simulation to the right numbers."""
    i.s.reset()
    i.init(h=1e-3)
    i.s.doStep(0.0, 0.1)
    x = i.s.getReal([i.vr("x")])[0]
    assert math.isfinite(x) and x != 0.0


# --------------------------------------------------------------------------- call order


def test_wrong_call_order(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    inst.expect_error(s.doStep, 0.0, 0.1, contains=("fmi2DoStep", "instantiated"))
    inst.expect_error(s.exitInitializationMode, contains=("fmi2ExitInitializationMode", "instantiated"))
    inst.expect_error(s.getReal, [vr("x")], contains=("fmi2GetReal", "instantiated"))
    inst.expect_error(s.terminate, contains=("fmi2Terminate",))
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    inst.expect_error(s.enterInitializationMode, contains=("initialization mode",))
    inst.expect_error(s.setupExperiment, None, 0.0, contains=("fmi2SetupExperiment", "initialization mode"))
    inst.expect_error(s.doStep, 0.0, 0.1, contains=("fmi2DoStep", "initialization mode"))
    s.exitInitializationMode()
    inst.expect_error(s.exitInitializationMode, contains=("step mode",))
    s.doStep(0.0, 0.1)
    s.terminate()
    inst.expect_error(s.doStep, 0.1, 0.1, contains=("fmi2DoStep", "terminated"))
    inst.expect_error(s.setReal, [vr("F_ext")], [1.0], contains=("fmi2SetReal", "terminated"))
    assert math.isfinite(s.getReal([vr("x")])[0])  # outputs stay readable after terminate
    still_usable(inst)


def test_communication_point_and_step_size(inst: Inst) -> None:
    s = inst.s
    inst.init()
    s.doStep(0.0, 0.1)
    inst.expect_error(s.doStep, 0.2, 0.1, contains=("currentCommunicationPoint", "0.20000000000000001", "0.1"))
    inst.expect_error(s.doStep, 0.0, 0.1, contains=("currentCommunicationPoint",))
    for dt, text in ((0.0, "0"), (-0.1, "-0.1"), (math.nan, "nan"), (math.inf, "inf")):
        inst.expect_error(s.doStep, 0.1, dt, contains=("communicationStepSize", text, "> 0"))
    s.doStep(0.1, 0.05)  # nothing above changed the state
    assert s.getRealStatus(fmi2LastSuccessfulTime) == 0.1 + 0.05


def test_nan_communication_point_is_named(inst: Inst) -> None:
    """currentCommunicationPoint = NaN (or inf) is refused with a sentence naming
    currentCommunicationPoint (not the step size, which is valid)."""
    s = inst.s
    inst.init()
    for tc in (math.nan, math.inf):
        inst.expect_error(s.doStep, tc, 0.1, contains=("currentCommunicationPoint", f"{tc}"))
    s.doStep(0.0, 0.1)


def test_stop_time(inst: Inst) -> None:
    s = inst.s
    inst.expect_error(s.setupExperiment, None, 1.0, 0.5, contains=("stopTime", "0.5", "startTime"))
    s.setupExperiment(startTime=0.0, stopTime=0.2)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 0.2)
    inst.expect_error(s.doStep, 0.2, 0.1, contains=("stop time", "0.2"))


def test_fixed_parameter_after_initialisation(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    inst.init()
    inst.expect_error(s.setReal, [vr("m")], [2.0], contains=("m", "fixed parameter", "step mode"))
    inst.expect_error(s.setInteger, [vr("scheme")], [1], contains=("scheme", "fixed parameter"))
    inst.expect_error(s.setBoolean, [vr("observe")], [True], contains=("observe", "fixed parameter"))
    inst.expect_error(s.setReal, [vr("x")], [1.0], contains=("x", "output"))
    inst.expect_error(s.setInteger, [vr("effects")], [0], contains=("effects", "calculated parameter"))
    s.setReal([vr("F_ext")], [0.5])  # inputs may be set in step mode
    s.doStep(0.0, 0.01)
    assert s.getReal([vr("m")])[0] == 1.0


def test_unknown_value_references_and_types(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    inst.init()
    for bad in (0, 22, 99, 2**32 - 1):
        inst.expect_error(s.getReal, [bad], contains=("unknown value reference", str(bad)))
        inst.expect_error(s.setReal, [bad], [1.0], contains=("unknown value reference", str(bad)))
        inst.expect_error(s.getInteger, [bad], contains=(str(bad),))
        inst.expect_error(s.getBoolean, [bad], contains=(str(bad),))
    inst.expect_error(s.getReal, [vr("mode")], contains=("mode", "Integer", "not Real"))
    inst.expect_error(s.setInteger, [vr("m")], [1], contains=("m", "Real", "not Integer"))
    inst.expect_error(s.getString, [vr("m")], contains=("String",))
    inst.expect_error(s.setString, [vr("m")], ["x"], contains=("String",))
    # a rejected call changes nothing, even its valid part
    inst.expect_error(s.setReal, [vr("F_ext"), 99], [3.0, 1.0], contains=("99",))
    assert s.getReal([vr("F_ext")])[0] == 0.0


def test_unsupported_functions_report(inst: Inst) -> None:
    s = inst.s
    inst.init()
    inst.expect_error(s.cancelStep, contains=("fmi2CancelStep",))
    inst.expect_error(s.getStatus, 0, contains=("fmi2GetStatus",))
    inst.expect_error(s.setRealInputDerivatives, [inst.vr("F_ext")], [1], [1.0], contains=("derivatives",))
    inst.expect_error(s.getRealOutputDerivatives, [inst.vr("x")], [1], contains=("derivatives",))
    inst.expect_error(s.getDirectionalDerivative, [inst.vr("x")], [inst.vr("F_ext")], [1.0],
                      contains=("directional",))
    for name in ("fmi2EnterEventMode", "fmi2EnterContinuousTimeMode"):
        getattr(s.dll, name).argtypes = [c_void_p]
        getattr(s.dll, name).restype = c_int
        assert inst.raw(name, s.component) == fmi2Error
        assert "co-simulation only" in inst.cb.last_error()
    inst.expect_error(s.setDebugLogging, True, ["noSuchCategory"], contains=("noSuchCategory",))
    s.doStep(0.0, 0.01)


# --------------------------------------------------------------------------- parameter values


@pytest.mark.parametrize("reals", [{"P0": 1e307, "N": 0.0, "omega": 0.0, "k": 1e-300},
                                   {"P0": 1e307, "N": 1.0, "omega": 0.0, "k": 1e-300}],
                         ids=["huge-force", "huge-force-through-the-LCP"])
def test_failed_step_leaves_the_last_good_state(inst: Inst, reals: dict[str, float]) -> None:
    """When a doStep fails (overflow), the outputs the host can still read are the last good ones
    (finite) and fmi2LastSuccessfulTime is the start of the failed step, not the time of the
    failure inside it."""
    s = inst.s
    inst.init(h=1e-3, **reals)
    s.doStep(0.0, 0.005)
    inst.expect_error(s.doStep, 0.005, 5.0, contains=("non-finite",))
    vrs = [inst.vr(n) for n in ("x", "v", "a", "F_friction", "x_max", "x_min", "stick_fraction", "E_friction")]
    out = s.getReal(vrs)
    assert all(math.isfinite(v) for v in out), f"outputs after the failed step: {out}"
    assert s.getRealStatus(fmi2LastSuccessfulTime) == 0.005


def test_subnormal_mass_is_refused_or_finite(inst: Inst) -> None:
    """m = 2.1e-314 (subnormal, inside "> 0"): found by the fuzzer, the acceleration output is
    inf with fmi2OK right after initialisation. Either the value is refused with a sentence, or
    every output is finite."""
    s = inst.s
    s.setupExperiment(startTime=0.0)
    try:
        s.setReal([inst.vr("m")], [2.1219957909652723e-314])
        s.enterInitializationMode()
        s.exitInitializationMode()
    except FMICallException:
        assert "m" in inst.cb.last_error()
        return
    out = s.getReal([inst.vr(n) for n in ("x", "v", "a", "F_friction")])
    assert all(math.isfinite(v) for v in out), f"outputs {out}"


# --------------------------------------------------------------------------- FMU states


def _run_outputs(i: Inst, t0: float, n: int, dt: float) -> np.ndarray:
    vrs = [i.vr(v) for v in ("x", "v", "a", "F_friction", "E_friction", "stick_fraction")]
    out = []
    for j in range(n):
        i.s.doStep(t0 + j * dt, dt)
        out.append(i.s.getReal(vrs) + i.s.getInteger([i.vr("mode"), i.vr("transitions")]))
    return np.array(out)


def _setup_observed(i: Inst) -> None:
    s = i.s
    s.setupExperiment(startTime=0.0)
    s.setReal([i.vr("h"), i.vr("x0")], [7e-4, 0.004])
    s.setBoolean([i.vr("observe")], [True])
    s.enterInitializationMode()
    s.exitInitializationMode()


def _serialised(i: Inst) -> bytes:
    _setup_observed(i)
    _run_outputs(i, 0.0, 10, 0.01)
    st_ = i.s.getFMUstate()
    data = i.s.serializeFMUstate(st_)
    i.s.freeFMUstate(st_)
    return data


def _deserialise_raw(i: Inst, data: bytes) -> tuple[int, c_void_p]:
    state = fmi2FMUstate()
    buf = ctypes.create_string_buffer(data, len(data))
    rc = i.raw("fmi2DeSerializeFMUstate", i.s.component, buf, c_size_t(len(data)), byref(state))
    return rc, state


def _fnv1a(b: bytes) -> int:
    h = 1469598103934665603
    for x in b:
        h = ((h ^ x) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def _forge(data: bytes, offset: int, value: bytes) -> bytes:
    """Replace bytes at offset (of the serialised buffer) and fix the checksum (header bytes 16..24)."""
    b = bytearray(data)
    b[offset:offset + len(value)] = value
    b[16:24] = struct.pack("<Q", _fnv1a(bytes(b[24:])))
    return bytes(b)


HEADER = 24  # magic[8], version, size (uint32), checksum (uint64)


@pytest.mark.parametrize("field,index,value", [("m", 0, -1.0), ("k", 1, math.nan), ("h", 11, 0.0),
                                                ("alpha", 12, 0.5)])
def test_forged_state_with_bad_parameter_rejected(inst: Inst, field: str, index: int, value: float) -> None:
    """A state with a valid checksum but an impossible parameter (the parameters are the first
    doubles of the payload) is rejected with a sentence."""
    data = _serialised(inst)
    assert struct.unpack_from("<d", data, HEADER + 11 * 8)[0] == 7e-4  # layout check: h
    rc, st_ = _deserialise_raw(inst, _forge(data, HEADER + 8 * index, struct.pack("<d", value)))
    assert rc == fmi2Error and not st_
    assert "rejected" in inst.cb.last_error()


FORGED_DERIVED_H = textwrap.dedent("""
    import struct, sys
    sys.path.insert(0, {testdir!r})
    import test_fmi_misuse as t
    from fmpy import extract, read_model_description
    import tempfile
    path = str(t.default_fmu_path())
    md = read_model_description(path)
    d = extract(path, unzipdir=tempfile.mkdtemp())
    i = t.Inst((d, md))
    data = t._serialised(i)
    hb = struct.pack("<d", 7e-4)
    first = data.find(hb)
    second = data.find(hb, first + 1)   # the model's copy of the parameters holds h again
    assert first == t.HEADER + 88 and second > first, (first, second)
    rc, st = t._deserialise_raw(i, t._forge(data, second, struct.pack("<d", {value!r})))
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


def test_tiny_internal_step_does_not_hang() -> None:
    """h = 1e-300 is inside the declared range (> 0); a doStep of 1 ms must then come back (with
    an error naming h, or done), not spin for 10^297 internal steps (child process, 10 s limit)."""
    code = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from dryfriction.fmu import OscillatorFMU, Settings
        from dryfriction.params import Oscillator
        f = OscillatorFMU()
        f.start(Oscillator(), Settings(h=1e-300))
        try:
            f.step_to(1e-3)
            print("returned ok")
        except Exception as e:
            print("returned", e)
    """)
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=10)
    except subprocess.TimeoutExpired:
        pytest.fail("fmi2DoStep(0, 1e-3) with h = 1e-300 did not return within 10 s")
    assert "returned" in r.stdout, r.stderr
