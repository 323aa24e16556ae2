# Sphinx configuration of femreg's documentation: MyST Markdown pages, built offline by
# tools/docs.sh (warnings are errors there). Everything it needs is a Debian 12 package
# (tools/setup.sh installs them).
import os
import re

_root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))

project = "femreg"
author = "the femreg authors"
copyright = "2026, the femreg authors (AGPL-3.0-or-later)"
# The one version source is the project() line of CMakeLists.txt.
with open(os.path.join(_root, "CMakeLists.txt"), encoding="utf-8") as _f:
    _m = re.search(r"project\(femreg VERSION ([0-9.]+)", _f.read())
version = release = _m.group(1) if _m else "unknown"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.mathjax"]
source_suffix = {".md": "markdown"}
root_doc = "index"
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

# Files that other pages include (generated tables) or that are not pages.
exclude_patterns = [
    "_build",
    "accuracy/**",
    "scaling/**",
    "api/generated/_*",
]

autodoc_member_order = "bysource"
autodoc_typehints = "none"

try:
    import sphinx_rtd_theme  # noqa: F401  (Debian: python3-sphinx-rtd-theme)
    html_theme = "sphinx_rtd_theme"
except ImportError:
    html_theme = "alabaster"
html_title = f"femreg {release}"
html_show_sourcelink = False


def _literal_blocks(app, what, name, obj, options, lines):
    """Docstrings show examples as indented blocks after a plain paragraph (Python's habit,
    not reStructuredText's): mark each such block literal with a '::' paragraph."""
    i = 1
    while i < len(lines) - 1:
        prev, blank, nxt = lines[i - 1], lines[i], lines[i + 1]
        if (not blank.strip() and prev.strip() and not prev.startswith(" ")
                and nxt.startswith("    ") and not prev.rstrip().endswith("::")):
            lines[i:i + 1] = ["", "::", ""]
            i += 3
        else:
            i += 1


def setup(app):
    app.connect("autodoc-process-docstring", _literal_blocks)
