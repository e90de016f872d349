"""The thin layer over an FMI 3.0 co-simulation FMU's C functions (the counterpart of
:mod:`dryfriction.fmi.fmi2`).

Plain ctypes on the FMU's shared library, every function typed once with array arguments as
``void *`` (ctypes arrays or numpy addresses), every status checked (``fmi3OK`` and
``fmi3Warning`` pass, anything else is an :class:`~dryfriction.errors.FMUCallError` with the FMU's
sentence; warnings become :class:`~dryfriction.diagnostics.DryFrictionWarning`). What FMI 3.0 adds:

- Configuration Mode (:meth:`Instance.enter_configuration_mode`) to set a structural parameter
  (UInt64, the chain's ``n``), arrays (``n_values`` values for one value reference),
- event mode (``event_mode_used``; :meth:`Instance.enter_event_mode`,
  :meth:`Instance.update_discrete_states`, :meth:`Instance.enter_step_mode`),
- early return (``early_return_allowed``; :meth:`Instance.do_step` returns
  :class:`StepResult` with ``early_return`` and ``last_successful_time``),
- the intermediate-update callback (``intermediate_update``: called with an
  :class:`IntermediateUpdate`; a true result requests an early return at its time; an exception
  it raises is raised again when the step returns).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from ctypes import (CFUNCTYPE, POINTER, byref, c_bool, c_char_p, c_double, c_int, c_int32, c_int64, c_size_t,
                    c_uint32, c_uint64, c_void_p)
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..errors import FMUCallError, FMUError, FMUFileError, status_name as _status_name
from ._base import BaseInstance, Capabilities, State, binary_path, load_library

__all__ = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "STATUS_NAMES", "FMUError", "FMUCallError", "Instance",
           "State", "StepResult", "DiscreteStates", "IntermediateUpdate", "IntermediateInputs", "Capabilities",
           "library_path", "status_name", "DTYPES"]

OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4
STATUS_NAMES = ("fmi3OK", "fmi3Warning", "fmi3Discard", "fmi3Error", "fmi3Fatal")


def status_name(status: int) -> str:
    """The name of an FMI 3.0 status code (``fmi3OK``, ``fmi3Warning``, ...)."""
    return _status_name(status, "fmi3")


LogMessageT = CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)
IntermediateUpdateT = CFUNCTYPE(None, c_void_p, c_double, c_bool, c_bool, c_bool, c_bool, POINTER(c_bool),
                                POINTER(c_double))

_VP, _SZ, _D, _I, _B = c_void_p, c_size_t, c_double, c_int, c_bool
_GS = (_VP, _SZ, _VP, _SZ)  # value references, nvr, values, nValues
#: name -> (restype, argtypes after the instance)
_SIGNATURES: dict[str, tuple[Any, tuple[Any, ...]]] = {
    "fmi3SetDebugLogging": (_I, (_B, _SZ, _VP)),
    "fmi3EnterConfigurationMode": (_I, ()),
    "fmi3ExitConfigurationMode": (_I, ()),
    "fmi3EnterInitializationMode": (_I, (_B, _D, _D, _B, _D)),
    "fmi3ExitInitializationMode": (_I, ()),
    "fmi3EnterEventMode": (_I, ()),
    "fmi3EnterStepMode": (_I, ()),
    "fmi3UpdateDiscreteStates": (_I, (_VP, _VP, _VP, _VP, _VP, _VP)),
    "fmi3Terminate": (_I, ()),
    "fmi3Reset": (_I, ()),
    "fmi3GetFloat64": (_I, _GS), "fmi3SetFloat64": (_I, _GS),
    "fmi3GetInt32": (_I, _GS), "fmi3SetInt32": (_I, _GS),
    "fmi3GetInt64": (_I, _GS), "fmi3SetInt64": (_I, _GS),
    "fmi3GetUInt64": (_I, _GS), "fmi3SetUInt64": (_I, _GS),
    "fmi3GetBoolean": (_I, _GS), "fmi3SetBoolean": (_I, _GS),
    "fmi3DoStep": (_I, (_D, _D, _B, _VP, _VP, _VP, _VP)),
    "fmi3GetFMUState": (_I, (_VP,)),
    "fmi3SetFMUState": (_I, (_VP,)),
    "fmi3FreeFMUState": (_I, (_VP,)),
    "fmi3SerializedFMUStateSize": (_I, (_VP, _VP)),
    "fmi3SerializeFMUState": (_I, (_VP, _VP, _SZ)),
    "fmi3DeserializeFMUState": (_I, (_VP, _SZ, _VP)),
    "fmi3GetOutputDerivatives": (_I, (_VP, _SZ, _VP, _VP, _SZ)),
    "fmi3GetDirectionalDerivative": (_I, (_VP, _SZ, _VP, _SZ, _VP, _SZ, _VP, _SZ)),
    "fmi3GetAdjointDerivative": (_I, (_VP, _SZ, _VP, _SZ, _VP, _SZ, _VP, _SZ)),
}
_CTYPE = {"Float64": c_double, "Int32": c_int32, "Int64": c_int64, "UInt64": c_uint64, "Boolean": c_bool}
#: numpy dtype of the values of each get/set family (fmi3Boolean is C's bool: one byte)
DTYPES = {"Float64": np.float64, "Int32": np.int32, "Int64": np.int64, "UInt64": np.uint64, "Boolean": np.bool_}
_CONVERT: dict[str, Callable[[Any], Any]] = {"Float64": float, "Int32": int, "Int64": int, "UInt64": int,
                                             "Boolean": bool}


class StepResult(NamedTuple):
    """The out-arguments of fmi3DoStep."""

    event_handling_needed: bool
    terminate_simulation: bool
    early_return: bool
    last_successful_time: float


class DiscreteStates(NamedTuple):
    """The out-arguments of fmi3UpdateDiscreteStates."""

    discrete_states_need_update: bool
    terminate_simulation: bool
    nominals_of_continuous_states_changed: bool
    values_of_continuous_states_changed: bool
    next_event_time_defined: bool
    next_event_time: float


class IntermediateUpdate(NamedTuple):
    """The arguments of the intermediate-update callback."""

    time: float
    set_requested: bool
    get_allowed: bool
    step_finished: bool
    can_return_early: bool


#: what a master sets at an intermediate update: ``f(time) -> (value references, Float64 values)``
IntermediateInputs = Callable[[float], tuple[Sequence[int], Sequence[float]]]


def library_path(unzip_dir: str | os.PathLike[str], model_identifier: str) -> Path:
    """The shared library of this platform inside an unzipped FMU (FMI 3.0's platform tuples)."""
    from fmpy import platform_tuple

    return binary_path(unzip_dir, platform_tuple, model_identifier)


class Instance(BaseInstance):
    """One instantiated FMI 3.0 co-simulation FMU (not thread-safe: one per thread)."""

    prefix = "fmi3"
    ctypes_of = _CTYPE
    dtypes = DTYPES

    def __init__(self, unzip_dir: str | os.PathLike[str], token: str, model_identifier: str,
                 name: str = "instance", logging: bool = False, *, event_mode_used: bool = False,
                 early_return_allowed: bool = False,
                 intermediate_update: Callable[[IntermediateUpdate], bool] | None = None,
                 required_intermediate: Sequence[int] = ()) -> None:
        super().__init__()
        lib = library_path(unzip_dir, model_identifier)
        if not lib.is_file():
            raise FMUFileError(f"the FMU has no binary for this platform: {lib}")
        self.dll, self.f = load_library(str(lib), _SIGNATURES)
        self.event_mode_used, self.early_return_allowed = bool(event_mode_used), bool(early_return_allowed)
        self._log_cb = LogMessageT(self._log)  # kept alive as long as the instance
        self._user_update = intermediate_update
        self._update_error: BaseException | None = None
        self._update_cb = IntermediateUpdateT(self._on_update) if intermediate_update else IntermediateUpdateT()
        instantiate = self.dll.fmi3InstantiateCoSimulation
        instantiate.restype = c_void_p
        instantiate.argtypes = [c_char_p, c_char_p, c_char_p, c_bool, c_bool, c_bool, c_bool, c_void_p, c_size_t,
                                c_void_p, LogMessageT, IntermediateUpdateT]
        self._free_instance = self.dll.fmi3FreeInstance
        self._free_instance.restype, self._free_instance.argtypes = None, [c_void_p]
        resources = os.path.join(str(unzip_dir), "resources") + os.path.sep
        req = (c_uint32 * len(required_intermediate))(*required_intermediate)
        comp = instantiate(name.encode(), token.encode(), resources.encode(), False, bool(logging),
                           self.event_mode_used, self.early_return_allowed, req, len(required_intermediate),
                           None, self._log_cb, self._update_cb)
        if not comp:
            raise FMUCallError(self._last_message(0) or "fmi3InstantiateCoSimulation returned NULL",
                               "fmi3InstantiateCoSimulation", ERROR)
        #: the fmi3Instance (an address)
        self.component = comp
        self._unzip_dir = str(unzip_dir)
        self._inputs_during_step: IntermediateInputs | None = None
        self._step_out = (c_bool(), c_bool(), c_bool(), c_double())
        self._step_refs = tuple(byref(x) for x in self._step_out)

    def _log(self, env: Any, status: int, category: bytes, message: bytes) -> None:
        self._logged(status, category, message)

    def _on_update(self, env: Any, t: float, set_requested: bool, get_allowed: bool, step_finished: bool,
                   can_return: bool, early_requested: Any, early_time: Any) -> None:
        assert self._user_update is not None
        try:
            if set_requested and self._inputs_during_step is not None:
                self._set_intermediate(float(t))
            want = bool(self._user_update(IntermediateUpdate(t, bool(set_requested), bool(get_allowed),
                                                             bool(step_finished), bool(can_return))))
        except BaseException as e:  # noqa: BLE001 - raised again when the step returns
            self._update_error = self._update_error or e
            want = bool(can_return)
        early_requested[0] = want
        early_time[0] = t

    def _set_intermediate(self, t: float) -> None:
        assert self._inputs_during_step is not None
        vrs, values = self._inputs_during_step(t)
        n = len(vrs)
        if n:
            self.call("SetFloat64", (c_uint32 * n)(*vrs), n, (c_double * n)(*[float(v) for v in values]), n)

    def set_intermediate_inputs(self, inputs: IntermediateInputs | None) -> None:
        """Let a master set inputs during a step: at every intermediate update at which the FMU
        requests them (``intermediateVariableSetRequested``), ``inputs(t)`` gives the value
        references and Float64 values to set (variables declared ``intermediateUpdate="true"``;
        the FMU checks that), before the instance's own callback runs. ``None`` stops it. Needs an
        instance made with an ``intermediate_update`` callback (the C callback is fixed at
        instantiation); an exception raised in ``inputs`` is raised again when the step returns."""
        if inputs is not None and self._user_update is None:
            raise FMUError("inputs during a step need an instance made with an intermediate_update callback "
                           "(fmi3InstantiateCoSimulation takes the callback once)")
        self._inputs_during_step = inputs

    # ---- output, directional and adjoint derivatives ------------------------------------------------
    def get_output_derivatives(self, vrs: Sequence[int], orders: Sequence[int] | int,
                               n_values: int | None = None) -> np.ndarray:
        """fmi3GetOutputDerivatives: the ``orders[i]``-th time derivative of the Float64 output
        ``vrs[i]`` at the current time (``n_values`` in all: arrays); an error where it does not exist."""
        nvr = len(vrs)
        order = [int(orders)] * nvr if isinstance(orders, int) else [int(o) for o in orders]
        if len(order) != nvr:
            raise ValueError(f"{nvr} value references need {nvr} orders, not {len(order)}")
        n = nvr if n_values is None else int(n_values)
        out = np.empty(n)
        self.call("GetOutputDerivatives", (c_uint32 * nvr)(*vrs), nvr, (c_int32 * nvr)(*order), out.ctypes.data, n)
        return out

    def _derivative(self, fn: str, unknowns: Sequence[int], knowns: Sequence[int], seed: Sequence[float],
                    n_out: int) -> np.ndarray:
        nu, nk, ns = len(unknowns), len(knowns), len(seed)
        out = np.empty(int(n_out))
        self.call(fn, (c_uint32 * nu)(*unknowns), nu, (c_uint32 * nk)(*knowns), nk,
                  (c_double * ns)(*[float(v) for v in seed]), ns, out.ctypes.data, out.size)
        return out

    def get_directional_derivative(self, unknowns: Sequence[int], knowns: Sequence[int], seed: Sequence[float],
                                   n_unknown_values: int | None = None) -> np.ndarray:
        """fmi3GetDirectionalDerivative: ``J seed``, ``J = d unknowns / d knowns`` (seed: one
        value per element of the knowns; the result one per element of the unknowns, default one
        per reference)."""
        return self._derivative("GetDirectionalDerivative", unknowns, knowns, seed,
                                len(unknowns) if n_unknown_values is None else n_unknown_values)

    def get_adjoint_derivative(self, unknowns: Sequence[int], knowns: Sequence[int], seed: Sequence[float],
                               n_known_values: int | None = None) -> np.ndarray:
        """fmi3GetAdjointDerivative: ``J^T seed`` (seed over the unknowns, the result over the knowns)."""
        return self._derivative("GetAdjointDerivative", unknowns, knowns, seed,
                                len(knowns) if n_known_values is None else n_known_values)

    def jacobian(self, unknowns: Sequence[int], knowns: Sequence[int]) -> np.ndarray:
        """The matrix ``d unknowns / d knowns`` [nu, nk] of scalar variables, one directional
        derivative per known."""
        nk = len(knowns)
        cols = [self.get_directional_derivative(unknowns, knowns, np.eye(nk)[j]) for j in range(nk)]
        return np.column_stack(cols) if cols else np.empty((len(unknowns), 0))

    # ---- life cycle -------------------------------------------------------------------------------
    def enter_configuration_mode(self) -> None:
        """``fmi3EnterConfigurationMode``: structural parameters may be set."""
        self.call("EnterConfigurationMode")

    def exit_configuration_mode(self) -> None:
        """``fmi3ExitConfigurationMode``."""
        self.call("ExitConfigurationMode")

    def enter_initialization_mode(self, start: float = 0.0, stop: float | None = None,
                                  tolerance: float | None = None) -> None:
        """``fmi3EnterInitializationMode`` with the start time, and the stop time and tolerance when given."""
        self.call("EnterInitializationMode", tolerance is not None, float(tolerance or 0.0), float(start),
                  stop is not None, float(stop or 0.0))

    def exit_initialization_mode(self) -> None:
        """``fmi3ExitInitializationMode``."""
        self.call("ExitInitializationMode")

    def enter_event_mode(self) -> None:
        """``fmi3EnterEventMode``."""
        self.call("EnterEventMode")

    def enter_step_mode(self) -> None:
        """``fmi3EnterStepMode``."""
        self.call("EnterStepMode")

    def update_discrete_states(self) -> DiscreteStates:
        """``fmi3UpdateDiscreteStates``: what the FMU reports after an event, as a :class:`DiscreteStates`."""
        out = (c_bool(), c_bool(), c_bool(), c_bool(), c_bool(), c_double())
        self.call("UpdateDiscreteStates", *[byref(x) for x in out])
        return DiscreteStates(*(bool(x.value) for x in out[:5]), out[5].value)

    def do_step(self, t: float, dt: float, no_set_prior_state: bool = True) -> StepResult:
        """One fmi3DoStep from ``t``; its out-arguments (checked; an exception of the
        intermediate-update callback is raised here)."""
        mark = len(self.messages)
        status = self.f.DoStep(self.component, float(t), float(dt), bool(no_set_prior_state), *self._step_refs)
        self._raise_update_error()
        if status:
            self.check("fmi3DoStep", status, mark)
        ev, term, early, last = self._step_out
        return StepResult(ev.value, term.value, early.value, last.value)

    def step_function(self) -> Callable[[float, float], int]:
        """The fast path of the stepping loop: ``step(t, dt)`` calls fmi3DoStep with reused
        out-arguments and returns its status, checked (a warning passes); the out-arguments are
        read with :meth:`last_step`."""
        fn, comp, msgs, check = self.f.DoStep, self.component, self.messages, self.check
        ev, term, early, last = self._step_refs
        raise_update_error = self._raise_update_error

        if self._user_update is None:
            def step(t: float, dt: float) -> int:
                mark = len(msgs)
                if s := fn(comp, t, dt, True, ev, term, early, last):
                    check("fmi3DoStep", s, mark)
                return s
        else:
            def step(t: float, dt: float) -> int:
                mark = len(msgs)
                s = fn(comp, t, dt, True, ev, term, early, last)
                raise_update_error()
                if s:
                    check("fmi3DoStep", s, mark)
                return s

        return step

    def last_step(self) -> StepResult:
        """The out-arguments of the last fmi3DoStep."""
        ev, term, early, last = self._step_out
        return StepResult(ev.value, term.value, early.value, last.value)

    def _raise_update_error(self) -> None:
        if self._update_error is not None:
            err, self._update_error = self._update_error, None
            raise err

    def terminate(self) -> None:
        """``fmi3Terminate``."""
        self.call("Terminate")

    def reset(self) -> None:
        """``fmi3Reset``: back to the instantiated state."""
        self.call("Reset")

    def set_debug_logging(self, on: bool, categories: Sequence[str] = ()) -> None:
        """``fmi3SetDebugLogging``: logging on or off for the given categories (all when none is given)."""
        arr = (c_char_p * len(categories))(*[c.encode() for c in categories])
        self.call("SetDebugLogging", bool(on), len(categories), arr)

    def free(self) -> None:
        """Free the remaining states and the instance (idempotent)."""
        if self.component:
            self._free_states()
            self._free_instance(self.component)
            self.component = 0

    # ---- values -----------------------------------------------------------------------------------
    def get(self, kind: str, vrs: Sequence[int], n_values: int | None = None) -> list[Any]:
        """Values of one type (Float64, Int32, Int64, UInt64, Boolean) by value reference;
        ``n_values`` in all (arrays), default one per reference."""
        n = len(vrs) if n_values is None else int(n_values)
        buf = (_CTYPE[kind] * n)()
        self.call(f"Get{kind}", (c_uint32 * len(vrs))(*vrs), len(vrs), buf, n)
        return list(buf)

    def set(self, kind: str, vrs: Sequence[int], values: Sequence[Any]) -> None:
        """Set values of one type; ``values`` holds every element of the variables (arrays: all
        their values, the FMU checks the count)."""
        conv = _CONVERT[kind]
        n = len(values)
        self.call(f"Set{kind}", (c_uint32 * len(vrs))(*vrs), len(vrs), (_CTYPE[kind] * n)(*[conv(v) for v in values]), n)

    def _bulk(self, what: str, kind: str, vrs: Sequence[int], n_values: int | None) -> Callable[[int], None]:
        fn, comp, check, msgs = getattr(self.f, what + kind), self.component, self.check, self.messages
        nvr = len(vrs)
        n = nvr if n_values is None else int(n_values)
        vr = (c_uint32 * nvr)(*vrs)
        name = f"fmi3{what}{kind}"

        def bulk(address: int) -> None:
            mark = len(msgs)
            if s := fn(comp, vr, nvr, address, n):
                check(name, s, mark)

        return bulk

    def _state_fn(self, what: str) -> str:
        return {"Get": "GetFMUState", "Set": "SetFMUState", "Free": "FreeFMUState",
                "SerializedSize": "SerializedFMUStateSize", "Serialize": "SerializeFMUState",
                "DeSerialize": "DeserializeFMUState"}[what]
