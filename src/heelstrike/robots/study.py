"""The paper's Figs. 2-3 for a robot: ``T_c``, ``T_a`` and loss per metre over step length and
strike speed, from gait-like pre-impact states, batched over configurations.

For every step length ``L`` the feet are placed by :func:`heelstrike.robots.states.
gait_configuration`; for every strike speed the pre-impact velocity is
:func:`heelstrike.robots.states.gait_velocity` (trailing sole at rest, leading sole descending,
base moving forward). The leading foot strikes with the paper's inert law (all its rows, no slip,
no rebound) and the trailing foot is left free, as in the paper; the impact is *admissible* when
the trailing foot lifts (its sole's vertical velocity after impact is positive: the rule of
:func:`heelstrike.robots.contacts.ground_admissible`, which ``impact --robot`` applies to a kept
trailing foot). All impacts of the grid are resolved in one batched call of
:func:`heelstrike.core.impact.impact`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.impact import impact
from heelstrike.robots.contacts import (
    ContactSpec,
    ground_admissible,
    mass_matrices_and_jacobians,
)
from heelstrike.robots.loading import Robot, RobotError, real_array, real_number
from heelstrike.robots.states import Leading, gait_configuration, gait_velocity

__all__ = ["RobotStudy", "robot_heel_strike_study"]



@dataclass(frozen=True, kw_only=True)
class RobotStudy(ResultDictMixin):
    """Heel-strike energetics of a robot over step length x strike speed.

    Every array has shape ``(len(step_length), len(strike_speed))``.

    Attributes
    ----------
    robot : str
    contact : str
        Contact type of the striking foot.
    step_length : ndarray, shape (nL,)
        Distance between the soles along ``x`` (m).
    strike_speed : ndarray, shape (nS,)
        Downward speed of the leading sole before impact (m/s).
    T, T_c, T_a : ndarray
        Pre-impact kinetic energy and its constrained (lost) and admissible parts (J).
    T_c_normal, T_c_tangential : ndarray
        ``T_c`` split by the nested projection: normal rows first (J).
    loss_per_metre : ndarray
        ``T_c / L`` (J/m); ``nan`` for ``L = 0``.
    trailing_lift_speed : ndarray
        Vertical velocity of the trailing sole after impact (m/s).
    admissible : ndarray of bool
        ``trailing_lift_speed > 0`` (:func:`heelstrike.robots.contacts.ground_admissible`).
    """

    robot: str
    contact: str
    step_length: FloatArray
    strike_speed: FloatArray
    T: FloatArray
    T_c: FloatArray
    T_a: FloatArray
    T_c_normal: FloatArray
    T_c_tangential: FloatArray
    loss_per_metre: FloatArray
    trailing_lift_speed: FloatArray
    admissible: NDArray[np.bool_]


def robot_heel_strike_study(
    robot: Robot,
    step_lengths: ArrayLike,
    strike_speeds: ArrayLike,
    *,
    contact: str | None = None,
    forward_speed: float = 0.5,
    leading: Leading = "left",
) -> RobotStudy:
    """Batched heel-strike study (module doc).

    Parameters
    ----------
    robot : Robot
        A robot with feet frames (e.g. ``load_robot("talos")``).
    step_lengths : array_like, shape (nL,)
        Step lengths (m), >= 0.
    strike_speeds : array_like, shape (nS,)
        Downward speeds of the leading sole (m/s), > 0.
    contact : {"flat", "point"}, optional
        Striking contact type (default: the robot's natural foot contact).
    forward_speed : float
        Forward speed of the base (m/s).
    leading : {"left", "right"}
        Striking foot.
    """
    L = np.atleast_1d(real_array(step_lengths, "step lengths"))
    S = np.atleast_1d(real_array(strike_speeds, "strike speeds"))
    forward_speed = real_number(forward_speed, "forward_speed")
    if L.ndim != 1 or S.ndim != 1 or L.size == 0 or S.size == 0:
        raise RobotError("step lengths and strike speeds must be non-empty 1-D arrays, got "
                         f"shapes {L.shape} and {S.shape}")
    if not (np.all(np.isfinite(L) & (L >= 0)) and np.all(np.isfinite(S) & (S > 0))):
        raise RobotError("step lengths must be finite and >= 0 m, strike speeds finite and "
                         "> 0 m/s")
    kind = contact or robot.foot_contact
    lead, trail = robot.feet if leading == "left" else robot.feet[::-1]
    strike = ContactSpec(frame=lead, kind=kind)  # type: ignore[arg-type]
    trailing = ContactSpec(frame=trail, kind="point")
    qs = np.stack([gait_configuration(robot, float(x), leading=leading) for x in L])
    data = robot.model.createData()
    # v is linear in the strike speed: one least-energy solve per speed and step length.
    vs = np.stack([
        np.stack([gait_velocity(robot, q, strike_speed=float(s), forward_speed=forward_speed,
                                leading=leading, data=data) for s in S])
        for q in qs
    ])  # (nL, nS, nv)
    Ms, As = mass_matrices_and_jacobians(robot, qs, [strike, trailing])
    k = strike.rows
    A = As[:, None, :k, :]
    res = impact(Ms[:, None], A, vs)
    normal = impact(Ms[:, None], A[..., list(strike.normal), :], vs)
    lift = np.einsum("lj,lsj->ls", As[:, 2 + k, :], res.velocity_post)
    with np.errstate(divide="ignore", invalid="ignore"):
        per_m = np.where(L[:, None] > 0, res.kinetic_energy_constrained / L[:, None], np.nan)
    T_cn = np.asarray(normal.kinetic_energy_constrained)
    return RobotStudy(
        robot=robot.name,
        contact=kind,
        step_length=L,
        strike_speed=S,
        T=np.asarray(res.kinetic_energy),
        T_c=np.asarray(res.kinetic_energy_constrained),
        T_a=np.asarray(res.kinetic_energy_admissible),
        T_c_normal=T_cn,
        T_c_tangential=np.asarray(res.kinetic_energy_constrained) - T_cn,
        loss_per_metre=np.asarray(per_m),
        trailing_lift_speed=np.asarray(lift),
        admissible=ground_admissible(lift, kept=False),
    )
