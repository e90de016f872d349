"""The oscillator's FMI 2.0 FMU driven through fmpy's FMU2Slave with counting callbacks (the FMI 2.0
API tests and the FMU-state tests), and the serialised FMU state taken
apart: its header, its checksum (FNV-1a over the payload), a forged buffer with a fixed checksum."""

from __future__ import annotations

import ctypes
import struct
import threading
from ctypes import byref, c_size_t, c_void_p

import numpy as np
import pytest
from fmpy import calloc, free
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE, fmi2FMUstate)

fmi2OK, fmi2Warning, fmi2Discard, fmi2Error = 0, 1, 2, 3
fmi2LastSuccessfulTime = 2


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


LOAD_LOCK = threading.Lock()


class Inst:
    """One FMU2Slave instance with counting callbacks; vr(name) by variable name."""

    def __init__(self, unzipped: tuple[str, object], name: str = "misuse", logging: bool = False) -> None:
        d, md = unzipped
        self.md = md
        self.vars = {v.name: v for v in md.modelVariables}
        self.cb = Counting()
        # fmpy's loader changes the process's working directory while it loads the library: not
        # thread-safe, so loading is serialised; instantiating and stepping run in parallel
        with LOAD_LOCK:
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


def run_outputs(i: Inst, t0: float, n: int, dt: float) -> np.ndarray:
    vrs = [i.vr(v) for v in ("x", "v", "a", "F_friction", "E_friction", "stick_fraction")]
    out = []
    for j in range(n):
        i.s.doStep(t0 + j * dt, dt)
        out.append(i.s.getReal(vrs) + i.s.getInteger([i.vr("mode"), i.vr("transitions")]))
    return np.array(out)


def setup_observed(i: Inst) -> None:
    s = i.s
    s.setupExperiment(startTime=0.0)
    s.setReal([i.vr("h"), i.vr("x0")], [7e-4, 0.004])
    s.setBoolean([i.vr("observe")], [True])
    s.enterInitializationMode()
    s.exitInitializationMode()


def serialised(i: Inst) -> bytes:
    setup_observed(i)
    run_outputs(i, 0.0, 10, 0.01)
    st_ = i.s.getFMUstate()
    data = i.s.serializeFMUstate(st_)
    i.s.freeFMUstate(st_)
    return data


def deserialise_raw(i: Inst, data: bytes) -> tuple[int, c_void_p]:
    state = fmi2FMUstate()
    buf = ctypes.create_string_buffer(data, len(data))
    rc = i.raw("fmi2DeSerializeFMUstate", i.s.component, buf, c_size_t(len(data)), byref(state))
    return rc, state


def fnv1a(b: bytes) -> int:
    h = 1469598103934665603
    for x in b:
        h = ((h ^ x) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def forge(data: bytes, offset: int, value: bytes) -> bytes:
    """Replace bytes at offset (of the serialised buffer) and fix the checksum (header bytes 16..24)."""
    b = bytearray(data)
    b[offset:offset + len(value)] = value
    b[16:24] = struct.pack("<Q", fnv1a(bytes(b[24:])))
    return bytes(b)


HEADER = 32  # magic[8], version, size (uint32), checksum (uint64), model hash (uint64): core/fmu_state.h
