"""Misuse of the FMI 2.0 API, through fmpy's FMU2Slave (and its raw ctypes functions where fmpy
hides the call): every case returns fmi2Error (or fmi2Discard) with a logged sentence that names the
variable / value / range, and the process and the instance keep working.

Also: every invalid parameter value, FMU-state round trips (bit-exact continuation), serialised
states (round trip; truncated, corrupted or forged ones rejected), 32 instances in parallel threads
against serial runs, and 10^4 instantiate/free cycles with balanced allocate/free callbacks.
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
from concurrent.futures import ThreadPoolExecutor
from ctypes import byref, c_double, c_int, c_size_t, c_uint, c_void_p, cast
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


def test_null_pointers_and_buffers(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    inst.init()
    c = s.component
    buf = (c_double * 1)()
    vrs = (c_uint * 1)(vr("x"))
    n0 = len(inst.cb.messages)
    assert inst.raw("fmi2GetReal", c, None, 1, buf) == fmi2Error
    assert inst.raw("fmi2GetReal", c, vrs, 1, None) == fmi2Error
    assert inst.raw("fmi2SetReal", c, None, 1, buf) == fmi2Error
    assert inst.raw("fmi2GetInteger", c, vrs, 1, None) == fmi2Error
    assert inst.raw("fmi2GetBoolean", c, None, 1, None) == fmi2Error
    assert inst.raw("fmi2GetReal", c, None, 0, None) == fmi2OK  # nothing asked, nothing read
    assert inst.raw("fmi2GetFMUstate", c, None) == fmi2Error
    assert inst.raw("fmi2SetFMUstate", c, None) == fmi2Error
    assert inst.raw("fmi2FreeFMUstate", c, None) == fmi2Error
    assert inst.raw("fmi2SerializedFMUstateSize", c, None, None) == fmi2Error
    assert inst.raw("fmi2SerializeFMUstate", c, None, None, 0) == fmi2Error
    assert inst.raw("fmi2DeSerializeFMUstate", c, None, 0, None) == fmi2Error
    assert inst.raw("fmi2SetDebugLogging", c, 1, 2, None) == fmi2Error
    assert inst.raw("fmi2GetRealStatus", c, fmi2LastSuccessfulTime, None) == fmi2Error
    logged = [m for st_, _, m in inst.cb.messages[n0:] if st_ >= fmi2Error]
    assert len(logged) >= 13 and any("NULL" in m for m in logged)
    # a NULL instance: an error, nothing else (there is nobody to log to)
    for fn in ("fmi2DoStep",):
        assert inst.raw(fn, None, c_double(0.0), c_double(0.1), 1) == fmi2Error
    for fn in ("fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset"):
        assert inst.raw(fn, None) == fmi2Error
    assert inst.raw("fmi2GetReal", None, vrs, 1, buf) == fmi2Error
    inst.raw("fmi2FreeInstance", None)  # a no-op
    s.doStep(0.0, 0.01)


def test_instantiate_rejections(unzipped: tuple[str, object]) -> None:
    d, md = unzipped
    dll = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier).dll
    dll.fmi2Instantiate.restype = c_void_p
    cb = Counting()
    inst = dll.fmi2Instantiate
    guid = md.guid.encode()
    assert inst(b"x", 1, guid, b"", None, 0, 0) is None  # NULL callbacks
    assert inst(b"x", 0, guid, b"", byref(cb.struct), 0, 0) is None  # model exchange
    assert "co-simulation only" in cb.last_error()
    assert inst(b"x", 1, b"{wrong}", b"", byref(cb.struct), 0, 0) is None
    assert "GUID" in cb.last_error() and "{wrong}" in cb.last_error()
    assert inst(b"", 1, guid, b"", byref(cb.struct), 0, 0) is None
    assert "instance name" in cb.last_error()
    assert inst(None, 1, guid, b"", byref(cb.struct), 0, 0) is None
    assert cb.allocs == cb.frees == 0


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


BAD_REALS = [
    ("m", 0.0, "> 0"), ("m", -1.0, "> 0"), ("k", -1.0, ">= 0"), ("c", -0.1, ">= 0"), ("N", -1.0, ">= 0"),
    ("mu_s", -0.1, ">= 0"), ("chi", -0.5, ">= 0"), ("h", 0.0, "> 0"), ("h", -1e-3, "> 0"),
    ("alpha", -0.34, "[-1/3, 0]"), ("alpha", 0.01, "[-1/3, 0]"), ("omega", -1.0, ">= 0"),
]
REALS = ["m", "k", "c", "P0", "omega", "phi", "N", "mu_s", "chi", "x0", "v0", "h", "alpha", "t_obs_start",
         "t_obs_stop", "F_ext", "N_ext"]
BAD_REALS += [(n, v, "finite") for n in REALS for v in (math.nan, math.inf, -math.inf)]


@pytest.mark.parametrize("name,value,valid", BAD_REALS, ids=[f"{n}={v}" for n, v, _ in BAD_REALS])
def test_bad_real_parameter(inst: Inst, name: str, value: float, valid: str) -> None:
    """Each invalid value is refused at once (instantiated or initialisation mode) with a sentence
    naming the variable, the value and the valid range; the instance stays usable."""
    s, vr = inst.s, inst.vr
    msg = inst.expect_error(s.setReal, [vr(name)], [value], contains=(f"variable {name} ", "valid range", valid))
    assert f"invalid value {value:.17g} for variable {name}" in msg, msg
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    inst.expect_error(s.setReal, [vr(name)], [value], contains=(name, valid))
    s.exitInitializationMode()
    assert s.getReal([vr(name)])[0] != value or math.isnan(value)
    still_usable(inst)


@pytest.mark.parametrize("name,value,valid", [
    ("scheme", 0, "1 (paper)"), ("scheme", 5, "4 (exact)"), ("scheme", -1, "one of"),
    ("frictionUpdates", -1, "[0, 100]"), ("frictionUpdates", 101, "[0, 100]"),
    ("frictionUpdates", 2**31 - 1, "[0, 100]"),
])
def test_bad_integer_parameter(inst: Inst, name: str, value: int, valid: str) -> None:
    msg = inst.expect_error(inst.s.setInteger, [inst.vr(name)], [value],
                            contains=(f"variable {name} ", str(value), "valid range", valid))
    assert msg
    inst.s.setInteger([inst.vr(name)], [1 if name == "scheme" else 100])
    still_usable(inst)


def test_empty_observation_window(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    s.setupExperiment(startTime=0.0)
    s.setReal([vr("t_obs_start"), vr("t_obs_stop")], [2.0, 1.0])
    s.enterInitializationMode()
    inst.expect_error(s.exitInitializationMode, contains=("t_obs_stop", "t_obs_start"))
    still_usable(inst)


def test_overflow_is_an_error_not_nan(inst: Inst) -> None:
    """P0 = 1e307 without friction: the state overflows within a few steps; doStep reports it
    (fmi2Error naming the time) instead of returning inf/NaN outputs, and only reset recovers."""
    s = inst.s
    inst.init(h=1e-3, P0=1e307, N=0.0, omega=0.0, k=1e-300)
    inst.expect_error(s.doStep, 0.0, 1e6, contains=("non-finite",))
    inst.expect_error(s.doStep, 0.0, 0.1, contains=("error",))
    still_usable(inst)


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


def test_fmu_state_round_trip_is_bit_exact(inst: Inst) -> None:
    s = inst.s
    _setup_observed(inst)
    _run_outputs(inst, 0.0, 37, 0.0123)
    t1 = 37 * 0.0123
    state = s.getFMUstate()
    a = _run_outputs(inst, t1, 200, 0.01)
    s.setFMUstate(state)
    assert s.getRealStatus(fmi2LastSuccessfulTime) == t1
    b = _run_outputs(inst, t1, 200, 0.01)
    assert np.array_equal(a, b)
    n_alloc = inst.cb.allocs
    assert inst.raw("fmi2GetFMUstate", s.component, byref(state)) == fmi2OK  # overwrite in place
    assert inst.cb.allocs == n_alloc
    s.setFMUstate(state)
    c = _run_outputs(inst, t1 + 2.0, 10, 0.01)
    s.setFMUstate(state)
    assert np.array_equal(c, _run_outputs(inst, t1 + 2.0, 10, 0.01))
    s.freeFMUstate(state)


def test_serialised_state_round_trip_across_instances(unzipped: tuple[str, object]) -> None:
    a, b = Inst(unzipped, "a"), Inst(unzipped, "b")
    try:
        _setup_observed(a)
        _run_outputs(a, 0.0, 50, 0.01)
        st_a = a.s.getFMUstate()
        data = a.s.serializeFMUstate(st_a)
        ref = _run_outputs(a, 0.5, 100, 0.01)
        st_b = b.s.deSerializeFMUstate(data)
        b.s.setFMUstate(st_b)  # b was only instantiated: the state carries the whole setup
        assert b.s.serializeFMUstate(st_b) == data
        got = _run_outputs(b, 0.5, 100, 0.01)
        assert np.array_equal(ref, got)
        a.s.freeFMUstate(st_a)
        b.s.freeFMUstate(st_b)
    finally:
        a.free()
        b.free()
    assert a.cb.allocs == a.cb.frees and b.cb.allocs == b.cb.frees


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


def test_truncated_and_corrupted_serialised_states_rejected(inst: Inst) -> None:
    data = _serialised(inst)
    n = len(data)
    for cut in (0, 1, 8, 23, 24, n // 2, n - 1):
        rc, st_ = _deserialise_raw(inst, data[:cut])
        assert rc == fmi2Error and not st_, cut
        assert "bytes given" in inst.cb.last_error()
    rc, _ = _deserialise_raw(inst, data + b"\0")
    assert rc == fmi2Error
    # every single flipped bit pattern (each byte xor 0x5a) is rejected
    for pos in range(n):
        bad = bytearray(data)
        bad[pos] ^= 0x5A
        rc, st_ = _deserialise_raw(inst, bytes(bad))
        assert rc == fmi2Error and not st_, f"corruption at byte {pos} accepted"
    assert any("checksum" in m for _, _, m in inst.cb.messages)
    assert any("not a serialised state" in m for _, _, m in inst.cb.messages)
    rc, st_ = _deserialise_raw(inst, data)
    assert rc == fmi2OK and st_
    inst.s.setFMUstate(st_)
    inst.s.freeFMUstate(st_)
    inst.s.doStep(0.1, 0.1)


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


def test_state_functions_reject_foreign_pointers(inst: Inst) -> None:
    s = inst.s
    inst.init()
    junk = ctypes.create_string_buffer(b"\x11" * 4096)
    assert inst.raw("fmi2SetFMUstate", s.component, cast(junk, c_void_p)) == fmi2Error
    assert "not a state of this FMU" in inst.cb.last_error()
    p = c_void_p(ctypes.addressof(junk))
    assert inst.raw("fmi2FreeFMUstate", s.component, byref(p)) == fmi2Error
    size = c_size_t(0)
    assert inst.raw("fmi2SerializedFMUstateSize", s.component, None, byref(size)) in (fmi2OK, fmi2Error)
    out = ctypes.create_string_buffer(4096)
    assert inst.raw("fmi2SerializeFMUstate", s.component, cast(junk, c_void_p), out, c_size_t(4096)) == fmi2Error
    st_ = s.getFMUstate()
    small = ctypes.create_string_buffer(8)
    assert inst.raw("fmi2SerializeFMUstate", s.component, st_, small, c_size_t(8)) == fmi2Error
    assert "too small" in inst.cb.last_error()
    s.freeFMUstate(st_)
    s.doStep(0.0, 0.01)


# --------------------------------------------------------------------------- threads, cycles


def _simulate(unzipped: tuple[str, object], k: int) -> np.ndarray:
    i = Inst(unzipped, f"thread{k}")
    try:
        s = i.s
        s.setupExperiment(startTime=0.0)
        s.setReal([i.vr("h"), i.vr("omega"), i.vr("x0")], [1e-3, 3.0 + 0.1 * k, 0.001 * k])
        s.setInteger([i.vr("scheme")], [1 + k % 3])
        s.setBoolean([i.vr("observe")], [True])
        s.enterInitializationMode()
        s.exitInitializationMode()
        return _run_outputs(i, 0.0, 300, 0.01)
    finally:
        i.free()


def test_32_instances_in_parallel_threads_match_serial(unzipped: tuple[str, object]) -> None:
    import os

    cwd = os.getcwd()
    serial = [_simulate(unzipped, k) for k in range(32)]
    with ThreadPoolExecutor(max_workers=32) as ex:
        parallel = list(ex.map(lambda k: _simulate(unzipped, k), range(32)))
    assert os.getcwd() == cwd  # loading from threads leaves the working directory alone
    for k in range(32):
        assert np.array_equal(serial[k], parallel[k]), f"instance {k} differs"
    assert len({a.tobytes() for a in serial}) == 32


def test_1e4_instantiate_free_cycles_balance(unzipped: tuple[str, object]) -> None:
    """10^4 instantiate / (init, step, state get/serialise/free) / free cycles: every allocation
    through the callbacks is freed (ASan's leak checker covers the rest in the C tests)."""
    d, md = unzipped
    cb = Counting()
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier)
    seen = set()
    for k in range(10**4):
        s.instantiate(callbacks=cb.struct)
        seen.add(s.component)
        if k % 100 == 0:
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            s.exitInitializationMode()
            s.doStep(0.0, 0.01)
            st_ = s.getFMUstate()
            s.deSerializeFMUstate(s.serializeFMUstate(st_), st_)
            s.freeFMUstate(st_)
        s.fmi2FreeInstance(s.component)  # (fmpy's freeInstance would also unload the library)
    s.freeLibrary()
    assert None not in seen
    assert cb.allocs == cb.frees and cb.allocs >= 2 * 10**4, (cb.allocs, cb.frees)
