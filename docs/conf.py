"""Sphinx configuration of pihyst's documentation site (``make docs``).

The pages are the Markdown of docs/ and the top-level README (MyST), and the API
reference generated from the docstrings (autosummary + numpydoc). ``make docs`` builds
with warnings as errors, so a broken link, a page left out of the index or a docstring
numpydoc cannot parse fails the build.
"""

import re

import pihyst

project = "pihyst"
author = "the pihyst developers"
copyright = "the pihyst developers, MIT licence"
release = pihyst.__version__
version = release

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
]

root_doc = "index"
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
templates_path = ["_templates"]
exclude_patterns = ["_build"]

# MyST: the Markdown of docs/ as GitHub renders it
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 4          # [text](page.md#a-heading) links, GitHub's slugs
myst_dmath_double_inline = True

# the API reference: one page per public callable, from the package's __all__
autosummary_generate = True
autosummary_ignore_module_all = False
autosummary_imported_members = True
autodoc_typehints = "none"        # numpydoc's Parameters section carries the types
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

html_theme = "alabaster"
html_title = f"pihyst {release}"
html_static_path = []

# The docstrings are written to be read in help() as well, where |x| is an absolute value
# or a norm; reStructuredText would read it as a substitution. Render each such |...| as
# literal text (doctest blocks are left alone: reStructuredText does not parse them).
_BARS = re.compile(r"(?<![|\w`\\])\|([^|\n`]+?)\|(?![|\w`])")


def _literal_bars(app, what, name, obj, options, lines):
    in_doctest = False
    for i, line in enumerate(lines):
        stripped = line.strip()
        if stripped.startswith(">>>"):
            in_doctest = True
        elif not stripped:
            in_doctest = False
        if not in_doctest:
            lines[i] = _BARS.sub(r"``|\1|``", line)


def setup(app):
    app.connect("autodoc-process-docstring", _literal_bars)
