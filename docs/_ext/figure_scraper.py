"""sphinx-gallery image scraper for matplotlib ``Figure`` objects made without pyplot."""

from __future__ import annotations

import weakref
from typing import Any

_scraped: weakref.WeakSet[Any] = weakref.WeakSet()


def scrape(block: Any, block_vars: dict[str, Any], gallery_conf: Any, **_: Any) -> str:
    """Save the matplotlib Figures a gallery block made, and return their reST.

    heelstrike draws with the object API (``matplotlib.figure.Figure``, no pyplot state), so
    sphinx-gallery's pyplot scraper would find nothing: this one looks for Figure objects in
    the example's namespace that it has not saved yet, in the order their names were bound.
    """
    from matplotlib.figure import Figure
    from sphinx_gallery.scrapers import figure_rst

    figures = []
    for value in list(block_vars["example_globals"].values()):
        if isinstance(value, Figure) and value not in _scraped:
            _scraped.add(value)
            figures.append(value)
    paths = []
    for fig, path in zip(figures, block_vars["image_path_iterator"], strict=False):
        fig.savefig(path, dpi=96)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
