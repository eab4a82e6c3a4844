"""Figures of a design (:class:`~heelstrike.analysis.design.DesignResult`): the cost history and the
foot before and after. Draw only."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from heelstrike.analysis.design import DesignResult
from heelstrike.plots import _new_figure

__all__ = ["cost_history_figure", "foot_figure"]


def cost_history_figure(res: DesignResult) -> Figure:
    """The cost at each accepted iterate of the design (the start is iterate 0).

    Parameters
    ----------
    res : DesignResult

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = _new_figure(6.0, 3.6)
    ax = fig.add_subplot()
    cost = res.cost_history
    ax.plot(np.arange(cost.size), cost, "o-", color="C0")
    ax.set_xlabel("iterate")
    ax.set_ylabel(res.cost_name)
    ax.set_title(f"design: {res.cost_name}, {res.status.value}")
    ax.grid(True, alpha=0.3)
    return fig


def foot_figure(res: DesignResult) -> Figure:
    """The stance foot's sole in the leg frame (hip at the origin) at the start and at the end.

    Parameters
    ----------
    res : DesignResult
        With ``foot_start`` and ``foot_final`` (shape (N, 2), m).

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        If the result has no foot outline.
    """
    if res.foot_start is None or res.foot_final is None:
        raise ValueError("the design result has no foot outline (a walker without a hip)")
    fig = _new_figure(6.0, 3.6)
    ax = fig.add_subplot()
    for pts, label, style in ((res.foot_start, "start", "--"), (res.foot_final, "designed", "-")):
        ax.plot(pts[:, 0], pts[:, 1], style, label=label)
    ax.set_aspect("equal")
    ax.set_xlabel("x in the leg frame (m)")
    ax.set_ylabel("y in the leg frame (m)")
    ax.set_title("foot sole, hip at the origin")
    ax.legend()
    ax.grid(True, alpha=0.3)
    return fig
