"""`dryfriction run`: what it prints (parameters and results with their units, the scheme and the step
used) and what it measured (a transient's window, said so)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from dryfriction.cli import main
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator


def test_run_in_physical_units_labels_its_output(fmu_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["run", "--scene", "sweep", "--m", "0.5", "--k", "2000", "--zeta", "0.003", "--P0", "10", "--f", "13",
            "--N", "20", "--mu-s", "0.3", "--mu-k", "0.2", "--h", "0", "--periods", "60", "--fmu", str(fmu_path)]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["units"]["amplitude"] == "m" and res["parameters"]["k"] == {"value": 2000.0, "unit": "N/m"}
    assert res["parameters"]["mu_k"]["value"] == pytest.approx(0.2)
    assert res["h_used"]["value"] == pytest.approx(2 * math.pi / (2 * math.pi * 13) / 1000, rel=1e-12)
    assert res["amplitude"] == pytest.approx(0.0061628, rel=1e-3)


def test_run_sweep_says_it_measured_a_transient(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--scene", "sweep", "--periods", "12", "--scheme", "exact"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["scheme"] == "exact" and res["h_used"]["unit"] == "s"
    assert (res["window_start_period"], res["window_periods"], res["run_periods"]) == (12.0, 1.0, 13.0)
    assert "periods 12 to 13" in res["measured"] and "dryfriction response" in res["measured"]
    # the window really is period 13 of one run from rest: the extremes of a sampled trajectory
    p = Oscillator()
    with OscillatorFMU2() as f:
        full = f.trajectory(p, np.linspace(0.0, 13 * p.period, 13 * 2000 + 1), Settings(scheme="exact"))
    window = full["x"][12 * 2000:]
    assert res["x_max"] == pytest.approx(window.max(), rel=1e-6)
    assert res["x_min"] == pytest.approx(window.min(), rel=1e-6)
    early = full["x"][11 * 2000:12 * 2000 + 1]  # the period before differs: it is a transient
    assert abs(early.max() - window.max()) > 1e-6 * abs(window.max())
