"""`dryfriction response`: the JSON object, the files it writes (and only with --out), and the sentence
for a resonance that never converges."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from dryfriction.cli import main


def test_response_json_on_the_engineer_example(fmu_path: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["response", "--m", "0.5", "--k", "2000", "--zeta", "0.003", "--P0", "10", "--N", "20", "--mu-s", "0.3",
            "--mu-k", "0.2", "--f-start", "5", "--f-stop", "15", "--num", "5", "--json", "--out", str(tmp_path),
            "--fmu", str(fmu_path)]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["f_hz"] == [5.0, 7.5, 10.0, 12.5, 15.0]
    assert all(res["converged"]) and len(res["amplitude_m"]) == 5 and len(res["stick_fraction"]) == 5
    assert res["amplitude_m"][2] == pytest.approx(0.23557, rel=1e-4)
    assert res["stick_fraction"][0] > 0.1 and res["stick_fraction"][2] == 0.0
    assert res["units"]["amplitude_m"] == "m"
    for name in ("response.csv", "response.nc", "response.png"):
        assert (tmp_path / name).stat().st_size > 0
    rows = (tmp_path / "response.csv").read_text().splitlines()
    assert rows[0].startswith("f_hz,amplitude_m,offset_m,stick_fraction,converged") and len(rows) == 6


def test_response_says_when_the_resonance_never_converges(fmu_path: Path, tmp_path: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    f_n = 10 / (2 * math.pi)
    argv = ["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3", "--f-start", str(f_n),
            "--f-stop", str(f_n), "--num", "1", "--max-periods", "256", "--format", "csv", "--no-plot",
            "--out", str(tmp_path), "--fmu", str(fmu_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "0 of 1 converged" in out and "never converges" in out


RESPONSE = ["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "0.5", "--mu-s", "0.3",
            "--f-start", "1", "--f-stop", "2", "--num", "2", "--min-periods", "4", "--max-periods", "8",
            "--no-progress"]


def test_response_json_writes_only_to_stdout(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(RESPONSE + ["--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["files"] == [] and list(tmp_path.iterdir()) == []
    assert res["scheme"] == "exact" and res["reason"] == [None, None]
    assert all(a > 0 for a in res["amplitude_m"])
    assert main(RESPONSE + ["--json", "--out", "r", "--format", "csv", "--no-plot"]) == 0
    res2 = json.loads(capsys.readouterr().out)
    assert res2["files"] == ["r/response.csv"] and (tmp_path / "r" / "response.csv").is_file()
    assert res2["amplitude_m"] == res["amplitude_m"]
