"""Driving the FMI 3.0 co-simulation FMU (build/fmi3/DryFrictionOscillator.fmu) through fmpy's
public ``FMU3Slave``: plain stepping, early return at every stick/slip switch, event mode with the
left and right limits of a switch, and the intermediate-update callback.

    with FMI3Oscillator(params={"scheme": 3}, early_return=True) as fmu:
        run = fmu.run(t_stop=4.0, dt=0.1, outputs=("x", "mode"))
    print(run.switch_times)

The semantics of the events are documented in docs/fmi3.md.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from . import locate
from .diagnostics import emit
from .fmi2 import FMUError

Intermediate = Callable[[float, bool], bool]  # (time, canReturnEarly) -> earlyReturnRequested


def default_fmi3_path() -> Path:
    """The FMI 3.0 oscillator FMU: ``$DFO_FMU3``, else the installed package's, else the build
    tree's (:func:`dryfriction.locate.fmu_path`; FMUFileError if there is none or it is not that FMU)."""
    return locate.fmu_path(locate.OSCILLATOR3)


@dataclass(frozen=True)
class Switch:
    """One event: time, mode before and after, and (event mode) the left and right limits of the
    friction force and the acceleration."""

    t: float
    mode_before: int
    mode_after: int
    F_left: float = float("nan")
    F_right: float = float("nan")
    a_left: float = float("nan")
    a_right: float = float("nan")

    @property
    def kind(self) -> str:
        if self.mode_before == 0:
            return "breakaway"
        if self.mode_after == 0:
            return "stop"
        return "reversal"


@dataclass
class Run:
    """Samples at every communication point (and every early return), and the switches met."""

    time: np.ndarray
    values: dict[str, np.ndarray]
    switches: list[Switch] = field(default_factory=list)

    @property
    def switch_times(self) -> np.ndarray:
        return np.array([s.t for s in self.switches])


class FMI3Oscillator:
    """One instance of the FMI 3.0 FMU with its event options, as a context manager."""

    def __init__(self, params: Mapping[str, float | int | bool] | None = None, *, early_return: bool = False,
                 event_mode: bool = False, intermediate: Intermediate | None = None,
                 fmu_path: str | os.PathLike[str] | None = None, start_time: float = 0.0) -> None:
        path = locate.fmu_path(locate.OSCILLATOR3, fmu_path)
        self.md = read_model_description(str(path))
        self._vars = {v.name: v for v in self.md.modelVariables}
        self._dir = extract(str(path), tempfile.mkdtemp(prefix="dfo_fmi3_"))
        self.early_return, self.event_mode = early_return, event_mode
        self._user_cb = intermediate
        self.updates: list[float] = []  # times of the intermediate updates
        #: (status, message) of every sentence the FMU logged
        self.messages: list[tuple[int, str]] = []
        self._warnings: list[str] = []
        self.slave = FMU3Slave(guid=self.md.guid, unzipDirectory=self._dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="dfo")
        self.slave.instantiate(eventModeUsed=event_mode, earlyReturnAllowed=early_return, logMessage=self._log,
                               intermediateUpdate=self._on_update if intermediate else None)
        self.time = start_time
        self._call("fmi3EnterInitializationMode", self.slave.enterInitializationMode, startTime=start_time)
        for name, value in (params or {}).items():
            self._set(name, value)
        self._call("fmi3ExitInitializationMode", self.slave.exitInitializationMode)
        if event_mode:  # a co-simulation FMU with event mode starts in event mode
            self._call("fmi3UpdateDiscreteStates", self.slave.updateDiscreteStates)
            self._call("fmi3EnterStepMode", self.slave.enterStepMode)

    def _log(self, env: Any, status: int, category: bytes, message: bytes) -> None:
        text = (message or b"").decode(errors="replace")
        self.messages.append((int(status), text))
        del self.messages[:-100]
        if status == 1:  # fmi3Warning
            self._warnings.append(text)

    def _call(self, what: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """An fmpy call: the warnings it logged emitted as DryFrictionWarning, an error status as
        :class:`FMUError` with the FMU's sentence."""
        from fmpy.fmi1 import FMICallException

        mark = len(self.messages)
        try:
            out = fn(*args, **kwargs)
        except FMICallException as e:
            said = [m for st, m in self.messages[mark:] if st >= 2]
            self._flush()
            raise FMUError(said[-1] if said else str(e), what, getattr(e, "status", 3)) from None
        self._flush()
        return out

    def _flush(self) -> None:
        if self._warnings:
            pending, self._warnings = self._warnings, []
            emit(pending, stacklevel=4)

    # fmpy's ctypes callback: (env, time, setRequested, getAllowed, stepFinished, canReturnEarly,
    # *earlyReturnRequested, *earlyReturnTime)
    def _on_update(self, env: Any, t: float, set_req: Any, get_ok: Any, finished: Any, can_return: Any,
                   early_req: Any, early_time: Any) -> None:
        self.updates.append(t)
        assert self._user_cb is not None
        want = bool(self._user_cb(t, bool(can_return)))
        early_req[0] = want
        early_time[0] = t

    def _set(self, name: str, value: float | int | bool) -> None:
        v = self._vars[name]
        vr = [v.valueReference]
        if v.type == "Float64":
            self._call(f"setting {name}", self.slave.setFloat64, vr, [float(value)])
        elif v.type == "Int32":
            self._call(f"setting {name}", self.slave.setInt32, vr, [int(value)])
        elif v.type == "Enumeration":
            self._call(f"setting {name}", self.slave.setInt64, vr, [int(value)])
        elif v.type == "Boolean":
            self._call(f"setting {name}", self.slave.setBoolean, vr, [bool(value)])
        else:
            raise ValueError(f"variable {name}: type {v.type} not handled")

    def get(self, names: Sequence[str]) -> dict[str, float]:
        out: dict[str, float] = {}
        for n in names:
            v = self._vars[n]
            vr = [v.valueReference]
            getter = {"Float64": self.slave.getFloat64, "Int32": self.slave.getInt32,
                      "Enumeration": self.slave.getInt64}.get(v.type, self.slave.getBoolean)
            out[n] = self._call(f"getting {n}", getter, vr)[0]
        return out

    def set_inputs(self, values: Mapping[str, float]) -> None:
        for name, value in values.items():
            self._set(name, value)

    def do_step(self, dt: float) -> tuple[bool, bool]:
        """One fmi3DoStep from the FMU's time; returns (eventHandlingNeeded, earlyReturn)."""
        event, terminate, early, t_last = self._call("fmi3DoStep", self.slave.doStep, self.time, dt)
        self.time = t_last  # tc + dt, or the switch it returned early at
        return bool(event), bool(early)

    def handle_event(self, mode_before: int) -> Switch:
        """Event mode at the current time: the left limits, fmi3UpdateDiscreteStates, the right limits."""
        left = self.get(["mode", "F_friction", "a"])
        self._call("fmi3EnterEventMode", self.slave.enterEventMode)
        need, terminate, _, _, _, _ = self._call("fmi3UpdateDiscreteStates", self.slave.updateDiscreteStates)
        if need or terminate:
            raise RuntimeError("fmi3UpdateDiscreteStates asked for another iteration or to terminate")
        right = self.get(["mode", "F_friction", "a"])
        self._call("fmi3EnterStepMode", self.slave.enterStepMode)
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

    def close(self) -> None:
        try:
            self.slave.terminate()
        except Exception:  # terminate is not allowed after an error: free anyway
            pass
        self.slave.freeInstance()
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> "FMI3Oscillator":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
