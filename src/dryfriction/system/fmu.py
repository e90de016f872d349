"""A structure's own FMU without a compiler: :func:`write_fmu` (``System.fmu``, ``dryfriction system fmu``).

The FMU is the package's prebuilt FMI 3.0 ``DryFrictionSystem`` FMU (its binaries and sources as
built, shipped in the wheel as the other FMUs) with the structure's values

* as the model description's start values (``n``, ``nc``, the arrays ``M``, ``C``, ``K``, ``W``
  row-major, every per-DOF and per-contact array, the scalars), and
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

__all__ = ["write_fmu", "structure_bytes", "RESOURCE", "MAGIC", "VERSION"]

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


def write_fmu(system: "System", path: str | os.PathLike[str], fmi: int = 3,
              base: str | os.PathLike[str] | None = None) -> Path:
    """Write the FMU of ``system`` to ``path`` (a ``.fmu`` name; its folder must exist) from the
    prebuilt ``DryFrictionSystem`` FMU (``base``; default the package's, :mod:`dryfriction.paths`):
    its binaries and sources unchanged, the structure's values as start values and in
    ``resources/structure.bin``. ``fmi``: 3 (FMI 3.0; FMI 2.0 at the structure's sizes is not
    offered yet). Returns the path written. UsageError for a path or an FMI version that cannot be."""
    if fmi == 2:
        raise UsageError("write_fmu: an FMI 2.0 FMU of a structure is not offered yet (its prebuilt binary has "
                         "fixed sizes); use fmi=3")
    if fmi != 3:
        raise UsageError(f"write_fmu: fmi must be 2 or 3, not {fmi!r}")
    out = Path(path)
    if out.suffix.lower() != ".fmu":
        raise UsageError(f"write_fmu: {out} must end with .fmu")
    if not out.parent.is_dir():
        raise UsageError(f"write_fmu: the folder {out.parent} does not exist")
    src = paths.fmu_path(paths.SYSTEM3, base)
    if src.resolve() == out.resolve():
        raise UsageError(f"write_fmu: {out} is the base FMU itself; give another name")
    tmp = out.with_name(out.name + ".part")
    try:
        with zipfile.ZipFile(src) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
            xml, vrs = _description(zin.read("modelDescription.xml"), system, out.stem)
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
