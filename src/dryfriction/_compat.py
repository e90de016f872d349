"""The package's former module paths and names, kept working for one release with a
:class:`DeprecationWarning` that names the new home.

``import dryfriction.fmu`` gives the very module object of ``dryfriction.drivers.oscillator`` (a
name patched or read through either is the one every module uses), ``dryfriction.fmu.OscillatorFMU``
the very class ``OscillatorFMU2``. This module holds the one table of both (:data:`MODULES`,
:data:`NAMES`) and the meta-path finder that serves them (:func:`install`, called by
``dryfriction/__init__.py``); there are no files at the old paths. It imports only the standard
library.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import sys
import warnings
from collections.abc import Sequence
from types import ModuleType
from typing import Any

__all__ = ["MODULES", "NAMES", "new_path", "install"]

#: former module path -> its home now (a former package maps its submodules too)
MODULES: dict[str, str] = {
    "dryfriction.driver": "dryfriction.drivers.base",
    "dryfriction.fmu": "dryfriction.drivers.oscillator",
    "dryfriction.fmu3": "dryfriction.drivers.oscillator3",
    "dryfriction.chain": "dryfriction.drivers.chain",
    "dryfriction.scenes": "dryfriction.drivers.scenes",
    "dryfriction.exact": "dryfriction.references.exact",
    "dryfriction.steady": "dryfriction.references.steady",
    "dryfriction.belt_reference": "dryfriction.references.belt",
    "dryfriction.chain_reference": "dryfriction.references.chain",
    "dryfriction.orbits": "dryfriction.analysis.orbits",
    "dryfriction.continuation": "dryfriction.analysis.continuation",
    "dryfriction.self_excited": "dryfriction.analysis.self_excited",
    "dryfriction.response": "dryfriction.analysis.response",
    "dryfriction.validation": "dryfriction.analysis.validation",
    "dryfriction.report": "dryfriction.analysis.report",
    "dryfriction.slip_events": "dryfriction.analysis.slip_events",
    "dryfriction.chaos.cli": "dryfriction.cli.lyapunov",
    "dryfriction.chaos": "dryfriction.analysis.chaos",
    "dryfriction.fmi2": "dryfriction.fmi.fmi2",
    "dryfriction.fmi3": "dryfriction.fmi.fmi3",
    "dryfriction.locate": "dryfriction.paths",
    "dryfriction.argparsing": "dryfriction.cli.options",
    "dryfriction.console": "dryfriction.cli.console",
    "dryfriction.belt_cli": "dryfriction.cli.belt",
    "dryfriction.chain_cli": "dryfriction.cli.chain",
    "dryfriction.continuation_cli": "dryfriction.cli.continuation",
    "dryfriction.orbit_cli": "dryfriction.cli.orbit",
}

#: (module now, former name) -> (home module, name): a former name read from the module it was in
#: (by its old path or its new one); ``*`` stands for every name the home module has
NAMES: dict[tuple[str, str], tuple[str, str]] = {
    ("dryfriction.drivers.oscillator", "OscillatorFMU"): ("dryfriction.drivers.oscillator", "OscillatorFMU2"),
    ("dryfriction.drivers.oscillator", "OscillatorFMU3"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.drivers.oscillator", "FMI3Oscillator"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.drivers.oscillator3", "FMI3Oscillator"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.drivers.chain", "ChainFMU"): ("dryfriction.drivers.chain", "ChainFMU3"),
    ("dryfriction.drivers.chain", "ChainError"): ("dryfriction.errors", "FMUCallError"),
    ("dryfriction.drivers.chain", "ChainWarning"): ("dryfriction.diagnostics", "DryFrictionWarning"),
    ("dryfriction.errors", "ChainError"): ("dryfriction.errors", "FMUCallError"),
    # what the former dryfriction.fmi3 re-exported besides the FMI 3.0 layer
    **{("dryfriction.fmi.fmi3", n): ("dryfriction.drivers.oscillator3", n)
       for n in ("OscillatorFMU3", "Run", "Switch", "Intermediate", "default_fmi3_path")},
    ("dryfriction.fmi.fmi3", "FMI3Oscillator"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.fmi.fmi3", "FMUError"): ("dryfriction.errors", "FMUError"),
    # the command line's parts of the work bound
    **{("dryfriction.budget", n): ("dryfriction.cli.options", n)
       for n in ("add_max_work_argument", "command_work", "check_command")},
    ("dryfriction.cli.continuation", "plot_branches"): ("dryfriction.analysis.plots", "plot_branches"),
    # the former module dryfriction.cli is the package's command-line module dryfriction.cli.main
    ("dryfriction.cli", "*"): ("dryfriction.cli.main", "*"),
}

_HOMES = {module for module, _ in NAMES}


def new_path(old: str) -> str | None:
    """The module path that replaced ``old`` (None: ``old`` is not a former path)."""
    for prefix in sorted(MODULES, key=len, reverse=True):
        if old == prefix or old.startswith(prefix + "."):
            return MODULES[prefix] + old[len(prefix):]
    return None


def _warn(old: str, new: str) -> None:
    """The DeprecationWarning, attributed to the line that imported or read the former name (the
    first frame outside importlib and this module)."""
    frame = sys._getframe(1)
    while frame.f_back is not None and (frame.f_globals.get("__name__", "").split(".")[0] == "importlib"
                                        or frame.f_globals.get("__name__") == __name__
                                        or frame.f_code.co_filename.startswith("<frozen importlib")):
        frame = frame.f_back
    warnings.warn_explicit(f"{old} is deprecated; use {new}", DeprecationWarning, frame.f_code.co_filename,
                           frame.f_lineno, module=frame.f_globals.get("__name__", "sys"),
                           registry=frame.f_globals.setdefault("__warningregistry__", {}))


def _former_name(module: ModuleType, name: str) -> Any:
    """A former name read from ``module``: warn, then the object at its home."""
    key = (module.__name__, name)
    if key not in NAMES:
        if ((module.__name__, "*") not in NAMES or name.startswith("__")
                or importlib.machinery.PathFinder.find_spec(f"{module.__name__}.{name}",
                                                            getattr(module, "__path__", None)) is not None):
            raise AttributeError(f"module {module.__name__!r} has no attribute {name!r}")
        home, _ = NAMES[(module.__name__, "*")]
        value = getattr(importlib.import_module(home), name)   # AttributeError when it has none
        _warn(f"{module.__name__}.{name}", f"{home}.{name}")
        return value
    home, new = NAMES[key]
    _warn(f"{module.__name__}.{name}", f"{home}.{new}")
    return getattr(importlib.import_module(home), new)


def _install_getattr(module: ModuleType) -> None:
    """``module.<former name>``: through the module's ``__getattr__`` (its own first, if it has one)."""
    own = module.__dict__.get("__getattr__")

    def __getattr__(name: str) -> Any:
        if own is not None:
            try:
                return own(name)
            except AttributeError:
                pass
        return _former_name(module, name)

    module.__getattr__ = __getattr__  # type: ignore[method-assign]


class _Alias:
    """Loads a former path as the very module object of its new home."""

    def __init__(self, new: str) -> None:
        self.new = new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        _warn(spec.name, self.new)
        module = importlib.import_module(self.new)
        self._spec = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = self._spec       # importlib set the alias's spec on the shared module


class _Home:
    """Runs a module that has former names with its usual loader, then gives it the names."""

    def __init__(self, inner: Any) -> None:
        self.inner = inner

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        return self.inner.create_module(spec)

    def exec_module(self, module: ModuleType) -> None:
        self.inner.exec_module(module)
        _install_getattr(module)

    def __getattr__(self, name: str) -> Any:        # get_source, get_resource_reader, ...
        return getattr(self.inner, name)


class Finder:
    """The meta-path finder of the former paths (first on ``sys.meta_path``; a finder and loaders
    by protocol, without importlib.abc, which would import importlib.resources at start)."""

    def find_spec(self, fullname: str, path: Sequence[str] | None = None,
                  target: ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        if not fullname.startswith("dryfriction."):
            return None
        new = new_path(fullname)
        if new is not None:
            return importlib.machinery.ModuleSpec(fullname, _Alias(new))
        if fullname in _HOMES:
            spec = importlib.machinery.PathFinder.find_spec(fullname, path, target)
            if spec is not None and spec.loader is not None:
                spec.loader = _Home(spec.loader)
            return spec
        return None


def install() -> None:
    """Put the finder first on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, Finder())
