"""Shared by the FMI 3.0 tests: the FMI 2.0 FMU driven directly through fmpy (the reference for
bit identity and for the switch times its event log reports), the schemes of the model
description's Scheme enumeration, and parameter sets."""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parents[1]
# DFO_FMU / DFO_FMU3 select other builds (the ASan/UBSan one)
FMU2 = Path(os.environ.get("DFO_FMU") or ROOT / "build" / "DryFrictionOscillator.fmu")
FMU3 = Path(os.environ.get("DFO_FMU3") or ROOT / "build" / "fmi3" / "DryFrictionOscillator.fmu")
SWITCH_LOG = re.compile(r"t = ([-+0-9.eE]+): (backward slip|stick|forward slip) -> (backward slip|stick|forward slip)")
MODE_OF = {"backward slip": -1, "stick": 0, "forward slip": 1}


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
        self.slave.instantiate(loggingOn=log_events, callbacks=None)
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
    on the grid k dt."""
    messages: list[str] = []
    from fmpy import simulate_fmu

    def logger(env, name, status, category, message):  # noqa: ANN001 - fmpy's ctypes callback
        messages.append(message.decode())

    simulate_fmu(str(FMU2), start_values=dict(params), stop_time=t_stop, output_interval=dt, debug_logging=True,
                 logger=logger, output=["x"])
    out = []
    for m in messages:
        g = SWITCH_LOG.search(m)
        if g:
            out.append((float(g.group(1)), MODE_OF[g.group(2)], MODE_OF[g.group(3)]))
    return out


def kinds(switches: Sequence[tuple[int, int]]) -> list[str]:
    return ["breakaway" if a == 0 else "stop" if b == 0 else "reversal" for a, b in switches]


def as_array(x: Sequence[float]) -> np.ndarray:
    return np.asarray(x, dtype=float)
