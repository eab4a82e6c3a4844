"""Figures: results in, :class:`~matplotlib.figure.Figure` out (matplotlib object API, Agg canvas).

- :mod:`heelstrike.plots.paper`: the paper's Figs. 2, 3a and 3b;
- :mod:`heelstrike.plots.gait`: passive gaits (walks, animations, phase portraits, bifurcation
  diagrams, basins, gait maps);
- :mod:`heelstrike.plots.models`: impact maps of described walkers;
- :mod:`heelstrike.plots.powered`: cost-of-transport figures of powered gaits;
- :mod:`heelstrike.plots.robots`: heel-strike studies of URDF/MJCF robots.

Drawing only: no computing (the data come from :mod:`heelstrike.analysis`), no file writing
(:mod:`heelstrike.outputs` writes figures and data, :mod:`heelstrike.io` the data files; the
animations alone render to the file they are given).

The paper's figure functions are re-exported here (``from heelstrike.plots import figure3b``).
They are loaded on first use, so ``import heelstrike.plots`` does not import matplotlib.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from heelstrike.plots.paper import figure2, figure3a, figure3b

__all__ = ["figure2", "figure3a", "figure3b"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        return getattr(importlib.import_module("heelstrike.plots.paper"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


def _new_figure(
    width: float, height: float, *, dpi: float | None = None,
    layout: Literal["constrained"] | None = "constrained",
) -> Figure:
    """A ``width`` x ``height`` (inches) figure on its own Agg canvas (no pyplot state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=dpi, layout=layout)
    FigureCanvasAgg(fig)
    return fig
