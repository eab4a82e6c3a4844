"""Tables of a simulated walk: energy, heel strikes, one step's kinematics and ground reaction,
the phase portrait and a strobe of stick figures.

Each function turns a :class:`~heelstrike.dynamics.hybrid.WalkResult` into a
:class:`pandas.DataFrame` in SI units, one column per quantity with its unit in the name
(``t_s``, ``kinetic_J``, ``normal_N``). :mod:`heelstrike.plots.gait` draws these tables and
:mod:`heelstrike.outputs` writes them (through :func:`heelstrike.io.write_csv`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from heelstrike._frames import slope_to_world
from heelstrike.dynamics.hybrid import WalkResult, ground_reaction
from heelstrike.models.compass import CompassGait

__all__ = [
    "WalkResult",
    "model_phase_portrait_table",
    "phase_portrait_table",
    "step_table",
    "strobe_table",
    "walk_energy_table",
    "walk_impact_table",
]


def _check_walk(walk: WalkResult, step: int | None = None) -> None:
    """Raise :class:`ValueError` if ``walk`` has no samples (or none in step ``step``)."""
    if walk.t.size == 0:
        raise ValueError("the walk has no samples")
    if step is not None and not np.any(walk.step == step):
        raise ValueError(f"the walk has no samples in step {step} (steps 0..{walk.step.max()})")


def walk_energy_table(walker: CompassGait, walk: WalkResult) -> pd.DataFrame:
    """Kinetic, potential and total mechanical energy at every sample of a walk.

    Parameters
    ----------
    walker : CompassGait
        The walker the walk was simulated with.
    walk : WalkResult
        A passive walk (:func:`heelstrike.dynamics.simulate`).

    Returns
    -------
    pandas.DataFrame
        One row per sample, columns ``t_s`` (s), ``step``, ``kinetic_J``, ``potential_J``,
        ``total_J`` (J). The potential energy is the walker's
        :meth:`~heelstrike.models.CompassGait.potential_energy` on the walk's slope. At a heel
        strike two rows share the impact time: the last sample of a step (just before the
        impact) and the first of the next (just after it, legs relabelled).
    """
    _check_walk(walk)
    T = np.asarray(walker.kinetic_energy(walk.q, walk.q_dot), dtype=float)
    U = np.asarray(walker.potential_energy(walk.q, walk.slope), dtype=float)
    return pd.DataFrame(
        {"t_s": walk.t, "step": walk.step, "kinetic_J": T, "potential_J": U, "total_J": T + U}
    )


def walk_impact_table(walker: CompassGait, walk: WalkResult) -> pd.DataFrame:
    """Mechanical energy just before and just after every heel strike of a walk.

    Returns
    -------
    pandas.DataFrame
        One row per impact: ``step`` (the step it ends), ``time_s`` (s), ``impact_angle_rad``,
        ``total_before_J`` and ``total_after_J`` (J, from the walk's samples on either side of
        the impact; after the last impact from the walk's final state), ``drop_J`` (their
        difference) and ``T_c_J``, the constrained kinetic energy of the impact (paper eq. 10),
        which an inert impact destroys: ``drop_J`` equals it.
    """
    _check_walk(walk)
    E = np.asarray(
        walker.kinetic_energy(walk.q, walk.q_dot) + walker.potential_energy(walk.q, walk.slope),
        dtype=float,
    )
    rows = []
    for r in walk.impacts:
        before = E[np.nonzero(walk.step == r.step)[0][-1]]
        nxt = np.nonzero(walk.step == r.step + 1)[0]
        if nxt.size:
            after = float(E[nxt[0]])
        else:
            after = float(
                walker.kinetic_energy(walk.final_q, walk.final_q_dot)
                + walker.potential_energy(walk.final_q, walk.slope)
            )
        rows.append(
            {
                "step": r.step,
                "time_s": r.time,
                "impact_angle_rad": r.impact_angle,
                "total_before_J": float(before),
                "total_after_J": after,
                "drop_J": float(before) - after,
                "T_c_J": r.kinetic_energy_constrained,
            }
        )
    cols = ["step", "time_s", "impact_angle_rad", "total_before_J", "total_after_J", "drop_J",
            "T_c_J"]
    return pd.DataFrame(rows, columns=cols)


def step_table(walker: CompassGait, walk: WalkResult, step: int = 0) -> pd.DataFrame:
    """Joint angles, rates and the stance foot's ground reaction over one step of a walk.

    Parameters
    ----------
    walker : CompassGait
    walk : WalkResult
        A passive walk.
    step : int
        Which step (0-based).

    Returns
    -------
    pandas.DataFrame
        One row per sample of the step: ``t_s`` (time since the step began, s), ``q3_rad``
        (stance leg from the vertical), ``q4_rad`` (hip angle, swing relative to stance),
        ``swing_rad`` (swing leg from the vertical, ``q3 + q4``), ``q3_dot_rad_s``,
        ``q4_dot_rad_s`` (rad/s), ``tangential_N`` and ``normal_N`` (force of the ground on the
        stance foot along and normal to the slope, N) and ``required_friction`` (``|tangential|
        / normal``, the smallest Coulomb coefficient that prevents slipping) from
        :func:`heelstrike.dynamics.hybrid.ground_reaction`.
    """
    _check_walk(walk, step)
    sel = walk.step == step
    gr = ground_reaction(walker, walk)
    q, qd = walk.q[sel], walk.q_dot[sel]
    t = walk.t[sel]
    return pd.DataFrame(
        {
            "t_s": t - t[0],
            "q3_rad": q[:, 2],
            "q4_rad": q[:, 3],
            "swing_rad": q[:, 2] + q[:, 3],
            "q3_dot_rad_s": qd[:, 2],
            "q4_dot_rad_s": qd[:, 3],
            "tangential_N": gr.tangential[sel],
            "normal_N": gr.normal[sel],
            "required_friction": gr.required_friction[sel],
        }
    )


def phase_portrait_table(walk: WalkResult) -> pd.DataFrame:
    """Leg angles and angular rates at every sample of a walk (the phase portrait's data).

    Returns
    -------
    pandas.DataFrame
        Columns ``t_s`` (s), ``step``, ``q3_rad``, ``q3_dot_rad_s`` (stance leg) and
        ``swing_rad``, ``swing_dot_rad_s`` (swing leg's absolute angle ``q3 + q4`` and its rate).
    """
    _check_walk(walk)
    q, qd = walk.q, walk.q_dot
    return pd.DataFrame(
        {
            "t_s": walk.t,
            "step": walk.step,
            "q3_rad": q[:, 2],
            "q3_dot_rad_s": qd[:, 2],
            "swing_rad": q[:, 2] + q[:, 3],
            "swing_dot_rad_s": qd[:, 2] + qd[:, 3],
        }
    )


def strobe_table(
    walker: CompassGait, walk: WalkResult, step: int = 0, frames: int = 7
) -> pd.DataFrame:
    """Positions of the walker at ``frames`` evenly spaced instants of one step.

    Returns
    -------
    pandas.DataFrame
        One row per frame, world frame (x along the horizontal, y up; m): ``t_s`` (time since
        the step began, s), ``hip_x_m``, ``hip_y_m``, ``stance_foot_x_m``, ``stance_foot_y_m``,
        ``swing_foot_x_m``, ``swing_foot_y_m`` (centres of the foot arcs), ``stance_rad`` and
        ``swing_rad`` (leg angles from the slope's normal) and ``stance_leg`` (which physical
        leg stands: 0 or 1). The last frame is the instant of heel strike.
    """
    if frames < 2:
        raise ValueError(f"frames must be >= 2, got {frames}")
    _check_walk(walk, step)
    ids = np.nonzero(walk.step == step)[0]
    t = walk.t[ids]
    want = np.linspace(t[0], t[-1], frames)
    pick = ids[np.clip(np.searchsorted(t, want), 0, ids.size - 1)]
    q = walk.q[pick]
    pos = walker.positions(q)
    hip = slope_to_world(pos.hip, walk.slope)
    st = slope_to_world(pos.right_foot_centre, walk.slope)
    sw = slope_to_world(pos.left_foot_centre, walk.slope)
    return pd.DataFrame(
        {
            "t_s": walk.t[pick] - t[0],
            "hip_x_m": hip[:, 0], "hip_y_m": hip[:, 1],
            "stance_foot_x_m": st[:, 0], "stance_foot_y_m": st[:, 1],
            "swing_foot_x_m": sw[:, 0], "swing_foot_y_m": sw[:, 1],
            "stance_rad": q[:, 2], "swing_rad": q[:, 2] + q[:, 3],
            "stance_leg": walk.stance_leg[pick],
        }
    )


def model_phase_portrait_table(walker: Any, walk: WalkResult) -> pd.DataFrame:
    """:func:`phase_portrait_table` of a described walker's walk.

    ``q3_rad``, ``q3_dot_rad_s``: the stance (root) link's angle ``q[2]`` and rate;
    ``swing_rad``, ``swing_dot_rad_s``: the absolute angle and rate of the link hanging from the
    hip joint (the swing thigh or leg). Angles are linear in ``q``, so rates are the same map of
    ``q_dot``.

    Parameters
    ----------
    walker : BuiltWalker
        With a joint named ``hip``.
    walk : WalkResult
        Its walk (``simulate_phased`` or ``simulate_phased_compiled``).
    """
    _check_walk(walk)
    swing = walker.description.links[walker.joint_index("hip") - 2].name
    return pd.DataFrame(
        {
            "t_s": walk.t,
            "step": walk.step,
            "q3_rad": walk.q[:, 2],
            "q3_dot_rad_s": walk.q_dot[:, 2],
            "swing_rad": walker.link_angles(walk.q)[swing],
            "swing_dot_rad_s": walker.link_angles(walk.q_dot)[swing],
        }
    )
