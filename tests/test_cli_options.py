"""The command line's options and small commands: the global options (--fmu, --strict) before or
after the subcommand, --fmu for every subcommand, the console script, --version, and `lyapunov`
(its JSON; its one-line errors)."""

from __future__ import annotations

import json
import subprocess
import sys
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


@pytest.mark.slow
@pytest.mark.min_versions
def test_console_script_study_list(fmu_path: Path) -> None:
    exe = Path(sys.executable).with_name("dryfriction")
    r = subprocess.run([str(exe), f"--fmu={fmu_path}", "study", "list"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "fig8_9" in r.stdout


# ---------------------------------------------------------------------------------- small commands


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    import dryfriction

    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.strip() == f"dryfriction {dryfriction.__version__}"


def test_lyapunov_cli_json_and_errors(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["lyapunov", "--lam", "0.5", "--mu-s-sigma", "0.6", "--chi", "1.0", "--z0", "0.3",
                     "--dz0", "-0.2", "--periods", "50", "--transient", "20", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["periods"] == 50 and d["scheme"] == "exact" and d["stroboscopic_period"] == 1
    assert d["map"] == "FMU" and d["steps_per_period"] is None             # h has no effect on exact
    assert d["lyapunov_per_period"] < -1.0
    assert d["lyapunov_per_second"] == pytest.approx(d["lyapunov_per_period"] / d["period_s"])
    assert main(["lyapunov", "--lam", "0.5", "--mu-s-sigma", "0.6", "--chi", "1.0", "--z0", "0.3",
                     "--dz0", "-0.2", "--periods", "50", "--transient", "20", "--scheme", "located", "--json"]) == 0
    dl = json.loads(capsys.readouterr().out)
    assert dl["scheme"] == "located" and dl["steps_per_period"] == 1000
    assert dl["lyapunov_per_period"] == pytest.approx(d["lyapunov_per_period"], abs=1e-3)
    for bad in (["--chi", "-1"], ["--chi", "0.5", "--d0", "0.5"], ["--chi", "0.5", "--scheme", "euler"],
                ["--chi", "nan"], ["--chi", "0.5", "--periods", "40", "--renorm", "50"]):
        assert main(["lyapunov", "--lam", "0.5", "--mu-s-sigma", "0.6", *bad]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("dryfriction: error:") and "\n" not in err
