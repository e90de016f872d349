"""Sphinx configuration of the dryfriction documentation (built by scripts/docs.sh).

Markdown pages through MyST; the API reference generated from the docstrings by autosummary,
recursively over the package, so it follows the package's layout. The build is offline: no
intersphinx, no remote images."""

from __future__ import annotations

import re
import sys
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

# autosummary imports every module of the package to list it; `python -m dryfriction` runs the
# command line when imported, so a stand-in module takes its place during the build
sys.modules.setdefault("dryfriction.__main__", types.ModuleType("dryfriction.__main__"))

import dryfriction  # noqa: E402

project = "dryfriction"
author = "the dryfriction authors"
copyright = "the dryfriction authors, BSD-2-Clause"
release = version = dryfriction.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}  # .rst first: autosummary writes its pages with the first
root_doc = "index"
exclude_patterns = ["_build", "_templates", "Thumbs.db", ".DS_Store"]
templates_path = ["_templates"]

# MyST: every heading up to level 4 gets an anchor, so `page.md#anchor` links are checked
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
suppress_warnings: list[str] = []

# the API reference
autosummary_generate = True
autosummary_imported_members = False
autosummary_ignore_module_all = True
autodoc_typehints = "description"
autodoc_typehints_description_target = "all"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
autoclass_content = "both"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

# offline: nothing fetched at build time (mathjax is loaded by the reader's browser only where a
# page has an equation)
html_theme = "furo"
html_title = f"dryfriction {release}"
html_static_path: list[str] = []
html_show_sourcelink = False

# -n (nitpicky): every reference into the package must resolve; names of other packages cannot,
# offline (no intersphinx), so they are not checked
# the structure's class as the drivers' and the FMU writer's annotations name it ("System" alone is
# also the co-simulation master's)
autodoc_type_aliases = {"Structure": "dryfriction.system.structure.System"}

nitpick_ignore_regex = [
    ("py:.*", r"(numpy|np|pathlib|xarray|xr|pandas|collections|collections\.abc|typing|argparse|contextlib|"
              r"ctypes|os|io|concurrent|dask|distributed|matplotlib|fmpy|scipy|enum|types|threading|"
              r"subprocess|dataclasses|array|json|signal|zipfile|tomllib|multiprocessing|xml|hashlib|shutil|tempfile|"
              r"logging|warnings|inspect|importlib|functools|itertools|math|random|re|sys|time|datetime)(\..*)?"),
    ("py:.*", r"(.*\._\w+.*|_\w+(\.\w+)*|T|dryfriction\.\w+(\.\w+)*\.T)"),  # private names, type variables
    ("py:attr", r".*"),                    # instance attributes named in the prose are not documented
    ("py:class", r"(OscillatorFMU|ChainFMU|FMI3Oscillator|ChainError)"),  # deprecated aliases
    ("py:func", r"dryfriction\.cli\.main\.main"),   # the module cli.main is shadowed by the function cli.main
    ("py:class", r"(Path|Any|Callable|Iterator|Iterable|Sequence|Mapping|ndarray|Dataset|DataArray|"
                 r"ArgumentParser|Namespace|TextIO|Figure|Axes|NDArray|float|int|str|bool|complex|bytes|"
                 r"None|object|type|Self|optional|callable|array_like|array-like|Client|LocalCluster|module|"
                 r"SimpleNamespace|Intermediate|Inputs|Structure)"),
]


def _keep_attribute_prose(app, what, name, obj, options, lines):  # noqa: ANN001
    """The package's attribute and property docstrings are prose ("the step h: the given one, ..."):
    undo napoleon's reading of the text before a first colon as a type."""
    if what not in {"attribute", "data", "property"}:
        return
    for i, line in enumerate(lines):
        if line.startswith(":type: "):
            head = line[len(":type: "):]
            del lines[i]
            if i and not lines[i - 1].strip():
                del lines[i - 1]
            first = next((j for j, text in enumerate(lines) if text.strip()), None)
            if first is None:
                lines.append(head)
            else:
                lines[first] = f"{head}: {lines[first]}"
            return



def _skip_aliases(app, what, name, obj, skip, options):  # noqa: ANN001
    """A class or function bound under a second name in its module (a deprecated alias) is
    documented once, under its own name."""
    own = getattr(obj, "__name__", name)
    if (isinstance(obj, type) or callable(obj)) and own != name and not name.startswith("_") \
            and getattr(obj, "__module__", "").startswith("dryfriction"):
        return True
    return None


def _resolve_short_names(app, env, node, contnode):  # noqa: ANN001
    """A reference by a short or re-exported name (``UsageError``, ``dryfriction.FMUCallError``,
    ``dryfriction.cosim.System``) resolves to the one documented object of that name."""
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    last = target.rsplit(".", 1)[-1]
    domain = env.get_domain("py")
    hits = [name for name in domain.objects if name.rsplit(".", 1)[-1] == last
            and name.startswith("dryfriction.") and ("." not in target or name.endswith(target.split(".", 1)[-1])
                                                    or target.startswith("dryfriction."))]
    if len(hits) > 1:  # (one name in two modules: the one under the target's package, or the referrer's)
        home = target.rsplit(".", 1)[0] + "." if "." in target else (node.get("py:module") or "") + "."
        near = [name for name in hits if name.startswith(home)]
        while not near and home.count(".") > 1:
            home = home[:-1].rsplit(".", 1)[0] + "."
            near = [name for name in hits if name.startswith(home)]
        hits = near
    if len(hits) != 1:
        return None
    node["reftarget"] = hits[0]
    return domain.resolve_xref(env, node["refdoc"], app.builder, node["reftype"], hits[0], node, contnode)


def _escape_bars(app, what, name, obj, options, lines):  # noqa: ANN001
    """The docstrings write absolute values as |x| in prose; outside literals and literal blocks a
    bar is escaped, so that reStructuredText does not read |x| as a substitution."""
    literal_indent = None
    for i, line in enumerate(lines):
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None:
            if line.strip() and indent <= literal_indent:
                literal_indent = None
            else:
                continue
        if line.rstrip().endswith("::"):
            literal_indent = indent
        parts = re.split(r"(``.*?``|`[^`]*`)", line)
        lines[i] = "".join(part if j % 2 else part.replace("|", "\\|") for j, part in enumerate(parts))


def setup(app):  # noqa: ANN001, ANN201
    """Register the docstring fix-up after napoleon (priority 500)."""
    app.connect("autodoc-process-docstring", _keep_attribute_prose, priority=600)
    app.connect("autodoc-skip-member", _skip_aliases)
    app.connect("autodoc-process-docstring", _escape_bars, priority=400)
    app.connect("missing-reference", _resolve_short_names)
