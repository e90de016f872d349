"""The FMUs' model descriptions, read once: the Python side's single source of truth.

One reader for every description of the package, both models and both FMI versions: the
oscillator's and the chain's FMI 2.0 descriptions (the chain's with structured names ``m[1]`` ...
``m[n]``), their FMI 3.0 descriptions (typed elements ``<Float64>``, arrays with ``<Dimension>``
bound to the structural parameter ``n``, ``<Annotations>``) and the chain's source description
(``dimension="n"``). Arrays may have several dimensions, each a structural parameter (FMI 3.0:
one ``<Dimension>`` each, the rows first; the source's ``dimension="nc n"``; FMI 2.0: the
structured names ``W[i,j]``, whose value references follow the build's layout, written into the
description's ``<Tool name="dryfriction.layout">`` and checked here against the elements).
Variables (name, value reference, type, causality, start, min, max, unit, the
structural parameters that size an array), the scheme names of the ``Scheme`` enumeration and the
effect bits of the vendor annotation (``<Tool name="dryfriction"><Effects>``, FMI 3.0:
``<Annotation type="dryfriction">``; parsed by :func:`parse_effects`, the one parser of that table)
come from ``modelDescription.xml``: the FMU's own (:func:`from_fmu`) or the repository's
(:func:`repository`). Nothing in the package keeps a copy of them, and nothing reads them at
import time (:func:`default` reads on first use). This module imports nothing of the package at
import time, so that a build script can load it by its path.

:meth:`ModelDescription.check` validates a Python value against a variable's declared range with
the sentence the FMU logs for the same value.
"""

from __future__ import annotations

import functools
import itertools
import math
import os
import re
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

__all__ = ["Variable", "Effect", "ArrayLayout", "fmi2_layout", "UINT32_MAX",
           "ModelDescription", "parse", "parse_effects", "from_xml", "from_fmu",
           "repository", "default", "default_fmu_path", "LazyMapping", "LazySequence"]

#: FMI 2.0: the C call family that reads/writes a variable of each declared type
CALL_TYPE = {"Real": "Real", "Integer": "Integer", "Enumeration": "Integer", "Boolean": "Boolean", "UInt64": "UInt64"}
#: FMI 3.0: the same (an enumeration is read and written as Int64)
CALL_TYPE3 = {"Float64": "Float64", "Float32": "Float32", "Int32": "Int32", "Int64": "Int64", "UInt64": "UInt64",
              "Int8": "Int8", "UInt8": "UInt8", "Int16": "Int16", "UInt16": "UInt16", "UInt32": "UInt32",
              "Enumeration": "Int64", "Boolean": "Boolean"}
#: the declared types holding real numbers and whole numbers (both FMI versions)
REAL_TYPES = ("Real", "Float64", "Float32")
INTEGER_TYPES = ("Integer", "Int32", "Int64", "UInt64", "Int8", "UInt8", "Int16", "UInt16", "UInt32")
_INDEXED = re.compile(r"^(\w+)\[(\d+(?:,\d+)*)\]$")
#: the vendor annotation of an FMI 2.0 description's array layout
LAYOUT_TOOL = "dryfriction.layout"


@dataclass(frozen=True)
class Variable:
    """One variable of a model description: name, value reference, causality, variability, type, unit, start
    value, valid range and, for an array, its dimension."""
    name: str
    vr: int
    type: str                    # Real, Integer, Enumeration, Boolean
    causality: str
    variability: str
    start: float | int | bool | None
    min: float | int | None
    max: float | int | None
    unit: str | None
    description: str
    declared_type: str | None = None
    zero: str | None = None          # what 0 means when the range is "0 or a normal number" (h)
    #: an array: the structural parameters that size it, space-separated, the rows first (FMI 3.0
    #: ``<Dimension>`` elements, the source's ``dimension="n"`` or ``dimension="nc n"``); None for a
    #: scalar (an FMI 2.0 element ``m[1]`` or ``W[1,2]`` is a scalar)
    dimension: str | None = None
    fmi_version: str = "2.0"

    @property
    def dimensions(self) -> tuple[str, ...]:
        """The structural parameters of an array's dimensions, the rows first; () for a scalar."""
        return tuple(self.dimension.split()) if self.dimension else ()

    @property
    def call_type(self) -> str:
        """The fmi2Get/Set (Real, Integer, Boolean) or fmi3Get/Set (Float64, Int32, Int64 for an
        enumeration, UInt64, Boolean) function family of the variable."""
        return (CALL_TYPE3 if self.fmi_version.startswith("3") else CALL_TYPE)[self.type]

    @property
    def is_real(self) -> bool:
        """Whether the variable is a real number (FMI 2.0 ``Real``, FMI 3.0 ``Float64``)."""
        return self.type in REAL_TYPES


@dataclass(frozen=True)
class Effect:
    """One bit of the ``effects`` calculated parameter: its value and what it means."""
    bit: int
    name: str
    description: str


@dataclass(frozen=True)
class ArrayLayout:
    """Where an FMI 2.0 build puts an array's elements: element (i, j) (1-based; i alone for a
    vector) at value reference ``first + (i - 1) cols + (j - 1)``, row-major."""

    name: str
    vr: int                          # the array's own value reference (FMI 3.0's)
    first: int                       # the value reference of its first element
    shape: tuple[int, ...]

    @property
    def count(self) -> int:
        """The number of elements."""
        return math.prod(self.shape)

    def element_vr(self, *index: int) -> int:
        """The value reference of element ``index`` (1-based, one index per dimension)."""
        if len(index) != len(self.shape) or not all(1 <= i <= n for i, n in zip(index, self.shape)):
            raise IndexError(f"{self.name}{list(index)}: outside its shape {self.shape}")
        k = 0
        for i, n in zip(index, self.shape):
            k = k * n + (i - 1)
        return self.first + k

    def elements(self) -> list[tuple[tuple[int, ...], int]]:
        """(index, value reference) of every element, row-major (indices 1-based)."""
        return [(idx, self.first + k)
                for k, idx in enumerate(itertools.product(*(range(1, s + 1) for s in self.shape)))]


#: the largest value reference (32 bits)
UINT32_MAX = 2**32 - 1


def fmi2_layout(arrays: Iterable[tuple[str, int, tuple[str, ...]]], sizes: Mapping[str, int],
                scalars: Iterable[tuple[str, int]] = ()) -> tuple[ArrayLayout, ...]:
    """The FMI 2.0 value references of the array elements for structural parameters ``sizes``
    (``{"n": 7, "nc": 3}``), the one layout of the generator (fmu_src/gen_model_vars.py, the
    builds' descriptions and DFO_FMI2_ARRAYS) and of a structure's FMI 2.0 FMU written for any
    sizes (dryfriction.system.fmu, resources/structure.bin). ``arrays``: (name, its own value
    reference, its dimensions' structural parameters row-major, ``("nc", "n")``); ``scalars``:
    (name, value reference) of the scalars (no structural parameter). The arrays in the order of
    their value references, each from the first value reference after its own and after the
    previous array's elements (no fixed stride: the declared value references are kept where the
    elements fit between them, any size as long as the last fits in 32 bits); the scalars' value
    references must all come before the arrays'. ValueError otherwise, naming the variable."""
    ordered = sorted(arrays, key=lambda a: a[1])
    scalars = list(scalars)
    if ordered and scalars:
        top = max(scalars, key=lambda s: s[1])
        if top[1] >= ordered[0][1]:
            raise ValueError(f"scalar {top[0]}: value reference {top[1]} is not below the arrays' "
                             f"({ordered[0][0]}: {ordered[0][1]})")
    out: list[ArrayLayout] = []
    end = 0
    for name, vr, dims in ordered:
        unknown = [d for d in dims if d not in sizes]
        if unknown:
            raise ValueError(f"array {name}: its dimension {unknown[0]} is not among the sizes "
                             f"{', '.join(sizes)}")
        first = max(vr + 1, end)
        lay = ArrayLayout(name, vr, first, tuple(int(sizes[d]) for d in dims))
        end = first + lay.count
        if end - 1 > UINT32_MAX:
            shown = ", ".join(f"{k} = {n}" for k, n in sizes.items())
            raise ValueError(f"with {shown} the FMI 2.0 value references of {name} end at {end - 1}, "
                             f"beyond 32 bits ({UINT32_MAX})")
        out.append(lay)
    return tuple(out)


@dataclass(frozen=True)
class ModelDescription:
    """What ``dryfriction.model`` reads from a model description: identifiers, variables, schemes, effects and
    log categories."""
    guid: str
    model_identifier: str
    variables: dict[str, Variable]
    schemes: dict[str, int]          # enumeration item name -> value, in declaration order
    effects: tuple[Effect, ...]
    effects_variable: str | None
    fmi_version: str = "2.0"
    #: FMI 2.0 with arrays: each array's layout (the ``dryfriction.layout`` annotation), by name
    layout: Mapping[str, ArrayLayout] = field(default_factory=dict)

    # ---- lookups ----
    def var(self, name: str) -> Variable:
        """The variable ``name`` (FMUError naming it when the model has none)."""
        try:
            return self.variables[name]
        except KeyError:
            raise KeyError(f"the FMU has no variable {name!r}") from None

    def vr(self, name: str) -> int:
        """The value reference of the variable ``name``."""
        return self.var(name).vr

    def names(self, causality: str | None = None) -> tuple[str, ...]:
        """The variables' names, of one causality when given."""
        return tuple(n for n, v in self.variables.items() if causality is None or v.causality == causality)

    def structural_parameters(self) -> tuple[str, ...]:
        """The structural parameters (the chain's ``n``)."""
        return self.names("structuralParameter")

    def arrays(self) -> dict[str, tuple[str, ...]]:
        """Array name -> its element names: an FMI 3.0 (or source) array is one variable (its own
        name, sized by :attr:`Variable.dimension`), an FMI 2.0 array the structured names
        ``m[1]`` ... ``m[n]`` (``W[1,1]``, ``W[1,2]`` ...: row-major) in index order."""
        out: dict[str, list[tuple[tuple[int, ...], str]]] = {}
        for name, v in self.variables.items():
            if v.dimension is not None:
                out[name] = [((), name)]
                continue
            index = _index(name)
            if index is not None:
                out.setdefault(index[0], []).append((index[1], name))
        return {k: tuple(n for _, n in sorted(v)) for k, v in out.items()}

    def shape(self, name: str) -> tuple[int, ...]:
        """An array's shape: FMI 2.0 the build's (its layout, else the largest index of each
        dimension among its element names), FMI 3.0 and the source at the structural parameters'
        start values."""
        if name in self.layout:
            return self.layout[name].shape
        v = self.variables.get(name)
        if v is not None and v.dimension is not None:
            return tuple(int(self.var(d).start) if d in self.variables else int(d) for d in v.dimensions)
        indices = [ix for n, ix in map(_index, self.arrays().get(name, ())) if n == name] if v is None else []
        if not indices:
            raise KeyError(f"the FMU has no array {name!r}")
        return tuple(max(ix[k] for ix in indices) for k in range(len(indices[0])))

    def parameter_starts(self) -> dict[str, Any]:
        """Declared start values of the parameters, by name."""
        return {n: v.start for n, v in self.variables.items() if v.causality == "parameter"}

    def scheme_value(self, scheme: str | int) -> int:
        """The enumeration value of a scheme name (or a value, checked)."""
        if isinstance(scheme, str):
            if scheme not in self.schemes:
                raise ValueError(f"scheme must be one of {', '.join(self.schemes)}, not {scheme!r}")
            return self.schemes[scheme]
        if int(scheme) not in self.schemes.values():
            raise ValueError(f"scheme must be one of {', '.join(f'{v} ({k})' for k, v in self.schemes.items())}, "
                             f"not {scheme!r}")
        return int(scheme)

    def effect_names(self, mask: int) -> list[str]:
        """The names of the effects whose bits are set in ``mask``."""
        return [e.name for e in self.effects if mask & e.bit]

    # ---- validation ----
    def valid_range(self, name: str) -> str:
        """The valid range of a variable in words, as the FMU's error messages give it."""
        v = self.var(name)
        if v.type == "Enumeration":
            return "one of " + ", ".join(f"{val} ({item})" for item, val in self.schemes.items())
        if v.type == "Boolean":
            return "true or false"
        lo, hi = v.min, v.max
        finite = v.is_real
        if v.zero is not None and lo == 0:
            return f"0 ({v.zero}) or > 0 (a normal number)"
        if lo is not None and hi is not None:
            return f"in [{lo:g}, {hi:g}]"
        if lo is not None:
            if v.is_real and lo > 0 and lo <= 2.2250738585072014e-308:
                return "> 0"
            return f">= {lo:g}"
        if hi is not None:
            return f"<= {hi:g}"
        return "finite" if finite else "any"

    def check(self, name: str, value: Any, where: str | None = None) -> None:
        """Raise ValueError with one sentence if ``value`` is outside the declared range of the
        variable ``name`` (finite for Reals, an item of the enumeration, within min/max)."""
        v = self.var(name)
        label = where or f"variable {name}"
        bad = False
        if v.type == "Boolean":
            bad = not isinstance(value, (bool, int)) or (not isinstance(value, bool) and value not in (0, 1))
        elif v.type == "Enumeration":
            bad = (isinstance(value, str) and value not in self.schemes) or (
                not isinstance(value, str) and (isinstance(value, bool) or not isinstance(value, int)
                                                or value not in self.schemes.values()))
        else:
            try:
                x = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{label} must be a number, not {value!r}") from None
            if v.type in INTEGER_TYPES and (isinstance(value, bool) or x != int(x)):
                raise ValueError(f"{label} must be a whole number, not {value!r}")
            bad = not math.isfinite(x) or (v.min is not None and x < v.min) or (v.max is not None and x > v.max)
            bad = bad or (v.zero is not None and x != 0 and abs(x) < 2.2250738585072014e-308)
        if bad:
            if v.type == "Enumeration":
                rng = "one of " + ", ".join(self.schemes)
            elif v.is_real and not math.isfinite(float(value)):
                rng = "finite"
            else:
                rng = self.valid_range(name)
            raise ValueError(f"invalid value {value!r} for {label}; valid range: {rng}")

    def check_all(self, values: Mapping[str, Any]) -> None:
        """Check every value against its variable's range (ValueError naming the first bad one)."""
        for name, value in values.items():
            self.check(name, value)


def _index(name: str) -> tuple[str, tuple[int, ...]] | None:
    """(array, index) of an FMI 2.0 element name (``m[3]``: ("m", (3,)); ``W[2,1]``: ("W", (2, 1))),
    None for any other name."""
    m = _INDEXED.match(name)
    return None if m is None else (m.group(1), tuple(int(i) for i in m.group(2).split(",")))


def _layout(root: ET.Element, variables: Mapping[str, Variable]) -> dict[str, ArrayLayout]:
    """The ``dryfriction.layout`` annotation of an FMI 2.0 description, checked against its elements:
    every element named by the layout present with the layout's value reference, and none beyond."""
    tool = _annotation(root, LAYOUT_TOOL)
    out: dict[str, ArrayLayout] = {}
    for a in (tool.iterfind("Layout/Array") if tool is not None else ()):
        lay = ArrayLayout(a.get("name", ""), int(a.get("valueReference", "0")), int(a.get("first", "0")),
                          tuple(int(n) for n in a.get("shape", "").split()))
        out[lay.name] = lay
    counts: dict[str, int] = {}
    for name, v in variables.items():
        index = _index(name)
        if index is None or index[0] not in out:
            continue
        lay = out[index[0]]
        try:
            want = lay.element_vr(*index[1])
        except IndexError:
            want = None
        if want != v.vr:
            raise ValueError(f"modelDescription.xml: {name} has value reference {v.vr}, its array's layout "
                             f"(first {lay.first}, shape {' x '.join(map(str, lay.shape))}) says {want}")
        counts[lay.name] = counts.get(lay.name, 0) + 1
    for lay in out.values():
        if counts.get(lay.name, 0) != lay.count:
            raise ValueError(f"modelDescription.xml: array {lay.name} has {counts.get(lay.name, 0)} elements, "
                             f"its layout {lay.count}")
    return out


def _number(text: str | None, kind: str) -> Any:
    if text is None:
        return None
    if kind == "Boolean":
        return text.strip().lower() in ("true", "1")
    if kind in INTEGER_TYPES or kind == "Enumeration":
        return int(text)
    return float(text)


def _start(text: str | None, kind: str, array: bool) -> Any:
    """A start value; an array's (FMI 3.0: space-separated) as a tuple when it holds several."""
    if text is None or not array:
        return _number(text, kind)
    parts = text.split()
    return _number(parts[0], kind) if len(parts) == 1 else tuple(_number(p, kind) for p in parts)


def _annotation(root: ET.Element, tool: str) -> ET.Element | None:
    """The vendor annotation of ``tool``: FMI 2.0 ``<VendorAnnotations><Tool name=...>``, FMI 3.0
    ``<Annotations><Annotation type=...>``."""
    el = root.find(f"VendorAnnotations/Tool[@name='{tool}']")
    return el if el is not None else root.find(f"Annotations/Annotation[@type='{tool}']")


def parse_effects(root: ET.Element) -> tuple[str | None, tuple[Effect, ...]]:
    """The effect table of a parsed model description (either FMI version): the variable holding
    the bitmask and the effects, in declaration order; (None, ()) without one."""
    tool = _annotation(root, "dryfriction")
    table = tool.find("Effects") if tool is not None else None
    if table is None:
        return None, ()
    return table.get("variable"), tuple(Effect(int(e.get("bit", "0")), e.get("name", ""), e.get("description", ""))
                                        for e in table.iterfind("Effect"))


def _enumerations(root: ET.Element) -> dict[str, dict[str, int]]:
    enums: dict[str, dict[str, int]] = {}
    for st in root.iterfind("TypeDefinitions/SimpleType"):  # FMI 2.0
        e = st.find("Enumeration")
        if e is not None:
            enums[st.get("name", "")] = {i.get("name", ""): int(i.get("value", "0")) for i in e.iterfind("Item")}
    for et in root.iterfind("TypeDefinitions/EnumerationType"):  # FMI 3.0
        enums[et.get("name", "")] = {i.get("name", ""): int(i.get("value", "0")) for i in et.iterfind("Item")}
    return enums


def parse(xml: bytes | str) -> ModelDescription:
    """A :class:`ModelDescription` of the text of a modelDescription.xml (FMI 2.0 or 3.0)."""
    root = ET.fromstring(xml)
    cs = root.find("CoSimulation")
    if cs is None:
        raise ValueError("modelDescription.xml has no CoSimulation element")
    version = root.get("fmiVersion", "2.0")
    fmi3 = version.startswith("3")
    enums = _enumerations(root)
    ranges = _annotation(root, "dryfriction.ranges")
    zero = {z.get("variable", ""): z.get("zero", "") for z in
            (ranges.iterfind("Ranges/ZeroOrNormal") if ranges is not None else ())}
    # (variable element, type element, dimension name) of every variable
    items: list[tuple[ET.Element, ET.Element, str | None]] = []
    if fmi3:
        els = list(root.iterfind("ModelVariables/*"))
        by_vr = {el.get("valueReference", ""): el.get("name", "") for el in els}
        for el in els:
            dims = [by_vr.get(d.get("valueReference", ""), d.get("start")) or "" for d in el.iterfind("Dimension")]
            items.append((el, el, " ".join(dims) if dims else None))
    else:
        for sv in root.iterfind("ModelVariables/ScalarVariable"):
            items.append((sv, next(iter(sv)), sv.get("dimension")))
    variables: dict[str, Variable] = {}
    schemes: dict[str, int] = {}
    for var_el, el, dname in items:
        kind = el.tag
        declared = el.get("declaredType")
        name = var_el.get("name", "")
        if kind == "Enumeration" and declared in enums and name == "scheme":
            schemes = enums[declared]
        lo, hi = _number(el.get("min"), kind), _number(el.get("max"), kind)
        if kind == "Enumeration" and declared in enums:
            vals = enums[declared].values()
            lo, hi = (min(vals) if lo is None else lo), (max(vals) if hi is None else hi)
        variables[name] = Variable(
            name=name, vr=int(var_el.get("valueReference", "0")), type=kind,
            causality=var_el.get("causality", "local"), variability=var_el.get("variability", "continuous"),
            start=_start(el.get("start"), kind, dname is not None), min=lo, max=hi, unit=el.get("unit"),
            description=var_el.get("description", ""), declared_type=declared, zero=zero.get(name),
            dimension=dname, fmi_version=version)
    if not schemes and "Scheme" in enums:
        schemes = enums["Scheme"]
    effects_var, effects = parse_effects(root)
    token = root.get("instantiationToken") if fmi3 else root.get("guid")
    return ModelDescription(guid=token or "", model_identifier=cs.get("modelIdentifier", ""),
                            variables=variables, schemes=schemes, effects=effects,
                            effects_variable=effects_var, fmi_version=version,
                            layout={} if fmi3 else _layout(root, variables))


def from_xml(path: str | os.PathLike[str]) -> ModelDescription:
    """The model description read from a ``modelDescription.xml`` file."""
    return parse(Path(path).read_bytes())


def from_fmu(path: str | os.PathLike[str]) -> ModelDescription:
    """The model description inside an FMU archive."""
    with zipfile.ZipFile(path) as z:
        return parse(z.read("modelDescription.xml"))


def repository_xml() -> Path:
    """The source checkout's modelDescription.xml (not there in an installed wheel)."""
    from . import paths

    root = paths.source_root()
    return (root if root is not None else paths.package_dir().parents[1]) / "modelDescription.xml"


@functools.lru_cache(maxsize=1)
def repository() -> ModelDescription:
    """The repository's modelDescription.xml (the one the FMU is generated from)."""
    return from_xml(repository_xml())


def default_fmu_path() -> Path:
    """The FMI 2.0 oscillator FMU: ``$DFO_FMU``, else the installed package's, else the build tree's
    (:func:`dryfriction.paths.fmu_path`; FMUFileError if there is none or it is not that FMU)."""
    from . import paths

    return paths.fmu_path(paths.OSCILLATOR)


@functools.lru_cache(maxsize=1)
def default() -> ModelDescription:
    """The model description, read on first use (never at import): the source checkout's
    modelDescription.xml, else the one inside the FMU :func:`default_fmu_path` finds (the installed
    package's): the same file, copied into the FMU by the build."""
    if repository_xml().is_file():
        return repository()
    return _cached_fmu(str(default_fmu_path()))


@functools.lru_cache(maxsize=8)
def _cached_fmu(path: str) -> ModelDescription:
    return from_fmu(path)


class LazyMapping(Mapping[Any, Any]):
    """A read-only mapping computed on first use (module-level tables derived from the model
    description without reading it at import time)."""

    def __init__(self, make: Callable[[], Mapping[Any, Any]]) -> None:
        self._make = make
        self._data: dict[Any, Any] | None = None

    def _get(self) -> dict[Any, Any]:
        if self._data is None:
            self._data = dict(self._make())
        return self._data

    def __getitem__(self, key: Any) -> Any:
        return self._get()[key]

    def __iter__(self) -> Iterator[Any]:
        return iter(self._get())

    def __len__(self) -> int:
        return len(self._get())

    def __repr__(self) -> str:
        return repr(self._get()) if self._data is not None else f"{type(self).__name__}(<not read yet>)"


class LazySequence(Sequence[Any]):
    """A read-only sequence computed on first use (a tuple once read; compares equal to it)."""

    def __init__(self, make: Callable[[], Iterable[Any]]) -> None:
        self._make = make
        self._data: tuple[Any, ...] | None = None

    def _get(self) -> tuple[Any, ...]:
        if self._data is None:
            self._data = tuple(self._make())
        return self._data

    def __getitem__(self, index: Any) -> Any:
        return self._get()[index]

    def __len__(self) -> int:
        return len(self._get())

    def __iter__(self) -> Iterator[Any]:
        return iter(self._get())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, LazySequence):
            other = other._get()
        return self._get() == other

    def __hash__(self) -> int:
        return hash(self._get())

    def __add__(self, other: Any) -> tuple[Any, ...]:
        return self._get() + tuple(other)

    def __repr__(self) -> str:
        return repr(self._get()) if self._data is not None else f"{type(self).__name__}(<not read yet>)"
