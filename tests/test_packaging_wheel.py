"""The package outside its repository: the wheel built from this checkout (scikit-build-core runs
the CMake build) carries the four FMUs, and installed into a fresh virtual environment in a
temporary folder, with no repository around it and no DFO_* variable set, its commands and the
README's "Five lines of Python" work and print real numbers.

Slow (a CMake build of the FMUs and an install of the dependencies): ``-m "not slow"`` skips it.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

from dryfriction import paths as locate

ROOT = Path(__file__).resolve().parents[1]
KINDS = {f"dryfriction/fmus/{k.relpath}": k for k in locate.KINDS}
#: the binaries folder of this platform in an FMI 2.0 and an FMI 3.0 FMU (the tests run on x86-64 Linux)
NATIVE = {"2.0": "binaries/linux64", "3.0": "binaries/x86_64-linux"}

pytestmark = [pytest.mark.slow,
              pytest.mark.no_sanitizer]  # builds and runs a separate, non-instrumented package


def _clean_env() -> dict[str, str]:
    """The environment without anything that points back into the repository."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("DFO_") and k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env["MPLBACKEND"] = "Agg"
    return env


def _run(cmd: list[str], cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    r = subprocess.run(cmd, cwd=cwd, env=_clean_env(), capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, f"{' '.join(cmd)} exited {r.returncode}:\n{r.stdout[-2000:]}\n{r.stderr[-4000:]}"
    assert "Traceback" not in r.stderr, r.stderr
    return r


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("wheelhouse")
    _run([sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "--quiet", "--wheel-dir", str(out)],
         cwd=out, timeout=900)
    wheels = list(out.glob("dryfriction-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="module")
def venv(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fresh virtual environment outside the repository with the wheel (and its dependencies
    from the index) installed; returns its bin/ folder. The install is uv's (from its cache, as
    scripts/setup.sh's: seconds) where this environment has uv, else the fresh venv's pip."""
    env_dir = tmp_path_factory.mktemp("fresh") / "venv"
    assert ROOT not in env_dir.parents
    _run([sys.executable, "-m", "venv", str(env_dir)], cwd=env_dir.parent)
    bin_dir = env_dir / "bin"
    if subprocess.run([sys.executable, "-m", "uv", "--version"], capture_output=True).returncode == 0:
        install = [sys.executable, "-m", "uv", "pip", "install", "--python", str(bin_dir / "python")]
    else:
        install = [str(bin_dir / "python"), "-m", "pip", "install"]
    _run([*install, "--quiet", str(wheel)], cwd=env_dir.parent, timeout=900)
    return bin_dir


@pytest.fixture()
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("work")
    assert not (d / "pyproject.toml").exists() and ROOT not in d.parents
    return d


def test_the_wheel_carries_the_four_fmus(wheel: Path, tmp_path: Path) -> None:
    """Each FMU in the wheel is the right model and FMI version, with this platform's binary."""
    assert re.fullmatch(r"dryfriction-[0-9.]+-py3-none-[a-z0-9_]+\.whl", wheel.name), wheel.name
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        assert set(KINDS) <= names, sorted(n for n in names if n.endswith(".fmu"))
        assert {f"dryfriction/configs/{p.name}" for p in (ROOT / "configs").glob("*.toml")} <= names
        assert "dryfriction/paths.py" in names and not any("__pycache__" in n for n in names)
        for name, kind in KINDS.items():
            data = z.read(name)
            path = tmp_path / Path(name).name
            path.write_bytes(data)
            assert locate.check_fmu(path, kind) == path  # the model identifier and FMI version
            inner = zipfile.ZipFile(io.BytesIO(data)).namelist()
            assert f"{NATIVE[kind.fmi_version]}/{kind.model_identifier}.so" in inner, (name, inner)
            assert any(n.startswith("sources/") and n.endswith(".c") for n in inner), name


def test_version_in_a_fresh_venv(venv: Path, workdir: Path) -> None:
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    r = _run([str(venv / "dryfriction"), "--version"], cwd=workdir)
    assert r.stdout.strip() == f"dryfriction {version}"


def test_the_fmus_come_from_the_package_data(venv: Path, workdir: Path) -> None:
    code = ("from dryfriction import locate\n"
            "print(locate.source_root())\n"
            "for k in locate.KINDS: print(locate.fmu_path(k))\n")
    lines = _run([str(venv / "python"), "-c", code], cwd=workdir).stdout.split()
    assert lines[0] == "None"  # no repository around the installed package
    site = venv.parent / "lib"
    for line, kind in zip(lines[1:], locate.KINDS, strict=True):
        path = Path(line)
        assert site in path.parents and path.as_posix().endswith(f"dryfriction/fmus/{kind.relpath}"), line


def test_response_json_in_a_fresh_venv(venv: Path, workdir: Path) -> None:
    """One frequency of the README's oscillator: its amplitude at 10 Hz, 0.2356 m, converged."""
    r = _run([str(venv / "dryfriction"), "response", "--m", "0.5", "--k", "2000", "--zeta", "0.003", "--P0", "10",
              "--N", "20", "--mu-s", "0.3", "--mu-k", "0.2", "--f-start", "10", "--f-stop", "10", "--num", "1",
              "--json", "--no-plot", "--format", "csv", "--out", str(workdir / "out")], cwd=workdir)
    data = json.loads(r.stdout)
    assert data["method"] == "orbit" and data["converged"] == [True] and data["f_hz"] == [10.0]
    (orbits,) = data["orbits"]
    (o,) = [o for o in orbits if o["stable"]]
    a = o["amplitude_m"]
    assert math.isfinite(a) and a > 0 and round(a, 4) == 0.2356, a
    assert 0.0 <= o["stick_fraction"] < 1.0 and o["residual"] <= 1e-12 and o["mu_max"] < 1.0


def test_study_list_in_a_fresh_venv(venv: Path, workdir: Path) -> None:
    r = _run([str(venv / "dryfriction"), "study", "list"], cwd=workdir)
    for name in ("fig2", "fig8_9", "chaos_scan", "chain2", "chain_waves"):
        assert re.search(rf"^{name}\s", r.stdout, re.M), (name, r.stdout)


def _readme_snippet() -> str:
    """The python block under the README's "Five lines of Python" heading, as printed there."""
    text = (ROOT / "README.md").read_text()
    section = text.split("\n## Five lines of Python\n", 1)[1]
    m = re.search(r"```python\n(.*?)```", section, re.S)
    assert m, "README: no python block under 'Five lines of Python'"
    return m.group(1)


def test_the_readmes_five_lines_in_a_fresh_venv(venv: Path, workdir: Path) -> None:
    """The snippet prints the table its comment promises: every orbit per frequency; at 10 Hz one,
    0.2356 m, stable."""
    code = _readme_snippet()
    assert len(code.strip().splitlines()) == 5
    out = _run([str(venv / "python"), "-c", code], cwd=workdir).stdout
    num = r"([0-9.eE+-]+)"
    rows = [(float(m.group(1)), int(m.group(2)), float(m.group(3)), m.group(4), float(m.group(5)),
             float(m.group(6)))
            for m in re.finditer(rf"^\s*([0-9.]+)\s+(\d+)\s+{num}\s+(True|False)\s+{num}\s+{num}\s*$", out, re.M)]
    assert sorted({r[0] for r in rows}) == [5.0, 7.5, 10.0, 12.5, 15.0], out
    at10 = [r for r in rows if r[0] == 10.0]   # stable: a bool (printed True), not a float
    assert len(at10) == 1 and round(at10[0][2], 4) == 0.2356 and at10[0][3] == "True" and at10[0][4] < 1.0, out
    assert all(math.isfinite(r[2]) and r[2] > 0 and 0.0 <= r[5] <= 1.0 for r in rows), out
