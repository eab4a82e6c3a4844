"""The one definition of "the trailing foot lifts" and of "step length", for every path.

The rule is plain float arithmetic, so the same function is the scipy backends' test
(:func:`heelstrike.dynamics.hybrid.simulate`, :func:`heelstrike.dynamics.phased.simulate_phased`),
the analysis' (:func:`heelstrike.analysis.heel_strike.heel_strike_study`,
:func:`heelstrike.analysis.model_gaits.model_heel_strike`) and, compiled with ``numba.njit``,
the compiled kernels' (:mod:`heelstrike.dynamics.compiled`,
:mod:`heelstrike.dynamics.compiled_phased`). :func:`step_length` is likewise the one definition
of a step's length (:meth:`heelstrike.models.base.PlanarWalker.step_length` for every scipy and
generated backend, compiled in the compass-gait kernel). This module imports neither numba nor
scipy.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._typing import BoolArray

__all__ = [
    "CONTACT_TOLERANCE",
    "LIFT_TOLERANCE",
    "grazes",
    "lift_velocity_scale",
    "lifts",
    "presses",
    "step_length",
    "trailing_foot_lifts",
]

#: Relative tolerance on the trailing foot's post-impact normal velocity: the foot lifts if
#: ``v_n+ > LIFT_TOLERANCE * l sum_j |q_j_dot-|`` (joint rates, ``q2_dot+`` and
#: ``l (|q3_dot-| + |q4_dot-|)`` for the paper's walker). It absorbs round-off, so that McGeer's
#: wheel (``R = l``, where ``q2_dot+ = 0`` exactly) is reported as not lifting.
LIFT_TOLERANCE = 1e-9

#: Largest foot clearance of a foot said to touch the ground, relative to the leg length
#: (``|clearance| <= CONTACT_TOLERANCE * l``; 1 um for a 1 m leg, loose enough for a state
#: copied with six decimals): both feet at a heel strike, the trailing foot at a step's start.
CONTACT_TOLERANCE = 1e-6


def lifts(normal_velocity: float, velocity_scale: float) -> bool:
    """The rule itself, for scalars (numba-compilable): ``v_n > LIFT_TOLERANCE * scale``.

    Parameters
    ----------
    normal_velocity : float
        Post-impact normal (upward) velocity of the trailing foot's contact point (m/s).
    velocity_scale : float
        Size of the pre-impact velocities (m/s), :func:`lift_velocity_scale`.
    """
    return normal_velocity > LIFT_TOLERANCE * velocity_scale


def grazes(normal_velocity: float, velocity_scale: float) -> bool:
    """The trailing foot neither lifts nor presses: ``|v_n| <= LIFT_TOLERANCE * scale``.

    The borderline of :func:`lifts`, met by McGeer's wheel (``R = l``), whose trailing foot
    leaves a heel strike with ``v_n+ = 0`` in exact arithmetic.

    Parameters
    ----------
    normal_velocity : float
        Post-impact normal (upward) velocity of the trailing foot's contact point (m/s).
    velocity_scale : float
        Size of the pre-impact velocities (m/s), :func:`lift_velocity_scale`.
    """
    return abs(normal_velocity) <= LIFT_TOLERANCE * velocity_scale


def presses(normal_velocity: float, velocity_scale: float) -> bool:
    """The foot moves into the ground: ``v_n < -LIFT_TOLERANCE * scale`` (numba-compilable).

    Neither :func:`lifts` nor :func:`grazes`. A state just after a heel strike never has its
    trailing foot (on the ground) pressing: the heel strike would not have lifted it.

    Parameters
    ----------
    normal_velocity : float
        Normal (upward) velocity of the foot's contact point (m/s).
    velocity_scale : float
        Size of the velocities (m/s), :func:`lift_velocity_scale`.
    """
    return normal_velocity < -LIFT_TOLERANCE * velocity_scale


def lift_velocity_scale(leg_length: float, joint_rates: NDArray[np.float64]) -> float:
    """Velocity scale of the lift rule: ``l sum_j |q_j_dot-|`` (m/s), numba-compilable.

    Parameters
    ----------
    leg_length : float
        Leg length ``l`` of the walker's scale (m).
    joint_rates : ndarray, shape (k,)
        Pre-impact angular rates (rad/s): ``q_dot[2:]`` (``(q3_dot, q4_dot)`` for the paper's
        walker).
    """
    s = 0.0
    for i in range(joint_rates.shape[0]):
        s += abs(joint_rates[i])
    return leg_length * s


def trailing_foot_lifts(normal_velocity: ArrayLike, velocity_scale: ArrayLike) -> BoolArray:
    """The one definition of an admissible heel strike: the trailing foot lifts.

    Parameters
    ----------
    normal_velocity : array_like, shape (...)
        Post-impact normal (upward) velocity of the trailing foot's contact point (m/s),
        ``q2_dot+`` for the paper's walker.
    velocity_scale : array_like, shape (...)
        Size of the pre-impact velocities (m/s), e.g. ``l (|q3_dot-| + |q4_dot-|)``.

    Returns
    -------
    ndarray of bool, shape (...)
        ``normal_velocity > LIFT_TOLERANCE * velocity_scale`` (:func:`lifts`, elementwise).
    """
    v = np.asarray(normal_velocity, dtype=float)
    return np.asarray(lifts(v, np.asarray(velocity_scale, dtype=float)))  # type: ignore[arg-type]


def step_length(stance_contact_start: float, striking_contact_impact: float) -> float:
    """The one definition of a step's length (m), for scalars (numba-compilable).

    The distance along the ground, in the walking direction ``-x``, from the stance foot's
    contact point at the start of the step to the striking (swing) foot's contact point at heel
    strike: ``x_stance(start) - x_striking(impact)``. It includes the arc rolled by the stance
    foot during the step; on a symmetric periodic compass gait it is
    ``2 (l - R) sin q3 + 2 R q3`` (:func:`heelstrike.analysis.heel_strike.step_length`).

    Parameters
    ----------
    stance_contact_start : float
        ``x`` (m) of the stance foot's contact point at the start of the step.
    striking_contact_impact : float
        ``x`` (m) of the striking foot's contact point at heel strike.
    """
    return stance_contact_start - striking_contact_impact
