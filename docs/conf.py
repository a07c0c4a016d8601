"""Sphinx configuration of pliant's documentation site: the guides (docs/*.md, through MyST) and
the API reference built from the docstrings (autodoc). Build it with
``python -m sphinx -W -b html docs build/docs`` (docs/README section in docs/api.md)."""

from importlib.metadata import version as _version

project = "pliant"
release = _version("pliant")
version = release
extensions = ["sphinx.ext.autodoc", "myst_parser"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build"]
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
myst_heading_anchors = 3
suppress_warnings = ["myst.xref_missing"]  # guides link to repository files outside the site
html_theme = "alabaster"
html_title = f"pliant {release}"
