"""Figures of the powered-walking cost study (:mod:`heelstrike.analysis.cost_study`).

Drawing only, from the study's :class:`xarray.Dataset`; matplotlib object API, Agg canvas.
:func:`heelstrike.outputs.write_cost_figures` writes them.
"""

from __future__ import annotations

import textwrap

import numpy as np
import xarray as xr
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from heelstrike.plots import _new_figure

__all__ = ["BRANCH_CAPTION", "NO_WORK_LABEL", "cost_figure", "paper_comparison_figure"]



def _target(ds: xr.Dataset) -> str:
    return str(ds.attrs.get("target", "step_length"))


def _mark_missing(ax: Axes, x: np.ndarray, y: np.ndarray, colour: object,
                  label: str | None) -> None:
    """Grid points where no gait was found (``y`` NaN): a marker on the bottom edge of the
    axes, so that a gap in a line is not read as missing data."""
    missing = ~np.isfinite(np.asarray(y, dtype=float))
    if np.any(missing):
        ax.plot(np.asarray(x)[missing], np.full(int(missing.sum()), 0.03), "v", ms=6,
                mfc="none", color=colour, transform=ax.get_xaxis_transform(), clip_on=False,
                label=label)


def cost_figure(ds: xr.Dataset, variable: str = "cost_of_transport") -> Figure:
    """``variable`` against the target (step length or speed), one line per foot radius,
    one panel per actuation model; on a log axis where the panel's values are positive and span
    more than two decades."""
    tgt = _target(ds)
    acts = [str(a) for a in ds["actuation"].values]
    fig = _new_figure(4.2 * len(acts) + 1.6, 4.4)
    axes = fig.subplots(1, len(acts), squeeze=False)[0]
    radii = ds["radius"].values
    cmap = colormaps["viridis"]
    unit = ds[variable].attrs.get("units", "")
    for ax, act in zip(axes, acts, strict=True):
        unstable_labelled = False
        for k, r in enumerate(radii):
            y = ds[variable].sel(actuation=act).isel(radius=k).values
            colour = cmap(0.85 * k / max(len(radii) - 1, 1))
            ax.plot(ds[tgt].values, y, "o-", ms=3, color=colour, label=f"R = {r:g} m")
            if "branch" in ds:
                fresh = ds["branch"].sel(actuation=act).isel(radius=k).values == 1
                ax.plot(ds[tgt].values[fresh], y[fresh], "s", ms=7, mfc="none", color=colour)
            if "stable" in ds:  # an unstable gait is no walker's steady state: marked
                unstable = ds["stable"].sel(actuation=act).isel(radius=k).values == 0
                label = None
                if np.any(unstable) and not unstable_labelled:  # in the legend only if drawn
                    label, unstable_labelled = "unstable gait", True
                ax.plot(ds[tgt].values[unstable], y[unstable], "x", ms=7, mew=1.5,
                        color="tab:red", label=label)
            _mark_missing(ax, ds[tgt].values, y, colour,
                          f"R = {r:g} m: no gait found" if np.any(~np.isfinite(y)) else None)
        ax.set_title(act)
        ax.set_xlabel(f"{tgt.replace('_', ' ')} ({ds[tgt].attrs.get('units', '')})")
        name = ds[variable].attrs.get("long_name", variable.replace("_", " "))
        # wrapped: "collision loss per metre T_c / L_S (eq. 16) (J/m)" ran off the figure
        ax.set_ylabel(textwrap.fill(f"{name} ({unit})", 34))
        values = np.asarray(ds[variable].sel(actuation=act).values, dtype=float)
        finite = values[np.isfinite(values)]
        if finite.size and finite.min() > 0 and finite.max() > 100 * finite.min():
            # positive values over more than two decades (R = 0.9 lay on the axis of R = 0)
            ax.set_yscale("log")
            ax.grid(alpha=0.3, which="both")
        else:
            ax.grid(alpha=0.3)
    # beside the panels: inside, "best" still covered data points (QA sweep 6); the radii
    # first, then the markers (QA sweep 7: they were interleaved)
    handles, labels = axes[-1].get_legend_handles_labels()
    order = sorted(range(len(labels)),
                   key=lambda i: (2 if "no gait" in labels[i] else labels[i] == "unstable gait",
                                  i))
    axes[-1].legend([handles[i] for i in order], [labels[i] for i in order], fontsize=7,
                    loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    _caption(fig, BRANCH_CAPTION)
    return fig


def _caption(fig: Figure, text: str) -> None:
    """``text`` as the figure's title at 7 pt, its lines wrapped to the figure's width (a
    caption wider than a one-panel figure ran over the panel's y label)."""
    chars = max(int(fig.get_figwidth() * 72.0 / (0.55 * 7.0)), 30)  # ~0.55 em a character
    lines = [textwrap.fill(p.strip(), chars) for p in text.split(";")]
    fig.suptitle(";\n".join(lines), fontsize=7)


#: Figure caption of how the study chose its gaits (see ``cost_study.BRANCH_NOTE``).
BRANCH_CAPTION = (
    "each point: the cheapest periodic gait found (a gait whose legs cross more than once "
    "a step only where no other was found; continuation from neighbours and fresh "
    "searches; open squares: found by a fresh search, not by continuation; red x: unstable "
    "gait, a Floquet multiplier |m| > 1; open triangles on the bottom edge: no gait found there)"
)

#: What the comparison figure draws on its bottom edge where the gait needs no work (actuator
#: work per step at or below the study's ``work_floor_J``, the integrator's round-off).
NO_WORK_LABEL = "no work needed (round-off)"


def paper_comparison_figure(ds: xr.Dataset) -> Figure:
    """Paper's impact-only ``eta`` (imposed velocities) vs the actuator work per metre that the
    real periodic gait needs, against the foot radius; one panel per step length."""
    tgt = _target(ds)
    if tgt != "step_length" or "eta_paper" not in ds:
        raise ValueError("the comparison needs a study over step length")
    L = ds[tgt].values
    fig = _new_figure(3.4 * len(L) + 2.0, 3.6)
    axes = fig.subplots(1, len(L), squeeze=False, sharey=True)[0]
    R = ds["radius"].values
    floor = float(ds.attrs.get("work_floor_J", 0.0))  # J per step; 0: every value drawn
    for j, (ax, length) in enumerate(zip(axes, L, strict=True)):
        eta = np.asarray(ds["eta_paper"].isel({tgt: j}).values, dtype=float)
        # at McGeer's wheel (R = l) the paper's loss is zero: its round-off (1e-32 J/m) would
        # stretch the log axis over 30 decades; it is drawn as a marker on the bottom edge
        zero = eta <= 1e-12 * np.nanmax(np.abs(eta), initial=0.0)
        ax.plot(R, np.where(zero, np.nan, eta), "k--",
                label="paper: impact only, q3_dot = 1 rad/s")
        if np.any(zero):
            # a filled diamond: the open triangles on the same edge mean "no gait found"
            ax.plot(R[zero], np.full(int(zero.sum()), 0.03), "kD", ms=5,
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label="paper: no loss (McGeer's wheel)" if j == 0 else None)
        for act in ds["actuation"].values:
            sel = ds.sel(actuation=act).isel({tgt: j})
            y = np.asarray(sel["work_per_metre"].values, dtype=float)
            # a gait needing no work (McGeer's wheel) has W_act of round-off (1e-13 J): on the
            # log axis its line dived to 1e-12; drawn as a marker on the bottom edge instead
            free = np.isfinite(y) & (y * float(length) <= floor)
            (line,) = ax.plot(R, np.where(free, np.nan, y), "o-", ms=3,
                              label=f"{act}: W_act / L")
            if np.any(free):  # drawn above the paper's diamond (same edge, same R)
                ax.plot(R[free], np.full(int(free.sum()), 0.09), "o", ms=6,
                        color=line.get_color(), transform=ax.get_xaxis_transform(),
                        clip_on=False, label=f"{act}: {NO_WORK_LABEL}")
            if "stable" in sel:  # 0: unstable; NaN: no gait, or stability undecided
                unstable = (sel["stable"].values == 0) & ~free
                ax.plot(R[unstable], y[unstable], "x", ms=7, mew=1.5, color="tab:red")
            _mark_missing(ax, R, y, line.get_color(),
                          f"{act}: no gait found" if np.any(~np.isfinite(y)) else None)
        ax.set_title(f"L = {length:g} m")
        ax.set_xlabel("foot radius R (m)")
        ax.set_yscale("log")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("energy per metre (J/m)")
    handles, labels = axes[0].get_legend_handles_labels()
    for ax in axes[1:]:  # entries drawn in later panels only (a marker of one step length)
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    # beside the panels: inside, it covered the data of the first panel
    axes[-1].legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
                    borderaxespad=0.0)
    _caption(fig, BRANCH_CAPTION)
    return fig
