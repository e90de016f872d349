"""The FMI 3.0 FMU's model description says what the FMI 2.0 one says (both generated from the one
modelDescription.xml), plus the independent variable time and the FMI 3.0 capabilities; fmpy and
fmu-manipulation-toolbox find it valid; the archive holds binaries/x86_64-linux and buildable
sources."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from fmi3_helpers import FMU2, FMU3

TYPES_2_TO_3 = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration", "Boolean": "Boolean"}


@pytest.fixture(scope="module")
def md2():
    return read_model_description(str(FMU2))


@pytest.fixture(scope="module")
def md3():
    if not FMU3.is_file():
        pytest.fail(f"FMI 3.0 FMU not built: {FMU3}")
    return read_model_description(str(FMU3))


@pytest.mark.min_versions
def test_fmpy_validate_finds_no_problem() -> None:
    assert validate_fmu(str(FMU3)) == []


def test_fmutool_check_reports_compliant() -> None:
    exe = shutil.which("fmutool") or str(Path(sys.executable).with_name("fmutool"))
    r = subprocess.run([exe, "-input", str(FMU3), "-check"], capture_output=True, text=True, timeout=120)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert "compliant with FMI-3.0" in out, out
    assert "No semantic error" in out, out
    assert "ERROR" not in out, out


def test_same_variables_as_fmi2(md2, md3) -> None:
    v3 = {v.name: v for v in md3.modelVariables}
    assert set(v3) == {v.name for v in md2.modelVariables} | {"time"}
    for a in md2.modelVariables:
        b = v3[a.name]
        assert b.type == TYPES_2_TO_3[a.type], a.name
        for attr in ("valueReference", "causality", "variability", "initial", "description", "unit",
                     "declaredType"):
            da, db = getattr(a, attr), getattr(b, attr)
            if attr == "declaredType":
                da, db = da and da.name, db and db.name
            assert da == db, (a.name, attr, da, db)
        for attr in ("min", "max", "start"):
            da, db = getattr(a, attr), getattr(b, attr)
            if da is None or db is None:
                assert da == db, (a.name, attr, da, db)
            elif a.type == "Boolean":
                assert str(da).lower() == str(db).lower(), (a.name, attr)
            else:
                assert float(da) == float(db), (a.name, attr, da, db)


def test_independent_time_variable(md3) -> None:
    time = [v for v in md3.modelVariables if v.causality == "independent"]
    assert len(time) == 1
    assert (time[0].name, time[0].valueReference, time[0].type, time[0].unit) == ("time", 0, "Float64", "s")


def test_enumeration_and_units_carried_over(md2, md3) -> None:
    t2 = {t.name: [(i.name, i.value) for i in t.items] for t in md2.typeDefinitions}
    t3 = {t.name: [(i.name, i.value) for i in t.items] for t in md3.typeDefinitions}
    assert t2 == t3
    assert [u.name for u in md2.unitDefinitions] == [u.name for u in md3.unitDefinitions]
    assert md3.defaultExperiment.stopTime == md2.defaultExperiment.stopTime
    assert md3.guid == md2.guid  # the instantiation token is the FMI 2.0 GUID


def test_output_dependencies_by_value_reference(md2, md3) -> None:
    def deps(md):
        return {u.variable.name: sorted(d.name for d in (u.dependencies or [])) for u in md.outputs}
    assert deps(md2) == deps(md3)
    assert {u.variable.name for u in md2.initialUnknowns} == {u.variable.name for u in md3.initialUnknowns}


def test_capabilities(md3) -> None:
    import xml.etree.ElementTree as ET
    root = ET.fromstring(zipfile.ZipFile(FMU3).read("modelDescription.xml"))
    cs = root.find("CoSimulation")
    for flag in ("canHandleVariableCommunicationStepSize", "canGetAndSetFMUState", "canSerializeFMUState",
                 "hasEventMode", "mightReturnEarlyFromDoStep", "canReturnEarlyAfterIntermediateUpdate",
                 "providesIntermediateUpdate"):
        assert cs.get(flag) == "true", flag
    assert root.find("ModelExchange") is None and root.find("ScheduledExecution") is None
    assert md3.coSimulation.modelIdentifier == "DryFrictionOscillator"


def test_archive_layout_and_build_description() -> None:
    names = set(zipfile.ZipFile(FMU3).namelist())
    assert "binaries/x86_64-linux/DryFrictionOscillator.so" in names
    md = read_model_description(str(FMU3))
    sources = md.buildConfigurations[0].sourceFileSets[0].sourceFiles
    assert "fmi3_cs.c" in sources and "fmi2_cs.c" not in sources
    for src in sources:
        assert f"sources/{src}" in names


def test_every_fmi3_function_exported() -> None:
    header = Path(__import__("fmpy").__file__).parent / "c-code" / "fmi3FunctionTypes.h"
    import re
    wanted = set(re.findall(r"\b(fmi3\w+)TYPE\b", header.read_text()))
    so = FMU3.parent / "lib" / "DryFrictionOscillator.so"
    out = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in out.splitlines() if line.strip()}
    assert wanted, "no function types found in fmi3FunctionTypes.h"
    assert wanted - exported == set()
    assert exported - wanted == set(), "only fmi3 functions are visible"
