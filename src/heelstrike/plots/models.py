"""Figures of the heel-strike study for any described walker (see
:func:`heelstrike.analysis.model_gaits.impact_map`): ``T_c``, ``T_a`` and ``eta`` over two swept
quantities.

Only admissible impacts (the trailing foot lifts) are coloured; the other grid cells are grey,
and the boundary between the two, drawn dashed, is taken from the same ``lifts`` decision that
the CSV holds (:func:`heelstrike.outputs.write_impact_map`), so figure and data agree cell by
cell. Drawing only, with matplotlib's object API (no pyplot state).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from numpy.typing import NDArray

from heelstrike.analysis.model_gaits import ANGLE, ImpactMap
from heelstrike.plots import _new_figure

__all__ = ["LIFT_BOUNDARY_GID", "impact_map_figure"]

#: ``gid`` of the dashed lift-boundary contour in :func:`impact_map_figure`.
LIFT_BOUNDARY_GID = "lift_boundary"

_NOT_LIFTING_COLOUR = "0.82"


def _label(name: str, units: Mapping[str, str]) -> str:
    if name == ANGLE:
        return "impact angle (deg)"
    return f"{name} ({units[name]})" if name in units else f"{name} (SI units)"


def _axis(name: str, values: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.degrees(values) if name == ANGLE else np.asarray(values, dtype=float)


def impact_map_figure(m: ImpactMap, units: Mapping[str, str] | None = None) -> Figure:
    """Three panels: ``T_c`` (J), ``T_a`` (J) and ``eta`` (J/m) over the two swept quantities.

    Cells where the trailing foot does not lift (``m.lifts`` False: the impact is not
    admissible) or the walker is invalid are masked grey; the lift boundary (gid
    :data:`LIFT_BOUNDARY_GID`) is the 0.5 level of ``m.lifts``, so it runs between a lifting and
    a non-lifting cell centre and never inside either region.

    Parameters
    ----------
    m : ImpactMap
    units : mapping of str to str, optional
        Unit of each swept parameter (e.g. :func:`parameter_units`); the impact angle is in
        degrees.

    Returns
    -------
    matplotlib.figure.Figure
    """
    u = dict(units or {})
    fig = _new_figure(14, 4.4)
    axes = fig.subplots(1, 3)
    xs, ys = _axis(m.x_name, m.x), _axis(m.y_name, m.y)
    X, Y = np.meshgrid(xs, ys)
    lifts = np.asarray(m.lifts, dtype=bool)
    grey = ListedColormap([_NOT_LIFTING_COLOUR])
    for ax, (title, Z) in zip(
        axes, (("$T_c$ (J)", m.T_c), ("$T_a$ (J)", m.T_a), (r"$\eta$ (J/m)", m.eta)),
        strict=True,
    ):
        shown = np.ma.masked_where(~lifts | ~np.isfinite(Z), Z)
        if m.x.size > 1 and m.y.size > 1:
            if not np.all(lifts):
                ax.pcolormesh(X, Y, np.ma.masked_where(lifts, np.zeros(Z.shape)),
                              shading="auto", cmap=grey)
            if np.any(~np.ma.getmaskarray(shown)):
                pc = ax.pcolormesh(X, Y, shown, shading="auto", cmap="viridis")
                fig.colorbar(pc, ax=ax, label=title)
            if np.any(lifts) and not np.all(lifts):
                cs = ax.contour(X, Y, lifts.astype(float), levels=[0.5], colors="k",
                                linestyles="--", linewidths=1.2)
                cs.set_gid(LIFT_BOUNDARY_GID)
            # the computed grid only: the cells' outer halves would show values never
            # computed, a negative foot radius at R = 0 (QA sweep 13), as the gait map does
            ax.set_xlim(float(np.min(xs)), float(np.max(xs)))
            ax.set_ylim(float(np.min(ys)), float(np.max(ys)))
            ax.set_xlabel(_label(m.x_name, u))
            ax.set_ylabel(_label(m.y_name, u))
        else:
            one_x = m.x.size > 1
            t = (xs if one_x else ys).ravel()
            z, ok = np.asarray(Z, dtype=float).ravel(), lifts.ravel()
            ax.plot(t[ok], z[ok], "o-", color="tab:blue")
            if not np.all(ok):
                ax.plot(t[~ok], z[~ok], "x", color="0.5")
            ax.set_xlabel(_label(m.x_name if one_x else m.y_name, u))
            ax.set_ylabel(title)
        ax.set_title(title)
    if m.x.size > 1 and m.y.size > 1:
        handles = [Patch(color=_NOT_LIFTING_COLOUR, label="trailing foot does not lift"),
                   Line2D([], [], color="k", ls="--", label="lift boundary")]
    else:
        handles = [Line2D([], [], color="tab:blue", marker="o", label="trailing foot lifts"),
                   Line2D([], [], color="0.5", marker="x", ls="",
                          label="trailing foot does not lift")]
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize="small")
    held = [] if ANGLE in (m.x_name, m.y_name) else [f"impact angle {np.degrees(m.angle):g} deg"]
    for name, values in ((m.x_name, m.x), (m.y_name, m.y)):
        if values.size == 1:
            v = float(_axis(name, values)[0])
            unit = "deg" if name == ANGLE else u.get(name, "(SI units)")
            held.append(f"{'impact angle' if name == ANGLE else name} = {v:g} {unit}")
    fig.suptitle(f"heel strike of '{m.walker_name}' at stance rate {m.stance_rate:g} rad/s"
                 + "".join(f", {h}" for h in held))
    return fig
