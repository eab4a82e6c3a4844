"""Data of the figures of Font & Kövecses (2008): Fig. 2, Fig. 3a and Fig. 3b.

This module computes what the figures show; :mod:`heelstrike.plots.paper` draws it and
:func:`heelstrike.outputs.reproduce_paper` writes figures and data
(:func:`heelstrike.outputs.write_figure_data`: one CSV per figure).

Conventions shared by the figures
---------------------------------
- The paper's walker (``mH = 2 m = 10 kg``, ``a = b = 0.5 m``, ``l = 1 m``) and pre-impact
  velocities ``q3_dot = 1 rad/s``, ``q4_dot = 0``.
- Impact angles run over ``(0, 45 deg]``: the grid starts one step above 0 because at ``q3 = 0``
  the step length vanishes and ``eta`` (eq. 16) is undefined.
- Only admissible impacts are shown (the trailing foot lifts, ``q2_dot+ > 0``), as in the paper.
- ``R = l`` (McGeer's synthetic wheel) is degenerate: both feet are arcs of one circle about the
  hip, so the impact changes nothing, ``T_c = 0`` and ``q2_dot+ = 0`` exactly. It is the limit
  ``R -> l`` of admissible impacts (``q2_dot+ > 0`` for every ``R < l`` near ``l``), and the paper
  plots it, so the figures keep it, flagged by the ``degenerate_wheel`` column. Its impacts
  are not admissible (``trailing_foot_lifts`` is false there); the ``shown`` column marks what
  the figures draw: admissible impacts and the wheel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import BoolArray, FloatArray
from heelstrike.analysis.heel_strike import heel_strike_study
from heelstrike.models.compass import CompassGait

__all__ = [
    "FIGURE_RADII",
    "MAX_IMPACT_ANGLE",
    "Figure3bData",
    "PaperFigureData",
    "figure2_data",
    "figure3a_data",
    "figure3b_data",
    "heel_strike_table",
    "impact_angle_grid",
    "paper_figure_data",
]

#: Foot radii (m) of the curves of Figs. 2 and 3a.
FIGURE_RADII: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)
#: Largest impact angle of the figures (rad): 45 deg.
MAX_IMPACT_ANGLE: float = float(np.deg2rad(45.0))


def impact_angle_grid(n: int = 180, max_angle: float = MAX_IMPACT_ANGLE) -> FloatArray:
    """``n`` evenly spaced impact angles in ``(0, max_angle]`` (rad), shape (n,).

    The grid is ``max_angle * (1..n) / n``: it starts one step above 0, where ``eta`` is
    undefined (zero step length).
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    if not (np.isfinite(max_angle) and max_angle > 0):
        raise ValueError(f"max_angle must be a positive angle (rad), got {max_angle}")
    return np.asarray(max_angle * np.arange(1, n + 1) / n, dtype=float)


def heel_strike_table(
    walker: CompassGait | None = None,
    radii: ArrayLike = FIGURE_RADII,
    impact_angles: ArrayLike | None = None,
    *,
    q3_dot: float = 1.0,
    q4_dot: float = 0.0,
) -> pd.DataFrame:
    """Long table of the heel-strike study over radii x impact angles, all impacts.

    Parameters
    ----------
    walker : CompassGait, optional
        Scalar-parameter walker (paper defaults); its ``foot_radius`` is replaced by ``radii``.
    radii : array_like, shape (n_R,)
        Foot radii ``R`` (m).
    impact_angles : array_like, shape (n_q3,), optional
        ``q3`` (rad); default :func:`impact_angle_grid`.
    q3_dot, q4_dot : float
        Pre-impact angular velocities (rad/s).

    Returns
    -------
    pandas.DataFrame
        ``n_R * n_q3`` rows ordered by ``R`` then ``q3``; columns ``R_m, q3_deg, q3_rad, T_J,
        T_c_J, T_a_J, energy_lost_J, step_length_m, eta_J_per_m, q2_dot_plus_m_per_s,
        trailing_foot_lifts, degenerate_wheel, shown``: an impact is admissible when
        ``trailing_foot_lifts`` (``q2_dot+ > 0``); ``shown`` is what the figures draw
        (admissible, or McGeer's wheel, see the module docstring).
    """
    w = CompassGait() if walker is None else walker
    R = np.atleast_1d(np.asarray(radii, dtype=float))
    q3 = impact_angle_grid() if impact_angles is None else np.asarray(impact_angles, float)
    q3 = np.atleast_1d(q3)
    s = heel_strike_study(w.replace(foot_radius=R[:, None]), q3[None, :],
                          q3_dot=q3_dot, q4_dot=q4_dot)
    lifts = s.trailing_foot_lifts
    data = {
        "R_m": s.foot_radius,
        "q3_deg": np.rad2deg(s.impact_angle),
        "q3_rad": s.impact_angle,
        "T_J": s.kinetic_energy,
        "T_c_J": s.kinetic_energy_constrained,
        "T_a_J": s.kinetic_energy_admissible,
        "energy_lost_J": s.energy_lost,
        "step_length_m": s.step_length,
        "eta_J_per_m": s.eta,
        "q2_dot_plus_m_per_s": s.trailing_foot_velocity,
        "trailing_foot_lifts": lifts,
        "degenerate_wheel": s.degenerate_wheel,
        "shown": lifts | s.degenerate_wheel,
    }
    return pd.DataFrame({k: np.ravel(v) for k, v in data.items()})


def figure2_data(
    walker: CompassGait | None = None,
    radii: ArrayLike = FIGURE_RADII,
    impact_angles: ArrayLike | None = None,
) -> pd.DataFrame:
    """Data of Fig. 2: ``T_c`` and ``T_a`` (J) against ``q3`` for several ``R``.

    Admissible impacts only (plus the degenerate wheel ``R = l``, see the module docstring):
    the rows with ``shown``. Columns as :func:`heel_strike_table`.
    """
    table = heel_strike_table(walker, radii, impact_angles)
    return table[table["shown"]].reset_index(drop=True)


def figure3a_data(
    walker: CompassGait | None = None,
    radii: ArrayLike = FIGURE_RADII,
    impact_angles: ArrayLike | None = None,
) -> pd.DataFrame:
    """Data of Fig. 3a: ``eta`` (J/m, eq. 16) against ``q3`` for several ``R``.

    Admissible impacts only (plus the degenerate wheel). Columns as :func:`heel_strike_table`.
    """
    return figure2_data(walker, radii, impact_angles)


@dataclass(frozen=True, kw_only=True)
class Figure3bData(ResultDictMixin):
    """Data of Fig. 3b: ``eta`` over the (``q3``, ``R``) plane.

    Attributes
    ----------
    impact_angle : ndarray, shape (n_q3,)
        ``q3`` (rad), in ``(0, 45 deg]``.
    foot_radius : ndarray, shape (n_R,)
        ``R`` (m), in ``[0, l]``.
    eta : ndarray, shape (n_R, n_q3)
        Energy lost per metre (J/m), ``nan`` where not ``shown`` (white).
    eta_all : ndarray, shape (n_R, n_q3)
        ``eta`` everywhere (J/m).
    q2_dot_plus : ndarray, shape (n_R, n_q3)
        Post-impact ``q2_dot+`` (m/s); its zero level is the dashed boundary.
    trailing_foot_lifts : ndarray of bool, shape (n_R, n_q3)
        The impact is admissible: the trailing foot lifts (``q2_dot+ > 0``).
    shown : ndarray of bool, shape (n_R, n_q3)
        Drawn in the figure: admissible, or the degenerate wheel ``R = l``.
    degenerate_wheel : ndarray of bool, shape (n_R,)
        ``R = l``.
    """

    impact_angle: FloatArray
    foot_radius: FloatArray
    eta: FloatArray
    eta_all: FloatArray
    q2_dot_plus: FloatArray
    trailing_foot_lifts: BoolArray
    shown: BoolArray
    degenerate_wheel: BoolArray

    def to_frame(self) -> pd.DataFrame:
        """Long table, one row per grid point (``R`` major): ``R_m, q3_deg, q3_rad,
        eta_J_per_m, q2_dot_plus_m_per_s, trailing_foot_lifts, shown, degenerate_wheel``; ``eta`` is
        ``nan`` where not shown."""
        Rg, qg = np.meshgrid(self.foot_radius, self.impact_angle, indexing="ij")
        wheel = np.broadcast_to(self.degenerate_wheel[:, None], Rg.shape)
        return pd.DataFrame(
            {
                "R_m": Rg.ravel(),
                "q3_deg": np.rad2deg(qg).ravel(),
                "q3_rad": qg.ravel(),
                "eta_J_per_m": self.eta.ravel(),
                "q2_dot_plus_m_per_s": self.q2_dot_plus.ravel(),
                "trailing_foot_lifts": self.trailing_foot_lifts.ravel(),
                "shown": self.shown.ravel(),
                "degenerate_wheel": wheel.ravel(),
            }
        )


def figure3b_data(
    walker: CompassGait | None = None,
    radii: ArrayLike | None = None,
    impact_angles: ArrayLike | None = None,
) -> Figure3bData:
    """Data of Fig. 3b: ``eta`` (J/m) over a grid of ``q3`` (rad) and ``R`` (m).

    Parameters
    ----------
    walker : CompassGait, optional
        Scalar-parameter walker (paper defaults).
    radii : array_like, shape (n_R,), optional
        Default: 101 values evenly spaced in ``[0, l]``.
    impact_angles : array_like, shape (n_q3,), optional
        Default: :func:`impact_angle_grid`.
    """
    w = CompassGait() if walker is None else walker
    l = float(np.asarray(w.leg_length))
    R = np.linspace(0.0, l, 101) if radii is None else np.asarray(radii, dtype=float)
    q3 = impact_angle_grid() if impact_angles is None else np.asarray(impact_angles, float)
    s = heel_strike_study(w.replace(foot_radius=R[:, None]), q3[None, :])
    shown = np.asarray(s.trailing_foot_lifts | s.degenerate_wheel)
    return Figure3bData(
        impact_angle=q3,
        foot_radius=R,
        eta=np.where(shown, s.eta, np.nan),
        eta_all=np.asarray(s.eta),
        q2_dot_plus=s.trailing_foot_velocity,
        trailing_foot_lifts=np.asarray(s.trailing_foot_lifts),
        shown=shown,
        degenerate_wheel=np.asarray(s.degenerate_wheel)[:, 0],
    )


@dataclass(frozen=True, kw_only=True)
class PaperFigureData(ResultDictMixin):
    """The data of the paper's three figures (see the ``figure*_data`` functions)."""

    figure2: pd.DataFrame
    figure3a: pd.DataFrame
    figure3b: Figure3bData


def paper_figure_data(walker: CompassGait | None = None) -> PaperFigureData:
    """Compute the data of Figs. 2, 3a and 3b for ``walker`` (default: the paper's)."""
    table = figure2_data(walker)  # Figs. 2 and 3a plot columns of one table
    return PaperFigureData(figure2=table, figure3a=table.copy(), figure3b=figure3b_data(walker))
