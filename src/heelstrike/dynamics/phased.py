"""Hybrid simulation of described walkers with several continuous phases and impacts.

For a :class:`~heelstrike.models.builder.BuiltWalker` one step is a sequence of continuous
phases of :class:`~heelstrike.dynamics.single_support.SingleSupport` (the stance foot rolling)
separated by inert impacts resolved with :mod:`heelstrike.core`:

Walkers with lockable joints (knees; McGeer 1990 style, e.g. ``kneed.toml``)
    1. *knee swing*: the stance knee is locked, the swing knee free. The swing knee first flexes
       (``swing_knee > 0``), then straightens; when it reaches its lock angle from flexion the
       **knee strike** is an inert impact with ``A = [A_R; lock rows]`` (the stance foot stays
       rolling, both knees locked), via :func:`heelstrike.core.impact.impact`;
    2. *locked swing*: both knees locked (the walker is a compass gait) until heel strike.
Walkers without lockable joints (``compass.toml``, ``torso.toml``)
    only the locked-swing phase.

Heel strike is looked for only once the stance leg has passed the vertical (stance angle
``> 0``) **and** the swing foot is ahead of the stance foot (its contact point at smaller ``x``)
**and** above the ground; it is then the swing foot's clearance falling through zero. This
excludes the mid-stance scuffing root of the clearance (the classical compass-gait convention:
scuffing of the swing foot near mid-stance is ignored; during the knee-swing phase ground
penetration of the swing foot is ignored too). For the compass gait this is the same event as
:meth:`heelstrike.models.CompassGait.heel_strike_function` (``2 q3 + q4`` rising through 0).

The **heel strike** is resolved with :func:`heelstrike.core.complementarity.resolve_impact`:
bilateral rows ``[A_L; lock rows]`` (the leading foot lands without slip, the knees stay
locked) and the trailing foot ``A_R`` as a unilateral candidate contact. Whether the trailing
foot lifts is *decided* by the complementarity conditions (and its separation velocity must pass
:func:`heelstrike.models._contact.lifts`); if it does not, the walk ends with
:attr:`~heelstrike.dynamics.hybrid.WalkStatus.TRAILING_FOOT_STAYS`. Otherwise the legs are
relabelled (:meth:`~heelstrike.models.base.PlanarWalker.swap_legs`) and the new swing knee is
unlocked.

Every impact (knee strikes too) is reported with ``T``, ``T_c``, ``T_a`` (Font & Kövecses 2008,
eq. 10) in :attr:`PhasedWalkResult.events`; :attr:`PhasedWalkResult.impacts` holds one
:class:`~heelstrike.dynamics.hybrid.ImpactRecord` per heel strike (step-level bookkeeping, as
:func:`heelstrike.dynamics.hybrid.simulate`), so :mod:`heelstrike.analysis.limit_cycle` works
unchanged with ``simulator=simulate_phased``.

Poincare section
----------------
:class:`PhasedWalker` (a :class:`BuiltWalker` with section hooks) uses the state just after heel
strike (legs relabelled): lockable joints at their lock angles with zero rate, stance foot
rolling with its contact point at ``x = 0``, and the ``hip`` coordinate eliminated by the
relation that the trailing (now "left") foot touches the ground (clearance 0). The section
coordinates are the remaining joint angles and all unlocked rates; for ``compass.toml`` these
are exactly :class:`~heelstrike.models.CompassGait`'s ``(q3, q3_dot, q4_dot)``.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.complementarity import CandidateContact, resolve_impact
from heelstrike.core.impact import impact
from heelstrike.dynamics.events import Event
from heelstrike.dynamics.hybrid import (
    ImpactRecord,
    PushOff,
    WalkResult,
    WalkStatus,
    integrate_segment,
)
from heelstrike.dynamics.single_support import SingleSupport, TorqueLaw
from heelstrike.models._contact import lift_velocity_scale, lifts
from heelstrike.models.builder import BuiltWalker, load_walker
from heelstrike.models.description import WalkerDescription

__all__ = [
    "PhasedImpact",
    "PhasedWalkResult",
    "PhasedWalker",
    "TorsoPD",
    "load_phased_walker",
    "simulate_phased",
    "stance_and_swing_locks",
]

ImpactKind = Literal["knee_strike", "heel_strike"]


# -- walker with a Poincare section ------------------------------------------------------------
class PhasedWalker(BuiltWalker):
    """A :class:`BuiltWalker` with a generic post-heel-strike Poincare section.

    See the module docstring for the section. Construct with :func:`load_phased_walker` or
    :meth:`from_built`.

    Parameters
    ----------
    description : WalkerDescription
    use_cache : bool
    **params : float
        Parameter values (scalars: the section is not batched).
    """

    def __init__(
        self, description: WalkerDescription, *, use_cache: bool = True, **params: ArrayLike
    ) -> None:
        super().__init__(description, use_cache=use_cache, **params)
        names = self.coordinate_names
        self.eliminated: int = names.index("hip") if "hip" in names else 3
        lock = set(self.lockable_joints)
        self._section_q = tuple(
            i for i in range(2, len(names)) if i not in lock and i != self.eliminated
        )
        self._section_v = tuple(i for i in range(2, len(names)) if i not in lock)

    @classmethod
    def from_built(cls, walker: BuiltWalker) -> PhasedWalker:
        """The same walker (description and parameter values) with section hooks.

        A described walker that already defines its Poincare section (the walker contract's
        ``description`` and ``has_poincare_section``: a phased walker) is returned as it is.
        """
        if walker.description is not None and walker.has_poincare_section:
            return cast(PhasedWalker, walker)
        return cls(walker.description, **walker.params)

    def replace(self, **params: ArrayLike) -> PhasedWalker:
        """A copy with some parameter values changed (no re-derivation)."""
        merged: dict[str, Any] = dict(self.params)
        merged.update(params)
        return PhasedWalker(self.description, **merged)

    @property
    def section_names(self) -> tuple[str, ...]:
        """Names of the section coordinates: angles (rad) then rates (rad/s)."""
        n = self.coordinate_names
        return tuple(n[i] for i in self._section_q) + tuple(f"{n[i]}_dot" for i in self._section_v)

    def touchdown_configuration(self, q: ArrayLike) -> FloatArray:
        """``q`` with the eliminated (hip) coordinate solved for zero swing-foot clearance.

        Newton's method from the symmetric guess ``hip = -2 q[2]`` (exact for straight
        symmetric legs), so the root found is the swing foot ahead, not the mid-stance one.

        Parameters
        ----------
        q : array_like, shape (n,)

        Returns
        -------
        ndarray, shape (n,)
        """
        q_ = np.array(q, dtype=float)
        j = self.eliminated
        q_[j] = -2.0 * q_[2]
        for _ in range(50):
            f = float(self.foot_clearance(q_, "left"))
            h = 1e-7
            qp, qm = q_.copy(), q_.copy()
            qp[j] += h
            qm[j] -= h
            fp, fm = self.foot_clearance(qp, "left"), self.foot_clearance(qm, "left")
            df = (float(fp) - float(fm)) / (2 * h)
            if df == 0.0:
                break
            step = f / df
            q_[j] -= step
            if abs(step) < 1e-15:
                break
        return q_

    def section_to_state(self, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Post-heel-strike ``(q, q_dot)``, each shape (n,), from section coordinates ``z``."""
        z_ = np.asarray(z, dtype=float)
        nq, nv = len(self._section_q), len(self._section_v)
        if z_.shape != (nq + nv,):
            raise ValueError(f"z must have shape ({nq + nv},): {self.section_names}")
        n = self.n_coordinates
        R = float(np.asarray(self.foot_radii[0]))
        q = np.zeros(n)
        q[1] = R
        for j, a in zip(self.lockable_joints, self.lock_angles, strict=True):
            q[j] = float(a)
        q[list(self._section_q)] = z_[:nq]
        q = self.touchdown_configuration(q)
        qd = np.zeros(n)
        qd[list(self._section_v)] = z_[nq:]
        qd[0] = -R * qd[2]
        return q, qd

    def state_to_section(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Section coordinates of a post-heel-strike state, shape (d,)."""
        q_, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        return np.concatenate(
            (q_[..., list(self._section_q)], qd[..., list(self._section_v)]), axis=-1
        )


def load_phased_walker(
    name_or_path: str | os.PathLike[str], **params: ArrayLike
) -> PhasedWalker:
    """:func:`~heelstrike.models.builder.load_walker` returning a :class:`PhasedWalker`."""
    return PhasedWalker.from_built(load_walker(name_or_path, **params))  # type: ignore[arg-type]


def check_initial_state(
    walker: BuiltWalker, q0: ArrayLike, q_dot0: ArrayLike, steps: int
) -> tuple[FloatArray, FloatArray]:
    """The one definition of a valid start of a phased walk: the state just after a heel strike.

    The stance foot is on the ground (``y = R``) and rolls without slip (``A_R q_dot = 0``),
    every lockable joint is locked at its angle with zero rate, the state is finite and of
    length ``n``, and at least one step is asked for. Both backends
    (:func:`simulate_phased`, :func:`~heelstrike.dynamics.compiled_phased.simulate_phased_compiled`)
    check it here.

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
    for j, a in zip(walker.lockable_joints, walker.lock_angles, strict=True):
        if abs(q[j] - float(a)) > 1e-9 or abs(qd[j]) > 1e-9:
            raise ValueError(
                f"initial state must have {walker.coordinate_names[j]} locked at {float(a)} rad "
                "with zero rate (the state just after a heel strike)"
            )
    return q, qd


def stance_and_swing_locks(walker: BuiltWalker) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """Split the lockable joints into stance-leg and swing-leg ones.

    Along the kinematic chain from the stance foot's link to the swing foot's link, a joint is
    on the stance side if its link's mirror comes later in the chain (e.g. the stance knee's
    ``stance_thigh`` before ``swing_thigh``), else on the swing side. Lockable joints off that
    chain count as swing-side.

    Returns
    -------
    stance, swing : tuple of int
        Coordinate indices.
    """
    desc = walker.description
    links = {lk.name: lk for lk in desc.links}
    chain: list[str] = []
    name: str | None = desc.feet[1].link
    while name is not None:
        chain.append(name)
        name = links[name].parent
    chain.reverse()
    index = {lk.name: 3 + k for k, lk in enumerate(desc.links[1:])}
    stance: list[int] = []
    swing: list[int] = []
    for j in walker.lockable_joints:
        lk = next(lk for lk in desc.links[1:] if index[lk.name] == j)
        if (
            lk.name in chain
            and lk.mirror in chain
            and chain.index(lk.mirror) > chain.index(lk.name)
        ):
            stance.append(j)
        else:
            swing.append(j)
    return tuple(stance), tuple(swing)


# -- torque law for the torso walker ------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class TorsoPD:
    """Hold a torso up by a PD torque across its joint (reaction on the stance leg).

    .. math:: u_{torso} = -k_p (\\theta_{torso} - \\theta_{ref}) - k_d \\dot\\theta_{torso},
              \\qquad \\theta_{torso} = q_2 + q_{torso},

    with ``theta_torso`` the torso's absolute angle from the ground normal (rad, positive leaning
    towards ``-x``, the walking direction). Other actuated joints (the hip) get zero torque.

    Parameters
    ----------
    walker : BuiltWalker
        Must have an actuated joint named ``torso`` (its coordinate is relative to the stance
        leg, whose absolute angle is ``q[2]``).
    angle : float
        ``theta_ref`` (rad); a forward lean (> 0) feeds energy in through the stance leg.
    kp : float
        Stiffness (N m / rad).
    kd : float
        Damping (N m s / rad).
    """

    walker: BuiltWalker
    angle: float = 0.0
    kp: float = 300.0
    kd: float = 30.0

    def __call__(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray:
        j = self.walker.joint_index("torso")
        col = self.walker.actuated_joints.index(j)
        q_, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        theta = q_[..., 2] + q_[..., j]
        omega = qd[..., 2] + qd[..., j]
        u = np.zeros((*q_.shape[:-1], len(self.walker.actuated_joints)))
        u[..., col] = -self.kp * (theta - self.angle) - self.kd * omega
        return u


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
        lifts). Knee strike: ``"stick"`` (the stance foot is bilateral).
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

    def step_losses(self, step: int) -> FloatArray:
        """``T_c`` (J) of every impact of one step, in order."""
        return np.asarray([e.kinetic_energy_constrained for e in self.events if e.step == step])


# -- integration -------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class _Shifted:
    law: TorqueLaw | Callable[[float, FloatArray, FloatArray], FloatArray]
    t0: float

    def __call__(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray:
        return np.asarray(self.law(t - self.t0, q, q_dot))


@dataclass(frozen=True, kw_only=True)
class _Seg:
    t: FloatArray
    q: FloatArray
    qd: FloatArray
    w: FloatArray
    event: str | None
    failed: bool


def _segment_outcome(seg: _Seg, want: str) -> WalkStatus | None:
    """Status that ends the walk after a segment, or None if it ended with the wanted event."""
    if seg.failed:
        return WalkStatus.INTEGRATION_FAILED
    if seg.event is None:
        return WalkStatus.NO_HEEL_STRIKE
    if seg.event != want:
        return WalkStatus(seg.event)
    return None


def _run_phase(
    sup: SingleSupport,
    q: FloatArray,
    qd: FloatArray,
    work: float,
    t0: float,
    t_end: float,
    events: Sequence[Event],
    rtol: float,
    atol: float,
    max_step: float,
) -> _Seg:
    q_ref = q.copy()
    x0 = np.concatenate((sup.pack(q, qd), [work]))
    m = len(sup.free_coordinates)
    seg = integrate_segment(sup, q_ref, x0, t0, t_end, list(events), rtol, atol, max_step)
    qs, qds = sup.unpack(seg.x[:, : 2 * m], q_ref)
    return _Seg(t=seg.t, q=qs, qd=qds, w=seg.x[:, -1], event=seg.event, failed=seg.failed)


def simulate_phased(
    walker: BuiltWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    slope: float = 0.0,
    steps: int = 1,
    torque: TorqueLaw | Callable[[float, FloatArray, FloatArray], FloatArray] | None = None,
    push_off: PushOff | None = None,
    friction: float | None = None,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
    knee_flex_threshold: float = 1e-6,
) -> PhasedWalkResult:
    """Simulate a described walker through knee strikes and heel strikes.

    Parameters
    ----------
    walker : BuiltWalker
        The walker (a plain :class:`BuiltWalker` or a :class:`PhasedWalker`).
    q0, q_dot0 : array_like, shape (n,)
        Initial state just after a heel strike: stance foot on the ground and rolling,
        lockable joints at their lock angles (the swing knee is released at once).
    slope : float
        Ground slope (rad), downhill towards ``-x``.
    steps : int
        Number of heel strikes to simulate.
    torque : TorqueLaw, optional
        Actuator law ``(t since step start, q, q_dot) -> u`` (N m), shape ``(n_u,)``.
    push_off : PushOff, optional
        Impulsive actuation applied just before each heel strike (e.g.
        :class:`heelstrike.dynamics.actuation.PushOff`).
    friction : float, optional
        Coulomb coefficient; a stance foot needing more ends the walk (``slipped``).
    max_step_duration : float
        Time bound of one step (s).
    rtol, atol, max_step : float
        Integrator (DOP853) settings.
    knee_flex_threshold : float
        The swing knee must flex past this angle (rad) before its strike is looked for.

    Returns
    -------
    PhasedWalkResult
    """
    q, qd = check_initial_state(walker, q0, q_dot0, steps)
    n = walker.n_coordinates
    leg_length = float(walker.scale.leg_length)  # velocity scale of the lift rule
    stance_locks, swing_locks = stance_and_swing_locks(walker)
    all_locks = stance_locks + swing_locks
    A_lock = walker.lock_jacobian(all_locks) if all_locks else np.zeros((0, n))

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

    def lock_angle(j: int) -> float:
        return float(walker.lock_angles[walker.lockable_joints.index(j)])

    for k in range(steps):
        t_step, work_start = t, work
        V_start = float(walker.potential_energy(q, slope))
        q_start = q.copy()
        law = None if torque is None else _Shifted(law=torque, t0=t_step)
        t_limit = t_step + max_step_duration

        def make(locked: tuple[int, ...], _law: Any = law) -> SingleSupport:
            return SingleSupport(walker=walker, slope=slope, torque=_law, locked=locked)

        def common(sup: SingleSupport, q_ref: FloatArray) -> list[Event]:
            m = len(sup.free_coordinates)

            def normal(tt: float, x: FloatArray) -> float:
                return float(sup.ground_reaction(tt, *sup.unpack(x[: 2 * m], q_ref))[1])

            evs = [
                Event(name="lost_contact", function=normal, direction=-1),
                Event(name="fell_forward", function=lambda tt, x: x[0] - 0.5 * np.pi, direction=1),
                Event(
                    name="fell_backward",
                    function=lambda tt, x: float(x[m]) if x[0] < 0.0 else (1.0 + float(x[0])),
                    direction=-1,
                ),
            ]
            if friction is not None:
                mu = float(friction)

                def slip(tt: float, x: FloatArray) -> float:
                    lam = sup.ground_reaction(tt, *sup.unpack(x[: 2 * m], q_ref))
                    return float(mu * lam[1] - abs(lam[0]))

                evs.append(Event(name="slipped", function=slip, direction=-1))
            return evs

        ended: WalkStatus | None = None

        def record(seg: _Seg, label: str, _k: int = k, _leg: int = stance) -> None:
            t_s.append(seg.t)
            q_s.append(seg.q)
            qd_s.append(seg.qd)
            w_s.append(seg.w)
            leg_s.append(np.full(len(seg.t), _leg))
            step_s.append(np.full(len(seg.t), _k))
            phase_s.append(np.full(len(seg.t), label))

        # -- knee swing: stance knee locked, swing knee free until knee strike -----------------
        if swing_locks:
            sup = make(stance_locks)
            idx = [sup.free_coordinates.index(j) for j in swing_locks]
            m = len(sup.free_coordinates)

            def flex(tt: float, x: FloatArray, _i: list[int] = idx) -> float:
                return float(min(x[i] - lock_angle(swing_locks[c]) for c, i in enumerate(_i)))

            stages = [
                ("knee_flexed", Event(name="knee_flexed",
                                      function=lambda tt, x: flex(tt, x) - knee_flex_threshold,
                                      direction=1)),
                ("knee_strike", Event(name="knee_strike", function=flex, direction=-1)),
            ]
            for want, ev in stages:
                seg = _run_phase(sup, q, qd, work, t, t_limit, [ev, *common(sup, q)], rtol, atol,
                                 max_step)
                record(seg, "knee_swing")
                t, q, qd = float(seg.t[-1]), seg.q[-1].copy(), seg.qd[-1].copy()
                work = float(seg.w[-1])
                ended = _segment_outcome(seg, want)
                if ended is not None:
                    break
            del m
            if ended is None:
                # knee strike: inert impact, stance foot rolling, both knees locked
                for j in swing_locks:
                    q[j] = lock_angle(j)  # remove the event-location round-off
                A_R = walker.contact_jacobian(q, "right")
                A = np.vstack((A_R, A_lock))
                M = walker.mass_matrix(q)
                res = impact(M, A, qd)
                qd_plus = np.asarray(res.velocity_post)
                events_out.append(
                    PhasedImpact(
                        kind="knee_strike", step=k, time=t, q=q.copy(), q_dot_minus=qd.copy(),
                        q_dot_plus=qd_plus.copy(), rows=A,
                        kinetic_energy=float(res.kinetic_energy),
                        kinetic_energy_constrained=float(res.kinetic_energy_constrained),
                        kinetic_energy_admissible=float(res.kinetic_energy_admissible),
                        energy_lost=float(res.energy_lost),
                        impulse=np.asarray(res.constraint_impulse, dtype=float),
                        lock_rows=A_lock.copy(), lock_velocity_post=A_lock @ qd_plus,
                        trailing_normal_velocity=float((A_R @ qd_plus)[1]),
                        trailing_mode="stick",
                    )
                )
                qd = qd_plus

        # -- locked swing until heel strike (guarded against mid-stance scuffing) -------------
        if ended is None:
            sup = make(all_locks)
            m = len(sup.free_coordinates)

            def armed(
                tt: float, x: FloatArray, _q: FloatArray, _s: SingleSupport = sup, _m: int = m
            ) -> float:
                qq, _ = _s.unpack(x[: 2 * _m], _q)
                xr, xl = walker.contact_point(qq, "right")[0], walker.contact_point(qq, "left")[0]
                ahead = float(xr - xl)
                return float(min(x[0], ahead, float(walker.foot_clearance(qq, "left"))))

            def strike(
                tt: float, x: FloatArray, _q: FloatArray, _s: SingleSupport = sup, _m: int = m
            ) -> float:
                qq, _ = _s.unpack(x[: 2 * _m], _q)
                return float(-walker.foot_clearance(qq, "left"))

            for want in ("armed", "heel_strike"):
                q_ref = q.copy()
                x_now = np.concatenate((sup.pack(q, qd), [work]))
                if want == "armed" and armed(t, x_now, q_ref) > 0.0:
                    continue
                fn = armed if want == "armed" else strike

                def ev_fn(
                    tt: float, x: FloatArray, _f: Any = fn, _r: FloatArray = q_ref
                ) -> float:
                    return float(_f(tt, x, _r))

                ev = Event(name=want, function=ev_fn, direction=1)
                seg = _run_phase(sup, q, qd, work, t, t_limit, [ev, *common(sup, q_ref)], rtol,
                                 atol, max_step)
                record(seg, "locked_swing")
                t, q, qd = float(seg.t[-1]), seg.q[-1].copy(), seg.qd[-1].copy()
                work = float(seg.w[-1])
                ended = _segment_outcome(seg, want)
                if ended is not None:
                    break
        if ended is not None:
            status = ended
            break

        # -- heel strike: leading foot lands, trailing foot decided by complementarity ---------
        push_work = 0.0
        if push_off is not None:
            qd_p, pw = push_off(walker, q, qd)
            qd, push_work = np.asarray(qd_p, dtype=float), float(pw)
            work += push_work
        M = walker.mass_matrix(q)
        A_L = walker.contact_jacobian(q, "left")
        A_R = walker.contact_jacobian(q, "right")
        bil = np.vstack((A_L, A_lock))
        mc = resolve_impact(M, qd, bil, [CandidateContact.from_jacobian(A_R, name="trailing")])
        res = mc.impact
        qd_plus = np.asarray(res.velocity_post)
        v_trail = float(mc.normal_velocity[0])
        events_out.append(
            PhasedImpact(
                kind="heel_strike", step=k, time=t, q=q.copy(), q_dot_minus=qd.copy(),
                q_dot_plus=qd_plus.copy(), rows=mc.active_rows,
                kinetic_energy=float(res.kinetic_energy),
                kinetic_energy_constrained=float(res.kinetic_energy_constrained),
                kinetic_energy_admissible=float(res.kinetic_energy_admissible),
                energy_lost=float(res.energy_lost),
                impulse=np.asarray(res.constraint_impulse, dtype=float),
                lock_rows=A_lock.copy(), lock_velocity_post=A_lock @ qd_plus,
                trailing_normal_velocity=v_trail, trailing_mode=mc.modes[0],
            )
        )
        records.append(
            ImpactRecord(
                step=k, time=t, q=q.copy(), q_dot_minus=qd.copy(), q_dot_plus=qd_plus.copy(),
                impact_angle=float(q[2]),
                kinetic_energy=float(res.kinetic_energy),
                kinetic_energy_constrained=float(res.kinetic_energy_constrained),
                kinetic_energy_admissible=float(res.kinetic_energy_admissible),
                energy_lost=float(res.energy_lost),
                impulse=np.asarray(mc.bilateral_impulse[:2], dtype=float),
                step_length=float(walker.step_length(q_start, q)),
                trailing_normal_velocity=v_trail,
                potential_energy_released=V_start - float(walker.potential_energy(q, slope)),
                actuator_work=work - work_start,
                push_off_work=push_work,
                step_duration=t - t_step,
            )
        )
        lifted = lifts(v_trail, lift_velocity_scale(leg_length, qd[2:]))
        if mc.modes[0] != "separate" or not lifted:
            status = WalkStatus.TRAILING_FOOT_STAYS
            qd = qd_plus
            break
        q, qd = walker.swap_legs(q, qd_plus)
        for j in all_locks:  # exact lock angles after relabelling (round-off of the swap)
            q[j] = lock_angle(j)
            qd[j] = 0.0
        stance = 1 - stance

    t_all = np.concatenate(t_s)
    q_all = np.concatenate(q_s)
    qd_all = np.concatenate(qd_s)
    return PhasedWalkResult(
        status=status,
        message=status.message,
        t=t_all,
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
        mechanical_energy=np.asarray(walker.mechanical_energy(q_all, qd_all, slope)),
    )
