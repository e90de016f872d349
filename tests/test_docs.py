"""The documentation: the README is a front page (its size, its links, no text shared with the
site's pages), the repository speaks of the software only (no issue numbers outside
CHANGELOG.md), every public name of the package has a docstring, and the site's build fails on a
broken internal link or anchor (scripts/docs.sh, docs/conf.py)."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
README_MAX_BYTES = 12_000


def _docs_pages() -> list[Path]:
    """The site's Markdown sources (not the build, not the generated API pages)."""
    return sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts and "generated" not in p.parts)


def _slug(heading: str) -> str:
    """A heading's anchor as GitHub and MyST (myst_heading_anchors) make it."""
    text = re.sub(r"[`*]|\[([^\]]*)\]\([^)]*\)", lambda m: m.group(1) or "", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    return {_slug(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.+?)\s*$", text, re.M)}


def _sentences(markdown: str) -> set[str]:
    """The prose sentences of a Markdown text, normalised: links reduced to their text, markup and
    case dropped, whitespace collapsed; code blocks and HTML comments left out."""
    text = re.sub(r"```.*?```|<!--.*?-->", " ", markdown, flags=re.S)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)
    text = re.sub(r"[`*|#]", " ", text)
    parts = re.split(r"(?<=[.!?;:])\s+|\n\s*\n|\n\s*[-|]", text)
    return {" ".join(p.lower().split()).rstrip(".:;") for p in parts}


def test_the_readme_is_a_front_page_of_at_most_12_kb() -> None:
    size = len(README.read_bytes())
    assert 2_000 < size <= README_MAX_BYTES, f"README.md is {size} bytes (at most {README_MAX_BYTES})"


def test_the_readmes_relative_links_resolve() -> None:
    links = re.findall(r"\]\(([^)\s]+)\)", README.read_text())
    relative = [u for u in links if not re.match(r"[a-z]+:", u)]
    assert len(relative) >= 10, relative
    for url in relative:
        path, _, anchor = url.partition("#")
        target = (ROOT / path) if path else README
        assert target.exists(), f"README.md links to {url}: no such file"
        if anchor:
            assert target.suffix == ".md" and anchor in _anchors(target), f"README.md links to {url}: no such heading"


def test_the_slug_rule_matches_the_headings_it_is_used_on() -> None:
    """The anchor rule the link test relies on, on headings with code, punctuation and links."""
    assert _slug("The FMU's coupling interface") == "the-fmus-coupling-interface"
    assert _slug("Steady states from orbits: `frequency_response(..., method=\"orbit\")`") == \
        "steady-states-from-orbits-frequency_response-methodorbit"
    assert _slug("Site springs and dampers; belts") == "site-springs-and-dampers-belts"


def test_no_sentence_of_12_words_is_both_in_the_readme_and_in_a_docs_page() -> None:
    readme = {s for s in _sentences(README.read_text()) if len(s.split()) >= 12}
    assert len(readme) >= 10, "the README's prose was not found"
    shared = {(page.name, s) for page in _docs_pages() for s in _sentences(page.read_text()) & readme}
    assert not shared, "written twice (keep it in one place):\n" + "\n".join(f"{p}: {s}" for p, s in sorted(shared))


def test_the_sentence_splitter_finds_a_repeated_sentence() -> None:
    page = "Intro.\n\nThe transient method runs 32, 64, 128 periods until the error left in the window is small. Next.\n"
    front = "# T\n\nThe transient method runs `32, 64, 128` periods until the error left in the [window](x.md) is small.\n"
    assert {s for s in _sentences(page) & _sentences(front) if len(s.split()) >= 12}


REPO_PATH = re.compile(r"(?<![\w/.-])((?:fmu_src|src|tests|scripts|bench|configs|examples|cmake)/(?:[\w./*-]|\[ch\])*(?:[\w*]|\[ch\]))")


def _named_paths(text: str) -> list[str]:
    """The repository paths a page names (``fmu_src/numerics/lcp.[ch]``, ``tests/c/chain_driver``,
    ``configs/*.toml``), link targets and link texts alike."""
    return [m.group(1) for m in REPO_PATH.finditer(text)]


def _exists(path: str) -> bool:
    """A named path exists: a file or folder, a [ch] pair, a glob that matches, or a program built
    from the C file of that name."""
    if "[ch]" in path:
        return all((ROOT / path.replace("[ch]", e)).exists() for e in "ch")
    if "*" in path:
        return any(ROOT.glob(path))
    return (ROOT / path).exists() or (ROOT / f"{path}.c").exists()


def test_every_path_the_docs_name_exists() -> None:
    """No stale paths: every repository path the README and the docs pages name is there."""
    named = {(page.name, path) for page in [README, *_docs_pages()] for path in _named_paths(page.read_text())}
    assert len(named) > 50
    stale = sorted((page, path) for page, path in named if not _exists(path))
    assert not stale, "paths that do not exist:\n" + "\n".join(f"{p}: {x}" for p, x in stale)


def test_a_stale_path_is_seen() -> None:
    names = _named_paths("the reference (src/dryfriction/chain_reference.py) and fmu_src/numerics/lcp.[ch]")
    assert names == ["src/dryfriction/chain_reference.py", "fmu_src/numerics/lcp.[ch]"]
    assert [_exists(n) for n in names] == [False, True]


ISSUE = re.compile(r"\bissues?\s+#?\d+", re.I)


def _tracked_text_files() -> list[Path]:
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    files = []
    for name in out.decode().split("\0"):
        if not name or name == "CHANGELOG.md":
            continue
        path = ROOT / name
        if path.suffix in {".png", ".csv", ".json", ".nc", ".fmu", ".whl", ".gz"} or not path.is_file():
            continue
        files.append(path)
    return files


def test_no_issue_numbers_outside_the_changelog() -> None:
    """Code, comments, messages and docs speak of the software, not of the project's history
    (CHANGELOG.md holds that), the C sources included."""
    files = _tracked_text_files()
    assert any(p.name == "README.md" for p in files) and len(files) > 100
    found = []
    for path in files:
        try:
            text = path.read_text()
        except UnicodeDecodeError:
            continue
        for n, line in enumerate(text.splitlines(), 1):
            if ISSUE.search(line):
                found.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()[:120]}")
    assert not found, "issue numbers (history belongs in CHANGELOG.md):\n" + "\n".join(found)


def test_the_issue_pattern_matches_what_it_must() -> None:
    # written so that this file does not match itself
    for text in (f"Issue {23}, the oscillator's part", f"item 1 of issue {22}", f"see issues {4} and 5",
                 f"(issue #{7})"):
        assert ISSUE.search(text), text
    for text in ("an issue with 3 blocks", "tissue 5", "the issue: 12 blocks"):
        assert not ISSUE.search(text), text


def _public_modules() -> list[str]:
    # importing dryfriction.__main__ would run the command line: it is not a module to document
    sys.modules.setdefault("dryfriction.__main__", types.ModuleType("dryfriction.__main__"))
    import dryfriction

    names = ["dryfriction"]
    for info in pkgutil.walk_packages(dryfriction.__path__, "dryfriction."):
        if not any(part.startswith("_") for part in info.name.split(".")[1:]):
            names.append(info.name)
    return names


def _undocumented(module_name: str) -> list[str]:
    """The public names defined in a module (functions, classes, and their public methods and
    properties) without a docstring."""
    module = importlib.import_module(module_name)
    missing = [] if (module.__doc__ or "").strip() else [module_name]
    for name, obj in vars(module).items():
        if name.startswith("_") or not (inspect.isclass(obj) or inspect.isfunction(obj)):
            continue
        if getattr(obj, "__module__", None) != module_name:
            continue                                   # documented where it is defined
        doc = (obj.__dict__.get("__doc__") if inspect.isclass(obj) else obj.__doc__) or ""
        if not doc.strip() or (inspect.isclass(obj) and doc.startswith(f"{name}(")):  # a dataclass's own
            missing.append(f"{module_name}.{name}")
        if inspect.isclass(obj):
            for attr, value in vars(obj).items():
                func = value.fget if isinstance(value, property) else getattr(value, "__func__", value)
                if not attr.startswith("_") and inspect.isfunction(func) and not (func.__doc__ or "").strip():
                    missing.append(f"{module_name}.{name}.{attr}")
    return missing


def test_every_public_name_has_a_docstring() -> None:
    modules = _public_modules()
    assert len(modules) > 40, modules
    missing = [name for module in modules for name in _undocumented(module)]
    assert not missing, f"{len(missing)} public names without a docstring:\n" + "\n".join(missing)


def test_the_docstring_check_sees_a_missing_one(monkeypatch: pytest.MonkeyPatch) -> None:
    module = types.ModuleType("dryfriction_probe", "A probe module.")

    def documented() -> None:
        """Has one."""

    def bare() -> None:
        pass

    class Thing:
        """A class."""

        def method(self) -> None:
            pass

    for obj in (documented, bare, Thing):
        obj.__module__ = "dryfriction_probe"
        setattr(module, obj.__name__, obj)
    monkeypatch.setitem(sys.modules, "dryfriction_probe", module)
    assert _undocumented("dryfriction_probe") == ["dryfriction_probe.bare", "dryfriction_probe.Thing.method"]


@pytest.mark.slow
def test_a_broken_anchor_fails_the_docs_build(tmp_path: Path) -> None:
    """The site's settings (docs/conf.py: MyST heading anchors, warnings as errors) turn a link to
    a heading that does not exist into a failed build; the same link to a heading that does exist
    builds."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text('extensions = ["myst_parser"]\nmyst_heading_anchors = 4\n'
                                 'exclude_patterns = ["_build"]\n')
    (src / "page.md").write_text("# Page\n\n## The default step\n\nText.\n")

    def build(anchor: str) -> subprocess.CompletedProcess[str]:
        (src / "index.md").write_text(f"# Index\n\n[the step](page.md#{anchor})\n\n```{{toctree}}\npage\n```\n")
        return subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "-n", "-q", "-E", str(src),
                               str(tmp_path / "out")], capture_output=True, text=True, timeout=300)

    good = build("the-default-step")
    assert good.returncode == 0, good.stderr
    bad = build("the-default-stpe")
    assert bad.returncode != 0 and "the-default-stpe" in bad.stderr, bad.stderr
    # and the project's own settings are those
    conf = (DOCS / "conf.py").read_text()
    assert "myst_heading_anchors = 4" in conf
    assert re.search(r"-W --keep-going -n", (ROOT / "scripts" / "docs.sh").read_text())


#: the modules whose docstrings hold the main entry points' examples
EXAMPLE_MODULES = ["dryfriction.analysis.response.sweep", "dryfriction.analysis.orbits",
                   "dryfriction.analysis.continuation", "dryfriction.references.exact",
                   "dryfriction.drivers.oscillator", "dryfriction.drivers.oscillator3",
                   "dryfriction.drivers.chain", "dryfriction.cosim.system"]


@pytest.mark.slow
@pytest.mark.parametrize("module", EXAMPLE_MODULES)
def test_the_docstring_examples_print_what_they_say(module: str) -> None:
    """Every ``>>>`` example of the main entry points runs and prints what its docstring shows (the
    API reference's examples are checked, not only rendered)."""
    import doctest
    import importlib

    mod = importlib.import_module(module)
    tests = [t for t in doctest.DocTestFinder().find(mod) if t.examples]
    assert tests, f"{module} has no example"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in tests:
        runner.run(t)
    result = runner.summarize(verbose=False)
    assert result.failed == 0 and result.attempted >= 1
