"""The one thin layer over an FMI 2.0 co-simulation FMU's C functions.

The FMU's shared library is loaded with plain ctypes from the folder fmpy's public ``extract``
unzipped it to; every function is typed here once, with array arguments as ``void *`` so that a
caller may pass ctypes arrays or raw addresses of numpy arrays (``arr.ctypes.data``). Every status
is checked: ``fmi2OK`` and ``fmi2Warning`` pass, anything else raises :class:`FMUError` naming the
function, the status and the FMU's last logged sentence. Every sentence the FMU logs with the
status ``fmi2Warning`` becomes a :class:`dryfriction.diagnostics.DryFrictionWarning` when the call
that logged it is checked.

Hot loops call the typed functions directly (:attr:`Instance.f`) and hand a non-zero status to
:meth:`Instance.check`, which returns on a warning and raises otherwise; everything else uses the
checked methods of :class:`Instance`.
"""

from __future__ import annotations

import ctypes
import os
import threading
from collections.abc import Sequence
from ctypes import (CFUNCTYPE, POINTER, Structure, byref, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p)
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from .diagnostics import emit

__all__ = [
    "OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING", "STATUS_NAMES", "LAST_SUCCESSFUL_TIME",
    "FMUError", "Instance", "State", "library_path",
]

# ---- fmi2Status -----------------------------------------------------------------------------------
OK, WARNING, DISCARD, ERROR, FATAL, PENDING = 0, 1, 2, 3, 4, 5
STATUS_NAMES = ("fmi2OK", "fmi2Warning", "fmi2Discard", "fmi2Error", "fmi2Fatal", "fmi2Pending")
# fmi2StatusKind / fmi2Type
LAST_SUCCESSFUL_TIME = 2
CO_SIMULATION = 1


def status_name(status: int) -> str:
    return STATUS_NAMES[status] if 0 <= status < len(STATUS_NAMES) else f"status {status}"


class FMUError(RuntimeError):
    """An FMI call that did not return fmi2OK or fmi2Warning (or a value the host refused).

    ``function`` and ``status`` name the call; ``message`` is the FMU's logged sentence."""

    def __init__(self, message: str, function: str | None = None, status: int | None = None) -> None:
        self.message, self.function, self.status = message, function, status
        text = message if function is None else f"{function} returned {status_name(status or 0)}: {message}"
        super().__init__(text)


# ---- callbacks --------------------------------------------------------------------------------------
LoggerT = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p)
AllocateT = CFUNCTYPE(c_void_p, c_size_t, c_size_t)
FreeT = CFUNCTYPE(None, c_void_p)
StepFinishedT = CFUNCTYPE(None, c_void_p, c_int)


class CallbackFunctions(Structure):
    _fields_ = [("logger", LoggerT), ("allocateMemory", AllocateT), ("freeMemory", FreeT),
                ("stepFinished", StepFinishedT), ("componentEnvironment", c_void_p)]


_LIBC = ctypes.CDLL(None)
# the C library's own calloc/free as the FMU's allocator: no Python in the allocation path
_CALLOC = AllocateT(ctypes.cast(_LIBC.calloc, c_void_p).value)
_FREE = FreeT(ctypes.cast(_LIBC.free, c_void_p).value)

_VP, _SZ, _D, _I, _U = c_void_p, c_size_t, c_double, c_int, c_uint
#: name -> (restype, argtypes after the component)
_SIGNATURES: dict[str, tuple[Any, tuple[Any, ...]]] = {
    "fmi2SetDebugLogging": (_I, (_I, _SZ, _VP)),
    "fmi2SetupExperiment": (_I, (_I, _D, _D, _I, _D)),
    "fmi2EnterInitializationMode": (_I, ()),
    "fmi2ExitInitializationMode": (_I, ()),
    "fmi2Terminate": (_I, ()),
    "fmi2Reset": (_I, ()),
    "fmi2GetReal": (_I, (_VP, _SZ, _VP)),
    "fmi2GetInteger": (_I, (_VP, _SZ, _VP)),
    "fmi2GetBoolean": (_I, (_VP, _SZ, _VP)),
    "fmi2SetReal": (_I, (_VP, _SZ, _VP)),
    "fmi2SetInteger": (_I, (_VP, _SZ, _VP)),
    "fmi2SetBoolean": (_I, (_VP, _SZ, _VP)),
    "fmi2DoStep": (_I, (_D, _D, _I)),
    "fmi2GetRealStatus": (_I, (_I, _VP)),
    "fmi2GetFMUstate": (_I, (_VP,)),
    "fmi2SetFMUstate": (_I, (_VP,)),
    "fmi2FreeFMUstate": (_I, (_VP,)),
    "fmi2SerializedFMUstateSize": (_I, (_VP, _VP)),
    "fmi2SerializeFMUstate": (_I, (_VP, _VP, _SZ)),
    "fmi2DeSerializeFMUstate": (_I, (_VP, _SZ, _VP)),
}
_CTYPE = {"Real": c_double, "Integer": c_int, "Boolean": c_int}


def library_path(unzip_dir: str | os.PathLike[str], model_identifier: str) -> Path:
    """The shared library of this platform inside an unzipped FMU (fmpy's platform names)."""
    from fmpy import platform, sharedLibraryExtension

    return Path(unzip_dir) / "binaries" / platform / f"{model_identifier}{sharedLibraryExtension}"


_LOAD_LOCK = threading.Lock()


class State:
    """An FMU state (fmi2FMUstate) of one instance; free it with :meth:`free` (or ``with``)."""

    def __init__(self, owner: "Instance", handle: c_void_p) -> None:
        self._owner, self.handle = owner, handle

    @property
    def freed(self) -> bool:
        return not self.handle

    def free(self) -> None:
        if self.handle and not self._owner.freed:
            self._owner._free_state(self)
        self.handle = c_void_p()

    def __enter__(self) -> "State":
        return self

    def __exit__(self, *exc: object) -> None:
        self.free()


class Instance:
    """One instantiated FMI 2.0 co-simulation FMU (not thread-safe: one per thread)."""

    def __init__(self, unzip_dir: str | os.PathLike[str], guid: str, model_identifier: str,
                 name: str = "instance", logging: bool = False) -> None:
        lib = library_path(unzip_dir, model_identifier)
        if not lib.is_file():
            raise FMUError(f"the FMU has no binary for this platform: {lib}")
        with _LOAD_LOCK:
            self.dll = ctypes.CDLL(str(lib))
        fns = {}
        for fname, (restype, argtypes) in _SIGNATURES.items():
            fn = getattr(self.dll, fname)
            fn.restype, fn.argtypes = restype, (c_void_p, *argtypes)
            fns[fname] = fn
        #: the typed C functions, by their short name (``f.DoStep``): status returned, not checked
        self.f = SimpleNamespace(**{k[4:]: v for k, v in fns.items()})
        self.messages: list[tuple[int, str, str]] = []
        self._warnings: list[str] = []  # logged with fmi2Warning, not yet emitted
        self._cb = CallbackFunctions()
        self._cb.logger = LoggerT(self._log)  # kept alive as long as the instance
        self._cb.allocateMemory = _CALLOC
        self._cb.freeMemory = _FREE
        instantiate = self.dll.fmi2Instantiate
        instantiate.restype = c_void_p
        instantiate.argtypes = [c_char_p, c_int, c_char_p, c_char_p, POINTER(CallbackFunctions), c_int, c_int]
        self._free_instance = self.dll.fmi2FreeInstance
        self._free_instance.restype, self._free_instance.argtypes = None, [c_void_p]
        resources = Path(unzip_dir, "resources").resolve().as_uri()
        comp = instantiate(name.encode(), CO_SIMULATION, guid.encode(), resources.encode(), byref(self._cb),
                           0, int(bool(logging)))
        if not comp:
            raise FMUError(self._last_message(0) or "fmi2Instantiate returned NULL", "fmi2Instantiate", ERROR)
        #: the fmi2Component (an address)
        self.component: int = comp
        self._states: list[State] = []

    # ---- status -----------------------------------------------------------------------------------
    def _log(self, env: Any, name: bytes, status: int, category: bytes, message: bytes) -> None:
        text = (message or b"").decode(errors="replace")
        self.messages.append((status, (category or b"").decode(errors="replace"), text))
        if status == WARNING:
            self._warnings.append(text)

    def flush_warnings(self) -> None:
        """Emit the warnings logged since the last flush as :class:`DryFrictionWarning`."""
        if self._warnings:
            pending, self._warnings = self._warnings, []
            emit(pending, stacklevel=4)

    def _last_message(self, since: int) -> str:
        msgs = self.messages[since:]
        for wanted in (DISCARD, WARNING, OK):
            for s, _, m in reversed(msgs):
                if s >= wanted:
                    return m
        return ""

    def check(self, function: str, status: int, since: int = 0) -> int:
        """Return ``status`` if it is fmi2OK or fmi2Warning, else raise :class:`FMUError` with the
        last sentence the FMU logged (after message index ``since``). The warnings logged so far
        are emitted first (:meth:`flush_warnings`)."""
        self.flush_warnings()
        if status == OK or status == WARNING:
            return status
        msg = self._last_message(since) or "no message logged"
        raise FMUError(msg, function, status)

    def call(self, function: str, *args: Any) -> int:
        """Call ``fmi2<function>`` (short name) with the component and check its status."""
        mark = len(self.messages)
        return self.check(f"fmi2{function}", getattr(self.f, function)(self.component, *args), mark)

    @property
    def freed(self) -> bool:
        return not self.component

    # ---- life cycle -------------------------------------------------------------------------------
    def setup_experiment(self, start: float = 0.0, stop: float | None = None,
                         tolerance: float | None = None) -> None:
        self.call("SetupExperiment", int(tolerance is not None), float(tolerance or 0.0), float(start),
                  int(stop is not None), float(stop or 0.0))

    def enter_initialization_mode(self) -> None:
        self.call("EnterInitializationMode")

    def exit_initialization_mode(self) -> None:
        self.call("ExitInitializationMode")

    def do_step(self, t: float, dt: float, no_set_prior_state: bool = True) -> int:
        return self.call("DoStep", float(t), float(dt), int(no_set_prior_state))

    def terminate(self) -> None:
        self.call("Terminate")

    def reset(self) -> None:
        self.call("Reset")

    def set_debug_logging(self, on: bool, categories: Sequence[str] = ()) -> None:
        arr = (c_char_p * len(categories))(*[c.encode() for c in categories])
        self.call("SetDebugLogging", int(bool(on)), len(categories), arr)

    def last_successful_time(self) -> float:
        out = c_double()
        self.call("GetRealStatus", LAST_SUCCESSFUL_TIME, byref(out))
        return out.value

    def free(self) -> None:
        """Free the remaining states and the instance (idempotent)."""
        if self.component:
            for st in list(self._states):
                st.free()
            self._free_instance(self.component)
            self.component = 0

    # ---- values -----------------------------------------------------------------------------------
    def get(self, kind: str, vrs: Sequence[int]) -> list[Any]:
        """Values of one type (Real, Integer, Boolean) by value reference."""
        n = len(vrs)
        buf = (_CTYPE[kind] * n)()
        self.call(f"Get{kind}", (c_uint * n)(*vrs), n, buf)
        return [bool(x) for x in buf] if kind == "Boolean" else list(buf)

    def set(self, kind: str, vrs: Sequence[int], values: Sequence[Any]) -> None:
        n = len(vrs)
        if len(values) != n:
            raise ValueError(f"{n} value references but {len(values)} values")
        conv = float if kind == "Real" else int
        self.call(f"Set{kind}", (c_uint * n)(*vrs), n, (_CTYPE[kind] * n)(*[conv(v) for v in values]))

    # ---- FMU states -------------------------------------------------------------------------------
    def get_state(self, into: State | None = None) -> State:
        """The current state (a new one, or overwriting ``into``)."""
        st = into if into is not None else State(self, c_void_p())
        self.call("GetFMUstate", byref(st.handle))
        if into is None:
            self._states.append(st)
        return st

    def set_state(self, state: State) -> None:
        self._own(state)
        self.call("SetFMUstate", state.handle)

    def _free_state(self, state: State) -> None:
        self._states.remove(state)
        self.call("FreeFMUstate", byref(state.handle))

    def serialize_state(self, state: State) -> bytes:
        self._own(state)
        size = c_size_t()
        self.call("SerializedFMUstateSize", state.handle, byref(size))
        buf = ctypes.create_string_buffer(size.value)
        self.call("SerializeFMUstate", state.handle, buf, size.value)
        return buf.raw

    def deserialize_state(self, data: bytes) -> State:
        st = State(self, c_void_p())
        self.call("DeSerializeFMUstate", ctypes.create_string_buffer(data, len(data)), len(data), byref(st.handle))
        self._states.append(st)
        return st

    def _own(self, state: State) -> None:
        if state._owner is not self or not state.handle:
            raise ValueError("the state belongs to another instance or was freed")
