"""The heel-strike study of Font & Kövecses (2008), section "Results and Discussion".

The right foot is on the ground and rolling (``q2 = R``), the legs are symmetric
(``q4 = -2 q3``) and the left foot strikes the ground. The pre-impact velocities are prescribed
(the paper: ``q3_dot = 1 rad/s``, ``q4_dot = 0``). The impact is resolved by the impact algebra
of :mod:`heelstrike.core.impact` with ``A = A_L`` (eq. 5) evaluated at the pre-impact state; the
energy lost per metre walked is ``eta = |W_col| / L_S`` (eq. 16) with the step length
``L_S = 2 (l - R) sin q3 + 2 R q3``.

Every function broadcasts: the impact angle and any walker parameter may be arrays, e.g.
``heel_strike_study(CompassGait(foot_radius=R[None, :]), q3[:, None])`` gives results of shape
``(len(q3), len(R))``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import BoolArray, FloatArray
from heelstrike.core._scalars import python_scalars
from heelstrike.core.impact import ImpactInputError, ImpactResult, impact
from heelstrike.models._contact import CONTACT_TOLERANCE, LIFT_TOLERANCE, trailing_foot_lifts
from heelstrike.models.base import Foot, PlanarWalker, check_backend_name, is_mcgeer_wheel
from heelstrike.models.compass import CompassGait, heel_strike_state

__all__ = [
    "CONTACT_TOLERANCE",
    "LIFT_TOLERANCE",
    "HeelStrikeStudy",
    "NotAHeelStrikeError",
    "check_heel_strike_state",
    "check_stance_foot_rolls",
    "check_striking_foot_approaches",
    "heel_strike_study",
    "loss_per_metre",
    "step_length",
    "symmetric_step_length",
    "trailing_foot_lifts",
]

class NotAHeelStrikeError(ValueError):
    """A configuration given as a heel strike does not have both feet on the ground."""


def check_striking_foot_approaches(
    walker: PlanarWalker, q: ArrayLike, q_dot: ArrayLike, *, foot: Foot = "left"
) -> None:
    """Check that the striking foot moves towards the ground before the impact.

    A foot leaving the ground does not strike it: the bilateral impact law (eqs. 2-13) would
    pull it down with a negative normal impulse and report an energy loss that never happens.

    Parameters
    ----------
    walker : PlanarWalker
        Scalar-parameter walker.
    q, q_dot : array_like, shape (n,)
        Pre-impact configuration (m, rad) and velocities (m/s, rad/s).
    foot : {"left", "right"}
        The striking foot.

    Raises
    ------
    NotAHeelStrikeError
        If the foot's pre-impact normal velocity is positive (away from the ground), or the
        walker is at rest (nothing strikes). (At McGeer's wheel, ``R = l``, the striking
        point's normal velocity is zero while the walker rolls: a valid, lossless impact.)
    """
    vn = float((walker.contact_jacobian(np.asarray(q, dtype=float), foot)
                @ np.asarray(q_dot, dtype=float))[1])
    if vn > 1e-12 * max(1.0, float(walker.scale.leg_length)):
        raise NotAHeelStrikeError(
            f"the striking foot moves away from the ground before the impact (normal velocity "
            f"+{vn:.6g} m/s): no heel strike happens with these pre-impact rates (the paper's "
            "rates q3_dot = 1 rad/s, q4_dot = 0 bring it down)")
    if not np.any(np.asarray(q_dot, dtype=float)):  # at rest: nothing strikes
        raise NotAHeelStrikeError(
            "the striking foot does not move towards the ground before the impact (every "
            "pre-impact rate is 0): no heel strike happens (the paper's rates q3_dot = 1 rad/s, "
            "q4_dot = 0 bring it down)")


def check_stance_foot_rolls(walker: PlanarWalker, q: ArrayLike, q_dot: ArrayLike) -> None:
    """Check that the stance foot's contact point is at rest before the impact.

    In single support the stance foot rolls without slipping (for a foot of radius ``R``,
    ``x_dot = -R`` times the stance leg's rate): pre-impact velocities where it slides or
    moves into the ground describe no walker's heel strike, and the decomposition would
    count their energy as lost.

    Parameters
    ----------
    walker : PlanarWalker
        Scalar-parameter walker.
    q, q_dot : array_like, shape (n,)
        Pre-impact configuration (m, rad) and velocities (m/s, rad/s).

    Raises
    ------
    NotAHeelStrikeError
        If the contact point's velocity exceeds round-off relative to ``l sum |q_dot|``.
    """
    qd = np.asarray(q_dot, dtype=float)
    v = walker.contact_jacobian(np.asarray(q, dtype=float), "right") @ qd
    scale = float(walker.scale.leg_length) * float(np.sum(np.abs(qd)))
    if float(np.max(np.abs(v))) > 1e-9 * max(scale, 1e-300):
        raise NotAHeelStrikeError(
            f"the stance foot's contact point moves before the impact (along the ground "
            f"{float(v[0]):+.6g} m/s, normal {float(v[1]):+.6g} m/s): in single support it "
            "rolls without slipping, x_dot = -R times the stance leg's rate (R its foot "
            "radius) and y_dot = 0")


def check_heel_strike_state(
    walker: PlanarWalker, q: ArrayLike, *, rtol: float = CONTACT_TOLERANCE
) -> None:
    """Check that ``q`` is a heel-strike configuration: both feet touch the ground.

    Parameters
    ----------
    walker : PlanarWalker
        Scalar-parameter walker.
    q : array_like, shape (n,)
        Pre-impact configuration (m, rad).
    rtol : float
        Accepted ``|clearance|`` of each foot relative to the leg length
        (:attr:`~heelstrike.models.base.PlanarWalker.scale`).

    Raises
    ------
    NotAHeelStrikeError
        If a foot is above (or below) the ground by more than ``rtol * l``; the message gives
        both clearances (m).
    """
    q_ = np.asarray(q, dtype=float)
    if not np.all(np.isfinite(q_)):
        raise NotAHeelStrikeError("the configuration must be finite")
    tol = rtol * float(walker.scale.leg_length)
    stance = float(walker.foot_clearance(q_, "right"))
    swing = float(walker.foot_clearance(q_, "left"))
    if abs(stance) > tol or abs(swing) > tol:
        raise NotAHeelStrikeError(
            f"not a heel strike: the stance foot is {stance:.6g} m and the swing foot "
            f"{swing:.6g} m above the ground; both must touch it (|clearance| <= {tol:.3g} m)"
        )


def symmetric_step_length(
    impact_angle: ArrayLike, leg_length: ArrayLike, foot_radius: ArrayLike
) -> FloatArray:
    """Step length ``L_S = 2 (l - R) sin q3 + 2 R q3`` (m) of a symmetric heel strike, the
    denominator of eq. (16): the one definition (:func:`step_length` of a compass gait, the
    powered search's targets and its geometric limit at ``q3 = pi/2``).

    The distance between the two contact points at heel strike (``2 (l - R) sin q3``) plus the
    arc ``2 R q3`` rolled by the stance foot while its leg turns from ``-q3`` to ``q3``.

    Parameters
    ----------
    impact_angle : array_like
        ``q3`` at impact (rad).
    leg_length, foot_radius : array_like
        ``l`` and ``R`` (m).

    Returns
    -------
    ndarray, shape broadcast of the inputs
        ``L_S`` (m).
    """
    q3 = np.asarray(impact_angle, dtype=float)
    l = np.asarray(leg_length, dtype=float)
    R = np.asarray(foot_radius, dtype=float)
    return np.asarray(2.0 * (l - R) * np.sin(q3) + 2.0 * R * q3)


def loss_per_metre(energy_lost: ArrayLike, step_length: ArrayLike) -> FloatArray:
    """Energy lost per metre walked, ``eta = W / L_S`` (J/m), paper eq. (16): the one
    definition (the heel-strike study, passive and powered gaits, described walkers).

    Parameters
    ----------
    energy_lost : array_like
        Energy lost per step (J), e.g. ``T_c``.
    step_length : array_like
        Step length ``L_S`` (m).

    Returns
    -------
    ndarray, shape broadcast of the inputs
        ``energy_lost / step_length``; NaN where ``step_length <= 0`` (no step: no distance to
        spread the loss over).
    """
    W, L = np.broadcast_arrays(np.asarray(energy_lost, dtype=float),
                               np.asarray(step_length, dtype=float))
    eta = np.full(W.shape, np.nan)
    np.divide(W, L, out=eta, where=L > 0)
    return eta


def step_length(walker: CompassGait, impact_angle: ArrayLike) -> FloatArray:
    """Step length ``L_S`` (m) of the compass gait (:func:`symmetric_step_length`).

    Parameters
    ----------
    walker : CompassGait
        Supplies ``l`` and ``R`` (m); may hold arrays.
    impact_angle : array_like
        ``q3`` at impact (rad).

    Returns
    -------
    ndarray, shape broadcast of ``impact_angle`` and the walker's parameters
        ``L_S`` (m).
    """
    return symmetric_step_length(impact_angle, walker.leg_length, walker.foot_radius)


@dataclass(frozen=True, kw_only=True)
class HeelStrikeStudy(ResultDictMixin):
    """Energy decomposition of one (batched) heel strike of the circular-feet compass gait.

    All arrays share the broadcast shape ``(...)`` of the impact angle and the walker's
    parameters, with a trailing axis where stated.

    Attributes
    ----------
    impact_angle : ndarray, shape (...)
        ``q3`` at impact (rad).
    foot_radius : ndarray, shape (...)
        ``R`` (m).
    leg_length : ndarray, shape (...)
        ``l`` (m).
    restitution : float
        Coefficient ``e`` of the constrained velocity (0 in the paper).
    state : ndarray, shape (..., 4)
        Pre-impact configuration ``q`` (m, m, rad, rad), ``q4 = -2 q3``.
    velocity_pre : ndarray, shape (..., 4)
        ``q_dot-`` (m/s, m/s, rad/s, rad/s).
    velocity_post : ndarray, shape (..., 4)
        ``q_dot+``; ``P_a q_dot-`` for ``e = 0`` (eq. 13).
    constraint_impulse : ndarray, shape (..., 2)
        ``lambda`` (N s): tangential (x) and normal (y) ground impulse on the striking foot.
    kinetic_energy : ndarray, shape (...)
        Pre-impact kinetic energy ``T`` (J), eq. (1).
    kinetic_energy_constrained : ndarray, shape (...)
        ``T_c`` (J), eq. (10): the part lost in an inert impact.
    kinetic_energy_admissible : ndarray, shape (...)
        ``T_a`` (J), eq. (10): the part kept.
    kinetic_energy_post : ndarray, shape (...)
        ``T+`` (J).
    energy_lost : ndarray, shape (...)
        ``|W_col| = T- - T+ = (1 - e^2) T_c`` (J), eq. (15).
    step_length : ndarray, shape (...)
        ``L_S = 2 (l - R) sin q3 + 2 R q3`` (m).
    eta : ndarray, shape (...)
        Energy lost per metre walked, ``|W_col| / L_S`` (J/m), eq. (16); ``nan`` where
        ``L_S = 0`` (``q3 = 0``).
    trailing_foot_lifts : ndarray of bool, shape (...)
        ``q2_dot+ > LIFT_TOLERANCE * l (|q3_dot-| + |q4_dot-|)``: the impact is admissible
        (the trailing, right foot leaves the ground). False at ``R = l``, where ``q2_dot+ = 0``.
    degenerate_wheel : ndarray of bool, shape (...)
        ``R = l`` (McGeer's synthetic wheel): both feet are arcs of one circle about the hip,
        nothing is lost (``T_c = 0``) and the trailing foot neither lifts nor presses.
        For one heel strike (shape ``()``) the fields of shape ``(...)`` are Python ``float``
        and ``bool``.
    impact : ImpactResult or None
        The full result of :func:`heelstrike.core.impact.impact` (projectors, impulses); None
        on the compiled backend, which forms no projectors.
    """

    impact_angle: FloatArray | float
    foot_radius: FloatArray | float
    leg_length: FloatArray | float
    restitution: float
    state: FloatArray
    velocity_pre: FloatArray
    velocity_post: FloatArray
    constraint_impulse: FloatArray
    kinetic_energy: FloatArray | float
    kinetic_energy_constrained: FloatArray | float
    kinetic_energy_admissible: FloatArray | float
    kinetic_energy_post: FloatArray | float
    energy_lost: FloatArray | float
    step_length: FloatArray | float
    eta: FloatArray | float
    trailing_foot_lifts: BoolArray | bool
    degenerate_wheel: BoolArray | bool
    impact: ImpactResult | None

    def __post_init__(self) -> None:
        # One heel strike (shape ()): the fields of shape (...) are Python floats and bools.
        python_scalars(self, (
            "impact_angle", "foot_radius", "leg_length", "kinetic_energy",
            "kinetic_energy_constrained", "kinetic_energy_admissible", "kinetic_energy_post",
            "energy_lost", "step_length", "eta", "trailing_foot_lifts", "degenerate_wheel",
        ))

    @property
    def trailing_foot_velocity(self) -> FloatArray:
        """``q2_dot+`` (m/s), vertical post-impact velocity of the trailing foot's centre."""
        return np.asarray(self.velocity_post[..., 1])


def heel_strike_study(
    walker: CompassGait,
    impact_angle: ArrayLike,
    *,
    q3_dot: ArrayLike = 1.0,
    q4_dot: ArrayLike = 0.0,
    restitution: float = 0.0,
    backend: Literal["scipy", "compiled"] = "scipy",
) -> HeelStrikeStudy:
    """Decompose the kinetic energy at heel strike and the loss per metre (paper eqs. 5-16).

    Parameters
    ----------
    walker : CompassGait
        The walker; any parameter may be an array broadcasting with ``impact_angle``.
    impact_angle : array_like
        ``q3`` at impact (rad), ``q4 = -2 q3``.
    q3_dot, q4_dot : array_like
        Pre-impact angular velocities (rad/s); the paper prescribes 1 and 0. The stance foot
        rolls: ``q1_dot = -R q3_dot``, ``q2_dot = 0``.
    restitution : float
        ``e`` in [0, 1] applied to the constrained velocity; 0 is the paper's inert impact.
    backend : {"scipy", "compiled"}
        ``"scipy"``: the reference projectors (:func:`heelstrike.core.impact.impact`, numpy and
        scipy). ``"compiled"``: the numba compass kernel
        (:func:`heelstrike.models.compass_fast.heel_strike_impact`, batched; no projectors,
        ``impact`` is None); the same numbers to round-off.

    Returns
    -------
    HeelStrikeStudy
        Broadcast over all inputs.

    Raises
    ------
    heelstrike.core.impact.ImpactInputError
        For non-finite angles or velocities, an angle outside ``0 <= q3 < pi/2`` (the leading
        foot ahead), or ``restitution`` outside [0, 1].
    NotAHeelStrikeError
        Where the striking foot moves away from the ground before the impact (e.g.
        ``q3_dot < 0``): no heel strike happens there, and the impact law would report a loss
        that never happens (QA sweep 12: it did, without a word).
    """
    check_backend_name(backend)
    for name, value, unit in (("impact_angle", impact_angle, "rad"),
                              ("q3_dot", q3_dot, "rad/s"), ("q4_dot", q4_dot, "rad/s")):
        if not np.all(np.isfinite(np.asarray(value, dtype=float))):
            raise ImpactInputError(f"{name} must be finite ({unit}), got {value!r}")
    q3 = np.asarray(impact_angle, dtype=float)
    if np.any((q3 < 0.0) | (q3 >= np.pi / 2)):
        bad = float(q3.ravel()[np.argmax(((q3 < 0.0) | (q3 >= np.pi / 2)).ravel())])
        raise ImpactInputError(
            f"impact_angle must satisfy 0 <= q3 < pi/2 rad (the leading foot ahead, the hip "
            f"above the ground), got {bad:g} rad ({np.degrees(bad):g} deg)")
    q, q_dot = heel_strike_state(walker, impact_angle, q3_dot=q3_dot, q4_dot=q4_dot)
    A = walker.contact_jacobian(q, "left")  # the striking foot's rows (x, y)
    vn = np.einsum("...j,...j->...", A[..., 1, :], q_dot)
    away = vn > 1e-12 * np.maximum(1.0, np.asarray(walker.leg_length, dtype=float))
    if np.any(away):
        i = np.unravel_index(int(np.argmax(away)), away.shape) if away.ndim else ()
        raise NotAHeelStrikeError(
            f"the striking foot moves away from the ground before the impact at "
            f"{int(np.sum(away))} of {away.size} state(s) (e.g. q3 = {float(q[i][2]):g} rad, "
            f"q3_dot = {float(q_dot[i][2]):g}, q4_dot = {float(q_dot[i][3]):g} rad/s: normal "
            f"velocity +{float(vn[i]):.6g} m/s): no heel strike happens there (the paper's "
            "rates q3_dot = 1 rad/s, q4_dot = 0 bring it down)")
    res: ImpactResult | None = None
    if backend == "compiled":
        from heelstrike.models.compass_fast import heel_strike_impact

        fast = heel_strike_impact(impact_angle, walker=walker, q3_dot=q3_dot, q4_dot=q4_dot,
                                  restitution=restitution)
        T, T_c, T_a = (np.asarray(x, dtype=float) for x in (
            fast.kinetic_energy, fast.kinetic_energy_constrained, fast.kinetic_energy_admissible))
        v_post, impulse = fast.velocity_post, fast.constraint_impulse
        lost = np.asarray(fast.energy_lost)
        v_pre = np.broadcast_to(np.asarray(q_dot, dtype=float), (*np.shape(T), 4))
        # v+ = v_a - e v_c with v_a, v_c M-orthogonal: T+ = T_a + e^2 T_c
        post = T_a + float(restitution) ** 2 * T_c
    else:
        res = impact(walker.mass_matrix(q), A, q_dot, restitution=restitution)
        T, T_c, T_a = (np.asarray(x, dtype=float) for x in (
            res.kinetic_energy, res.kinetic_energy_constrained, res.kinetic_energy_admissible))
        v_post, impulse = res.velocity_post, res.constraint_impulse
        lost, post = np.asarray(res.energy_lost), np.asarray(res.kinetic_energy_post)
        v_pre = res.velocity_pre
    shape = np.shape(T)

    def bc(x: ArrayLike) -> FloatArray:
        return np.asarray(np.broadcast_to(np.asarray(x, dtype=float), shape))

    q3 = bc(q[..., 2])
    R = bc(walker.foot_radius)
    l = bc(walker.leg_length)
    L_S = bc(step_length(walker, q3))
    eta = loss_per_metre(lost, L_S)
    qd_pre = np.broadcast_to(q_dot, (*shape, 4))
    scale = l * (np.abs(qd_pre[..., 2]) + np.abs(qd_pre[..., 3]))
    lifts = trailing_foot_lifts(np.asarray(v_post)[..., 1], scale)
    return HeelStrikeStudy(
        impact_angle=q3,
        foot_radius=R,
        leg_length=l,
        restitution=float(restitution),
        state=np.asarray(np.broadcast_to(q, (*shape, 4))),
        velocity_pre=np.asarray(v_pre, dtype=float),
        velocity_post=np.asarray(v_post, dtype=float),
        constraint_impulse=np.asarray(impulse, dtype=float),
        kinetic_energy=np.asarray(T, dtype=float),
        kinetic_energy_constrained=np.asarray(T_c, dtype=float),
        kinetic_energy_admissible=np.asarray(T_a, dtype=float),
        kinetic_energy_post=np.asarray(post, dtype=float),
        energy_lost=np.asarray(lost, dtype=float),
        step_length=L_S,
        eta=eta,
        trailing_foot_lifts=np.asarray(lifts, dtype=bool),
        degenerate_wheel=is_mcgeer_wheel(R, l),
        impact=res,
    )
