"""Sphinx configuration of the workbench's documentation site.

`make docs` builds it with warnings as errors (``-W --keep-going``) into
``docs/_build/html``. The pages are markdown (MyST); the API reference is
generated from the numpydoc docstrings of every module of ``workbench`` and
``instruments`` (autosummary, recursive), the way colour-science documents its
own API.
"""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

# The GUI modules import PySide6; they must import without a display.
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
# pyvista must not try to open a render window while its modules are imported.
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
# Matplotlib without a GUI backend.
os.environ.setdefault("MPLBACKEND", "Agg")

import workbench  # noqa: E402  (after the environment above)

project = "VR colour workbench"
author = "the VR colour workbench authors"
copyright = "the VR colour workbench authors"
release = workbench.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx.ext.mathjax",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "api/_templates"]
templates_path = ["api/_templates"]

# MyST: markdown pages, headings get anchors so pages can link to sections.
myst_enable_extensions = ["colon_fence", "deflist", "dollarmath"]
myst_heading_anchors = 3
highlight_language = "none"  # a block without a language is shown as it is

# The API reference: one page per module, generated at every build (the
# generated pages are not kept in git: docs/api/generated/ is ignored).
autosummary_generate = True
autosummary_generate_overwrite = True
autosummary_ignore_module_all = True  # recurse into every public submodule
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_preserve_defaults = True
autoclass_content = "class"

# numpydoc renders the docstrings; a docstring it cannot parse is a warning,
# and warnings fail the build. Its style validation stays off: this is a
# parse check, not a style audit.
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()
numpydoc_xref_param_type = False

# Python cross-references that do not resolve are reported for the project's
# own names; types from numpy, the standard library and the other libraries
# are not documented here (no network for intersphinx), so they are not.
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(?!(workbench|instruments)\b).*"),
]

# `python -m workbench` runs the command line when imported; autosummary
# imports every module it recurses into, so this one is mocked (and skipped).
autodoc_mock_imports = ["workbench.__main__"]


def _resolve_through_the_code(app, env, node, contnode):
    """Resolve ``pkg.name`` to where the object is documented.

    The API pages document an object once, in the module that defines it; a
    docstring may name it where it is re-exported (``workbench.diagnostics.
    diagnose``) or name a module constant, a type variable or a private helper
    that has no entry of its own. Such a reference resolves when the name
    exists in the code: to the defining module's entry, or else to the page of
    the module that holds it. A name that does not exist stays unresolved,
    and the build fails on it.
    """
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    if not target.startswith(("workbench.", "instruments.")):
        return None
    import importlib

    parts = target.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        module_name = ".".join(parts[:cut])
        try:
            obj = importlib.import_module(module_name)
        except ImportError:
            continue
        try:
            for attribute in parts[cut:]:
                obj = getattr(obj, attribute)
        except AttributeError:
            return None
        break
    else:
        return None
    domain = env.get_domain("py")
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if module and qualname:
        found = domain.objects.get(f"{module}.{qualname}")
        if found is not None:
            return _reference(app.builder, node, found.docname, found.node_id, contnode)
    if not (module and qualname) or "<locals>" in qualname:
        module = module_name  # a constant or an instance: the module that holds it
    found = domain.modules.get(module)
    if found is not None:
        return _reference(app.builder, node, found.docname, found.node_id, contnode)
    return None


def _reference(builder, node, docname, anchor, contnode):
    from sphinx.util.nodes import make_refnode

    return make_refnode(builder, node["refdoc"], docname, anchor, contnode, node["reftarget"])


def _numpydoc_warnings_fail_the_build():
    """numpydoc reports what it cannot parse (an unknown section, whose text it
    drops) as a Python warning, which Sphinx would not count; send it to
    Sphinx's log as a warning, so ``-W`` fails on it."""
    import warnings

    from sphinx.util import logging

    logger = logging.getLogger("numpydoc")
    show = warnings.showwarning

    def showwarning(message, category, filename, lineno, file=None, line=None):
        if "numpydoc" in str(filename):
            logger.warning("numpydoc: %s", message)
        else:
            show(message, category, filename, lineno, file, line)

    warnings.showwarning = showwarning


def _screenshots_open_full_size(app, doctree, docname):
    """A screenshot is shown at the column's width; a click opens it at full
    size (Sphinx links an image to its file when it was given a width)."""
    from docutils import nodes

    for image in doctree.findall(nodes.image):
        if "screenshots/" in image.get("uri", "") and "width" not in image:
            image["width"] = "100%"


def setup(app):
    app.connect("missing-reference", _resolve_through_the_code)
    app.connect("doctree-resolved", _screenshots_open_full_size)
    _numpydoc_warnings_fail_the_build()


html_theme = "furo"
html_title = f"VR colour workbench {release}"
html_static_path = ["_static"]
html_css_files = ["workbench.css"]
html_show_sourcelink = False
html_last_updated_fmt = None
