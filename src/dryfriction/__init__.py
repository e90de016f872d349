"""Dry-friction oscillator and chain: FMI 2.0 and FMI 3.0 co-simulation FMU tooling, analytical
references and sweeps.

The public names below are importable from here and from their home module; each is imported on
first use, so that ``import dryfriction`` itself is immediate (the console script installs its
signal handlers before anything heavy is loaded). The deprecated module paths and names
of the previous release (listed in the changelog and in :mod:`dryfriction._compat`) still work for
one release, with a DeprecationWarning naming the new home."""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

from . import _compat

_compat.install()

__version__ = "0.2.0"

#: public name -> the module that defines it
_EXPORTS = {
    "Oscillator": ".params",
    "frequency_response": ".analysis.response",
    "steady_state": ".analysis.response",
    "find_orbits": ".analysis.orbits",
    "Orbit": ".analysis.orbits",
    "continue_orbits": ".analysis.continuation",
    "Branch": ".analysis.continuation",
    "solve_exact": ".references.exact",
    "OscillatorFMU2": ".drivers.oscillator",
    "Settings": ".drivers.oscillator",
    "OscillatorFMU3": ".drivers.oscillator3",
    "ChainFMU2": ".drivers.chain",
    "ChainFMU3": ".drivers.chain",
    "open_chain": ".drivers.chain",
    "SystemFMU3": ".drivers.system",
    "System": ".system",
    "Contact": ".system",
    "FMUError": ".errors",
    "FMUCallError": ".errors",
    "FMUFileError": ".errors",
    "UsageError": ".errors",
    "DryFrictionWarning": ".diagnostics",
}
__all__ = list(_EXPORTS)

if TYPE_CHECKING:
    from .analysis.continuation import Branch, continue_orbits
    from .analysis.orbits import Orbit, find_orbits
    from .analysis.response import frequency_response, steady_state
    from .system import Contact, System
    from .diagnostics import DryFrictionWarning
    from .drivers.chain import ChainFMU2, ChainFMU3, open_chain
    from .drivers.oscillator import OscillatorFMU2, Settings
    from .drivers.oscillator3 import OscillatorFMU3
    from .drivers.system import SystemFMU3
    from .errors import FMUCallError, FMUError, FMUFileError, UsageError
    from .params import Oscillator
    from .references.exact import solve_exact


def __getattr__(name: str) -> Any:
    """``dryfriction.Oscillator`` & co.: imported from their module on first use."""
    if name in _EXPORTS:
        value = getattr(import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
