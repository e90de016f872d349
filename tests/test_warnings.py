"""What a user reads: the FMUs' warnings reach Python and the command line, errors are one line,
a transient says it is one, and a frequency that cannot be computed does not end its sweep."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from dryfriction import DryFrictionWarning, Oscillator
from dryfriction.cli import main
from dryfriction.fmu import OscillatorFMU, Settings

# the default oscillator (m = 1 kg, k = 100 N/m, omega = 5 rad/s): its shortest period is the natural one
T_NAT = 2 * math.pi / 10.0
COARSE = Settings(h=T_NAT / 2)  # two internal steps per natural period: far too coarse


def _fmu_messages(caught: list[warnings.WarningMessage]) -> list[str]:
    return [str(w.message) for w in caught if issubclass(w.category, DryFrictionWarning)]


def test_a_coarse_step_is_a_python_warning_with_the_fmus_sentence(fmu: OscillatorFMU) -> None:
    p = Oscillator()
    with pytest.warns(DryFrictionWarning) as caught:
        fmu.start(p, COARSE)
    said = _fmu_messages(list(caught))
    assert len(said) == 1, said
    # the FMU's own sentence, with the step to choose: 1/1000 of the natural period
    assert "takes only 2 internal steps per 0.628319 s" in said[0]
    assert f"Choose h <= {T_NAT / 1000:.6g} s" in said[0]


def test_a_resolved_step_warns_nothing(fmu: OscillatorFMU) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", DryFrictionWarning)
        fmu.start(Oscillator(), Settings(h=T_NAT / 2000))
        fmu.step_to(1.0)


def test_the_error_filter_turns_the_warning_into_an_exception(fmu: OscillatorFMU) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", DryFrictionWarning)
        with pytest.raises(DryFrictionWarning, match="internal steps per"):
            fmu.start(Oscillator(), COARSE)


def test_fmi3_and_chain_warnings_are_the_same_category(chain_fmu2: Path, chain_fmu3: Path) -> None:
    from dryfriction.chain import ChainFMU, ChainFMU2
    from dryfriction.fmi3 import FMI3Oscillator

    with pytest.warns(DryFrictionWarning, match="internal steps per 0.628319 s"):
        FMI3Oscillator({"h": T_NAT / 2}).close()
    for make in (lambda: ChainFMU(2, fmu_path=chain_fmu3), lambda: ChainFMU2(fmu_path=chain_fmu2)):
        with pytest.warns(DryFrictionWarning, match="internal steps per"):
            with make() as chain:
                r = chain.run(0.05, 0.01, {"k": 1e5, "h": 1e-3})
        assert np.all(np.isfinite(r.x))


@pytest.mark.slow
def test_warnings_on_dask_workers_reach_the_client(fmu_path: Path) -> None:
    from dryfriction.response import frequency_response

    p = Oscillator.physical(m=1, k=100, P0=1, f=1, N=0.5, mu_s=0.3)
    with pytest.warns(DryFrictionWarning) as caught:
        ds = frequency_response(p, [0.8, 1.2], scheme="located", h=T_NAT / 2, min_periods=4, max_periods=8,
                                workers=1, fmu_path=fmu_path)
    said = _fmu_messages(list(caught))
    assert said and all("internal steps per" in m for m in said)
    assert len(said) == len(set(said))  # each sentence once
    assert np.all(np.isfinite(ds["amplitude_m"].values))


# ---- the command line -----------------------------------------------------------------------------

SWEEP = ["run", "--scene", "sweep", "--periods", "3"]


def test_cli_prints_the_fmus_warning_as_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(SWEEP + ["--steps-per-period", "2"]) == 0
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("dryfriction: warning: fmi2ExitInitializationMode: h = "), cap.err
    assert "Choose h <=" in lines[0]
    assert json.loads(cap.out)["amplitude"] > 0  # the result is still printed


def test_cli_strict_makes_the_warning_an_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(SWEEP + ["--steps-per-period", "2", "--strict"]) == 2
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("dryfriction: error: ") and "internal steps per" in lines[0]
    assert cap.out == ""


def test_cli_an_error_the_fmu_reports_is_one_line_and_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    # 31 periods of 1.26 s in steps of 1e-12 s: beyond the FMU's work bound for a Bossak scheme
    assert main(SWEEP + ["--h", "1e-12"]) == 2
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("dryfriction: error: ") and "internal steps of h" in lines[0]
    assert cap.out == ""


def test_run_sweep_says_it_measured_a_transient(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--scene", "sweep", "--periods", "12", "--scheme", "exact"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["scheme"] == "exact" and res["h_used"]["unit"] == "s"
    assert (res["window_start_period"], res["window_periods"], res["run_periods"]) == (12.0, 1.0, 13.0)
    assert "periods 12 to 13" in res["measured"] and "dryfriction response" in res["measured"]
    # the window really is period 13 of one run from rest: the extremes of a sampled trajectory
    p = Oscillator()
    with OscillatorFMU() as f:
        full = f.trajectory(p, np.linspace(0.0, 13 * p.period, 13 * 2000 + 1), Settings(scheme="exact"))
    window = full["x"][12 * 2000:]
    assert res["x_max"] == pytest.approx(window.max(), rel=1e-6)
    assert res["x_min"] == pytest.approx(window.min(), rel=1e-6)
    early = full["x"][11 * 2000:12 * 2000 + 1]  # the period before differs: it is a transient
    assert abs(early.max() - window.max()) > 1e-6 * abs(window.max())


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


def test_one_point_that_cannot_be_computed_does_not_end_the_sweep(fmu_path: Path, tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    from dryfriction.response import frequency_response, steady_state

    # a 1.6 kHz oscillator on the located scheme (h derived: 1/1000 of its period): at 0.001 Hz the
    # shortest run (4 periods, 4000 s) takes 6e9 internal steps, beyond the FMU's bound
    p = Oscillator.physical(m=0.01, k=0.01 * (2 * math.pi * 1600) ** 2, P0=1, f=10, N=0.5, mu_s=0.3, zeta=0.01)
    ds = frequency_response(p, [0.001, 10.0], scheme="located", min_periods=4, max_periods=8, fmu_path=fmu_path)
    amp, reason = ds["amplitude_m"].values, ds["reason"].values
    assert math.isnan(amp[0]) and not bool(ds["converged"].values[0])
    assert "internal steps" in reason[0]
    assert reason[1] == "" and amp[1] > 0
    with OscillatorFMU(fmu_path) as f:
        ref = steady_state(f, p.with_(omega=2 * math.pi * 10.0), min_periods=4, max_periods=8,
                           settings=Settings(h=0.0, scheme="located"))
    assert amp[1] == ref.amplitude
    # the command line: the row says why, the table goes on, exit 0
    argv = ["response", "--m", "0.01", "--k", repr(0.01 * (2 * math.pi * 1600) ** 2), "--zeta", "0.01", "--P0", "1",
            "--N", "0.5", "--mu-s", "0.3", "--f-start", "0.001", "--f-stop", "10", "--num", "2", "--scheme", "located",
            "--min-periods", "4", "--max-periods", "8", "--out", str(tmp_path), "--format", "csv", "--no-plot",
            "--no-progress", "--fmu", str(fmu_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "not computed: " in out and "1 not computed" in out
    import csv

    rows = list(csv.DictReader((tmp_path / "response.csv").open()))
    assert rows[0]["amplitude_m"] == "nan" and "internal steps" in rows[0]["reason"]
    assert float(rows[1]["amplitude_m"]) == pytest.approx(ref.amplitude, rel=1e-9) and rows[1]["reason"] == ""


def test_console_script_warning_is_one_stderr_line(tmp_path: Path) -> None:
    exe = Path(sys.executable).with_name("dryfriction")
    env = {**os.environ, "PYTHONWARNINGS": ""}
    r = subprocess.run([str(exe), *SWEEP, "--steps-per-period", "2"], capture_output=True, text=True, cwd=tmp_path,
                       env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("dryfriction: warning: "), r.stderr


def test_the_readmes_error_line_is_the_one_printed(capsys: pytest.CaptureFixture[str]) -> None:
    import re

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    quoted = re.findall(r"`(dryfriction: error: [^`]+)`", readme)
    assert quoted, "the README quotes an error line"
    for line in quoted:
        m = re.fullmatch(r"dryfriction: error: --m must be > 0, not (\S+)", line)
        assert m, f"a quoted error line without a command here to check it: {line}"
        assert main(["run", "--m", m.group(1), "--k", "1", "--P0", "1", "--f", "1", "--N", "1", "--mu-s", "0.1"]) == 2
        assert capsys.readouterr().err.strip() == line


@pytest.mark.parametrize("command", [["study", "list"], ["scenes"], ["run", "--scene", "sweep"]])
def test_an_unusable_fmu_option_is_refused_before_any_work(command: list[str], tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    import zipfile

    bogus = tmp_path / "notes.fmu"
    bogus.write_text("not an archive")
    empty = tmp_path / "empty.fmu"
    with zipfile.ZipFile(empty, "w") as z:
        z.writestr("readme.txt", "no model description")
    for path, words in ((bogus, "is not an FMU (not a zip archive)"), (empty, "no modelDescription.xml")):
        assert main(["--fmu", str(path), *command]) == 2
        cap = capsys.readouterr()
        lines = cap.err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("dryfriction: error: ") and words in lines[0], cap.err
        assert cap.out == ""


def test_a_free_mass_responds_by_the_exact_scheme(fmu_path: Path) -> None:
    """k = 0: the response's default is the exact scheme (closed form), equal to the located scheme
    at a fine step within its error (second order: 1e-6 relative at T/4000)."""
    from dryfriction.response import frequency_response

    p = Oscillator.physical(m=1, k=0, c=0.5, P0=1, f=1, N=0.5, mu_s=0.3, mu_k=0.2)
    ex = frequency_response(p, [0.5, 2.0], min_periods=8, max_periods=64, fmu_path=fmu_path)
    assert ex.attrs["scheme"] == "exact" and np.all(ex["converged"].values)
    lo = frequency_response(p, [0.5, 2.0], scheme="located", h=1 / 2.0 / 4000, min_periods=8, max_periods=64,
                            fmu_path=fmu_path)
    np.testing.assert_allclose(ex["amplitude_m"].values, lo["amplitude_m"].values, rtol=1e-5)
    assert np.all(ex["amplitude_m"].values > 0)
