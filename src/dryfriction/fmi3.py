"""The former home of the FMI 3.0 oscillator driver, kept as a thin re-export: the FMI 3.0 layer is
:mod:`dryfriction.fmi.fmi3`, the driver :class:`dryfriction.fmu3.OscillatorFMU3` (``FMI3Oscillator``
is the same class), the FMU's path :func:`dryfriction.paths.fmu_path` (``default_fmi3_path``)."""

from __future__ import annotations

from .errors import FMUCallError, FMUError
from .fmi.fmi3 import (DTYPES, STATUS_NAMES, DiscreteStates, Instance, IntermediateUpdate, State, StepResult,
                       library_path, status_name)
from .fmu3 import FMI3Oscillator, Intermediate, OscillatorFMU3, Run, Switch, default_fmi3_path

__all__ = ["FMI3Oscillator", "OscillatorFMU3", "Run", "Switch", "Intermediate", "default_fmi3_path", "FMUError",
           "FMUCallError", "Instance", "State", "StepResult", "DiscreteStates", "IntermediateUpdate", "library_path",
           "status_name", "STATUS_NAMES", "DTYPES"]
