"""Gait-like pre-impact states of a biped robot: stance sole at rest, swing sole descending.

The configuration places both feet flat on the ground (point feet: on the ground; world ``z``
up, ``x`` forward), the leading (swing) foot ``step_length`` ahead of the trailing (stance) one,
each at the lateral offset it has in the reference pose, with the base level and midway between
them; its height is left to the inverse kinematics (damped Gauss-Newton on the feet's and base's
placements, minimum-norm steps, so joints that move neither stay at the reference pose).

The velocity is the one of least kinetic energy (``min 1/2 v^T M v``) among those with the
trailing sole at rest (6 rows; 3 for point feet), the leading sole moving with
``(swing_forward_speed, 0, -strike_speed)`` and no rotation (6 rows; 3 for point feet), and the
base moving forward at ``forward_speed`` without sideways or angular velocity (5 rows).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.robots.loading import Robot, RobotError, _pin, real_number

__all__ = [
    "MAX_RATE_PER_SPEED",
    "JointLimitViolation",
    "gait_configuration",
    "gait_state",
    "gait_velocity",
    "joint_limit_violations",
]

Leading = Literal["left", "right"]


def _feet(robot: Robot, leading: Leading) -> tuple[str, str]:
    left, right = robot.feet
    if not left or not right:
        raise RobotError(f"robot {robot.name!r} has no feet frames for gait states")
    if leading not in ("left", "right"):
        raise RobotError(f"leading must be 'left' or 'right', got {leading!r}")
    return (left, right) if leading == "left" else (right, left)


def gait_configuration(
    robot: Robot,
    step_length: float,
    *,
    leading: Leading = "left",
    max_iterations: int = 200,
    tol: float = 1e-10,
) -> FloatArray:
    """Configuration (nq,) with both feet flat, the leading one ``step_length`` (m) ahead.

    The feet are on the ground plane ``z = 0`` (the base is placed above it), for every robot
    alike; the impact itself does not depend on that height (a translation of the whole robot
    leaves ``M`` and the contact Jacobians unchanged).

    Raises
    ------
    RobotError
        If the inverse kinematics does not converge (step too long for the legs).
    """
    pin = _pin()
    step_length = real_number(step_length, "step_length")
    tol = real_number(tol, "tol")
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, int | np.integer) \
            or max_iterations < 1:
        raise RobotError(f"max_iterations must be an int >= 1, got {max_iterations!r:.40}")
    if not (np.isfinite(step_length) and step_length >= 0.0):
        raise RobotError(f"step_length must be finite and >= 0 m, got {step_length!r}")
    lead, trail = _feet(robot, leading)
    _require_enough_joints(robot)
    model = robot.model
    data = model.createData()
    q = robot.reference_q.copy()
    pin.framesForwardKinematics(model, data, q)
    fl, ft = robot.frame_id(lead), robot.frame_id(trail)
    base0 = data.oMi[1].translation.copy()
    z0 = 0.5 * (data.oMf[fl].translation[2] + data.oMf[ft].translation[2])
    target_lead = pin.SE3(np.eye(3), np.array(
        [base0[0] + 0.5 * step_length, data.oMf[fl].translation[1], z0]))
    target_trail = pin.SE3(np.eye(3), np.array(
        [base0[0] - 0.5 * step_length, data.oMf[ft].translation[1], z0]))
    base_rows = [0, 1, 3, 4, 5]
    point_feet = robot.foot_contact == "point"
    for _ in range(max_iterations):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        errs, jacs = [], []
        for fid, target in ((fl, target_lead), (ft, target_trail)):
            if point_feet:
                errs.append(target.translation - data.oMf[fid].translation)
                jacs.append(np.array(pin.getFrameJacobian(
                    model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED))[:3])
                continue
            errs.append(np.array(pin.log6(data.oMf[fid].actInv(target)).vector))
            jacs.append(np.array(pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL)))
        oMb = data.oMi[1]
        target_b = pin.SE3(np.eye(3), np.array([base0[0], base0[1], oMb.translation[2]]))
        errs.append(np.array(pin.log6(oMb.actInv(target_b)).vector)[base_rows])
        jacs.append(np.array(
            pin.getJointJacobian(model, data, 1, pin.ReferenceFrame.LOCAL))[base_rows])
        err, J = np.concatenate(errs), np.vstack(jacs)
        if np.max(np.abs(err)) < tol:
            q = np.array(q, dtype=float)
            q[2] -= z0  # the feet at z = z0 -> on the ground plane z = 0
            return q
        dq = J.T @ np.linalg.solve(J @ J.T + 1e-10 * np.eye(J.shape[0]), err)
        q = pin.integrate(model, q, dq)
    raise RobotError(
        f"no feet placement for step length {step_length:g} m on robot {robot.name!r}"
    )


def gait_velocity(
    robot: Robot,
    q: FloatArray,
    *,
    strike_speed: float,
    forward_speed: float = 0.5,
    swing_forward_speed: float = 0.0,
    leading: Leading = "left",
    data: Any = None,
) -> FloatArray:
    """Least-kinetic-energy pre-impact velocity (nv,) of a gait-like state (module doc).

    Parameters
    ----------
    strike_speed : float
        Downward speed of the leading sole (m/s), > 0 for an impact (a negative one makes a
        rising sole, a state with no impact, which ``heelstrike robot state`` refuses).
    forward_speed : float
        Forward speed of the base (m/s).
    swing_forward_speed : float
        Forward speed of the leading sole (m/s).

    Raises
    ------
    RobotError
        If a speed is not finite, or the robot cannot meet the constraints: fewer degrees of
        freedom than rows (flat feet: 17, point feet: 11), rows that are not independent at
        ``q``, or a velocity that misses them beyond round-off or has an entry beyond
        :data:`MAX_RATE_PER_SPEED` times the largest speed (a state is never returned
        unchecked).
    """
    pin = _pin()
    speeds = {"strike_speed": real_number(strike_speed, "strike_speed"),
              "forward_speed": real_number(forward_speed, "forward_speed"),
              "swing_forward_speed": real_number(swing_forward_speed, "swing_forward_speed")}
    for what, value in speeds.items():
        if not math.isfinite(value):
            raise RobotError(f"{what} must be finite, got {value!r} m/s")
    lead, trail = _feet(robot, leading)
    model = robot.model
    data = model.createData() if data is None else data
    q_, _ = robot.check_state(q)
    M = robot.mass_matrix(q_, data)
    pin.computeJointJacobians(model, data, q_)
    pin.updateFramePlacements(model, data)
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    J_trail = np.array(pin.getFrameJacobian(model, data, robot.frame_id(trail), lwa))
    J_lead = np.array(pin.getFrameJacobian(model, data, robot.frame_id(lead), lwa))
    J_base = np.array(pin.getJointJacobian(model, data, 1, lwa))[[0, 1, 3, 4, 5]]
    k = _require_enough_joints(robot)
    C = np.vstack((J_trail[:k], J_lead[:k], J_base))
    d = np.zeros(C.shape[0])
    d[k], d[k + 2] = speeds["swing_forward_speed"], -speeds["strike_speed"]
    d[2 * k] = speeds["forward_speed"]
    with np.errstate(all="ignore"):  # a singular system is refused below, by its rank
        X = np.linalg.solve(M, C.T)
        S = C @ X
        eig = np.linalg.eigvalsh(0.5 * (S + S.T)) if np.isfinite(S).all() else np.zeros(1)
        if not eig[0] > _RANK_TOLERANCE * eig[-1]:
            raise RobotError(
                f"robot {robot.name!r} cannot meet the feet constraints of a gait state at "
                f"this pose: its {C.shape[0]} rows ({k} per sole, 5 for the base) are not "
                "independent (straight or folded legs: a singular pose)")
        v = np.asarray(X @ np.linalg.solve(S, d))
    _require_state(robot, q_, v, C, d, speeds)
    return v


#: Gait states whose feet constraints are worse conditioned than this are refused.
_RANK_TOLERANCE = 1e-12

#: Every entry of a gait state's velocity (rad/s for a joint, m/s for the base's linear
#: velocity) is at most this times the largest speed asked (m/s): the rate of a lever of
#: 1 cm. Typical shipped bipeds need 7 to 10 times the speed.
MAX_RATE_PER_SPEED = 100.0


def _point_hint(robot: Robot) -> str:
    return (": point feet (foot_contact 'point', 3 rows per sole) need fewer"
            if robot.foot_contact == "flat" else "")


def _require_enough_joints(robot: Robot) -> int:
    """Rows per sole (6 flat, 3 point), refusing a robot with fewer degrees of freedom than
    the gait state's constraints."""
    k = 3 if robot.foot_contact == "point" else 6  # point feet: no sole orientation
    rows = 2 * k + 5
    if robot.nv < rows:
        raise RobotError(
            f"robot {robot.name!r} cannot meet the feet constraints of a gait state: "
            f"{robot.foot_contact} feet need {rows} independent velocity rows ({k} per sole, 5 "
            f"for the base), the robot has nv = {robot.nv} degrees of freedom"
            f"{_point_hint(robot)}")
    return k


def _require_state(robot: Robot, q: FloatArray, v: FloatArray, C: FloatArray, d: FloatArray,
                   speeds: dict[str, float]) -> None:
    """Refuse a gait velocity that is not finite, misses its constraints ``C v = d`` beyond
    round-off, or has an entry beyond :data:`MAX_RATE_PER_SPEED` times the largest speed."""
    bound = MAX_RATE_PER_SPEED * max(abs(x) for x in speeds.values())
    with np.errstate(all="ignore"):
        residual = float(np.max(np.abs(C @ v - d))) if np.isfinite(v).all() else math.inf
    if not residual <= 1e-8 * max(float(np.max(np.abs(d))), 1e-300):
        raise RobotError(f"robot {robot.name!r}: the gait state misses its feet constraints "
                         f"by {residual:.3g} m/s (the legs are singular at this pose)")
    i = int(np.argmax(np.abs(v)))
    if abs(float(v[i])) > bound:
        raise RobotError(
            f"robot {robot.name!r}: the gait state needs v[{i}] = {float(v[i]):.3g} (rad/s or "
            f"m/s), beyond the {bound:.3g} allowed ({MAX_RATE_PER_SPEED:g} times the largest "
            "speed asked, a 1 cm lever): the legs are near a singular pose")
    robot.check_state(q, v)


def gait_state(
    robot: Robot,
    step_length: float,
    strike_speed: float,
    *,
    forward_speed: float = 0.5,
    swing_forward_speed: float = 0.0,
    leading: Leading = "left",
) -> tuple[FloatArray, FloatArray]:
    """Pre-impact ``(q, v-)``: :func:`gait_configuration` and :func:`gait_velocity`."""
    q = gait_configuration(robot, step_length, leading=leading)
    v = gait_velocity(robot, q, strike_speed=strike_speed, forward_speed=forward_speed,
                      swing_forward_speed=swing_forward_speed, leading=leading)
    return q, v


@dataclass(frozen=True, kw_only=True)
class JointLimitViolation(ResultDictMixin):
    """A joint of a configuration outside the model's position limits.

    Attributes
    ----------
    joint : str
        Joint name in the model.
    position : float
        Its coordinate in the configuration (rad, or m for a prismatic joint).
    lower, upper : float
        The model's position limits (same unit).
    unit : {"rad", "m"}
        Unit of ``position``, ``lower`` and ``upper``.
    """

    joint: str
    position: float
    lower: float
    upper: float
    unit: str


#: Limits beyond this magnitude mean "unbounded" (URDF files without limits get huge ones).
_UNBOUNDED = 1e10


def joint_limit_violations(
    robot: Robot, q: ArrayLike, *, tol: float = 1e-9
) -> list[JointLimitViolation]:
    """Joints of ``q`` outside the model's ``lowerPositionLimit``/``upperPositionLimit``.

    Only one-coordinate joints are checked (revolute in rad, prismatic in m); the free flyer,
    continuous (unbounded) revolute joints, spherical joints and joints with infinite, huge
    (``> 1e10``) or empty limits are skipped.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (nq,)
        Configuration (Pinocchio conventions).
    tol : float
        Tolerance (rad or m) beyond the limits before a joint counts as outside them.

    Returns
    -------
    list of JointLimitViolation
        In joint order; empty when the configuration is within the limits.
    """
    tol = real_number(tol, "tol")
    q_, _ = robot.check_state(q)
    model = robot.model
    lo_all, hi_all = np.asarray(model.lowerPositionLimit), np.asarray(model.upperPositionLimit)
    out: list[JointLimitViolation] = []
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        if int(joint.nq) != 1 or int(joint.nv) != 1:
            continue
        i = int(joint.idx_q)
        lo, hi = float(lo_all[i]), float(hi_all[i])
        if not (abs(lo) < _UNBOUNDED and abs(hi) < _UNBOUNDED and lo < hi):
            continue
        x = float(q_[i])
        if lo - tol <= x <= hi + tol:
            continue
        kind = joint.shortname()
        prismatic = kind.startswith("JointModelP") and kind != "JointModelPlanar"
        out.append(JointLimitViolation(joint=str(model.names[jid]), position=x, lower=lo,
                                       upper=hi, unit="m" if prismatic else "rad"))
    return out
