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
from dryfriction.analysis.response import MAX_PERIODS, ORBIT_FREQUENCY_STEPS, frequency_response, response_work
from dryfriction.budget import SAMPLE_STEPS
from dryfriction.studies import STUDIES, effective_config, run_study, study_work
from dryfriction.sweep import SweepSpec, nondim_table
from dryfriction.sweep.engine import sweep_work

BLOCK = ["--m", "0.5", "--k", "2000", "--zeta", "0.003", "--P0", "10", "--N", "20", "--mu-s", "0.3", "--mu-k", "0.2"]
RESPONSE = ["response", *BLOCK, "--f-start", "5", "--f-stop", "15"]


def _one_line_error(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert re.match(r"dryfriction: error: ", lines[0]) and "Traceback" not in err
    return lines[0]


def test_response_of_1e8_frequencies_refused_before_any_work(capsys: pytest.CaptureFixture[str],
                                                              tmp_path: Path) -> None:
    out = tmp_path / "never"
    assert main([*RESPONSE, "--num", "100000000", "--out", str(out)]) == 2
    cap = capsys.readouterr()
    line = _one_line_error(cap.err)
    assert "--max-work 1e+10" in line and "100,000,000 frequencies" in line
    assert cap.out == "" and not out.exists()
    # docs/cli.md quotes it
    page = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    quoted = re.search(r'--num 100000000` says\s+"([^"]+)"', page)
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
    from dryfriction.cli import build_parser, command_work

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
    with pytest.raises(WorkBoundError, match=r"about 9e\+06 steps of work \(study fig8_9: sweep fig8_9: 300 runs x 30 "
                                             r"periods x 1,000 steps\) exceed the bound --max-work 1,000"):
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
    assert line == f"dryfriction: error: --out {blocker}/fig8_9: {blocker} is a file, not a folder"
    with pytest.raises(Exception, match="has .* MB free"):
        check_writable(tmp_path, nbytes=1e18)
    # response: before the work, nothing created
    assert main([*RESPONSE, "--num", "3", "--out", str(blocker / "resp")]) == 2
    line = _one_line_error(capsys.readouterr().err)
    assert f"--out {blocker}/resp: {blocker} is a file, not a folder" in line
    fresh = tmp_path / "new" / "deeper"
    assert check_writable(fresh) == fresh and not (tmp_path / "new").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".probe")]


def _by_hand_belt_map() -> float:
    """belt_map --quick counted point by point: v_belt 0.1 ... 1.0 (5), N 0.5 ... 1.5 (3); m = k = 1,
    mu_s - mu_k = 0.2; 500 steps per natural period; a transient of max(20, 5 cycles) natural
    periods sampled 256 times each, then 10 orbit periods of Newton; 3 grazing continuations of 200
    points x 10 orbit periods (the grid's mean orbit)."""
    Tn = 2 * math.pi
    total, cycles = 0.0, []
    for N in (0.5, 1.0, 1.5):
        for v in (0.1, 0.325, 0.55, 0.775, 1.0):
            cycle = 1 + 2 * 0.2 * N / v / Tn
            cycles.append(cycle)
            tr = max(20.0, 5 * cycle)
            total += (tr + 10 * cycle) * 500 + tr * 256 * SAMPLE_STEPS
    return total + 3 * 200 * 10 * (sum(cycles) / len(cycles)) * 500


#: every study's work with --quick, counted by hand from configs/<study>.toml (steps; a sampled point
#: counts SAMPLE_STEPS, an exact-scheme period EXACT_PERIOD_STEPS, a chain's step once per block)
QUICK_BY_HAND = {
    "fig2": 1 * 1 * 1000 + (1 * 1000 + 1) * SAMPLE_STEPS,
    "fig3": 10 * 100 * 1000,                                  # no lambda of 0.3 ... 3.0 in (0.97, 1.03)
    "fig4": 2 * (20 + 4) * 1000 + 2 * (4 * 500 + 1) * SAMPLE_STEPS,
    "fig5_6": (20 + 2 * 50) * 1000 + ((20 * 100 + 1) + 2 * (50 * 100 + 1)) * SAMPLE_STEPS,
    "fig7": 10 * 30 * 30 * 2000,
    "fig8_9": 12 * 5 * 5 * 30 * 1000,
    "fig10_11": (2 * 12 + 1 * 7) * 5 * 5 * 30 * 1000,
    # Fig. 12/13: 2 x 17 periods, 2 sampled; Fig. 14: 0.05 apart down to 1e-4 is 9 halvings, + 2 ends;
    # its 2 trajectories of 30 periods sampled 500 times each
    "fig12_14": 2 * 17 * 1000 + 2 * (2 * 500 + 1) * SAMPLE_STEPS + (2 + 9) * 30 * 1000
                + 2 * 30 * 1000 + 2 * (30 * 500 + 1) * SAMPLE_STEPS,
    # scan 11 chi x 4 ICs x 2 and refinement 5 x 4 x 2, check 1 chi (FMU and exact pairs), section
    "chaos_scan": (11 * 4 * 2 * (50 + 150) + 5 * 4 * 2 * (50 + 200) + 2 * 2 * (50 + 100) + (200 + 1000))
                  * EXACT_PERIOD_STEPS,
    "chaos_basins": 21 * 21 * ((400 + 16) + (200 + 16)) * EXACT_PERIOD_STEPS,
    "chaos_transients": 5 * 5 * 5 * 300 * EXACT_PERIOD_STEPS,
    "chain2": 2 * 12 * 2 * 2 * 24 * 1000 * 2,
    "chain_waves": 2 * 64 * (2 * 2 * math.pi / 0.05 / 0.01),  # P0 0.5 and 1.0; h = 0.01 s
    # h = dt / ceil(dt * 100 / (2 pi / sqrt(401))) = 0.1 / 32; 700 time units; 256 blocks
    "burridge_knopoff": 256 * 700 / (0.1 / 32),
    # fig8_9's sweep; 7 chi in [0.2, 0.8]: 5 long runs of 400 periods each, at most 2 x 2 doubling
    # runs of 2000; a continuation of 400 points x 8 branches x 10 exact periods
    "fig8_9_orbits": 12 * 5 * 5 * 30 * 1000 + 7 * 5 * 400 * 1000 + 7 * 2 * 2 * 2000 * 1000
                     + 400 * 8 * 10 * EXACT_PERIOD_STEPS,
    # fig10_11's sweeps; fig10: 2 chi x 3 pieces ([0.05, 0.35], [0.35, 0.98], [1.02, 1.6]) x 2 ways,
    # fig11: 1 chi x 1 piece x 2 ways
    "fig10_11_orbits": (2 * 12 + 1 * 7) * 5 * 5 * 30 * 1000 + (12 + 2) * 400 * 8 * 10 * EXACT_PERIOD_STEPS,
    "belt_map": _by_hand_belt_map(),
}


def test_every_studys_quick_work_counted_by_hand() -> None:
    assert set(QUICK_BY_HAND) == set(STUDIES)
    for name, steps in QUICK_BY_HAND.items():
        est = study_work(name, effective_config(name, quick=True))
        assert est.total == pytest.approx(steps, rel=1e-9), name
        assert 1e6 <= est.out_bytes <= 30e6, name    # a figure (1 MB) at least; the results and chunks
    # the sweeps' parts agree with the engine's count of their tables
    cfg = effective_config("fig8_9", quick=True)
    from dryfriction.studies.fig8_9_bifurcation import spec

    sp, _ = spec(cfg)
    assert study_work("fig8_9", cfg).parts[0][1] == pytest.approx(sweep_work(sp, list(range(sp.n_chunks))), rel=1e-12)


def test_second_sweep_too_large_refused_before_the_first(tmp_path: Path, fmu_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    # fig10's sweep is small; fig11's, 1 x 100,000 x 25 runs x 30 periods x 1000 steps, is not: the
    # study is refused before fig10's first chunk
    argv = ["study", "fig10_11", "--quick", "--workers", "0", "--no-progress", "--out", str(tmp_path),
            "--fmu", str(fmu_path), "--set", "fig11.lam.num=100000"]
    assert main(argv) == 2
    line = _one_line_error(capsys.readouterr().err)
    assert line == ("dryfriction: error: about 7.5e+10 steps of work (study fig10_11: sweep fig11: 2.5e+06 runs "
                    "x 30 periods x 1,000 steps; sweep fig10: 600 runs x 30 periods x 1,000 steps) exceed the "
                    "bound --max-work 1e+10 (steps); ask for less or raise --max-work")
    assert not list(tmp_path.rglob("*")), "nothing written"
    # a trajectory study and a chain study are bounded too
    with pytest.raises(WorkBoundError, match=r"study fig5_6: fig6 trajectories: 2 runs x 1e\+07 periods"):
        run_study("fig5_6", quick=True, out=tmp_path, fmu=fmu_path, workers=0, progress=False,
                  sets=["beating.periods=1e7"])
    with pytest.raises(WorkBoundError, match=r"study burridge_knopoff: run: 256 blocks x"):
        run_study("burridge_knopoff", quick=True, out=tmp_path, workers=0, progress=False, max_work=1e7)
    assert not list(tmp_path.rglob("*"))


def test_study_all_checks_every_study_first(tmp_path: Path, fmu_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    # fig2 (3e5 steps) would pass; fig3 (1e6) does not: nothing runs
    assert main(["study", "all", "--quick", "--workers", "0", "--no-progress", "--out", str(tmp_path),
                 "--fmu", str(fmu_path), "--max-work", "5e5"]) == 2
    out = capsys.readouterr()
    assert "study fig3: sweep fig3: 10 runs x 100 periods" in _one_line_error(out.err)
    assert "== study" not in out.out and not list(tmp_path.rglob("*"))


def test_output_estimate_checked_against_the_free_space(tmp_path: Path, fmu_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    import shutil
    from collections import namedtuple

    est = study_work("fig8_9", effective_config("fig8_9", quick=True))
    # 300 runs: chunks and dataset 2 x 300 x columns x 8 bytes + 400 per chunk (12), 2 figures of 1 MB
    from dryfriction.sweep.runner import OUTPUT_COLUMNS

    assert est.out_bytes == pytest.approx(2 * 300 * len(OUTPUT_COLUMNS) * 8 + 400 * 12 + 2e6, rel=1e-12)
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1e12, 0, 2.0 * est.out_bytes))   # not the margin
    with pytest.raises(Exception, match=r"has 4\.\d+ MB free, the results and chunks of study fig8_9 need about 4"):
        run_study("fig8_9", quick=True, out=tmp_path, fmu=fmu_path, workers=0, progress=False)
    assert not list(tmp_path.rglob("*"))


def test_study_memory_refused_before_the_work(tmp_path: Path, fmu_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import dryfriction.budget as budget
    from dryfriction.sweep.runner import OUTPUT_COLUMNS, PARAM_COLUMNS

    # 1000 x 5 x 5 runs hold their table, outputs and dataset: 25,000 x (18 + 2 x 6) x 8 bytes = 6 MB
    row = (len(PARAM_COLUMNS) + 2 * len(OUTPUT_COLUMNS)) * 8
    assert study_work("fig8_9", effective_config("fig8_9", True, sets=["sweep.chi.num=1000"])).memory == 25000 * row
    monkeypatch.setattr(budget, "memory_limit", lambda: 1e6)
    with pytest.raises(WorkBoundError, match=r"about 0\.006 GB of memory \(study fig8_9: sweep fig8_9: 25,000 runs .*"
                                             r"\(0\.001 GB\); ask for less \(--set\)"):
        run_study("fig8_9", quick=True, out=tmp_path, fmu=fmu_path, workers=0, progress=False,
                  sets=["sweep.chi.num=1000"], max_work=1e15)
    assert not list(tmp_path.rglob("*"))


def test_every_default_study_within_the_default_bound() -> None:
    # 'dryfriction study all' at full size is not refused: the largest, fig10_11 and its orbit study,
    # 263,917 runs x 30 periods x 1000 steps = 7.9e9 (+ 18 continuations of 1.6e6 steps)
    totals = {n: study_work(n, effective_config(n)).total for n in STUDIES}
    assert max(totals.values()) <= DEFAULT_MAX_WORK
    assert totals["fig10_11"] == pytest.approx(263917 * 30 * 1000, rel=1e-12)
    assert totals["fig10_11_orbits"] == pytest.approx(263917 * 30 * 1000 + 18 * 400 * 8 * 10 * EXACT_PERIOD_STEPS,
                                                      rel=1e-12)
    assert max(totals, key=totals.__getitem__) == "fig10_11_orbits"
