"""A structure's own FMU without a compiler: :func:`write_fmu` (``System.fmu``, ``dryfriction system fmu``).

The FMU is the package's prebuilt ``DryFrictionSystem`` FMU (its binaries and sources as built,
shipped in the wheel as the other FMUs; FMI 3.0 for any sizes, FMI 2.0 only at the sizes its binary
was built for) with the structure's values

* as the model description's start values (FMI 3.0: ``n``, ``nc``, the arrays ``M``, ``C``, ``K``,
  ``W`` row-major, every per-DOF and per-contact array, the scalars; FMI 2.0: the flattened
  elements as Modelica tools name them, ``M[1,2]``, ``x0[3]``, 1-based), and
* in ``resources/structure.bin``, a small little-endian binary file the binary reads at
  instantiation (fmu_src/models/system/sys_inst_resources.c), so that its defaults are the
  description's starts whatever a host sets or not.

The file: the magic ``DFOSTRUC``, uint32 version 1, uint32 the number of records, uint64 ``n``,
uint64 ``nc``; each record a parameter's value reference (uint32), 0 (uint32), the number of its
values (uint64) and those values as IEEE 754 doubles. The instantiation token stays the prebuilt
FMU's (the binary checks it); the model name becomes the file's stem.
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

if TYPE_CHECKING:
    from .structure import System

__all__ = ["write_fmu", "structure_bytes", "fmi2_sizes", "RESOURCE", "MAGIC", "VERSION"]

#: where the structure's values live in the FMU
RESOURCE = "resources/structure.bin"
MAGIC = b"DFOSTRUC"
VERSION = 1
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


def structure_bytes(system: "System", vrs: dict[str, int]) -> bytes:
    """The bytes of ``resources/structure.bin`` for ``system``; ``vrs``: the FMI 3.0 value
    reference of every parameter by name (from the model description)."""
    sv = system.start_values()
    records = []
    for name, value in sv.items():
        if name in _SIZES:
            continue
        vals = np.atleast_1d(np.asarray(value, dtype=np.float64)).ravel()
        records.append(struct.pack("<IIQ", vrs[name], 0, vals.size) + vals.astype("<f8").tobytes())
    head = struct.pack("<8sIIQQ", MAGIC, VERSION, len(records), system.n, system.nc)
    return head + b"".join(records)


def _description(xml: bytes, system: "System", name: str) -> tuple[bytes, dict[str, int]]:
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
    return out, vrs


_ELEMENT = re.compile(r"^(\w+)\[(\d+)(?:,(\d+))?\]$")


def fmi2_sizes(root: ET.Element) -> dict[str, int]:
    """The sizes an FMI 2.0 system FMU was built for (its ``dryfriction.layout`` annotation:
    ``sizes="n=2,nc=1"``)."""
    layout = root.find("VendorAnnotations/Tool[@name='dryfriction.layout']/Layout")
    if layout is None:
        raise UsageError("write_fmu: the base FMI 2.0 FMU has no dryfriction.layout annotation: not the "
                         "DryFrictionSystem FMU")
    return {k.strip(): int(v) for k, v in (part.split("=") for part in layout.get("sizes", "").split(","))}


def _description2(xml: bytes, system: "System", name: str) -> tuple[bytes, dict[str, int]]:
    """The prebuilt FMI 2.0 model description (sizes fixed when built, which must be the system's)
    with this system's start values on the flattened elements (``M[1,2]``, ``x0[3]``, 1-based)."""
    root = ET.fromstring(xml)
    if root.get("fmiVersion", "") != "2.0":
        raise UsageError("write_fmu: the base FMU is not an FMI 2.0 FMU")
    sizes = fmi2_sizes(root)
    if (sizes.get("n"), sizes.get("nc")) != (system.n, system.nc):
        raise UsageError(f"write_fmu: the prebuilt FMI 2.0 binary serves n = {sizes.get('n')}, nc = {sizes.get('nc')} "
                         f"only (fixed when built) but the structure has n = {system.n}, nc = {system.nc}; use "
                         "fmi=3 (--fmi 3)")
    root.set("modelName", name)
    root.set("description", f"{name}: a structure of n = {system.n} degrees of freedom and nc = {system.nc} "
                            f"friction contacts (its values in {RESOURCE}). " + root.get("description", ""))
    sv = {k: np.atleast_1d(np.asarray(v)) for k, v in system.start_values().items() if k not in _SIZES}
    cols = {"M": system.n, "C": system.n, "K": system.n, "W": system.n}
    mv = root.find("ModelVariables")
    if mv is None:
        raise UsageError("write_fmu: the base FMU's model description has no <ModelVariables>")
    seen = set()
    for var in mv:
        vname = var.get("name", "")
        m = _ELEMENT.match(vname)
        base, idx = (m.group(1), (int(m.group(2)) - 1) * cols.get(m.group(1), 1) + int(m.group(3) or 1) - 1) \
            if m else (vname, 0)
        if base not in sv:
            continue
        typed = next(iter(var))
        typed.set("start", _text(sv[base][idx].item()))
        seen.add(base)
    missing = [k for k in sv if k not in seen]
    if missing:
        raise UsageError(f"write_fmu: the base FMU has no variable {missing[0]}: not the DryFrictionSystem FMU")
    # the binary reads FMI 3.0's array value references from the file: the arrays' own (the layout's)
    vrs = {a.get("name", ""): int(a.get("valueReference", "0"))
           for a in root.iterfind("VendorAnnotations/Tool[@name='dryfriction.layout']/Layout/Array")}
    vrs.update({v.get("name", ""): int(v.get("valueReference", "0")) for v in mv
                if not _ELEMENT.match(v.get("name", ""))})
    return ET.tostring(root, encoding="utf-8", xml_declaration=True), vrs


def write_fmu(system: "System", path: str | os.PathLike[str], fmi: int = 3,
              base: str | os.PathLike[str] | None = None) -> Path:
    """Write the FMU of ``system`` to ``path`` (a ``.fmu`` name; its folder must exist) from the
    prebuilt ``DryFrictionSystem`` FMU (``base``; default the package's, :mod:`dryfriction.paths`):
    its binaries and sources unchanged, the structure's values as start values and in
    ``resources/structure.bin``. ``fmi``: 3 (FMI 3.0, any sizes) or 2 (FMI 2.0: the flattened
    elements ``M[1,2]``, ``x0[3]``; only at the sizes the prebuilt FMI 2.0 binary was built for,
    n = 2, nc = 1 by default). Returns the path written. UsageError for a path, an FMI version or
    sizes that cannot be."""
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
            xml, vrs = describe(zin.read("modelDescription.xml"), system, out.stem)
            zout.writestr("modelDescription.xml", xml)
            for item in zin.infolist():
                if item.filename in ("modelDescription.xml", RESOURCE):
                    continue
                zout.writestr(item, zin.read(item.filename))
            zout.writestr(RESOURCE, structure_bytes(system, vrs))
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    return out
