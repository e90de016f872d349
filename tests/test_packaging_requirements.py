"""The package's declared requirements and its one version: requires-python and the dependency
minimums allow nothing the code cannot run on, and every file that names the version names the
same one."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]


def _lower_bound(spec: str) -> tuple[int, ...]:
    m = re.search(r">=\s*([0-9.]+)", spec)
    assert m, spec
    return tuple(int(x) for x in m.group(1).split("."))


def _sources() -> str:
    files = [*ROOT.joinpath("src").rglob("*.py"), *ROOT.joinpath("tests").glob("*.py"),
             *ROOT.joinpath("bench").glob("*.py"), *ROOT.joinpath("scripts").glob("*.py")]
    return "\n".join(f.read_text() for f in files if f.name != Path(__file__).name)


def test_declared_minimums_cover_what_the_code_uses() -> None:
    """requires-python and the numpy minimum allow nothing the code cannot run on: tomllib needs
    Python 3.11, np.trapezoid NumPy 2.0 (the full check: scripts/check_min_versions.sh)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    text = _sources()
    if re.search(r"^\s*(import tomllib|from tomllib)", text, re.M):
        assert _lower_bound(project["requires-python"]) >= (3, 11)
    numpy = next(d for d in project["dependencies"] if re.match(r"numpy\b", d))
    if "np.trapezoid(" in text:
        assert _lower_bound(numpy) >= (2, 0)
    deps = {re.match(r"[A-Za-z0-9_.-]+", d).group(0).lower() for d in project["dependencies"]}
    assert "tomli-w" in deps  # the config writer


def test_one_version_everywhere() -> None:
    """The package, pyproject.toml, the model description and CITATION.cff name the same version,
    and CHANGELOG.md has its section."""
    import tomllib

    import dryfriction
    from dryfriction.model import repository_xml

    root = repository_xml().parent
    v = dryfriction.__version__
    assert tomllib.loads((root / "pyproject.toml").read_text())["project"]["version"] == v
    assert f'version="{v}"' in repository_xml().read_text()
    assert f"version: {v}" in (root / "CITATION.cff").read_text()
    assert f"## {v} " in (root / "CHANGELOG.md").read_text()
