"""Figures of real robots: the paper's Figs. 2-3 for a URDF/MJCF robot (draw only).

The data come from :func:`heelstrike.robots.robot_heel_strike_study`.
"""

from __future__ import annotations

from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from heelstrike.plots import _new_figure
from heelstrike.robots.study import RobotStudy

__all__ = ["plot_robot_study"]


def plot_robot_study(study: RobotStudy, fig: Figure | None = None) -> Figure:
    """Draw a robot's heel-strike study (nothing is shown or saved; pyplot is not used).

    Left: ``T_c`` (solid) and ``T_a`` (dashed) against step length, one colour per strike
    speed, inadmissible impacts (trailing foot not lifting) marked with crosses. Right: loss per
    metre ``T_c / L`` over (step length, strike speed), with the trailing foot's lift-off
    boundary (its post-impact vertical velocity = 0) dashed; a line over step length when the
    study has one strike speed.

    Parameters
    ----------
    study : RobotStudy
        From :func:`heelstrike.robots.robot_heel_strike_study`; arrays of shape
        ``(n_step_lengths, n_strike_speeds)``.
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (a new 10 x 4.6 inch figure on an Agg canvas if None).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = _new_figure(10, 4.6) if fig is None else fig
    ax1, ax2 = fig.subplots(1, 2)
    L, S = study.step_length, study.strike_speed
    colours = [f"C{i % 10}" for i in range(S.size)]
    for j in range(S.size):
        ax1.plot(L, study.T_c[:, j], "-", color=colours[j])
        ax1.plot(L, study.T_a[:, j], "--", color=colours[j])
        bad = ~study.admissible[:, j]
        ax1.plot(L[bad], study.T_c[bad, j], "x", color=colours[j])
    ax1.set_xlabel("step length (m)")
    ax1.set_ylabel("energy (J)")
    ax1.set_title(f"{study.robot}: {study.contact} strike")
    # one legend below the panels (inside, it covered curves): line style = energy, colour =
    # strike speed
    handles = [Line2D([], [], color="k", ls="-", label="T_c (lost)"),
               Line2D([], [], color="k", ls="--", label="T_a (kept)"),
               Line2D([], [], color="k", ls="none", marker="x", label="inadmissible"),
               *(Line2D([], [], color=c, label=f"{s:g} m/s")
                 for c, s in zip(colours, S, strict=True))]
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 9),
               fontsize="small")
    if L.size > 1 and S.size > 1:
        mesh = ax2.pcolormesh(L, S, study.loss_per_metre.T, shading="nearest")
        fig.colorbar(mesh, ax=ax2, label="T_c / L (J/m)")
        ax2.contour(L, S, study.trailing_lift_speed.T, levels=[0.0], colors="k",
                    linestyles="--")
        ax2.set_ylabel("strike speed (m/s)")
    else:
        ax2.plot(L, study.loss_per_metre[:, 0], "o-")
        ax2.set_ylabel("T_c / L (J/m)")
    ax2.set_xlabel("step length (m)")
    return fig
