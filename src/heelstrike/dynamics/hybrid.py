"""Hybrid walking simulation: single support, heel strike by the paper's projector, leg swap.

One step is integrated in two phases with scipy's ``solve_ivp`` (DOP853):

1. *before mid-stance* (stance angle ``q3 < 0``) until ``q3`` rises through 0; if the stance leg
   stops and rolls back first, the walker has fallen backward;
2. *after mid-stance* until the walker's heel-strike function rises through zero (the swing
   foot lands ahead of the stance foot).

**Scuffing convention.** A rigid straight-legged compass gait's swing foot passes through the
ground near mid-stance, when the legs are nearly parallel. As is classical for the compass gait
(Goswami et al. 1998; Garcia et al. 1998), this is ignored: a heel strike is only looked for
after mid-stance, and the compass walker's event function ``2 q3 + q4`` has no root at the
scuffing configuration ``q4 = 0``.

At heel strike the impact is resolved with :func:`heel_strike` (``q_dot+ = P_a q_dot-`` with the
striking foot's Jacobian, eq. 13), the trailing foot must lift (its contact point's normal
velocity after impact must be positive: :func:`heelstrike.models._contact.lifts`, relative to
``l sum |q_dot-|``), and the legs are relabelled.

Failures are reported in :attr:`WalkResult.status`, never raised from inside the integrator.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.impact import ImpactResult, impact
from heelstrike.dynamics.events import Event, to_scipy
from heelstrike.dynamics.single_support import SingleSupport, TorqueLaw
from heelstrike.models._contact import lift_velocity_scale, lifts
from heelstrike.models.base import PlanarWalker

__all__ = [
    "GroundReaction",
    "ImpactRecord",
    "PushOff",
    "WalkResult",
    "WalkStatus",
    "heel_strike",
    "simulate",
]

#: An impulsive actuation applied just before heel strike: ``(walker, q, q_dot) ->
#: (q_dot_after, work)``; the work (J) is what the actuator does on the walker.
PushOff = Callable[[PlanarWalker, FloatArray, FloatArray], tuple[FloatArray, float]]


class WalkStatus(StrEnum):
    """How a simulation ended: the one status vocabulary of every backend.

    Each member is its string name (a :class:`~enum.StrEnum`, so ``status == "completed"``
    holds), carries a human-readable ``message`` and a stable integer ``code``: the
    code the compiled (numba) kernels write and ensemble results store (:meth:`from_code`
    converts back). Codes never change meaning; new statuses get new codes.

    ``NO_CONSISTENT_ASSIGNMENT`` and ``NO_LEG_SWAP`` are reported by the compiled phased
    kernels only and raised as errors by their Python wrappers, as the scipy backend does.
    """

    code: int
    message: str

    # Members are defined as ``value, code, message``; ``WalkStatus("completed")`` looks a
    # member up by value (the defaults only let type checkers accept that call).
    def __new__(cls, value: str, code: int = -1, message: str = "") -> WalkStatus:
        obj = str.__new__(cls, value)
        obj._value_ = value
        obj.code = code
        obj.message = message
        return obj

    COMPLETED = "completed", 0, "all requested steps were taken"
    FELL_FORWARD = "fell_forward", 1, "the stance leg fell forward to the ground"
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
        "the ground's normal force on the stance foot became negative",
    )
    SLIPPED = "slipped", 5, "the stance foot needs more friction than the given coefficient"
    NO_HEEL_STRIKE = (
        "no_heel_strike",
        6,
        "no heel strike (or knee strike) within the time bound of a step",
    )
    INTEGRATION_FAILED = "integration_failed", 7, "the integrator failed"
    NO_CONSISTENT_ASSIGNMENT = (
        "no_consistent_assignment",
        8,
        "no consistent contact assignment at an impact (rank-deficient constraints?)",
    )
    NO_LEG_SWAP = "no_leg_swap", 9, "no leg swap: the walker declares no link mirrors"

    @classmethod
    def from_code(cls, code: int) -> WalkStatus:
        """The member with integer code ``code`` (as written by the compiled kernels).

        Raises
        ------
        ValueError
            If no status has that code.
        """
        try:
            return _BY_CODE[int(code)]
        except (KeyError, TypeError, ValueError):
            raise ValueError(f"no walk status has code {code!r}") from None

    @classmethod
    def names_by_code(cls) -> tuple[str, ...]:
        """Status names indexed by code: ``names_by_code()[s.code] == s.value``."""
        return tuple(_BY_CODE[c].value for c in range(len(_BY_CODE)))


_BY_CODE: dict[int, WalkStatus] = {s.code: s for s in WalkStatus}
if sorted(_BY_CODE) != list(range(len(WalkStatus))):  # pragma: no cover - definition check
    raise RuntimeError("WalkStatus codes must be 0, 1, ... without gaps or repeats")


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
    argument is the time since the start of each step.
    """
    if torque is None:
        passive = SingleSupport(walker=walker, slope=walk.slope)
        lam = passive.ground_reaction(0.0, walk.q, walk.q_dot)
    else:
        starts = {int(k): float(walk.t[walk.step == k][0]) for k in np.unique(walk.step)}
        sup = SingleSupport(walker=walker, slope=walk.slope, torque=torque)
        lam = np.array(
            [
                sup.ground_reaction(float(t) - starts[int(k)], q, qd)
                for t, k, q, qd in zip(walk.t, walk.step, walk.q, walk.q_dot, strict=True)
            ]
        ).reshape(-1, 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(lam[:, 1] > 0, np.abs(lam[:, 0]) / lam[:, 1], np.inf)
    return GroundReaction(
        t=walk.t, tangential=lam[:, 0], normal=lam[:, 1], required_friction=mu
    )


def heel_strike(
    walker: PlanarWalker,
    q: ArrayLike,
    q_dot: ArrayLike,
    *,
    restitution: float = 0.0,
) -> tuple[ImpactResult, FloatArray]:
    """Resolve the left foot's heel strike with the paper's projector.

    Parameters
    ----------
    walker : PlanarWalker
    q, q_dot : array_like, shape (..., n)
        Pre-impact state (stance foot labelled "right").
    restitution : float
        Restitution of the constrained velocity (0: inert, the paper).

    Returns
    -------
    result : ImpactResult
        The decomposition with ``A = A_L(q)``.
    trailing_normal_velocity : ndarray, shape (...)
        Normal velocity of the trailing ("right") foot's contact point after impact (m/s).
    """
    M = walker.mass_matrix(q)
    A = walker.contact_jacobian(q, "left")
    res = impact(M, A, q_dot, restitution=restitution)
    A_R = walker.contact_jacobian(q, "right")
    v_trailing = np.einsum("...ij,...j->...i", A_R, res.velocity_post)[..., 1]
    return res, np.asarray(v_trailing)


#: Events of the stance foot's contact (normal force, friction cone), checked at the start of
#: every integrated segment as well as for sign changes.
CONTACT_EVENTS: tuple[str, ...] = (WalkStatus.LOST_CONTACT.value, WalkStatus.SLIPPED.value)


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


@dataclass(frozen=True, kw_only=True)
class _ShiftedTorque:
    """A torque law whose clock restarts at ``t0`` (the start of a step)."""

    law: TorqueLaw
    t0: float

    def __call__(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray:
        return self.law(t - self.t0, q, q_dot)


def _step_events(
    walker: PlanarWalker,
    support: SingleSupport,
    q_ref: FloatArray,
    friction: float | None,
    *,
    before: bool,
) -> list[list[Event]]:
    """Events of each phase of one step: the phase's own, then the contact checks common to
    both phases (:data:`CONTACT_EVENTS`)."""
    m = len(support.free_coordinates)

    def state(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        return support.unpack(x[: 2 * m], q_ref)

    def normal(t: float, x: FloatArray) -> float:
        return float(support.ground_reaction(t, *state(x))[1])

    common = [Event(name="lost_contact", function=normal, direction=-1)]
    if friction is not None:
        mu = float(friction)

        def slip(t: float, x: FloatArray) -> float:
            lam = support.ground_reaction(t, *state(x))
            return float(mu * lam[1] - abs(lam[0]))

        common.append(Event(name="slipped", function=slip, direction=-1))

    def strike(t: float, x: FloatArray) -> float:
        return float(walker.heel_strike_function(state(x)[0]))

    phases: list[list[Event]] = []
    if before:
        phases.append(
            [
                Event(name="midstance", function=lambda t, x: x[0], direction=1),
                Event(name="fell_backward", function=lambda t, x: x[m], direction=-1),
                *common,
            ]
        )
    phases.append(
        [
            Event(name="heel_strike", function=strike, direction=1),
            Event(name="fell_backward", function=lambda t, x: x[0], direction=-1),
            Event(name="fell_forward", function=lambda t, x: x[0] - 0.5 * np.pi, direction=1),
            *common,
        ]
    )
    return phases


def simulate(
    walker: PlanarWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    slope: float = 0.0,
    steps: int = 1,
    torque: TorqueLaw | None = None,
    push_off: PushOff | None = None,
    restitution: float = 0.0,
    friction: float | None = None,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
    torque_resets_each_step: bool = True,
) -> WalkResult:
    """Simulate a walker for a number of steps.

    Parameters
    ----------
    walker : PlanarWalker
        The walker model.
    q0, q_dot0 : array_like, shape (n,)
        Initial state with the stance foot on the ground and rolling (``A_R q_dot0 = 0``).
    slope : float
        Ground slope (rad), downhill towards ``-x``.
    steps : int
        Number of heel strikes to simulate.
    torque : TorqueLaw, optional
        Actuator law in single support (time since the step's start, q, q_dot) -> u.
    push_off : PushOff, optional
        Impulsive actuation applied just before each heel strike.
    restitution : float
        Restitution of the heel strike's constrained velocity (0: the paper's inert impact).
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

    Returns
    -------
    WalkResult
    """
    if steps < 1:
        raise ValueError("steps must be >= 1")
    q = np.array(q0, dtype=float)
    qd = np.array(q_dot0, dtype=float)
    n = walker.n_coordinates
    if q.shape != (n,) or qd.shape != (n,):
        raise ValueError(f"q0 and q_dot0 must have shape ({n},)")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        raise ValueError("initial state must be finite")
    support = SingleSupport(walker=walker, slope=slope, torque=torque)
    m = len(support.free_coordinates)
    R = float(np.asarray(walker.foot_radii[0]))
    leg_length = float(walker.scale.leg_length)  # velocity scale of the lift rule
    if abs(q[1] - R) > 1e-9 or np.max(np.abs(walker.contact_jacobian(q, "right") @ qd)) > 1e-9:
        raise ValueError(
            "initial state must have the stance foot on the ground (q2 = R) and rolling "
            "without slip (q1_dot = -R q3_dot, q2_dot = 0)"
        )

    ts: list[FloatArray] = []
    xs: list[FloatArray] = []
    qrefs: list[FloatArray] = []
    legs: list[NDArray[np.int_]] = []
    step_ids: list[NDArray[np.int_]] = []
    impacts: list[ImpactRecord] = []
    t = 0.0
    work = 0.0
    stance = 0
    status = WalkStatus.COMPLETED

    for k in range(steps):
        q_ref = q.copy()
        t_step = t
        x = np.concatenate((support.pack(q, qd), [work]))
        V_start = float(walker.potential_energy(q, slope))
        work_start = work
        step_support = support
        if torque is not None and torque_resets_each_step:
            step_support = SingleSupport(
                walker=walker, slope=slope, torque=_ShiftedTorque(law=torque, t0=t_step)
            )
        phases = _step_events(walker, step_support, q_ref, friction, before=x[0] < 0.0)
        t_limit = t_step + max_step_duration
        ended: WalkStatus | None = None
        for events in phases:
            seg = integrate_segment(
                step_support, q_ref, x, t, t_limit, events, rtol, atol, max_step
            )
            ts.append(seg.t)
            xs.append(seg.x)
            qrefs.append(np.broadcast_to(q_ref, (len(seg.t), n)))
            legs.append(np.full(len(seg.t), stance))
            step_ids.append(np.full(len(seg.t), k))
            t, x = float(seg.t[-1]), seg.x[-1].copy()
            if seg.failed:
                ended = WalkStatus.INTEGRATION_FAILED
                break
            if seg.event is None:
                ended = WalkStatus.NO_HEEL_STRIKE
                break
            if seg.event not in ("midstance", "heel_strike"):
                ended = WalkStatus(seg.event)
                break
        work = float(x[-1])
        if ended is not None:
            status = ended
            q, qd = step_support.unpack(x[: 2 * m], q_ref)
            break

        # -- heel strike -----------------------------------------------------------------------
        q, qd = step_support.unpack(x[: 2 * m], q_ref)
        push_work = 0.0
        if push_off is not None:
            qd, push_work = push_off(walker, q, qd)
            qd = np.asarray(qd, dtype=float)
            work += float(push_work)
        res, v_trailing = heel_strike(walker, q, qd, restitution=restitution)
        qd_plus = np.asarray(res.velocity_post)
        impacts.append(
            ImpactRecord(
                step=k,
                time=t,
                q=q.copy(),
                q_dot_minus=qd.copy(),
                q_dot_plus=qd_plus.copy(),
                impact_angle=float(q[2]),
                kinetic_energy=float(res.kinetic_energy),
                kinetic_energy_constrained=float(res.kinetic_energy_constrained),
                kinetic_energy_admissible=float(res.kinetic_energy_admissible),
                energy_lost=float(res.energy_lost),
                impulse=np.asarray(res.constraint_impulse, dtype=float).copy(),
                step_length=float(walker.step_length(q_ref, q)),
                trailing_normal_velocity=float(v_trailing),
                potential_energy_released=V_start - float(walker.potential_energy(q, slope)),
                actuator_work=work - work_start,
                push_off_work=float(push_work),
                step_duration=t - t_step,
            )
        )
        if not lifts(float(v_trailing), lift_velocity_scale(leg_length, qd[2:])):
            status = WalkStatus.TRAILING_FOOT_STAYS
            qd = qd_plus
            break
        q, qd = walker.swap_legs(q, qd_plus)
        stance = 1 - stance

    t_all = np.concatenate(ts)
    x_all = np.concatenate(xs)
    ref_all = np.concatenate(qrefs)
    q_all, qd_all = support.unpack(x_all[:, : 2 * m], ref_all)
    return WalkResult(
        status=status,
        message=status.message,
        t=t_all,
        q=q_all,
        q_dot=qd_all,
        stance_leg=np.concatenate(legs),
        step=np.concatenate(step_ids),
        actuator_work=x_all[:, -1],
        impacts=tuple(impacts),
        final_q=np.asarray(q),
        final_q_dot=np.asarray(qd),
        slope=float(slope),
    )
