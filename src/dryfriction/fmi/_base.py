"""What the FMI 2.0 and FMI 3.0 layers share: status checks, the log, FMU state handles, the
fast path of bulk get/set (see :mod:`dryfriction.fmi`)."""

from __future__ import annotations

import ctypes
import os
import threading
from collections.abc import Callable, Sequence
from ctypes import c_void_p
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from ..diagnostics import emit
from ..errors import FMUCallError

__all__ = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "BaseInstance", "Capabilities", "State", "load_library",
           "read_capabilities"]

OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4

_LOAD_LOCK = threading.Lock()


def load_library(path: str, signatures: dict[str, tuple[Any, tuple[Any, ...]]]) -> tuple[ctypes.CDLL, SimpleNamespace]:
    """The shared library and its functions typed once (the instance handle first), by their
    short name (``fmi2DoStep`` -> ``DoStep``)."""
    with _LOAD_LOCK:
        dll = ctypes.CDLL(path)
    fns = {}
    for fname, (restype, argtypes) in signatures.items():
        fn = getattr(dll, fname)
        fn.restype, fn.argtypes = restype, (c_void_p, *argtypes)
        fns[fname[4:]] = fn
    return dll, SimpleNamespace(**fns)


@dataclass(frozen=True)
class Capabilities:
    """What an FMU's ``<CoSimulation>`` element declares about coupling (both FMI versions):
    FMI 2.0 ``canInterpolateInputs``, ``maxOutputDerivativeOrder``, ``providesDirectionalDerivative``;
    FMI 3.0 ``maxOutputDerivativeOrder``, ``providesDirectionalDerivatives``,
    ``providesAdjointDerivatives``, ``providesIntermediateUpdate``, and the value references of
    the variables declared ``intermediateUpdate="true"``. Missing attributes take the standard's
    defaults (false, 0)."""

    fmi_version: int = 2
    can_interpolate_inputs: bool = False
    max_output_derivative_order: int = 0
    directional_derivatives: bool = False
    adjoint_derivatives: bool = False
    can_get_and_set_state: bool = False
    intermediate_update: bool = False
    #: value references of the variables a host may set or get during an intermediate update
    intermediate_vrs: tuple[int, ...] = ()


def read_capabilities(unzip_dir: str | os.PathLike[str]) -> Capabilities:
    """The coupling capabilities of the FMU unzipped to ``unzip_dir`` (its modelDescription.xml)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(Path(unzip_dir) / "modelDescription.xml").getroot()
    cs = root.find("CoSimulation")
    a = cs.attrib if cs is not None else {}

    def flag(name: str) -> bool:
        return a.get(name, "false").strip().lower() == "true"

    version = 3 if root.attrib.get("fmiVersion", "2").startswith("3") else 2
    order = int(a.get("maxOutputDerivativeOrder", "0"))
    if version == 2:
        return Capabilities(2, flag("canInterpolateInputs"), order, flag("providesDirectionalDerivative"), False,
                            flag("canGetAndSetFMUstate"))
    mv = root.find("ModelVariables")
    vrs = tuple(int(v.attrib["valueReference"]) for v in (mv if mv is not None else [])
                if v.attrib.get("intermediateUpdate", "false") == "true")
    return Capabilities(3, False, order, flag("providesDirectionalDerivatives"), flag("providesAdjointDerivatives"),
                        flag("canGetAndSetFMUState"), flag("providesIntermediateUpdate"), vrs)


class State:
    """An FMU state of one instance; free it with :meth:`free` (or ``with``); the instance frees
    the states left when it is freed."""

    def __init__(self, owner: "BaseInstance", handle: c_void_p) -> None:
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


class BaseInstance:
    """Status checks and the log of one instance (subclasses: the FMI 2.0 and FMI 3.0 layers)."""

    #: "fmi2" or "fmi3": the prefix of the function names
    prefix = "fmi2"
    #: the typed C functions, by their short name (``f.DoStep``): status returned, not checked
    f: SimpleNamespace
    component: int
    #: the C type of each get/set family (``Real``: c_double, ...)
    ctypes_of: dict[str, Any] = {}
    #: the numpy dtype of each get/set family
    dtypes: dict[str, Any] = {}

    def __init__(self) -> None:
        #: (status, category, message) of every sentence the FMU logged
        self.messages: list[tuple[int, str, str]] = []
        self._warnings: list[str] = []  # logged with a warning status, not yet emitted
        self._states: list[State] = []
        self.component = 0
        self._unzip_dir = ""
        self._capabilities: Capabilities | None = None

    @property
    def capabilities(self) -> Capabilities:
        """What the FMU's model description declares about coupling (read once)."""
        if self._capabilities is None:
            self._capabilities = read_capabilities(self._unzip_dir)
        return self._capabilities

    # ---- log and status ---------------------------------------------------------------------------
    def _logged(self, status: int, category: bytes | None, message: bytes | None) -> None:
        text = (message or b"").decode(errors="replace")
        self.messages.append((int(status), (category or b"").decode(errors="replace"), text))
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
        """Return ``status`` if it is OK or Warning, else raise :class:`FMUCallError` with the last
        sentence the FMU logged (after message index ``since``). The warnings logged so far are
        emitted first (:meth:`flush_warnings`)."""
        self.flush_warnings()
        if status == OK or status == WARNING:
            return status
        raise FMUCallError(self._last_message(since) or "no message logged", function, status)

    def call(self, function: str, *args: Any) -> int:
        """Call ``<prefix><function>`` (short name) with the component and check its status."""
        mark = len(self.messages)
        return self.check(f"{self.prefix}{function}", getattr(self.f, function)(self.component, *args), mark)

    @property
    def freed(self) -> bool:
        return not self.component

    # ---- values -----------------------------------------------------------------------------------
    def _vr_array(self, vrs: Sequence[int]) -> Any:
        return (ctypes.c_uint32 * len(vrs))(*vrs)

    def bulk_get(self, kind: str, vrs: Sequence[int], n_values: int | None = None) -> Callable[[int], None]:
        """The fast path: a function ``get(address)`` that reads ``kind`` values of ``vrs``
        (``n_values`` in all: FMI 3.0 arrays; default one per reference) into the buffer at
        ``address`` (a preallocated numpy array's ``.ctypes.data`` of :attr:`dtypes` [kind]) with one
        typed call; the status is looked at only when it is not OK."""
        return self._bulk("Get", kind, vrs, n_values)

    def bulk_set(self, kind: str, vrs: Sequence[int], n_values: int | None = None) -> Callable[[int], None]:
        """The fast path of a set: ``set(address)`` writes the values at ``address`` (see :meth:`bulk_get`)."""
        return self._bulk("Set", kind, vrs, n_values)

    def _bulk(self, what: str, kind: str, vrs: Sequence[int], n_values: int | None) -> Callable[[int], None]:
        raise NotImplementedError

    # ---- FMU states -------------------------------------------------------------------------------
    def get_state(self, into: State | None = None) -> State:
        """The current state (a new one, or overwriting ``into``)."""
        st = into if into is not None else State(self, c_void_p())
        self.call(self._state_fn("Get"), ctypes.byref(st.handle))
        if into is None:
            self._states.append(st)
        return st

    def set_state(self, state: State) -> None:
        self._own(state)
        self.call(self._state_fn("Set"), state.handle)

    def _free_state(self, state: State) -> None:
        self._states.remove(state)
        self.call(self._state_fn("Free"), ctypes.byref(state.handle))

    def serialize_state(self, state: State) -> bytes:
        self._own(state)
        size = ctypes.c_size_t()
        self.call(self._state_fn("SerializedSize"), state.handle, ctypes.byref(size))
        buf = ctypes.create_string_buffer(size.value)
        self.call(self._state_fn("Serialize"), state.handle, buf, size.value)
        return buf.raw

    def deserialize_state(self, data: bytes) -> State:
        st = State(self, c_void_p())
        self.call(self._state_fn("DeSerialize"), ctypes.create_string_buffer(data, len(data)), len(data),
                  ctypes.byref(st.handle))
        self._states.append(st)
        return st

    def _state_fn(self, what: str) -> str:
        raise NotImplementedError

    def _own(self, state: State) -> None:
        if state._owner is not self or not state.handle:
            raise ValueError("the state belongs to another instance or was freed")

    def _free_states(self) -> None:
        for st in list(self._states):
            st.free()


def binary_path(unzip_dir: str | os.PathLike[str], folder: str, model_identifier: str) -> Path:
    """The shared library of this platform inside an unzipped FMU: binaries/<folder>/<id><ext>."""
    from fmpy import sharedLibraryExtension

    return Path(unzip_dir) / "binaries" / folder / f"{model_identifier}{sharedLibraryExtension}"
