"""Where the FMUs and the study configs come from: the one place that decides, for the whole package.

An FMU of each kind (the oscillator, the chain and the system, FMI 2.0 and FMI 3.0) is, in this order:

1. the path given (``--fmu PATH``, ``fmu_path=...``);
2. the environment variable of its kind: ``DFO_FMU``, ``DFO_FMU3``, ``DFO_CHAIN_FMU``,
   ``DFO_CHAIN_FMU3``, ``DFO_SYSTEM_FMU``, ``DFO_SYSTEM_FMU3``;
3. the package data of an installed wheel: ``dryfriction/fmus/DryFrictionOscillator.fmu``,
   ``DryFrictionChain.fmu``, ``DryFrictionSystem.fmu``, ``fmi3/DryFrictionOscillator.fmu``,
   ``fmi3/DryFrictionChain.fmu``, ``fmi3/DryFrictionSystem.fmu``;
4. the CMake build tree of a source checkout (an editable install): ``<repository>/build/``, the
   same names.

Every FMU is checked before it is used: a path that is not there, not a zip archive, a zip without
``modelDescription.xml``, another model's FMU or an FMU of the other FMI version raises
:class:`FMUFileError` with one sentence (``README.md is not an FMU (not a zip archive)``).

Nothing here is read at import time.
"""

from __future__ import annotations

import functools
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree as ET

from .errors import FMUFileError

__all__ = ["FMUFileError", "Kind", "OSCILLATOR", "OSCILLATOR3", "CHAIN", "CHAIN3", "SYSTEM", "SYSTEM3", "KINDS",
           "fmu_path",
           "check_fmu", "extract", "candidates", "package_dir", "source_root", "build_dir", "configs_dir"]


@dataclass(frozen=True)
class Kind:
    """One of the package's FMUs: its model identifier, FMI version, place in the build tree and package
    data (``relpath``) and the environment variable that selects another file."""

    model_identifier: str
    fmi_version: str          # "2.0" or "3.0"
    relpath: str
    env: str

    def describe(self) -> str:
        """The FMU in words (``the FMI 2.0 DryFrictionOscillator FMU``)."""
        return f"the FMI {self.fmi_version} {self.model_identifier} FMU"


OSCILLATOR = Kind("DryFrictionOscillator", "2.0", "DryFrictionOscillator.fmu", "DFO_FMU")
OSCILLATOR3 = Kind("DryFrictionOscillator", "3.0", "fmi3/DryFrictionOscillator.fmu", "DFO_FMU3")
CHAIN = Kind("DryFrictionChain", "2.0", "DryFrictionChain.fmu", "DFO_CHAIN_FMU")
CHAIN3 = Kind("DryFrictionChain", "3.0", "fmi3/DryFrictionChain.fmu", "DFO_CHAIN_FMU3")
SYSTEM = Kind("DryFrictionSystem", "2.0", "DryFrictionSystem.fmu", "DFO_SYSTEM_FMU")
SYSTEM3 = Kind("DryFrictionSystem", "3.0", "fmi3/DryFrictionSystem.fmu", "DFO_SYSTEM_FMU3")
KINDS = (OSCILLATOR, OSCILLATOR3, CHAIN, CHAIN3, SYSTEM, SYSTEM3)


def package_dir() -> Path:
    """The installed package's folder (``dryfriction/``; its data: ``fmus/``, ``configs/``)."""
    return Path(__file__).resolve().parent


def source_root() -> Path | None:
    """The repository this package is imported from (a source checkout or an editable install:
    ``<root>/src/dryfriction``), or None for an installed wheel."""
    root = package_dir().parents[1]
    if (root / "CMakeLists.txt").is_file() and (root / "pyproject.toml").is_file() and \
            (root / "src" / "dryfriction").is_dir():
        return root
    return None


def build_dir() -> Path | None:
    """The CMake build tree of the source checkout (``<root>/build``), or None without one."""
    root = source_root()
    return root / "build" if root is not None else None


def candidates(kind: Kind) -> list[Path]:
    """The default places of an FMU, in order: the package data, then the build tree."""
    places = [package_dir() / "fmus" / kind.relpath]
    build = build_dir()
    if build is not None:
        places.append(build / kind.relpath)
    return places


def fmu_path(kind: Kind, explicit: str | os.PathLike[str] | None = None, *, check: bool = True) -> Path:
    """The FMU of ``kind`` to use: ``explicit`` if given, else ``$<kind.env>``, else the package data,
    else the build tree; checked (:func:`check_fmu`) unless ``check`` is false. FMUFileError when
    there is none or it cannot be used."""
    origin = None
    if explicit is not None:
        path = Path(explicit)
    elif os.environ.get(kind.env):
        path, origin = Path(os.environ[kind.env]), kind.env
    else:
        places = candidates(kind)
        path = next((p for p in places if p.is_file()), None)  # type: ignore[assignment]
        if path is None:
            where = " nor ".join(str(p) for p in places)
            raise FMUFileError(f"{kind.describe()} is not there ({where}): build it (bash scripts/setup.sh, "
                               f"or cmake -S . -B build && cmake --build build), or give --fmu PATH or set {kind.env}")
    return check_fmu(path, kind, origin) if check else path


def check_fmu(path: str | os.PathLike[str], kind: Kind, origin: str | None = None) -> Path:
    """``path`` if it is an FMU of ``kind`` (the model identifier and the FMI version), else
    FMUFileError with one sentence naming the path (``origin``: the environment variable it came
    from, named in the sentence)."""
    p = Path(path)
    label = f"{origin}={p}" if origin else str(p)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise FMUFileError(f"FMU not found: {label} (no such file)") from None
    except OSError as e:
        raise FMUFileError(f"FMU {label} cannot be read ({e.strerror})") from None
    if p.is_dir():
        raise FMUFileError(f"{label} is a folder, not an FMU file")
    found = _inspect(str(p), st.st_mtime_ns, st.st_size)
    if isinstance(found, str):
        raise FMUFileError(f"{label} is not an FMU ({found})")
    identifier, version = found
    if (identifier, version) != (kind.model_identifier, kind.fmi_version):
        raise FMUFileError(f"{label} is the FMI {version} {identifier} FMU, not {kind.describe()} this needs")
    return p


@functools.lru_cache(maxsize=32)
def _inspect(path: str, mtime_ns: int, size: int) -> tuple[str, str] | str:
    """(model identifier, FMI version "2.0" / "3.0") of an FMU file, or why it is not one (the
    file's time and size are part of the cache key)."""
    try:
        with zipfile.ZipFile(path) as z:
            try:
                xml = z.read("modelDescription.xml")
            except KeyError:
                return "no modelDescription.xml in the archive"
    except zipfile.BadZipFile:
        return "not a zip archive"
    except OSError as e:
        return f"cannot be read: {e.strerror or e}"
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as e:
        return f"its modelDescription.xml is not valid XML: {e}"
    if root.tag != "fmiModelDescription":
        return f"its modelDescription.xml has the root element <{root.tag}>, not <fmiModelDescription>"
    version = root.get("fmiVersion", "")
    major = version.split(".")[0]
    if major not in ("2", "3"):
        return f"FMI version {version!r}: only 2.0 and 3.0 are supported"
    cs = root.find("CoSimulation")
    if cs is None:
        return "no co-simulation interface in its modelDescription.xml"
    return cs.get("modelIdentifier", ""), f"{major}.0"


def extract(path: str | os.PathLike[str], prefix: str = "dfo-fmu-") -> str:
    """Unzip an FMU (fmpy's ``extract``) into a new temporary folder and return the folder; an
    archive that cannot be unzipped is an :class:`FMUFileError` naming the path (fmpy's or the zip
    module's exception translated)."""
    import tempfile

    from fmpy import extract as fmpy_extract

    where = tempfile.mkdtemp(prefix=prefix)
    try:
        return str(fmpy_extract(str(path), unzipdir=where))
    except Exception as e:  # noqa: BLE001 - whatever fmpy or zipfile raise: one sentence
        import shutil

        shutil.rmtree(where, ignore_errors=True)
        raise FMUFileError(f"{path} cannot be unzipped ({type(e).__name__}: {e})") from None


def configs_dir() -> Path:
    """The study configs (``<study>.toml``): ``$DFO_CONFIGS``, else the package data
    (``dryfriction/configs``), else the source checkout's ``configs/``."""
    env = os.environ.get("DFO_CONFIGS")
    if env:
        return Path(env)
    packaged = package_dir() / "configs"
    if packaged.is_dir():
        return packaged
    root = source_root()
    return root / "configs" if root is not None else packaged
