"""Figure of a replayed motion: kinetic energy over time, touchdowns, predicted and recorded
losses (draw only; the data come from :func:`heelstrike.robots.replay.replay`)."""

from __future__ import annotations

from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from heelstrike.plots import _new_figure
from heelstrike.robots.replay import ReplayResult

__all__ = ["plot_replay"]


def plot_replay(result: ReplayResult, fig: Figure | None = None) -> Figure:
    """Draw the kinetic energy of a recorded motion with its touchdowns (nothing is saved).

    The kinetic energy ``T`` (J) of every sample against time (s); each touchdown is a dotted
    vertical line at its time, with two bars hanging from the pre-impact ``T``: the rigid
    prediction's ``T_c`` (just left of the touchdown) and the recorded loss over the window
    (at the window's end, where it was measured). A legend below the axes.

    Parameters
    ----------
    result : ReplayResult
        Arrays of shape (N,) and the touchdowns.
    fig : matplotlib.figure.Figure, optional
        Where to draw; None: a new 8 x 4.4 inch figure on an Agg canvas.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``, or the new figure, with one axes.
    """
    fig = fig if fig is not None else _new_figure(8, 4.4)
    ax = fig.subplots()
    ax.plot(result.time, result.kinetic, "-", color="C0", lw=1.2)
    span = float(result.time[-1] - result.time[0])
    gap = 0.006 * span
    for d in result.touchdowns:
        ax.axvline(d.time, color="0.5", ls=":", lw=0.8)
        ax.vlines(d.time_pre - gap, d.T - d.T_c, d.T, color="C3", lw=3.0)
        ax.vlines(d.time_post, d.T - d.recorded_loss, d.T, color="C2", lw=3.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("kinetic energy (J)")
    ax.set_title(f"{result.robot}: {len(result.touchdowns)} touchdown(s), window "
                 f"{result.window * 1e3:g} ms")
    handles = [Line2D([], [], color="C0", label="kinetic energy T"),
               Line2D([], [], color="0.5", ls=":", label="touchdown"),
               Line2D([], [], color="C3", lw=3.0, label="predicted loss T_c (rigid)"),
               Line2D([], [], color="C2", lw=3.0, label="recorded loss over the window")]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize="small")
    return fig
