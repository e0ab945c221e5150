"""Sphinx configuration of the sb3-twodrl documentation: the Markdown pages (MyST) and the API reference (autodoc).

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (needs the ``docs`` extra).
"""

import sys
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "envs"))  # the env package's folder, envs/twodrl_envs/
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

project = "sb3-twodrl"
author = "sb3-twodrl contributors"
copyright = "sb3-twodrl contributors"
release = metadata.version("sb3-twodrl")

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "repository_links",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_ext"]

myst_heading_anchors = 4
"""GitHub-style anchors (``page.md#a-heading``) for headings down to ``####``, as the pages link them."""

autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": True, "member-order": "bysource"}
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_preserve_defaults = True

html_theme = "furo"
html_title = "sb3-twodrl"
