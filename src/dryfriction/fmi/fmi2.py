"""The thin layer over an FMI 2.0 co-simulation FMU's C functions.

The FMU's shared library is loaded with plain ctypes from the folder the FMU was unzipped to; every
function is typed here once, with array arguments as ``void *`` so that a caller may pass ctypes
arrays or raw addresses of numpy arrays (``arr.ctypes.data``). Every status is checked: ``fmi2OK``
and ``fmi2Warning`` pass, anything else raises :class:`~dryfriction.errors.FMUCallError` naming the
function, the status and the FMU's last logged sentence. Every sentence the FMU logs with the
status ``fmi2Warning`` becomes a :class:`dryfriction.diagnostics.DryFrictionWarning` when the call
that logged it is checked.

Hot loops call the typed functions directly (:attr:`Instance.f`) and hand a non-zero status to
:meth:`Instance.check`, or use :meth:`Instance.bulk_get` / :meth:`Instance.bulk_set` (one typed
call into a preallocated numpy buffer); everything else uses the checked methods of
:class:`Instance`.
"""

from __future__ import annotations

import ctypes
import os
from ctypes import CFUNCTYPE, POINTER, Structure, byref, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..errors import FMUCallError, FMUError, FMUFileError, status_name as _status_name
from ._base import BaseInstance, Capabilities, State, binary_path, load_library

__all__ = [
    "OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING", "STATUS_NAMES", "LAST_SUCCESSFUL_TIME",
    "FMUError", "FMUCallError", "Instance", "State", "Capabilities", "library_path", "status_name",
]

# ---- fmi2Status -----------------------------------------------------------------------------------
OK, WARNING, DISCARD, ERROR, FATAL, PENDING = 0, 1, 2, 3, 4, 5
STATUS_NAMES = ("fmi2OK", "fmi2Warning", "fmi2Discard", "fmi2Error", "fmi2Fatal", "fmi2Pending")
# fmi2StatusKind / fmi2Type
LAST_SUCCESSFUL_TIME = 2
CO_SIMULATION = 1


def status_name(status: int) -> str:
    """The name of an FMI 2.0 status code (``fmi2OK``, ``fmi2Warning``, ...)."""
    return _status_name(status, "fmi2")


# ---- callbacks --------------------------------------------------------------------------------------
LoggerT = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p)
AllocateT = CFUNCTYPE(c_void_p, c_size_t, c_size_t)
FreeT = CFUNCTYPE(None, c_void_p)
StepFinishedT = CFUNCTYPE(None, c_void_p, c_int)


class CallbackFunctions(Structure):
    """The ``fmi2CallbackFunctions`` structure handed to ``fmi2Instantiate`` (logger, memory, step finished,
    environment)."""
    _fields_ = [("logger", LoggerT), ("allocateMemory", AllocateT), ("freeMemory", FreeT),
                ("stepFinished", StepFinishedT), ("componentEnvironment", c_void_p)]


_LIBC = ctypes.CDLL(None)
# the C library's own calloc/free as the FMU's allocator: no Python in the allocation path
_CALLOC = AllocateT(ctypes.cast(_LIBC.calloc, c_void_p).value)
_FREE = FreeT(ctypes.cast(_LIBC.free, c_void_p).value)

_VP, _SZ, _D, _I = c_void_p, c_size_t, c_double, c_int
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
    "fmi2SetRealInputDerivatives": (_I, (_VP, _SZ, _VP, _VP)),
    "fmi2GetRealOutputDerivatives": (_I, (_VP, _SZ, _VP, _VP)),
    "fmi2GetDirectionalDerivative": (_I, (_VP, _SZ, _VP, _SZ, _VP, _VP)),
}
_CTYPE = {"Real": c_double, "Integer": c_int, "Boolean": c_int}
#: numpy dtype of the values of each get/set family (fmi2Boolean is an int)
DTYPES = {"Real": np.float64, "Integer": np.int32, "Boolean": np.int32}


def library_path(unzip_dir: str | os.PathLike[str], model_identifier: str) -> Path:
    """The shared library of this platform inside an unzipped FMU (fmpy's platform names)."""
    from fmpy import platform

    return binary_path(unzip_dir, platform, model_identifier)


class Instance(BaseInstance):
    """One instantiated FMI 2.0 co-simulation FMU (not thread-safe: one per thread)."""

    prefix = "fmi2"
    ctypes_of = _CTYPE
    dtypes = DTYPES

    def __init__(self, unzip_dir: str | os.PathLike[str], guid: str, model_identifier: str,
                 name: str = "instance", logging: bool = False) -> None:
        super().__init__()
        lib = library_path(unzip_dir, model_identifier)
        if not lib.is_file():
            raise FMUFileError(f"the FMU has no binary for this platform: {lib}")
        self.dll, self.f = load_library(str(lib), _SIGNATURES)
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
            raise FMUCallError(self._last_message(0) or "fmi2Instantiate returned NULL", "fmi2Instantiate", ERROR)
        #: the fmi2Component (an address)
        self.component = comp
        self._unzip_dir = str(unzip_dir)

    def _log(self, env: Any, name: bytes, status: int, category: bytes, message: bytes) -> None:
        self._logged(status, category, message)

    # ---- life cycle -------------------------------------------------------------------------------
    def setup_experiment(self, start: float = 0.0, stop: float | None = None,
                         tolerance: float | None = None) -> None:
        """``fmi2SetupExperiment``: the start time, and the stop time and tolerance when given."""
        self.call("SetupExperiment", int(tolerance is not None), float(tolerance or 0.0), float(start),
                  int(stop is not None), float(stop or 0.0))

    def enter_initialization_mode(self) -> None:
        """``fmi2EnterInitializationMode``."""
        self.call("EnterInitializationMode")

    def exit_initialization_mode(self) -> None:
        """``fmi2ExitInitializationMode``."""
        self.call("ExitInitializationMode")

    def do_step(self, t: float, dt: float, no_set_prior_state: bool = True) -> int:
        """``fmi2DoStep`` from ``t`` over ``dt``; returns the status (an error raises FMUCallError)."""
        return self.call("DoStep", float(t), float(dt), int(no_set_prior_state))

    def step_function(self) -> Callable[[float, float], int]:
        """The fast path of the stepping loop: ``step(t, dt)`` calls fmi2DoStep and returns its
        status, checked (a warning passes)."""
        fn, comp, msgs, check = self.f.DoStep, self.component, self.messages, self.check

        def step(t: float, dt: float) -> int:
            mark = len(msgs)
            if s := fn(comp, t, dt, 1):
                check("fmi2DoStep", s, mark)
            return s

        return step

    def terminate(self) -> None:
        """``fmi2Terminate``."""
        self.call("Terminate")

    def reset(self) -> None:
        """``fmi2Reset``: back to the instantiated state."""
        self.call("Reset")

    def set_debug_logging(self, on: bool, categories: Sequence[str] = ()) -> None:
        """``fmi2SetDebugLogging``: logging on or off for the given categories (all when none is given)."""
        arr = (c_char_p * len(categories))(*[c.encode() for c in categories])
        self.call("SetDebugLogging", int(bool(on)), len(categories), arr)

    def last_successful_time(self) -> float:
        """The time the last ``fmi2DoStep`` reached (``fmi2GetRealStatus``), s."""
        out = c_double()
        self.call("GetRealStatus", LAST_SUCCESSFUL_TIME, byref(out))
        return out.value

    def free(self) -> None:
        """Free the remaining states and the instance (idempotent)."""
        if self.component:
            self._free_states()
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
        """Set the variables ``vrs`` of type ``kind`` (``Real``, ``Integer``, ``Boolean``, ``String``) to
        ``values`` (ValueError for lengths that differ)."""
        n = len(vrs)
        if len(values) != n:
            raise ValueError(f"{n} value references but {len(values)} values")
        conv = float if kind == "Real" else int
        self.call(f"Set{kind}", (c_uint * n)(*vrs), n, (_CTYPE[kind] * n)(*[conv(v) for v in values]))

    # ---- coupling at second order (canInterpolateInputs, maxOutputDerivativeOrder,
    #      providesDirectionalDerivative) ------------------------------------------------------------
    def set_real_input_derivatives(self, vrs: Sequence[int], orders: Sequence[int] | int,
                                   values: Sequence[float]) -> None:
        """fmi2SetRealInputDerivatives: the ``orders[i]``-th time derivative of the real input
        ``vrs[i]`` at the current communication point (held for the next fmi2DoStep only, as the
        standard says). The FMU checks the order against what it takes; a host that asks an FMU
        declaring ``canInterpolateInputs="false"`` gets its refusal as :class:`FMUCallError`."""
        n = len(vrs)
        order = [int(orders)] * n if isinstance(orders, int) else [int(o) for o in orders]
        if len(order) != n or len(values) != n:
            raise ValueError(f"{n} value references need {n} orders and {n} values, not {len(order)} and "
                             f"{len(values)}")
        self.call("SetRealInputDerivatives", (c_uint * n)(*vrs), n, (c_int * n)(*order),
                  (c_double * n)(*[float(v) for v in values]))

    def get_real_output_derivatives(self, vrs: Sequence[int], orders: Sequence[int] | int) -> np.ndarray:
        """fmi2GetRealOutputDerivatives: the ``orders[i]``-th time derivative of the real output
        ``vrs[i]`` at the current communication point (an error where it does not exist)."""
        n = len(vrs)
        order = [int(orders)] * n if isinstance(orders, int) else [int(o) for o in orders]
        if len(order) != n:
            raise ValueError(f"{n} value references need {n} orders, not {len(order)}")
        out = np.empty(n)
        self.call("GetRealOutputDerivatives", (c_uint * n)(*vrs), n, (c_int * n)(*order), out.ctypes.data)
        return out

    def get_directional_derivative(self, unknowns: Sequence[int], knowns: Sequence[int],
                                   seed: Sequence[float]) -> np.ndarray:
        """fmi2GetDirectionalDerivative: ``J seed`` with ``J = d unknowns / d knowns`` at the current point."""
        nu, nk = len(unknowns), len(knowns)
        if len(seed) != nk:
            raise ValueError(f"{nk} knowns need a seed of {nk} values, not {len(seed)}")
        out = np.empty(nu)
        self.call("GetDirectionalDerivative", (c_uint * nu)(*unknowns), nu, (c_uint * nk)(*knowns), nk,
                  (c_double * nk)(*[float(v) for v in seed]), out.ctypes.data)
        return out

    def jacobian(self, unknowns: Sequence[int], knowns: Sequence[int]) -> np.ndarray:
        """The matrix ``d unknowns / d knowns`` [nu, nk], one directional derivative per known."""
        nk = len(knowns)
        cols = [self.get_directional_derivative(unknowns, knowns, np.eye(nk)[j]) for j in range(nk)]
        return np.column_stack(cols) if cols else np.empty((len(unknowns), 0))

    def _bulk(self, what: str, kind: str, vrs: Sequence[int], n_values: int | None) -> Callable[[int], None]:
        if n_values is not None and n_values != len(vrs):
            raise ValueError(f"FMI 2.0 has no arrays: {len(vrs)} value references, {n_values} values")
        fn, comp, n, check, msgs = getattr(self.f, what + kind), self.component, len(vrs), self.check, self.messages
        vr = (c_uint * n)(*vrs)
        name = f"fmi2{what}{kind}"

        def bulk(address: int) -> None:
            mark = len(msgs)
            if s := fn(comp, vr, n, address):
                check(name, s, mark)

        return bulk

    def _state_fn(self, what: str) -> str:
        return {"Get": "GetFMUstate", "Set": "SetFMUstate", "Free": "FreeFMUstate",
                "SerializedSize": "SerializedFMUstateSize", "Serialize": "SerializeFMUstate",
                "DeSerialize": "DeSerializeFMUstate"}[what]
