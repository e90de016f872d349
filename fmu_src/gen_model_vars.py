"""Generate model_vars.h from modelDescription.xml, the single source of truth for the variables.

Usage: python gen_model_vars.py SOURCE.xml OUT [--header|--fmi3|--fmi3-build|--fmi2 SIZE|--config [SIZE]]

SOURCE.xml is a model's description (FMI 2.0 syntax; the oscillator's is the top-level
modelDescription.xml, every other model's fmu_src/models/<name>/modelDescription.xml). OUT is:

  model_vars.h                --header (the default): the C view of the variables
  fmi3/modelDescription.xml   --fmi3: the FMI 3.0 model description
  fmi3/buildDescription.xml   --fmi3-build: the FMI 3.0 sources' build description
  fmi2/modelDescription.xml   --fmi2 SIZE: a model with structural parameters, for an FMI 2.0 build
                              whose structural parameters are all SIZE, or each its own value
                              (SIZE n=4,nc=2); arrays as name[i], matrices as name[i,j]
  <model>_config.h            --config [SIZE]: a model with structural parameters: its build
                              configuration (with SIZE: an FMI 2.0 build's, with the layout of its
                              array elements' value references; without: FMI 3.0's)

Arrays: a source variable with dimension="n" is a vector of the structural parameter n, one with
dimension="nc n" a matrix of nc rows of n (row-major; at most two dimensions). FMI 3.0 declares
one <Dimension> per structural parameter. FMI 2.0 has no arrays: every element is a variable whose
value reference comes from a layout generated for the build's sizes (fmi2_layout, the package's
dryfriction.model.fmi2_layout, which a structure's FMU written for other sizes uses too: no fixed
stride, each array's elements from its own value reference + 1 and after the previous array's,
any size whose last value reference fits in 32 bits), written into the description
(<Tool name="dryfriction.layout">) and the build's configuration header (DFO_FMI2_ARRAYS).

A matrix (dimension="n n", "nc n") may start as a diagonal one: its start is the diagonal's (i = j), the
annotation <Tool name="dryfriction.starts"><Starts><DiagonalStart variable=... offDiagonal=.../> ...
</Starts></Tool> gives
the start of every other element (M = I: start="1", offDiagonal="0"); FMI 3.0 and FMI 2.0 list the
elements' starts so, the C table has DFO_DIAG_STARTS for the instance core.

The C structs a model's parameters and inputs live in (reached by offsetof) are named by the source
itself, in the vendor annotation <Tool name="dryfriction.c"><Structs header=... parameters=...
inputs=.../></Tool>; a model with structural parameters keeps its values in slots and needs none.

Three stages, so that other views of the same model (an FMI 3.0 model description) can be added
as further emitters without touching the parser:

1. ``parse``: modelDescription.xml -> ``Model``, a neutral description (variables with name, value
   reference, type, causality, variability, start, min, max, unit, description, an optional array
   shape; enumeration types; log categories; the ``effects`` bits of the vendor annotation; the
   declared output dependencies). Consistency is checked here (unique names and value references,
   start values inside their ranges, effect bits distinct powers of two, <ModelStructure> listing
   what FMI asks: the outputs, never a local variable).
2. ``Model`` is plain data (frozen dataclasses), independent of any FMI version.
3. Emitters: ``emit_c_header`` writes the C view used by the instance core -- GUID, identifier,
   ``VR_<name>``/``START_<name>`` macros, the effect bits, the enumeration values, the log
   categories and ONE variable table (name, value reference, type, causality, variability, where
   the value lives: ``offsetof`` into the parameter or input struct, whose field has the variable's
   name, or an output id the core switches on; start, min, max, whether it must be a normal
   number, the enumeration items and the valid range as text for error messages).

4. ``emit_fmi3_model_description`` writes the FMI 3.0 model description of the same model: the same
   names, value references, units, ranges, start values and descriptions in FMI 3.0 types (Float64,
   Int32, Enumeration, Boolean), plus the independent variable ``time`` (value reference
   ``TIME_VR``), the FMI 3.0 co-simulation capabilities, and the output dependencies by value
   reference; ``emit_fmi3_build_description`` the sources' buildDescription.xml. What the neutral
   model does not carry (units, default experiment, metadata, vendor annotations) is read from the
   same source file.

Standard library only, and the package's model-description reader (src/dryfriction/model.py,
loaded by its path) for the effect table, so that one piece of code parses it.
"""

from __future__ import annotations

import importlib.util
import itertools
import re
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

MAX_RANK = 2  # arrays: vectors and matrices
UINT32_MAX = 2**32 - 1  # the largest value reference
TIME_VR = 0  # the FMI 3.0 independent variable `time` (no variable of the source may use it)
FMI3_GLUE, FMI2_GLUE = "fmi3_cs.c", "fmi2_cs.c"
FMI3_ME_GLUE, FMI2_ME_GLUE = "fmi3_me.c", "fmi2_me.c"
DBL_MIN = sys.float_info.min  # the smallest positive normal double
INT_MIN, INT_MAX = -(2**31), 2**31 - 1
CAUSALITIES = ("parameter", "calculatedParameter", "input", "output", "local", "structuralParameter")
# computed by the instance core (an output id): outputs, local variables (read by value reference,
# not listed in <ModelStructure>, so that a host records them only when asked) and calculated parameters
COMPUTED = ("output", "local", "calculatedParameter")

# --------------------------------------------------------------------------------------- model


@dataclass(frozen=True)
class EnumItem:
    name: str
    value: int
    description: str = ""


@dataclass(frozen=True)
class Variable:
    """One variable, independent of the FMI version that declares it."""

    name: str
    vr: int
    type: str  # "Real", "Integer", "Boolean", "Enumeration"
    causality: str  # "parameter", "calculatedParameter", "input", "output", "local", "structuralParameter"
    variability: str  # "constant", "fixed", "tunable", "discrete", "continuous"
    initial: str | None = None
    start: float | int | bool | None = None
    min: float | None = None
    max: float | None = None
    unit: str | None = None
    description: str = ""
    declared_type: str | None = None  # the enumeration type of an Enumeration
    #: an array: the structural parameters of its dimensions, row-major (the source's dimension="n" or
    #: dimension="nc n": nc rows of n); () for a scalar
    dims: tuple[str, ...] = ()
    dependencies: tuple[str, ...] | None = None  # outputs: the knowns it depends on at once (None: all)
    zero: str | None = None  # min 0 and a ZeroOrNormal annotation: what 0 means; other values are normal
    #: a matrix's off-diagonal start (<DiagonalStart>): start is then the diagonal's (i = j); None: every element's
    start_off: float | None = None

    def element_start(self, idx: tuple[int, ...]) -> float | int | bool | None:
        """The start of element idx (1-based; () for a scalar)."""
        if self.start_off is not None and len(idx) == 2 and idx[0] != idx[1]:
            return self.start_off
        return self.start

    @property
    def normal(self) -> bool:
        """A positive lower bound equal to the smallest normal double, or 0 with a meaning
        (``<ZeroOrNormal>``): a value other than 0 must be a normal number."""
        return self.type == "Real" and (self.min == DBL_MIN or (self.zero is not None and self.min == 0))


def _load_reader() -> Any:
    """The package's model-description reader (src/dryfriction/model.py, which imports nothing of
    the package), loaded by its path: the effect table is parsed by one piece of code, for the C
    view here and for the Python side at run time."""
    path = Path(__file__).resolve().parents[1] / "src" / "dryfriction" / "model.py"
    spec = importlib.util.spec_from_file_location("_dryfriction_model_reader", path)
    if spec is None or spec.loader is None:
        raise SystemExit(f"gen_model_vars: cannot load the model-description reader {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve their module by name
    spec.loader.exec_module(module)
    return module


_READER = _load_reader()
Effect = _READER.Effect


@dataclass(frozen=True)
class Model:
    name: str
    guid: str
    identifier: str
    variables: tuple[Variable, ...]
    enumerations: dict[str, tuple[EnumItem, ...]] = field(default_factory=dict)
    log_categories: tuple[tuple[str, str], ...] = ()
    effects_variable: str | None = None
    effects: tuple[Effect, ...] = ()
    structs: dict[str, str] = field(default_factory=dict)  # the C structs: header, parameters, inputs
    # coupling capabilities of the co-simulation FMU (CoSimulation's attributes): input derivatives
    # (canInterpolateInputs; FMI 3.0: its continuous real inputs are intermediateUpdate="true"), the
    # highest output derivative order, directional (FMI 3.0: and adjoint) derivatives
    can_interpolate_inputs: bool = False
    max_output_derivative_order: int = 0
    provides_directional_derivative: bool = False
    # Model Exchange (a <ModelExchange> element): the number of event indicators, and the continuous
    # states with their derivatives (variable names, from the `derivative` attributes)
    model_exchange: bool = False
    event_indicators: int = 0
    states: tuple[tuple[str, str], ...] = ()
    #: the variables that read the event indicators, in order (<Tool name="dryfriction.me">)
    indicator_variables: tuple[str, ...] = ()

    def intermediate_input(self, v: Variable) -> bool:
        """An input a host may set during an FMI 3.0 intermediate update."""
        return (self.can_interpolate_inputs and v.causality == "input" and v.type == "Real"
                and v.variability == "continuous")

    def variable(self, name: str) -> Variable:
        return next(v for v in self.variables if v.name == name)


# --------------------------------------------------------------------------------------- parse


class ModelError(Exception):
    pass


def _number(text: str | None, kind: str) -> float | int | bool | None:
    if text is None:
        return None
    if kind == "Boolean":
        if text not in ("true", "false", "1", "0"):
            raise ModelError(f"invalid Boolean {text!r}")
        return text in ("true", "1")
    if kind == "Real":
        return float(text)
    return int(text)  # Integer, Enumeration, UInt64


def parse(xml_path: Path) -> Model:
    root = ET.parse(xml_path).getroot()
    cs = root.find("CoSimulation")
    if cs is None:
        raise ModelError("no CoSimulation element")
    enums: dict[str, tuple[EnumItem, ...]] = {}
    for st in root.iterfind("TypeDefinitions/SimpleType"):
        e = st.find("Enumeration")
        if e is not None:
            enums[st.get("name")] = tuple(
                EnumItem(i.get("name"), int(i.get("value")), i.get("description", "")) for i in e.iterfind("Item"))
    svs = list(root.find("ModelVariables"))
    deps: dict[int, tuple[int, ...] | None] = {}
    for u in root.iterfind("ModelStructure/Outputs/Unknown"):
        d = u.get("dependencies")
        deps[int(u.get("index"))] = None if d is None else tuple(int(i) for i in d.split())
    _check_structure(root, svs, set(deps))
    zero = {z.get("variable"): z.get("zero", "") for z in
            root.iterfind("VendorAnnotations/Tool[@name='dryfriction.ranges']/Ranges/ZeroOrNormal")}
    diag = {d.get("variable"): float(d.get("offDiagonal", "0")) for d in
            root.iterfind("VendorAnnotations/Tool[@name='dryfriction.starts']/Starts/DiagonalStart")}
    unknown = set(diag) - {sv.get("name") for sv in svs}
    if unknown:
        raise ModelError(f"DiagonalStart: no variable {', '.join(sorted(unknown))}")
    variables = []
    for index, sv in enumerate(svs, start=1):
        kind_el = next(iter(sv))
        kind = kind_el.tag
        name = sv.get("name")
        if kind not in ("Real", "Integer", "Boolean", "Enumeration", "UInt64"):
            raise ModelError(f"variable {name}: unsupported type {kind}")
        declared = kind_el.get("declaredType")
        lo, hi = _number(kind_el.get("min"), kind), _number(kind_el.get("max"), kind)
        if kind == "Enumeration":
            if declared not in enums:
                raise ModelError(f"variable {name}: unknown enumeration type {declared}")
            values = [i.value for i in enums[declared]]
            lo = min(values) if lo is None else lo
            hi = max(values) if hi is None else hi
        dep_names = None
        if index in deps and deps[index] is not None:
            dep_names = tuple(svs[i - 1].get("name") for i in deps[index])
        variables.append(Variable(
            name=name, vr=int(sv.get("valueReference")), type=kind, causality=sv.get("causality", "local"),
            variability=sv.get("variability", "continuous"), initial=sv.get("initial"),
            start=_number(kind_el.get("start"), kind), min=None if lo is None else float(lo),
            max=None if hi is None else float(hi), unit=kind_el.get("unit"),
            description=sv.get("description", ""), declared_type=declared, dependencies=dep_names,
            zero=zero.get(name), dims=tuple((sv.get("dimension") or "").split()), start_off=diag.get(name)))
    effects_var, effects = _READER.parse_effects(root)
    structs_el = root.find("VendorAnnotations/Tool[@name='dryfriction.c']/Structs")
    structs = {} if structs_el is None else {k: structs_el.get(k, "") for k in ("header", "parameters", "inputs")}
    ei = root.find("VendorAnnotations/Tool[@name='dryfriction.me']/EventIndicators")
    model = Model(
        name=root.get("modelName"), guid=root.get("guid"), identifier=cs.get("modelIdentifier"),
        can_interpolate_inputs=cs.get("canInterpolateInputs", "false") == "true",
        max_output_derivative_order=int(cs.get("maxOutputDerivativeOrder", "0")),
        provides_directional_derivative=cs.get("providesDirectionalDerivative", "false") == "true",
        variables=tuple(variables), enumerations=enums,
        log_categories=tuple((c.get("name"), c.get("description", "")) for c in root.iterfind("LogCategories/Category")),
        effects_variable=effects_var, effects=tuple(effects), structs=structs,
        model_exchange=root.find("ModelExchange") is not None,
        event_indicators=int(root.get("numberOfEventIndicators", "0")),
        states=tuple((svs[int(next(iter(sv)).get("derivative")) - 1].get("name"), sv.get("name"))
                     for sv in svs if next(iter(sv)).get("derivative") is not None),
        indicator_variables=tuple(ei.get("variables", "").split()) if ei is not None else ())
    check(model)
    return model


def _check_structure(root: ET.Element, svs: list[ET.Element], outputs: set[int]) -> None:
    """<ModelStructure> lists what FMI 2.0 (and 3.0) require and nothing else: <Outputs> exactly the
    variables of causality output, <InitialUnknowns> exactly the outputs with initial approx or
    calculated and the calculated parameters (a local variable is in neither list)."""
    def indices(*causalities: str, initial: tuple[str | None, ...] | None = None) -> set[int]:
        return {i for i, sv in enumerate(svs, start=1) if sv.get("causality", "local") in causalities
                and (initial is None or sv.get("initial") in initial)}

    def differ(listed: set[int], want: set[int]) -> str:
        def names(ix: set[int]) -> str:
            return ", ".join(svs[i - 1].get("name", "?") if 0 < i <= len(svs) else f"index {i}" for i in sorted(ix))
        return "; ".join(f"{what} {names(ix)}" for what, ix in (("missing", want - listed), ("listed", listed - want))
                         if ix)

    want = indices("output")
    if outputs != want:
        raise ModelError(f"ModelStructure/Outputs must list exactly the outputs: {differ(outputs, want)}")
    init = {int(u.get("index")) for u in root.iterfind("ModelStructure/InitialUnknowns/Unknown")}
    # an output's initial defaults to calculated (FMI 2.0 and 3.0)
    want = indices("output", initial=("approx", "calculated", None)) | indices("calculatedParameter")
    if init != want:
        raise ModelError("ModelStructure/InitialUnknowns must list exactly the outputs with initial approx or "
                         f"calculated and the calculated parameters: {differ(init, want)}")


def _in_range(v: Variable, x: float) -> bool:
    return (v.min is None or x >= v.min) and (v.max is None or x <= v.max)


def check(model: Model) -> None:
    names, vrs = set(), set()
    for v in model.variables:
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", v.name):
            raise ModelError(f"variable {v.name!r}: not a C identifier")
        if v.name in names or v.vr in vrs:
            raise ModelError(f"variable {v.name}: duplicate name or value reference {v.vr}")
        names.add(v.name)
        vrs.add(v.vr)
        if v.vr == TIME_VR or v.name == "time":
            raise ModelError(f"variable {v.name}: name time and value reference {TIME_VR} are FMI 3.0's time")
        for d in v.dims:
            if d not in {s.name for s in model.variables if s.causality == "structuralParameter"}:
                raise ModelError(f"variable {v.name}: dimension {d} is not a structural parameter")
        if len(v.dims) > MAX_RANK:
            raise ModelError(f"variable {v.name}: {len(v.dims)} dimensions (at most {MAX_RANK})")
        if v.causality == "structuralParameter" and (v.type != "UInt64" or v.dims):
            raise ModelError(f"variable {v.name}: a structural parameter is a scalar UInt64")
        if v.causality not in CAUSALITIES:
            raise ModelError(f"variable {v.name}: unsupported causality {v.causality}")
        if v.start is not None and v.type != "Boolean" and not _in_range(v, float(v.start)):
            raise ModelError(f"variable {v.name}: start {v.start} outside its range")
        if v.type == "Enumeration" and v.start is not None:
            if int(v.start) not in {i.value for i in model.enumerations[v.declared_type]}:
                raise ModelError(f"variable {v.name}: start {v.start} is not an item of {v.declared_type}")
        if v.min is not None and v.max is not None and v.min > v.max:
            raise ModelError(f"variable {v.name}: min > max")
        if v.start_off is not None:
            if v.type != "Real" or len(v.dims) != 2 or v.start is None:
                raise ModelError(f"variable {v.name}: a DiagonalStart is for a Real matrix with a start")
            if not _in_range(v, v.start_off):
                raise ModelError(f"variable {v.name}: off-diagonal start {v.start_off} outside its range")
    if model.model_exchange and len(model.indicator_variables) != model.event_indicators:
        raise ModelError(f"numberOfEventIndicators is {model.event_indicators}, but the dryfriction.me annotation "
                         f"names {len(model.indicator_variables)} event indicator variables")
    for n in model.indicator_variables:
        if n not in names or model.variable(n).type != "Real" or model.variable(n).causality != "local":
            raise ModelError(f"event indicator {n}: not a local Real variable")
    bits = [e.bit for e in model.effects]
    if any(b <= 0 or b & (b - 1) for b in bits) or len(set(bits)) != len(bits):
        raise ModelError("effect bits must be distinct powers of two")
    if model.effects and model.effects_variable not in names:
        raise ModelError(f"effects variable {model.effects_variable} is not a variable")
    for v in model.variables:
        for d in v.dependencies or ():
            if model.variable(d).causality != "input":
                raise ModelError(f"output {v.name}: dependency {d} is not an input")


# --------------------------------------------------------------------------------- C emitter

C_TYPES = {"Real": "DFO_REAL", "Integer": "DFO_INTEGER", "Enumeration": "DFO_INTEGER", "Boolean": "DFO_BOOLEAN",
           "UInt64": "DFO_UINT64"}
C_CAUSALITIES = {"parameter": "DFO_PARAMETER", "calculatedParameter": "DFO_CALCULATED", "input": "DFO_INPUT",
                 "output": "DFO_OUTPUT", "structuralParameter": "DFO_STRUCTURAL", "local": "DFO_LOCAL"}
# the kinds every model's table has (one enum for all models: the shared core switches on them)
C_KIND_ENUMS = [
    "typedef enum { DFO_REAL, DFO_INTEGER, DFO_BOOLEAN, DFO_UINT64 } dfo_var_type;",
    "typedef enum { DFO_PARAMETER, DFO_CALCULATED, DFO_INPUT, DFO_OUTPUT, DFO_STRUCTURAL, DFO_LOCAL } dfo_var_causality;",
    "typedef enum { DFO_CONSTANT, DFO_FIXED, DFO_TUNABLE, DFO_DISCRETE, DFO_CONTINUOUS } dfo_var_variability;",
]
C_VARIABILITIES = {"constant": "DFO_CONSTANT", "fixed": "DFO_FIXED", "tunable": "DFO_TUNABLE",
                   "discrete": "DFO_DISCRETE", "continuous": "DFO_CONTINUOUS"}


def upper_snake(name: str) -> str:
    return re.sub(r"([a-z0-9])([A-Z])", r"\1_\2", name).upper()


def c_double(x: float) -> str:
    s = repr(float(x))
    return s if any(c in s for c in ".en") else s + ".0"


def text_number(x: float) -> str:
    """A bound as people read it: 0, 100, -1/3 (when the double is exactly that fraction's)."""
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    f = Fraction(x).limit_denominator(12)
    if f.denominator > 1 and float(f) == x:
        return f"{f.numerator}/{f.denominator}"
    return repr(x)


def range_text(model: Model, v: Variable) -> str:
    if v.type == "Enumeration":
        return "one of " + ", ".join(f"{i.value} ({i.name})" for i in model.enumerations[v.declared_type])
    if v.type == "Boolean":
        return "true or false"
    if v.normal and v.zero is not None:
        return f"0 ({v.zero}) or > 0 (a normal number, >= {DBL_MIN!r})"
    if v.normal:
        return f"> 0 (a normal number, >= {v.min!r})"
    lo, hi = v.min, v.max
    if lo is not None and hi is not None:
        return f"in [{text_number(lo)}, {text_number(hi)}]"
    if lo is not None:
        return f">= {text_number(lo)}"
    if hi is not None:
        return f"<= {text_number(hi)}"
    return "finite"


def _c_header_head(model: Model, source: str, before_guid: list[str], after_time: list[str]) -> list[str]:
    """The opening of model_vars.h: guard, identity, and the value references and start values."""
    L = [
        f"/* Generated from {source} by fmu_src/gen_model_vars.py. Do not edit. */",
        "#ifndef DFO_MODEL_VARS_H",
        "#define DFO_MODEL_VARS_H",
        "",
        "#include <stddef.h>",
        "",
        *before_guid,
        f'#define MODEL_GUID "{model.guid}"',
        f'#define MODEL_IDENTIFIER "{model.identifier}"',
        f"#define DFO_VR_TIME {TIME_VR}u /* FMI 3.0: the independent variable time */",
        "/* coupling capabilities (the description's CoSimulation attributes) */",
        f"#define DFO_CAN_INTERPOLATE_INPUTS {int(model.can_interpolate_inputs)}",
        f"#define DFO_MAX_OUTPUT_DERIVATIVE_ORDER {model.max_output_derivative_order}",
        f"#define DFO_PROVIDES_DIRECTIONAL_DERIVATIVE {int(model.provides_directional_derivative)}",
        "/* Model Exchange (the description's ModelExchange element): the glues fmi2_me.c, fmi3_me.c */",
        f"#define DFO_MODEL_EXCHANGE {int(model.model_exchange)}",
        *after_time,
        "",
        "/* value references and start values */",
    ]
    for v in model.variables:
        L.append(f"#define VR_{v.name} {v.vr}u")
        if v.start is not None:
            start = c_double(v.start) if v.type == "Real" else str(int(v.start))
            L.append(f"#define START_{v.name} {start}")
        if v.type in ("Real", "Integer", "UInt64") and v.causality == "structuralParameter":
            L.append(f"#define MAX_{v.name} {int(v.max)}")
    L += _c_scale_limit(model)
    return L


def _c_scale_limit(model: Model) -> list[str]:
    """DFO_SCALE_LIMIT, the mass's declared maximum (its minimum the reciprocal, checked here): the
    scales the computation honours, m and every stiffness k > 0 within [1/limit, limit] and the
    motion's scales (force over mass, force over stiffness) at least 1/limit^2, checked by the
    instance core at the end of initialisation (dfo_scale.h). None without a bounded m."""
    m = next((v for v in model.variables if v.name == "m" and v.type == "Real"), None)
    if m is None or m.max is None:
        return []
    if m.min is None or m.min != 1.0 / m.max:
        raise SystemExit(f"gen_model_vars: m's range [{m.min}, {m.max}] is not [1/limit, limit]")
    return ["/* the scales the computation honours: m's declared range [1/limit, limit] (dfo_scale.h) */",
            f"#define DFO_SCALE_LIMIT {c_double(m.max)}"]


def _c_enumerations(model: Model) -> list[str]:
    L = ["", "/* enumeration items */"]
    for tname, items in model.enumerations.items():
        L.append("enum {")
        L += [f"    DFO_MD_{upper_snake(tname)}_{upper_snake(i.name)} = {i.value}," for i in items]
        L.append("};")
        vals = ", ".join(str(i.value) for i in items)
        L.append(f"static const int DFO_ITEMS_{tname}[{len(items)}] = {{{vals}}};")
    return L


def _c_log_categories(model: Model) -> list[str]:
    L = ["", "/* log categories, in the order of <LogCategories> */", "enum {"]
    L += [f"    DFO_{upper_snake(name)} = {k}," for k, (name, _) in enumerate(model.log_categories)]
    L += [f"    DFO_NUM_LOG_CATEGORIES = {len(model.log_categories)}", "};",
          "static const char *const DFO_LOG_CATEGORIES[DFO_NUM_LOG_CATEGORIES] = {"]
    L += [f'    "{name}",' for name, _ in model.log_categories]
    return L


def _c_var_info_struct(where: list[str], start_comment: str) -> list[str]:
    """typedef dfo_var_info: the fields every model has, with `where` (how the value is found) between."""
    return [
        "typedef struct {",
        "    unsigned int vr;",
        "    const char *name;",
        "    dfo_var_type type;",
        "    dfo_var_causality causality;",
        "    dfo_var_variability variability;",
        "    dfo_var_home home;",
        *where,
        "    int has_start;",
        f"    double start, min, max; /* {start_comment} */",
        "    int normal;         /* must be a normal number (min is the smallest normal double) */",
        "    int n_items;        /* Enumeration: the allowed values */",
        "    const int *items;",
        "    const char *range;  /* the valid range as text, for error messages */",
        "} dfo_var_info;",
    ]


def _c_var_row(model: Model, v: Variable, c_type: str, c_causality: str, where: str) -> str:
    """One row of DFO_VARS; `where` holds the fields between home (included) and has_start."""
    lo, hi = _bounds(v)
    start = c_double(float(v.start)) if v.start is not None else "0.0"
    if v.type == "Enumeration":
        items = model.enumerations[v.declared_type]
        n_items, items_ptr = str(len(items)), f"DFO_ITEMS_{v.declared_type}"
    else:
        n_items, items_ptr = "0", "NULL"
    rng = range_text(model, v).replace('"', '\\"')
    return (f'    {{{v.vr}u, "{v.name}", {c_type}, {c_causality}, {C_VARIABILITIES[v.variability]}, {where}, '
            f'{int(v.start is not None)}, {start}, {lo}, {hi}, {int(v.normal)}, {n_items}, {items_ptr}, "{rng}"}},')


def _bounds(v: Variable) -> tuple[str, str]:
    if v.type == "Real":
        return (c_double(v.min) if v.min is not None else "-1.7976931348623157e308",
                c_double(v.max) if v.max is not None else "1.7976931348623157e308")
    if v.type == "Boolean":
        return "0.0", "1.0"
    if v.type == "UInt64":
        return c_double(v.min if v.min is not None else 0), c_double(v.max if v.max is not None else 2.0**53)
    return (c_double(v.min) if v.min is not None else c_double(INT_MIN),
            c_double(v.max) if v.max is not None else c_double(INT_MAX))


def emit_c_header(model: Model, source: str = "modelDescription.xml") -> str:
    if any(v.causality == "structuralParameter" for v in model.variables):
        return emit_c_header_indexed(model, source)
    computed = [v for v in model.variables if v.causality in COMPUTED]
    stored = [v for v in model.variables if v.causality in ("parameter", "input")]
    if stored and not all(model.structs.get(k) for k in ("header", "parameters", "inputs")):
        raise ModelError("parameters and inputs live in C structs: name them in <Tool name=\"dryfriction.c\">"
                         "<Structs header=... parameters=... inputs=.../>")
    header = model.structs.get("header", "")
    params_struct, inputs_struct = model.structs.get("parameters", ""), model.structs.get("inputs", "")
    L = _c_header_head(model, source, [f'#include "{header}"', ""] if header else [], [])
    L += _c_enumerations(model)
    if model.effects:
        L += ["", f"/* bits of the calculated parameter {model.effects_variable} */", "enum {"]
        L += [f"    DFO_MD_EFFECT_{upper_snake(e.name)} = {e.bit}, /* {e.description} */" for e in model.effects]
        L += [f"    DFO_MD_EFFECTS_ALL = {sum(e.bit for e in model.effects)}", "};"]
    L += _c_log_categories(model)
    L += ["};", "", "/* outputs, local variables and calculated parameters: ids the instance core computes */", "enum {"]
    L += [f"    DFO_OUT_{v.name}," for v in computed]
    L += ["    DFO_NUM_OUTS", "};", ""]
    L += [
        *C_KIND_ENUMS,
        f"/* where a value lives: a field of {params_struct} or {inputs_struct} (named as the variable; Real: double,",
        " * Integer, Enumeration and Boolean: int), or computed by the core from its output id */",
        "typedef enum { DFO_IN_PARAMS, DFO_IN_INPUTS, DFO_COMPUTED } dfo_var_home;",
        "#define DFO_VARS_BY_OFFSET 1 /* a table of scalars stored at struct offsets (instance_common.h) */",
        "",
        *_c_var_info_struct([
            "    size_t offset;      /* DFO_IN_PARAMS / DFO_IN_INPUTS: offset of the field */",
            "    size_t set_offset;  /* DFO_IN_INPUTS: offset of the int <name>_set (the input has been set) */",
            "    int id;             /* DFO_COMPUTED: DFO_OUT_<name> */",
        ], "absent bounds: the type's extremes"),
        "",
        "/* the struct fields have the types the table says (a compile error otherwise) */",
    ]
    for v in model.variables:
        if v.causality in ("parameter", "input"):
            struct = params_struct if v.causality == "parameter" else inputs_struct
            ctype = "double" if v.type == "Real" else "int"
            L.append(f"typedef char dfo_field_check_{v.name}[sizeof((({struct} *)0)->{v.name}) == sizeof({ctype}) ? 1 : -1];")
    L += ["", f"#define DFO_NUM_VARS {len(model.variables)}", "static const dfo_var_info DFO_VARS[DFO_NUM_VARS] = {"]
    for v in model.variables:
        if v.causality == "parameter":
            home, off, set_off, ident = "DFO_IN_PARAMS", f"offsetof({params_struct}, {v.name})", "0", "-1"
        elif v.causality == "input":
            home, off, ident = "DFO_IN_INPUTS", f"offsetof({inputs_struct}, {v.name})", "-1"
            set_off = f"offsetof({inputs_struct}, {v.name}_set)"
        else:
            home, off, set_off, ident = "DFO_COMPUTED", "0", "0", f"DFO_OUT_{v.name}"
        L.append(_c_var_row(model, v, C_TYPES[v.type], C_CAUSALITIES[v.causality], f"{home}, {off}, {set_off}, {ident}"))
    L += ["};", "", "#endif", ""]
    return "\n".join(L)


# ------------------------------------------------------------------ the FMI 2.0 array layout


#: where an array's elements sit among an FMI 2.0 build's value references: the package's own
#: (src/dryfriction/model.py), so that a structure's FMU written for other sizes has this layout
ArrayLayout = _READER.ArrayLayout


def fmi2_layout(model: Model, sizes: dict[str, int]) -> tuple[ArrayLayout, ...]:
    """The FMI 2.0 value references of the array elements for a build's structural parameters: the
    package's layout (dryfriction.model.fmi2_layout: each array from the first value reference after
    its own and after the previous array's elements) of this model's arrays and scalars."""
    arrays = [(v.name, v.vr, v.dims) for v in model.variables if v.dims]
    scalars = [(v.name, v.vr) for v in model.variables if not v.dims and v.causality != "structuralParameter"]
    try:
        return _READER.fmi2_layout(arrays, sizes, scalars)
    except ValueError as e:
        raise ModelError(str(e)) from None


def build_sizes(model: Model, text: str | int) -> dict[str, int]:
    """The structural parameters of a build: ``SIZE`` (every one) or ``name=SIZE,name=SIZE`` (each),
    every value inside its declared range."""
    structural = [v for v in model.variables if v.causality == "structuralParameter"]
    if not structural:
        raise ModelError("a build configuration is for a model with structural parameters")
    text = str(text)
    if "=" in text:
        sizes: dict[str, int] = {}
        for part in text.split(","):
            name, _, value = part.partition("=")
            sizes[name.strip()] = int(value)
        unknown = set(sizes) - {v.name for v in structural}
        missing = [v.name for v in structural if v.name not in sizes]
        if unknown or missing:
            raise ModelError(f"sizes {text!r}: give each of {', '.join(v.name for v in structural)} once")
    else:
        sizes = {v.name: int(text) for v in structural}
    for v in structural:
        if not (v.min <= sizes[v.name] <= v.max):
            raise ModelError(f"{v.name} = {sizes[v.name]} outside [{text_number(v.min)}, {text_number(v.max)}]")
    return {v.name: sizes[v.name] for v in structural}


def emit_c_header_indexed(model: Model, source: str) -> str:
    """The C view of a model with structural parameters and arrays over them (the chain): values live
    in slots (scalar parameters, array parameters, array inputs), outputs are computed by id; the
    instance core (chain_instance.c) sizes the arrays by the structural parameters. The FMI 2.0
    value references of the elements depend on a build's sizes: emit_build_config writes them."""
    for v in model.variables:
        if v.causality == "input" and not v.dims:
            raise ModelError(f"input {v.name}: scalar inputs are not supported in an indexed model")
    groups = {
        "DFO_SP": [v for v in model.variables if v.causality == "parameter" and not v.dims],
        "DFO_AP": [v for v in model.variables if v.causality == "parameter" and v.dims],
        "DFO_AI": [v for v in model.variables if v.causality == "input"],
        "DFO_OUT": [v for v in model.variables if v.causality in COMPUTED],
        "DFO_STRUCT": [v for v in model.variables if v.causality == "structuralParameter"],
    }
    arrays = [v for v in model.variables if v.dims]
    L = _c_header_head(model, source, [], [])
    L += _c_enumerations(model)
    L += _c_log_categories(model)
    L += ["};", "", "/* slots: scalar parameters (SP), array parameters (AP), array inputs (AI), computed (OUT),",
          " * structural parameters (STRUCT) */"]
    for prefix, vs in groups.items():
        L.append("enum {")
        L += [f"    {prefix}_{v.name}," for v in vs]
        L += [f"    {prefix.replace('DFO_', 'DFO_NUM_')}", "};"]
    L += [
        "",
        *C_KIND_ENUMS,
        "/* where a value lives: the slot of its group (DFO_SP_, DFO_AP_, DFO_AI_, DFO_OUT_, DFO_STRUCT_) */",
        "typedef enum { DFO_IN_PARAMS, DFO_IN_ARRAYS, DFO_IN_INPUTS, DFO_COMPUTED, DFO_IN_STRUCT } dfo_var_home;",
        "",
        *_c_var_info_struct([
            "    int array;          /* an array (of the product of its dimensions' values) */",
            "    int slot;           /* index in its group */",
            f"    int ndims, dims[{MAX_RANK}]; /* an array's dimensions: DFO_STRUCT_ slots, row-major; -1 unused */",
        ], "absent bounds: the type's extremes; an array's start is every element's"),
        "",
        f"#define DFO_NUM_VARS {len(model.variables)}",
        "static const dfo_var_info DFO_VARS[DFO_NUM_VARS] = {",
    ]
    homes = {"DFO_SP": "DFO_IN_PARAMS", "DFO_AP": "DFO_IN_ARRAYS", "DFO_AI": "DFO_IN_INPUTS", "DFO_OUT": "DFO_COMPUTED",
             "DFO_STRUCT": "DFO_IN_STRUCT"}
    causalities, types = C_CAUSALITIES, C_TYPES
    for v in model.variables:
        prefix = next(p for p, vs in groups.items() if v in vs)
        dims = [f"DFO_STRUCT_{d}" for d in v.dims] + ["-1"] * (MAX_RANK - len(v.dims))
        L.append(_c_var_row(model, v, types[v.type], causalities[v.causality],
                            f"{homes[prefix]}, {int(bool(v.dims))}, {prefix}_{v.name}, {len(v.dims)}, "
                            f"{{{', '.join(dims)}}}"))
    diag = [(i, v) for i, v in enumerate(model.variables) if v.start_off is not None]
    L += ["};", "", "/* matrices that start diagonal (dryfriction.starts): the variable's index in DFO_VARS and the",
          " * start of its elements (i, j) with i != j (its start is that of the elements (i, i)) */",
          f"#define DFO_NUM_DIAG_STARTS {len(diag)}"]
    if diag:
        L += ["typedef struct {", "    int var;", "    double off;", "} dfo_diag_start;",
              "static const dfo_diag_start DFO_DIAG_STARTS[DFO_NUM_DIAG_STARTS] = {"]
        L += [f"    {{{i}, {c_double(v.start_off)}}}, /* {v.name} */" for i, v in diag]
        L.append("};")
    L += ["", "/* the arrays' own value references (FMI 3.0), in declaration order */",
          f"#define DFO_NUM_ARRAYS {len(arrays)}",
          f"static const unsigned int DFO_ARRAY_VRS[DFO_NUM_ARRAYS] = {{{', '.join(f'{v.vr}u' for v in arrays)}}};",
          "", "#endif", ""]
    return "\n".join(L)


# ------------------------------------------------------------------------- FMI 3.0 emitters

FMI3_TYPES = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration", "Boolean": "Boolean",
              "UInt64": "UInt64"}
# FMI 2.0 co-simulation attributes kept under their FMI 3.0 names
FMI3_CS_KEPT = {"canHandleVariableCommunicationStepSize": "canHandleVariableCommunicationStepSize",
                "canBeInstantiatedOnlyOncePerProcess": "canBeInstantiatedOnlyOncePerProcess",
                "canGetAndSetFMUstate": "canGetAndSetFMUState", "canSerializeFMUstate": "canSerializeFMUState",
                "providesDirectionalDerivative": "providesDirectionalDerivatives"}
# what the FMI 3.0 glue (fmi3_cs.c) adds: events, early return, intermediate update
FMI3_CS_EVENTS = {"hasEventMode": "true", "mightReturnEarlyFromDoStep": "true",
                  "canReturnEarlyAfterIntermediateUpdate": "true", "providesIntermediateUpdate": "true"}
ROOT_ATTRIBUTES = ("modelName", "description", "version", "author", "copyright", "license", "generationTool",
                   "generationDateAndTime", "variableNamingConvention")


def _xml_number(x: float | int | bool, kind: str) -> str:
    if kind == "Boolean":
        return "true" if x else "false"
    if kind in ("Integer", "Enumeration", "UInt64"):
        return str(int(x))
    return repr(float(x))


def _attrs(pairs: list[tuple[str, str | None]]) -> str:
    from xml.sax.saxutils import quoteattr
    return "".join(f" {k}={quoteattr(v)}" for k, v in pairs if v is not None)


def _source_files(root: ET.Element) -> list[str]:
    files = [f.get("name") for f in root.iterfind("CoSimulation/SourceFiles/File")]
    return [{FMI2_GLUE: FMI3_GLUE, FMI2_ME_GLUE: FMI3_ME_GLUE}.get(f, f) for f in files]


# FMI 2.0 Model Exchange attributes kept under their FMI 3.0 names
FMI3_ME_KEPT = {"canBeInstantiatedOnlyOncePerProcess": "canBeInstantiatedOnlyOncePerProcess",
                "canGetAndSetFMUstate": "canGetAndSetFMUState", "canSerializeFMUstate": "canSerializeFMUState",
                "providesDirectionalDerivative": "providesDirectionalDerivatives"}


def _fmi3_model_exchange(model: Model, root: ET.Element) -> list[str]:
    """The FMI 3.0 <ModelExchange> element of a model that declares one (else nothing): FMI 2.0's
    attributes under their FMI 3.0 names; completedIntegratorStepNotNeeded becomes
    needsCompletedIntegratorStep."""
    me = root.find("ModelExchange")
    if me is None:
        return []
    needs = "false" if me.get("completedIntegratorStepNotNeeded", "false") == "true" else "true"
    return ["  <ModelExchange" + _attrs([("modelIdentifier", model.identifier)]
                                     + [(new, me.get(old)) for old, new in FMI3_ME_KEPT.items()]
                                     + [("needsCompletedIntegratorStep", needs)]) + "/>", ""]


def emit_fmi3_model_description(model: Model, source: Path) -> str:
    root = ET.parse(source).getroot()
    cs = root.find("CoSimulation")
    L = ['<?xml version="1.0" encoding="UTF-8"?>',
         f"<!-- Generated from {source.name} by fmu_src/gen_model_vars.py. Do not edit. -->",
         "<fmiModelDescription" + _attrs([("fmiVersion", "3.0")] + [(a, root.get(a)) for a in ROOT_ATTRIBUTES[:1]]
                                         + [("instantiationToken", model.guid)]
                                         + [(a, root.get(a)) for a in ROOT_ATTRIBUTES[1:]]) + ">",
         "",
         *_fmi3_model_exchange(model, root),
         "  <CoSimulation" + _attrs([("modelIdentifier", model.identifier)]
                                    + [(new, cs.get(old)) for old, new in FMI3_CS_KEPT.items()]
                                    + [("providesAdjointDerivatives",
                                        "true" if model.provides_directional_derivative else "false")]
                                    + list(FMI3_CS_EVENTS.items())
                                    + [("maxOutputDerivativeOrder", str(model.max_output_derivative_order))]) + "/>",
         ""]
    units = root.find("UnitDefinitions")
    if units is not None:
        L.append("  <UnitDefinitions>")
        for u in units.iterfind("Unit"):
            b = u.find("BaseUnit")
            base = "" if b is None else "<BaseUnit" + _attrs(sorted(b.attrib.items())) + "/>"
            L.append("    <Unit" + _attrs([("name", u.get("name"))]) + ">" + base + "</Unit>")
        L += ["  </UnitDefinitions>", ""]
    if model.enumerations:
        L.append("  <TypeDefinitions>")
        for st in root.iterfind("TypeDefinitions/SimpleType"):
            name = st.get("name")
            if name not in model.enumerations:
                continue
            L.append("    <EnumerationType" + _attrs([("name", name), ("description", st.get("description"))]) + ">")
            for it in model.enumerations[name]:
                L.append("      <Item" + _attrs([("name", it.name), ("value", str(it.value)),
                                                  ("description", it.description or None)]) + "/>")
            L.append("    </EnumerationType>")
        L += ["  </TypeDefinitions>", ""]
    if model.log_categories:
        L.append("  <LogCategories>")
        L += ["    <Category" + _attrs([("name", n), ("description", d or None)]) + "/>" for n, d in model.log_categories]
        L += ["  </LogCategories>", ""]
    de = root.find("DefaultExperiment")
    if de is not None:
        L += ["  <DefaultExperiment" + _attrs(list(de.attrib.items())) + "/>", ""]
    L.append("  <ModelVariables>")
    L.append("    <Float64" + _attrs([("name", "time"), ("valueReference", str(TIME_VR)), ("causality", "independent"),
                                      ("variability", "continuous"), ("description", "simulation time"),
                                      ("unit", "s")]) + "/>")
    for v in model.variables:
        kind = FMI3_TYPES[v.type]
        pairs: list[tuple[str, str | None]] = [
            ("name", v.name), ("valueReference", str(v.vr)), ("description", v.description or None),
            ("causality", v.causality), ("variability", v.variability), ("initial", v.initial)]
        if model.intermediate_input(v):
            pairs.append(("intermediateUpdate", "true"))
        state_of = {d: st for st, d in model.states}  # a state derivative: the state's value reference
        if v.name in state_of:
            pairs.append(("derivative", str(model.variable(state_of[v.name]).vr)))
        if kind == "Enumeration":
            pairs.append(("declaredType", v.declared_type))
        if kind in ("Float64", "Int32", "UInt64"):
            if kind != "UInt64":
                pairs.append(("unit", v.unit))
            src = next(sv for sv in root.iterfind("ModelVariables/ScalarVariable") if sv.get("name") == v.name)
            el = next(iter(src))
            # the bounds as the source writes them (Int32 outputs without bounds stay without)
            pairs += [("min", el.get("min")), ("max", el.get("max"))]
        if v.dims:
            if v.start is not None:  # one start value per element at the structural parameters' starts
                shape = [int(model.variable(d).start) for d in v.dims]
                idxs = itertools.product(*(range(1, s + 1) for s in shape))
                pairs.append(("start", " ".join(_xml_number(v.element_start(i), v.type) for i in idxs)))
            L.append(f"    <{kind}" + _attrs(pairs) + ">")
            # one <Dimension> per structural parameter, the outermost (rows) first
            L += ["      <Dimension" + _attrs([("valueReference", str(model.variable(d).vr))]) + "/>" for d in v.dims]
            L.append(f"    </{kind}>")
            continue
        if v.start is not None:
            pairs.append(("start", _xml_number(v.start, v.type)))
        L.append(f"    <{kind}" + _attrs(pairs) + "/>")
    L += ["  </ModelVariables>", "", "  <ModelStructure>"]
    by_name = {v.name: v for v in model.variables}
    for v in model.variables:
        if v.causality == "output":
            deps = None if v.dependencies is None else " ".join(str(by_name[d].vr) for d in v.dependencies)
            L.append("    <Output" + _attrs([("valueReference", str(v.vr)), ("dependencies", deps)]) + "/>")
    for _, d in model.states:
        L.append("    <ContinuousStateDerivative" + _attrs([("valueReference", str(by_name[d].vr))]) + "/>")
    idx_to_vr = {i: v.vr for i, v in enumerate(model.variables, start=1)}
    for u in root.iterfind("ModelStructure/InitialUnknowns/Unknown"):
        d = u.get("dependencies")
        deps = None if d is None else " ".join(str(idx_to_vr[int(i)]) for i in d.split())
        L.append("    <InitialUnknown" + _attrs([("valueReference", str(idx_to_vr[int(u.get("index"))])),
                                                 ("dependencies", deps)]) + "/>")
    L += ["    <EventIndicator" + _attrs([("valueReference", str(by_name[n].vr))]) + "/>"
          for n in model.indicator_variables]
    L += ["  </ModelStructure>", ""]
    # FMI 2.0's VendorAnnotations/Tool are FMI 3.0's Annotations/Annotation (after the structure)
    tools = root.findall("VendorAnnotations/Tool")
    if tools:
        L.append("  <Annotations>")
        for tool in tools:
            L.append("    <Annotation" + _attrs([("type", tool.get("name"))]) + ">")
            for child in tool:
                L.append("      " + ET.tostring(child, encoding="unicode").strip())
            L.append("    </Annotation>")
        L += ["  </Annotations>", ""]
    L += ["</fmiModelDescription>", ""]
    return "\n".join(L)


def emit_fmi3_build_description(model: Model, source: Path) -> str:
    root = ET.parse(source).getroot()
    L = ['<?xml version="1.0" encoding="UTF-8"?>',
         f"<!-- Generated from {source.name} by fmu_src/gen_model_vars.py. Do not edit. -->",
         '<fmiBuildDescription fmiVersion="3.0">',
         "  <BuildConfiguration" + _attrs([("modelIdentifier", model.identifier)]) + ">",
         '    <SourceFileSet language="C99">']
    L += ["      <SourceFile" + _attrs([("name", f)]) + "/>" for f in _source_files(root)]
    L += ["    </SourceFileSet>", "  </BuildConfiguration>", "</fmiBuildDescription>", ""]
    return "\n".join(L)


LAYOUT_TOOL = "dryfriction.layout"  # the vendor annotation holding an FMI 2.0 build's array layout


def _element_name(name: str, idx: tuple[int, ...]) -> str:
    """FMI 2.0's structured name of an array element: m[3], W[2,3]."""
    return f"{name}[{','.join(str(i) for i in idx)}]" if idx else name


def _layout_tool(layouts: tuple[ArrayLayout, ...], sizes: dict[str, int],
                 dims: dict[str, tuple[str, ...]]) -> ET.Element:
    """<Tool name="dryfriction.layout">: the build's sizes and every array's first element's value
    reference, shape and dimensions' structural parameters (dryfriction.model reads it and checks the
    elements against it; dryfriction.system.fmu lays the arrays out again for a structure's sizes)."""
    tool = ET.Element("Tool", {"name": LAYOUT_TOOL})
    lay = ET.SubElement(tool, "Layout", {"sizes": ",".join(f"{k}={n}" for k, n in sizes.items())})
    lay.text = "\n        "
    for k, a in enumerate(layouts):
        el = ET.SubElement(lay, "Array", {"name": a.name, "valueReference": str(a.vr), "first": str(a.first),
                                          "shape": " ".join(str(n) for n in a.shape),
                                          "dims": " ".join(dims[a.name])})
        el.tail = "\n        " if k + 1 < len(layouts) else "\n      "
    lay.tail = "\n    "
    tool.text = "\n      "
    tool.tail = "\n  "
    return tool


def emit_fmi2_model_description(model: Model, source: Path, size: int | str) -> str:
    """The FMI 2.0 model description of an indexed model for a build's structural parameters
    (``size``: one value for all, or ``n=4,nc=2``; build_sizes): every array element a
    ScalarVariable with its structured name (``m[i]``, ``W[i,j]``) and the value reference of the
    layout (fmi2_layout; written into the description's ``dryfriction.layout`` annotation), the
    structural parameters left out (fixed by the build), an array output's dependency on an array
    input of the same shape meaning the same element (of another shape: every element)."""
    root = ET.parse(source).getroot()
    sizes = build_sizes(model, size)
    layouts = {a.name: a for a in fmi2_layout(model, sizes)}
    structural = set(sizes)
    vendor = root.find("VendorAnnotations")
    if vendor is None:
        vendor = ET.Element("VendorAnnotations")
        vendor.text, vendor.tail = "\n    ", "\n\n  "
        root.insert(list(root).index(root.find("ModelVariables")), vendor)
    elif len(vendor):
        vendor[-1].tail = "\n    "
    vendor.append(_layout_tool(tuple(layouts.values()), sizes, {v.name: v.dims for v in model.variables if v.dims}))
    if model.model_exchange:  # the source counts the indicator variables, FMI 2.0 their elements
        root.set("numberOfEventIndicators", str(sum(layouts[n].count if model.variable(n).dims else 1
                                                    for n in model.indicator_variables)))
    head = ET.tostring(root, encoding="unicode").split("<ModelVariables>")[0]
    head = re.sub(r"\s*<!--.*?-->", "", head, flags=re.S)  # the source's own comments
    shown = ", ".join(f"{k} = {n}" for k, n in sizes.items())
    L = ['<?xml version="1.0" encoding="UTF-8"?>',
         f"<!-- Generated from {source.name} by fmu_src/gen_model_vars.py for {shown}. Do not edit. -->",
         head.rstrip().replace("\n", "\n", 1), "", "  <ModelVariables>"]

    def elements(v: Variable) -> list[tuple[tuple[int, ...], int]]:
        return layouts[v.name].elements() if v.dims else [((), v.vr)]

    index: dict[tuple[str, tuple[int, ...]], int] = {}
    srcs = {sv.get("name"): sv for sv in root.iterfind("ModelVariables/ScalarVariable")}
    state_of = {d: st for st, d in model.states}  # a state derivative's element: its state's element
    k = 0
    for v in model.variables:
        if v.name in structural:
            continue
        sv = srcs[v.name]
        el = next(iter(sv))
        for idx, vr in elements(v):
            k += 1
            index[(v.name, idx)] = k
            attrs = [(a, sv.get(a)) for a in ("causality", "variability", "initial")]
            where = "" if not idx else (f" (block {idx[0]})" if len(idx) == 1 else
                                        f" (element {', '.join(str(i) for i in idx)})")
            L.append("    <ScalarVariable" + _attrs([("name", _element_name(v.name, idx)), ("valueReference", str(vr))]
                                                    + attrs + [("description", sv.get("description") + where)]) + ">"
                     + f"<{el.tag}" + _attrs([(a, str(index[(state_of[v.name], idx)]) if a == "derivative" else
                                               _xml_number(v.element_start(idx), v.type) if a == "start" and
                                               v.start_off is not None else x)
                                              for a, x in el.attrib.items()]) + "/></ScalarVariable>")

    def dep_indices(v: Variable, idx: tuple[int, ...], d: str) -> list[int]:
        dv = model.variable(d)
        if not dv.dims:
            return [index[(d, ())]]
        if dv.dims == v.dims:
            return [index[(d, idx)]]
        return [index[(d, j)] for j, _ in elements(dv)]

    L += ["  </ModelVariables>", "", "  <ModelStructure>", "    <Outputs>"]
    outputs = [v for v in model.variables if v.causality == "output"]
    for v in outputs:
        for idx, _ in elements(v):
            deps = None
            if v.dependencies is not None:
                deps = " ".join(str(i) for d in v.dependencies for i in dep_indices(v, idx, d))
            L.append("      <Unknown" + _attrs([("index", str(index[(v.name, idx)])), ("dependencies", deps)]) + "/>")
    L.append("    </Outputs>")
    if model.states:
        L.append("    <Derivatives>")
        L += ["      <Unknown" + _attrs([("index", str(index[(d, idx)]))]) + "/>"
              for _, d in model.states for idx, _ in elements(model.variable(d))]
        L.append("    </Derivatives>")
    L.append("    <InitialUnknowns>")
    for v in outputs + [v for v in model.variables if v.causality == "calculatedParameter"]:
        for idx, _ in elements(v):
            L.append("      <Unknown" + _attrs([("index", str(index[(v.name, idx)]))]) + "/>")
    L += ["    </InitialUnknowns>", "  </ModelStructure>", "", "</fmiModelDescription>", ""]
    return "\n".join(L)


def emit_build_config(model: Model, source: Path, size: int | str | None) -> str:
    """The build configuration header of an indexed model (``chain_config.h``), shipped in an FMU's
    sources/ so that a plain compile of its listed files builds that FMU: with sizes (an FMI 2.0
    build, whose structural parameters are fixed: one value for all, or ``n=4,nc=2``)
    ``DFO_<MODEL>_FIXED_<NAME> size`` for each of them and the value references of the array
    elements (fmi2_layout: ``DFO_FMI2_ARRAYS``); without, none (FMI 3.0: set in Configuration Mode)."""
    structural = [v for v in model.variables if v.causality == "structuralParameter"]
    if not structural:
        raise ModelError("a build configuration is for a model with structural parameters")
    prefix = "DFO_" + upper_snake(model.identifier.replace("DryFriction", "")) + "_FIXED_"
    guard = "DFO_" + upper_snake(model.identifier.replace("DryFriction", "")) + "_CONFIG_H"
    sizes = build_sizes(model, size) if size is not None else None
    L = [f"/* Generated from {source.name} by fmu_src/gen_model_vars.py"
         + (f" for an FMI 2.0 build with {', '.join(f'{k} = {n}' for k, n in sizes.items())}" if sizes is not None
            else " for an FMI 3.0 build (structural parameters set in Configuration Mode)") + ". Do not edit. */",
         f"#ifndef {guard}", f"#define {guard}", ""]
    for v in structural:
        if sizes is None:
            L.append(f"/* {v.name}: a structural parameter, start {int(v.start)} (no {prefix}{upper_snake(v.name)}) */")
            continue
        L.append(f"#define {prefix}{upper_snake(v.name)} {sizes[v.name]} /* {v.name}, fixed by this build */")
    if sizes is not None:
        layouts = fmi2_layout(model, sizes)
        L += ["",
              "/* FMI 2.0: the value references of the array elements (the layout of the model description's",
              " * dryfriction.layout annotation): element (i, j) of array vr (1-based; i alone for a vector) is",
              " * first + (i - 1) cols + (j - 1), for count elements; arrays in the order of their value references */",
              "typedef struct {",
              "    unsigned int vr, first, count, cols;",
              "} dfo_fmi2_array;",
              f"#define DFO_FMI2_NUM_ARRAYS {len(layouts)}",
              "static const dfo_fmi2_array DFO_FMI2_ARRAYS[DFO_FMI2_NUM_ARRAYS] = {"]
        L += [f"    {{{a.vr}u, {a.first}u, {a.count}u, {a.shape[-1] if len(a.shape) > 1 else 1}u}}, /* {a.name} */"
              for a in layouts]
        L.append("};")
    L += ["", "#endif", ""]
    return "\n".join(L)


EMITTERS = {"--header": lambda m, src: emit_c_header(m, src.name), "--fmi3": emit_fmi3_model_description,
            "--fmi3-build": emit_fmi3_build_description}


def main(argv: list[str]) -> int:
    sized = None
    if len(argv) == 5 and argv[3] == "--fmi2":  # an indexed model's FMI 2.0 description for a size
        sized = lambda md: emit_fmi2_model_description(md, Path(argv[1]), argv[4])  # noqa: E731
    elif len(argv) in (4, 5) and argv[3] == "--config":  # an indexed model's build configuration header
        sized = lambda md: emit_build_config(md, Path(argv[1]), argv[4] if len(argv) == 5 else None)  # noqa: E731
    if sized is not None:
        try:
            text = sized(parse(Path(argv[1])))
        except (ModelError, ET.ParseError, OSError, ValueError) as e:
            print(f"gen_model_vars: {argv[1]}: {e}", file=sys.stderr)
            return 1
        out = Path(argv[2])
        if not out.exists() or out.read_text() != text:
            out.write_text(text)
        return 0
    if len(argv) not in (3, 4) or (len(argv) == 4 and argv[3] not in EMITTERS):
        print("usage: gen_model_vars.py SOURCE.xml OUT "
              "[--header|--fmi3|--fmi3-build|--fmi2 SIZE|--config [SIZE]]",
              file=sys.stderr)
        return 2
    try:
        model = parse(Path(argv[1]))
    except (ModelError, ET.ParseError, OSError, ValueError) as e:
        print(f"gen_model_vars: {argv[1]}: {e}", file=sys.stderr)
        return 1
    out = Path(argv[2])
    kind = argv[3] if len(argv) == 4 else "--header"
    if kind == "--header" and out.suffix != ".h":
        print(f"gen_model_vars: no emitter for {out.name} (a C header .h, or give --fmi3 / --fmi3-build)",
              file=sys.stderr)
        return 2
    text = EMITTERS[kind](model, Path(argv[1]))
    if not out.exists() or out.read_text() != text:
        out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
