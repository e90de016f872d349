"""Dry-friction oscillator and chain: FMI 2.0 and FMI 3.0 co-simulation FMU tooling, analytical
references and sweeps."""

from .diagnostics import DryFrictionWarning
from .errors import FMUCallError, FMUError, FMUFileError
from .params import Oscillator

__all__ = ["Oscillator", "DryFrictionWarning", "FMUError", "FMUCallError", "FMUFileError"]
__version__ = "0.2.0"
