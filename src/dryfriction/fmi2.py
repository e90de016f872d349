"""The former name of the FMI 2.0 layer, kept as a thin re-export of :mod:`dryfriction.fmi.fmi2`
(the same objects)."""

from __future__ import annotations

from .fmi.fmi2 import (CO_SIMULATION, DISCARD, DTYPES, ERROR, FATAL, LAST_SUCCESSFUL_TIME, OK, PENDING, STATUS_NAMES,
                       WARNING, CallbackFunctions, FMUCallError, FMUError, Instance, State, library_path, status_name)

__all__ = [
    "OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING", "STATUS_NAMES", "LAST_SUCCESSFUL_TIME",
    "FMUError", "FMUCallError", "Instance", "State", "library_path", "status_name", "CO_SIMULATION",
    "CallbackFunctions", "DTYPES",
]
