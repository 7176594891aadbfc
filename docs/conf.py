"""Sphinx configuration of the vesicle-tube HTML reference (``make docs``).

The source folder is docs/ itself: the Markdown pages (MyST) and one API page per package in
docs/api/ (reStructuredText, the markup autodoc writes). The command-line modules are the
application layer, not API: they are left out, and so is every private module.
:func:`check_api_pages` fails the build (with ``-W``) when a public module is on no API page,
so a new module cannot go undocumented unnoticed.
"""

import pkgutil
import re
import sys
import tomllib
from pathlib import Path

from sphinx.util import logging

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))          # document the tree being built, installed or not

project = "vesicle-tube"
author = "vesicle-tube developers"
copyright = author
release = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",      # MathJax served with the pages: equations render offline
    "myst_parser",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# validation.md.in is the template of validation.md; data/ and figures/ are inputs of pages,
# not pages (an image a page references is still copied into the output).
exclude_patterns = ["validation.md.in", "data", "figures", "Thumbs.db", ".DS_Store"]

# MyST: $...$ and $$...$$ as in theory.md; anchors on headings down to ###, so that a link to
# a section (user-guide.md#9-checking-your-results) resolves.
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

# autodoc + napoleon: numpydoc docstrings; members in source order (modules read top to bottom
# like the method), or in __all__'s order where a module has one. Members without a docstring
# are left out, so a dataclass field is described once, by its class's Attributes section.
autodoc_member_order = "bysource"
autodoc_preserve_defaults = True
napoleon_google_docstring = False
napoleon_numpy_docstring = True

# Literal blocks without a language (docstring tables and formulas, ASCII diagrams) stay plain;
# fenced blocks that name one and the docstrings' >>> examples are highlighted.
highlight_language = "none"

html_theme = "alabaster"
html_title = f"vesicle-tube {release}"

# Public modules that are not API: the command line (the application layer).
NOT_API = {"correlations.cli"}
PACKAGES = ("lubrication", "bem", "correlations")


def public_modules(package):
    """Modules of ``package`` that belong in the API reference, found without importing them."""
    found = []
    for info in pkgutil.iter_modules([str(ROOT / package)], prefix=f"{package}."):
        name = info.name
        last = name.rsplit(".", 1)[1]
        if not last.startswith("_") and name not in NOT_API:
            found.append(name)
    return sorted(found)


def check_api_pages(app):
    """Warn (an error under ``-W``) for a public module that no API page documents."""
    log = logging.getLogger(__name__)
    for package in PACKAGES:
        page = DOCS / "api" / f"{package}.rst"
        listed = set(re.findall(r"^\.\. automodule:: +(\S+)", page.read_text(), flags=re.M))
        for name in public_modules(package):
            if name not in listed:
                log.warning(f"public module {name} is on no API page: add it to "
                            f"docs/api/{package}.rst, or to NOT_API in docs/conf.py if it is "
                            "not API.")


def setup(app):
    app.connect("builder-inited", check_api_pages)
