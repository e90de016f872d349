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


# ---------------------------------------------------------------------------------- help and lists


def _parsers() -> list[tuple[str, object]]:
    import argparse

    from dryfriction.cli.main import build_parser

    found = []

    def walk(p: argparse.ArgumentParser) -> None:
        found.append((p.prog, p))
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for sub in a.choices.values():
                    walk(sub)

    walk(build_parser())
    return found


def test_every_option_of_every_command_has_help() -> None:
    import argparse

    parsers = _parsers()
    assert {prog.split()[-1] for prog, _ in parsers} >= {"dryfriction", "validate", "run", "response", "scenes",
                                                         "lyapunov", "chain", "continuation", "bifurcation",
                                                         "orbit", "belt", "study"}
    missing = [f"{prog} {'/'.join(a.option_strings) or a.dest}" for prog, p in parsers
               for a in p._actions if not a.help or a.help == argparse.SUPPRESS]  # type: ignore[attr-defined]
    assert missing == []


def test_study_list_columns_are_aligned(capsys: pytest.CaptureFixture[str]) -> None:
    from dryfriction.studies import STUDIES

    assert main(["study", "list"]) == 0
    rows = capsys.readouterr().out.splitlines()
    head, table = rows[0], rows[1:1 + len(STUDIES)]
    figures, title = head.index("figures"), head.index("title")
    for row, (name, module) in zip(table, STUDIES.items()):
        assert row.startswith(name + " ")
        assert row[figures - 2:figures] == "  " and row[figures:].startswith(", ".join(module.FIGURES))
        assert row[title - 2:title] == "  " and row[title:] == module.TITLE
    assert any(len(n) > 9 for n in STUDIES)  # long names (burridge_knopoff) among them
    assert rows[-1].startswith("aliases: ")


# ---------------------------------------------------------------------------------- JSON

#: the keys that are booleans wherever a JSON object of the command line has them
BOOLEAN_KEYS = {"stable", "converged", "neutral", "coexists_with_steady_sliding"}


def _booleans(doc: object, path: str = "") -> list[tuple[str, object]]:
    """(path, value) of every value under a key of BOOLEAN_KEYS (each element of a list)."""
    out: list[tuple[str, object]] = []
    if isinstance(doc, dict):
        for k, v in doc.items():
            if k in BOOLEAN_KEYS:
                vals = v if isinstance(v, list) else [v]
                out += [(f"{path}.{k}", x) for x in vals]
            else:
                out += _booleans(v, f"{path}.{k}")
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _booleans(v, f"{path}[{i}]")
    return out


@pytest.mark.parametrize("argv, least", [
    (["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "0.5", "--mu-s", "0.3", "--f-start", "1",
      "--f-stop", "2", "--num", "2", "--json"], 4),
    (["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "0.5", "--mu-s", "0.3", "--f-start", "1",
      "--f-stop", "2", "--num", "2", "--method", "transient", "--max-periods", "64", "--json"], 2),
    (["orbit", "--lam", "0.5", "--mu-s-sigma", "0.6", "--chi", "0.7", "--json"], 1),
    (["continuation", "--param", "chi", "--from", "0.7", "--to", "0.65", "--max-points", "4", "--json",
      "--no-progress"], 8),
    (["belt", "--v-belt", "0.2", "--json", "--no-plot", "--periods", "20"], 4),
])
def test_json_booleans_are_booleans(argv: list[str], least: int, capsys: pytest.CaptureFixture[str],
                                    monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 0
    found = _booleans(json.loads(capsys.readouterr().out))
    assert len(found) >= least and all(type(v) is bool for _, v in found), found


def test_run_json_counts_are_whole_numbers(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--scene", "stiction", "--periods", "3"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert type(res["transitions"]) is int and res["transitions"] >= 2
