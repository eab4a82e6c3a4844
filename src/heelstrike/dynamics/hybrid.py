"""Hybrid walking simulation: the one loop that runs every walker's declared step schedule.

A walker declares the hybrid schedule of its step as data
(:meth:`~heelstrike.models.base.PlanarWalker.step_schedule`, :mod:`heelstrike.models.schedule`:
Drake's witness + reset idea): continuous phases with the joints they hold locked, each
integrated stage by stage (scipy's ``solve_ivp``, DOP853) until a guard fires, and the resets
between them. :func:`simulate` runs any schedule, so the paper's compass gait, the kneed
walker's knee strike and the torso walker are the same loop:

- **the compass gait** (and any hand-written walker): one phase, first until the stance leg
  passes the vertical (stopping before it is a fall backward), then until the walker's
  heel-strike function rises through zero. *Scuffing convention*: a rigid straight-legged
  compass gait's swing foot passes through the ground near mid-stance; as is classical
  (Goswami et al. 1998; Garcia et al. 1998) this is ignored: the compass walker's event function
  ``2 q3 + q4`` has no root at the scuffing configuration ``q4 = 0``. The heel strike is
  :func:`heel_strike` (``q_dot+ = P_a q_dot-`` with the striking foot's Jacobian, eq. 13); the
  trailing foot must then lift (:func:`heelstrike.models._contact.lifts`, relative to
  ``l sum |q_dot-|``).
- **described walkers with knees** (McGeer 1990, ``kneed.toml``): a knee-swing phase (stance
  knee locked, swing knee free) ending in the **knee strike**, an inert impact with
  ``A = [A_R; lock rows]`` (:func:`heelstrike.core.impact.impact`), then a locked-swing phase
  (the walker is a compass gait) until the swing foot's clearance falls through zero once the
  strike is armed (stance leg past the vertical, swing foot ahead and above the ground). The heel
  strike has bilateral rows ``[A_L; lock rows]`` and the trailing foot ``A_R`` as a unilateral
  candidate (:func:`heelstrike.core.complementarity.resolve_impact`); if it does not separate
  and lift, the walk ends with ``trailing_foot_stays``.

After a heel strike the legs are relabelled (``swap_legs``) and the locks reset exactly. Every
impact (knee strikes too) is reported with ``T``, ``T_c``, ``T_a`` (Font & Kovecses 2008,
eq. 10) in :attr:`PhasedWalkResult.events`; :attr:`WalkResult.impacts` holds one
:class:`ImpactRecord` per heel strike.

Failures are reported in :attr:`WalkResult.status`, never raised from inside the integrator.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.complementarity import CandidateContact, resolve_impact
from heelstrike.core.impact import ImpactResult, impact
from heelstrike.dynamics.events import Event, to_scipy
from heelstrike.dynamics.single_support import SingleSupport, TorqueLaw
from heelstrike.models._contact import grazes, lift_velocity_scale, lifts
from heelstrike.models.base import PlanarWalker
from heelstrike.models.schedule import Guard, Stage, StepSchedule
from heelstrike.status import CodedStatus, check_codes

__all__ = [
    "GroundReaction",
    "ImpactRecord",
    "PhasedImpact",
    "PhasedWalkResult",
    "PushOff",
    "WalkResult",
    "WalkStatus",
    "check_initial_state",
    "cut_off_profile",
    "heel_strike",
    "lock_torques",
    "simulate",
]

ImpactKind = Literal["knee_strike", "heel_strike"]

#: An impulsive actuation applied just before heel strike: ``(walker, q, q_dot, locks) ->
#: (q_dot_after, work)``, ``locks`` the rows (k, n) of the joints locked then (the locks hold
#: through the impulse); the work (J) is what the actuator does on the walker.
PushOff = Callable[[PlanarWalker, FloatArray, FloatArray, FloatArray],
                   tuple[FloatArray, float]]


class WalkStatus(CodedStatus):
    """How a simulation ended: the one status vocabulary of every backend.

    Each member is its string name (a :class:`~enum.StrEnum`, so ``status == "completed"``
    holds), carries a human-readable ``message`` and a stable integer ``code``: the
    code the compiled (numba) kernels write and ensemble results store (:meth:`from_code`
    converts back). Codes never change meaning; new statuses get new codes.

    ``NO_CONSISTENT_ASSIGNMENT`` and ``NO_LEG_SWAP`` are reported by the compiled phased
    kernels only and raised as errors by their Python wrappers, as the scipy backend does.

    A walk's :attr:`WalkResult.message` says more where it can: for ``off_profile`` which
    foot, its contact angle and its range; for a walk of a walker file declaring its
    heel-strike guard that ends before the strike, the guard's expression and the values it
    took (``no_heel_strike`` when it was never below zero, so it could not rise through zero).

    ``CONVERGED``, ``KEEPS_WALKING`` and ``INADMISSIBLE_START`` are the outcomes a basin of
    attraction (:mod:`heelstrike.analysis.basin`) gives where a walk completed or was not
    started; no simulation returns them. A basin stores the member codes, so code 0
    (``COMPLETED``) means the same everywhere.
    """

    COMPLETED = "completed", 0, "all requested steps were taken"
    FELL_FORWARD = (
        "fell_forward", 1,
        "the stance leg rotated forward to the horizontal, q3 = 90 deg, with no heel strike",
    )
    FELL_BACKWARD = "fell_backward", 2, "the walker stopped and fell backward"
    TRAILING_FOOT_STAYS = (
        "trailing_foot_stays",
        3,
        "after heel strike the trailing foot does not lift (its contact point's normal "
        "velocity is not positive, or the complementarity conditions keep it on the ground): "
        "double support would begin, which this gait model does not allow",
    )
    LOST_CONTACT = (
        "lost_contact",
        4,
        "the ground's normal force on the stance foot became negative: the ground would have "
        "to pull, so the walker leaves it, as when it topples forward fast",
    )
    SLIPPED = "slipped", 5, "the stance foot needs more friction than the given coefficient"
    NO_HEEL_STRIKE = (
        "no_heel_strike",
        6,
        "no heel strike (or knee strike) within the time bound of a step, or a heel-strike "
        "guard declared by the walker file ([events] heel_strike) that could not cross zero",
    )
    INTEGRATION_FAILED = "integration_failed", 7, "the integrator failed"
    NO_CONSISTENT_ASSIGNMENT = (
        "no_consistent_assignment",
        8,
        "no consistent contact assignment at an impact (rank-deficient constraints?)",
    )
    NO_LEG_SWAP = ("no_leg_swap", 9, "no leg swap: the walker declares no link mirrors "
                   "(link.mirror), which a walk past its first heel strike needs")
    CONVERGED = (
        "converged", 10,
        "came within the tolerance of the gait's fixed point (the walk stops there)",
    )
    KEEPS_WALKING = (
        "keeps_walking", 11,
        "took every step without coming within the tolerance of the gait's fixed point "
        "(another attractor, or slow convergence)",
    )
    INADMISSIBLE_START = (
        "inadmissible_start", 12,
        "not walked: the trailing foot is on the ground and moving into it, a state no heel "
        "strike leaves",
    )
    OFF_PROFILE = (
        "off_profile", 13,
        "a profile foot's contact angle left its profile's phi_range (the stance foot's during "
        "the step, or the swing foot's as it comes down to the heel strike): beyond it the "
        "support function would be extrapolated past the shape the walker file gives",
    )


check_codes(WalkStatus)


@dataclass(frozen=True, kw_only=True)
class ImpactRecord(ResultDictMixin):
    """One heel strike of a simulation (pre-swap labels: the "left" foot strikes).

    Attributes
    ----------
    step : int
        Index of the step that this impact ends (0-based).
    time : float
        Time of impact (s).
    q : ndarray, shape (n,)
        Configuration at impact.
    q_dot_minus, q_dot_plus : ndarray, shape (n,)
        Velocities before (after any push-off) and after heel strike.
    impact_angle : float
        Stance-leg angle ``q3`` at heel strike (rad).
    kinetic_energy, kinetic_energy_constrained, kinetic_energy_admissible : float
        ``T``, ``T_c``, ``T_a`` just before impact (J), eq. (10).
    energy_lost : float
        Kinetic energy dissipated by the impact (J); ``T_c`` for an inert impact.
    impulse : ndarray, shape (2,)
        Ground impulse on the striking foot (tangential, normal) (N s).
    step_length : float
        Distance along the ground (m) from the stance foot's contact point at the start of the
        step to the striking foot's contact point; ``2 (l - R) sin q3 + 2 R q3`` on a
        symmetric periodic gait.
    trailing_normal_velocity : float
        Normal velocity of the trailing foot's contact point after impact (m/s), > 0 to lift.
    potential_energy_released : float
        Drop of potential energy from the start of the step to the impact (J).
    actuator_work : float
        Work done by the actuators during the step, push-off included (J).
    push_off_work : float
        Work of the impulsive push-off alone (J).
    """

    step: int
    time: float
    q: FloatArray
    q_dot_minus: FloatArray
    q_dot_plus: FloatArray
    impact_angle: float
    kinetic_energy: float
    kinetic_energy_constrained: float
    kinetic_energy_admissible: float
    energy_lost: float
    impulse: FloatArray
    step_length: float
    trailing_normal_velocity: float
    potential_energy_released: float
    actuator_work: float
    push_off_work: float
    step_duration: float

    @classmethod
    def of_step(
        cls,
        walker: PlanarWalker,
        slope: float,
        *,
        step: int,
        step_start: tuple[float, FloatArray],
        time: float,
        q: FloatArray,
        q_dot_minus: FloatArray,
        q_dot_plus: FloatArray,
        kinetic_energy: float,
        kinetic_energy_constrained: float,
        kinetic_energy_admissible: float,
        impulse: FloatArray,
        trailing_normal_velocity: float,
        energy_lost: float | None = None,
        actuator_work: float = 0.0,
        push_off_work: float = 0.0,
    ) -> ImpactRecord:
        """The record of a heel strike, every backend's one bookkeeping of a step.

        ``step_start`` is the step's start ``(time (s), configuration q, shape (n,))``; the
        step's length, duration and potential energy released are measured from it, with the
        walker's own :meth:`~heelstrike.models.base.PlanarWalker.step_length` and
        :meth:`~heelstrike.models.base.PlanarWalker.potential_energy` on ``slope`` (rad).
        ``energy_lost`` is ``T_c`` unless given (an inert impact destroys ``T_c``); the other
        arguments are the attributes of the same name.
        """
        t_start, q_start = step_start
        T_c = float(kinetic_energy_constrained)
        return cls(
            step=step, time=time, q=np.array(q, dtype=float),
            q_dot_minus=np.array(q_dot_minus, dtype=float),
            q_dot_plus=np.array(q_dot_plus, dtype=float), impact_angle=float(q[2]),
            kinetic_energy=float(kinetic_energy), kinetic_energy_constrained=T_c,
            kinetic_energy_admissible=float(kinetic_energy_admissible),
            energy_lost=T_c if energy_lost is None else float(energy_lost),
            impulse=np.asarray(impulse, dtype=float),
            step_length=float(walker.step_length(q_start, q)),
            trailing_normal_velocity=float(trailing_normal_velocity),
            potential_energy_released=float(walker.potential_energy(q_start, slope))
            - float(walker.potential_energy(q, slope)),
            actuator_work=float(actuator_work), push_off_work=float(push_off_work),
            step_duration=time - t_start,
        )


@dataclass(frozen=True, kw_only=True)
class WalkResult(ResultDictMixin):
    """Outcome of :func:`simulate`.

    Attributes
    ----------
    status : WalkStatus
        How the simulation ended; ``message`` explains it.
    t : ndarray, shape (N,)
        Times (s).
    q, q_dot : ndarray, shape (N, n)
        States, the current stance foot labelled "right", in the ground frame.
    stance_leg : ndarray of int, shape (N,)
        Which physical leg is the stance leg (0: the initial stance leg, 1: the other).
    step : ndarray of int, shape (N,)
        Step index of every sample.
    actuator_work : ndarray, shape (N,)
        Cumulative actuator work (J) from the start. An impulsive push-off happens at an impact,
        between samples: it appears from the next step's first sample on, so the last sample
        of a walk does not include its final push-off (the :class:`ImpactRecord` does).
    impacts : tuple of ImpactRecord
        Every heel strike, in order.
    final_q, final_q_dot : ndarray, shape (n,)
        Last state (after the last impact's relabelling if the walk completed).
    slope : float
        Ground slope (rad).
    """

    status: WalkStatus
    message: str
    t: FloatArray
    q: FloatArray
    q_dot: FloatArray
    stance_leg: NDArray[np.int_]
    step: NDArray[np.int_]
    actuator_work: FloatArray
    impacts: tuple[ImpactRecord, ...]
    final_q: FloatArray
    final_q_dot: FloatArray
    slope: float

    @property
    def ok(self) -> bool:
        """True if every requested step was taken."""
        return self.status is WalkStatus.COMPLETED

    @property
    def n_steps(self) -> int:
        """Number of completed heel strikes."""
        return len(self.impacts)

    def impact_array(self, name: str) -> FloatArray:
        """Stack one :class:`ImpactRecord` field over all impacts."""
        return np.asarray([getattr(r, name) for r in self.impacts], dtype=float)

    def impact_losses(self) -> tuple[tuple[str, float], ...]:
        """Every impact in order with its loss ``T_c`` (J): ``("heel_strike", T_c)`` per step
        (a walker with knees also lists its knee strikes, :class:`PhasedWalkResult`)."""
        return tuple(("heel_strike", r.kinetic_energy_constrained) for r in self.impacts)


@dataclass(frozen=True, kw_only=True)
class GroundReaction(ResultDictMixin):
    """Contact force on the stance foot along a walk.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Times (s).
    tangential, normal : ndarray, shape (N,)
        Force of the ground on the stance foot along and normal to the ground (N).
    required_friction : ndarray, shape (N,)
        ``|tangential| / normal``: the smallest Coulomb coefficient that prevents slipping.
    """

    t: FloatArray
    tangential: FloatArray
    normal: FloatArray
    required_friction: FloatArray


def ground_reaction(
    walker: PlanarWalker, walk: WalkResult, torque: TorqueLaw | None = None
) -> GroundReaction:
    """Ground reaction on the stance foot at every sample of a walk.

    ``torque`` must be the law the walk was simulated with (None for a passive walk); its time
    argument is the time since the start of each step. The joints that a sample's phase locks
    (``walk.phase`` of a :class:`PhasedWalkResult`, the walker's
    :meth:`~heelstrike.models.base.PlanarWalker.step_schedule`) are held, their torques part of
    the balance (a kneed walker's knees; see
    :meth:`~heelstrike.dynamics.single_support.SingleSupport.ground_reaction`).
    """
    lam = _constraint_forces(walker, walk, torque)[0][:, :2]
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(lam[:, 1] > 0, np.abs(lam[:, 0]) / lam[:, 1], np.inf)
    return GroundReaction(
        t=walk.t, tangential=lam[:, 0], normal=lam[:, 1], required_friction=mu
    )


def lock_torques(
    walker: PlanarWalker, walk: WalkResult, torque: TorqueLaw | None = None
) -> dict[str, FloatArray]:
    """Torque each lock exerts to hold its joint at every sample of a walk.

    Walker files' locks (a kneed walker's knees) are two-sided latches: the constraint
    ``q[j] = lock angle`` holds whatever torque it takes. A knee stop that can only push
    holds only where that torque has one sign; where it changes sign over a step (the kneed
    walker's stance knee at 3 deg, QA sweep 13) such a stop would let the knee buckle.

    Parameters
    ----------
    walker : PlanarWalker
    walk : WalkResult
        A sampled walk (a :class:`PhasedWalkResult` labels each sample's phase).
    torque : TorqueLaw, optional
        The law the walk was simulated with (None: passive).

    Returns
    -------
    dict of str to ndarray
        Per lockable joint (by coordinate name), shape (N,): the holding torque (N m) on its
        coordinate where the sample's phase locks it, NaN where the joint is free.
    """
    forces, locked = _constraint_forces(walker, walk, torque)
    names = walker.coordinate_names
    out: dict[str, FloatArray] = {}
    for j, _angle in walker.step_schedule().lock_angles:
        out[names[j]] = np.where(locked[:, j], forces[:, j], np.nan)
    return out


def _constraint_forces(
    walker: PlanarWalker, walk: WalkResult, torque: TorqueLaw | None
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """``M q_ddot + h - B u`` at every sample (N, n) (:meth:`SingleSupport.constraint_forces`,
    each sample with its phase's locks) and which joints each sample's phase locks (N, n)."""
    locks = {phase.name: phase.locked for phase in walker.step_schedule().phases}
    n = walk.t.size
    names = walk.phase if isinstance(walk, PhasedWalkResult) and len(walk.phase) == n \
        else np.full(n, "")
    out = np.empty((n, np.asarray(walk.q).shape[1]))
    held = np.zeros(out.shape, dtype=bool)
    if torque is not None:  # the law's clock: time since the start of each step
        starts = {int(k): float(walk.t[walk.step == k][0]) for k in np.unique(walk.step)}
    for name in np.unique(names):
        sel = np.flatnonzero(names == name)
        if str(name) in locks:
            locked = locks[str(name)]
        elif name == "" and not any(locks.values()):
            locked = ()  # a walk without phase labels (the compass kernel's), nothing locked
        else:
            raise ValueError(f"the walk's phase {str(name)!r} is none of the walker's phases "
                             f"{sorted(locks)}: which joints it holds is unknown")
        for j in locked:
            held[sel, j] = True
        sup = SingleSupport(walker=walker, slope=walk.slope, torque=torque, locked=locked)
        if torque is None:
            out[sel] = sup.constraint_forces(0.0, walk.q[sel], walk.q_dot[sel])
            continue
        for i in sel:
            out[i] = sup.constraint_forces(float(walk.t[i]) - starts[int(walk.step[i])],
                                           walk.q[i], walk.q_dot[i])
    return out, held


def heel_strike(
    walker: PlanarWalker,
    q: ArrayLike,
    q_dot: ArrayLike,
    *,
    restitution: float = 0.0,
    locks: tuple[int, ...] = (),
) -> tuple[ImpactResult, FloatArray]:
    """Resolve the left foot's heel strike with the paper's projector (eq. 13).

    Parameters
    ----------
    walker : PlanarWalker
    q, q_dot : array_like, shape (..., n)
        Pre-impact state (stance foot labelled "right").
    restitution : float
        Restitution of the constrained velocity (0: inert, the paper).
    locks : tuple of int
        Joint coordinates locked through the impact (their rows ``e_j`` join ``A_L``).

    Returns
    -------
    result : ImpactResult
        The decomposition with ``A = [A_L(q); lock rows]``.
    trailing_normal_velocity : ndarray, shape (...)
        Normal velocity of the trailing ("right") foot's contact point after impact (m/s).
    """
    M = walker.mass_matrix(q)
    A = walker.contact_jacobian(q, "left")
    if locks:
        rows = np.eye(walker.n_coordinates)[list(locks)]
        A = np.concatenate((A, np.broadcast_to(rows, (*A.shape[:-2], *rows.shape))), axis=-2)
    res = impact(M, A, q_dot, restitution=restitution)
    A_R = walker.contact_jacobian(q, "right")
    v_trailing = np.einsum("...ij,...j->...i", A_R, res.velocity_post)[..., 1]
    return res, np.asarray(v_trailing)


#: Events of the stance foot's contact (normal force, friction cone, a profile foot's contact
#: angle inside its range), checked at the start of every integrated segment as well as for
#: sign changes.
CONTACT_EVENTS: tuple[str, ...] = (WalkStatus.LOST_CONTACT.value, WalkStatus.SLIPPED.value,
                                   WalkStatus.OFF_PROFILE.value)


@dataclass(frozen=True, kw_only=True)
class Segment(ResultDictMixin):
    """One integrated stretch of single support: samples ``t`` (N,), states ``x`` (N, 2m + 1),
    the terminal event that ended it (None: time bound reached) and whether the solver failed."""

    t: FloatArray
    x: FloatArray  # (N, 2m + 1)
    event: str | None
    failed: bool


def integrate_segment(
    support: SingleSupport,
    q_ref: FloatArray,
    x0: FloatArray,
    t0: float,
    t_end: float,
    events: list[Event],
    rtol: float,
    atol: float,
    max_step: float,
) -> Segment:
    """Integrate ``support.rhs`` from ``t0`` until a terminal event or ``t_end`` (DOP853).

    The last sample is placed exactly at the terminal event's state. A contact event
    (:data:`CONTACT_EVENTS`) whose function is already ``<= 0`` at the start ends the segment
    at once: a sign change cannot be detected from there, and the stance foot's contact is
    already lost (e.g. a launch so fast that the ground would have to pull the foot down).
    """
    if t_end <= t0:
        return Segment(t=np.array([t0]), x=x0[None, :], event=None, failed=False)
    for ev in events:
        if ev.name in CONTACT_EVENTS and ev.function(t0, x0) <= 0.0:
            return Segment(t=np.array([t0]), x=x0[None, :], event=ev.name, failed=False)
    from scipy.integrate import solve_ivp  # lazy: ~0.7 s per process otherwise

    sol: Any = solve_ivp(
        support.rhs,
        (t0, t_end),
        x0,
        method="DOP853",
        rtol=rtol,
        atol=atol,
        max_step=max_step,
        events=to_scipy(events),
        args=(q_ref,),
    )
    ts, xs = sol.t, sol.y.T
    hit: str | None = None
    if sol.status == 1:
        for ev, t_ev, x_ev in zip(events, sol.t_events, sol.y_events, strict=True):
            if len(t_ev) and ev.terminal:
                hit = ev.name
                ts = np.append(ts[:-1], t_ev[0])
                xs = np.vstack((xs[:-1], x_ev[0]))
                break
    return Segment(t=ts, x=xs, event=hit, failed=sol.status < 0)


# -- results -----------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class PhasedImpact(ResultDictMixin):
    """One impact (knee strike or heel strike) of a phased simulation.

    Attributes
    ----------
    kind : {"knee_strike", "heel_strike"}
    step : int
        Step index (0-based).
    time : float
        Time of impact (s).
    q : ndarray, shape (n,)
        Configuration (pre-swap labels).
    q_dot_minus, q_dot_plus : ndarray, shape (n,)
        Velocities before and after the impact.
    rows : ndarray, shape (k, n)
        Final active constraint rows ``A`` (``[A_R; locks]`` for a knee strike,
        ``[A_L; locks]`` (+ trailing foot rows if it stays) for a heel strike).
    kinetic_energy, kinetic_energy_constrained, kinetic_energy_admissible : float
        ``T``, ``T_c``, ``T_a`` just before impact (J), eq. (10); ``T_c`` is lost.
    energy_lost : float
        ``T- - T+`` (J).
    impulse : ndarray, shape (k,)
        Constraint impulses of ``rows`` (N s, N m s).
    lock_rows : ndarray, shape (k_l, n)
        Jacobian of the knee locks engaged through the impact.
    lock_velocity_post : ndarray, shape (k_l,)
        ``A_lock q_dot+`` (rad/s), zero for an inert lock.
    trailing_normal_velocity : float
        Heel strike: normal velocity of the trailing foot's contact point after impact (m/s);
        knee strike: that of the stance foot (0: it stays rolling).
    trailing_mode : str
        Heel strike: the complementarity decision for the trailing foot (``"separate"``: it
        lifts), or under the projector's rules ``"separate"`` / ``"penetrating"`` by the sign
        of its normal velocity, ``"graze"`` when the ``"lift_or_graze"`` rule finds it zero
        to round-off. Knee strike: ``"stick"`` (the stance foot is bilateral).
    """

    kind: ImpactKind
    step: int
    time: float
    q: FloatArray
    q_dot_minus: FloatArray
    q_dot_plus: FloatArray
    rows: FloatArray
    kinetic_energy: float
    kinetic_energy_constrained: float
    kinetic_energy_admissible: float
    energy_lost: float
    impulse: FloatArray
    lock_rows: FloatArray
    lock_velocity_post: FloatArray
    trailing_normal_velocity: float
    trailing_mode: str


@dataclass(frozen=True, kw_only=True)
class PhasedWalkResult(WalkResult):
    """:class:`~heelstrike.dynamics.hybrid.WalkResult` plus every impact and phase label.

    Attributes
    ----------
    events : tuple of PhasedImpact
        Every impact in order (knee strikes and heel strikes).
    phase : ndarray of str, shape (N,)
        Phase of every sample (``"knee_swing"``, ``"locked_swing"``).
    mechanical_energy : ndarray, shape (N,)
        ``T + V`` (J) of every sample.
    """

    events: tuple[PhasedImpact, ...] = ()
    phase: NDArray[np.str_] = field(default_factory=lambda: np.array([], dtype=str))
    mechanical_energy: FloatArray = field(default_factory=lambda: np.array([]))

    def impact_losses(self) -> tuple[tuple[str, float], ...]:
        """Every impact in order (knee strikes and heel strikes) with its loss ``T_c`` (J)."""
        return tuple((e.kind, e.kinetic_energy_constrained) for e in self.events)


# -- the one loop ------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class _ShiftedTorque:
    """A torque law whose clock restarts at ``t0`` (the start of a step)."""

    law: TorqueLaw | Callable[[float, FloatArray, FloatArray], FloatArray]
    t0: float

    def __call__(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray:
        return np.asarray(self.law(t - self.t0, q, q_dot))


def _segment_outcome(seg: Segment, want: str) -> WalkStatus | None:
    """Status that ends the walk after a segment, or None if it ended with the wanted event."""
    if seg.failed:
        return WalkStatus.INTEGRATION_FAILED
    if seg.event is None:
        return WalkStatus.NO_HEEL_STRIKE
    if seg.event != want:
        return WalkStatus(seg.event)
    return None


def _ended_message(
    walker: PlanarWalker, status: WalkStatus, stage: Stage, k: int, t: float,
    qs: FloatArray, qds: FloatArray,
) -> tuple[WalkStatus, str]:
    """The status and message of a walk whose step ``k`` ended in ``status`` at time ``t``
    during ``stage`` (its samples ``qs``, ``qds``, shape (N, n)).

    ``off_profile``: which foot, its contact angle and range
    (:meth:`~heelstrike.models.builder.BuiltWalker.profile_excursion`). A stage that was to end
    in the heel strike of a guard declared by the walker file (``[events] heel_strike``) that
    was never below zero over the stage (it rises through zero at the strike, so from there it
    cannot fire): the guard's expression and the values it took. The status is what stopped
    the integration (a fall, lost contact...), as the compiled kernels report it, so that both
    backends classify a walk alike; a guard that was below zero (armed) when the walker failed
    is not the reason, and the message is the status's, as on the compiled kernels. Otherwise
    the status's message.
    """
    if status is WalkStatus.OFF_PROFILE:
        where = walker.profile_excursion(qs[-1])
        if where is not None:
            return status, f"{status.message}: {where} (step {k}, t = {t:.6g} s)"
    desc = walker.description
    if (desc is None or desc.events is None or stage.until.name != "heel_strike"
            or status is WalkStatus.OFF_PROFILE):
        return status, status.message
    g = np.array([stage.until.function(a, b) for a, b in zip(qs, qds, strict=True)])
    said = (f"the declared heel-strike guard {desc.events.heel_strike!r} (events.heel_strike) "
            f"did not rise through zero in step {k}: it took values in "
            f"[{float(g.min()):.6g}, {float(g.max()):.6g}]")
    if g.size > 1 and bool(np.all(g >= 0.0)):
        return status, (
            f"{status.message}; no heel strike before that: {said}, never below zero, so it "
            f"cannot rise through zero (t = {t:.6g} s)")
    return status, status.message


def cut_off_profile(walker: PlanarWalker, walk: PhasedWalkResult,
                    tol: float = 1e-9) -> PhasedWalkResult:
    """A walk computed without the ``off_profile`` guards (the compiled kernels), ended where a
    profile foot first leaves its ``phi_range``.

    Checked on the walk's samples (the stance foot's contact angle) and at every heel strike
    (the striking foot's, :meth:`~heelstrike.models.builder.BuiltWalker.profile_margin`
    below ``-tol`` rad): the walk is cut at the first sample out of range (kept, the walk's
    last) or just before the first heel strike out of range (that strike and what follows
    dropped), with status ``off_profile`` and a message naming the foot and its angle. Unlike
    :func:`simulate`, whose guards locate the range's end exactly, the sample is the
    integrator's (the range's end lies between it and the one before). A walker without
    profile feet, or a walk inside the ranges, is returned as it is.

    Parameters
    ----------
    walker : PlanarWalker
        The walker of the walk's first step (a walker whose legs differ alternates with
        :meth:`~heelstrike.models.base.PlanarWalker.after_swap`: each step's samples and heel
        strike are checked against the ranges of the walker taking it).
    walk : PhasedWalkResult
    tol : float
        Tolerance (rad) on the range's ends.

    Returns
    -------
    PhasedWalkResult
        ``walk`` itself, or the walk cut (its samples, impacts and events up to the cut).
    """
    if walker.is_batched or walk.t.size == 0:
        return walk
    stride = [walker]  # the walkers of a period: step k is taken by stride[k % len(stride)]
    while len(stride) < walker.steps_per_period:
        stride.append(stride[-1].after_swap())
    if all(w.profile_ranges == (None, None) for w in stride):
        return walk
    of_step = np.asarray(walk.step) % len(stride)
    stance = np.full(walk.t.shape, np.inf)
    for r, w in enumerate(stride):
        at = of_step == r
        stance[at] = np.asarray(w.profile_margin(walk.q[at], "right"))
    bad = np.flatnonzero(stance < -tol)
    cut: tuple[float, int, FloatArray] | None = None  # (time, step, q) of the first excursion
    if bad.size:
        i = int(bad[0])
        cut = (float(walk.t[i]), int(walk.step[i]), walk.q[i])
    for e in walk.events:
        w = stride[e.step % len(stride)]
        if e.kind == "heel_strike" and float(w.profile_margin(e.q, "left")) < -tol:
            if cut is None or e.time < cut[0] or (e.time == cut[0] and e.step <= cut[1]):
                cut = (float(e.time), int(e.step), e.q)
            break
    if cut is None:
        return walk
    t_cut, k_cut, q_cut = cut
    keep = (walk.step < k_cut) | ((walk.step == k_cut) & (walk.t <= t_cut))
    n = max(int(np.count_nonzero(keep)), 1)
    where = (stride[k_cut % len(stride)].profile_excursion(q_cut, tol=-tol)
             or "a profile foot left its range")
    message = (f"{WalkStatus.OFF_PROFILE.message}: {where} (step {k_cut}, t = {t_cut:.6g} s; "
               "located to the integrator's samples)")

    def kept(e: PhasedImpact | ImpactRecord) -> bool:
        return e.time < t_cut or (e.time == t_cut and e.step < k_cut)

    return replace(
        walk, status=WalkStatus.OFF_PROFILE, message=message, t=walk.t[:n], q=walk.q[:n],
        q_dot=walk.q_dot[:n], stance_leg=walk.stance_leg[:n], step=walk.step[:n],
        actuator_work=walk.actuator_work[:n],
        impacts=tuple(r for r in walk.impacts if kept(r)),
        final_q=walk.q[n - 1].copy(), final_q_dot=walk.q_dot[n - 1].copy(),
        events=tuple(e for e in walk.events if kept(e)),
        phase=walk.phase[:n] if walk.phase.size == walk.t.size else walk.phase,
        mechanical_energy=(walk.mechanical_energy[:n]
                           if walk.mechanical_energy.size == walk.t.size
                           else walk.mechanical_energy),
    )


def _events(
    support: SingleSupport, q_ref: FloatArray, stage: Stage, friction: float | None
) -> list[Event]:
    """A stage's guards as integrator events on the reduced state ``x``, then the stance
    foot's contact checks (:data:`CONTACT_EVENTS`)."""
    m = len(support.free_coordinates)

    def state(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        return support.unpack(x[: 2 * m], q_ref)

    def event(guard: Guard) -> Event:
        fn = guard.function
        return Event(name=guard.name, function=lambda t, x: fn(*state(x)),
                     direction=guard.direction)

    def normal(t: float, x: FloatArray) -> float:
        return float(support.ground_reaction(t, *state(x))[1])

    events = [event(stage.until), *(event(g) for g in stage.failures),
              Event(name="lost_contact", function=normal, direction=-1)]
    if friction is not None:
        mu = float(friction)

        def slip(t: float, x: FloatArray) -> float:
            lam = support.ground_reaction(t, *state(x))
            return float(mu * lam[1] - abs(lam[0]))

        events.append(Event(name="slipped", function=slip, direction=-1))
    return events


def _impact_event(
    kind: ImpactKind, step: int, time: float, q: FloatArray, q_dot_minus: FloatArray,
    res: ImpactResult, rows: FloatArray, lock_rows: FloatArray, trailing_normal_velocity: float,
    trailing_mode: str,
) -> PhasedImpact:
    """The :class:`PhasedImpact` record of one resolved impact."""
    q_dot_plus = np.asarray(res.velocity_post)
    return PhasedImpact(
        kind=kind, step=step, time=time, q=q.copy(), q_dot_minus=q_dot_minus.copy(),
        q_dot_plus=q_dot_plus.copy(), rows=rows,
        kinetic_energy=float(res.kinetic_energy),
        kinetic_energy_constrained=float(res.kinetic_energy_constrained),
        kinetic_energy_admissible=float(res.kinetic_energy_admissible),
        energy_lost=float(res.energy_lost),
        impulse=np.asarray(res.constraint_impulse, dtype=float),
        lock_rows=lock_rows.copy(), lock_velocity_post=lock_rows @ q_dot_plus,
        trailing_normal_velocity=trailing_normal_velocity, trailing_mode=trailing_mode,
    )


def check_initial_state(
    walker: PlanarWalker, q0: ArrayLike, q_dot0: ArrayLike, steps: int,
    schedule: StepSchedule | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The one definition of a valid start of a walk: the state just after a heel strike.

    The stance foot is on the ground (``y = R``) and rolls without slip (``A_R q_dot = 0``),
    every lockable joint of the walker's :meth:`~heelstrike.models.base.PlanarWalker.step_schedule`
    is locked at its angle with zero rate, the state is finite and of length ``n``, and at least
    one step is asked for. Every backend checks it here.

    Returns
    -------
    q, q_dot : ndarray, shape (n,)
        Float copies of the state.

    Raises
    ------
    ValueError
        Naming what is wrong.
    """
    if steps < 1:
        raise ValueError("steps must be >= 1")
    n = walker.n_coordinates
    q = np.array(q0, dtype=float)
    qd = np.array(q_dot0, dtype=float)
    if q.shape != (n,) or qd.shape != (n,):
        raise ValueError(f"q0 and q_dot0 must have shape ({n},)")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        raise ValueError("initial state must be finite")
    R = float(np.asarray(walker.foot_radii[0]))
    if abs(q[1] - R) > 1e-9 or np.max(np.abs(walker.contact_jacobian(q, "right") @ qd)) > 1e-9:
        raise ValueError(
            "initial state must have the stance foot on the ground (y = R) and rolling without "
            "slip (A_R q_dot = 0)"
        )
    sched = walker.step_schedule() if schedule is None else schedule
    for j, a in sched.lock_angles:
        if abs(q[j] - a) > 1e-9 or abs(qd[j]) > 1e-9:
            raise ValueError(
                f"initial state must have {walker.coordinate_names[j]} locked at {a} rad "
                "with zero rate (the state just after a heel strike)"
            )
    return q, qd


def simulate(
    walker: PlanarWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    slope: float = 0.0,
    steps: int = 1,
    torque: TorqueLaw | Callable[[float, FloatArray, FloatArray], FloatArray] | None = None,
    push_off: PushOff | None = None,
    restitution: float = 0.0,
    friction: float | None = None,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
    torque_resets_each_step: bool = True,
    knee_flex_threshold: float = 1e-6,
) -> PhasedWalkResult:
    """Simulate any walker for a number of steps: the one hybrid loop (scipy reference).

    Runs the walker's declared :meth:`~heelstrike.models.base.PlanarWalker.step_schedule`
    (:mod:`heelstrike.models.schedule`): its phases, each integrated with scipy's DOP853
    stage by stage until the stage's guard fires, the knee strikes (an inert impact with
    ``A = [A_R; lock rows]``) and the heel strike (``[A_L; lock rows]`` by the paper's
    projector, eq. 13, with the trailing foot decided by the schedule's rule); then the legs
    are relabelled and the locks reset exactly. The next step is taken by
    :meth:`walker.after_swap() <heelstrike.models.base.PlanarWalker.after_swap>`: the walker
    itself, or for a walker whose legs differ the walker with the other leg in stance (the two
    alternate; each sample's ``mechanical_energy`` is that of the walker taking its step).

    Parameters
    ----------
    walker : PlanarWalker
        The walker model.
    q0, q_dot0 : array_like, shape (n,)
        Initial state just after a heel strike: stance foot on the ground and rolling
        (``A_R q_dot0 = 0``), lockable joints at their lock angles with zero rate.
    slope : float
        Ground slope (rad), downhill towards ``-x``.
    steps : int
        Number of heel strikes to simulate.
    torque : TorqueLaw, optional
        Actuator law in single support ``(time since the step's start, q, q_dot) -> u`` (N m).
    push_off : PushOff, optional
        Impulsive actuation applied just before each heel strike, the schedule's locked
        joints held (e.g. :class:`~heelstrike.dynamics.actuation.PushOff`).
    restitution : float
        Restitution of the heel strike's constrained velocity (0: the paper's inert impact);
        only with the projector's trailing-foot rules (``"lift_rule"``, ``"lift_or_graze"``).
    friction : float, optional
        Coulomb coefficient; if given, a stance foot needing more friction ends the walk.
    max_step_duration : float
        Time bound (s) for one step; exceeding it ends the walk with ``no_heel_strike``.
    rtol, atol : float
        Integrator tolerances.
    max_step : float
        Largest integrator step (s).
    torque_resets_each_step : bool
        Whether the torque law's time restarts at 0 at every step (default) or runs on.
    knee_flex_threshold : float
        The swing knee must flex past this angle (rad) before its strike is looked for.

    Returns
    -------
    PhasedWalkResult
        Every heel strike in ``impacts``, every impact (knee strikes too) in ``events``.
    """
    schedule = walker.step_schedule(knee_flex_threshold=knee_flex_threshold)
    if restitution != 0.0 and schedule.trailing_foot == "complementarity":
        raise ValueError(
            "restitution is only supported with the lift rule for the trailing foot (walkers "
            "whose heel strike resolves the trailing foot by complementarity are inert)"
        )
    q, qd = check_initial_state(walker, q0, q_dot0, steps, schedule)
    n = walker.n_coordinates
    leg_length = float(walker.scale.leg_length)  # velocity scale of the lift rule
    lock_angle = dict(schedule.lock_angles)
    A_lock = np.eye(n)[list(schedule.locks)]

    t_s: list[FloatArray] = []
    q_s: list[FloatArray] = []
    qd_s: list[FloatArray] = []
    w_s: list[FloatArray] = []
    leg_s: list[NDArray[np.int_]] = []
    step_s: list[NDArray[np.int_]] = []
    phase_s: list[NDArray[np.str_]] = []
    records: list[ImpactRecord] = []
    events_out: list[PhasedImpact] = []
    t, work, stance = 0.0, 0.0, 0
    status = WalkStatus.COMPLETED
    message = status.message
    # a walker whose legs differ alternates with the walker after its leg swap
    # (PlanarWalker.after_swap); each step's samples keep the energy of the step's walker
    alternating = walker.after_swap() is not walker
    schedules = {id(walker): schedule}
    energy_s: list[FloatArray] = []

    for k in range(steps):
        t_step, work_start = t, work
        q_start = q.copy()
        law = torque
        if torque is not None and torque_resets_each_step:
            law = _ShiftedTorque(law=torque, t0=t_step)
        t_limit = t_step + max_step_duration
        ended: WalkStatus | None = None
        for phase in schedule.phases:
            sup = SingleSupport(walker=walker, slope=slope, torque=law, locked=phase.locked)
            m = len(sup.free_coordinates)
            i_stage, rearming = 0, False
            while i_stage < len(phase.stages):
                stage = phase.stages[i_stage]
                i_stage += 1
                if stage.skip is not None and not rearming and stage.skip(q, qd):
                    continue
                rearming = False
                q_ref = q.copy()
                x0 = np.concatenate((sup.pack(q, qd), [work]))
                raw = integrate_segment(sup, q_ref, x0, t, t_limit,
                                        _events(sup, q_ref, stage, friction), rtol, atol,
                                        max_step)
                qs, qds = sup.unpack(raw.x[:, : 2 * m], q_ref)
                # a stage that starts where the previous one ended (same step and phase, no
                # impact between) does not repeat its start sample: each state is listed once
                first = int(bool(step_s) and step_s[-1].size > 0 and step_s[-1][-1] == k
                            and phase_s[-1][-1] == phase.name and t_s[-1][-1] == raw.t[0]
                            and np.array_equal(q_s[-1][-1], qs[0])
                            and np.array_equal(qd_s[-1][-1], qds[0]))
                t_s.append(raw.t[first:])
                q_s.append(qs[first:])
                qd_s.append(qds[first:])
                w_s.append(raw.x[first:, -1])
                if alternating:
                    energy_s.append(np.asarray(walker.mechanical_energy(
                        qs[first:], qds[first:], slope)))
                leg_s.append(np.full(len(raw.t) - first, stance))
                step_s.append(np.full(len(raw.t) - first, k))
                phase_s.append(np.full(len(raw.t) - first, phase.name))
                t, q, qd = float(raw.t[-1]), qs[-1].copy(), qds[-1].copy()
                work = float(raw.x[-1, -1])
                ended = _segment_outcome(raw, stage.until.name)
                if ended is not None:
                    ended, message = _ended_message(walker, ended, stage, k, t, qs, qds)
                    break
                if stage.reject is not None and stage.reject(q, qd):
                    i_stage, rearming = 0, True  # not the planned event: arm the guard anew
            if ended is not None or phase.reset == "heel_strike":
                break
            # -- knee strike: inert impact, stance foot rolling, the strike joints lock --------
            for j in phase.strike_joints:
                q[j] = lock_angle[j]  # remove the event-location round-off
            A_R = walker.contact_jacobian(q, "right")
            A = np.vstack((A_R, A_lock))
            res = impact(walker.mass_matrix(q), A, qd)
            qd_plus = np.asarray(res.velocity_post)
            events_out.append(_impact_event("knee_strike", k, t, q, qd, res, A, A_lock,
                                            float((A_R @ qd_plus)[1]), "stick"))
            qd = qd_plus
        if ended is not None:
            status = ended
            break

        # -- heel strike: the leading foot lands, the trailing foot by the schedule's rule -----
        push_work = 0.0
        if push_off is not None:
            qd_p, pw = push_off(walker, q, qd, A_lock)
            qd, push_work = np.asarray(qd_p, dtype=float), float(pw)
            work += push_work
        mode: str
        if schedule.trailing_foot == "complementarity":
            A_R = walker.contact_jacobian(q, "right")
            bilateral = np.vstack((walker.contact_jacobian(q, "left"), A_lock))
            mc = resolve_impact(walker.mass_matrix(q), qd, bilateral,
                                [CandidateContact.from_jacobian(A_R, name="trailing")])
            res, rows, mode = mc.impact, mc.active_rows, mc.modes[0]
            v_trail = float(mc.normal_velocity[0])
            foot_impulse = np.asarray(mc.bilateral_impulse[:2], dtype=float)
        else:
            res, v = heel_strike(walker, q, qd, restitution=restitution, locks=schedule.locks)
            rows = np.vstack((walker.contact_jacobian(q, "left"), A_lock))
            v_trail = float(v)
            mode = "separate" if v_trail >= 0.0 else "penetrating"
            if schedule.trailing_foot == "lift_or_graze" and grazes(
                    v_trail, lift_velocity_scale(leg_length, qd[2:])):
                mode = "graze"
            foot_impulse = np.asarray(res.constraint_impulse, dtype=float)[:2].copy()
        qd_plus = np.asarray(res.velocity_post)
        events_out.append(_impact_event("heel_strike", k, t, q, qd, res, rows, A_lock, v_trail,
                                        mode))
        records.append(
            ImpactRecord.of_step(
                walker, slope, step=k, step_start=(t_step, q_start), time=t, q=q,
                q_dot_minus=qd, q_dot_plus=qd_plus, kinetic_energy=float(res.kinetic_energy),
                kinetic_energy_constrained=float(res.kinetic_energy_constrained),
                kinetic_energy_admissible=float(res.kinetic_energy_admissible),
                energy_lost=float(res.energy_lost), impulse=foot_impulse,
                trailing_normal_velocity=v_trail, actuator_work=work - work_start,
                push_off_work=push_work,
            )
        )
        lifted = lifts(v_trail, lift_velocity_scale(leg_length, qd[2:]))
        if not (mode == "graze" or (mode == "separate" and lifted)):
            status = WalkStatus.TRAILING_FOOT_STAYS
            message = status.message
            qd = qd_plus
            break
        q, qd = walker.swap_legs(q, qd_plus)
        next_walker = walker.after_swap()
        if next_walker is not walker:
            walker = next_walker
            if id(walker) not in schedules:
                schedules[id(walker)] = walker.step_schedule(
                    knee_flex_threshold=knee_flex_threshold)
            schedule = schedules[id(walker)]
            leg_length = float(walker.scale.leg_length)
            lock_angle = dict(schedule.lock_angles)
        for j, a in schedule.lock_angles:  # exact lock angles after relabelling (swap round-off)
            q[j] = a
            qd[j] = 0.0
        stance = 1 - stance

    q_all = np.concatenate(q_s)
    qd_all = np.concatenate(qd_s)
    return PhasedWalkResult(
        status=status,
        message=message,
        t=np.concatenate(t_s),
        q=q_all,
        q_dot=qd_all,
        stance_leg=np.concatenate(leg_s),
        step=np.concatenate(step_s),
        actuator_work=np.concatenate(w_s),
        impacts=tuple(records),
        final_q=np.asarray(q),
        final_q_dot=np.asarray(qd),
        slope=float(slope),
        events=tuple(events_out),
        phase=np.concatenate(phase_s),
        mechanical_energy=(np.concatenate(energy_s) if alternating
                           else np.asarray(walker.mechanical_energy(q_all, qd_all, slope))),
    )
