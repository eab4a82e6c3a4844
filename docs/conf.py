"""Sphinx configuration of the heelstrike documentation.

Build (HTML into docs/_build/html, every warning an error):

    pip install '.[docs]' && sphinx-build -W --keep-going -b html docs docs/_build/html

Why Sphinx + sphinx-gallery + numpydoc (and not mkdocs-material + mkdocstrings): the library's
docstrings are numpydoc already, and numpydoc renders their Parameters/Returns sections with
shapes and units as they are; sphinx-gallery *executes* every example while the site is built
and puts the figure the script drew under it, so a gallery page cannot show a figure that the
current code does not draw; autodoc/autosummary give the API reference and the cross-references
from the paper's equations to the functions that implement them, all checked at build time
(``-W``: a broken reference fails the build). Theme: furo (light, readable, few dependencies).

Math: typeset by MathJax 3 shipped *with the built site* (``_static/mathjax/``, copied from the
PyPI package ``sphinx-mathjax-offline`` of the ``docs`` extra), never loaded from a CDN, so the
equations render on a site opened from disk with no network (checked in headless Chromium with
the network off by ``tests/test_docs_site.py``).
"""

from __future__ import annotations

import os
import sys
from importlib.metadata import version as _version
from pathlib import Path
from typing import Any

os.environ.setdefault("MPLBACKEND", "Agg")

project = "heelstrike"
author = "heelstrike developers"
copyright = "heelstrike developers, BSD-3-Clause"
release = _version("heelstrike")
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static/mathjax/ (no CDN: works offline)
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**.ipynb", "**.py.md5", "**.zip"]
html_theme = "furo"
html_title = f"heelstrike {release}"
html_static_path: list[str] = []
# the MathJax copy that sphinx-mathjax-offline puts into the site (relative to _static/)
mathjax_path = "mathjax/tex-chtml.js"

# -- API reference --------------------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = False
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types, shapes and units
# members defined in each module only: a package's __all__ re-exports (heelstrike.core.impact is
# both a function and a module) are documented once, in their own module
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
numpydoc_show_class_members = False  # autosummary lists members; avoids duplicate stubs
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# No network at build time: intersphinx inventories are not fetched (links to numpy etc. stay
# plain text), so the build is the same offline and on CI.
intersphinx_mapping: dict[str, tuple[str, str | None]] = {}

# Nitpicky: every cross-reference must resolve (with -W a dangling one fails the build), helped
# by _resolve_heelstrike below (package re-exports, unqualified names, attributes described in
# their class's Attributes section). Ignored, narrowly:
nitpicky = True
nitpick_ignore_regex = [
    # third-party objects: no intersphinx inventories (the build needs no network)
    (r"py:.*", r"(numpy|matplotlib|pandas|scipy|xarray|dask|distributed|zarr|pinocchio|pin"
               r"|collections\.abc|abc|dataclasses|enum|functools|typing|concurrent\.futures|filelock"
               r"|os|pathlib|shutil|subprocess|tempfile|mujoco)"
               r"(\..*)?"),
    # private modules (heelstrike.models._generated, ...) and functions are not documented
    (r"py:.*", r"heelstrike(\.\w+)*\._\w+(\..*)?"),
    (r"py:func", r"_\w+"),
    # a role split across two docstring lines (":func:`heelstrike.robots.states.<newline>
    # gait_configuration`") is read as a target ending in "."; to be fixed in the docstrings
    (r"py:.*", r"heelstrike(\.\w+)*\.\s+\w+"),
]
nitpick_ignore = [
    ("py:class", "CacheWarning"),  # defined in the private heelstrike.models._generated
    ("py:attr", "coordinate_names"),  # class attribute named in BuiltWalker's docstring
    ("py:data", "SHIPPED_ROBOTS"),  # module constant without a docstring (heelstrike.robots)
]

# -- gallery --------------------------------------------------------------------------------------
# heelstrike draws on matplotlib Figure objects without pyplot; _ext/figure_scraper.py finds them.
sys.path.insert(0, str(Path(__file__).parent / "_ext"))

sphinx_gallery_conf = {
    "examples_dirs": str(Path(__file__).parent.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": ("figure_scraper.scrape",),
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "abort_on_example_error": True,
    "matplotlib_animations": False,
    "reference_url": {"heelstrike": None},
    "doc_module": ("heelstrike",),
    "backreferences_dir": None,
    "min_reported_time": 1,
}


# -- cross-references to re-exported and unqualified heelstrike names --------------------------
def _documented(domain: Any, target: str, context: str | None) -> list[str]:
    """Documented full names that ``target`` may mean (see :func:`_resolve_heelstrike`)."""
    import importlib

    if target.startswith("heelstrike."):
        parts = target.split(".")
        for cut in range(len(parts) - 1, 1, -1):
            try:
                obj: Any = importlib.import_module(".".join(parts[:cut]))
            except ImportError:
                continue
            try:
                for name in parts[cut:]:
                    obj = getattr(obj, name)
            except AttributeError:
                return []
            module = getattr(obj, "__module__", None)
            qualname = getattr(obj, "__qualname__", None)
            full = f"{module}.{qualname}"
            return [full] if module and qualname and full in domain.objects else []
        return []
    names = [f"{context}.{target}", target] if context else [target]
    for name in names:
        found = [
            full for full in domain.objects
            if full.startswith("heelstrike.") and full.endswith("." + name)
        ]
        if found:
            return found
    return []


def _resolve_heelstrike(app: Any, env: Any, node: Any, contnode: Any) -> Any:
    """Resolve references that Sphinx leaves dangling but that name one documented object.

    ``heelstrike.models.CompassGait`` (a package re-export) goes to
    ``heelstrike.models.compass.CompassGait``; ``BuiltWalker`` (unqualified) to the one class of
    that name; an attribute that has no entry of its own (``WalkResult.status``, a dataclass
    field described in its class's Attributes section) to its class. Ambiguous names stay
    unresolved (and are reported: nitpicky).
    """
    if node.get("refdomain") != "py":
        return None
    domain = env.get_domain("py")
    target = str(node.get("reftarget", "")).lstrip("~.")
    context = node.get("py:class")
    found = _documented(domain, target, context)
    if not found and node.get("reftype") in ("attr", "meth", "obj") and "." in target:
        found = _documented(domain, target.rsplit(".", 1)[0], context)  # the owner class
    elif not found and node.get("reftype") in ("attr", "obj") and context:
        found = _documented(domain, context, None)
    if len(set(found)) != 1:
        return None
    from sphinx.util.nodes import make_refnode

    entry = domain.objects[found[0]]
    return make_refnode(
        app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, found[0]
    )


def setup(app: Any) -> None:
    app.connect("missing-reference", _resolve_heelstrike)
