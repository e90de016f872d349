"""The model description is the FMU's single source of truth, and it tells the truth.

- the valid ranges are FMI min/max attributes, and the binary enforces exactly them (the C table
  is generated from the XML);
- the effect bits are a machine-readable vendor annotation, and the `effects` value follows them;
- a value the run has not computed (the observables while `observe` is false; x_max, x_min before
  the window's first sample) reads NaN (transitions -1) with fmi2OK and one logNotComputed sentence
  per run saying "set observe = true", as their descriptions say; `observe` is on by default;
- `<ModelStructure>` declares which outputs follow the inputs at once (a, F_friction) and which only
  through the state: setting an input and reading the outputs without a step agrees with it;
- author, copyright, license (BSD-2-Clause, LICENSE shipped in the FMU), generationDateAndTime;
- the FMU's own description equals the repository's and drives the FMU (dryfriction.model reads what
  the XML declares: names, ranges, schemes, effect bits);
- the FMI 3.0 description says what the FMI 2.0 one says (both generated from the one
  modelDescription.xml), plus the independent variable time, with the same enumeration, units and
  output dependencies;
- the sensitivity's Jacobian (dx_dx0 ... dv_dv0) is local in both versions, in neither <Outputs> nor
  <InitialUnknowns>, and the generator refuses a <ModelStructure> that lists anything but what FMI
  asks for.
"""

from __future__ import annotations

import math
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Iterator
from ctypes import c_double, c_int, c_uint
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException, calloc, free
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)

from dryfriction import model
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator
from dryfriction.sweep.runner import PARAM_COLUMNS


ROOT = Path(__file__).resolve().parents[1]
XML = ROOT / "modelDescription.xml"
fmi2OK, fmi2Warning = 0, 1
OBSERVABLES = ("x_max", "x_min", "stick_fraction", "transitions", "E_friction")
JACOBIAN = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")  # local variables (sensitivity = true, scheme exact)
DBL_MIN = sys.float_info.min
TYPES_2_TO_3 = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration", "Boolean": "Boolean"}


class Logged:
    """Callbacks that keep every log message (status, category, text)."""

    def __init__(self) -> None:
        self.messages: list[tuple[int, str, str]] = []
        self.struct = fmi2CallbackFunctions()
        self.struct.logger = fmi2CallbackLoggerTYPE(self._log)
        self.struct.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, size: calloc(n, size))
        self.struct.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: free(p))

    def _log(self, env: object, name: bytes, status: int, category: bytes, message: bytes) -> None:
        self.messages.append((status, category.decode(), message.decode(errors="replace")))

    def warnings(self) -> list[tuple[str, str]]:
        return [(c, m) for s, c, m in self.messages if s == fmi2Warning]


class Slave:
    def __init__(self, unzipped: tuple[str, object]) -> None:
        d, md = unzipped
        self.md = md
        self.vars = {v.name: v for v in md.modelVariables}
        self.log = Logged()
        self.s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                           instanceName="md")
        self.s.instantiate(callbacks=self.log.struct)

    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def start(self, **values: float | int | bool) -> None:
        s = self.s
        s.setupExperiment(startTime=0.0)
        for name, value in values.items():
            kind = self.vars[name].type
            if kind == "Real":
                s.setReal([self.vr(name)], [float(value)])
            elif kind == "Boolean":
                s.setBoolean([self.vr(name)], [bool(value)])
            else:
                s.setInteger([self.vr(name)], [int(value)])
        s.enterInitializationMode()
        s.exitInitializationMode()

    def get_status(self, name: str) -> tuple[int, float]:
        """(status, value) of one output through the raw C function: fmpy hides warnings."""
        v = self.vars[name]
        vr = (c_uint * 1)(v.valueReference)
        if v.type == "Real":
            out = (c_double * 1)()
            st = self.s.dll.fmi2GetReal(self.s.component, vr, 1, out)
        else:
            out = (c_int * 1)()
            st = self.s.dll.fmi2GetInteger(self.s.component, vr, 1, out)
        return st, out[0]

    def outputs(self, names: list[str]) -> dict[str, float]:
        reals = [n for n in names if self.vars[n].type == "Real"]
        ints = [n for n in names if self.vars[n].type != "Real"]
        out = dict(zip(reals, self.s.getReal([self.vr(n) for n in reals])))
        out.update(zip(ints, self.s.getInteger([self.vr(n) for n in ints])))
        return out


@pytest.fixture
def slave(unzipped: tuple[str, object]) -> Iterator[Slave]:
    sl = Slave(unzipped)
    yield sl
    sl.s.freeInstance()


# ----------------------------------------------------------------------------- ranges


def _ranged(md: object) -> list[tuple[str, str, float | None, float | None]]:
    out = []
    for v in md.modelVariables:
        if v.causality in ("parameter", "input") and v.type in ("Real", "Integer") and (v.min or v.max):
            out.append((v.name, v.type, None if v.min is None else float(v.min), None if v.max is None else float(v.max)))
    return out


def test_the_ranges_are_in_the_model_description() -> None:
    md = read_model_description(str(XML))
    by = {v.name: v for v in md.modelVariables}
    assert (float(by["m"].min), float(by["m"].max)) == (1e-100, 1e100)  # the scales computed right (HAZARDS.md)
    assert float(by["h"].min) == 0.0   # h: 0 (derived) or a normal number
    assert float(by["h"].start) == 0.0 and by["h_used"].causality == "calculatedParameter"
    assert (float(by["k"].min), float(by["k"].max)) == (0.0, 1e100)   # k > 0 below 1e-100: at exit-initialisation
    for n in ("c", "N", "mu_s", "chi", "omega"):
        assert float(by[n].min) == 0.0 and by[n].max is None, n
    assert float(by["alpha"].min) == -1.0 / 3.0 and float(by["alpha"].max) == 0.0
    assert (int(by["frictionUpdates"].min), int(by["frictionUpdates"].max)) == (0, 100)
    assert by["scheme"].type == "Enumeration" and by["scheme"].declaredType.name == "Scheme"
    assert [(i.name, int(i.value)) for i in by["scheme"].declaredType.items] == [
        ("paper", 1), ("consistent", 2), ("located", 3), ("exact", 4)]


@pytest.mark.parametrize("side", ["min", "max"])
def test_the_binary_enforces_exactly_the_declared_ranges(unzipped: tuple[str, object], side: str) -> None:
    """Each declared bound is accepted and the next representable value beyond it is refused with
    a sentence naming the variable, its value reference and the range: the C table is the XML's."""
    sl = Slave(unzipped)
    try:
        checked = 0
        for name, kind, lo, hi in _ranged(unzipped[1]):
            bound = lo if side == "min" else hi
            if bound is None:
                continue
            vr = sl.vr(name)
            if kind == "Real":
                beyond = math.nextafter(bound, -math.inf if side == "min" else math.inf)
                sl.s.setReal([vr], [bound])
                with pytest.raises(FMICallException):
                    sl.s.setReal([vr], [beyond])
            else:
                beyond = int(bound) + (-1 if side == "min" else 1)
                sl.s.setInteger([vr], [int(bound)])
                with pytest.raises(FMICallException):
                    sl.s.setInteger([vr], [beyond])
            msg = [m for s, _, m in sl.log.messages if s >= 3][-1]
            assert f"for variable {name} (value reference {vr}); valid range:" in msg, msg
            checked += 1
            sl.s.reset()
        assert checked >= (9 if side == "min" else 2)
        # a subnormal h is below the normal minimum, a subnormal m below m's
        for name, rng in (("m", "in [1e-100, 1e+100]"), ("h", "a normal number")):
            with pytest.raises(FMICallException):
                sl.s.setReal([sl.vr(name)], [DBL_MIN / 2])
            assert rng in sl.log.messages[-1][2]
    finally:
        sl.s.freeInstance()


def test_the_generator_refuses_an_inconsistent_description(tmp_path: Path) -> None:
    """A start value outside its own range is caught at build time, with one line and status 1."""
    good = '<Real min="0" max="1e+100" unit="N/m" start="100"/>'
    bad = XML.read_text().replace(good, good.replace('start="100"', 'start="-1"'))
    assert bad != XML.read_text()
    (tmp_path / "md.xml").write_text(bad)
    r = subprocess.run([sys.executable, str(ROOT / "fmu_src" / "gen_model_vars.py"), str(tmp_path / "md.xml"),
                        str(tmp_path / "model_vars.h")], capture_output=True, text=True)
    assert r.returncode == 1 and "variable k" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = subprocess.run([sys.executable, str(ROOT / "fmu_src" / "gen_model_vars.py"), str(XML),
                        str(tmp_path / "model_vars.h")], capture_output=True, text=True)
    text = (tmp_path / "model_vars.h").read_text()
    assert r.returncode == 0 and "offsetof(dfo_params, mu_s)" in text and "DFO_MD_EFFECT_FRICTION = 1" in text


@pytest.mark.parametrize("case", ["local in Outputs", "output missing", "local in InitialUnknowns"])
def test_the_generator_keeps_the_model_structure_to_the_standard(tmp_path: Path, case: str) -> None:
    """<Outputs> lists exactly the outputs and <InitialUnknowns> exactly the outputs (initial
    calculated) and the calculated parameters (FMI 2.0 and 3.0): a local variable listed there, or
    an output left out, is refused at build time with one line naming it, status 1."""
    src = XML.read_text()
    index = {sv.get("name"): i for i, sv in enumerate(ET.fromstring(src).find("ModelVariables"), start=1)}
    outputs_end, initial_end = "    </Outputs>", "    </InitialUnknowns>"
    bad, named = {
        "local in Outputs": (src.replace(outputs_end, f'      <Unknown index="{index["dx_dx0"]}" dependencies=""/>\n'
                                         + outputs_end), "dx_dx0"),
        "output missing": (src.replace(f'      <Unknown index="{index["x"]}" dependencies=""/>\n', "", 1), "missing x"),
        "local in InitialUnknowns": (src.replace(initial_end, f'      <Unknown index="{index["dv_dv0"]}"/>\n'
                                                 + initial_end), "dv_dv0"),
    }[case]
    assert bad != src
    (tmp_path / "md.xml").write_text(bad)
    r = _gen(str(tmp_path / "md.xml"), str(tmp_path / "model_vars.h"))
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert named in r.stderr and "ModelStructure" in r.stderr, r.stderr
    assert not (tmp_path / "model_vars.h").exists()


def _gen(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(ROOT / "fmu_src" / "gen_model_vars.py"), *args], capture_output=True,
                          text=True)


def test_the_chain_source_expands_to_both_fmi_versions(tmp_path: Path) -> None:
    """The chain's one source (arrays of the structural parameter n): FMI 2.0 for a build's n with
    structured names and per-element value references and dependencies, FMI 3.0 with <Dimension>."""
    src = ROOT / "fmu_src" / "models" / "chain" / "modelDescription.xml"
    assert _gen(str(src), str(tmp_path / "md2.xml"), "--fmi2", "3").returncode == 0
    root2 = ET.parse(tmp_path / "md2.xml").getroot()
    assert root2.get("fmiVersion") == "2.0" and root2.get("variableNamingConvention") == "structured"
    svs = root2.findall("ModelVariables/ScalarVariable")
    vr = {sv.get("name"): int(sv.get("valueReference")) for sv in svs}
    assert "n" not in vr and "m[3]" in vr and "m[4]" not in vr and "m[0]" not in vr
    assert vr["m[2]"] == 100002 and vr["mode[3]"] == 1700003 and vr["scheme"] == 7
    assert len(set(vr.values())) == len(vr)
    index = {sv.get("name"): k for k, sv in enumerate(svs, start=1)}
    deps = {int(u.get("index")): u.get("dependencies") for u in root2.iterfind("ModelStructure/Outputs/Unknown")}
    assert len(deps) == 5 * 3
    assert deps[index["a[2]"]] == f"{index['F_ext[2]']} {index['N_ext[2]']}" and deps[index["x[2]"]] == ""
    assert _gen(str(src), str(tmp_path / "md3.xml"), "--fmi3").returncode == 0
    root3 = ET.parse(tmp_path / "md3.xml").getroot()
    n = root3.find("ModelVariables/UInt64[@name='n']")
    assert n.get("causality") == "structuralParameter" and n.get("start") == "2" and n.get("max") == "4096"
    m = root3.find("ModelVariables/Float64[@name='m']")
    assert m.find("Dimension").get("valueReference") == n.get("valueReference") and len(m.get("start").split()) == 2
    assert root3.find("ModelVariables/Int32[@name='mode']/Dimension") is not None
    for size in ("0", "4097"):
        r = _gen(str(src), str(tmp_path / "bad.xml"), "--fmi2", size)
        assert r.returncode == 1 and f"n = {size}" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    bad = src.read_text().replace('dimension="n" causality="parameter"', 'dimension="k_end" causality="parameter"', 1)
    (tmp_path / "bad_src.xml").write_text(bad)
    r = _gen(str(tmp_path / "bad_src.xml"), str(tmp_path / "vars.h"))
    assert r.returncode == 1 and "dimension k_end is not a structural parameter" in r.stderr


def test_the_chain_build_configuration_header(tmp_path: Path) -> None:
    """chain_config.h, generated into each chain FMU's sources/: the FMI 2.0 build's n (checked
    against n's range), none for FMI 3.0 (n set in Configuration Mode); the oscillator has no
    structural parameter to configure."""
    src = ROOT / "fmu_src" / "models" / "chain" / "modelDescription.xml"
    assert _gen(str(src), str(tmp_path / "c2.h"), "--config", "3").returncode == 0
    text2 = (tmp_path / "c2.h").read_text()
    assert "#define DFO_CHAIN_FIXED_N 3 " in text2 and "#ifndef DFO_CHAIN_CONFIG_H" in text2
    assert _gen(str(src), str(tmp_path / "c3.h"), "--config").returncode == 0
    assert "#define DFO_CHAIN_FIXED_N" not in (tmp_path / "c3.h").read_text()
    for size in ("0", "4097"):
        r = _gen(str(src), str(tmp_path / "bad.h"), "--config", size)
        assert r.returncode == 1 and f"n = {size}" in r.stderr and not (tmp_path / "bad.h").exists()
    r = _gen(str(XML), str(tmp_path / "osc.h"), "--config", "2")
    assert r.returncode == 1 and "structural parameters" in r.stderr

# ----------------------------------------------------------------------------- effects


def test_effect_bits_are_a_vendor_annotation() -> None:
    root = ET.parse(XML).getroot()
    eff = root.find("VendorAnnotations/Tool[@name='dryfriction']/Effects")
    assert eff is not None and eff.get("variable") == "effects"
    assert [(int(e.get("bit")), e.get("name")) for e in eff.iterfind("Effect")] == [
        (1, "friction"), (2, "coefficientUpdate"), (4, "damping"), (8, "forceInput"), (16, "normalInput"),
        (32, "observables"), (64, "sensitivity"), (128, "belt"), (256, "stribeck")]


def test_effects_value_follows_the_annotation(slave: Slave) -> None:
    bits = {e.get("name"): int(e.get("bit")) for e in ET.parse(XML).getroot().iterfind(".//Effect")}
    slave.start(c=0.3, chi=0.7, observe=True)
    slave.s.setReal([slave.vr("F_ext")], [0.1])
    (effects,) = slave.s.getInteger([slave.vr("effects")])
    assert effects == bits["friction"] | bits["coefficientUpdate"] | bits["damping"] | bits["observables"]
    slave.s.reset()
    slave.start(mu_s=0.0, chi=1.0, observe=False)
    (effects,) = slave.s.getInteger([slave.vr("effects")])
    assert effects == 0


# ----------------------------------------------------------------------------- observe


def test_observable_descriptions_say_set_observe() -> None:
    md = read_model_description(str(XML))
    for v in md.modelVariables:
        if v.name in OBSERVABLES:
            assert "set observe = true" in v.description, v.name


def test_observe_is_on_by_default() -> None:
    md = read_model_description(str(XML))
    assert next(v for v in md.modelVariables if v.name == "observe").start in ("true", True)


@pytest.mark.parametrize("observe", [False, True])
def test_observables_not_computed_read_nan_with_ok(slave: Slave, observe: bool) -> None:
    """With the window set but observe false, the observables are not results: NaN (transitions
    -1) with fmi2OK, one logNotComputed sentence per run (status OK) saying "set observe = true";
    never a warning status. With observe true, fmi2OK and the real values."""
    slave.start(x0=0.004, chi=0.5, t_obs_start=1.0, t_obs_stop=3.0, observe=observe)
    slave.s.doStep(0.0, 4.0)
    got = {}
    for name in OBSERVABLES:
        for _ in range(3):  # a host sampling every step: noted once
            st, value = slave.get_status(name)
            got[name] = (st, value)
    notes = [(s, m) for s, c, m in slave.log.messages if c == "logNotComputed"]
    assert all(st == fmi2OK for st, _ in got.values()) and slave.log.warnings() == []
    if observe:
        assert notes == []
        assert got["x_max"][1] > 0.0 > got["x_min"][1] and 0.0 < got["stick_fraction"][1] < 1.0
        assert got["transitions"][1] > 0 and got["E_friction"][1] > 0.0
    else:
        assert all(math.isnan(got[n][1]) for n in OBSERVABLES if n != "transitions"), got
        assert got["transitions"][1] == -1
        assert len(notes) == 1 and notes[0][0] == fmi2OK
        assert "variable x_max " in notes[0][1] and "set observe = true" in notes[0][1]


def test_extremes_before_the_window_read_nan(slave: Slave) -> None:
    """observe on, the window not yet open: x_max and x_min have no sample and read NaN (OK, one
    note); the accumulated observables are 0 (nothing observed yet), then real values."""
    slave.start(x0=0.004, chi=0.5, t_obs_start=1.0, t_obs_stop=3.0, observe=True)
    before = {n: slave.get_status(n) for n in OBSERVABLES}
    assert all(st == fmi2OK for st, _ in before.values())
    assert math.isnan(before["x_max"][1]) and math.isnan(before["x_min"][1])
    assert before["stick_fraction"][1] == 0.0 and before["transitions"][1] == 0 and before["E_friction"][1] == 0.0
    notes = [m for s, c, m in slave.log.messages if c == "logNotComputed"]
    assert len(notes) == 1 and "not taken a sample" in notes[0]
    slave.s.doStep(0.0, 1.5)
    st, x_max = slave.get_status("x_max")
    assert st == fmi2OK and math.isfinite(x_max)


# ----------------------------------------------------------------------------- ModelStructure


def _declared_dependencies(md: object) -> dict[str, set[str]]:
    return {u.variable.name: {d.name for d in u.dependencies} for u in md.outputs}


def test_every_output_declares_its_dependencies() -> None:
    md = read_model_description(str(XML))
    deps = {u.variable.name: u.dependencies for u in md.outputs}
    assert set(deps) == {v.name for v in md.modelVariables if v.causality == "output"}
    assert all(d is not None for d in deps.values())  # no "depends on everything"
    assert {n for n, d in deps.items() if d} == {"a", "F_friction"}
    assert all({x.causality for x in d} <= {"input"} for d in deps.values())
    init = {u.variable.name: u.dependencies for u in md.initialUnknowns}
    assert all(d is not None for d in init.values())
    assert [x.name for x in init["x"]] == ["x0"] and [x.name for x in init["v"]] == ["v0"]


def _same(a: object, b: object) -> bool:
    """Equal, or both NaN (a value not computed, such as the sensitivity while it is off)."""
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


def _perturbed(slave: Slave, names: list[str], mode_wanted: int) -> dict[str, set[str]]:
    """Step to a communication point in the wanted mode (0 stuck, 1 sliding), then set each input in
    turn and read every output without a step: the inputs each output responds to."""
    slave.start(k=100.0, N=1.0, mu_s=0.4, chi=0.5, P0=1.0, omega=5.0, c=0.2, observe=True)
    inputs = ["F_ext", "N_ext", "v_belt"]
    slave.s.setReal([slave.vr(n) for n in inputs], [0.0, 0.0, 0.0])
    t = 0.0
    for j in range(4000):
        slave.s.doStep(t, 1.25e-3)
        t += 1.25e-3
        if j > 40 and (slave.s.getInteger([slave.vr("mode")])[0] != 0) == bool(mode_wanted):
            break
    assert (slave.s.getInteger([slave.vr("mode")])[0] != 0) == bool(mode_wanted)
    base = slave.outputs(names)
    responds: dict[str, set[str]] = {n: set() for n in names}
    for inp in inputs:
        slave.s.setReal([slave.vr(inp)], [0.5 if inp == "N_ext" else 0.05])
        now = slave.outputs(names)
        for n in names:
            if not _same(now[n], base[n]):
                responds[n].add(inp)
        slave.s.setReal([slave.vr(inp)], [0.0])
        back = slave.outputs(names)  # back to the step's inputs: the step's values, exactly
        assert all(_same(back[n], base[n]) for n in names)
    return responds


def test_outputs_follow_inputs_as_declared(slave: Slave) -> None:
    """Stuck, F_ext moves the friction (it holds the new static force); sliding, N_ext moves it
    (-s mu_k N) and F_ext moves the acceleration; x, v, mode and the observables never move without
    a step. The union over both modes is exactly the declared dependencies."""
    declared = _declared_dependencies(slave.md)
    names = sorted(declared)
    stuck = _perturbed(slave, names, 0)
    slave.s.reset()
    sliding = _perturbed(slave, names, 1)
    # a belt set moving under a stuck block makes it slide: its friction and acceleration follow v_belt
    assert stuck["F_friction"] == {"F_ext", "v_belt"} and sliding["F_friction"] == {"N_ext"}
    assert sliding["a"] == {"F_ext", "N_ext"}
    found = {n: stuck[n] | sliding[n] for n in names}
    assert found == declared


def _initial_values(slave: Slave, values: dict[str, float | int | bool], names: list[str]) -> dict[str, float]:
    slave.s.reset()
    slave.s.setupExperiment(startTime=0.0)
    for name, value in values.items():
        kind = slave.vars[name].type
        if kind == "Real":
            slave.s.setReal([slave.vr(name)], [float(value)])
        elif kind == "Boolean":
            slave.s.setBoolean([slave.vr(name)], [bool(value)])
        else:
            slave.s.setInteger([slave.vr(name)], [int(value)])
    slave.s.enterInitializationMode()
    return slave.outputs(names)


def _changed(kind: str, value: float | int | bool, name: str) -> float | int | bool:
    if kind == "Boolean":
        return not value
    if name == "scheme":
        return 1 if value != 1 else 3
    if kind != "Real":
        return int(value) + 1
    if name == "alpha":
        return value - 0.05
    return value * 1.25 + 0.01


@pytest.mark.parametrize("case", ["stuck", "sliding", "moving"])
def test_initial_unknowns_depend_only_on_what_they_declare(slave: Slave, case: str) -> None:
    """In initialisation mode, change one known (parameter or input) at a time and read every
    initial unknown: whatever changes must be declared in <InitialUnknowns> (a declared dependency
    may not show at a given point, an undeclared one is a lie)."""
    base: dict[str, float | int | bool] = {
        "x0": 0.004, "observe": True, "F_ext": 0.0, "N_ext": 0.0, "c": 0.0, "chi": 0.7,
        **({"P0": 0.3} if case == "stuck" else {}), **({"v0": 0.2} if case == "moving" else {})}
    declared = {u.variable.name: {d.name for d in u.dependencies} for u in slave.md.initialUnknowns}
    names = sorted(declared)
    knowns = [v for v in slave.md.modelVariables if v.causality in ("parameter", "input")]
    full = {v.name: base.get(v.name, v.start if v.type != "Boolean" else v.start in ("true", True))
            for v in knowns}
    full = {n: (float(x) if slave.vars[n].type == "Real" else x) for n, x in full.items()}
    full = {n: (int(x) if slave.vars[n].type in ("Integer", "Enumeration") else x) for n, x in full.items()}
    ref = _initial_values(slave, full, names)
    mode = ref["mode"]
    assert (mode == 0) == (case == "stuck")
    seen: dict[str, set[str]] = {n: set() for n in names}
    for v in knowns:
        if v.name == "t_obs_stop":
            continue  # 1e300 * 1.25 overflows; t_obs_start covers the window
        now = _initial_values(slave, {**full, v.name: _changed(v.type, full[v.name], v.name)}, names)
        for n in names:
            if not _same(now[n], ref[n]):
                seen[n].add(v.name)
    for n in names:
        assert seen[n] <= declared[n], f"{n} changes with undeclared {sorted(seen[n] - declared[n])}"
    assert seen["x"] == {"x0"} and seen["effects"] >= {"c", "observe"}


def test_friction_follows_the_sliding_law_at_once(slave: Slave) -> None:
    """Sliding: F = -mode mu_k (N + N_ext) for the N_ext just set, no step in between."""
    _perturbed(slave, ["x"], 1)
    mode = slave.s.getInteger([slave.vr("mode")])[0]
    slave.s.setReal([slave.vr("N_ext")], [0.75])
    (F,) = slave.s.getReal([slave.vr("F_friction")])
    assert F == pytest.approx(-mode * 0.5 * 0.4 * (1.0 + 0.75), rel=1e-15)


# ----------------------------------------------------------------------------- metadata


def test_metadata_and_license(fmu_path: Path) -> None:
    root = ET.parse(XML).getroot()
    assert root.get("author") == "DryFrictionOscillator developers"
    assert root.get("license") == "BSD-2-Clause; see LICENSE"
    assert "2026" in root.get("copyright") and "DryFrictionOscillator developers" in root.get("copyright")
    assert root.get("generationDateAndTime", "").endswith("Z")
    license_text = (ROOT / "LICENSE").read_text()
    assert "Copyright (c) 2026, DryFrictionOscillator developers" in license_text
    assert "Redistribution and use in source and binary forms" in license_text
    with zipfile.ZipFile(fmu_path) as z:
        assert z.read("documentation/LICENSE").decode() == license_text
        assert z.read("modelDescription.xml") == XML.read_bytes()


# ------------------------------------- the FMU's own description, and what dryfriction.model reads

def test_model_description_is_the_source_of_truth(fmu: OscillatorFMU2) -> None:
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
        if v.name in ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0"):  # not computed: sensitivity is off by default
            assert np.isnan(float(value)), v.name
            continue
        assert np.isfinite(float(value)), v.name
        if v.causality == "parameter":
            assert float(value) == float(v.start), (v.name, value, v.start)


@pytest.mark.min_versions
def test_model_module_reads_what_the_xml_declares() -> None:
    md = model.from_xml(XML)
    root = ET.parse(XML).getroot()
    svs = root.findall("ModelVariables/ScalarVariable")
    assert list(md.variables) == [sv.get("name") for sv in svs]
    for sv in svs:
        v = md.var(sv.get("name"))
        assert v.vr == int(sv.get("valueReference")) and v.causality == sv.get("causality")
        el = next(iter(sv))
        assert v.type == el.tag and v.unit == el.get("unit")
        if el.get("min") is not None:
            assert v.min == float(el.get("min"))
    items = root.findall("TypeDefinitions/SimpleType[@name='Scheme']/Enumeration/Item")
    assert md.schemes == {i.get("name"): int(i.get("value")) for i in items}
    bits = root.findall("VendorAnnotations/Tool[@name='dryfriction']/Effects/Effect")
    assert [(e.bit, e.name) for e in md.effects] == [(int(b.get("bit")), b.get("name")) for b in bits]
    assert md.effects_variable == "effects"
    # the package's defaults are the declared starts (h: None, period / 1000, by design; observe:
    # off unless a run reads the observables, by design, the FMU's own start being true)
    p, st = Oscillator(), Settings()
    assert md.parameter_starts()["observe"] is True and st.observe is False
    for name, start in md.parameter_starts().items():
        if name in ("h", "observe", "sensitivity"):  # sensitivity: not in Settings (the orbits set it)
            continue
        value = getattr(p, name) if hasattr(p, name) else getattr(st, name)
        if name == "scheme":
            value = md.schemes[value]
        assert value == start, name
    assert PARAM_COLUMNS[:-1] == tuple(n for n in md.names("parameter") if md.var(n).type == "Real")


def test_fmus_own_description_equals_the_repositorys(fmu: OscillatorFMU2) -> None:
    assert fmu.md == model.from_xml(XML)


def test_effects_are_named_by_the_vendor_annotation(fmu: OscillatorFMU2) -> None:
    fmu.start(Oscillator(c=0.5, chi=1.0), Settings(h=1e-3, observe=True))
    mask = int(fmu.get(["effects"])["effects"])
    assert fmu.effects() == [e.name for e in fmu.md.effects if mask & e.bit]
    assert set(fmu.effects()) == {"friction", "damping", "observables"}


# ------------------------------------------ the FMI 3.0 description says what the FMI 2.0 one says

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


def test_the_jacobian_is_local_in_both_versions(md2, md3) -> None:
    """dx_dx0 ... dv_dv0 (NaN unless sensitivity = true with scheme exact) are local variables in the
    FMI 2.0 and the generated FMI 3.0 description, at their value references 51-54, in neither
    <Outputs> nor <InitialUnknowns>: a host records them only when asked. Every other output stays an
    output, listed in both."""
    for md in (md2, md3):
        by_name = {v.name: v for v in md.modelVariables}
        assert [(by_name[n].causality, by_name[n].valueReference) for n in JACOBIAN] == \
            [("local", 51), ("local", 52), ("local", 53), ("local", 54)], md.fmiVersion
        listed = {u.variable.name for u in md.outputs} | {u.variable.name for u in md.initialUnknowns}
        assert not listed & set(JACOBIAN)
        assert {u.variable.name for u in md.outputs} == {v.name for v in md.modelVariables if v.causality == "output"}
        assert {"x", "v", "a", "F_friction", "mode", *OBSERVABLES} <= {u.variable.name for u in md.outputs}
        # and Model Exchange's event indicators (tests/test_model_exchange.py), local as well
        assert [v.name for v in md.modelVariables if v.causality == "local"] == \
            [*JACOBIAN, "event_indicator_0", "event_indicator_1"]


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


# ------------------------------------------------------------------ arrays of several dimensions

#: a synthetic source with two structural parameters and matrices over them: M (n x n), W (nc x n)
SPEC2D = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Grid" guid="{00000000-0000-4000-8000-000000000001}"
  variableNamingConvention="structured" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="DryFrictionGrid" canHandleVariableCommunicationStepSize="true"/>
  <LogCategories><Category name="logAll" description="every call"/></LogCategories>
  <ModelVariables>
    <ScalarVariable name="n" valueReference="1"
      causality="structuralParameter" variability="fixed" description="dofs"><UInt64 start="3" min="1" max="100000"/></ScalarVariable>
    <ScalarVariable name="nc" valueReference="2"
      causality="structuralParameter" variability="fixed" description="contacts"><UInt64 start="2" min="1" max="100000"/></ScalarVariable>
    <ScalarVariable name="h" valueReference="3"
      causality="parameter" variability="fixed" initial="exact" description="step"><Real min="0" start="0.001"/></ScalarVariable>
    <ScalarVariable name="M" valueReference="100" dimension="n n"
      causality="parameter" variability="fixed" initial="exact" description="mass matrix"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="W" valueReference="200" dimension="nc n"
      causality="parameter" variability="fixed" initial="exact" description="contact rows"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="F_ext" valueReference="300" dimension="n"
      causality="input" variability="continuous" description="force"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="x" valueReference="400" dimension="n"
      causality="output" variability="continuous" initial="calculated" description="position"><Real/></ScalarVariable>
    <ScalarVariable name="f" valueReference="500" dimension="nc"
      causality="output" variability="continuous" initial="calculated" description="contact force"><Real/></ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs><Unknown index="7" dependencies="6"/><Unknown index="8" dependencies="6"/></Outputs>
    <InitialUnknowns><Unknown index="7"/><Unknown index="8"/></InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""

#: prints the generated C view: every FMI 2.0 layout row, then every array's dimensions (DFO_STRUCT_ slots)
LAYOUT_C = r"""
#include <stdio.h>
#include "cfg.h"
#include "model_vars.h"
int main(void)
{
    for (int a = 0; a < DFO_FMI2_NUM_ARRAYS; a++)
        printf("L %u %u %u %u\n", DFO_FMI2_ARRAYS[a].vr, DFO_FMI2_ARRAYS[a].first, DFO_FMI2_ARRAYS[a].count,
               DFO_FMI2_ARRAYS[a].cols);
    for (int v = 0; v < DFO_NUM_VARS; v++)
        if (DFO_VARS[v].array)
            printf("D %s %d %d %d\n", DFO_VARS[v].name, DFO_VARS[v].ndims, DFO_VARS[v].dims[0], DFO_VARS[v].dims[1]);
    printf("S %d %d\n", DFO_STRUCT_n, DFO_STRUCT_nc);
    return 0;
}
"""


def _spec2d(tmp_path: Path) -> Path:
    src = tmp_path / "grid.xml"
    src.write_text(SPEC2D)
    return src


def test_the_generator_lays_out_matrices_over_two_structural_parameters(tmp_path: Path) -> None:
    """A source with n and nc and the arrays M (n x n), W (nc x n), F_ext, x (n), f (nc): the FMI 2.0
    description of n = 3, nc = 2 names every element (W[2,3], row-major) with the layout's value
    reference (each array from its own value reference + 1: M 101 ... 109, W 201 ... 206), writes the
    layout into its annotation, and maps dependencies element to element (x[i] on F_ext[i]) or on
    every element (f on F_ext); dryfriction.model reads the same; FMI 3.0 gives M two <Dimension>s."""
    src = _spec2d(tmp_path)
    r = _gen(str(src), str(tmp_path / "md2.xml"), "--fmi2", "n=3,nc=2")
    assert r.returncode == 0, r.stderr
    md2 = model.from_xml(tmp_path / "md2.xml")
    assert md2.arrays()["W"] == ("W[1,1]", "W[1,2]", "W[1,3]", "W[2,1]", "W[2,2]", "W[2,3]")
    assert [md2.vr(e) for e in md2.arrays()["M"]] == list(range(101, 110))
    assert [md2.vr(e) for e in md2.arrays()["W"]] == list(range(201, 207))
    assert md2.vr("x[3]") == 403 and md2.vr("f[2]") == 502 and md2.vr("h") == 3 and "n" not in md2.variables
    assert md2.layout["W"].shape == (2, 3) and md2.layout["W"].element_vr(2, 1) == md2.vr("W[2,1]") == 204
    assert md2.shape("M") == (3, 3) and md2.shape("f") == (2,)
    root = ET.parse(tmp_path / "md2.xml").getroot()
    svs = root.findall("ModelVariables/ScalarVariable")
    assert len({sv.get("valueReference") for sv in svs}) == len(svs) == 1 + 9 + 6 + 3 + 3 + 2
    index = {sv.get("name"): k for k, sv in enumerate(svs, start=1)}
    deps = {int(u.get("index")): u.get("dependencies") for u in root.iterfind("ModelStructure/Outputs/Unknown")}
    assert deps[index["x[2]"]] == str(index["F_ext[2]"])
    assert deps[index["f[1]"]] == " ".join(str(index[f"F_ext[{i}]"]) for i in (1, 2, 3))
    assert "W[2,3]" in (tmp_path / "md2.xml").read_text() and "(element 2, 3)" in (tmp_path / "md2.xml").read_text()
    # FMI 3.0: one <Dimension> per structural parameter, the rows first; the start values at n = 3, nc = 2
    assert _gen(str(src), str(tmp_path / "md3.xml"), "--fmi3").returncode == 0
    root3 = ET.parse(tmp_path / "md3.xml").getroot()
    w = root3.find("ModelVariables/Float64[@name='W']")
    assert [d.get("valueReference") for d in w.iterfind("Dimension")] == ["2", "1"] and len(w.get("start").split()) == 6
    md3 = model.from_xml(tmp_path / "md3.xml")
    assert md3.var("W").dimensions == ("nc", "n") and md3.var("M").dimension == "n n" and md3.var("x").dimension == "n"
    assert md3.shape("W") == (2, 3) and md3.vr("W") == 200 and md3.layout == {}
    assert set(md3.arrays()) == set(md2.arrays()) == {"M", "W", "F_ext", "x", "f"}


def test_the_generated_header_and_description_agree_on_the_layout(tmp_path: Path) -> None:
    """The C view compiled and run (chain_config.h's DFO_FMI2_ARRAYS for n = 3, nc = 2; model_vars.h's
    dimensions of each array) says what the FMI 2.0 description and dryfriction.model say."""
    import shutil

    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    src = _spec2d(tmp_path)
    for args in (("cfg.h", "--config", "n=3,nc=2"), ("model_vars.h",), ("md2.xml", "--fmi2", "n=3,nc=2")):
        r = _gen(str(src), str(tmp_path / args[0]), *args[1:])
        assert r.returncode == 0, r.stderr
    (tmp_path / "main.c").write_text(LAYOUT_C)
    exe = tmp_path / "layout"
    subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-I", str(tmp_path), str(tmp_path / "main.c"),
                    "-o", str(exe)], check=True, capture_output=True, text=True)
    lines = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout.split("\n")
    rows = [tuple(int(x) for x in ln.split()[1:]) for ln in lines if ln.startswith("L ")]
    md2 = model.from_xml(tmp_path / "md2.xml")
    want = sorted((a.vr, a.first, a.count, a.shape[-1] if len(a.shape) > 1 else 1) for a in md2.layout.values())
    assert rows == want == [(100, 101, 9, 3), (200, 201, 6, 3), (300, 301, 3, 1), (400, 401, 3, 1), (500, 501, 2, 1)]
    n_slot, nc_slot = (int(x) for x in next(ln for ln in lines if ln.startswith("S ")).split()[1:])
    dims = {ln.split()[1]: tuple(int(x) for x in ln.split()[2:]) for ln in lines if ln.startswith("D ")}
    assert dims == {"M": (2, n_slot, n_slot), "W": (2, nc_slot, n_slot), "F_ext": (1, n_slot, -1),
                    "x": (1, n_slot, -1), "f": (1, nc_slot, -1)}
    for name, (first_vr, count) in {"M": (101, 9), "W": (201, 6)}.items():
        elements = md2.arrays()[name]
        assert [md2.vr(e) for e in elements] == list(range(first_vr, first_vr + count))


@pytest.mark.parametrize("sizes, fits", [("n=46000,nc=2", True), ("n=65536,nc=1", False), ("n=1,nc=100000", True)])
def test_the_layout_takes_any_size_that_fits_in_32_bits(tmp_path: Path, sizes: str, fits: bool) -> None:
    """No stride: M's n^2 elements push the later arrays up (n = 46000: M ends at 2116000100, W
    starts after it), and a layout whose last value reference passes 2^32 - 1 (n = 65536: M alone
    has 2^32 elements) is refused with one line naming the array."""
    src = _spec2d(tmp_path)
    r = _gen(str(src), str(tmp_path / "cfg.h"), "--config", sizes)
    if not fits:
        assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1
        assert "beyond 32 bits" in r.stderr and "of M" in r.stderr and not (tmp_path / "cfg.h").exists()
        return
    assert r.returncode == 0, r.stderr
    text = (tmp_path / "cfg.h").read_text()
    rows = [tuple(int(x.rstrip("u")) for x in ln.split("{")[1].split("}")[0].split(", "))
            for ln in text.splitlines() if ln.strip().startswith("{") and "/*" in ln]
    n, nc = (int(p.split("=")[1]) for p in sizes.split(","))
    counts = [n * n, nc * n, n, n, nc]
    assert [c for _, _, c, _ in rows] == counts
    end = 0
    for (vr, first, count, _), declared in zip(rows, (100, 200, 300, 400, 500)):
        assert vr == declared and first == max(declared + 1, end)  # after its own and the previous array's
        end = first + count
    assert end - 1 <= 2**32 - 1


@pytest.mark.parametrize("sizes, says", [("n=3", "give each of n, nc once"), ("n=3,nc=0", "nc = 0 outside"),
                                         ("n=3,nc=2,q=1", "give each of n, nc once")])
def test_the_generator_refuses_bad_sizes(tmp_path: Path, sizes: str, says: str) -> None:
    """The sizes of a build name every structural parameter once, inside its range: else one line."""
    r = _gen(str(_spec2d(tmp_path)), str(tmp_path / "md2.xml"), "--fmi2", sizes)
    assert r.returncode == 1 and says in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_a_scalar_above_the_arrays_is_refused(tmp_path: Path) -> None:
    """The layout keeps every scalar's value reference, so the scalars must all come before the arrays'."""
    bad = SPEC2D.replace('name="h" valueReference="3"', 'name="h" valueReference="250"')
    (tmp_path / "bad.xml").write_text(bad)
    r = _gen(str(tmp_path / "bad.xml"), str(tmp_path / "md2.xml"), "--fmi2", "2")
    assert r.returncode == 1 and "scalar h: value reference 250 is not below the arrays'" in r.stderr


def test_the_reader_refuses_a_layout_its_elements_contradict(tmp_path: Path) -> None:
    """dryfriction.model checks an FMI 2.0 description's elements against its layout annotation: an
    element moved off its place is one sentence, not a silently wrong value reference."""
    src = _spec2d(tmp_path)
    assert _gen(str(src), str(tmp_path / "md2.xml"), "--fmi2", "n=2,nc=2").returncode == 0
    text = (tmp_path / "md2.xml").read_text()
    moved = text.replace('name="W[2,1]" valueReference="203"', 'name="W[2,1]" valueReference="299"')
    assert moved != text
    with pytest.raises(ValueError, match=r"W\[2,1\] has value reference 299, its array's layout .* says 203"):
        model.parse(moved)
