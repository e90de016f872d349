"""Independent FMI hosts run every FMU with its default settings to the end, without a warning.

The FMI standard's reference host fmusim (modelica/Reference-FMUs v0.0.39) runs all four FMUs with
their default experiment and start values, the FMI 3.0 ones also with early return and event mode,
the FMI 3.0 chain also with n = 3 (and array start values of that size); the FMU Compliance Checker
(modelica-tools/FMUComplianceChecker, FMI 1/2 only) runs the two FMI 2.0 FMUs. Each must reach the
default stop time, exit 0 and report no warning or error (fmusim: every logged message of status OK,
nothing on stderr; the checker: its summary counts 0 of each, for the FMU and for itself), and its x
must equal fmpy's on the same settings within 1e-12 at every output point. What each host records
by default is exactly the FMU's outputs: the oscillator's sensitivity Jacobian (dx_dx0 ... dv_dv0,
NaN unless asked for) is local, not an output, so no empty column. A second co-simulation library,
libcosim (libcosimpy), steps the FMI 2.0 oscillator and chain to the package's / fmpy's trajectories.

The tools come from ``FMUSIM`` / ``FMUCHECK`` (paths of the executables), else from
``../shared/tools/`` beside the repository (see its README). When neither is there a test is
skipped with a reason that says it did not run; so is fmusim when its runtime libraries (libxml2,
zlib) are missing (``scripts/test.sh`` installs them on Debian).
"""

from __future__ import annotations

import csv
import math
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from dryfriction.drivers.chain import ChainFMU3, ChainFMU2, default_chain_fmu, default_chain_fmu3
from dryfriction.drivers.oscillator3 import default_fmi3_path
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings, default_fmu_path
from dryfriction.params import Oscillator


# external programs (fmusim, the Compliance Checker, libcosim) run every FMU: the quick loop leaves them out
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
TOOLS = ROOT.parent / "shared" / "tools"
TOL = 1e-12


def _tool(env: str, rel: str, what: str) -> Path:
    given = os.environ.get(env)
    path = Path(given) if given else TOOLS / rel
    if not (path.is_file() and os.access(path, os.X_OK)):
        where = f"{env}={given} is not an executable file" if given else f"{env} is not set and {path} is not there"
        pytest.skip(f"did not run: {what} not found ({where})")
    return path


def fmusim() -> Path:
    path = _tool("FMUSIM", "fmusim/fmusim", "fmusim")
    ldd = subprocess.run(["ldd", str(path)], capture_output=True, text=True)
    missing = re.findall(r"^\s*(\S+) => not found", ldd.stdout, flags=re.M)
    if missing:
        pytest.skip(f"did not run: fmusim ({path}) needs {', '.join(missing)} at runtime, not installed "
                    "(Debian: apt-get install libxml2 zlib1g)")
    return path


def fmucheck() -> Path:
    return _tool("FMUCHECK", "fmucheck/fmuCheck.linux64", "the FMU Compliance Checker")


FMUS = {
    "fmi2-oscillator": default_fmu_path,
    "fmi2-chain": default_chain_fmu,
    "fmi3-oscillator": default_fmi3_path,
    "fmi3-chain": default_chain_fmu3,
}


def _fmu(key: str) -> Path:
    path = FMUS[key]()
    if not path.is_file():
        pytest.fail(f"FMU not built: {path} (cmake --build build)")
    return path


def _experiment(path: Path) -> tuple[float, float, float]:
    de = read_model_description(str(path)).defaultExperiment
    return float(de.startTime or 0.0), float(de.stopTime), float(de.stepSize)


def _x_columns(names: list[str]) -> list[int]:
    """The columns of x (FMI 2.0: x or x[1], x[2], ...; FMI 3.0: the array x in one column)."""
    cols = [i for i, n in enumerate(names) if n == "x" or re.fullmatch(r"x\[\d+\]", n)]
    assert cols, f"no x among the columns {names}"
    return cols


def _read_csv(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(t, x[rows, blocks]) of a host's CSV (an FMI 3.0 array: values separated by blanks)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    names = [n.strip().strip('"') for n in rows[0]]
    cols = _x_columns(names)
    t = np.array([float(r[0]) for r in rows[1:]])
    x = np.array([[float(v) for c in cols for v in r[c].split()] for r in rows[1:]])
    return t, x


def _assert_records_the_outputs(csv_path: Path, fmu: Path, host: str) -> None:
    """A host's CSV has the columns time and the FMU's outputs, no other (no local variable: the
    oscillator's dx_dx0 ... dv_dv0 are local, read by value reference only when asked for)."""
    with open(csv_path, newline="") as f:
        names = [n.strip().strip('"') for n in next(csv.reader(f))]
    md = read_model_description(str(fmu))
    outputs = {v.name for v in md.modelVariables if v.causality == "output"}
    assert len(names) == len(set(names)) and set(names) == {"time"} | outputs, (host, fmu.name, names)
    assert not set(names) & {"dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0"}


def _on_grid(t: np.ndarray, x: np.ndarray, t0: float, h: float) -> dict[int, np.ndarray]:
    """The rows at the output points t0 + k h (the last row of each: after an event), by k."""
    k = np.rint((t - t0) / h)
    out = {}
    for i in np.flatnonzero(np.abs(t - (t0 + k * h)) <= 1e-9 * max(1.0, abs(t[-1]))):
        out[int(k[i])] = x[i]
    return out


def _fmpy_x(path: Path, h: float, stop: float, **options) -> tuple[np.ndarray, np.ndarray]:
    md = read_model_description(str(path))
    names = [v.name for v in md.modelVariables if v.name == "x" or re.fullmatch(r"x\[\d+\]", v.name)]
    res = simulate_fmu(str(path), stop_time=stop, output_interval=h, output=names, **options)
    x = np.column_stack([np.asarray(res[n], dtype=float).reshape(len(res), -1) for n in names])
    return np.asarray(res["time"], dtype=float), x


def _assert_same_x(host: tuple[np.ndarray, np.ndarray], ref: tuple[np.ndarray, np.ndarray], t0: float, h: float,
                   stop: float, what: str) -> None:
    a, b = _on_grid(*host, t0, h), _on_grid(*ref, t0, h)
    n_points = int(round((stop - t0) / h))
    assert set(a) == set(b) == set(range(n_points + 1)), (what, sorted(set(a) ^ set(b))[:10])
    worst = max(float(np.max(np.abs(a[k] - b[k]))) for k in a)
    assert worst <= TOL, f"{what}: x differs from fmpy's by {worst:.3g} (> {TOL})"


def _replay_fmi3_events(path: Path, t0: float, h: float, ks: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """fmpy's FMU3Slave with early return and event mode, stepping as fmusim does: towards each
    output point t0 + k h of ``ks`` in turn, from every early return (a switch) on, with event mode
    at each event; x sampled after every doStep and after every event handling (fmusim's rows)."""
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(path))
    xvar = next(v for v in md.modelVariables if v.name == "x")
    n = int(next((v.start for v in md.modelVariables if v.name == "n"), 1) or 1)
    unzip = extract(str(path))
    s = FMU3Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="replay")
    s.instantiate(eventModeUsed=True, earlyReturnAllowed=True)
    try:
        s.enterInitializationMode(startTime=t0)
        s.exitInitializationMode()
        while s.updateDiscreteStates()[0]:
            pass
        s.enterStepMode()
        t, rows = t0, [(t0, s.getFloat64([xvar.valueReference], n))]
        for k in ks[1:]:
            target = t0 + k * h
            while t < target:
                event, terminate, early, last = s.doStep(t, target - t)
                assert not terminate
                t = last if early and last < target else target
                rows.append((t, s.getFloat64([xvar.valueReference], n)))
                if event:
                    s.enterEventMode()
                    while s.updateDiscreteStates()[0]:
                        pass
                    s.enterStepMode()
                    rows.append((t, s.getFloat64([xvar.valueReference], n)))
        s.terminate()
    finally:
        s.freeInstance()
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows], dtype=float)


def _run_fmusim(tmp_path: Path, fmu: Path, *options: str) -> tuple[np.ndarray, np.ndarray]:
    out, log = tmp_path / "out.csv", tmp_path / "log.txt"
    r = subprocess.run([str(fmusim()), "--interface-type", "cs", "--logging-on", "--log-file", str(log),
                        "--output-file", str(out), *options, str(fmu)], capture_output=True, text=True,
                       timeout=600)
    messages = log.read_text().splitlines() if log.exists() else []
    bad = [m for m in messages if not m.startswith("[OK]")]
    assert r.returncode == 0, f"fmusim exited {r.returncode}: {r.stderr.strip()[-500:]} {bad[:3]}"
    assert bad == [], f"fmusim logged {len(bad)} messages of a status other than OK: {bad[:3]}"
    assert r.stderr.strip() == "", r.stderr[-500:]
    assert messages, "fmusim --logging-on logged nothing: the log was not read"
    _assert_records_the_outputs(out, fmu, "fmusim")
    return _read_csv(out)


CASES = [
    ("fmi2-oscillator", ()),
    ("fmi2-chain", ()),
    ("fmi3-oscillator", ()),
    ("fmi3-chain", ()),
    ("fmi3-oscillator", ("--early-return-allowed", "--event-mode-used")),
    ("fmi3-chain", ("--early-return-allowed", "--event-mode-used")),
]


@pytest.mark.parametrize("key,options", CASES, ids=[f"{k}{'-events' if o else ''}" for k, o in CASES])
def test_fmusim_runs_to_the_end_without_warnings(tmp_path: Path, key: str, options: tuple[str, ...]) -> None:
    fmu = _fmu(key)
    t0, stop, h = _experiment(fmu)
    t, x = _run_fmusim(tmp_path, fmu, *options)
    assert t[0] == t0 and abs(t[-1] - stop) <= 1e-12 * stop, (t[0], t[-1], stop)
    assert np.all(np.isfinite(x))
    if not options:
        _assert_same_x((t, x), _fmpy_x(fmu, h, stop), t0, h, stop, f"fmusim {key}")
        return
    # early return and event mode: fmusim v0.0.39 counts an early return that falls just before an
    # output point (1.7e-5 s before 1.91 here) as that point and steps on to the next one, so its
    # communication points are not fmpy.simulate_fmu's; the reference is fmpy's FMU3Slave stepping
    # towards the same output points (every row, switches included, within 1e-12)
    k = np.rint((t - t0) / h)
    ks = sorted({int(kk) for kk, tt in zip(k, t) if abs(tt - (t0 + kk * h)) <= 1e-9 * stop})
    assert len(ks) >= 0.99 * (round((stop - t0) / h) + 1) and ks[-1] == round((stop - t0) / h)
    ref_t, ref_x = _replay_fmi3_events(fmu, t0, h, ks)
    assert ref_t.size == t.size, (ref_t.size, t.size)
    assert np.max(np.abs(ref_t - t)) <= 1e-12 * stop
    worst = float(np.max(np.abs(ref_x - x)))
    assert worst <= TOL, f"fmusim {key} with events: x differs from fmpy's by {worst:.3g} (> {TOL})"
    switches = t[np.abs((t - t0) / h - k) > 1e-6]
    assert switches.size > 10  # the default run switches: early returns did happen
    # and fmpy.simulate_fmu with the same options finds the same switches (1e-9 s: its own points)
    sim_t = _fmpy_x(fmu, h, stop, early_return_allowed=True, use_event_mode=True)[0]
    sim_sw = np.unique(sim_t[np.abs((sim_t - t0) / h - np.rint((sim_t - t0) / h)) > 1e-6])
    assert np.allclose(np.unique(switches), sim_sw, rtol=0, atol=1e-9)


def test_fmusim_chain_with_three_blocks(tmp_path: Path) -> None:
    """n = 3 set as a start value (Configuration Mode), with array start values of that size."""
    fmu = _fmu("fmi3-chain")
    t0, stop, h = _experiment(fmu)
    m, P0 = [1.0, 1.0, 2.0], [1.0, 0.5, 1.0]
    t, x = _run_fmusim(tmp_path, fmu, "--start-value", "n", "3", "--start-value", "m", " ".join(map(str, m)),
                       "--start-value", "P0", " ".join(map(str, P0)))
    assert x.shape[1] == 3 and abs(t[-1] - stop) <= 1e-12 * stop
    # fmpy's simulate_fmu cannot set a structural parameter: the reference is fmpy's FMU3Slave
    # through dryfriction.drivers.chain (Configuration Mode for n, the same output points t0 + k h)
    with ChainFMU3(n=3, params={"m": m, "P0": P0}, fmu_path=fmu) as chain:
        ref = chain.run(stop, h, start_time=t0)
    _assert_same_x((t, x), (ref.t, ref.x), t0, h, stop, "fmusim fmi3-chain n = 3")
    assert not np.array_equal(x[:, 0], x[:, 2])  # the heavier third block moves otherwise


def _summary(text: str) -> tuple[int, int, int]:
    """(FMU warnings and errors, checker warnings, checker errors) from the checker's summary."""
    fmu = re.search(r"FMU reported:\s*(\d+) warning\(s\) and error\(s\)", text)
    chk = re.search(r"Checker reported:\s*(\d+) Warning\(s\)\s*(\d+) Error\(s\)", text)
    assert fmu and chk, f"no summary in the checker's output: {text[-800:]}"
    return int(fmu.group(1)), int(chk.group(1)), int(chk.group(2))


@pytest.mark.parametrize("key", ["fmi2-oscillator", "fmi2-chain"])
def test_compliance_checker_finds_nothing(tmp_path: Path, key: str) -> None:
    """The checker's own defaults, with the default experiment's step as communication step and an
    output at every step (-n 0): stop time from the default experiment."""
    fmu = _fmu(key)
    t0, stop, h = _experiment(fmu)
    out, log = tmp_path / "out.csv", tmp_path / "log.txt"
    r = subprocess.run([str(fmucheck()), "-h", repr(h), "-n", "0", "-o", str(out), "-e", str(log), str(fmu)],
                       capture_output=True, text=True, timeout=600)
    text = r.stdout + r.stderr + (log.read_text() if log.exists() else "")
    assert r.returncode == 0, f"the checker exited {r.returncode}: {text[-800:]}"
    assert _summary(text) == (0, 0, 0), [ln for ln in text.splitlines() if "WARNING" in ln or "ERROR" in ln][:5]
    bad = [ln for ln in text.splitlines() if re.match(r"\s*\[(WARNING|ERROR|FATAL)\]", ln)]
    assert bad == [], bad[:5]
    _assert_records_the_outputs(out, fmu, "the checker")
    t, x = _read_csv(out)
    assert t[0] == t0 and math.isclose(t[-1], stop, rel_tol=1e-12), (t[0], t[-1], stop)
    _assert_same_x((t, x), _fmpy_x(fmu, h, stop), t0, h, stop, f"checker {key}")


# ---------------------------------------------------------------------------------------- libcosim

@pytest.mark.min_versions
def test_libcosim_gives_the_same_trajectory(fmu_path: Path, fmu: OscillatorFMU2) -> None:
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


def test_libcosim_steps_the_fmi2_chain_to_fmpys_trajectory(chain_fmu2: Path) -> None:
    """A second host (libcosim via libcosimpy) gives x[i](t) of our FMI 2.0 driver, bit for bit."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    dt, steps = 0.01, 300
    ex = CosimExecution.from_step_size(step_size=int(round(dt * 1e9)))
    idx = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(chain_fmu2), instance_name="chain"))
    obs = CosimObserver.create_last_value()
    ex.add_observer(observer=obs)
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        vrs = [f2.md.vr(f"x[{i}]") for i in range(1, f2.n + 1)]
        xs = []
        for _ in range(steps):
            assert ex.step()
            xs.append(obs.last_real_values(slave_index=idx, variable_references=vrs))
        ref = f2.run(steps * dt, dt)  # the FMU's start values, as libcosim uses them
    xs = np.array(xs)
    assert np.max(np.abs(ref.x[1:])) > 1e-4  # it moves
    assert np.max(np.abs(xs - ref.x[1:])) <= 1e-12 * np.max(np.abs(ref.x))
