"""Sphinx configuration of cspace's documentation (``make docs``).

Sphinx rather than MkDocs: cspace's docstrings are numpy-style reStructuredText with Sphinx
roles (``:func:``, ``:class:``, ``:mod:``) throughout, which autodoc and napoleon render and
cross-link as they are; mkdocstrings would show those roles as raw text. The guides are
Markdown (MyST), so the benchmark reports in ``benchmarks/reports`` are included unchanged.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs"))

import cspace  # noqa: E402

project = "cspace"
author = "the cspace developers"
release = version = cspace.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
    "cli_reference",  # docs/cli_reference.py: the CLI reference from the argument parser
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_enable_extensions = ["colon_fence", "dollarmath"]
myst_heading_anchors = 3
exclude_patterns = ["_build"]
html_theme = "furo"
html_title = f"cspace {release}"

autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the numpy docstrings say the types, with units and shapes
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_param = False  # types as text: "(vertices, faces) or path" is not a cross-reference
napoleon_use_ivar = True  # "Attributes" as fields: dataclass fields are not described twice
# Docstrings name private helpers and submodules for the curious: unresolved names are fine.
nitpicky = False
suppress_warnings = ["myst.xref_missing", "myst.header"]
