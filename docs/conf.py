"""Sphinx configuration of the dryfriction documentation (built by scripts/docs.sh).

Markdown pages through MyST; the API reference generated from the docstrings by autosummary,
recursively over the package, so it follows the package's layout. The build is offline: no
intersphinx, no remote images."""

from __future__ import annotations

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

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
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
autodoc_typehints_description_target = "documented_params"
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
nitpick_ignore_regex = [
    ("py:.*", r"(numpy|np|pathlib|xarray|xr|pandas|collections|collections\.abc|typing|argparse|contextlib|"
              r"ctypes|os|io|concurrent|dask|distributed|matplotlib|fmpy|scipy|enum|types|threading|"
              r"subprocess|dataclasses|array|json|signal|zipfile|tomllib|multiprocessing)(\..*)?"),
    ("py:class", r"(Path|Any|Callable|Iterator|Iterable|Sequence|Mapping|ndarray|Dataset|DataArray|"
                 r"ArgumentParser|Namespace|TextIO|Figure|Axes|NDArray|float|int|str|bool|complex|bytes|"
                 r"None|object|type|Self|optional|callable|array_like|array-like|Client|LocalCluster)"),
]
