"""The package's layout: the layers and the import circles read from the source of every module
(its imports at any depth, those inside functions too), the former module paths and names as
deprecated aliases of the very same objects, the canonical public names at the top level, and
``import dryfriction`` that imports nothing heavy.

The tables here are written out independently of :mod:`dryfriction._compat` (the one table the
package serves the former paths from): a path or a name missing there fails here.
"""

from __future__ import annotations

import ast
import importlib
import json
import re
import subprocess
import sys
import warnings
from pathlib import Path
from types import ModuleType

import pytest

import dryfriction

PACKAGE = Path(dryfriction.__file__).resolve().parent
ROOT = Path(__file__).resolve().parents[1]

#: the layers, bottom to top: a module imports only from its own layer or below. ``params`` is in
#: the layer of ``model``: an oscillator's defaults and units are read from the model description;
#: ``system`` (a structure with friction contacts) beside them: it makes systems of oscillators.
LAYERS: dict[int, tuple[str, ...]] = {
    0: ("errors", "diagnostics", "atomic", "paths", "roots", "budget", "cluster", "_compat"),
    1: ("model", "params", "fmi", "system"),
    2: ("drivers",),
    3: ("references",),
    4: ("analysis", "cosim", "sweep"),
    5: ("studies",),
    6: ("cli", "__main__"),
}
_LAYER = {top: n for n, tops in LAYERS.items() for top in tops}

#: the former modules by their new package: former name (under dryfriction.) -> name in the package
_MOVES = {
    "drivers": {"driver": "base", "fmu": "oscillator", "fmu3": "oscillator3", "chain": "chain", "scenes": "scenes"},
    "references": {"exact": "exact", "steady": "steady", "belt_reference": "belt", "chain_reference": "chain"},
    "analysis": {name: name for name in ("orbits", "continuation", "self_excited", "response", "validation", "report",
                                         "slip_events", "chaos", "chaos.attractors", "chaos.batch", "chaos.lyapunov",
                                         "chaos.maps")},
    "cli": {"chaos.cli": "lyapunov", "argparsing": "options", "console": "console", "belt_cli": "belt",
            "chain_cli": "chain", "continuation_cli": "continuation", "orbit_cli": "orbit"},
    "fmi": {"fmi2": "fmi2", "fmi3": "fmi3"},
}
#: former module path -> its home now
FORMER_PATHS = {"dryfriction.locate": "dryfriction.paths",
                **{f"dryfriction.{old}": f"dryfriction.{package}.{new}"
                   for package, moves in _MOVES.items() for old, new in moves.items()}}

#: (former module path, former name) -> (home, name) of the same object, read with a warning
FORMER_NAMES = {
    ("dryfriction.fmu", "OscillatorFMU"): ("dryfriction.drivers.oscillator", "OscillatorFMU2"),
    ("dryfriction.fmu", "OscillatorFMU3"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.fmu", "FMI3Oscillator"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.fmu3", "FMI3Oscillator"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.fmi3", "FMI3Oscillator"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.fmi3", "OscillatorFMU3"): ("dryfriction.drivers.oscillator3", "OscillatorFMU3"),
    ("dryfriction.fmi3", "Run"): ("dryfriction.drivers.oscillator3", "Run"),
    ("dryfriction.fmi3", "Switch"): ("dryfriction.drivers.oscillator3", "Switch"),
    ("dryfriction.fmi3", "Intermediate"): ("dryfriction.drivers.oscillator3", "Intermediate"),
    ("dryfriction.fmi3", "default_fmi3_path"): ("dryfriction.drivers.oscillator3", "default_fmi3_path"),
    ("dryfriction.chain", "ChainFMU"): ("dryfriction.drivers.chain", "ChainFMU3"),
    ("dryfriction.chain", "ChainError"): ("dryfriction.errors", "FMUCallError"),
    ("dryfriction.chain", "ChainWarning"): ("dryfriction.diagnostics", "DryFrictionWarning"),
    ("dryfriction.errors", "ChainError"): ("dryfriction.errors", "FMUCallError"),
    ("dryfriction.budget", "add_max_work_argument"): ("dryfriction.cli.options", "add_max_work_argument"),
    ("dryfriction.budget", "command_work"): ("dryfriction.cli", "command_work"),
    ("dryfriction.cli", "RUN_UNITS"): ("dryfriction.cli.run", "RUN_UNITS"),
    ("dryfriction.cli", "PHYSICAL"): ("dryfriction.cli.options", "PHYSICAL"),
    ("dryfriction.chain_cli", "chain_main"): ("dryfriction.cli.chain", "run"),
    ("dryfriction.studies", "main"): ("dryfriction.cli.study", "main"),
    ("dryfriction.studies", "run_args"): ("dryfriction.cli.study", "run"),
    ("dryfriction.continuation_cli", "plot_branches"): ("dryfriction.analysis.plots", "plot_branches"),
}

#: (former module path, name, the name's home): a name a former module re-exported that its new
#: home has too (the module's warning only)
FORMER_REEXPORTS = [
    ("dryfriction.fmi3", "FMUError", "dryfriction.errors"),
    ("dryfriction.fmi3", "FMUCallError", "dryfriction.errors"),
    ("dryfriction.fmi3", "Instance", "dryfriction.fmi.fmi3"),
    ("dryfriction.fmi2", "FMUError", "dryfriction.errors"),
    ("dryfriction.fmi2", "Instance", "dryfriction.fmi.fmi2"),
    ("dryfriction.locate", "FMUFileError", "dryfriction.errors"),
    ("dryfriction.argparsing", "UsageError", "dryfriction.errors"),
    ("dryfriction.fmu", "FMUError", "dryfriction.errors"),
    ("dryfriction.console", "result_set", "dryfriction.atomic"),
]

#: the canonical public names: importable from the top level and from their home
CANONICAL = {
    "Oscillator": "dryfriction.params",
    "frequency_response": "dryfriction.analysis.response",
    "steady_state": "dryfriction.analysis.response",
    "find_orbits": "dryfriction.analysis.orbits",
    "Orbit": "dryfriction.analysis.orbits",
    "continue_orbits": "dryfriction.analysis.continuation",
    "Branch": "dryfriction.analysis.continuation",
    "solve_exact": "dryfriction.references.exact",
    "OscillatorFMU2": "dryfriction.drivers.oscillator",
    "OscillatorFMU3": "dryfriction.drivers.oscillator3",
    "ChainFMU2": "dryfriction.drivers.chain",
    "ChainFMU3": "dryfriction.drivers.chain",
    "open_chain": "dryfriction.drivers.chain",
    "SystemFMU3": "dryfriction.drivers.system",
    "Settings": "dryfriction.drivers.oscillator",
    "System": "dryfriction.system",
    "Contact": "dryfriction.system",
    "FMUError": "dryfriction.errors",
    "FMUCallError": "dryfriction.errors",
    "FMUFileError": "dryfriction.errors",
    "UsageError": "dryfriction.errors",
    "DryFrictionWarning": "dryfriction.diagnostics",
}

#: the former class names, as words (none of them left in the code outside the deprecation table)
FORMER_WORDS = ("OscillatorFMU", "FMI3Oscillator", "ChainFMU", "ChainError", "ChainWarning")


# ---- the imports, read from the source -------------------------------------------------------------

def _modules() -> dict[str, Path]:
    """Every module of the package: dotted name -> file."""
    out = {}
    for f in sorted(PACKAGE.rglob("*.py")):
        parts = list(f.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = f
    return out


MODULES = _modules()


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or \
        (isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def imports_of(name: str) -> list[tuple[str, int, bool]]:
    """(imported module, line, executed when the module is imported) for every import statement of
    module ``name`` that names a module of the package; ``from X import y`` names ``X.y`` when that
    is a module, else ``X``. Imports inside functions are not executed at import time, nor those
    under ``if TYPE_CHECKING``."""
    file = MODULES[name]
    here = name.split(".") if file.name == "__init__.py" else name.split(".")[:-1]
    found: list[tuple[str, int, bool]] = []

    def visit(node: ast.AST, eager: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                visit(child, False)
                continue
            if isinstance(child, ast.If) and _is_type_checking(child):
                for sub in child.body:
                    visit(ast.Module(body=[sub], type_ignores=[]), False)
                for sub in child.orelse:
                    visit(ast.Module(body=[sub], type_ignores=[]), eager)
                continue
            if isinstance(child, ast.Import):
                found.extend((a.name, child.lineno, eager) for a in child.names
                             if a.name.split(".")[0] == "dryfriction")
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base_parts = here[:len(here) - (child.level - 1)]
                    base = ".".join(base_parts + ([child.module] if child.module else []))
                else:
                    base = child.module or ""
                if base.split(".")[0] != "dryfriction":
                    continue
                for a in child.names:
                    sub = f"{base}.{a.name}"
                    found.append((sub if sub in MODULES else base, child.lineno, eager))
            visit(child, eager)

    visit(ast.parse(file.read_text(), str(file)), True)
    return found


def layer(name: str) -> int | None:
    """The layer of a module (None: the package's top, ``dryfriction`` itself); a program's
    ``__main__`` (``python -m dryfriction.studies``) is at the top, with the command line."""
    parts = name.split(".")
    if len(parts) > 2 and parts[-1] == "__main__":
        return _LAYER["__main__"]
    return None if len(parts) == 1 else _LAYER.get(parts[1])


def test_the_reader_sees_imports_in_functions_and_relative_ones() -> None:
    """The reader itself, on modules whose imports are known: a relative import two levels up, one
    inside a function, one under TYPE_CHECKING."""
    found = imports_of("dryfriction.cli.study")
    assert any(m == "dryfriction.studies" and e for m, _, e in found)               # from ..studies import ...
    assert any(m == "dryfriction.sweep.engine" and not e for m, _, e in found)        # inside a function
    top = imports_of("dryfriction")
    assert ("dryfriction._compat", True) in [(m, e) for m, _, e in top]
    assert any(m == "dryfriction.analysis.response" and not e for m, _, e in top)   # TYPE_CHECKING


def test_every_module_has_a_layer() -> None:
    unknown = sorted(m for m in MODULES if m != "dryfriction" and layer(m) is None)
    assert unknown == [], f"modules in no layer of LAYERS (tests/test_layout.py): {unknown}"


def test_every_import_names_a_module_that_exists() -> None:
    """No module imports a former path (they are deprecation aliases for other code only)."""
    bad = [(m, t, ln) for m in MODULES for t, ln, _ in imports_of(m) if t not in MODULES]
    assert bad == []


#: modules that still import from a layer above (module -> why); their test is expected to fail
_PENDING: dict[str, str] = {}


@pytest.mark.parametrize("name", [pytest.param(m, marks=pytest.mark.xfail(reason=_PENDING[m], strict=True))
                                  if m in _PENDING else m
                                  for m in sorted(MODULES) if m != "dryfriction"])
def test_no_import_from_a_higher_layer(name: str) -> None:
    """Every import of the module (at any depth) is of its own layer or one below."""
    own = layer(name)
    assert own is not None
    above = sorted({(t, ln) for t, ln, _ in imports_of(name) if (layer(t) or 0) > own})
    assert above == [], f"{name} (layer {own}) imports from above: " + \
        ", ".join(f"{t} (layer {layer(t)}, line {ln})" for t, ln in above)


def find_circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (or a module importing itself)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in edges.get(v, ()):
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            strong(v)
    return out


def test_the_circle_finder_finds_a_circle() -> None:
    assert find_circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert find_circles({"a": {"b"}, "b": set(), "c": {"c"}}) == [["c"]]


def test_no_import_circle() -> None:
    """No circle among the imports a module runs when it is imported (module level)."""
    edges = {m: {t for t, _, eager in imports_of(m) if eager and t != m} for m in MODULES}
    assert find_circles(edges) == []


# ---- the former paths and names -----------------------------------------------------------------------

@pytest.mark.parametrize("old", sorted(FORMER_PATHS))
def test_a_former_path_is_its_new_module_with_a_warning(old: str, monkeypatch: pytest.MonkeyPatch) -> None:
    new = importlib.import_module(FORMER_PATHS[old])
    monkeypatch.delitem(sys.modules, old, raising=False)
    with pytest.warns(DeprecationWarning, match=re.escape(f"{old} is deprecated; use {FORMER_PATHS[old]}")):
        module = importlib.import_module(old)
    assert module is new
    assert module.__name__ == module.__spec__.name == FORMER_PATHS[old]   # the module is not renamed
    assert not (PACKAGE.parent / (old.replace(".", "/") + ".py")).exists()  # no file at the old path


def test_a_former_package_serves_its_former_submodules(monkeypatch: pytest.MonkeyPatch) -> None:
    """``import dryfriction.chaos.maps`` from scratch: both warn, both are the new modules."""
    for name in ("dryfriction.chaos", "dryfriction.chaos.maps"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        import dryfriction.chaos.maps as maps  # noqa: F401
    import dryfriction.analysis.chaos.maps as new_maps

    assert maps is new_maps
    assert [str(w.message) for w in rec if w.category is DeprecationWarning] == [
        "dryfriction.chaos is deprecated; use dryfriction.analysis.chaos",
        "dryfriction.chaos.maps is deprecated; use dryfriction.analysis.chaos.maps"]
    assert rec[0].filename == __file__                    # attributed to the import statement


@pytest.mark.parametrize("key", sorted(FORMER_NAMES))
def test_a_former_name_is_the_same_object_with_a_warning(key: tuple[str, str]) -> None:
    old_module, name = key
    home, new_name = FORMER_NAMES[key]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        module = importlib.import_module(old_module)
    expected = getattr(importlib.import_module(home), new_name)
    with pytest.warns(DeprecationWarning, match=re.escape(f"is deprecated; use {home}.{new_name}")) as rec:
        value = getattr(module, name)
    assert value is expected
    assert any(w.filename == __file__ for w in rec)


@pytest.mark.parametrize("old_module,name,home", FORMER_REEXPORTS)
def test_a_former_reexport_is_the_same_object(old_module: str, name: str, home: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        module = importlib.import_module(old_module)
    assert getattr(module, name) is getattr(importlib.import_module(home), name)


def test_the_former_import_statements_work() -> None:
    """The statements of the former README and examples, as written there."""
    ns: dict[str, object] = {}
    with pytest.warns(DeprecationWarning):
        exec("from dryfriction.fmu import OscillatorFMU, Settings\n"
             "from dryfriction.chain import ChainFMU\n"
             "from dryfriction.response import frequency_response\n"
             "from dryfriction.fmu3 import OscillatorFMU3\n"
             "from dryfriction import locate, fmi2\n", ns)
    from dryfriction import ChainFMU3, OscillatorFMU2, OscillatorFMU3, Settings, frequency_response, paths
    from dryfriction.fmi import fmi2

    assert ns["OscillatorFMU"] is OscillatorFMU2 and ns["Settings"] is Settings and ns["ChainFMU"] is ChainFMU3
    assert ns["frequency_response"] is frequency_response and ns["OscillatorFMU3"] is OscillatorFMU3
    assert ns["locate"] is paths and ns["fmi2"] is fmi2


def test_an_unknown_name_is_still_an_attribute_error() -> None:
    import dryfriction.drivers.oscillator as oscillator

    with pytest.raises(AttributeError, match="OscillatorFMU4"):
        oscillator.OscillatorFMU4  # noqa: B018
    with pytest.raises(ImportError):
        importlib.import_module("dryfriction.no_such_module")


def test_the_command_line_package_keeps_main_the_function() -> None:
    """``dryfriction.cli.main`` is the console script's function (the dispatcher), also once every
    command's module is imported."""
    import dryfriction.cli
    from dryfriction.cli import COMMANDS, build_parser, main

    build_parser()                        # imports every command's module
    assert callable(main) and not isinstance(main, ModuleType) and dryfriction.cli.main is main
    assert all(isinstance(sys.modules[f"dryfriction.cli.{m}"], ModuleType) for m in COMMANDS.values())


# ---- the canonical names --------------------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(CANONICAL))
def test_a_canonical_name_from_the_top_and_from_its_home(name: str) -> None:
    home = importlib.import_module(CANONICAL[name])
    assert getattr(dryfriction, name) is getattr(home, name)
    assert name in dir(dryfriction)


def test_the_top_level_exports_exactly_the_canonical_names() -> None:
    assert sorted(dryfriction.__all__) == sorted(CANONICAL)
    with pytest.raises(AttributeError):
        dryfriction.OscillatorFMU  # noqa: B018


def test_the_code_uses_the_canonical_names() -> None:
    """No former class name and no import of a former path in the package, the tests, the
    examples, the scripts and the benchmarks (outside the deprecation table and this file)."""
    skip = {PACKAGE / "_compat.py", Path(__file__).resolve()}
    words = re.compile(r"\b(" + "|".join(FORMER_WORDS) + r")\b")
    paths = re.compile(r"(?<![\w.])(" + "|".join(re.escape(p) for p in sorted(FORMER_PATHS, key=len, reverse=True))
                       + r")(?![\w])")
    found = []
    for folder in (PACKAGE, ROOT / "tests", ROOT / "examples", ROOT / "scripts", ROOT / "bench"):
        for f in sorted(folder.rglob("*.py")):
            if f.resolve() in skip:
                continue
            text = f.read_text()
            found += [f"{f.name}: {m.group(1)}" for m in words.finditer(text)]
            found += [f"{f.name}: {m.group(1)}" for m in paths.finditer(text)]
    assert found == []


# ---- import dryfriction stays light ---------------------------------------------------------------------

HEAVY = ("numpy", "scipy", "xarray", "matplotlib", "dask", "distributed", "fmpy", "h5py", "h5netcdf", "pandas")


def test_import_dryfriction_imports_nothing_heavy() -> None:
    """``import dryfriction`` loads the package and its deprecation table only; a canonical name
    then loads its module (and what that needs)."""
    code = ("import json, sys\nimport dryfriction\nbefore = sorted(sys.modules)\n"
            "dryfriction.Oscillator\nprint(json.dumps([before, sorted(sys.modules)]))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    before, after = json.loads(r.stdout)
    assert [m for m in before if m.split(".")[0] in HEAVY] == []
    assert [m for m in before if m.startswith("dryfriction")] == ["dryfriction", "dryfriction._compat"]
    assert "dryfriction.params" in after and "dryfriction.analysis" not in after


@pytest.mark.slow
def test_every_module_imports_without_a_deprecation_warning() -> None:
    """Every module of the package, imported fresh with DeprecationWarning an error: none of them
    uses a former path or name (a process of its own: nothing imported before)."""
    code = ("import importlib, json, pkgutil, warnings, dryfriction\n"
            "names = [m.name for m in pkgutil.walk_packages(dryfriction.__path__, 'dryfriction.')\n"
            "         if not m.name.endswith('__main__')]\n"
            "with warnings.catch_warnings(record=True) as rec:\n"
            "    warnings.simplefilter('always')\n"
            "    for n in names:\n        importlib.import_module(n)\n"
            "bad = [str(w.message) for w in rec if 'deprecated; use dryfriction' in str(w.message)]\n"
            "print(json.dumps([len(names), bad]))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    count, deprecated = json.loads(r.stdout)
    assert deprecated == []
    assert count == len([m for m in MODULES if m != "dryfriction" and not m.endswith("__main__")])
