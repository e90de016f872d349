"""The command line (``dryfriction``) and the declared requirements of the package."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from dryfriction.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.min_versions
@pytest.mark.parametrize("argv", [
    ["--fmu={fmu}", "study", "list"],
    ["--fmu", "{fmu}", "study", "list"],
    ["study", "list", "--fmu", "{fmu}"],
    ["study", "--fmu={fmu}", "list"],
])
def test_study_accepts_the_global_options_before_or_after(argv: list[str], fmu_path: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    assert main([a.format(fmu=fmu_path) for a in argv]) == 0
    out = capsys.readouterr().out
    for name in ("fig2", "fig3", "fig8_9", "fig12_14"):
        assert name in out


@pytest.mark.parametrize("argv", [["--fmu", "{fmu}", "scenes"], ["scenes", "--fmu", "{fmu}"]])
def test_every_subcommand_accepts_fmu(argv: list[str], fmu_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([a.format(fmu=fmu_path) for a in argv]) == 0
    assert "sweep" in capsys.readouterr().out


def test_run_uses_the_given_fmu_after_the_subcommand(fmu_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--scene", "sweep", "--periods", "3", "--fmu", str(fmu_path)]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["x_max"] > res["x_min"] and "friction" in res["effects"]


@pytest.mark.parametrize("argv, words", [
    (["--fmu", "/nonexistent.fmu", "study", "list"], "--fmu: no such file"),
    (["study", "fig99"], "unknown study"),
    (["study", "fig3", "--set", "numerics.alpha=0.5"], "numerics.alpha"),
    (["run", "--scheme", "fast"], "invalid choice"),
    (["bogus"], "invalid choice"),
])
def test_bad_arguments_are_one_line_and_exit_2(argv: list[str], words: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.min_versions
def test_console_script_study_list(fmu_path: Path) -> None:
    exe = Path(sys.executable).with_name("dryfriction")
    r = subprocess.run([str(exe), f"--fmu={fmu_path}", "study", "list"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "fig8_9" in r.stdout


# --------------------------------------------------------------------------- declared requirements


def _lower_bound(spec: str) -> tuple[int, ...]:
    m = re.search(r">=\s*([0-9.]+)", spec)
    assert m, spec
    return tuple(int(x) for x in m.group(1).split("."))


def _sources() -> str:
    files = [*ROOT.joinpath("src").rglob("*.py"), *ROOT.joinpath("tests").glob("*.py"),
             *ROOT.joinpath("bench").glob("*.py"), *ROOT.joinpath("scripts").glob("*.py")]
    return "\n".join(f.read_text() for f in files if f.name != Path(__file__).name)


def test_declared_minimums_cover_what_the_code_uses() -> None:
    """requires-python and the numpy minimum allow nothing the code cannot run on: tomllib needs
    Python 3.11, np.trapezoid NumPy 2.0 (the full check: scripts/check_min_versions.sh)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    text = _sources()
    if re.search(r"^\s*(import tomllib|from tomllib)", text, re.M):
        assert _lower_bound(project["requires-python"]) >= (3, 11)
    numpy = next(d for d in project["dependencies"] if re.match(r"numpy\b", d))
    if "np.trapezoid(" in text:
        assert _lower_bound(numpy) >= (2, 0)
    deps = {re.match(r"[A-Za-z0-9_.-]+", d).group(0).lower() for d in project["dependencies"]}
    assert "tomli-w" in deps  # the config writer
