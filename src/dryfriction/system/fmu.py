"""A structure's own FMU without a compiler: :func:`write_fmu` (``System.fmu``, ``dryfriction system fmu``).

The FMU is the package's prebuilt ``DryFrictionSystem`` FMU (its binaries and sources as built,
shipped in the wheel as the other FMUs; no compiler on the user's machine; FMI 3.0 and FMI 2.0 for
any sizes) with the structure's values

* as the model description's start values (FMI 3.0: ``n``, ``nc``, the arrays ``M``, ``C``, ``K``,
  ``W`` row-major, every per-DOF and per-contact array, the scalars; FMI 2.0: the flattened
  elements as Modelica tools name them, ``M[1,2]``, ``x0[3]``, 1-based, at the value references of
  the layout for the structure's sizes, :func:`dryfriction.model.fmi2_layout`, the generator's), and
* in ``resources/structure.bin``, a small little-endian binary file the binary reads at
  instantiation (fmu_src/models/system/sys_inst_resources.c), so that its defaults are the
  description's starts whatever a host sets or not, and, FMI 2.0, its sizes and layout are these.

The file: the magic ``DFOSTRUC``, uint32 version (1, or 2 with a layout), uint32 the number of
records, uint64 ``n``, uint64 ``nc``; version 2 then uint32 the number of arrays, uint32 0 and for
each array (in the order of its value reference) uint32 its own value reference and uint32 its
first element's FMI 2.0 value reference; each record a parameter's (FMI 3.0) value reference
(uint32), 0 (uint32), the number of its values (uint64) and those values as IEEE 754 doubles. The
FMI 3.0 FMU's file is version 1, the FMI 2.0 FMU's version 2. The instantiation token stays the
prebuilt FMU's (the binary checks it); the model name becomes the file's stem.
"""

from __future__ import annotations

import os
import re
import struct
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.etree import ElementTree as ET

import numpy as np

from .. import paths
from ..errors import UsageError
from ..model import LAYOUT_TOOL, ArrayLayout, fmi2_layout

if TYPE_CHECKING:
    from .structure import System
    from .structure import System as Structure  # (the annotations' name: the API reference links it)

__all__ = ["write_fmu", "structure_bytes", "fmi2_sizes", "RESOURCE", "MAGIC", "VERSION"]

#: where the structure's values live in the FMU
RESOURCE = "resources/structure.bin"
MAGIC = b"DFOSTRUC"
VERSION = 2
#: the parameters written (every value of System.start_values but the sizes)
_SIZES = ("n", "nc")
#: the inputs whose starts follow the sizes (zeros)
_INPUTS = {"F_ext": "n", "N_ext": "nc", "v_belt": "nc"}


def _text(x: Any) -> str:
    """A start value as text: a float's shortest exact form, an int as it is."""
    if isinstance(x, (bool, np.bool_)):
        return "true" if x else "false"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return repr(float(x))


def structure_bytes(system: "Structure", vrs: dict[str, int], layout: tuple[ArrayLayout, ...] = ()) -> bytes:
    """The bytes of ``resources/structure.bin`` for ``system``; ``vrs``: the FMI 3.0 value
    reference of every parameter by name (from the model description); ``layout``: an FMI 2.0
    FMU's array layout (its elements' value references for the system's sizes), written as the
    file's layout section (version 2), or none (version 1)."""
    sv = system.start_values()
    records = []
    for name, value in sv.items():
        if name in _SIZES:
            continue
        vals = np.atleast_1d(np.asarray(value, dtype=np.float64)).ravel()
        records.append(struct.pack("<IIQ", vrs[name], 0, vals.size) + vals.astype("<f8").tobytes())
    if not layout:
        return struct.pack("<8sIIQQ", MAGIC, 1, len(records), system.n, system.nc) + b"".join(records)
    head = struct.pack("<8sIIQQ", MAGIC, VERSION, len(records), system.n, system.nc)
    lay = struct.pack("<II", len(layout), 0) + b"".join(struct.pack("<II", a.vr, a.first)
                                                         for a in sorted(layout, key=lambda a: a.vr))
    return head + lay + b"".join(records)


def _description(xml: bytes, system: "Structure", name: str) -> tuple[bytes, dict[str, int], tuple[ArrayLayout, ...]]:
    """The prebuilt FMI 3.0 model description with this system's start values (and the value
    references of its parameters)."""
    root = ET.fromstring(xml)
    if root.get("fmiVersion", "").split(".")[0] != "3":
        raise UsageError("write_fmu: the base FMU is not an FMI 3.0 FMU")
    root.set("modelName", name)
    root.set("description", f"{name}: a structure of n = {system.n} degrees of freedom and nc = {system.nc} "
                            f"friction contacts (its values in {RESOURCE}). " + root.get("description", ""))
    sv = system.start_values()
    sizes = {"n": system.n, "nc": system.nc}
    vrs: dict[str, int] = {}
    mv = root.find("ModelVariables")
    if mv is None:
        raise UsageError("write_fmu: the base FMU's model description has no <ModelVariables>")
    for var in mv:
        vname = var.get("name", "")
        vrs[vname] = int(var.get("valueReference", "0"))
        if vname in sv:
            value = sv[vname]
            if np.ndim(value) == 0:
                var.set("start", _text(value))
            elif len(value):
                var.set("start", " ".join(_text(v) for v in value))
            elif "start" in var.attrib:
                del var.attrib["start"]  # an empty array (nc = 0) has no start
        elif vname in _INPUTS:
            count = sizes[_INPUTS[vname]]
            if count:
                var.set("start", " ".join(["0.0"] * count))
            elif "start" in var.attrib:
                del var.attrib["start"]
    missing = [k for k in sv if k not in vrs]
    if missing:
        raise UsageError(f"write_fmu: the base FMU has no variable {missing[0]}: not the DryFrictionSystem FMU")
    out = ET.tostring(root, encoding="utf-8", xml_declaration=True)
    return out, vrs, ()


_ELEMENT = re.compile(r"^(\w+)\[(\d+)(?:,(\d+))?\]$")


def fmi2_sizes(root: ET.Element) -> dict[str, int]:
    """The sizes an FMI 2.0 system FMU was built for (its ``dryfriction.layout`` annotation:
    ``sizes="n=2,nc=1"``)."""
    layout = root.find("VendorAnnotations/Tool[@name='dryfriction.layout']/Layout")
    if layout is None:
        raise UsageError("write_fmu: the base FMI 2.0 FMU has no dryfriction.layout annotation: not the "
                         "DryFrictionSystem FMU")
    return {k.strip(): int(v) for k, v in (part.split("=") for part in layout.get("sizes", "").split(","))}


_SUFFIX = re.compile(r" \((?:element \d+(?:, \d+)*|block \d+)\)$")


def _element_name(name: str, idx: tuple[int, ...]) -> str:
    """An array element's name as Modelica tools flatten it: ``x[3]``, ``M[1,2]`` (1-based)."""
    return f"{name}[{','.join(str(i) for i in idx)}]"


def _description2(xml: bytes, system: "Structure", name: str) -> tuple[bytes, dict[str, int], tuple[ArrayLayout, ...]]:
    """The FMI 2.0 model description for this system's sizes, from the prebuilt one (whatever sizes
    it was built for): each array's elements flattened (``M[1,2]``, ``x0[3]``, 1-based) at the value
    references of the package's layout (:func:`dryfriction.model.fmi2_layout`, the generator's), each
    from its first element's declaration, the structure's start values on them, the output
    dependencies and initial unknowns of the prebuilt description carried over element by element
    (an array on an array of the same dimensions: the same element; of others: every element), the
    ``dryfriction.layout`` annotation for these sizes. Returns the description, the FMI 3.0 value
    reference of every parameter (the records of the structure file) and the layout."""
    root = ET.fromstring(xml)
    if root.get("fmiVersion", "") != "2.0":
        raise UsageError("write_fmu: the base FMU is not an FMI 2.0 FMU")
    lay_el = root.find(f"VendorAnnotations/Tool[@name='{LAYOUT_TOOL}']/Layout")
    if lay_el is None:
        raise UsageError("write_fmu: the base FMI 2.0 FMU has no dryfriction.layout annotation: not the "
                         "DryFrictionSystem FMU")
    mv = root.find("ModelVariables")
    if mv is None:
        raise UsageError("write_fmu: the base FMU's model description has no <ModelVariables>")
    arrays: list[tuple[str, int, tuple[str, ...]]] = []
    for a in lay_el.iterfind("Array"):
        if a.get("dims") is None:
            raise UsageError(f"write_fmu: the base FMI 2.0 FMU's layout gives no dimensions of array {a.get('name')} "
                             "(built before layouts had them): rebuild it")
        arrays.append((a.get("name", ""), int(a.get("valueReference", "0")), tuple(a.get("dims", "").split())))
    dims = {a[0]: a[2] for a in arrays}
    old = list(mv)
    base_of = []  # each old variable's (array name or the scalar's name, is an element)
    for var in old:
        m = _ELEMENT.match(var.get("name", ""))
        base_of.append((m.group(1), True) if m and m.group(1) in dims else (var.get("name", ""), False))
    scalars = [(var.get("name", ""), int(var.get("valueReference", "0"))) for var, (_, el) in zip(old, base_of)
               if not el]
    sizes = {"n": system.n, "nc": system.nc}
    try:
        layouts = fmi2_layout(arrays, sizes, scalars)
    except ValueError as e:
        raise UsageError(f"write_fmu: {e}") from None
    lays = {a.name: a for a in layouts}
    root.set("modelName", name)
    root.set("description", f"{name}: a structure of n = {system.n} degrees of freedom and nc = {system.nc} "
                            f"friction contacts (its values in {RESOURCE}). " + root.get("description", ""))
    sv = {k: np.atleast_1d(np.asarray(v)).ravel() for k, v in system.start_values().items() if k not in _SIZES}
    missing = [k for k in sv if k not in dims and k not in {s for s, _ in scalars}]
    if missing:
        raise UsageError(f"write_fmu: the base FMU has no variable {missing[0]}: not the DryFrictionSystem FMU")

    # the variables: the scalars as they are, each array's elements from its first element's declaration
    new: list[ET.Element] = []
    index: dict[tuple[str, tuple[int, ...]], int] = {}
    done: set[str] = set()
    for var, (base, is_el) in zip(old, base_of):
        if not is_el:
            if base in sv:
                next(iter(var)).set("start", _text(sv[base][0].item()))
            new.append(var)
            index[(base, ())] = len(new)
            continue
        if base in done:
            continue
        done.add(base)
        what = _SUFFIX.sub("", var.get("description", ""))
        proto = next(iter(var))
        for k, (idx, vr) in enumerate(lays[base].elements()):
            where = f" (block {idx[0]})" if len(idx) == 1 else f" (element {', '.join(str(i) for i in idx)})"
            el = ET.Element(var.tag, {**var.attrib, "name": _element_name(base, idx), "valueReference": str(vr),
                                      "description": what + where})
            typed = ET.SubElement(el, proto.tag, dict(proto.attrib))
            if base in sv:
                typed.set("start", _text(sv[base][k].item()))
            el.text, el.tail = var.text, var.tail
            new.append(el)
            index[(base, idx)] = len(new)
    for var in old:
        mv.remove(var)
    mv.extend(new)

    # the structure, variable by variable: an output's dependencies by variable, then element by element
    def var_of(i: int) -> str:
        return base_of[i - 1][0]

    def elements(base: str) -> list[tuple[int, ...]]:
        return [idx for idx, _ in lays[base].elements()] if base in lays else [()]

    ms = root.find("ModelStructure")
    if ms is not None:
        for part in ms:
            order: list[str] = []
            deps: dict[str, list[str] | None] = {}
            for u in part:
                v = var_of(int(u.get("index", "0")))
                if v not in deps:
                    order.append(v)
                    deps[v] = None
                if u.get("dependencies") is not None:
                    known = deps[v] or []
                    for d in (var_of(int(i)) for i in u.get("dependencies", "").split()):
                        if d not in known:
                            known.append(d)
                    deps[v] = known
            tail = part[-1].tail if len(part) else None
            text = part.text
            for u in list(part):
                part.remove(u)
            for v in order:
                for idx in elements(v):
                    attrs = {"index": str(index[(v, idx)])}
                    if deps[v] is not None:
                        attrs["dependencies"] = " ".join(
                            str(index[(d, j)]) for d in deps[v]
                            for j in ([idx] if idx and dims.get(d) == dims.get(v) else elements(d)))
                    u = ET.SubElement(part, "Unknown", attrs)
                    u.tail = text
            if len(part):
                part[-1].tail = tail

    # the layout annotation for these sizes
    lay_el.set("sizes", ",".join(f"{k}={v}" for k, v in sizes.items()))
    for a in lay_el.iterfind("Array"):
        L = lays[a.get("name", "")]
        a.set("first", str(L.first))
        a.set("shape", " ".join(str(x) for x in L.shape))
    # the binary reads FMI 3.0's array value references from the file: the arrays' own (the layout's)
    vrs = {a.name: a.vr for a in layouts}
    vrs.update(dict(scalars))
    return ET.tostring(root, encoding="utf-8", xml_declaration=True), vrs, layouts


def write_fmu(system: "Structure", path: str | os.PathLike[str], fmi: int = 3,
              base: str | os.PathLike[str] | None = None) -> Path:
    """Write the FMU of ``system`` to ``path`` (a ``.fmu`` name; its folder must exist) from the
    prebuilt ``DryFrictionSystem`` FMU (``base``; default the package's, :mod:`dryfriction.paths`):
    its binaries and sources unchanged, the structure's values as start values and in
    ``resources/structure.bin``. ``fmi``: 3 (FMI 3.0) or 2 (FMI 2.0: the flattened elements
    ``M[1,2]``, ``x0[3]`` at the value references of the layout for the structure's sizes, which
    the file gives the binary); any sizes either way. Returns the path written. UsageError for a
    path or an FMI version that cannot be, or a base FMU that is not the DryFrictionSystem's."""
    if fmi not in (2, 3):
        raise UsageError(f"write_fmu: fmi must be 2 or 3, not {fmi!r}")
    out = Path(path)
    if out.suffix.lower() != ".fmu":
        raise UsageError(f"write_fmu: {out} must end with .fmu")
    if not out.parent.is_dir():
        raise UsageError(f"write_fmu: the folder {out.parent} does not exist")
    src = paths.fmu_path(paths.SYSTEM3 if fmi == 3 else paths.SYSTEM, base)
    describe = _description if fmi == 3 else _description2
    if src.resolve() == out.resolve():
        raise UsageError(f"write_fmu: {out} is the base FMU itself; give another name")
    tmp = out.with_name(out.name + ".part")
    try:
        with zipfile.ZipFile(src) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
            xml, vrs, layout = describe(zin.read("modelDescription.xml"), system, out.stem)
            zout.writestr("modelDescription.xml", xml)
            for item in zin.infolist():
                if item.filename in ("modelDescription.xml", RESOURCE):
                    continue
                zout.writestr(item, zin.read(item.filename))
            zout.writestr(RESOURCE, structure_bytes(system, vrs, layout))
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    return out
