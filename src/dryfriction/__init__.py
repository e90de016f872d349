"""Dry-friction oscillator: FMI 2.0 co-simulation FMU tooling, analytical references and sweeps."""

from .diagnostics import DryFrictionWarning
from .params import Oscillator

__all__ = ["Oscillator", "DryFrictionWarning"]
__version__ = "0.2.0"
