"""Figures of Font & Kövecses (2008), drawn with matplotlib's object API (Agg canvas).

No :mod:`matplotlib.pyplot` is used: every function builds its own
:class:`~matplotlib.figure.Figure` on a :class:`~matplotlib.backends.backend_agg.FigureCanvasAgg`,
so nothing leaks into pyplot's global state and no display is needed. The data come from
:mod:`heelstrike.analysis.paper`.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib as mpl
import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import Colormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from heelstrike.analysis.paper import (
    Figure3bData,
    figure2_data,
    figure3a_data,
    figure3b_data,
    paper_figure_data,
    write_figure_data,
)
from heelstrike.models.compass import CompassGait

__all__ = ["figure2", "figure3a", "figure3b", "reproduce_paper"]


def _new_figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _radius_colours(radii: np.ndarray, cmap: Colormap) -> dict[float, tuple[float, ...]]:
    lo, hi = float(np.min(radii)), float(np.max(radii))
    span = hi - lo if hi > lo else 1.0
    return {float(r): tuple(cmap(0.8 * (float(r) - lo) / span)) for r in radii}


def _radius_label(r: float, wheel: bool) -> str:
    return f"R = {r:g} m" + (" (wheel, degenerate)" if wheel else "")


def figure2(data: pd.DataFrame | None = None, walker: CompassGait | None = None) -> Figure:
    """Fig. 2: pre-impact ``T_c`` (lost) and ``T_a`` (kept) against ``q3`` for several ``R``.

    Parameters
    ----------
    data : pandas.DataFrame, optional
        As returned by :func:`heelstrike.analysis.paper.figure2_data` (computed if omitted).
    walker : CompassGait, optional
        Walker for computing ``data`` (default: the paper's).

    Returns
    -------
    matplotlib.figure.Figure
        Two panels sharing the ``q3`` (deg) axis: ``T_c`` (J) and ``T_a`` (J).
    """
    df = figure2_data(walker) if data is None else data
    fig = _new_figure(9.0, 3.8)
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
    ax_c.legend(fontsize="small", loc="upper left")
    fig.suptitle(
        "Fig. 2: decomposition of the pre-impact kinetic energy "
        r"($\dot q_3^- = 1$ rad/s, $\dot q_4^- = 0$; admissible impacts only)",
        fontsize="medium",
    )
    return fig


def figure3a(data: pd.DataFrame | None = None, walker: CompassGait | None = None) -> Figure:
    """Fig. 3a: energy lost per metre ``eta`` (J/m, eq. 16) against ``q3`` for several ``R``.

    Parameters
    ----------
    data : pandas.DataFrame, optional
        As returned by :func:`heelstrike.analysis.paper.figure3a_data` (computed if omitted).
    walker : CompassGait, optional
        Walker for computing ``data`` (default: the paper's).
    """
    df = figure3a_data(walker) if data is None else data
    fig = _new_figure(5.5, 4.2)
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
    ax.legend(fontsize="small", loc="upper left")
    ax.set_title(r"Fig. 3a: $\eta = T_c / L_S$ (admissible impacts only)", fontsize="medium")
    return fig


def figure3b(data: Figure3bData | None = None, walker: CompassGait | None = None) -> Figure:
    """Fig. 3b: filled contours of ``eta`` (J/m) over ``q3`` (deg) and ``R`` (m).

    Impacts after which the trailing foot does not lift are left white; their boundary
    ``q2_dot+ = 0`` is drawn dashed (over ``R < l``: at ``R = l`` it vanishes identically).

    Parameters
    ----------
    data : Figure3bData, optional
        As returned by :func:`heelstrike.analysis.paper.figure3b_data` (computed if omitted).
    walker : CompassGait, optional
        Walker for computing ``data`` (default: the paper's).
    """
    d = figure3b_data(walker) if data is None else data
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


def reproduce_paper(
    out_dir: str | Path,
    walker: CompassGait | None = None,
    formats: tuple[str, ...] = ("png", "pdf"),
) -> list[Path]:
    """Write the paper's Figs. 2, 3a and 3b as images plus one CSV of data per figure.

    Parameters
    ----------
    out_dir : str or Path
        Output directory (created if needed).
    walker : CompassGait, optional
        Walker (default: the paper's, ``mH = 2 m = 10 kg``, ``a = b = 0.5 m``, ``l = 1 m``).
    formats : tuple of str
        Image formats understood by matplotlib.

    Returns
    -------
    list of Path
        ``fig2.png, fig2.pdf, fig2.csv, fig3a.png, ...`` in that order.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    data = paper_figure_data(walker)
    csvs = dict(zip(("fig2", "fig3a", "fig3b"), write_figure_data(data, out), strict=True))
    figures = {
        "fig2": figure2(data.figure2),
        "fig3a": figure3a(data.figure3a),
        "fig3b": figure3b(data.figure3b),
    }
    paths: list[Path] = []
    for name, fig in figures.items():
        for ext in formats:
            path = out / f"{name}.{ext}"
            fig.savefig(path, dpi=150, metadata=_metadata(ext))
            paths.append(path)
        paths.append(csvs[name])
    return paths


def _metadata(ext: str) -> dict[str, str | None]:
    """Reproducible files: no creation date in PDFs."""
    if ext == "pdf":
        return {"CreationDate": None, "Creator": "heelstrike"}
    return {"Software": "heelstrike"} if ext == "png" else {}
