"""Generate model_vars.h from modelDescription.xml, the single source of truth for the variables.

Usage: python gen_model_vars.py modelDescription.xml model_vars.h

The header gives the C side the GUID, the model identifier, a value reference VR_<name> and a
start value START_<name> for every variable, and a table of names, types and causalities used
for value-reference look-ups and error messages. Standard library only.
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

TYPES = {"Real": "DFO_REAL", "Integer": "DFO_INTEGER", "Enumeration": "DFO_INTEGER", "Boolean": "DFO_BOOLEAN"}
CAUSALITIES = {
    "parameter": "DFO_PARAMETER",
    "calculatedParameter": "DFO_CALCULATED",
    "input": "DFO_INPUT",
    "output": "DFO_OUTPUT",
}


def c_start(kind: str, start: str) -> str:
    if kind == "Boolean":
        return "1" if start in ("true", "1") else "0"
    if kind == "Real":
        return repr(float(start))
    return str(int(start))


def generate(xml_path: Path) -> str:
    root = ET.parse(xml_path).getroot()
    cs = root.find("CoSimulation")
    if cs is None:
        raise SystemExit(f"{xml_path}: no CoSimulation element")
    lines = [
        "/* Generated from modelDescription.xml by fmu_src/gen_model_vars.py. Do not edit. */",
        "#ifndef DFO_MODEL_VARS_H",
        "#define DFO_MODEL_VARS_H",
        "",
        f'#define MODEL_GUID "{root.get("guid")}"',
        f'#define MODEL_IDENTIFIER "{cs.get("modelIdentifier")}"',
        "",
        "typedef enum { DFO_REAL, DFO_INTEGER, DFO_BOOLEAN } dfo_var_type;",
        "typedef enum { DFO_PARAMETER, DFO_CALCULATED, DFO_INPUT, DFO_OUTPUT } dfo_var_causality;",
        "typedef struct {",
        "    unsigned int vr;",
        "    const char *name;",
        "    dfo_var_type type;",
        "    dfo_var_causality causality;",
        "} dfo_var_info;",
        "",
    ]
    table = []
    for sv in root.find("ModelVariables"):
        name, vr, causality = sv.get("name"), int(sv.get("valueReference")), sv.get("causality")
        kind_el = next(iter(sv))
        kind = kind_el.tag
        if kind not in TYPES or causality not in CAUSALITIES:
            raise SystemExit(f"{xml_path}: variable {name}: unsupported type {kind} or causality {causality}")
        lines.append(f"#define VR_{name} {vr}u")
        if kind_el.get("start") is not None:
            lines.append(f"#define START_{name} {c_start(kind, kind_el.get('start'))}")
        table.append(f'    {{{vr}u, "{name}", {TYPES[kind]}, {CAUSALITIES[causality]}}},')
    log_categories = [c.get("name") for c in root.find("LogCategories")]
    lines += [
        "",
        f"#define DFO_NUM_VARS {len(table)}",
        "static const dfo_var_info DFO_VARS[DFO_NUM_VARS] = {",
        *table,
        "};",
        "",
        f"#define DFO_NUM_LOG_CATEGORIES {len(log_categories)}",
        "static const char *const DFO_LOG_CATEGORIES[DFO_NUM_LOG_CATEGORIES] = {",
        *[f'    "{c}",' for c in log_categories],
        "};",
        "",
        "#endif",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print("usage: gen_model_vars.py modelDescription.xml model_vars.h", file=sys.stderr)
        return 2
    text = generate(Path(argv[1]))
    out = Path(argv[2])
    if not out.exists() or out.read_text() != text:
        out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
