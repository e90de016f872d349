"""The examples in examples/ run (quick sizes) and check themselves (each exits non-zero when its
own check fails)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.slow
@pytest.mark.parametrize("name, args", [
    ("frequency_sweep.py", ["--num", "3"]),
    ("cosimulation.py", ["--periods", "20"]),
    ("rollback.py", []),
    ("split_chain.py", ["--periods", "4"]),
    ("friction_pendulum.py", []),
    ("beam_friction_damper.py", ["--quick"]),
    ("two_mass_jenkins.py", ["--quick"]),
])
def test_example_runs(name: str, args: list[str], fmu_path: Path, tmp_path: Path) -> None:
    if name in ("frequency_sweep.py", "friction_pendulum.py", "beam_friction_damper.py", "two_mass_jenkins.py"):
        args = [*args, "--out", str(tmp_path)]
    env = {**os.environ, "DFO_FMU": str(fmu_path), "MPLBACKEND": "Agg"}
    if name in ("beam_friction_damper.py", "two_mass_jenkins.py") and "DFO_SYSTEM_FMU3" not in env:
        env["DFO_SYSTEM_FMU3"] = str(Path(__file__).resolve().parents[1] / "build" / "fmi3" / "DryFrictionSystem.fmu")
    r = subprocess.run([sys.executable, str(EXAMPLES / name), *args], capture_output=True, text=True, timeout=300,
                       env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    if name == "frequency_sweep.py":
        assert "converged" in r.stdout and (tmp_path / "sweep.png").stat().st_size > 0
    if name == "rollback.py":
        assert "bit-identical: True" in r.stdout
    if name == "split_chain.py":
        assert "inputs hold" in r.stdout and "inputs extrapolate" in r.stdout
    if name == "friction_pendulum.py":
        assert "5 events" in r.stdout and ": stuck" in r.stdout and (tmp_path / "pendulum.png").stat().st_size > 0
    if name == "beam_friction_damper.py":  # its own checks: the closed forms of N = 0 and of the stuck damper
        assert "checks: pass" in r.stdout and (tmp_path / "beam_friction_damper.png").stat().st_size > 0
    if name == "two_mass_jenkins.py":  # its own checks: the two linear limits' closed forms, the minimum inside
        assert "checks: pass" in r.stdout and (tmp_path / "two_mass_jenkins.png").stat().st_size > 0


def test_examples_are_all_tested() -> None:
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == ["beam_friction_damper.py", "cosimulation.py",
                                                             "frequency_sweep.py", "friction_pendulum.py",
                                                             "rollback.py", "split_chain.py", "two_mass_jenkins.py"]
