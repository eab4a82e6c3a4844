"""Figures of Font & Kövecses (2008), drawn with matplotlib's object API (Agg canvas).

No :mod:`matplotlib.pyplot` is used: every function builds its own
:class:`~matplotlib.figure.Figure` on a :class:`~matplotlib.backends.backend_agg.FigureCanvasAgg`,
so nothing leaks into pyplot's global state and no display is needed. Drawing only: each
function takes the data that :mod:`heelstrike.analysis.paper` computes
(:func:`~heelstrike.analysis.paper.paper_figure_data`); whoever wants a figure computes its data
first. :func:`heelstrike.outputs.reproduce_paper` writes the figures and their CSVs.
"""

from __future__ import annotations

import matplotlib as mpl
import numpy as np
import pandas as pd
from matplotlib.colors import Colormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from heelstrike.analysis.paper import Figure3bData
from heelstrike.plots import _new_figure

__all__ = ["figure2", "figure3a", "figure3b"]



def _radius_colours(radii: np.ndarray, cmap: Colormap) -> dict[float, tuple[float, ...]]:
    lo, hi = float(np.min(radii)), float(np.max(radii))
    span = hi - lo if hi > lo else 1.0
    return {float(r): tuple(cmap(0.8 * (float(r) - lo) / span)) for r in radii}


def _radius_label(r: float, wheel: bool) -> str:
    return f"R = {r:g} m" + (" (wheel, degenerate)" if wheel else "")


def figure2(data: pd.DataFrame) -> Figure:
    """Fig. 2: pre-impact ``T_c`` (lost) and ``T_a`` (kept) against ``q3`` for several ``R``.

    Parameters
    ----------
    data : pandas.DataFrame
        As returned by :func:`heelstrike.analysis.paper.figure2_data` (one row per ``(R, q3)``;
        ``R_m`` in m, ``q3_deg`` in deg, ``T_c_J`` and ``T_a_J`` in J).

    Returns
    -------
    matplotlib.figure.Figure
        Two panels sharing the ``q3`` (deg) axis: ``T_c`` (J) and ``T_a`` (J).
    """
    df = data
    fig = _new_figure(10.5, 3.8)
    ax_c, ax_a = fig.subplots(1, 2, sharex=True)
    radii = np.unique(df["R_m"].to_numpy())
    colours = _radius_colours(radii, mpl.colormaps["viridis"])
    for r, group in df.groupby("R_m", sort=True):
        r_ = float(r)
        wheel = bool(group["degenerate_wheel"].all())
        style = {"color": colours[r_], "ls": ":" if wheel else "-", "lw": 1.8}
        label = _radius_label(r_, wheel)
        ax_c.plot(group["q3_deg"], group["T_c_J"], label=label, **style)
        ax_a.plot(group["q3_deg"], group["T_a_J"], label=label, **style)
    ax_c.set_title("constrained part $T_c$ (lost at impact)")
    ax_a.set_title("admissible part $T_a$ (kept)")
    ax_c.set_ylabel("$T_c$ (J)")
    ax_a.set_ylabel("$T_a$ (J)")
    for ax in (ax_c, ax_a):
        ax.set_xlabel("impact angle $q_3$ (deg)")
        ax.set_xlim(0.0, 45.0)
        ax.grid(alpha=0.3)
    ax_a.set_ylim(bottom=0.0)
    # beside the panels: inside, the R = 0 curve ran under it between 14 and 22 deg
    ax_a.legend(*ax_c.get_legend_handles_labels(), fontsize="small", loc="upper left",
                bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    fig.suptitle(
        "Fig. 2: decomposition of the pre-impact kinetic energy "
        r"($\dot q_3^- = 1$ rad/s, $\dot q_4^- = 0$; admissible impacts only)",
        fontsize="medium",
    )
    return fig


def figure3a(data: pd.DataFrame) -> Figure:
    """Fig. 3a: energy lost per metre ``eta`` (J/m, eq. 16) against ``q3`` for several ``R``.

    Parameters
    ----------
    data : pandas.DataFrame
        As returned by :func:`heelstrike.analysis.paper.figure3a_data` (one row per
        ``(R, q3)``; ``eta_J_per_m`` in J/m).

    Returns
    -------
    matplotlib.figure.Figure
    """
    df = data
    fig = _new_figure(7.0, 4.2)
    ax = fig.subplots()
    radii = np.unique(df["R_m"].to_numpy())
    colours = _radius_colours(radii, mpl.colormaps["viridis"])
    for r, group in df.groupby("R_m", sort=True):
        r_ = float(r)
        wheel = bool(group["degenerate_wheel"].all())
        ax.plot(group["q3_deg"], group["eta_J_per_m"], color=colours[r_],
                ls=":" if wheel else "-", lw=1.8, label=_radius_label(r_, wheel))
    ax.set_xlabel("impact angle $q_3$ (deg)")
    ax.set_ylabel(r"energy lost per metre $\eta$ (J/m)")
    ax.set_xlim(0.0, 45.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    ax.set_title(r"Fig. 3a: $\eta = T_c / L_S$ (admissible impacts only)", fontsize="medium")
    return fig


def figure3b(data: Figure3bData) -> Figure:
    """Fig. 3b: filled contours of ``eta`` (J/m) over ``q3`` (deg) and ``R`` (m).

    Impacts after which the trailing foot does not lift are left white; their boundary
    ``q2_dot+ = 0`` is drawn dashed (over ``R < l``: at ``R = l`` it vanishes identically).

    Parameters
    ----------
    data : Figure3bData
        As returned by :func:`heelstrike.analysis.paper.figure3b_data`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    d = data
    fig = _new_figure(5.8, 4.4)
    ax = fig.subplots()
    q3_deg = np.rad2deg(d.impact_angle)
    eta = np.ma.masked_invalid(d.eta)
    vmax = float(np.nanmax(d.eta)) if np.any(np.isfinite(d.eta)) else 1.0
    levels = MaxNLocator(nbins=12).tick_values(0.0, vmax)
    cs = ax.contourf(q3_deg, d.foot_radius, eta, levels=levels, cmap="viridis")
    fig.colorbar(cs, ax=ax, label=r"$\eta$ (J/m)")
    regular = ~d.degenerate_wheel
    handles = []
    if np.count_nonzero(regular) >= 2:
        q2 = d.q2_dot_plus[regular]
        if np.nanmin(q2) < 0.0 < np.nanmax(q2):
            ax.contour(q3_deg, d.foot_radius[regular], q2, levels=[0.0], colors="k",
                       linestyles="--", linewidths=1.5)
            handles.append(Line2D([], [], color="k", ls="--",
                                  label=r"$\dot q_2^+ = 0$"))
    ax.set_xlabel("impact angle $q_3$ (deg)")
    ax.set_ylabel("foot radius $R$ (m)")
    ax.set_xlim(0.0, 45.0)
    ax.set_ylim(float(d.foot_radius.min()), float(d.foot_radius.max()))
    if handles:
        ax.legend(handles=handles, fontsize="small", loc="upper left")
    ax.set_title(r"Fig. 3b: $\eta$ over ($q_3$, $R$); white: foot does not lift",
                 fontsize="medium")
    return fig
