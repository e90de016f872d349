"""The FMI 3.0 oscillator and the rules of the standard: fmpy and fmu-manipulation-toolbox find it
valid, its capabilities, the archive (binaries/x86_64-linux, buildable sources), every fmi3 function
exported, fmi3UpdateDiscreteStates' report and phase rules, fmi3EnterEventMode only with event mode
(the static checks also over the TwoMass FMU).
(Its model description against the FMI 2.0 one: test_model_description.py; events:
test_fmi3_events.py; the C hosts: tests/fmi3_c.)"""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from dryfriction.drivers.oscillator3 import OscillatorFMU3

from fmi3_helpers import DT, FMU3


def _fmu3_of(model: str) -> Path:
    """The FMI 3.0 FMU of a model: the oscillator's, or the TwoMass model's (test_two_mass_fmu.py)."""
    if model == "oscillator":
        return FMU3
    from test_two_mass_fmu import FMU3 as TWO_MASS_FMU3
    return TWO_MASS_FMU3


@pytest.mark.min_versions
@pytest.mark.parametrize("model", ["oscillator", "two_mass"])
def test_fmpy_validate_finds_no_problem(model: str) -> None:
    assert validate_fmu(str(_fmu3_of(model))) == []


@pytest.mark.parametrize("model", ["oscillator", "two_mass"])
def test_fmutool_check_reports_compliant(model: str) -> None:
    exe = shutil.which("fmutool") or str(Path(sys.executable).with_name("fmutool"))
    r = subprocess.run([exe, "-input", str(_fmu3_of(model)), "-check"], capture_output=True, text=True, timeout=120)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert "compliant with FMI-3.0" in out, out
    assert "No semantic error" in out, out
    assert "ERROR" not in out, out


def test_capabilities(md3) -> None:
    import xml.etree.ElementTree as ET
    root = ET.fromstring(zipfile.ZipFile(FMU3).read("modelDescription.xml"))
    cs = root.find("CoSimulation")
    for flag in ("canHandleVariableCommunicationStepSize", "canGetAndSetFMUState", "canSerializeFMUState",
                 "hasEventMode", "mightReturnEarlyFromDoStep", "canReturnEarlyAfterIntermediateUpdate",
                 "providesIntermediateUpdate"):
        assert cs.get(flag) == "true", flag
    assert root.find("ScheduledExecution") is None
    # Model Exchange too (tests/test_model_exchange.py), from the same library
    me = root.find("ModelExchange")
    assert me.get("modelIdentifier") == cs.get("modelIdentifier") and me.get("needsCompletedIntegratorStep") == "true"
    assert md3.coSimulation.modelIdentifier == "DryFrictionOscillator"


@pytest.mark.parametrize("model", ["oscillator", "two_mass"])
def test_archive_layout_and_build_description(model: str) -> None:
    fmu3 = _fmu3_of(model)
    names = set(zipfile.ZipFile(fmu3).namelist())
    md = read_model_description(str(fmu3))
    assert f"binaries/x86_64-linux/{md.coSimulation.modelIdentifier}.so" in names
    sources = md.buildConfigurations[0].sourceFileSets[0].sourceFiles
    assert "fmi3_cs.c" in sources and "fmi2_cs.c" not in sources
    for src in sources:
        assert f"sources/{src}" in names


@pytest.mark.parametrize("model", ["oscillator", "two_mass"])
def test_every_fmi3_function_exported(model: str) -> None:
    header = Path(__import__("fmpy").__file__).parent / "c-code" / "fmi3FunctionTypes.h"
    import re
    wanted = set(re.findall(r"\b(fmi3\w+)TYPE\b", header.read_text()))
    fmu3 = _fmu3_of(model)
    so = fmu3.parent / "lib" / f"{read_model_description(str(fmu3)).coSimulation.modelIdentifier}.so"
    out = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in out.splitlines() if line.strip()}
    assert wanted, "no function types found in fmi3FunctionTypes.h"
    assert wanted - exported == set()
    assert exported - wanted == set(), "only fmi3 functions are visible"


# ------------------------------------------------------ phases: update discrete states, event mode

def test_update_discrete_states_report_and_phase_rules() -> None:
    fmu = OscillatorFMU3({}, early_return=True, event_mode=True)
    try:
        s = fmu.slave
        # a switch: eventHandlingNeeded with earlyReturn
        while True:
            event, early = fmu.do_step(DT)
            if event:
                break
        assert early
        left = fmu.get(["mode", "F_friction", "a", "x", "v"])
        s.enterEventMode()
        state = s.getFMUState()
        assert s.updateDiscreteStates() == (False, False, False, False, False, 0.0)
        right = fmu.get(["mode", "F_friction", "a", "x", "v"])
        assert left["mode"] != right["mode"]
        assert (left["x"], left["v"]) == (right["x"], right["v"])  # continuous across the switch
        # a second update has nothing left to do
        assert s.updateDiscreteStates()[0] is False
        assert fmu.get(["mode"])["mode"] == right["mode"]
        # the state taken in event mode holds the pending event (left limits), also serialised
        blob = s.serializeFMUState(state)
        s.setFMUState(s.deserializeFMUState(blob))
        assert fmu.get(["mode", "F_friction", "a", "x", "v"]) == left
        with pytest.raises(FMICallException):
            s.doStep(fmu.time, DT)  # not in event mode
        s.updateDiscreteStates()
        s.enterStepMode()
        fmu.do_step(DT)
        s.freeFMUState(state)
    finally:
        fmu.close()


def test_enter_event_mode_needs_event_mode_used() -> None:
    fmu = OscillatorFMU3({}, early_return=True)
    try:
        with pytest.raises(FMICallException):
            fmu.slave.enterEventMode()
    finally:
        fmu.close()
