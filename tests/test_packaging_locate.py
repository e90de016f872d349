"""Where the FMUs come from (dryfriction.paths): the order (explicit path, DFO_FMU..., package
data, build tree), the one exception for every unusable FMU path, and nothing read at import time."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from dryfriction import paths as locate, model
from dryfriction.drivers.chain import ChainFMU3, ChainFMU2
from dryfriction.drivers.oscillator3 import OscillatorFMU3, default_fmi3_path
from dryfriction.drivers.oscillator import OscillatorFMU2
from dryfriction.drivers.system import SystemFMU3
from dryfriction import System
from dryfriction.paths import FMUFileError
from dryfriction.analysis.response import frequency_response
from dryfriction.studies import run_study

from helpers import _bad_xml, _not_zip, _zip_without_md


ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def fmus(fmu_path: Path, chain_fmu2: Path, chain_fmu3: Path) -> dict[locate.Kind, Path]:
    return {locate.OSCILLATOR: fmu_path, locate.OSCILLATOR3: default_fmi3_path(), locate.CHAIN: chain_fmu2,
            locate.CHAIN3: chain_fmu3, locate.SYSTEM: locate.fmu_path(locate.SYSTEM),
            locate.SYSTEM3: locate.fmu_path(locate.SYSTEM3)}


@pytest.fixture()
def no_env(monkeypatch: pytest.MonkeyPatch) -> None:
    for kind in locate.KINDS:
        monkeypatch.delenv(kind.env, raising=False)


# ------------------------------------------------------------------ one exception, one sentence each

@pytest.mark.parametrize("make, words", [
    (lambda d: d / "missing.fmu", "FMU not found: {path} (no such file)"),
    (_not_zip, "{path} is not an FMU (not a zip archive)"),
    (_zip_without_md, "{path} is not an FMU (no modelDescription.xml in the archive)"),
    (_bad_xml, "{path} is not an FMU (its modelDescription.xml is not valid XML"),
    (lambda d: d, "{path} is a folder, not an FMU file"),
])
def test_an_unusable_path_is_one_fmu_file_error(make, words: str, tmp_path: Path) -> None:
    path = make(tmp_path)
    for kind in locate.KINDS:
        with pytest.raises(FMUFileError) as err:
            locate.fmu_path(kind, path)
        msg = str(err.value)
        assert msg.startswith(words.format(path=path)), msg
        assert "\n" not in msg and isinstance(err.value, ValueError)


def test_another_model_or_fmi_version_is_refused_by_every_driver(fmus: dict[locate.Kind, Path]) -> None:
    """Each of the drivers takes its own FMU only; the sentence names what the file is and
    what the driver needs."""
    drivers = {locate.OSCILLATOR: lambda p: OscillatorFMU2(p), locate.OSCILLATOR3: lambda p: OscillatorFMU3(fmu_path=p),
               locate.CHAIN: lambda p: ChainFMU2(fmu_path=p), locate.CHAIN3: lambda p: ChainFMU3(2, fmu_path=p),
               locate.SYSTEM3: lambda p: SystemFMU3(System(M=[[1.0]], K=[[1.0]]), p)}
    for need, open_ in drivers.items():
        for have, path in fmus.items():
            if have == need:
                assert locate.fmu_path(need, path) == path
                continue
            with pytest.raises(FMUFileError) as err:
                open_(path)
            assert str(err.value) == (f"{path} is the FMI {have.fmi_version} {have.model_identifier} FMU, "
                                      f"not the FMI {need.fmi_version} {need.model_identifier} FMU this needs")


def test_the_response_and_a_study_check_their_fmu(fmus: dict[locate.Kind, Path], tmp_path: Path) -> None:
    from dryfriction import Oscillator

    with pytest.raises(FMUFileError, match="not the FMI 2.0 DryFrictionOscillator FMU"):
        frequency_response(Oscillator(), [1.0], fmu_path=fmus[locate.OSCILLATOR3])
    with pytest.raises(FMUFileError, match="not the FMI 3.0 DryFrictionChain FMU"):
        run_study("chain2", quick=True, out=tmp_path, fmu=fmus[locate.OSCILLATOR], workers=0)
    assert not any(tmp_path.iterdir())  # refused before any work


def test_the_environment_variable_is_named_in_the_sentence(no_env: None, tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DFO_FMU", str(_not_zip(tmp_path)))
    with pytest.raises(FMUFileError) as err:
        OscillatorFMU2()
    assert str(err.value) == f"DFO_FMU={tmp_path / 'README.md'} is not an FMU (not a zip archive)"


# ------------------------------------------------------------------------------------------ the order

def test_the_order_explicit_environment_package_build(no_env: None, fmus: dict[locate.Kind, Path], tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    build = locate.build_dir()
    assert build == ROOT / "build" and locate.source_root() == ROOT
    # a source checkout without package data: the build tree
    assert not (locate.package_dir() / "fmus").exists()
    for kind in locate.KINDS:
        assert locate.candidates(kind) == [locate.package_dir() / "fmus" / kind.relpath, build / kind.relpath]
        assert locate.fmu_path(kind) == build / kind.relpath
    # package data (an installed wheel) before the build tree
    pkg = tmp_path / "pkg"
    for kind in locate.KINDS:
        (pkg / "fmus" / kind.relpath).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(fmus[kind], pkg / "fmus" / kind.relpath)
    monkeypatch.setattr(locate, "package_dir", lambda: pkg)
    for kind in locate.KINDS:
        assert locate.fmu_path(kind) == pkg / "fmus" / kind.relpath
    # the environment variable before both, the explicit path before everything
    other = tmp_path / "other.fmu"
    shutil.copy(fmus[locate.OSCILLATOR], other)
    monkeypatch.setenv("DFO_FMU", str(other))
    assert locate.fmu_path(locate.OSCILLATOR) == other
    assert locate.fmu_path(locate.OSCILLATOR3) == pkg / "fmus" / locate.OSCILLATOR3.relpath
    assert locate.fmu_path(locate.OSCILLATOR, fmus[locate.OSCILLATOR]) == fmus[locate.OSCILLATOR]


def test_no_fmu_anywhere_is_one_sentence_naming_where_it_looked(no_env: None, tmp_path: Path,
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """An installed package without its data and without a repository: the model description and
    every FMU are one FMUFileError, raised on first use."""
    monkeypatch.setattr(locate, "package_dir", lambda: tmp_path)
    monkeypatch.setattr(locate, "source_root", lambda: None)
    monkeypatch.setattr(model, "repository_xml", lambda: tmp_path / "modelDescription.xml")
    model.default.cache_clear()
    try:
        for kind in locate.KINDS:
            with pytest.raises(FMUFileError) as err:
                locate.fmu_path(kind)
            msg = str(err.value)
            assert msg.startswith(f"{kind.describe()} is not there ({tmp_path / 'fmus' / kind.relpath}): build it")
            assert msg.endswith(f"or give --fmu PATH or set {kind.env}") and "\n" not in msg
        with pytest.raises(FMUFileError, match="DryFrictionOscillator FMU is not there"):
            model.default()
    finally:
        monkeypatch.undo()
        model.default.cache_clear()
    assert model.default().model_identifier == "DryFrictionOscillator"  # found again


def test_the_configs_come_from_the_package_data_else_the_repository(monkeypatch: pytest.MonkeyPatch,
                                                                     tmp_path: Path) -> None:
    monkeypatch.delenv("DFO_CONFIGS", raising=False)
    assert locate.configs_dir() == ROOT / "configs"
    (tmp_path / "configs").mkdir()
    monkeypatch.setattr(locate, "package_dir", lambda: tmp_path)
    assert locate.configs_dir() == tmp_path / "configs"
    monkeypatch.setenv("DFO_CONFIGS", str(ROOT / "configs"))
    assert locate.configs_dir() == ROOT / "configs"


# --------------------------------------------------------------------------- nothing read at import

@pytest.mark.slow
def test_importing_every_module_reads_no_model_description_fmu_or_config() -> None:
    """Every module of the package is imported with recorders on: an audit hook on every file
    opened (no modelDescription.xml, no .fmu, no study config) and on the calls that would find
    them (model.default, locate.fmu_path, locate.configs_dir; a cached result would hide a second
    reader from the hook). Then the first use reads the model description, and both recorders see
    it (the check can fail)."""
    code = r'''
import importlib, json, os, pkgutil, sys
events = []
def hook(event, args):
    if event == "open" and isinstance(args[0], (str, bytes, os.PathLike)):
        p = os.fsdecode(args[0])
        if os.path.basename(p) == "modelDescription.xml" or p.endswith((".fmu", ".toml")):
            events.append("open " + os.path.basename(p))
sys.addaudithook(hook)
import dryfriction.paths as locate, dryfriction.model as model
def recorded(owner, name):
    real = getattr(owner, name)
    def call(*args, **kwargs):
        events.append(name)
        return real(*args, **kwargs)
    setattr(owner, name, call)
for owner, name in ((model, "default"), (locate, "fmu_path"), (locate, "configs_dir")):
    recorded(owner, name)
import dryfriction
names = [m.name for m in pkgutil.walk_packages(dryfriction.__path__, "dryfriction.") if not m.name.endswith("__main__")]
for name in names:
    importlib.import_module(name)
at_import = list(events)
from dryfriction import Oscillator
Oscillator()
print(json.dumps({"modules": names, "at_import": at_import, "at_use": events[len(at_import):]}))
'''
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert {"dryfriction.paths", "dryfriction.cli", "dryfriction.drivers.oscillator", "dryfriction.analysis.validation",
            "dryfriction.studies.chain2", "dryfriction.sweep.runner"} <= set(res["modules"])
    assert res["at_import"] == []
    assert "default" in res["at_use"] and "open modelDescription.xml" in res["at_use"], res["at_use"]
