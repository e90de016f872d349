"""What the command line says when something is wrong: every error is one line and exit status 2
(bad arguments of every subcommand, an unusable --fmu, an error the FMU reports), every warning
the FMU logs is one stderr line, --strict makes it an error, and the error lines quoted by docs/cli.md
are the ones printed."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from dryfriction.cli import main
from dryfriction.cli.study import main as studies_main

from helpers import _not_zip, _zip_without_md


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


@pytest.mark.parametrize("argv, words", [
    (["run", "--m", "-1", "--k", "1"], "--m must be > 0"),
    (["run", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3", "--f", "1", "--lam", "0.5"],
     "not both"),
    (["run", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3"], "frequency is missing"),
    (["run", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0", "--mu-k", "0.2", "--f", "1"],
     "mu_k with mu_s = 0"),
    (["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3", "--f-start", "5",
      "--f-stop", "1"], "--f-stop 1 must be >= --f-start 5"),
    (["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3", "--f-start", "0",
      "--f-stop", "1"], "--f-start must be > 0"),
    (["response", "--m", "1", "--k", "100", "--N", "1", "--mu-s", "0.3", "--f-start", "1", "--f-stop", "2"],
     "--P0"),
    (["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3", "--zeta", "0.1", "--c", "1",
      "--f-start", "1", "--f-stop", "2"], "--c or --zeta, not both"),
])
def test_bad_physical_arguments_are_one_line(argv: list[str], words: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1, err


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


@pytest.mark.slow
def test_console_script_warning_is_one_stderr_line(tmp_path: Path) -> None:
    exe = Path(sys.executable).with_name("dryfriction")
    env = {**os.environ, "PYTHONWARNINGS": ""}
    r = subprocess.run([str(exe), *SWEEP, "--steps-per-period", "2"], capture_output=True, text=True, cwd=tmp_path,
                       env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("dryfriction: warning: "), r.stderr


def test_the_docs_error_lines_are_the_ones_printed(capsys: pytest.CaptureFixture[str]) -> None:
    import re

    page = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    quoted = re.findall(r"`(dryfriction: error: [^`]+)`", page)
    assert quoted, "docs/cli.md quotes an error line"
    for line in quoted:
        m = re.fullmatch(r"dryfriction: error: --m must be > 0, not (\S+)", line)
        typo = re.fullmatch(r"dryfriction: error: unknown option (\S+); did you mean \S+\?", line)
        assert m or typo, f"a quoted error line without a command here to check it: {line}"
        if m:
            argv = ["run", "--m", m.group(1), "--k", "1", "--P0", "1", "--f", "1", "--N", "1", "--mu-s", "0.1"]
        else:
            argv = ["response", "--m", "1", typo.group(1), "5"]  # type: ignore[union-attr]
        assert main(argv) == 2
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


@pytest.mark.parametrize("make, words", [
    (_not_zip, "is not an FMU (not a zip archive)"),
    (_zip_without_md, "is not an FMU (no modelDescription.xml in the archive)"),
])
@pytest.mark.parametrize("command", [["run", "--scene", "sweep", "--periods", "3"],
                                     ["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "1", "--mu-s", "0.3",
                                      "--f-start", "1", "--f-stop", "1", "--num", "1", "--json"],
                                     ["chain", "--t-end", "1"]])
def test_the_cli_reports_an_unusable_fmu_in_one_line(make, words: str, command: list[str], tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str],
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    path = make(tmp_path)
    assert main(["--fmu", str(path), *command]) == 2
    err = capsys.readouterr().err
    assert f"{path} {words}" in err and len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err


@pytest.mark.parametrize("argv, words", [
    (["fig99"], "unknown study"),
    (["fig8_9", "--set", "sweep.chi.num=abc"], "sweep.chi.num must be an integer"),
    (["fig8_9", "--set", "sweep.nope=1"], "unknown key 'sweep.nope'"),
    (["fig8_9", "--set", "sweep.chi.num=0"], "sweep.chi.num must be in [1, 10,000,000], not 0"),
    (["fig8_9", "--set", "sweep.chi.num=10000000000"], "sweep.chi.num must be in [1, 10,000,000], not 10000000000"),
    (["fig10_11", "--set", "fig11.lam.num=100000"],    # 3 x 100,000 x 41 x 41 runs x 30 periods x 1000 steps
     "about 1.51e+13 steps of work (study fig10_11: sweep fig11: 5.04e+08 runs x 30 periods x 1,000 steps"),
    (["fig8_9", "--set", "numerics.scheme=fast"], "invalid value 'fast' for numerics.scheme; valid range: one of"),
    (["fig8_9", "--set", "params.lam=-1"], "params.lam"),
    (["fig8_9", "--set", "sweep.obs_periods=40"], "sweep.obs_periods must be in"),
    (["fig7", "--set", "numerics.alpha=0.5"], "for numerics.alpha; valid range: in [-0.333333, 0]"),
    (["fig3", "--workers", "-1"], "--workers must be >= 0"),
    (["fig3", "--workers", "two"], "invalid int value"),
    (["fig3", "--config", "/nonexistent.toml"], "config file not found"),
    (["fig3", "--fmu", "/nonexistent.fmu"], "FMU not found"),
    (["fig3", "--bogus"], "unknown option --bogus (dryfriction study --help lists the options)"),
])
@pytest.mark.min_versions
def test_bad_input_is_one_line_and_exit_2_before_work(argv: list[str], words: str, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    assert studies_main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert words in err
    assert len(err.strip().splitlines()) == 1
    assert not any(tmp_path.iterdir())  # no work started, nothing written


@pytest.mark.parametrize("argv, words", [
    (["chain2", "--set", "chain.configs=[\"all\"]"], "chain.configs must be a non-empty list of both, second"),
    (["chain2", "--set", "window.obs_periods=100"], "window.obs_periods must be in"),
    (["chain_waves", "--set", "chain.n=1"], "chain.n must be in [2, 4096]"),
    (["chain_waves", "--set", "numerics.h=0"], "numerics.h must be > 0"),
])
def test_chain_studies_bad_input_is_one_line(argv: list[str], words: str, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    assert studies_main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("argv, words, status", [
    (["--n", "3", "--set", "m=1,1,-1"], "invalid value -1 for m[3]", 2),
    (["--n", "3", "--set", "m=1,2"], "m needs 3 values (one per block, n = 3)", 2),
    (["--n", "5000"], "invalid value 5000 for n", 2),
    (["--set", "mass=1"], "the chain has no parameter 'mass'", 2),
    (["--set", "scheme=exact"], "scheme must be one of paper, consistent, located, not 'exact'", 2),
])
def test_chain_command_bad_values(argv: list[str], words: str, status: int, tmp_path: Path, chain_fmu3: Path,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    from dryfriction.cli import main

    assert main(["chain", *argv, "--out", str(tmp_path / "out"), "--fmu", str(chain_fmu3)]) == status
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("argv, words", [
    (["chain", "--n", "0"], "--n must be >= 1, not 0"),
    (["chain", "--dt", "-1"], "--dt must be > 0, not -1"),
    (["chain", "--fmi", "4"], "invalid choice: 4"),
    (["chain", "--set", "N=heavy"], "--set N: 'heavy' is not a number"),
    (["chain", "--fmu", "/nonexistent.fmu"], "--fmu: no such file"),
])
def test_chain_command_bad_input_is_one_line(argv: list[str], words: str, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_output_into_a_closed_pipe_is_quiet() -> None:
    """`dryfriction orbit ... --json | head -c 10`: the reader gone before the output is written
    ends the command quietly (exit 141, as the shell's tools), no traceback on stderr."""
    cmd = [sys.executable, "-m", "dryfriction", "orbit", "--m", "1", "--k", "1", "--zeta", "0.01", "--P0", "1",
           "--f", "0.16", "--N", "0.1", "--mu-s", "0.3", "--mu-k", "0.2", "--period", "2", "--json"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert p.stdout is not None and p.stderr is not None
    p.stdout.close()                      # the reader is gone before anything is written
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 141, err
    assert "Traceback" not in err and err == ""


# ---- the output path: refused before the computation -------------------------------------------

@pytest.fixture
def read_only_dir(tmp_path: Path) -> Iterator[Path]:
    """A folder nothing can be written in: without write permission, or (as root, whom permissions
    do not stop) a read-only tmpfs mounted there; skipped where neither is possible."""
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    mounted = False
    if os.access(ro, os.W_OK):
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(ro)], capture_output=True)
        if r.returncode != 0:
            ro.chmod(0o755)
            pytest.skip("running as root without the right to mount a read-only file system")
        mounted = True
    try:
        yield ro
    finally:
        if mounted:
            subprocess.run(["umount", str(ro)], check=True)
        ro.chmod(0o755)


@pytest.fixture
def small_fs(tmp_path: Path) -> Iterator[Path]:
    """A file system of 32 KiB (a tmpfs; mounting needs root's rights, else skipped)."""
    mnt = tmp_path / "small"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=32k", "tmpfs", str(mnt)], capture_output=True)
    if r.returncode != 0:
        pytest.skip("no right to mount a small file system")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", str(mnt)], check=True)


def test_a_full_disk_while_the_results_are_written(small_fs: Path, fmu_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """A folder without room for the estimated files is refused before the work (exit 2); a disk
    that fills after that check (the check bypassed here) while the files are written: the PNG
    (some 60 KB) does not fit, one line naming the folder and the cause, exit 1, the older result
    set there untouched, nothing else left."""
    out = small_fs / "out"
    out.mkdir()
    (out / "response.csv").write_text("an older table\n")
    argv = ["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "0.5", "--mu-s", "0.3", "--f-start", "1",
            "--f-stop", "2", "--num", "2", "--format", "csv", "--no-progress", "--out", str(out), "--fmu", str(fmu_path)]
    assert main(argv) == 2
    line = capsys.readouterr().err
    assert line.startswith(f"dryfriction: error: the output folder {out} has ") and "MB free" in line, line
    import dryfriction.budget

    monkeypatch.setattr(dryfriction.budget, "check_writable", lambda folder, *a, **k: Path(folder))
    assert main(argv) == 1
    cap = capsys.readouterr()
    assert cap.err == f"dryfriction: error: cannot write {out}: no space left on the device; nothing of it was kept\n"
    assert [p.name for p in small_fs.iterdir()] == ["out"] and [p.name for p in out.iterdir()] == ["response.csv"]
    assert (out / "response.csv").read_text() == "an older table\n"


#: each command that writes a result set, and the function that computes it (must not be called)
OUT_COMMANDS = {
    "response": (["response", "--m", "1", "--k", "100", "--P0", "1", "--N", "0.5", "--mu-s", "0.3", "--f-start", "1",
                  "--f-stop", "2", "--num", "2"], "dryfriction.analysis.response.frequency_response"),
    "chain": (["chain", "--t-end", "1"], "dryfriction.drivers.chain.ChainFMU3.run"),
    "continuation": (["continuation", "--param", "chi", "--from", "0.7", "--to", "0.6"],
                     "dryfriction.analysis.continuation.continue_orbits"),
    "bifurcation": (["bifurcation", "--quick"], "dryfriction.sweep.runner.run_batch"),
    "belt": (["belt", "--v-belt", "0.2"], "dryfriction.analysis.self_excited.self_excited"),
    "validate": (["validate", "--quick"], "dryfriction.analysis.report.run_validation"),
}


def _no_computation(monkeypatch: pytest.MonkeyPatch, target: str) -> None:
    def computed(*args: object, **kwargs: object) -> None:
        raise AssertionError("the computation started")

    monkeypatch.setattr(target, computed)


@pytest.mark.parametrize("command", list(OUT_COMMANDS))
@pytest.mark.parametrize("bad", ["empty", "file", "long", "read-only", "read-only itself"])
def test_an_unusable_out_is_refused_before_the_computation(command: str, bad: str, tmp_path: Path,
                                                           request: pytest.FixtureRequest,
                                                           capsys: pytest.CaptureFixture[str],
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    argv, compute = OUT_COMMANDS[command]
    _no_computation(monkeypatch, compute)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notes.txt").write_text("a file")
    out, words = {
        "empty": ("", "--out must name a folder, not ''"),
        "file": ("notes.txt", "--out notes.txt is a file, not a folder"),
        "long": ("x" * 300, "bytes long, more than the 237 it may have here (255 per name"),
        "read-only": ("", ""),
        "read-only itself": ("", ""),
    }[bad]
    if bad == "read-only":          # the folder to be made inside a read-only one
        out = str(request.getfixturevalue("read_only_dir") / "results")
        words = f"--out {out}: cannot write in {Path(out).parent} ("
    elif bad == "read-only itself":  # an existing folder that cannot be written
        out = str(request.getfixturevalue("read_only_dir"))
        words = f"--out {out}: cannot write in it"
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main([*argv, "--out", out]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dryfriction: error: --out") and words in err and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    if bad == "read-only":
        assert list(Path(out).parent.iterdir()) == []
    if bad == "read-only itself":
        assert list(Path(out).iterdir()) == []


def test_run_out_is_a_file(tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """``run --out`` names a CSV file: a folder, '' and a name too long are refused before the run."""
    _no_computation(monkeypatch, "dryfriction.drivers.scenes.run_validation")
    for out, words in ((str(tmp_path), f"--out {tmp_path} is a folder, not a file"),
                       ("", "--out must name a file, not ''"),
                       (str(tmp_path / ("x" * 300)), "bytes long, more than the")):
        assert main(["run", "--periods", "2", "--out", out]) == 2
        err = capsys.readouterr().err
        assert err.startswith("dryfriction: error: ") and words in err and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


# ---- what the messages say ------------------------------------------------------------------------

@pytest.mark.parametrize("command", [["scenes"], ["chain", "--t-end", "1"], ["study", "list"]])
def test_fmu_option_naming_a_directory(command: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--fmu", str(tmp_path), *command]) == 2
    assert capsys.readouterr().err == f"dryfriction: error: --fmu: {tmp_path} is a directory, not an FMU file\n"


@pytest.mark.parametrize("argv, line", [
    # a required option missing too: the unknown one is reported, with the closest valid one
    (["response", "--m", "1", "--f-strat", "5"], "unknown option --f-strat; did you mean --f-start?"),
    (["response", "--m", "1", "--f-strat=5", "--f-stop", "6"], "unknown option --f-strat; did you mean --f-start?"),
    (["run", "--sceen", "sweep"], "unknown option --sceen; did you mean --scene?"),
    (["--strickt", "scenes"], "unknown option --strickt; did you mean --strict?"),
    (["continuation", "--param", "chi", "--form", "0.7", "--to", "0.6"], "unknown option --form; did you mean --from?"),
    (["study", "fig3", "--quik"], "unknown option --quik; did you mean --quick?"),
    (["scenes", "--zzz"], "unknown option --zzz (dryfriction scenes --help lists the options)"),
])
def test_a_typo_is_named_with_the_closest_option(argv: list[str], line: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert capsys.readouterr().err == f"dryfriction: error: {line}\n"


def test_an_abbreviation_is_still_accepted(fmu_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--scen", "sweep", "--periods", "3", "--fmu", str(fmu_path)]) == 0
    assert json.loads(capsys.readouterr().out)["scene"] == "sweep"


@pytest.mark.parametrize("argv, line", [
    (["fig99"], "dryfriction: error: unknown study 'fig99'; the studies are: "),
    (["fig3", "--quik"], "dryfriction: error: unknown option --quik; did you mean --quick?"),
    (["fig3", "--fmu", "/nonexistent.fmu"], "dryfriction: error: FMU not found: /nonexistent.fmu (no such file)"),
])
def test_python_m_dryfriction_studies_has_the_one_prefix(argv: list[str], line: str, tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    assert studies_main([*argv, "--out", str(tmp_path)], prog="python -m dryfriction.studies") == 2
    err = capsys.readouterr().err
    assert err.startswith(line) and err.count("\n") == 1, err


def test_a_study_that_fails_says_error(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """A study that fails (here: a RuntimeError from its run) is one line with the one prefix, exit 1."""
    from dryfriction import studies

    def fail(ctx: object) -> None:
        raise RuntimeError("the sweep lost its workers")

    monkeypatch.setattr(studies.STUDIES["fig3"], "run", fail)
    assert studies_main(["fig3", "--quick", "--workers", "0", "--no-progress", "--out", str(tmp_path)]) == 1
    assert capsys.readouterr().err == "dryfriction: error: the sweep lost its workers\n"
