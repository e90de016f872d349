"""FMI 2.0 conformance of DryFrictionOscillator.fmu: static checks by fmpy and the FMU Manipulation
Toolbox, the model description as the single source of truth, a second host (libcosim), the
source-code FMU rebuilt by fmpy, and the FMU's errors for bad values."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from dryfriction import fmi2
from dryfriction.fmu import FMUError, OscillatorFMU, Settings
from dryfriction.params import Oscillator


@pytest.mark.min_versions
def test_fmpy_validate_finds_no_problem(fmu_path: Path) -> None:
    assert validate_fmu(str(fmu_path)) == []


@pytest.mark.min_versions
def test_fmutool_check_reports_compliant(fmu_path: Path) -> None:
    exe = shutil.which("fmutool") or str(Path(sys.executable).with_name("fmutool"))
    r = subprocess.run([exe, "-input", str(fmu_path), "-check"], capture_output=True, text=True, timeout=120)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert "compliant with FMI-2.0" in out, out
    assert "No semantic error" in out, out
    assert "ERROR" not in out, out


def test_archive_layout(fmu_path: Path) -> None:
    names = set(zipfile.ZipFile(fmu_path).namelist())
    assert "modelDescription.xml" in names
    assert "binaries/linux64/DryFrictionOscillator.so" in names
    md = read_model_description(str(fmu_path))
    sources = md.buildConfigurations[0].sourceFileSets[0].sourceFiles
    assert sources
    for src in sources:
        assert f"sources/{src}" in names
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    assert md.coSimulation.canHandleVariableCommunicationStepSize


def test_model_description_is_the_source_of_truth(fmu: OscillatorFMU) -> None:
    """Every variable of modelDescription.xml reads back through its value reference with the
    declared start value, and unique value references per type (observe at its start, true: every
    output computed and finite)."""
    fmu.start(Oscillator(), Settings(h=0.0, alpha=-0.1, observe=True))  # h, alpha, observe at their starts
    seen: set[tuple[str, int]] = set()
    for v in fmu.md.variables.values():
        key = (v.call_type, v.vr)
        assert key not in seen, f"duplicate value reference {key}"
        seen.add(key)
        value = fmu.get([v.name])[v.name]
        assert np.isfinite(float(value)), v.name
        if v.causality == "parameter":
            assert float(value) == float(v.start), (v.name, value, v.start)


@pytest.mark.min_versions
def test_libcosim_gives_the_same_trajectory(fmu_path: Path, fmu: OscillatorFMU) -> None:
    """A second host (libcosim via libcosimpy) steps the FMU to the same x(t) as fmpy (1e-12)."""
    from libcosimpy.CosimEnums import CosimExecutionState  # noqa: F401  (import check)
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    dt, n = 0.01, 300
    ex = CosimExecution.from_step_size(step_size=int(round(dt * 1e9)))
    idx = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(fmu_path), instance_name="dfo"))
    obs = CosimObserver.create_last_value()
    ex.add_observer(observer=obs)
    vr_x = fmu.vr("x")
    xs = []
    for _ in range(n):
        assert ex.step()
        xs.append(obs.last_real_values(slave_index=idx, variable_references=[vr_x])[0])
    p = Oscillator()
    ref = fmu.trajectory(p, np.arange(n + 1) * dt, Settings(h=0.0), outputs=("x",))["x"][1:]  # the FMU's default h
    assert np.max(np.abs(np.array(xs) - ref)) <= 1e-12 * np.max(np.abs(ref))


@pytest.mark.slow
def test_source_fmu_rebuilds_with_fmpy(fmu_path: Path, fmu: OscillatorFMU, tmp_path: Path) -> None:
    """A host can rebuild the binary from sources/ (fmpy's CMake build) and gets the same numbers."""
    from fmpy import extract
    from fmpy.build import build_platform_binary

    unzip = Path(extract(str(fmu_path), unzipdir=str(tmp_path / "fmu")))
    shutil.rmtree(unzip / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(unzip, build_dir=tmp_path / "build")
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as z:
        for f in unzip.rglob("*"):
            z.write(f, f.relative_to(unzip).as_posix())
    p = Oscillator()
    t = np.linspace(0, 4 * p.period, 81)
    with OscillatorFMU(rebuilt) as other:
        a = other.trajectory(p, t, Settings(h=p.period / 500))
    b = fmu.trajectory(p, t, Settings(h=p.period / 500))
    for k in ("x", "v", "F_friction", "mode"):
        assert np.allclose(a[k], b[k], rtol=1e-12, atol=1e-15), k


def test_an_fmu_error_names_the_function_the_status_and_the_sentence(fmu: OscillatorFMU) -> None:
    """The driver's error: the FMI function, its status and the FMU's logged sentence (the bad
    values themselves are the C API test's: tests/fmi_c/test_fmi_api.c, test_bad_values)."""
    fmu.reset()
    with pytest.raises(FMUError) as err:
        fmu.set({"m": 0.0})
    e = err.value
    assert (e.function, e.status) == ("fmi2SetReal", fmi2.ERROR)
    assert "variable m " in e.message and "valid range: > 0" in e.message, e.message
    assert str(e).startswith("fmi2SetReal returned fmi2Error: "), str(e)
    # the instance stays usable: a valid run after the rejected value
    r = fmu.trajectory(Oscillator(), [0.0, 0.5], Settings(h=1e-3))
    assert np.all(np.isfinite(r["x"])) and r["x"][-1] != 0.0
    # an error found at initialisation names that call
    with pytest.raises(FMUError, match="t_obs_stop must be >= t_obs_start") as err:
        fmu.start(Oscillator(), Settings(observe=True, t_obs_start=2.0, t_obs_stop=1.0))
    assert err.value.function == "fmi2ExitInitializationMode"
    fmu.reset()


def test_only_fmi2_functions_are_exported(fmu_path: Path, tmp_path: Path) -> None:
    with zipfile.ZipFile(fmu_path) as z:
        so = tmp_path / "dfo.so"
        so.write_bytes(z.read("binaries/linux64/DryFrictionOscillator.so"))
    out = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    symbols = {line.split()[-1] for line in out.splitlines() if line.split()[1:2] == ["T"]}
    assert symbols, out
    assert all(s.startswith("fmi2") for s in symbols), sorted(s for s in symbols if not s.startswith("fmi2"))
    for required in ("fmi2Instantiate", "fmi2DoStep", "fmi2GetFMUstate", "fmi2DeSerializeFMUstate",
                     "fmi2SetTime", "fmi2GetDerivatives", "fmi2Reset"):
        assert required in symbols


def test_wrong_guid_is_refused(fmu: OscillatorFMU) -> None:
    with pytest.raises(FMUError, match="does not match the FMU's GUID") as err:
        fmi2.Instance(fmu.unzip_dir, "{00000000-0000-0000-0000-000000000000}", fmu.md.model_identifier, "wrong-guid")
    assert err.value.function == "fmi2Instantiate"


def test_log_categories_are_honoured(fmu_path: Path) -> None:
    """logEvents reports every stick/slip switch when on, nothing when off."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7)
    for on in (True, False):
        with OscillatorFMU(fmu_path, logging=on) as f:
            f.trajectory(p, [0.0, 2 * p.period], Settings(h=p.period / 1000))
            events = [m for s, c, m in f.messages if c == "logEvents" and "->" in m]
            calls = [m for s, c, m in f.messages if c == "logAll"]
            if on:
                assert len(events) >= 4 and any("stick -> " in m for m in events), events
                assert "fmi2DoStep" in calls
            else:
                assert events == [] and calls == []
    with OscillatorFMU(fmu_path) as f:
        with pytest.raises(FMUError, match="fmi2SetDebugLogging returned fmi2Error"):
            f.set_debug_logging(True, ["noSuchCategory"])
        assert any("unknown log category noSuchCategory" in m for s, c, m in f.messages)
