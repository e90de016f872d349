"""Shared by the FMI 3.0 tests: the FMI 2.0 FMU driven directly through fmpy (the reference for
bit identity and for the switch times its event log reports), the schemes of the model
description's Scheme enumeration, and parameter sets."""

from __future__ import annotations

import math
import re
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)

from dryfriction.drivers.oscillator3 import default_fmi3_path
from dryfriction.model import default_fmu_path


ROOT = Path(__file__).resolve().parents[1]
# the FMUs dryfriction.paths finds: DFO_FMU / DFO_FMU3 select other builds (the ASan/UBSan one)
FMU2 = default_fmu_path()
FMU3 = default_fmi3_path()
SWITCH_LOG = re.compile(r"t = ([-+0-9.eE]+): (backward slip|stick|forward slip) -> (backward slip|stick|forward slip)")
MODE_OF = {"backward slip": -1, "stick": 0, "forward slip": 1}
DT = 0.1  # the coarse master's communication step (the FMI 3.0 event and API tests)


def schemes() -> list[int]:
    """Every value of the Scheme enumeration of the model description (a scheme added there is
    covered without touching the tests)."""
    md = read_model_description(str(FMU3))
    scheme_type = next(t for t in md.typeDefinitions if t.name == "Scheme")
    return [int(item.value) for item in scheme_type.items]


def scheme_names() -> dict[int, str]:
    md = read_model_description(str(FMU3))
    scheme_type = next(t for t in md.typeDefinitions if t.name == "Scheme")
    return {int(item.value): item.name for item in scheme_type.items}


class FMI2Run:
    """The FMI 2.0 FMU with the given parameters, stepped by the caller (logEvents recorded)."""

    def __init__(self, params: Mapping[str, float | int | bool], log_events: bool = False) -> None:
        self.md = read_model_description(str(FMU2))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.dir = extract(str(FMU2), tempfile.mkdtemp(prefix="dfo_fmi2_"))
        self.switches: list[tuple[float, int, int]] = []
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="ref")
        # Own callbacks, never fmpy's defaults: those go through fmpy's one process-wide logger proxy,
        # which simulate_fmu(logger=...) repoints to a callback freed when it returns (a later
        # message from this FMU would then jump to freed memory).
        self.messages: list[str] = []
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.slave.instantiate(loggingOn=log_events, callbacks=self._callbacks)
        if log_events:
            self.slave.setDebugLogging(True, ["logEvents"])
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        for name, value in params.items():
            v = self.vars[name]
            if v.type == "Real":
                self.slave.setReal([v.valueReference], [float(value)])
            elif v.type in ("Integer", "Enumeration"):
                self.slave.setInteger([v.valueReference], [int(value)])
            else:
                self.slave.setBoolean([v.valueReference], [bool(value)])
        self.slave.exitInitializationMode()

    def _log(self, env, name, status, category, message) -> None:  # noqa: ANN001 - a ctypes callback
        text = message.decode(errors="replace")
        self.messages.append(text)
        g = SWITCH_LOG.search(text)
        if g:
            self.switches.append((float(g.group(1)), MODE_OF[g.group(2)], MODE_OF[g.group(3)]))

    def get(self, names: Sequence[str]) -> list[float]:
        out = []
        for n in names:
            v = self.vars[n]
            if v.type == "Real":
                out.append(self.slave.getReal([v.valueReference])[0])
            elif v.type in ("Integer", "Enumeration"):
                out.append(self.slave.getInteger([v.valueReference])[0])
            else:
                out.append(self.slave.getBoolean([v.valueReference])[0])
        return out

    def close(self) -> None:
        self.slave.terminate()
        self.slave.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


def fmi2_switches(params: Mapping[str, float | int | bool], t_stop: float, dt: float) -> list[tuple[float, int, int]]:
    """The switches (time, mode before, mode after) the FMI 2.0 FMU's event log reports over a run
    on the grid k dt (the communication points fmpy's simulate_fmu would use)."""
    run = FMI2Run(params, log_events=True)
    try:
        t, k = 0.0, 0
        while not (t > t_stop or math.isclose(t, t_stop)):
            t_next = min((k + 1) * dt, t_stop)
            run.slave.doStep(t, t_next - t)
            t, k = t_next, k + 1
        return list(run.switches)
    finally:
        run.close()


def kinds(switches: Sequence[tuple[int, int]]) -> list[str]:
    return ["breakaway" if a == 0 else "stop" if b == 0 else "reversal" for a, b in switches]


def as_array(x: Sequence[float]) -> np.ndarray:
    return np.asarray(x, dtype=float)


def assert_fmi3_equals_fmi2_on_belt(params: Mapping[str, float | int | bool], outputs: Sequence[str]) -> None:
    """FMI 3.0 gives FMI 2.0's bits over 15 communication steps of uneven length, with v_belt
    changed from params' value to 0.1 before step 3 and to -0.2 before step 8."""
    from dryfriction.drivers.oscillator3 import OscillatorFMU3

    ref, fmu = FMI2Run(params), OscillatorFMU3(params)
    try:
        t = 0.0
        for i, dt in enumerate([0.37, 1.1, 0.05, 2.3, 0.6] * 3):
            if i in (3, 8):
                vb = 0.1 if i == 3 else -0.2
                ref.slave.setReal([ref.vars["v_belt"].valueReference], [vb])
                fmu.set_inputs({"v_belt": vb})
            ref.slave.doStep(t, dt)
            fmu.do_step(dt)
            t += dt
            a, b = ref.get(list(outputs)), list(fmu.get(list(outputs)).values())
            assert np.array_equal(np.asarray(a, float).view(np.int64), np.asarray(b, float).view(np.int64)), (i, a, b)
    finally:
        ref.close()
        fmu.close()
