"""Every FMU rebuilds from its own sources/, the way a host does, to the shipped binary's numbers.

For each of the four FMUs, on an unzipped copy without its binaries:

- the source list (FMI 2.0 ``<SourceFiles>``, FMI 3.0 ``sources/buildDescription.xml``) names
  exactly the ``.c`` files of ``sources/`` (so ``sources/*.c`` is the list), and the FMI 2.0 chain's
  ``n`` is in its generated ``sources/chain_config.h``;
- ``fmpy compile`` (the command of docs/platforms.md: ``fmpy.build.build_platform_binary``, fmpy's CMake
  project over the listed sources with its own flags, here with all warnings as errors) gives a
  binary whose outputs are the shipped one's bit for bit, on several parameter sets of every scheme
  (the FMI 3.0 FMUs also with early return and event mode);
- so does the ``cc`` line of docs/platforms.md, run as written there;
- and a host compiling with fused multiply-add contraction on (``-O2 -mfma -ffp-contract=fast``,
  where the CPU has FMA): ``sources/dfo_fp.h`` keeps the numbers.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu

from dryfriction.drivers.chain import default_chain_fmu, default_chain_fmu3
from dryfriction.drivers.oscillator3 import default_fmi3_path
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings, default_fmu_path
from dryfriction.params import Oscillator


# the rebuilds of the four FMUs from their sources/ build with compilers (not run under the
# sanitizer's LD_PRELOAD), about a minute in all: each is marked no_sanitizer and slow

ROOT = Path(__file__).resolve().parents[1]
FMUS = {
    "fmi2-oscillator": default_fmu_path,
    "fmi2-chain": default_chain_fmu,
    "fmi3-oscillator": default_fmi3_path,
    "fmi3-chain": default_chain_fmu3,
}
# parameter sets (every scheme of the model), run by fmpy.simulate_fmu over the default experiment
RUNS = {
    "oscillator": [{}, {"scheme": 1, "c": 0.3, "chi": 0.5}, {"scheme": 2, "omega": 8.0, "x0": 0.01},
                   {"scheme": 4, "c": 0.2, "phi": 0.7, "v0": -0.1}, {"observe": False, "chi": 1.2, "h": 1e-3}],
    "chain": [{}, {"scheme": 1, "k_end": 50.0, "c_end": 0.1}, {"scheme": 2, "omega": 8.0, "h": 1e-3}],
}


def _platform_dir(fmi_version: str) -> str:
    import fmpy

    return fmpy.platform if fmi_version == "2.0" else fmpy.platform_tuple


def _has_fma() -> bool:
    try:
        return re.search(r"^flags\s*:.*\bfma\b", Path("/proc/cpuinfo").read_text(), flags=re.M) is not None
    except OSError:
        return False


def _readme_cc() -> list[str]:
    """The compiler call of docs/platforms.md (its rebuild listing), as words."""
    text = (ROOT / "docs" / "platforms.md").read_text()
    blocks = re.findall(r"```sh\n(.*?)```", text, flags=re.S)
    lines = [ln for b in blocks for ln in b.replace("\\\n", " ").splitlines()
             if ln.startswith("cc ") and "sources/*.c" in ln]
    assert len(lines) == 1, f"docs/platforms.md should list one cc line over sources/*.c, found {lines}"
    return shlex.split(lines[0].split("#")[0])


@pytest.fixture(scope="module")
def shipped(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Each FMU unzipped once (its shipped binaries)."""
    out = {}
    for key, where in FMUS.items():
        path = where()
        if not path.is_file():
            pytest.fail(f"FMU not built: {path} (cmake --build build)")
        out[key] = Path(extract(str(path), unzipdir=str(tmp_path_factory.mktemp(key))))
    return out


def _bare_copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    shutil.rmtree(dst / "binaries")
    return dst


def _listed_sources(unzipped: Path) -> list[str]:
    md = read_model_description(str(unzipped))
    if md.fmiVersion == "2.0":
        root = ET.parse(unzipped / "modelDescription.xml").getroot()
        return [f.get("name") for f in root.iterfind("CoSimulation/SourceFiles/File")]
    root = ET.parse(unzipped / "sources" / "buildDescription.xml").getroot()
    return [f.get("name") for f in root.iterfind("BuildConfiguration/SourceFileSet/SourceFile")]


@pytest.mark.no_sanitizer
@pytest.mark.slow
@pytest.mark.parametrize("key", list(FMUS))
def test_the_source_list_is_exactly_the_sources(shipped: dict[str, Path], key: str) -> None:
    d = shipped[key]
    listed = _listed_sources(d)
    assert len(listed) == len(set(listed))
    assert sorted(listed) == sorted(p.name for p in (d / "sources").glob("*.c")), key
    if key == "fmi2-chain":
        md = read_model_description(str(d))
        n = sum(1 for v in md.modelVariables if re.fullmatch(r"x\[\d+\]", v.name))
        cfg = (d / "sources" / "chain_config.h").read_text()
        assert re.search(rf"#define DFO_CHAIN_FIXED_N {n}\b", cfg), cfg
    elif key == "fmi3-chain":
        assert "#define DFO_CHAIN_FIXED_N" not in (d / "sources" / "chain_config.h").read_text()


BUILT = sorted(p.relative_to(ROOT / "build").as_posix() for d in ("build", "build/fmi3") for p in (ROOT / d).glob("*.fmu"))


@pytest.mark.parametrize("name", BUILT)
def test_every_fmu_lists_exactly_its_sources(tmp_path: Path, name: str) -> None:
    """Every FMU of the build (the example models' too): its source list names exactly the .c files
    of its sources/, so that a host compiling the list links."""
    d = Path(extract(str(ROOT / "build" / name), unzipdir=str(tmp_path)))
    listed = _listed_sources(d)
    assert len(listed) == len(set(listed)), name
    assert sorted(listed) == sorted(p.name for p in (d / "sources").glob("*.c")), name


def _outputs(unzipped: Path) -> list[str]:
    md = read_model_description(str(unzipped))
    return [v.name for v in md.modelVariables if v.causality == "output"]


def _same_bits(a: np.ndarray, b: np.ndarray, what: str) -> None:
    assert a.dtype.names == b.dtype.names and a.shape == b.shape, what
    for n in a.dtype.names:
        x, y = np.ascontiguousarray(a[n], dtype=float), np.ascontiguousarray(b[n], dtype=float)
        assert np.array_equal(x.view(np.int64), y.view(np.int64)), (
            f"{what}: {n} differs from the shipped binary's by up to {np.nanmax(np.abs(x - y)):.3g}")


def _compare(shipped_dir: Path, rebuilt: Path, key: str, how: str) -> None:
    model = "chain" if "chain" in key else "oscillator"
    names = _outputs(shipped_dir)
    options = [{}]
    if key.startswith("fmi3"):
        options.append({"early_return_allowed": True, "use_event_mode": True})
    for start in RUNS[model]:
        for opt in options:
            ref = simulate_fmu(str(shipped_dir), start_values=dict(start), output=names, output_interval=0.01, **opt)
            new = simulate_fmu(str(rebuilt), start_values=dict(start), output=names, output_interval=0.01, **opt)
            _same_bits(ref, new, f"{key} rebuilt by {how}, {start} {opt}")


@pytest.mark.no_sanitizer
@pytest.mark.slow
@pytest.mark.parametrize("key", list(FMUS))
def test_fmpy_compile_rebuilds_the_same_numbers(shipped: dict[str, Path], key: str, tmp_path: Path) -> None:
    """The `fmpy compile X.fmu` of docs/platforms.md (fmpy's command line, here with all warnings as errors) on
    the FMU without its binaries."""
    from fmpy.util import create_zip_archive

    env = dict(os.environ)
    if shutil.which("cmake") is None:  # the venv's cmake (a test dependency) beside its python
        env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    if shutil.which("cmake", path=env.get("PATH")) is None:
        pytest.skip("did not run: no cmake for fmpy's build")
    bare = _bare_copy(shipped[key], tmp_path / "bare")
    fmu = tmp_path / "rebuilt.fmu"
    create_zip_archive(fmu, bare)
    r = subprocess.run([sys.executable, "-m", "fmpy.cli", "compile", "--all-warnings", "--warning-as-error", str(fmu)],
                       capture_output=True, text=True, env=env, timeout=900)
    assert r.returncode == 0, f"fmpy compile failed: {(r.stdout + r.stderr)[-3000:]}"
    d = Path(extract(str(fmu), unzipdir=str(tmp_path / "rebuilt")))
    md = read_model_description(str(d))
    lib = d / "binaries" / _platform_dir(md.fmiVersion)
    assert lib.is_dir() and any(lib.iterdir()), f"fmpy compile built nothing into {lib}"
    _compare(shipped[key], d, key, "fmpy compile")


@pytest.mark.no_sanitizer
@pytest.mark.slow
@pytest.mark.parametrize("variant", ["readme", "fma"])
@pytest.mark.parametrize("key", list(FMUS))
def test_the_docs_cc_line_rebuilds_the_same_numbers(shipped: dict[str, Path], key: str, variant: str,
                                                      tmp_path: Path) -> None:
    if shutil.which("cc") is None:
        pytest.skip("did not run: no cc")
    if variant == "fma" and not _has_fma():
        pytest.skip("did not run: this CPU has no FMA instructions")
    d = _bare_copy(shipped[key], tmp_path / "fmu")
    md = read_model_description(str(d))
    words = _readme_cc()
    i = words.index("-o")
    out = Path("binaries") / _platform_dir(md.fmiVersion) / f"{md.coSimulation.modelIdentifier}.so"
    words[i + 1] = str(out)
    if variant == "fma":  # a host's own flags: contraction on, FMA instructions available
        words = [w for w in words if w != "-ffp-contract=off"] + ["-mfma", "-ffp-contract=fast"]
    (d / out.parent).mkdir(parents=True)
    cmd = " ".join(shlex.quote(w) if w != "sources/*.c" else w for w in words)  # the shell expands the glob
    r = subprocess.run(cmd, shell=True, cwd=d, capture_output=True, text=True)
    assert r.returncode == 0, f"{cmd}: {r.stderr[-2000:]}"
    assert r.stderr == "", r.stderr[-2000:]  # no warning either
    if variant == "fma":
        dis = subprocess.run(["objdump", "-d", str(d / out)], capture_output=True, text=True)
        if dis.returncode == 0:
            assert "vfmadd" not in dis.stdout and "vfmsub" not in dis.stdout, "fused multiply-adds in the binary"
    _compare(shipped[key], d, key, f"the cc line of docs/platforms.md ({variant})")


# ------------------------ the oscillator's source FMU, rebuilt by fmpy (also under the sanitizers)

@pytest.mark.slow
def test_source_fmu_rebuilds_with_fmpy(fmu_path: Path, fmu: OscillatorFMU2, tmp_path: Path,
                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """A host can rebuild the binary from sources/ (fmpy's CMake build) and gets the same numbers."""
    from fmpy import extract
    from fmpy.build import build_platform_binary

    unzip = Path(extract(str(fmu_path), unzipdir=str(tmp_path / "fmu")))
    shutil.rmtree(unzip / "binaries")
    (tmp_path / "build").mkdir()
    with monkeypatch.context() as m:  # CMake and the compiler without the sanitizers' preload (not our C)
        m.delenv("LD_PRELOAD", raising=False)
        build_platform_binary(unzip, build_dir=tmp_path / "build")
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as z:
        for f in unzip.rglob("*"):
            z.write(f, f.relative_to(unzip).as_posix())
    p = Oscillator()
    t = np.linspace(0, 4 * p.period, 81)
    with OscillatorFMU2(rebuilt) as other:
        a = other.trajectory(p, t, Settings(h=p.period / 500))
    b = fmu.trajectory(p, t, Settings(h=p.period / 500))
    for k in ("x", "v", "F_friction", "mode"):
        assert np.allclose(a[k], b[k], rtol=1e-12, atol=1e-15), k
