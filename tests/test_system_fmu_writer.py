"""A structure's own FMU without a compiler (dryfriction.system.fmu, ``dryfriction system fmu``) and the
System's runs through the FMI 3.0 FMU (dryfriction.drivers.system).

The written FMU is the prebuilt binary with the structure in resources/structure.bin and as start
values: fmpy validates it; run in fmpy and in fmusim with NO start values it gives, bit for bit, the
run of the prebuilt FMU with the structure's values set through the package's own FMI layer; a
bad or truncated structure file is an error at instantiation naming the file. The FMI 2.0 FMU (the
prebuilt binary at any sizes, the layout in the structure file): the same with flattened names,
bit for bit the FMI 3.0 FMU's run, the generator's description at the binary's own sizes, states and
their serialisation, a value reference outside the layout refused, a percent-encoded resource URI
decoded, fmusim and the Compliance Checker to the end. The driver is checked
against plain fmpy calls, and a held input F_ext against the same force as an excitation of
frequency 0. "A user who has M and K as .mtx files gets a working FMU in two commands": tested
as it reads."""

from __future__ import annotations

import csv

import os
import shutil
import struct
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from dryfriction import Contact, FMUCallError, System
from dryfriction.cli import main
from dryfriction.drivers.system import SystemFMU3, run, trajectory
from dryfriction.errors import UsageError
from dryfriction.fmi import fmi2
from dryfriction.system.fmu import MAGIC, RESOURCE, write_fmu

ROOT = Path(__file__).resolve().parents[1]
FMUSIM = Path(os.environ.get("FMUSIM", ROOT.parent / "shared" / "tools" / "fmusim" / "fmusim"))
FMUCHECK = Path(os.environ.get("FMUCHECK", ROOT.parent / "shared" / "tools" / "fmucheck" / "fmuCheck.linux64"))


def structure(nc_between: bool = True) -> System:
    """Three DOFs, a ground contact and one between DOFs, damping, an excitation, an initial state."""
    M = np.array([[2.0, 0.3, 0.0], [0.3, 1.0, 0.1], [0.0, 0.1, 1.5]])
    K = np.array([[300.0, -100.0, 0.0], [-100.0, 200.0, -100.0], [0.0, -100.0, 150.0]])
    contacts = [Contact(dof=0, N=2.0, mu_s=0.4, mu_k=0.3)]
    if nc_between:
        contacts.append(Contact(between=(1, 2), N=1.0, mu_s=0.3, mu_k=0.25))
    return System(M=M, K=K, C=0.01 * K, contacts=contacts, F_c=[1.0, 0.5, 0.0], F_s=[0.0, 0.0, 0.2], omega=8.0,
                  x0=[0.001, 0.0, -0.002], v0=[0.0, 0.01, 0.0], h=2e-4)


@pytest.fixture(scope="module")
def sys3() -> System:
    return structure()


@pytest.fixture(scope="module")
def written(sys3: System, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_fmu(sys3, tmp_path_factory.mktemp("fmu") / "Three.fmu")


def fmpy_run(path: Path, stop: float, dt: float) -> np.ndarray:
    """fmpy's simulate_fmu with no start values: x, f, E_friction at every output time."""
    res = simulate_fmu(str(path), stop_time=stop, output_interval=dt, output=["x", "f", "E_friction", "mode"])
    return res


def test_the_written_fmu_validates_and_carries_the_structure(written: Path, sys3: System) -> None:
    assert validate_fmu(str(written)) == []
    md = read_model_description(str(written))
    starts = {v.name: v.start for v in md.modelVariables}
    assert starts["n"] == "3" and starts["nc"] == "2"
    assert [float(x) for x in starts["M"].split()] == sys3.M.ravel().tolist()
    assert [float(x) for x in starts["W"].split()] == [1.0, 0.0, 0.0, 0.0, 1.0, -1.0]
    assert md.modelName == "Three" and md.coSimulation.modelIdentifier == "DryFrictionSystem"
    with zipfile.ZipFile(written) as z:
        data = z.read(RESOURCE)
    assert data[:8] == MAGIC
    version, nrec, n, nc = struct.unpack_from("<IIQQ", data, 8)
    assert (version, n, nc) == (1, 3, 2) and nrec == len(sys3.start_values()) - 2


def test_fmpy_with_no_start_values_is_the_prebuilt_fmu_with_them(written: Path, sys3: System) -> None:
    res = fmpy_run(written, 2.0, 0.01)
    with SystemFMU3(sys3) as fmu:  # the prebuilt FMU (build/fmi3), the values set by the driver
        ref = fmu.run(2.0, 0.01)
    assert np.array_equal(res["time"], ref.t)
    assert np.array_equal(np.asarray(res["x"]).reshape(ref.x.shape), ref.x)  # bit for bit
    assert np.array_equal(np.asarray(res["f"]).reshape(ref.f.shape), ref.f)
    assert np.array_equal(res["E_friction"], ref.E_friction)
    modes = np.asarray(res["mode"]).reshape(ref.mode.shape)
    assert np.array_equal(modes, ref.mode)
    assert {0, 1}.issubset(set(modes[:, 0])) and ref.E_friction[-1] > 0  # it sticks and slips


def test_the_written_fmu_is_its_structure_in_the_driver_too(written: Path, sys3: System) -> None:
    """The driver on the written FMU (values set again) and on the prebuilt one: the same run."""
    a = run(sys3, 1.0, 0.02, fmu_path=written)
    b = run(sys3, 1.0, 0.02)
    assert a.x.tobytes() == b.x.tobytes() and a.mode.tobytes() == b.mode.tobytes()


def test_reset_goes_back_to_the_structure(written: Path, tmp_path: Path) -> None:
    """After fmi3Reset the binary's values are the structure's again (not the prebuilt defaults)."""
    md = read_model_description(str(written))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = extract(str(written), unzipdir=str(tmp_path / "x"))
    s = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="DryFrictionSystem")
    s.instantiate()
    try:
        rows = []
        for _ in range(2):
            s.enterInitializationMode(startTime=0.0)
            s.exitInitializationMode()
            s.doStep(0.0, 0.5)
            rows.append(s.getFloat64([vr["x"]], nValues=3) + s.getFloat64([vr["E_friction"]]))
            assert s.getUInt64([vr["n"], vr["nc"]]) == [3, 2]
            s.reset()
        assert rows[0] == rows[1] and rows[0][-1] > 0
    finally:
        s.freeInstance()


def _rewrite(src: Path, dst: Path, data: bytes) -> Path:
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            zout.writestr(item, data if item.filename == RESOURCE else zin.read(item.filename))
    return dst


@pytest.mark.parametrize("cut, words", [
    (lambda b: b[:20], "is truncated: 20 bytes, fewer than its 32-byte header"),
    (lambda b: b[:-4], "is truncated: the value of scheme needs 8 bytes, 4 are left"),
    (lambda b: b[:-8 - 4 * 24], "is truncated: the 2 values of delta need 16 bytes, 8 are left"),
    (lambda b: b"NOTSTRUC" + b[8:], "does not begin with the magic DFOSTRUC"),
    (lambda b: b + b"\0", "has 1 bytes after its last record"),
    (lambda b: b[:8] + struct.pack("<I", 7) + b[12:], "has the version 7; this FMU reads versions 1 to 2"),
])
def test_a_bad_structure_file_is_an_error_at_instantiation(written: Path, sys3: System, tmp_path: Path, cut,
                                                           words: str) -> None:
    with zipfile.ZipFile(written) as z:
        data = z.read(RESOURCE)
    bad = _rewrite(written, tmp_path / "Bad.fmu", cut(data))
    with pytest.raises(FMUCallError) as err:
        SystemFMU3(sys3, bad)
    msg = str(err.value)
    assert "structure.bin" in msg and words in msg, msg


def test_a_value_out_of_range_in_the_file_is_named(written: Path, sys3: System, tmp_path: Path) -> None:
    with zipfile.ZipFile(written) as z:
        data = bytearray(z.read(RESOURCE))
    # the record of N (value reference 900000): its first value made negative
    rec = data.find(struct.pack("<IIQ", 900000, 0, 2))
    assert rec > 0
    struct.pack_into("<d", data, rec + 16, -1.0)
    bad = _rewrite(written, tmp_path / "BadN.fmu", bytes(data))
    with pytest.raises(FMUCallError, match=r"structure\.bin gives N element 0 \(0-based\) the value -1"):
        SystemFMU3(sys3, bad)


@pytest.mark.skipif(not FMUSIM.is_file(), reason="fmusim not there (../shared/tools/fmusim; or set FMUSIM)")
def test_fmusim_runs_the_written_fmu_with_no_start_values(written: Path, sys3: System, tmp_path: Path) -> None:
    out = tmp_path / "out.csv"
    r = subprocess.run([str(FMUSIM), "--interface-type", "cs", "--output-interval", "0.01", "--stop-time", "2",
                        "--output-file", str(out), str(written)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = out.read_text().splitlines()
    head = [h.strip('"') for h in lines[0].split(",")]
    last = lines[-1].split(",")
    ref = run(sys3, 2.0, 0.01)
    assert float(last[0]) == 2.0 and len(lines) == ref.t.size + 1
    x = [float(v) for v in last[head.index("x")].split()]
    assert np.allclose(x, ref.x[-1], rtol=1e-15, atol=1e-17)  # fmusim prints 16 significant digits
    assert float(last[head.index("E_friction")]) == pytest.approx(ref.E_friction[-1], rel=1e-14)


# ----------------------------------------------------------------------------- the driver


def test_the_driver_is_plain_fmpy_calls(sys3: System, tmp_path: Path) -> None:
    """The driver's run against the prebuilt FMU driven by fmpy's FMU3Slave by hand."""
    from dryfriction.drivers.system import default_system_fmu3

    path = default_system_fmu3()
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    d = extract(str(path), unzipdir=str(tmp_path / "p"))
    s = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="DryFrictionSystem")
    s.instantiate()
    times = np.arange(51) * 0.02
    try:
        s.enterConfigurationMode()
        s.setUInt64([vr["n"], vr["nc"]], [3, 2])
        s.exitConfigurationMode()
        s.enterInitializationMode(startTime=0.0)
        for name, value in sys3.start_values().items():
            if name in ("n", "nc"):
                continue
            if name in ("scheme", "friction_law"):
                s.setInt64([vr[name]], [int(v) for v in np.ravel(value)])
            else:
                s.setFloat64([vr[name]], [float(v) for v in np.ravel(value)])
        s.setFloat64([vr["F_ext"]], [0.1, -0.2, 0.3])
        s.exitInitializationMode()
        rows = []
        for k, t in enumerate(times):
            if k:
                s.doStep(times[k - 1], t - times[k - 1])
            rows.append(s.getFloat64([vr["x"], vr["v"], vr["f"]], nValues=8))
    finally:
        s.terminate()
        s.freeInstance()
    ref = np.array(rows)
    got = trajectory(sys3, times, inputs={"F_ext": [0.1, -0.2, 0.3]})
    assert np.array_equal(np.hstack([got.x, got.v, got.f]), ref)


def test_a_held_force_is_an_excitation_of_frequency_zero() -> None:
    """F_ext held from the start and F_c with omega = 0 are the same force: the same run (the
    engine adds them in one place or the other: equal to rounding)."""
    base = structure()
    F = np.array([1.5, -1.0, 1.2])
    held = run(base.replace(F_c=0.0, F_s=0.0, omega=0.0), 2.0, 0.01, inputs={"F_ext": F})
    excited = run(base.replace(F_c=F, F_s=0.0, omega=0.0), 2.0, 0.01)
    assert {0, 1} <= set(excited.mode[:, 0].tolist())  # it slips, then sticks
    assert np.array_equal(held.mode, excited.mode)
    assert np.max(np.abs(held.x - excited.x)) <= 1e-13 * np.max(np.abs(excited.x))


def test_inputs_by_function_and_every_output(sys3: System) -> None:
    """A function of (t, outputs) sets the inputs before each step; N_ext = -N frees a contact."""
    seen = []

    def inputs(t: float, out: dict) -> dict:
        seen.append((t, out["x"].copy()))
        return {"N_ext": [-10.0, 0.0]}  # the ground contact's normal force floored at 0: no friction

    r = run(sys3, 0.5, 0.05, inputs=inputs)
    assert len(seen) == r.t.size - 1 and np.array_equal(seen[3][1], r.x[3])
    assert np.all(r.f[1:, 0] == 0.0)  # the ground contact carries no force from the first step on
    assert r.a.shape == (11, 3) and r.s.shape == (11, 2) and np.all(np.isnan(r.s))
    with pytest.raises(ValueError, match="the system's inputs are F_ext, N_ext, v_belt, not 'P'"):
        run(sys3, 0.5, 0.05, inputs={"P": 1.0})
    with pytest.raises(ValueError, match=r"F_ext needs 3 values"):
        run(sys3, 0.5, 0.05, inputs={"F_ext": [1.0, 2.0]})


def test_the_fmi_version_and_the_name_are_checked(sys3: System, tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="must end with .fmu"):
        write_fmu(sys3, tmp_path / "a.zip")
    with pytest.raises(UsageError, match="fmi must be 2 or 3, not 4"):
        write_fmu(sys3, tmp_path / "a.fmu", fmi=4)


# ----------------------------------------------------------------------------- two commands, no compiler


def test_mtx_files_to_a_working_fmu_in_two_commands(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The user has M.mtx and K.mtx (as an FE code exports them: symmetric, sparse coordinates) and
    writes a TOML file; `dryfriction system fmu` makes the FMU; fmpy runs it with no start values."""
    from scipy.io import mmwrite
    from scipy.sparse import coo_matrix

    n = 6
    k = 1000.0
    K = np.diag(np.full(n, 2 * k)) - np.diag(np.full(n - 1, k), 1) - np.diag(np.full(n - 1, k), -1)
    K[-1, -1] = k
    M = np.diag(np.full(n, 0.5))
    mmwrite(str(tmp_path / "M.mtx"), coo_matrix(M), symmetry="symmetric")
    mmwrite(str(tmp_path / "K.mtx"), coo_matrix(K), symmetry="symmetric")
    (tmp_path / "beam.toml").write_text(
        '[structure]\nM = "M.mtx"\nK = "K.mtx"\n\n[damping]\nrayleigh = [0.5, 1e-4]\n\n'
        "[excitation]\nomega = 20.0\ndof = 5\namplitude = 10.0\n\n"
        "[[contact]]\ndof = 5\nN = 5.0\nmu_s = 0.4\nmu_k = 0.3\n\n"
        "[[contact]]\nbetween = [2, 3]\nN = 3.0\nmu_s = 0.3\n", encoding="utf-8")
    assert main(["system", "fmu", str(tmp_path / "beam.toml"), "-o", str(tmp_path / "Beam.fmu")]) == 0
    assert "n = 6, nc = 2" in capsys.readouterr().out
    res = simulate_fmu(str(tmp_path / "Beam.fmu"), stop_time=1.0, output_interval=0.01, output=["x", "mode"])
    ref = run(System.from_file(tmp_path / "beam.toml"), 1.0, 0.01)
    assert np.array_equal(np.asarray(res["x"]).reshape(ref.x.shape), ref.x)
    assert np.max(np.abs(ref.x[:, 5])) > 1e-3  # it moves
    modes = np.asarray(res["mode"]).reshape(ref.mode.shape)
    assert {0, 1, -1} <= set(modes[:, 0].tolist())  # the tip's contact sticks and slips both ways
    assert np.array_equal(System.from_file(tmp_path / "beam.toml").K, K)


def test_the_command_refuses_what_it_cannot_write(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "s.toml").write_text("[structure]\nM = [[1.0]]\nK = [[4.0]]\n", encoding="utf-8")
    assert main(["system", "fmu", str(tmp_path / "s.toml"), "-o", str(tmp_path / "nodir" / "S.fmu")]) == 2
    err = capsys.readouterr().err
    assert "does not exist" in err and err.count("\n") == 1, err
    assert main(["system", "fmu", str(tmp_path / "s.toml"), "-o", str(tmp_path / "S.fmu"), "--fmi", "4"]) == 2
    assert not (tmp_path / "S.fmu").exists() and not list(tmp_path.glob("*.part"))
    capsys.readouterr()
    # FMI 2.0 at sizes other than the binary's (n = 1, nc = 0: no contact at all)
    assert main(["system", "fmu", str(tmp_path / "s.toml"), "-o", str(tmp_path / "S.fmu"), "--fmi", "2"]) == 0
    assert validate_fmu(str(tmp_path / "S.fmu")) == []
    names = [v.name for v in read_model_description(str(tmp_path / "S.fmu")).modelVariables]
    assert "M[1,1]" in names and "x[1]" in names and not [m for m in names if m.startswith(("f[", "W[", "mode["))]


# ----------------------------------------------------------------------------- FMI 2.0 at the binary's own sizes


def two_dofs() -> System:
    """A structure of the prebuilt FMI 2.0 binary's sizes (n = 2, nc = 1): a contact between the DOFs."""
    M = np.array([[2.0, 0.3], [0.3, 1.0]])
    K = np.array([[300.0, -100.0], [-100.0, 100.0]])
    return System(M=M, K=K, C=0.01 * K, contacts=[Contact(between=(0, 1), N=1.0, mu_s=0.4, mu_k=0.3)],
                  F_c=[2.0, 0.5], omega=9.0, x0=[0.001, 0.0], h=2e-4)


@pytest.fixture(scope="module")
def written2(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_fmu(two_dofs(), tmp_path_factory.mktemp("fmu2") / "Two.fmu", fmi=2)


def test_fmi2_flattened_starts_and_fmpy_with_none_set(written2: Path) -> None:
    s = two_dofs()
    assert validate_fmu(str(written2)) == []
    starts = {v.name: v.start for v in read_model_description(str(written2)).modelVariables}
    assert [float(starts[f"M[{i},{j}]"]) for i in (1, 2) for j in (1, 2)] == s.M.ravel().tolist()
    assert (float(starts["W[1,1]"]), float(starts["W[1,2]"]), float(starts["x0[1]"])) == (1.0, -1.0, 0.001)
    assert starts["scheme"] == "3" and float(starts["mu_k[1]"]) == 0.3
    res = simulate_fmu(str(written2), stop_time=2.0, output_interval=0.01,
                       output=["x[1]", "x[2]", "f[1]", "mode[1]", "E_friction"])
    ref = run(s, 2.0, 0.01)  # the FMI 3.0 prebuilt FMU with the values set
    assert np.array_equal(np.column_stack([res["x[1]"], res["x[2]"]]), ref.x)  # bit for bit
    assert np.array_equal(res["f[1]"], ref.f[:, 0]) and np.array_equal(res["E_friction"], ref.E_friction)
    assert set(res["mode[1]"].tolist()) == {-1, 0, 1}


def test_fmi2_reads_its_resources_through_a_percent_encoded_uri(written2: Path, tmp_path: Path) -> None:
    """fmpy hands FMI 2.0 a file: URI (Path.as_uri: a space as %20, a percent sign as %25): the
    binary decodes it and reads the structure; without the file the prebuilt defaults run."""
    s = two_dofs()
    md = read_model_description(str(written2))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    rows = {}
    for label, keep in (("with", True), ("without", False)):
        d = Path(extract(str(written2), unzipdir=str(tmp_path / f"a b%20c {label}")))
        assert " " in str(d) and "%" in str(d)
        if not keep:
            (d / RESOURCE).unlink()
        slave = FMU2Slave(guid=md.guid, unzipDirectory=str(d), modelIdentifier="DryFrictionSystem")
        slave.instantiate()
        try:
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            slave.doStep(0.0, 0.5)
            rows[label] = slave.getReal([vr["x[1]"], vr["x[2]"]])
        finally:
            slave.terminate()
            slave.freeInstance()
    ref = trajectory(s, [0.0, 0.5])
    assert rows["with"] == ref.x[-1].tolist()
    assert rows["without"] != rows["with"]


def test_fmi2_refuses_a_file_of_other_sizes_without_a_layout(written2: Path, sys3: System, tmp_path: Path) -> None:
    """A version 1 structure file (no layout: the FMI 3.0 FMU's) of other sizes than the FMI 2.0
    binary's own: refused at instantiation."""
    with zipfile.ZipFile(write_fmu(sys3, tmp_path / "T3.fmu")) as z:
        data3 = z.read(RESOURCE)
    bad = _rewrite(written2, tmp_path / "Bad2.fmu", data3)
    md = read_model_description(str(bad))
    d = extract(str(bad), unzipdir=str(tmp_path / "bad2"))
    with pytest.raises(FMUCallError) as err:
        fmi2.Instance(d, md.guid, "DryFrictionSystem", name="bad")
    assert "structure.bin gives n = 3, nc = 2 and no layout (version 1), but without one this FMI 2.0 binary serves " \
        "n = 2, nc = 1 only (its own layout)" in str(err.value), str(err.value)


@pytest.mark.skipif(not FMUCHECK.is_file(), reason="the Compliance Checker not there (../shared/tools/fmucheck; "
                                                   "or set FMUCHECK)")
def test_the_compliance_checker_runs_the_fmi2_fmu(written2: Path, tmp_path: Path) -> None:
    out, log = tmp_path / "out.csv", tmp_path / "log.txt"
    r = subprocess.run([str(FMUCHECK), "-h", "0.01", "-s", "2", "-o", str(out), "-e", str(log), str(written2)],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    report = log.read_text(errors="replace") + r.stdout
    assert "0 warning(s) and error(s)" in report, report
    lines = out.read_text().splitlines()
    head = [h.strip('"') for h in lines[0].split(",")]
    last = [float(v) for v in lines[-1].split(",")]
    ref = run(two_dofs(), 2.0, 0.01)
    assert last[0] == 2.0
    assert last[head.index("x[1]")] == pytest.approx(ref.x[-1, 0], rel=1e-15)  # 17 printed digits
    assert last[head.index("E_friction")] == pytest.approx(ref.E_friction[-1], rel=1e-15)


# ----------------------------------------------------------------------------- FMI 2.0 at any size


def structure_of(n: int, nc: int, seed: int) -> System:
    """A random structure of n DOFs and nc contacts: a coupled SPD mass matrix, a chain of springs
    to the ground, Rayleigh damping; contacts on the ground and between DOFs, rigid and Jenkins
    (k_t > 0), mu_s above and below mu_k; driven near its first resonance; an initial state."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n)) * 0.2
    M = np.eye(n) + A @ A.T
    k = rng.uniform(100.0, 300.0, n + 1)
    K = np.diag(k[:-1] + k[1:])
    for i in range(n - 1):
        K[i, i + 1] = K[i + 1, i] = -k[i + 1]
    w1 = float(np.sqrt(np.min(np.linalg.eigvals(np.linalg.solve(M, K)).real)))
    contacts = []
    for j in range(nc):
        mu_s, mu_k = (0.4, 0.3) if j % 2 == 0 else (0.25, 0.3)
        kw = dict(N=rng.uniform(2.0, 4.0), mu_s=mu_s, mu_k=mu_k, k_t=0.0 if j % 2 == 0 else 400.0)
        if j == 1 and n > 1:
            contacts.append(Contact(between=(0, n - 1), **kw))
        else:
            contacts.append(Contact(dof=(2 * j) % n, **kw))
    return System(M=M, K=K, C=1e-3 * K + 0.05 * M, contacts=contacts, F_c=rng.uniform(0.5, 2.0, n),
                  F_s=rng.uniform(-0.5, 0.5, n), omega=0.9 * w1, x0=rng.uniform(-1e-3, 1e-3, n),
                  v0=rng.uniform(-1e-2, 1e-2, n), h=1e-3)


SIZES = [(1, 1, 11), (3, 2, 12), (7, 3, 13)]


@pytest.fixture(scope="module", params=SIZES, ids=[f"n{n}nc{nc}" for n, nc, _ in SIZES])
def any_size(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> tuple[System, Path, Path]:
    n, nc, seed = request.param
    s = structure_of(n, nc, seed)
    d = tmp_path_factory.mktemp(f"any{n}_{nc}")
    return s, write_fmu(s, d / f"S{n}x{nc}.fmu", fmi=2), write_fmu(s, d / f"S{n}x{nc}_3.fmu", fmi=3)


def test_fmi2_at_any_size_validates_with_its_layout(any_size: tuple[System, Path, Path]) -> None:
    """The description: every element at the value reference of the package's layout (the
    generator's, independently recomputed here from its rule), starts the structure's, the layout
    annotation and the file's layout section the same."""
    s, fmu2, fmu3 = any_size
    assert validate_fmu(str(fmu2)) == []
    md = read_model_description(str(fmu2))
    byname = {v.name: v for v in md.modelVariables}
    n, nc = s.n, s.nc
    # the rule: arrays in the order of their own value references, each from max(own + 1, previous end);
    # the arrays and their shapes from the FMI 3.0 description (its <Dimension>s: n or nc)
    md3 = read_model_description(str(fmu3))
    size_of = {v.valueReference: {"n": n, "nc": nc}[v.name] for v in md3.modelVariables if v.name in ("n", "nc")}
    shapes = {v.name: tuple(size_of[d.valueReference] for d in v.dimensions) for v in md3.modelVariables
              if v.dimensions}
    assert shapes["M"] == (n, n) and shapes["W"] == (nc, n) and shapes["mode"] == (nc,) and len(shapes) >= 21
    own = {v.name: v.valueReference for v in md3.modelVariables if v.name in shapes}
    firsts, end = {}, 0
    for name in sorted(shapes, key=own.get):
        firsts[name] = max(own[name] + 1, end)
        end = firsts[name] + int(np.prod(shapes[name]))
    for name, shp in shapes.items():
        elements = [byname[name + "[" + ",".join(str(i + 1) for i in idx) + "]"].valueReference
                    for idx in np.ndindex(*shp)]
        assert elements == list(range(firsts[name], firsts[name] + len(elements)))
        assert len([v for v in byname if v.startswith(name + "[")]) == int(np.prod(shp))
    with zipfile.ZipFile(fmu2) as z:
        data = z.read(RESOURCE)
    version, nrec, fn, fnc = struct.unpack_from("<IIQQ", data, 8)
    nlay, zero = struct.unpack_from("<II", data, 32)
    assert (version, fn, fnc, zero, nlay) == (2, n, nc, 0, len(shapes))
    entries = [struct.unpack_from("<II", data, 40 + 8 * k) for k in range(nlay)]
    assert entries == sorted((own[a], firsts[a]) for a in shapes)
    assert [float(byname[f"M[{i + 1},{j + 1}]"].start) for i in range(n) for j in range(n)] == s.M.ravel().tolist()
    assert [float(byname[f"W[{j + 1},{i + 1}]"].start) for j in range(nc) for i in range(n)] == s.W.ravel().tolist()
    assert [float(byname[f"k_t[{j + 1}]"].start) for j in range(nc)] == [c.k_t for c in s.contacts]
    # a[i] depends on every input element F_ext[i] (the same element), N_ext, v_belt (all)
    a1 = next(u for u in md.outputs if u.variable.name == "a[1]")
    deps = sorted(d.name for d in a1.dependencies)
    assert deps == sorted(["F_ext[1]"] + [f"N_ext[{j + 1}]" for j in range(nc)]
                          + [f"v_belt[{j + 1}]" for j in range(nc)])


def _fmpy_fmi2(path: Path, n: int, nc: int, stop: float, dt: float) -> dict[str, np.ndarray]:
    names = [f"x[{i + 1}]" for i in range(n)] + [f"f[{j + 1}]" for j in range(nc)] + \
        [f"mode[{j + 1}]" for j in range(nc)] + ["E_friction"]
    res = simulate_fmu(str(path), stop_time=stop, output_interval=dt, output=names)
    return {"time": res["time"], "x": np.column_stack([res[f"x[{i + 1}]"] for i in range(n)]),
            "f": np.column_stack([res[f"f[{j + 1}]"] for j in range(nc)]),
            "mode": np.column_stack([res[f"mode[{j + 1}]"] for j in range(nc)]), "E_friction": res["E_friction"]}


def test_fmi2_at_any_size_is_the_fmi3_fmu_bit_for_bit(any_size: tuple[System, Path, Path]) -> None:
    """fmpy, no start values, on the FMI 2.0 and the FMI 3.0 FMU written for the structure: the same
    engine, the same numbers bit for bit; the run sticks and slips."""
    s, fmu2, fmu3 = any_size
    a = _fmpy_fmi2(fmu2, s.n, s.nc, 1.5, 0.01)
    b = simulate_fmu(str(fmu3), stop_time=1.5, output_interval=0.01, output=["x", "f", "mode", "E_friction"])
    assert np.array_equal(a["time"], b["time"])
    assert a["x"].tobytes() == np.asarray(b["x"], dtype=float).reshape(a["x"].shape).tobytes()
    assert a["f"].tobytes() == np.asarray(b["f"], dtype=float).reshape(a["f"].shape).tobytes()
    assert np.array_equal(a["mode"], np.asarray(b["mode"]).reshape(a["mode"].shape))
    assert a["E_friction"].tobytes() == np.asarray(b["E_friction"], dtype=float).tobytes()
    assert np.max(np.abs(a["x"])) > 1e-4 and a["E_friction"][-1] > 0  # it moves and friction works
    assert 0 in a["mode"] and np.any(a["mode"] != 0)  # sticks and slips
    ref = run(s, 1.5, 0.01)  # and the package's driver on the prebuilt FMI 3.0 FMU, values set
    assert a["x"].tobytes() == ref.x.tobytes()


def test_fmi2_at_any_size_states_and_unknown_references(any_size: tuple[System, Path, Path],
                                                        tmp_path: Path) -> None:
    """Get/set FMU state and its serialisation round trip at the file's sizes; a value reference
    beyond an array's elements refused with a sentence naming the array and its range."""
    s, fmu2, _ = any_size
    md = read_model_description(str(fmu2))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    xs = [vr[f"x[{i + 1}]"] for i in range(s.n)] + [vr["E_friction"]]
    d = extract(str(fmu2), unzipdir=str(tmp_path / "u"))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="DryFrictionSystem")
    slave.instantiate()
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(0.0, 0.3)
        state = slave.getFMUstate()
        blob = slave.serializeFMUstate(state)
        slave.doStep(0.3, 0.4)
        first = slave.getReal(xs)
        slave.setFMUstate(state)
        slave.doStep(0.3, 0.4)
        assert slave.getReal(xs) == first
        slave.doStep(0.7, 0.2)
        state2 = slave.deSerializeFMUstate(blob)
        slave.setFMUstate(state2)
        slave.doStep(0.3, 0.4)
        assert slave.getReal(xs) == first
        assert first == trajectory(s, [0.0, 0.7]).x[-1].tolist() + [first[-1]]
        slave.freeFMUstate(state)
        slave.freeFMUstate(state2)
    finally:
        slave.terminate()
        slave.freeInstance()
    inst = fmi2.Instance(d, md.guid, "DryFrictionSystem", name="vr")
    try:
        last = vr[f"x[{s.n}]"]
        with pytest.raises(FMUCallError) as err:
            inst.set("Real", [last + 1], [0.0])
        lo, hi = vr["x[1]"], last
        assert (f"value reference {last + 1} is no variable of this FMU: beyond the elements of x, x[1] to x[{s.n}] at "
                f"value references {lo} to {hi} (n = {s.n}, nc = {s.nc})") in str(err.value), str(err.value)
        with pytest.raises(FMUCallError) as err:  # M's own (FMI 3.0) value reference: no element
            inst.set("Real", [100000], [1.0])
        assert ("value reference 100000 is no variable of this FMU: no scalar has it and the array elements begin at "
                "100001 (M[1,1])") in str(err.value), str(err.value)
    finally:
        inst.free()


@pytest.mark.skipif(not FMUCHECK.is_file(), reason="the Compliance Checker not there (../shared/tools/fmucheck; "
                                                   "or set FMUCHECK)")
def test_the_compliance_checker_runs_fmi2_at_any_size(any_size: tuple[System, Path, Path], tmp_path: Path) -> None:
    s, fmu2, _ = any_size
    out, log = tmp_path / "out.csv", tmp_path / "log.txt"
    r = subprocess.run([str(FMUCHECK), "-h", "0.01", "-s", "1", "-o", str(out), "-e", str(log), str(fmu2)],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    report = log.read_text(errors="replace") + r.stdout
    assert "0 warning(s) and error(s)" in report, report
    lines = out.read_text().splitlines()
    head = [h.strip('"') for h in lines[0].split(",")]
    last = [float(v) for v in lines[-1].split(",")]
    ref = run(s, 1.0, 0.01)
    assert last[0] == 1.0
    for i in range(s.n):
        assert last[head.index(f"x[{i + 1}]")] == pytest.approx(ref.x[-1, i], rel=1e-15, abs=1e-300)


def test_fmi2_a_start_value_set_by_the_host_is_used(any_size: tuple[System, Path, Path]) -> None:
    """fmpy setting an element's start (F_c[n], the last DOF's excitation) on the FMI 2.0 FMU: the
    run of the structure with that value, bit for bit."""
    s, fmu2, _ = any_size
    F_c = s.F_c.copy()
    F_c[-1] = 3.0
    a = simulate_fmu(str(fmu2), stop_time=0.5, output_interval=0.01, start_values={f"F_c[{s.n}]": 3.0},
                     output=[f"x[{i + 1}]" for i in range(s.n)])
    ref = run(s.replace(F_c=F_c), 0.5, 0.01)
    assert np.column_stack([a[f"x[{i + 1}]"] for i in range(s.n)]).tobytes() == ref.x.tobytes()
    assert ref.x.tobytes() != run(s, 0.5, 0.01).x.tobytes()


def test_fmi2_written_at_the_builds_sizes_is_the_generators_description(written2: Path) -> None:
    """The writer's flattening (from each array's first element) against the generator's own at the
    binary's sizes (n = 2, nc = 1): the same variables, value references, descriptions and model
    structure; only the start values, the name and the description differ."""
    import xml.etree.ElementTree as ET

    from dryfriction import paths

    with zipfile.ZipFile(paths.fmu_path(paths.SYSTEM)) as z:
        base = ET.fromstring(z.read("modelDescription.xml"))
    with zipfile.ZipFile(written2) as z:
        ours = ET.fromstring(z.read("modelDescription.xml"))

    def variables(root: ET.Element) -> list[tuple]:
        return [(v.get("name"), v.get("valueReference"), v.get("causality"), v.get("description"), next(iter(v)).tag,
                 next(iter(v)).get("unit")) for v in root.iterfind("ModelVariables/ScalarVariable")]

    def structure(root: ET.Element) -> list[tuple]:
        return [(part.tag, u.get("index"), u.get("dependencies")) for part in root.find("ModelStructure")
                for u in part]

    assert variables(ours) == variables(base) and len(variables(base)) > 40
    assert structure(ours) == structure(base) and len(structure(base)) > 15
    lay = "VendorAnnotations/Tool[@name='dryfriction.layout']/Layout/Array"
    assert [a.attrib for a in ours.iterfind(lay)] == [a.attrib for a in base.iterfind(lay)]


def test_fmi2_a_bad_layout_in_the_file_is_named(tmp_path: Path) -> None:
    """The layout section of the structure file checked at instantiation: an array's elements put
    before its own value reference, and an array missing."""
    s = structure_of(3, 2, 12)
    fmu2 = write_fmu(s, tmp_path / "L.fmu", fmi=2)
    with zipfile.ZipFile(fmu2) as z:
        data = bytearray(z.read(RESOURCE))
    md = read_model_description(str(fmu2))
    bad = bytearray(data)
    assert struct.unpack_from("<II", bad, 40) == (100000, 100001)  # M's entry
    struct.pack_into("<I", bad, 44, 99999)
    d = extract(str(_rewrite(fmu2, tmp_path / "B1.fmu", bytes(bad))), unzipdir=str(tmp_path / "b1"))
    with pytest.raises(FMUCallError) as err:
        fmi2.Instance(d, md.guid, "DryFrictionSystem", name="bad")
    assert "structure.bin puts the 9 elements of M at the value references from 99999; valid: from 100001 (after " \
        "its own 100000 and the previous array's elements), the last at most 4294967295" in str(err.value), str(err.value)
    bad = bytearray(data)
    nlay = struct.unpack_from("<I", bad, 32)[0]
    assert nlay >= 21
    struct.pack_into("<I", bad, 32, nlay - 1)
    d = extract(str(_rewrite(fmu2, tmp_path / "B2.fmu", bytes(bad))), unzipdir=str(tmp_path / "b2"))
    with pytest.raises(FMUCallError) as err:
        fmi2.Instance(d, md.guid, "DryFrictionSystem", name="bad")
    assert f"structure.bin has a layout of {nlay - 1} arrays; this FMU has {nlay}" in str(err.value), str(err.value)


def test_fmi2_a_state_of_other_sizes_is_refused(tmp_path: Path) -> None:
    """The same binary (the same instantiation token) written for n = 3, nc = 2 and n = 1, nc = 1: a
    state serialised by the one is refused by the other, in a sentence with both sizes; by its own
    instance it is taken."""
    insts = []
    try:
        for n, nc, seed in ((3, 2, 12), (1, 1, 11)):
            fmu2 = write_fmu(structure_of(n, nc, seed), tmp_path / f"S{n}.fmu", fmi=2)
            md = read_model_description(str(fmu2))
            inst = fmi2.Instance(extract(str(fmu2), unzipdir=str(tmp_path / f"u{n}")), md.guid, "DryFrictionSystem",
                                 name=f"s{n}")
            insts.append(inst)
            inst.setup_experiment(0.0)
            inst.enter_initialization_mode()
            inst.exit_initialization_mode()
            inst.do_step(0.0, 0.1)
        blob = insts[0].serialize_state(insts[0].get_state())
        insts[0].set_state(insts[0].deserialize_state(blob))
        with pytest.raises(FMUCallError) as err:
            insts[1].deserialize_state(blob)
        assert "rejected, its sizes n = 3, nc = 2 are not this instance's (n = 1, nc = 1, from its structure file or " \
            "its build)" in str(err.value), str(err.value)
    finally:
        for inst in insts:
            inst.free()


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no gcc")
def test_fmi2_at_another_size_rebuilds_from_its_sources(tmp_path: Path) -> None:
    """The written FMI 2.0 FMU (n = 3, nc = 2) rebuilt from its sources/ (a plain C99 compile of the
    listed files: its binary's own sizes in system_config.h, the structure's in the file) runs the
    structure: the prebuilt FMI 3.0 FMU's numbers."""
    s = structure_of(3, 2, 12)
    fmu2 = write_fmu(s, tmp_path / "R.fmu", fmi=2)
    md = read_model_description(str(fmu2))
    d = Path(extract(str(fmu2), unzipdir=str(tmp_path / "r")))
    files = [str(d / "sources" / f) for f in md.buildConfigurations[0].sourceFileSets[0].sourceFiles]
    so = d / "binaries" / "linux64" / "DryFrictionSystem.so"
    so.unlink()
    r = subprocess.run(["gcc", "-std=c99", "-O1", "-shared", "-fPIC", "-I", str(d / "sources"), *files, "-o", str(so),
                        "-lm", "-Wl,--no-undefined"], capture_output=True, text=True, timeout=300,
                       env={k: v for k, v in os.environ.items() if k != "LD_PRELOAD"})  # gcc: not our C
    assert r.returncode == 0, r.stderr
    vr = {v.name: v.valueReference for v in md.modelVariables}
    inst = fmi2.Instance(str(d), md.guid, "DryFrictionSystem", name="rebuilt")
    try:
        inst.setup_experiment(0.0)
        inst.enter_initialization_mode()
        inst.exit_initialization_mode()
        inst.do_step(0.0, 0.5)
        x = inst.get("Real", [vr[f"x[{i + 1}]"] for i in range(3)])
    finally:
        inst.free()
    ref = trajectory(s, [0.0, 0.5]).x[-1]
    assert x == ref.tolist() and np.max(np.abs(ref)) > 1e-3  # the same IEEE operations: bit for bit


def test_the_layout_lets_an_array_run_past_the_next_ones_own_reference() -> None:
    """The layout rule (dryfriction.model.fmi2_layout, the generator's): M's n^2 elements beyond
    C's own value reference push C's after them; beyond 32 bits an error naming the array."""
    from dryfriction.model import fmi2_layout

    arrays = [("C", 200000, ("n", "n")), ("M", 100000, ("n", "n")), ("W", 800000, ("nc", "n"))]
    lay = {a.name: a for a in fmi2_layout(arrays, {"n": 320, "nc": 2}, [("omega", 3)])}
    assert (lay["M"].first, lay["C"].first, lay["W"].first) == (100001, 100001 + 320**2, 800001)
    assert lay["C"].elements()[-1] == ((320, 320), 100001 + 2 * 320**2 - 1)
    with pytest.raises(ValueError, match=r"with n = 70000, nc = 2 the FMI 2\.0 value references of M end at "
                                         r"4900100000, beyond 32 bits \(4294967295\)"):
        fmi2_layout(arrays, {"n": 70000, "nc": 2})
    with pytest.raises(ValueError, match=r"scalar omega: value reference 100000 is not below the arrays' \(M: 100000\)"):
        fmi2_layout(arrays, {"n": 2, "nc": 1}, [("omega", 100000)])


@pytest.mark.skipif(not FMUSIM.is_file(), reason="fmusim not there (../shared/tools/fmusim; or set FMUSIM)")
def test_fmusim_runs_fmi2_at_any_size(any_size: tuple[System, Path, Path], tmp_path: Path) -> None:
    s, fmu2, _ = any_size
    out = tmp_path / "out.csv"
    r = subprocess.run([str(FMUSIM), "--interface-type", "cs", "--output-interval", "0.01", "--stop-time", "1",
                        "--output-file", str(out), str(fmu2)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = out.read_text().splitlines()
    head = next(csv.reader([lines[0]]))  # (quoted names: the Jacobian's dx_dx0[1,2] hold a comma)
    last = lines[-1].split(",")
    assert len(head) == len(last)
    ref = run(s, 1.0, 0.01)
    assert float(last[0]) == 1.0 and len(lines) == ref.t.size + 1
    x = [float(last[head.index(f"x[{i + 1}]")]) for i in range(s.n)]
    assert np.allclose(x, ref.x[-1], rtol=1e-15, atol=1e-17)  # fmusim prints 16 significant digits
    assert [int(last[head.index(f"mode[{j + 1}]")]) for j in range(s.nc)] == ref.mode[-1].tolist()


def test_the_run_command_is_system_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    spec = tmp_path / "one.toml"
    spec.write_text("[structure]\nM = [[1.0]]\nK = [[100.0]]\n[excitation]\nomega = 5.0\nF_c = [1.0]\n"
                    "[[contact]]\ndof = 0\nN = 1.0\nmu_s = 0.4\nmu_k = 0.3\n", encoding="utf-8")
    assert main(["system", "run", str(spec), "--t-end", "2", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    ref = run(System.from_file(spec), 2.0)  # dt: 1/100 of the excitation period
    assert np.array_equal(got["t"], ref.t) and np.array_equal(got["x"], ref.x.tolist())
    assert got["mode"] == ref.mode.tolist() and {-1, 0, 1} <= {m[0] for m in got["mode"]}
