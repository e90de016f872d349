"""Dry-friction oscillator and chain: FMI 2.0 and FMI 3.0 co-simulation FMU tooling, analytical
references and sweeps.

The names below are imported on first use, so that ``import dryfriction`` itself is immediate
(the console script installs its signal handlers before anything heavy is loaded)."""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

from . import _compat

_compat.install()   # the former module paths (dryfriction.fmu, ...): deprecated aliases

__all__ = ["Oscillator", "DryFrictionWarning", "FMUError", "FMUCallError", "FMUFileError"]
__version__ = "0.2.0"

#: public name -> the module that defines it
_EXPORTS = {"Oscillator": ".params", "DryFrictionWarning": ".diagnostics", "FMUError": ".errors",
            "FMUCallError": ".errors", "FMUFileError": ".errors"}

if TYPE_CHECKING:
    from .diagnostics import DryFrictionWarning
    from .errors import FMUCallError, FMUError, FMUFileError
    from .params import Oscillator


def __getattr__(name: str) -> Any:
    """``dryfriction.Oscillator`` & co.: imported from their module on first use."""
    if name in _EXPORTS:
        value = getattr(import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
