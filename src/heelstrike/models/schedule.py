"""The hybrid schedule of a step, declared by the walker as data (Drake's witness + reset).

A step of every planar walker is a sequence of continuous :class:`Phase` objects, each with the
joints it holds locked and its :class:`Stage` objects (stretches integrated until a
:class:`Guard`, a witness function, crosses zero), ending in a reset: a **knee strike** (the
swing knee locks) or the **heel strike**. :func:`heelstrike.dynamics.hybrid.simulate` is the one
loop that runs any schedule; the walker only declares it
(:meth:`heelstrike.models.base.PlanarWalker.step_schedule`):

- the paper's compass gait (and any hand-written walker): one phase, "before mid-stance" then
  "until :meth:`~heelstrike.models.base.PlanarWalker.heel_strike_function` rises through zero",
  heel strike by the projector with the striking foot's Jacobian (eq. 13) and the lift test;
- a described walker: a knee-swing phase (stance knee locked) ending in a knee strike when it has
  lockable joints, then a locked-swing phase "until armed" and "until the swing foot's clearance
  falls through zero" (a touch with the swing foot not ahead of the stance foot is rejected and
  the strike armed anew), heel strike with the trailing foot as a complementarity candidate
  (:func:`heelstrike.core.complementarity.resolve_impact`); a walker file may declare its own
  heel-strike guard and trailing-foot rule instead (``[events]``,
  :class:`heelstrike.models.description.EventsSpec`).

Guards are functions of the configuration and velocities ``(q, q_dot)``, each shape (n,); a
guard named after a :class:`~heelstrike.dynamics.hybrid.WalkStatus` (``"fell_forward"``...)
ends the walk with that status when it fires.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from heelstrike._typing import FloatArray

__all__ = [
    "Guard",
    "Phase",
    "Stage",
    "StepSchedule",
    "TrailingFootRule",
    "fell_backward_rate",
    "fell_forward",
]

#: How the heel strike decides the trailing foot: ``"lift_rule"`` (the paper's projector with
#: the striking foot's rows only, then the trailing foot must lift), ``"lift_or_graze"`` (the
#: same projector; the trailing foot must lift or graze, leaving with zero normal velocity to
#: :data:`~heelstrike.models._contact.LIFT_TOLERANCE`, as when both feet are arcs of one
#: circle: McGeer's wheel) or ``"complementarity"`` (the trailing foot is a unilateral
#: candidate contact of the impact).
TrailingFootRule = Literal["lift_rule", "lift_or_graze", "complementarity"]
#: What ends a phase: a knee strike (its ``strike_joints`` lock) or the heel strike.
ResetKind = Literal["knee_strike", "heel_strike"]
#: A witness ``g(q, q_dot) -> float``; ``q`` and ``q_dot`` have shape (n,).
Witness = Callable[[FloatArray, FloatArray], float]


@dataclass(frozen=True, kw_only=True)
class Guard:
    """A terminal event: ``function(q, q_dot)`` crossing zero in ``direction``.

    Attributes
    ----------
    name : str
        The event's name; a walk status name (``"fell_forward"``...) ends the walk with it.
    function : callable
        The witness ``g(q, q_dot) -> float`` (SI units of whatever it measures).
    direction : {1, -1}
        ``1``: fires when ``g`` rises through zero; ``-1``: when it falls through zero.
    """

    name: str
    function: Witness
    direction: Literal[-1, 1]


@dataclass(frozen=True, kw_only=True)
class Stage:
    """One integrated stretch of a phase: until ``until`` fires, or a failure guard does.

    Attributes
    ----------
    until : Guard
        The guard that ends the stage as planned (the walk goes on).
    failures : tuple of Guard
        Guards that end the walk (named after walk statuses). The stance foot's contact
        checks (``lost_contact``, ``slipped``) are added by the simulator to every stage.
    skip : callable or None
        ``skip(q, q_dot) -> bool`` at the stage's start: True if the stage is already past
        (e.g. the stance leg already beyond the vertical).
    reject : callable or None
        ``reject(q, q_dot) -> bool`` when ``until`` fires: True if that crossing is not the
        planned event (a swing foot touching the ground level with or behind the stance foot
        is no heel strike). The phase then starts again at its first stage, whose ``skip`` is
        not consulted, so the guard must be armed anew.
    """

    until: Guard
    failures: tuple[Guard, ...] = ()
    skip: Callable[[FloatArray, FloatArray], bool] | None = None
    reject: Callable[[FloatArray, FloatArray], bool] | None = None


@dataclass(frozen=True, kw_only=True)
class Phase:
    """A continuous phase of a step and the reset that ends it.

    Attributes
    ----------
    name : str
        Label of its samples (``"knee_swing"``, ``"locked_swing"``).
    locked : tuple of int
        Joint coordinates (``>= 3``) held at their lock angles during the phase.
    stages : tuple of Stage
        Run in order.
    reset : {"knee_strike", "heel_strike"}
        The impact that ends the phase.
    strike_joints : tuple of int
        Knee strike: the joints that reach their lock angles and lock.
    """

    name: str
    locked: tuple[int, ...]
    stages: tuple[Stage, ...]
    reset: ResetKind
    strike_joints: tuple[int, ...] = ()


@dataclass(frozen=True, kw_only=True)
class StepSchedule:
    """The hybrid schedule of one step (see the module docstring).

    Attributes
    ----------
    phases : tuple of Phase
        In order; the last one ends with the heel strike.
    lock_angles : tuple of (int, float)
        Every lockable joint with its lock angle (rad): locked through the heel strike, and at
        the start of every step.
    trailing_foot : {"lift_rule", "lift_or_graze", "complementarity"}
        How the heel strike decides the trailing foot (:data:`TrailingFootRule`).
    """

    phases: tuple[Phase, ...]
    lock_angles: tuple[tuple[int, float], ...] = ()
    trailing_foot: TrailingFootRule = "lift_rule"

    def __post_init__(self) -> None:
        if not self.phases or self.phases[-1].reset != "heel_strike":
            raise ValueError("a step schedule must end with a heel-strike phase")

    @property
    def locks(self) -> tuple[int, ...]:
        """The lockable joints' coordinate indices."""
        return tuple(j for j, _ in self.lock_angles)


def fell_forward() -> Guard:
    """The stance leg reaching the horizontal ahead (the ground, for a point foot):
    ``q3 - pi/2`` rising through zero."""
    return Guard(name="fell_forward", function=lambda q, qd: float(q[2]) - 0.5 * np.pi,
                 direction=1)


def fell_backward_rate() -> Guard:
    """The stance leg stopping before the vertical: ``q3_dot`` falling through zero."""
    return Guard(name="fell_backward", function=lambda q, qd: float(qd[2]), direction=-1)
