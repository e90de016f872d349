"""Work bounded before it starts (dryfriction.budget): every command and the API estimate their
work from their arguments and refuse, in one line naming the option and the limit, what exceeds
the bound unless it is raised; the estimates against counts made by hand; frequencies that are not
numbers refused by the API."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from dryfriction.budget import DEFAULT_MAX_WORK, EXACT_PERIOD_STEPS, WorkBoundError, check_writable
from dryfriction.cli import main
from dryfriction.params import Oscillator
from dryfriction.response import MAX_PERIODS, ORBIT_FREQUENCY_STEPS, frequency_response, response_work
from dryfriction.studies import run_study
from dryfriction.sweep import SweepSpec, nondim_table
from dryfriction.sweep.engine import sweep_work

BLOCK = ["--m", "0.5", "--k", "2000", "--zeta", "0.003", "--P0", "10", "--N", "20", "--mu-s", "0.3", "--mu-k", "0.2"]
RESPONSE = ["response", *BLOCK, "--f-start", "5", "--f-stop", "15"]


def _one_line_error(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert re.match(r"dryfriction( study)?: error: ", lines[0]) and "Traceback" not in err
    return lines[0]


def test_response_of_1e8_frequencies_refused_before_any_work(capsys: pytest.CaptureFixture[str],
                                                              tmp_path: Path) -> None:
    out = tmp_path / "never"
    assert main([*RESPONSE, "--num", "100000000", "--out", str(out)]) == 2
    cap = capsys.readouterr()
    line = _one_line_error(cap.err)
    assert "--max-work 1e+10" in line and "100,000,000 frequencies" in line
    assert cap.out == "" and not out.exists()
    # the README quotes it
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    quoted = re.search(r'--num 100000000` says\s+"([^"]+)"', readme)
    assert quoted and " ".join(quoted.group(1).split()) == line.removeprefix("dryfriction: error: ")


def test_response_bound_raised_and_lowered(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # three frequencies of the orbit method: 3 x (12,000 + the cold searches' share) + one cold search
    work, _ = response_work(Oscillator(m=1, k=1), 3, "orbit")
    cold = 6 * (60 + 10) * EXACT_PERIOD_STEPS
    assert work == pytest.approx(3 * (ORBIT_FREQUENCY_STEPS + cold / 100) + cold)
    assert main([*RESPONSE, "--num", "3", "--max-work", f"{work * 0.99:.6g}", "--json"]) == 2
    assert "--max-work" in _one_line_error(capsys.readouterr().err)
    assert main([*RESPONSE, "--num", "3", "--max-work", f"{work * 1.01:.6g}", "--json"]) == 0
    assert capsys.readouterr().out.count("{") >= 1


def test_api_refuses_a_million_frequencies_unless_raised(fmu_path: Path) -> None:
    p = Oscillator.physical(m=0.5, k=2000, zeta=0.003, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2)
    f = np.linspace(5, 15, 10**6)
    with pytest.raises(WorkBoundError, match=r"1e\+06|1,000,000 frequencies.*max_work 1e\+10"):
        frequency_response(p, f, fmu_path=fmu_path)
    # the transient method's bound: 2 max_periods periods per frequency, each EXACT_PERIOD_STEPS
    work, _ = response_work(p, 7, "transient")
    assert work == 7 * 2 * MAX_PERIODS * EXACT_PERIOD_STEPS
    with pytest.raises(WorkBoundError, match="max_work"):
        frequency_response(p, [5.0, 6.0], method="transient", max_work=work / 7, fmu_path=fmu_path)
    with pytest.raises(WorkBoundError, match="max_work must be a number > 0"):
        frequency_response(p, [5.0], max_work=-1, fmu_path=fmu_path)


@pytest.mark.parametrize("bad, what", [(["5", "6"], "str '5'"), ("5", "the string '5'"), ([True, 6.0], "bool True"),
                                       ([5.0, None], "NoneType None")])
def test_api_refuses_frequencies_that_are_not_numbers(bad: object, what: str) -> None:
    p = Oscillator.physical(m=0.5, k=2000, zeta=0.003, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2)
    with pytest.raises(ValueError, match="the frequencies must be numbers in Hz, not " + what):
        frequency_response(p, bad)  # type: ignore[arg-type]


@pytest.mark.parametrize("argv", [
    ["run", "--periods", "30"],
    ["lyapunov", "--lam", "0.5", "--mu-s-sigma", "0.6", "--chi", "0.7"],
    ["orbit", "--lam", "0.5", "--mu-s-sigma", "0.6", "--chi", "0.7"],
    ["continuation", "--param", "chi", "--from", "0.7", "--to", "0.6"],
    ["bifurcation", "--quick"],
    ["belt", "--v-belt", "0.3"],
    ["chain", "--n", "3"],
    ["response", *BLOCK, "--f-start", "5", "--f-stop", "15"],
    ["study", "fig8_9", "--quick", "--workers", "0"],
    ["study", "chaos_scan", "--quick", "--workers", "0"],
    ["study", "chaos_basins", "--quick", "--workers", "0"],
    ["study", "chaos_transients", "--quick", "--workers", "0"],
    ["study", "chain2", "--quick", "--workers", "0"],
])
def test_every_command_refuses_work_above_max_work(argv: list[str], capsys: pytest.CaptureFixture[str],
                                                   tmp_path: Path) -> None:
    out = ["--out", str(tmp_path / "o")] if argv[0] in ("study", "chain", "belt", "bifurcation") else []
    assert main([*argv, *out, "--max-work", "10"]) == 2
    cap = capsys.readouterr()
    line = _one_line_error(cap.err)
    assert "exceed the bound --max-work 10 (steps)" in line
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").rglob("*.nc"))


def test_run_work_is_its_steps() -> None:
    from dryfriction.budget import command_work
    from dryfriction.cli import build_parser

    args = build_parser().parse_args(["run", "--periods", "30", "--steps-per-period", "1000"])
    assert command_work(args)[0] == 31 * 1000        # the periods, one more for the observed window
    args = build_parser().parse_args(["lyapunov", "--lam", "0.5", "--mu-s-sigma", "0.6", "--chi", "0.7",
                                      "--periods", "500", "--transient", "100", "--steps-per-period", "200",
                                      "--scheme", "located"])
    assert command_work(args)[0] == 2 * 600 * 200    # two trajectories
    args = build_parser().parse_args(["lyapunov", "--lam", "0.5", "--mu-s-sigma", "0.6", "--chi", "0.7"])
    assert command_work(args)[0] == 2 * 600 * EXACT_PERIOD_STEPS  # the default: the exact scheme


def test_sweep_work_counts_each_runs_steps() -> None:
    # 6 runs of 10 periods at 100 steps per period (Bossak): 6,000 steps; exact: 6 x 10 x EXACT
    P = nondim_table({"lam": np.array([0.5, 0.8, 1.2, 1.5, 2.0, 3.0]), "mu_s_sigma": 0.6, "chi": 0.7},
                     10.0, 9.0, 10.0, 100)
    bossak = SweepSpec("w", P, {"scheme": "located"}, chunk_runs=4)
    assert sweep_work(bossak, [0, 1]) == pytest.approx(6000.0, rel=1e-12)
    assert sweep_work(bossak, [1]) == pytest.approx(2000.0, rel=1e-12)
    exact = SweepSpec("w", P, {"scheme": "exact"}, chunk_runs=4)
    assert sweep_work(exact, [0, 1]) == pytest.approx(60 * EXACT_PERIOD_STEPS, rel=1e-12)


def test_study_refused_before_any_chunk(tmp_path: Path, fmu_path: Path) -> None:
    with pytest.raises(WorkBoundError, match=r"300 runs of sweep fig8_9\) exceed the bound --max-work 1,000"):
        run_study("fig8_9", quick=True, out=tmp_path, fmu=fmu_path, workers=0, progress=False, max_work=1000)
    assert not list(tmp_path.rglob("*.chunk")) and not list(tmp_path.rglob("*.nc"))
    assert not (tmp_path / "fig8_9" / "config.toml").exists()
    assert DEFAULT_MAX_WORK == 1e10 and math.isfinite(DEFAULT_MAX_WORK)


def test_unwritable_output_folder_found_before_the_work(tmp_path: Path, fmu_path: Path,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    assert main(["study", "fig8_9", "--quick", "--workers", "0", "--no-progress", "--out", str(blocker),
                 "--fmu", str(fmu_path)]) == 2
    line = _one_line_error(capsys.readouterr().err)
    assert f"cannot write into the output folder {blocker}/fig8_9" in line and "Not a directory" in line
    with pytest.raises(Exception, match="has .* MB free"):
        check_writable(tmp_path, nbytes=1e18)
    # response: before the work, nothing created
    assert main([*RESPONSE, "--num", "3", "--out", str(blocker / "resp")]) == 2
    line = _one_line_error(capsys.readouterr().err)
    assert f"--out {blocker}/resp: {blocker} is a file, not a folder" in line
    fresh = tmp_path / "new" / "deeper"
    assert check_writable(fresh) == fresh and not (tmp_path / "new").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".probe")]
