"""Driving the FMI 3.0 oscillator FMU (build/fmi3/DryFrictionOscillator.fmu) through the package's
FMI 3.0 layer (:mod:`dryfriction.fmi.fmi3`): plain stepping, early return at every stick/slip
switch, event mode with the left and right limits of a switch, and the intermediate-update
callback::

    with OscillatorFMU3(params={"scheme": 3}, early_return=True) as fmu:
        run = fmu.run(t_stop=4.0, dt=0.1, outputs=("x", "mode"))
    print(run.switch_times)

The semantics of the events are documented in docs/fmi3.md.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import paths
from .base import Driver, Run, Switch
from ..errors import FMUCallError
from ..fmi import fmi3
from ..fmi._base import State

__all__ = ["OscillatorFMU3", "Run", "Switch", "Intermediate", "default_fmi3_path"]

#: the intermediate-update callback: (time, canReturnEarly) -> earlyReturnRequested
Intermediate = Callable[[float, bool], bool]


def default_fmi3_path() -> Path:
    """The FMI 3.0 oscillator FMU: ``$DFO_FMU3``, else the installed package's, else the build
    tree's (:func:`dryfriction.paths.fmu_path`; FMUFileError if there is none or it is not that FMU)."""
    return paths.fmu_path(paths.OSCILLATOR3)


class OscillatorFMU3(Driver):
    """One instance of the FMI 3.0 oscillator FMU with its event options, as a context manager:
    instantiated, ``params`` set in Initialization Mode, then in step mode at ``start_time``.

    Parameters
    ----------
    params
        The FMU's variables by name (``m``, ``k``, ``scheme``, ...), set in Initialization Mode.
    early_return
        Return from ``fmi3DoStep`` at every stick/slip switch (``earlyReturnAllowed``).
    event_mode
        Enter Event Mode at every switch and record the left and right limits (``eventModeUsed``).
    intermediate
        An intermediate-update callback ``(t, can_return_early) -> bool``.
    fmu_path
        The FMU; default: the environment's ``DFO_FMU3``, the installed package's, the checkout's
        ``build/fmi3/``.
    start_time
        The start time, s.
    logging
        Switch the FMU's debug logging on.

    Raises
    ------
    dryfriction.FMUFileError
        ``fmu_path`` is not the FMI 3.0 oscillator FMU.
    dryfriction.FMUCallError
        A call the FMU refuses, with the FMU's sentence.

    Examples
    --------
    >>> from dryfriction import OscillatorFMU3
    >>> with OscillatorFMU3({"scheme": 3}, early_return=True) as fmu:
    ...     run = fmu.run(t_stop=5.0, dt=0.1, outputs=("x", "mode"))
    >>> [s.kind for s in run.switches][:3]
    ['reversal', 'reversal', 'stop']
    """

    KIND = paths.OSCILLATOR3
    TERMINATE_ON_CLOSE = True

    def __init__(self, params: Mapping[str, float | int | bool | str] | None = None, *, early_return: bool = False,
                 event_mode: bool = False, intermediate: Intermediate | None = None,
                 fmu_path: str | os.PathLike[str] | None = None, start_time: float = 0.0,
                 logging: bool = False) -> None:
        self._open(fmu_path, "dfo_fmi3_")
        self.early_return, self.event_mode = early_return, event_mode
        self._user_cb = intermediate
        self.updates: list[float] = []  # times of the intermediate updates
        try:
            self.inst = fmi3.Instance(self.unzip_dir, self.md.guid, self.md.model_identifier, "dfo", logging,
                                      event_mode_used=event_mode, early_return_allowed=early_return,
                                      intermediate_update=self._on_update if intermediate else None)
        except BaseException:
            shutil.rmtree(self.unzip_dir, ignore_errors=True)
            raise
        try:
            self.time = float(start_time)
            self.inst.enter_initialization_mode(self.time)
            self.set(params or {})
            self.inst.exit_initialization_mode()
            if event_mode:  # a co-simulation FMU with event mode starts in event mode
                self.inst.update_discrete_states()
                self.inst.enter_step_mode()
        except BaseException:
            self.close()
            raise
        self._slave: _FmpyStyleSlave | None = None
        self._step = self.inst.step_function()  # the fast path: fmi3DoStep with reused out-arguments
        self._step_out = self.inst._step_out

    def _on_update(self, info: fmi3.IntermediateUpdate) -> bool:
        if info.set_requested:  # an input point (an internal step's end), not a switch: no input set here
            return False
        self.updates.append(info.time)
        assert self._user_cb is not None
        return bool(self._user_cb(info.time, info.can_return_early))

    @property
    def slave(self) -> "_FmpyStyleSlave":
        """The instance under fmpy's ``FMU3Slave`` method names (``enterEventMode``,
        ``updateDiscreteStates``, ``getFMUState`` ...), for code written against the fmpy-based
        driver this class replaced; its errors are :class:`FMUCallError` and fmpy's
        ``FMICallException`` at once."""
        if self._slave is None:
            self._slave = _FmpyStyleSlave(self.inst)
        return self._slave

    def set_inputs(self, values: Mapping[str, float]) -> None:
        """Set the inputs (``F_ext``, ``N_ext``, ``v_belt``) by name; they hold until set again."""
        self.set(values)

    def do_step(self, dt: float) -> tuple[bool, bool]:
        """One fmi3DoStep from the FMU's time; returns (eventHandlingNeeded, earlyReturn)."""
        self._step(self.time, dt)
        event, _, early, last = self._step_out
        self.time = last.value  # tc + dt, or the switch it returned early at
        return event.value, early.value

    def handle_event(self, mode_before: int) -> Switch:
        """Event mode at the current time: the left limits, fmi3UpdateDiscreteStates, the right limits."""
        left = self.get(["mode", "F_friction", "a"])
        self.inst.enter_event_mode()
        upd = self.inst.update_discrete_states()
        if upd.discrete_states_need_update or upd.terminate_simulation:
            raise RuntimeError("fmi3UpdateDiscreteStates asked for another iteration or to terminate")
        right = self.get(["mode", "F_friction", "a"])
        self.inst.enter_step_mode()
        return Switch(self.time, int(left["mode"]), int(right["mode"]), left["F_friction"], right["F_friction"],
                      left["a"], right["a"])

    def run(self, t_stop: float, dt: float, outputs: Sequence[str] = ("x", "v", "mode")) -> Run:
        """Step to t_stop on the host's grid t0 + k dt, sampling the outputs at every point reached; an
        early return adds the switch as a point and the next step goes on to the grid point it
        interrupted. Every change of mode met at an early return or an event is a Switch."""
        names = list(dict.fromkeys(list(outputs) + ["mode"]))
        times, rows, switches = [self.time], [self.get(names)], []
        mode = int(rows[0]["mode"])
        t0, k = self.time, 1
        while True:
            target = min(t0 + k * dt, t_stop)
            if target <= self.time:
                if target >= t_stop:
                    break
                k += 1
                continue
            event, early = self.do_step(target - self.time)
            if not early:
                self.time = target  # the grid point itself, not an accumulation of steps
                k += 1
            if event:
                sw = self.handle_event(mode)
                switches.append(sw)
            row = self.get(names)
            if not event and int(row["mode"]) != mode and self.early_return:
                switches.append(Switch(self.time, mode, int(row["mode"])))
            mode = int(row["mode"])
            times.append(self.time)
            rows.append(row)
        values = {n: np.array([r[n] for r in rows]) for n in outputs}
        return Run(np.array(times), values, switches)

    def __enter__(self) -> "OscillatorFMU3":
        return self



def _compat_error() -> type[FMUCallError]:
    from fmpy.fmi1 import FMICallException

    class FMUCallErrorFmpy(FMUCallError, FMICallException):  # type: ignore[misc]
        """An FMUCallError that is fmpy's FMICallException too (the fmpy-style surface)."""

    return FMUCallErrorFmpy


class _FmpyStyleSlave:
    """fmpy's FMU3Slave method names over an :class:`dryfriction.fmi.fmi3.Instance` (see
    :attr:`OscillatorFMU3.slave`)."""

    def __init__(self, inst: fmi3.Instance) -> None:
        self._inst = inst
        self._error = _compat_error()

    @property
    def component(self) -> int:
        return self._inst.component

    def _do(self, fn: Callable[..., Any], *args: Any) -> Any:
        try:
            return fn(*args)
        except FMUCallError as e:
            raise self._error(e.message, e.function, e.status) from None

    def enterEventMode(self) -> None:  # noqa: N802 - fmpy's names
        self._do(self._inst.enter_event_mode)

    def enterStepMode(self) -> None:  # noqa: N802
        self._do(self._inst.enter_step_mode)

    def updateDiscreteStates(self) -> tuple[bool, bool, bool, bool, bool, float]:  # noqa: N802
        return tuple(self._do(self._inst.update_discrete_states))  # type: ignore[return-value]

    def doStep(self, currentCommunicationPoint: float, communicationStepSize: float,  # noqa: N802,N803
               noSetFMUStatePriorToCurrentPoint: bool = True) -> tuple[bool, bool, bool, float]:  # noqa: N803
        return tuple(self._do(self._inst.do_step, currentCommunicationPoint, communicationStepSize,  # type: ignore
                              noSetFMUStatePriorToCurrentPoint))

    def getFMUState(self) -> State:  # noqa: N802
        return self._do(self._inst.get_state)

    def setFMUState(self, state: State) -> None:  # noqa: N802
        self._do(self._inst.set_state, state)

    def freeFMUState(self, state: State) -> None:  # noqa: N802
        self._do(state.free)

    def serializeFMUState(self, state: State) -> bytes:  # noqa: N802
        return self._do(self._inst.serialize_state, state)

    def deserializeFMUState(self, serializedState: bytes) -> State:  # noqa: N802,N803
        return self._do(self._inst.deserialize_state, serializedState)

    def reset(self) -> None:
        self._do(self._inst.reset)

    def terminate(self) -> None:
        self._do(self._inst.terminate)

    def _getter(kind: str) -> Callable[..., list[Any]]:  # type: ignore[misc]
        def get(self: "_FmpyStyleSlave", vr: Sequence[int], nValues: int | None = None) -> list[Any]:  # noqa: N803
            return self._do(self._inst.get, kind, list(vr), nValues)
        return get

    def _setter(kind: str) -> Callable[..., None]:  # type: ignore[misc]
        def set_(self: "_FmpyStyleSlave", vr: Sequence[int], values: Sequence[Any]) -> None:
            self._do(self._inst.set, kind, list(vr), list(values))
        return set_

    getFloat64, setFloat64 = _getter("Float64"), _setter("Float64")  # noqa: N815
    getInt32, setInt32 = _getter("Int32"), _setter("Int32")  # noqa: N815
    getInt64, setInt64 = _getter("Int64"), _setter("Int64")  # noqa: N815
    getUInt64, setUInt64 = _getter("UInt64"), _setter("UInt64")  # noqa: N815
    getBoolean, setBoolean = _getter("Boolean"), _setter("Boolean")  # noqa: N815
