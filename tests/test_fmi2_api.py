"""The FMI 2.0 oscillator and the rules of the standard. Static: fmpy's validation and the FMU
Manipulation Toolbox find it compliant, the archive's layout, only fmi2 functions exported, a wrong
GUID refused, the log categories honoured (the static checks also over the TwoMass FMU). Misuse, through fmpy's FMU2Slave (and its raw ctypes
functions where fmpy hides the call): every case returns fmi2Error (or fmi2Discard) with a logged
sentence that names the variable / value / range, and the process and the instance keep working;
steps that must not hang.

Checked once, in the C API tests (tests/fmi_c) and not again here: every invalid parameter value,
NULL instances and arrays, instantiate rejections, overflow, 32 instances in parallel threads, 10^4
instantiate/free cycles. FMU states (forged serialised states among them): test_fmu_state.py. The
package's own driver (OscillatorFMU2): test_fmi_layer.py.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
import textwrap
import zipfile
from ctypes import c_int, c_void_p
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from dryfriction.fmi import fmi2
from dryfriction.drivers.oscillator import FMUError, OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from fmi2_helpers import Inst, fmi2Error, fmi2LastSuccessfulTime


# --------------------------------------------------------------------------- plumbing


def still_usable(i: Inst) -> None:
    """After fmi2Reset the instance runs a valid simulation to the right numbers."""
    i.s.reset()
    i.init(h=1e-3)
    i.s.doStep(0.0, 0.1)
    x = i.s.getReal([i.vr("x")])[0]
    assert math.isfinite(x) and x != 0.0


# --------------------------------------------------------------------------- call order


def test_wrong_call_order(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    inst.expect_error(s.doStep, 0.0, 0.1, contains=("fmi2DoStep", "instantiated"))
    inst.expect_error(s.exitInitializationMode, contains=("fmi2ExitInitializationMode", "instantiated"))
    inst.expect_error(s.getReal, [vr("x")], contains=("fmi2GetReal", "instantiated"))
    inst.expect_error(s.terminate, contains=("fmi2Terminate",))
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    inst.expect_error(s.enterInitializationMode, contains=("initialization mode",))
    inst.expect_error(s.setupExperiment, None, 0.0, contains=("fmi2SetupExperiment", "initialization mode"))
    inst.expect_error(s.doStep, 0.0, 0.1, contains=("fmi2DoStep", "initialization mode"))
    s.exitInitializationMode()
    inst.expect_error(s.exitInitializationMode, contains=("step mode",))
    s.doStep(0.0, 0.1)
    s.terminate()
    inst.expect_error(s.doStep, 0.1, 0.1, contains=("fmi2DoStep", "terminated"))
    inst.expect_error(s.setReal, [vr("F_ext")], [1.0], contains=("fmi2SetReal", "terminated"))
    assert math.isfinite(s.getReal([vr("x")])[0])  # outputs stay readable after terminate
    still_usable(inst)


def test_communication_point_and_step_size(inst: Inst) -> None:
    s = inst.s
    inst.init()
    s.doStep(0.0, 0.1)
    inst.expect_error(s.doStep, 0.2, 0.1, contains=("currentCommunicationPoint", "0.20000000000000001", "0.1"))
    inst.expect_error(s.doStep, 0.0, 0.1, contains=("currentCommunicationPoint",))
    for dt, text in ((0.0, "0"), (-0.1, "-0.1"), (math.nan, "nan"), (math.inf, "inf")):
        inst.expect_error(s.doStep, 0.1, dt, contains=("communicationStepSize", text, "> 0"))
    s.doStep(0.1, 0.05)  # nothing above changed the state
    assert s.getRealStatus(fmi2LastSuccessfulTime) == 0.1 + 0.05


def test_nan_communication_point_is_named(inst: Inst) -> None:
    """currentCommunicationPoint = NaN (or inf) is refused with a sentence naming
    currentCommunicationPoint (not the step size, which is valid)."""
    s = inst.s
    inst.init()
    for tc in (math.nan, math.inf):
        inst.expect_error(s.doStep, tc, 0.1, contains=("currentCommunicationPoint", f"{tc}"))
    s.doStep(0.0, 0.1)


def test_stop_time(inst: Inst) -> None:
    s = inst.s
    inst.expect_error(s.setupExperiment, None, 1.0, 0.5, contains=("stopTime", "0.5", "startTime"))
    s.setupExperiment(startTime=0.0, stopTime=0.2)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 0.2)
    inst.expect_error(s.doStep, 0.2, 0.1, contains=("stop time", "0.2"))


def test_fixed_parameter_after_initialisation(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    inst.init()
    inst.expect_error(s.setReal, [vr("m")], [2.0], contains=("m", "fixed parameter", "step mode"))
    inst.expect_error(s.setInteger, [vr("scheme")], [1], contains=("scheme", "fixed parameter"))
    inst.expect_error(s.setBoolean, [vr("observe")], [True], contains=("observe", "fixed parameter"))
    inst.expect_error(s.setReal, [vr("x")], [1.0], contains=("x", "output"))
    inst.expect_error(s.setReal, [vr("dx_dx0")], [1.0], contains=("dx_dx0", "is a local variable and cannot be set"))
    inst.expect_error(s.setInteger, [vr("effects")], [0], contains=("effects", "calculated parameter"))
    s.setReal([vr("F_ext")], [0.5])  # inputs may be set in step mode
    s.doStep(0.0, 0.01)
    assert s.getReal([vr("m")])[0] == 1.0


def test_unknown_value_references_and_types(inst: Inst) -> None:
    s, vr = inst.s, inst.vr
    inst.init()
    for bad in (0, 22, 99, 2**32 - 1):
        inst.expect_error(s.getReal, [bad], contains=("unknown value reference", str(bad)))
        inst.expect_error(s.setReal, [bad], [1.0], contains=("unknown value reference", str(bad)))
        inst.expect_error(s.getInteger, [bad], contains=(str(bad),))
        inst.expect_error(s.getBoolean, [bad], contains=(str(bad),))
    inst.expect_error(s.getReal, [vr("mode")], contains=("mode", "Integer", "not Real"))
    inst.expect_error(s.setInteger, [vr("m")], [1], contains=("m", "Real", "not Integer"))
    inst.expect_error(s.getString, [vr("m")], contains=("String",))
    inst.expect_error(s.setString, [vr("m")], ["x"], contains=("String",))
    # a rejected call changes nothing, even its valid part
    inst.expect_error(s.setReal, [vr("F_ext"), 99], [3.0, 1.0], contains=("99",))
    assert s.getReal([vr("F_ext")])[0] == 0.0


def test_unsupported_functions_report(inst: Inst) -> None:
    s = inst.s
    inst.init()
    inst.expect_error(s.cancelStep, contains=("fmi2CancelStep",))
    inst.expect_error(s.getStatus, 0, contains=("fmi2GetStatus",))
    # the coupling functions exist (tests/test_coupling_fmu.py); out of their range they say why
    inst.expect_error(s.setRealInputDerivatives, [inst.vr("F_ext")], [3], [1.0], contains=("F_ext", "1 to 2"))
    inst.expect_error(s.getRealOutputDerivatives, [inst.vr("a")], [1], contains=("no output derivative for a",))
    inst.expect_error(s.getDirectionalDerivative, [inst.vr("x")], [inst.vr("m")], [1.0],
                      contains=("known m", "not an input"))
    for name in ("fmi2EnterEventMode", "fmi2EnterContinuousTimeMode"):
        getattr(s.dll, name).argtypes = [c_void_p]
        getattr(s.dll, name).restype = c_int
        assert inst.raw(name, s.component) == fmi2Error
        # the FMU has Model Exchange too (tests/test_model_exchange.py): not through this instance
        assert "made for co-simulation" in inst.cb.last_error()
    inst.expect_error(s.setDebugLogging, True, ["noSuchCategory"], contains=("noSuchCategory",))
    s.doStep(0.0, 0.01)


# --------------------------------------------------------------------------- parameter values


@pytest.mark.parametrize("reals", [{"P0": 1e307, "N": 0.0, "omega": 0.0, "k": 1e-100},
                                   {"P0": 1e307, "N": 1.0, "omega": 0.0, "k": 1e-100}],
                         ids=["huge-force", "huge-force-through-the-LCP"])
def test_failed_step_leaves_the_last_good_state(inst: Inst, reals: dict[str, float]) -> None:
    """When a doStep fails (overflow), the outputs the host can still read are the last good ones
    (finite) and fmi2LastSuccessfulTime is the start of the failed step, not the time of the
    failure inside it."""
    s = inst.s
    inst.init(h=1e-3, **reals)
    s.doStep(0.0, 0.005)
    inst.expect_error(s.doStep, 0.005, 5.0, contains=("non-finite",))
    vrs = [inst.vr(n) for n in ("x", "v", "a", "F_friction", "x_max", "x_min", "stick_fraction", "E_friction")]
    out = s.getReal(vrs)
    assert all(math.isfinite(v) for v in out), f"outputs after the failed step: {out}"
    assert s.getRealStatus(fmi2LastSuccessfulTime) == 0.005


def test_subnormal_mass_is_refused_or_finite(inst: Inst) -> None:
    """m = 2.1e-314 (subnormal, inside "> 0"): found by the fuzzer, the acceleration output is
    inf with fmi2OK right after initialisation. Either the value is refused with a sentence, or
    every output is finite."""
    s = inst.s
    s.setupExperiment(startTime=0.0)
    try:
        s.setReal([inst.vr("m")], [2.1219957909652723e-314])
        s.enterInitializationMode()
        s.exitInitializationMode()
    except FMICallException:
        assert "m" in inst.cb.last_error()
        return
    out = s.getReal([inst.vr(n) for n in ("x", "v", "a", "F_friction")])
    assert all(math.isfinite(v) for v in out), f"outputs {out}"


# ------------------------------------------------------------------------ steps that must not hang


def test_tiny_internal_step_does_not_hang() -> None:
    """h = 1e-300 is inside the declared range (> 0); a doStep of 1 ms must then come back (with
    an error naming h, or done), not spin for 10^297 internal steps (child process, 10 s limit)."""
    code = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
        from dryfriction.params import Oscillator
        f = OscillatorFMU2()
        f.start(Oscillator(), Settings(h=1e-300))
        try:
            f.step_to(1e-3)
            print("returned ok")
        except Exception as e:
            print("returned", e)
    """)
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=10)
    except subprocess.TimeoutExpired:
        pytest.fail("fmi2DoStep(0, 1e-3) with h = 1e-300 did not return within 10 s")
    assert "returned" in r.stdout, r.stderr


# --------------------------------------- static checks, the archive, exports, GUID, log categories

@pytest.fixture(params=["oscillator", "two_mass"])
def any_fmu_path(request: pytest.FixtureRequest) -> Path:
    """The FMI 2.0 FMUs the standard's static checks run over: the oscillator's and the TwoMass
    model's (a folder on the friction engine; test_two_mass_fmu.py)."""
    if request.param == "oscillator":
        return request.getfixturevalue("fmu_path")
    from test_two_mass_fmu import FMU2
    return FMU2


@pytest.mark.min_versions
def test_fmpy_validate_finds_no_problem(any_fmu_path: Path) -> None:
    assert validate_fmu(str(any_fmu_path)) == []


@pytest.mark.min_versions
def test_fmutool_check_reports_compliant(any_fmu_path: Path) -> None:
    exe = shutil.which("fmutool") or str(Path(sys.executable).with_name("fmutool"))
    r = subprocess.run([exe, "-input", str(any_fmu_path), "-check"], capture_output=True, text=True, timeout=120)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert "compliant with FMI-2.0" in out, out
    assert "No semantic error" in out, out
    assert "ERROR" not in out, out


def test_archive_layout(any_fmu_path: Path) -> None:
    names = set(zipfile.ZipFile(any_fmu_path).namelist())
    md = read_model_description(str(any_fmu_path))
    assert "modelDescription.xml" in names
    assert f"binaries/linux64/{md.coSimulation.modelIdentifier}.so" in names
    sources = md.buildConfigurations[0].sourceFileSets[0].sourceFiles
    assert sources
    for src in sources:
        assert f"sources/{src}" in names
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    assert md.coSimulation.canHandleVariableCommunicationStepSize


def test_only_fmi2_functions_are_exported(any_fmu_path: Path, tmp_path: Path) -> None:
    ident = read_model_description(str(any_fmu_path)).coSimulation.modelIdentifier
    with zipfile.ZipFile(any_fmu_path) as z:
        so = tmp_path / "dfo.so"
        so.write_bytes(z.read(f"binaries/linux64/{ident}.so"))
    out = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    symbols = {line.split()[-1] for line in out.splitlines() if line.split()[1:2] == ["T"]}
    assert symbols, out
    assert all(s.startswith("fmi2") for s in symbols), sorted(s for s in symbols if not s.startswith("fmi2"))
    for required in ("fmi2Instantiate", "fmi2DoStep", "fmi2GetFMUstate", "fmi2DeSerializeFMUstate",
                     "fmi2SetTime", "fmi2GetDerivatives", "fmi2Reset"):
        assert required in symbols


def test_wrong_guid_is_refused(fmu: OscillatorFMU2) -> None:
    with pytest.raises(FMUError, match="does not match the FMU's GUID") as err:
        fmi2.Instance(fmu.unzip_dir, "{00000000-0000-0000-0000-000000000000}", fmu.md.model_identifier, "wrong-guid")
    assert err.value.function == "fmi2Instantiate"


def test_log_categories_are_honoured(fmu_path: Path) -> None:
    """logEvents reports every stick/slip switch when on, nothing when off."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7)
    for on in (True, False):
        with OscillatorFMU2(fmu_path, logging=on) as f:
            f.trajectory(p, [0.0, 2 * p.period], Settings(h=p.period / 1000))
            events = [m for s, c, m in f.messages if c == "logEvents" and "->" in m]
            calls = [m for s, c, m in f.messages if c == "logAll"]
            if on:
                assert len(events) >= 4 and any("stick -> " in m for m in events), events
                assert "fmi2DoStep" in calls
            else:
                assert events == [] and calls == []
    with OscillatorFMU2(fmu_path) as f:
        with pytest.raises(FMUError, match="fmi2SetDebugLogging returned fmi2Error"):
            f.set_debug_logging(True, ["noSuchCategory"])
        assert any("unknown log category noSuchCategory" in m for s, c, m in f.messages)
