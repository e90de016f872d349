"""`dryfriction response`: the JSON object, the files it writes (and only with --out), and the sentence
for a resonance that never converges; both methods (orbit, the default, and transient)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import pytest

from dryfriction.cli import main

ENGINEER = ["--m", "0.5", "--k", "2000", "--zeta", "0.003", "--P0", "10", "--N", "20", "--mu-s", "0.3", "--mu-k", "0.2",
            "--f-start", "5", "--f-stop", "15", "--num", "5"]


def test_response_json_on_the_engineer_example(fmu_path: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """The orbit method: one stable orbit per frequency, 0.23557 m at 10 Hz (the transient method's
    0.2356 m), stuck 23 % of the time at 5 Hz; the CSV one row per orbit."""
    argv = ["response", *ENGINEER, "--json", "--out", str(tmp_path), "--fmu", str(fmu_path)]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["method"] == "orbit" and res["f_hz"] == [5.0, 7.5, 10.0, 12.5, 15.0]
    assert all(res["converged"]) and res["n_orbits"] == [1] * 5
    orbits = [o[0] for o in res["orbits"]]
    assert all(o["stable"] and o["period"] == 1 and o["mu_max"] < 1 for o in orbits)
    assert orbits[2]["amplitude_m"] == pytest.approx(0.23557, rel=1e-4)
    assert orbits[0]["stick_fraction"] == pytest.approx(0.2324, abs=1e-3) and orbits[2]["stick_fraction"] == 0.0
    assert res["units"]["amplitude_m"] == "m"
    for name in ("response.csv", "response.nc", "response.png"):
        assert (tmp_path / name).stat().st_size > 0
    rows = list(csv.DictReader((tmp_path / "response.csv").open()))
    assert len(rows) == 5 and rows[2]["stable"] == "true" and rows[2]["orbit"] == "0"
    assert float(rows[2]["amplitude_m"]) == pytest.approx(orbits[2]["amplitude_m"], rel=1e-9)
    import xarray as xr

    with xr.open_dataset(tmp_path / "response.nc") as ds:
        assert ds["amplitude_m"].dims == ("f_hz", "orbit")
        assert float(ds["amplitude_m"].values[2, 0]) == orbits[2]["amplitude_m"]


def test_response_transient_method_keeps_its_columns(fmu_path: Path, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["response", "--method", "transient", *ENGINEER, "--json", "--out", str(tmp_path), "--fmu", str(fmu_path)]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    assert all(res["converged"]) and len(res["amplitude_m"]) == 5 and len(res["stick_fraction"]) == 5
    assert res["amplitude_m"][2] == pytest.approx(0.23557, rel=1e-4)
    assert res["stick_fraction"][0] > 0.1 and res["stick_fraction"][2] == 0.0
    rows = (tmp_path / "response.csv").read_text().splitlines()
    assert rows[0].startswith("f_hz,amplitude_m,offset_m,stick_fraction,converged") and len(rows) == 6


def test_response_says_when_the_resonance_never_converges(fmu_path: Path, tmp_path: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    """Undamped at resonance with 4 mu_k N < pi P0: no orbit (the orbit method) and not converged (the
    transient method), with the sentence."""
    f_n = 10 / (2 * math.pi)
    argv = ["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3", "--f-start", str(f_n),
            "--f-stop", str(f_n), "--num", "1", "--max-periods", "256", "--format", "csv", "--no-plot",
            "--out", str(tmp_path), "--fmu", str(fmu_path)]
    assert main(argv + ["--method", "transient"]) == 0
    out = capsys.readouterr().out
    assert "0 of 1 converged" in out and "never converges" in out
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "no orbit found" in out and "0 of 1 with a stable orbit" in out and "never converges" in out


RESPONSE = ["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "0.5", "--mu-s", "0.3",
            "--f-start", "1", "--f-stop", "2", "--num", "2", "--min-periods", "4", "--max-periods", "8",
            "--no-progress"]


@pytest.mark.parametrize("method", ["orbit", "transient"])
def test_response_json_writes_only_to_stdout(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                             monkeypatch: pytest.MonkeyPatch, method: str) -> None:
    monkeypatch.chdir(tmp_path)
    argv = RESPONSE + ["--method", method]
    assert main(argv + ["--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["files"] == [] and list(tmp_path.iterdir()) == []
    assert res["scheme"] == "exact" and res["reason"] == [None, None]
    amps = res["amplitude_m"] if method == "transient" else [o["amplitude_m"] for f in res["orbits"] for o in f]
    assert amps and all(a > 0 for a in amps)
    assert main(argv + ["--json", "--out", "r", "--format", "csv", "--no-plot"]) == 0
    res2 = json.loads(capsys.readouterr().out)
    assert res2["files"] == ["r/response.csv"] and (tmp_path / "r" / "response.csv").is_file()
    assert res2.get("amplitude_m") == res.get("amplitude_m") and res2.get("orbits") == res.get("orbits")


def test_response_method_errors(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(RESPONSE + ["--method", "orbit", "--scheme", "located"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["dryfriction: error: --method orbit needs the exact scheme, not --scheme located "
                   "(or --method transient)"]
    assert main(RESPONSE + ["--method", "fourier"]) == 2
    assert "--method" in capsys.readouterr().err
