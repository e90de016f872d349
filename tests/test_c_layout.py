"""The layout of the C sources (fmu_src/): no include circle, and no circle of calls between the .c files
of one folder.

The #include graph is read from the quoted includes of every file under fmu_src/ (a header resolved by
its name: the FMUs' sources/ folder is flat, so every name is unique, which is checked too; generated
and FMI headers outside fmu_src/ are leaves). The call graph joins two .c files of one folder when one
calls a function the other defines (a non-static definition): a file that calls into another that
calls back would be a circle. Across folders the layers call down and a model's instance core is
called back through core/instance.h's model API (a plug-in interface, the same names in every
model), so the call check stays inside a folder, where the private headers are.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

FMU_SRC = Path(__file__).resolve().parents[1] / "fmu_src"

_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)
_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.DOTALL)
_STRING = re.compile(r'"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'')
_IDENT = re.compile(r"\b[A-Za-z_]\w*\b")
# a function definition at file scope: a line starting with its type, the name, the parameters, then {
_DEFINITION = re.compile(r"^([A-Za-z_][\w \t\n\*]*?)\b([A-Za-z_]\w*)\s*\(([^;{}()]*(?:\([^()]*\)[^;{}()]*)*)\)\s*\{",
                         re.MULTILINE)


def sources(root: Path) -> list[Path]:
    """Every .c and .h file under root, sorted."""
    return sorted(p for p in root.rglob("*") if p.suffix in (".c", ".h") and p.is_file())


def code_of(text: str) -> str:
    """C text without comments and string or character literals (their places kept as spaces)."""
    return _STRING.sub('""', _COMMENT.sub(" ", text))


def include_graph(root: Path) -> dict[str, list[str]]:
    """File name -> the names of the files under root it includes (quoted includes; names unique)."""
    files = sources(root)
    names = [p.name for p in files]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"file names not unique under {root} (the FMU's sources/ folder is flat): {twice}")
    known = set(names)
    return {p.name: [n for n in _INCLUDE.findall(code_of_includes(p.read_text())) if n in known] for p in files}


def code_of_includes(text: str) -> str:
    """C text without comments (the include lines kept: their quoted names are not literals to drop)."""
    return _COMMENT.sub(" ", text)


def find_cycle(graph: dict[str, list[str]]) -> list[str] | None:
    """A cycle of the directed graph as the list of its nodes, the first repeated at the end; None if none."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in graph.get(node, []):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)) is not None:
                return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)) is not None:
            return cycle
    return None


def defined_functions(code: str) -> set[str]:
    """The functions a C file (code_of'd) defines with external linkage."""
    out = set()
    for m in _DEFINITION.finditer(code):
        words = m.group(1).split()
        if "static" in words or m.group(2) in ("if", "for", "while", "switch", "return", "sizeof"):
            continue
        out.add(m.group(2))
    return out


def call_graph(folder: Path) -> dict[str, list[str]]:
    """.c file name -> the .c files of the same folder whose functions it uses (not itself)."""
    files = sorted(folder.glob("*.c"))
    code = {p.name: code_of(p.read_text()) for p in files}
    owner: dict[str, str] = {}
    for name, text in code.items():
        for f in defined_functions(text):
            owner[f] = name
    graph = {}
    for name, text in code.items():
        used = {owner[i] for i in set(_IDENT.findall(text)) if i in owner}
        graph[name] = sorted(used - {name})
    return graph


def folders(root: Path) -> list[Path]:
    """Every folder under root (root included) that holds a .c file."""
    return sorted({p.parent for p in root.rglob("*.c")})


def test_no_include_circle() -> None:
    graph = include_graph(FMU_SRC)
    assert len(graph) > 40 and sum(map(len, graph.values())) > 80  # the graph was read
    assert "scheme_state.h" in graph["newmark.h"] and "newmark.h" not in graph["exact.h"]
    cycle = find_cycle(graph)
    assert cycle is None, "include circle: " + " -> ".join(cycle)


@pytest.mark.parametrize("folder", [p.relative_to(FMU_SRC).as_posix() for p in folders(FMU_SRC)])
def test_no_call_circle_in_a_folder(folder: str) -> None:
    graph = call_graph(FMU_SRC / folder)
    cycle = find_cycle(graph)
    assert cycle is None, f"{folder}: circle of calls between files: " + " -> ".join(cycle)


def test_the_checks_find_circles(tmp_path: Path) -> None:
    """The two checks on a small tree with an include circle and a call circle (and a clean twin)."""
    (tmp_path / "a.h").write_text('#include "b.h"\nint a(void);\n')
    (tmp_path / "b.h").write_text('/* #include "c.h" in a comment */\n#include "a.h"\nint b(void);\n')
    (tmp_path / "a.c").write_text('#include "a.h"\nstatic int s(void) { return 1; }\n'
                                  'int a(void)\n{\n    return b() + s();\n}\n')
    (tmp_path / "b.c").write_text('#include "b.h"\nint\nb(void) { return a(); }\nconst char *t = "c()";\n')
    (tmp_path / "c.c").write_text('int c(void) { return 0; }\nstatic int d(void) { return c(); }\n')
    graph = include_graph(tmp_path)
    assert graph["b.h"] == ["a.h"] and find_cycle(graph) == ["a.h", "b.h", "a.h"]
    assert defined_functions(code_of((tmp_path / "a.c").read_text())) == {"a"}
    assert call_graph(tmp_path) == {"a.c": ["b.c"], "b.c": ["a.c"], "c.c": []}
    assert find_cycle(call_graph(tmp_path)) == ["a.c", "b.c", "a.c"]
    (tmp_path / "b.c").write_text('#include "b.h"\nint b(void) { return 2; }\n')
    (tmp_path / "b.h").write_text("int b(void);\n")
    assert find_cycle(include_graph(tmp_path)) is None and find_cycle(call_graph(tmp_path)) is None
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "a.h").write_text("")
    with pytest.raises(ValueError, match="not unique"):
        include_graph(tmp_path)
