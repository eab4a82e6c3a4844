"""Contacts of a robot with flat ground (world ``z`` up) and its impact with per-contact laws.

A contact is a frame of the robot and a type:

``point`` (3 rows)
    the frame origin's linear velocity ``(x, y, z)``; normal row ``z``, tangential ``x, y``.
``arc`` (3 rows, radius ``R``)
    an arc heel: the material point a distance ``R`` below the frame origin along the ground
    normal, ``v + omega x (-R e_z)``; the frame sits at the arc's centre. ``R = 0`` is ``point``.
``flat`` (6 rows)
    a sole flat on the ground: the frame's linear and angular velocity ``(x, y, z, wx, wy, wz)``;
    normal rows ``z, wx, wy`` (the principal one is ``z``), tangential rows ``x, y, wz`` (the
    twist weighted by ``1 / torsion_radius`` in the friction cone).

All rows come from the frame Jacobian in ``LOCAL_WORLD_ALIGNED`` (origin at the frame, axes of
the world), so impulses are world-aligned forces (N s) and moments about the frame origin
(N m s). The impact laws are :mod:`heelstrike.core.contact_laws` (which knows no robot) and
:func:`heelstrike.core.impact.impact` for the batched inert (paper) law with its projectors.

Speed: one ``crba`` and one ``computeJointJacobians`` per configuration, then one frame Jacobian
per contact, on the robot's reused ``Data``. With only persistent contacts (the paper's inert
law) :func:`robot_impact` takes the direct path :func:`heelstrike.core.contact_laws.
inert_contact_impact` (Cholesky factorizations, no complementarity machinery) and
:func:`inert_energy_split_batch` its batched form; the complementarity solver runs only when a
striking contact's friction, restitution or separation has to be decided.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.contact_laws import (
    ContactImpact,
    ContactLaw,
    ContactRows,
    InertImpactBatch,
    InertLayout,
    check_inert_batch,
    inert_contact_impact,
    inert_contact_impact_batch,
    resolve_contact_impact,
)
from heelstrike.core.impact import ImpactInputError, ImpactResult, impact
from heelstrike.robots.loading import Robot, RobotError, _pin, real_array

__all__ = [
    "ContactKind",
    "ContactSpec",
    "RobotImpact",
    "centre_of_pressure",
    "contact_heights",
    "contact_jacobian",
    "ground_admissible",
    "inert_energy_split_batch",
    "inert_impact_batch",
    "mass_matrices_and_jacobians",
    "parse_contact",
    "robot_impact",
    "robot_matrices",
]

ContactKind = Literal["point", "flat", "arc"]
_ROWS = {"point": 3, "arc": 3, "flat": 6}


@dataclass(frozen=True, kw_only=True)
class ContactSpec:
    """A contact of a robot frame with the ground.

    Parameters
    ----------
    frame : str
        Frame name in the robot model.
    kind : {"point", "flat", "arc"}
        Contact type (module doc).
    radius : float
        Arc heel radius (m), ``kind="arc"`` only, >= 0.
    torsion_radius : float
        Flat contacts: radius (m) of the torsional friction limit, ``|tau_z| <= rho mu f_z``
        on the cone's boundary, > 0.
    """

    frame: str
    kind: ContactKind = "point"
    radius: float = 0.0
    torsion_radius: float = 0.05

    def __post_init__(self) -> None:
        if self.kind not in _ROWS:
            raise RobotError(f"contact type must be point, flat or arc, got {self.kind!r}")
        if not (np.isfinite(self.radius) and self.radius >= 0.0):
            raise RobotError(f"arc radius must be >= 0 m, got {self.radius!r}")
        if not (np.isfinite(self.torsion_radius) and self.torsion_radius > 0.0):
            raise RobotError(f"torsion radius must be > 0 m, got {self.torsion_radius!r}")

    @property
    def rows(self) -> int:
        """Number of constraint rows."""
        return _ROWS[self.kind]

    @property
    def normal(self) -> tuple[int, ...]:
        """Normal row indices (principal first)."""
        return (2, 3, 4) if self.kind == "flat" else (2,)

    @property
    def tangential(self) -> tuple[int, ...]:
        """Tangential row indices."""
        return (0, 1, 5) if self.kind == "flat" else (0, 1)

    @property
    def tangential_weights(self) -> tuple[float, ...]:
        """Weights of the tangential rows in the friction norm."""
        return (1.0, 1.0, 1.0 / self.torsion_radius) if self.kind == "flat" else (1.0, 1.0)


def parse_contact(text: str) -> ContactSpec:
    """Parse ``FRAME:point``, ``FRAME:flat`` or ``FRAME:arc:RADIUS`` (m).

    The type is read from the end, so a frame name may itself hold colons
    (``base:foot:point`` is the frame ``base:foot``).

    Raises
    ------
    RobotError
        On a malformed specification.
    """
    if not isinstance(text, str):
        raise RobotError(f"a contact is a text FRAME:point|flat|arc:RADIUS, got "
                         f"{type(text).__name__}")
    frame, _, kind = text.rpartition(":")
    if kind in ("point", "flat") and frame:
        return ContactSpec(frame=frame, kind=kind)  # type: ignore[arg-type]
    frame, _, arc = frame.rpartition(":")
    if arc == "arc" and frame:
        try:
            radius = float(kind)
        except ValueError:
            raise RobotError(f"invalid arc radius in contact {text!r}") from None
        return ContactSpec(frame=frame, kind="arc", radius=radius)
    raise RobotError(f"invalid contact {text!r}: use FRAME:point, FRAME:flat or FRAME:arc:RADIUS"
                     " (the type is read after the last colon, so FRAME may hold colons)")


def _contact_specs(what: str, items: Any) -> tuple[ContactSpec, ...]:
    """``items`` as a tuple of :class:`ContactSpec`, refusing anything else by name (a text
    such as ``"x:flat"`` is what :func:`parse_contact` reads, not a contact)."""
    if isinstance(items, str | ContactSpec) or not isinstance(items, Sequence):
        raise RobotError(f"{what} must be a sequence of ContactSpec, got "
                         f"{type(items).__name__}" + (
                             f" (parse_contact({items!r}) makes one)"
                             if isinstance(items, str) else ""))
    for i, c in enumerate(items):
        if not isinstance(c, ContactSpec):
            hint = f": parse_contact({c!r}) makes one" if isinstance(c, str) else ""
            raise RobotError(f"{what}[{i}] must be a ContactSpec, got {type(c).__name__}"
                             f"{hint}")
    return tuple(items)


def _skew(r: FloatArray) -> FloatArray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def contact_jacobian(robot: Robot, data: Any, spec: ContactSpec) -> FloatArray:
    """Rows (k, nv) of one contact; needs ``computeJointJacobians`` and frame placements done.

    Parameters
    ----------
    robot : Robot
    data : pinocchio.Data
        Data on which ``computeJointJacobians(model, data, q)`` and
        ``updateFramePlacements(model, data)`` were called.
    spec : ContactSpec
    """
    pin = _pin()
    fid = robot.frame_id(spec.frame)
    J6 = np.array(
        pin.getFrameJacobian(robot.model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    )
    if spec.kind == "flat":
        return J6
    if spec.kind == "arc" and spec.radius > 0.0:
        r = np.array([0.0, 0.0, -spec.radius])
        return np.asarray(J6[:3] - _skew(r) @ J6[3:])
    return np.asarray(J6[:3])


class _RowPlan:
    """How to fill the stacked rows of a fixed list of contacts from frame Jacobians.

    ``getFrameJacobian`` places the frame itself (from ``data.oMi`` after
    ``computeJointJacobians``), so no ``updateFramePlacements`` is needed.
    """

    def __init__(self, robot: Robot, contacts: Sequence[ContactSpec]) -> None:
        pin = _pin()
        self.model = robot.model
        self.lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        self.get = pin.getFrameJacobian
        self.items: list[tuple[int, int, int, FloatArray | None]] = []
        start = 0
        for c in contacts:
            fid = robot.frame_id(c.frame)
            skew = _skew(np.array([0.0, 0.0, -c.radius])) if c.kind == "arc" and c.radius > 0.0 \
                else None
            self.items.append((fid, start, c.rows, skew))
            start += c.rows
        self.k = start
        self.layout = InertLayout(normal=tuple(c.normal for c in contacts),
                                  tangential=tuple(c.tangential for c in contacts))

    def fill(self, data: Any, out: FloatArray) -> None:
        """Write the rows (k, nv) into ``out``; needs ``computeJointJacobians`` done."""
        for fid, start, rows, skew in self.items:
            J6 = self.get(self.model, data, fid, self.lwa)
            if rows == 6:
                out[start:start + 6] = J6
            elif skew is None:
                out[start:start + 3] = J6[:3]
            else:
                out[start:start + 3] = J6[:3] - skew @ J6[3:]


def ground_admissible(
    value: ArrayLike, *, kept: bool, scale: ArrayLike = 0.0
) -> NDArray[np.bool_]:
    """The paper's admissibility of a foot that does not strike: the ground can only push.

    The one rule used by :func:`heelstrike.robots.study.robot_heel_strike_study` (trailing foot
    left free) and :meth:`RobotImpact.pulling_contacts` (trailing foot kept).

    - A foot left **free** is admissible when it lifts: ``value`` is the vertical velocity of
      its sole after impact (m/s), admissible when ``> 0``.
    - A foot **kept** on the ground (bilateral, inert) is admissible when the ground pushes on
      it: ``value`` is its normal (vertical) impulse (N s), admissible when ``>= 0`` up to
      round-off (``-1e-9 * scale``). A negative impulse means the ground would have to pull:
      released, the foot would lift (for one normal row exactly; the two tests are the two sides
      of the same complementarity).

    Parameters
    ----------
    value : array_like, shape (...)
        Lift velocity (m/s, free) or normal impulse (N s, kept).
    kept : bool
        Whether the foot is kept on the ground.
    scale : array_like, shape (...)
        Kept feet: impulse scale of the impact (N s, e.g. the largest impulse) for the round-off
        tolerance.

    Returns
    -------
    ndarray of bool, shape (...)
    """
    x = np.asarray(value, dtype=float)
    if not kept:
        return np.asarray(x > 0.0)
    return np.asarray(x >= -1e-9 * np.abs(np.asarray(scale, dtype=float)))


@dataclass(frozen=True, kw_only=True)
class RobotImpact(ResultDictMixin):
    """Impact of a robot with per-contact laws.

    Attributes
    ----------
    contacts : tuple of ContactSpec
        Contacts in report order: the striking ones, then the kept ones.
    bilateral : tuple of bool
        Whether each contact is kept (persistent, bilateral, inert).
    result : ContactImpact
        The solution of :func:`heelstrike.core.contact_laws.resolve_contact_impact`.
    M : ndarray, shape (nv, nv)
        Mass matrix at impact.
    jacobians : tuple of ndarray
        Rows of every contact, shape (k_i, nv).
    """

    contacts: tuple[ContactSpec, ...]
    bilateral: tuple[bool, ...]
    result: ContactImpact
    M: FloatArray
    jacobians: tuple[FloatArray, ...]

    def pulling_contacts(self) -> list[tuple[str, float]]:
        """Kept contacts the ground would have to pull on: ``(frame, normal impulse (N s))``.

        The impact is admissible (:func:`ground_admissible`) when this is empty. A kept
        contact's normal impulse is its principal normal row (the vertical force impulse).
        Striking contacts are unilateral, so their normal impulse is never negative. Round-off
        is judged against the largest impulse or the robot's momentum scale
        ``sqrt(2 T m)`` (N s, ``m`` the largest diagonal entry of ``M``), whichever is larger:
        when nothing strikes, every impulse is round-off (1e-15 N s) and none pulls.
        """
        lam = self.result.impulse
        momentum = float(np.sqrt(2.0 * max(float(self.result.T), 0.0)
                                 * float(np.max(np.diag(self.M), initial=0.0))))
        scale = max(float(np.max(np.abs(lam), initial=0.0)), momentum)
        out: list[tuple[str, float]] = []
        start = 0
        for c, kept in zip(self.contacts, self.bilateral, strict=True):
            lam_n = float(lam[start + c.normal[0]])
            start += c.rows
            if kept and not bool(ground_admissible(lam_n, kept=True, scale=scale)):
                out.append((c.frame, lam_n))
        return out

    @property
    def loss_beyond_T_c(self) -> float:
        """``energy_lost - T_c = T_a - T_plus`` (J).

        ``T_c`` counts the rows active in the resolved impact, and a slipping contact's
        tangential rows are not active: the admissible energy its friction dissipates is this
        (``>= 0`` without restitution, 0 to round-off when nothing slips). With restitution the
        energy the rebound returns is subtracted too, so it can be negative.
        """
        return float(self.result.energy_lost - self.result.T_c)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: ``T``, ``T_c``, ``T_a``, ``qdot_plus``, ``impulse``, ``contacts``.

        Also ``loss_beyond_T_c`` (J, :attr:`loss_beyond_T_c`), ``admissible`` (no kept contact
        pulls on the ground) and ``pulling_contacts`` (``frame``, ``normal_impulse`` in N s, of
        :meth:`pulling_contacts`).

        Per contact: ``frame``, ``type``, ``role`` (strike/keep), ``mode``, ``T_c_normal``,
        ``T_c_tangential`` (J), ``force_impulse`` (N s, world axes), ``moment_impulse`` (N m s
        about the frame origin, flat contacts), ``centre_of_pressure`` (m, flat contacts:
        :func:`centre_of_pressure`), ``normal_velocity_pre``/``_post`` and
        ``slip_speed_post`` (m/s, of the contact point).
        """
        r = self.result
        pulling = self.pulling_contacts()
        contacts = []
        start = 0
        for i, c in enumerate(self.contacts):
            lam = r.impulse[start : start + c.rows]
            start += c.rows
            u_pre, u_post = r.contact_velocity_pre[i], r.contact_velocity_post[i]
            item: dict[str, Any] = {
                "frame": c.frame,
                "type": c.kind,
                "role": "keep" if self.bilateral[i] else "strike",
                "mode": r.modes[i],
                "T_c_normal": float(r.T_c_normal[i]),
                "T_c_tangential": float(r.T_c_tangential[i]),
                "force_impulse": [float(x) for x in lam[:3]],
            }
            if c.kind == "flat":
                item["moment_impulse"] = [float(x) for x in lam[3:6]]
                item["centre_of_pressure"] = centre_of_pressure(lam)
            item["normal_velocity_pre"] = float(u_pre[2])
            item["normal_velocity_post"] = float(u_post[2])
            item["slip_speed_post"] = float(np.hypot(u_post[0], u_post[1]))
            contacts.append(item)
        return {
            "T": r.T,
            "T_c": r.T_c,
            "T_a": r.T_a,
            "T_plus": r.T_post,
            "energy_lost": r.energy_lost,
            "loss_beyond_T_c": self.loss_beyond_T_c,
            "qdot_plus": [float(x) for x in r.velocity_post],
            "impulse": [float(x) for x in r.impulse],
            "contacts": contacts,
            "admissible": not pulling,
            "pulling_contacts": [{"frame": f, "normal_impulse": lam_n} for f, lam_n in pulling],
        }


def _row_plan(robot: Robot, contacts: tuple[ContactSpec, ...]) -> _RowPlan:
    """The row plan of ``contacts``, kept on the robot (a few contact sets per robot)."""
    plans = robot.cache.setdefault("row_plans", {})
    plan = plans.get(contacts)
    if plan is None:
        if len(plans) >= 32:
            plans.clear()
        plan = plans[contacts] = _RowPlan(robot, contacts)
    return plan


def centre_of_pressure(impulse: ArrayLike) -> list[float] | None:
    """Where a flat contact's impulse acts: ``(x, y)`` (m, world axes) from the frame origin.

    For a force impulse ``F`` and a moment impulse ``M`` about the frame origin (the six rows
    of a ``flat`` contact), the point ``p`` on the sole's plane with ``M_x = p_y F_z`` and
    ``M_y = -p_x F_z``: ``p = (-M_y / F_z, M_x / F_z)`` (the twist ``M_z`` stays a torsion).
    A sole is treated as unbounded, so ``p`` may lie outside the real sole: compare it with
    the sole's size. None when ``F_z`` is zero to round-off (no normal impulse).

    Parameters
    ----------
    impulse : array_like, shape (6,)
        ``(F_x, F_y, F_z, M_x, M_y, M_z)`` (N s, N m s).
    """
    lam = np.asarray(impulse, dtype=float)
    if abs(float(lam[2])) <= 1e-12 * max(float(np.max(np.abs(lam))), 1e-300):
        return None
    return [float(-lam[4] / lam[2]), float(lam[3] / lam[2])]


def robot_impact(
    robot: Robot,
    q: ArrayLike,
    v: ArrayLike,
    *,
    strike: Sequence[ContactSpec] = (),
    keep: Sequence[ContactSpec] = (),
    friction: float = float("inf"),
    restitution: float = 0.0,
) -> RobotImpact:
    """Impact of ``robot`` at ``(q, v-)`` with striking and kept contacts.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (nq,)
        Configuration at impact (Pinocchio conventions).
    v : array_like, shape (nv,)
        Pre-impact velocity ``v-``.
    strike : sequence of ContactSpec
        Unilateral contacts with ``friction`` and ``restitution`` (their lift is decided).
        None (only ``keep``): every contact kept, the paper's inert impact.
    keep : sequence of ContactSpec
        Persistent bilateral inert contacts.
    friction : float
        Coulomb coefficient of the striking contacts (``inf``: an unbounded cone; a contact
        then slips only where sticking would need the ground to pull, a Painlevé-type case).
    restitution : float
        Newton coefficient of the striking contacts' normal rows, in [0, 1].

    Returns
    -------
    RobotImpact
    """
    strike, keep = _contact_specs("strike", strike), _contact_specs("keep", keep)
    if not strike and not keep:
        raise RobotError("give at least one contact")
    q_, v_ = robot.check_state(q, v)
    law = ContactLaw(friction=friction, restitution=restitution)
    specs = (*strike, *keep)
    bil = tuple([False] * len(strike) + [True] * len(keep))
    plan = _row_plan(robot, specs)
    M, A = _matrices(robot, plan, q_)
    jacs = tuple(A[sl] for sl in plan.layout.slices)
    try:
        if not strike:
            # Only persistent contacts: the paper's inert law, solved directly.
            res = inert_contact_impact(M, v_, A, plan.layout)
            return RobotImpact(contacts=specs, bilateral=bil, result=res, M=M, jacobians=jacs)
        rows = [
            ContactRows(jacobian=J, normal=s.normal, tangential=s.tangential,
                        tangential_weights=s.tangential_weights, bilateral=b, law=law,
                        name=s.frame)
            for J, s, b in zip(jacs, specs, bil, strict=True)
        ]
        res = resolve_contact_impact(M, v_, rows)
    except ImpactInputError as exc:
        raise ImpactInputError(f"{exc}{_why(robot, M, jacs, specs, str(exc))}") from None
    return RobotImpact(contacts=specs, bilateral=bil, result=res, M=M, jacobians=jacs)


def _why(robot: Robot, M: FloatArray, jacs: Sequence[FloatArray],
         specs: Sequence[ContactSpec], message: str) -> str:
    """What makes the impact algebra refuse a robot's matrices, in the robot's names: the
    joints that move no mass (``M`` singular) or the contacts whose rows repeat others'."""
    if "not positive definite" in message:
        d = np.diag(M)
        tiny = np.flatnonzero(d <= 1e-12 * max(float(np.max(np.abs(d))), 1e-300))
        names = []
        for jid in range(1, robot.model.njoints):
            j = robot.model.joints[jid]
            if any(int(j.idx_v) <= i < int(j.idx_v) + int(j.nv) for i in tiny):
                names.append(str(robot.model.names[jid]))
        if names:
            return (f": joint(s) {', '.join(names)} move no mass (a massless link at the end "
                    "of a chain, or a second floating base)")
        return ""
    if "rank deficient" in message:
        rank, seen, bad = 0, np.zeros((0, M.shape[0])), []
        for J, s in zip(jacs, specs, strict=True):
            trial = np.vstack((seen, J))
            r = int(np.linalg.matrix_rank(trial, tol=1e-9 * max(float(np.abs(trial).max()),
                                                                 1e-300)))
            if r < rank + J.shape[0]:
                bad.append(s.frame)
            seen, rank = trial, r
        if not bad:
            return ""
        return (f": the rows of {', '.join(bad)} repeat those of the contacts before (points "
                "of one rigid body, or a frame that does not move): give a sole as one "
                "FRAME:flat contact, not as several points, and drop a contact on a fixed frame")
    return ""


def _matrices(robot: Robot, plan: _RowPlan, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    data = robot.data
    M = robot._mass_matrix(q, data)
    _pin().computeJointJacobians(robot.model, data, q)
    A = np.empty((plan.k, robot.nv))
    plan.fill(data, A)
    return M, A


#: Height (m) of a contact point above or below the ground plane ``z = 0`` beyond which
#: ``heelstrike impact --robot`` notes that the contact does not touch the ground.
GROUND_GAP_TOLERANCE = 1e-3


def contact_heights(
    robot: Robot, q: ArrayLike, contacts: Sequence[ContactSpec]
) -> list[float]:
    """World height ``z`` (m) of each contact's point at configuration ``q`` (nq,).

    The frame's origin for point and flat contacts; for an arc heel, the lowest point of the
    arc, ``radius`` below its centre (the frame's origin). The ground is the plane ``z = 0``
    (:func:`heelstrike.robots.states.gait_configuration` places the feet on it): an impact
    computed with a contact far from it treats that contact as touching all the same.
    """
    pin = _pin()
    contacts = _contact_specs("contacts", contacts)
    q_, _ = robot.check_state(q)
    data = robot.data
    pin.framesForwardKinematics(robot.model, data, q_)
    return [float(data.oMf[robot.frame_id(c.frame)].translation[2])
            - (c.radius if c.kind == "arc" else 0.0) for c in contacts]


def robot_matrices(
    robot: Robot, q: ArrayLike, contacts: Sequence[ContactSpec]
) -> tuple[FloatArray, FloatArray]:
    """Mass matrix (nv, nv) and stacked contact rows (k, nv) at one configuration (nq,).

    ``crba`` (symmetrised) and ``computeJointJacobians`` once, then one frame Jacobian
    (``LOCAL_WORLD_ALIGNED``) per contact; the robot's ``Data`` is reused.
    """
    q_, _ = robot.check_state(q)
    return _matrices(robot, _row_plan(robot, _contact_specs("contacts", contacts)), q_)


def mass_matrices_and_jacobians(
    robot: Robot, qs: ArrayLike, contacts: Sequence[ContactSpec]
) -> tuple[FloatArray, FloatArray]:
    """Mass matrices (B, nv, nv) and stacked contact rows (B, k, nv) at configurations (B, nq).

    One Pinocchio ``Data`` is reused for all configurations.
    """
    q_all = robot.check_states(qs)
    plan = _row_plan(robot, _contact_specs("contacts", contacts))
    Ms = np.empty((q_all.shape[0], robot.nv, robot.nv))
    As = np.empty((q_all.shape[0], plan.k, robot.nv))
    _assemble(robot, plan, q_all, Ms, As)
    return Ms, As


def _assemble(robot: Robot, plan: _RowPlan, q_all: FloatArray, Ms: FloatArray,
              As: FloatArray) -> None:
    """Fill ``Ms[:B]`` (symmetrised ``crba``) and ``As[:B]`` at checked configurations (B, nq).

    The loop holds Pinocchio calls only; the symmetrisation is one numpy call for the batch.
    """
    pin = _pin()
    crba, jacobians = pin.crba, pin.computeJointJacobians
    model, data = robot.model, robot.data
    for b, q in enumerate(q_all):
        Ms[b] = crba(model, data, q)
        jacobians(model, data, q)
        plan.fill(data, As[b])
    B = q_all.shape[0]
    il = np.tril_indices(robot.nv, -1)
    Ms[:B, il[0], il[1]] = Ms[:B, il[1], il[0]]


def inert_energy_split_batch(
    robot: Robot,
    qs: ArrayLike,
    vs: ArrayLike,
    contacts: Sequence[ContactSpec],
    *,
    chunk: int = 256,
    check: bool = True,
) -> InertImpactBatch:
    """The paper's inert impact with the energy split, batched: all ``contacts`` bilateral.

    The numbers of :func:`robot_impact` with ``keep=contacts`` (and no strike) for every
    configuration, computed chunk by chunk: Pinocchio fills the mass matrices and contact rows
    of a chunk (one ``Data`` reused), then :func:`heelstrike.core.contact_laws.
    inert_contact_impact_batch` solves the chunk with numpy's stacked solvers.

    Parameters
    ----------
    robot : Robot
    qs : array_like, shape (B, nq)
        Configurations at impact.
    vs : array_like, shape (B, nv)
        Pre-impact velocities.
    contacts : sequence of ContactSpec
        Persistent contacts (bilateral, inert), in report order.
    chunk : int
        Configurations per chunk (bounds memory: ``chunk * nv^2`` floats).
    check : bool
        Validate ``M`` and the rank of the rows (see the core function).

    Returns
    -------
    InertImpactBatch
        Arrays with leading shape ``(B,)``; impulses in contact order.
    """
    if not _contact_specs("contacts", contacts):
        raise RobotError("give at least one contact")
    q_all = robot.check_states(qs)
    v_all = real_array(vs, "velocities")
    if v_all.shape != (q_all.shape[0], robot.nv):
        raise RobotError(
            f"velocities must be (B={q_all.shape[0]}, nv={robot.nv}), got {v_all.shape}"
        )
    if not np.all(np.isfinite(v_all)):
        raise RobotError("q and v must be finite")
    plan = _row_plan(robot, tuple(contacts))
    size = max(1, min(int(chunk), q_all.shape[0]))
    Ms = np.empty((size, robot.nv, robot.nv))
    As = np.empty((size, plan.k, robot.nv))
    parts = []
    for i in range(0, q_all.shape[0], size):
        q_c = q_all[i:i + size]
        B = q_c.shape[0]
        _assemble(robot, plan, q_c, Ms, As)
        v_c = v_all[i:i + size]
        if check:  # M is symmetric by construction
            check_inert_batch(Ms[:B], v_c, As[:B], symmetric=True)
        parts.append(inert_contact_impact_batch(Ms[:B], v_c, As[:B], plan.layout, check=False))
    return InertImpactBatch(**{
        f.name: np.concatenate([getattr(p, f.name) for p in parts])
        for f in dataclasses.fields(InertImpactBatch)
    })


def inert_impact_batch(
    robot: Robot,
    qs: ArrayLike,
    vs: ArrayLike,
    contacts: Sequence[ContactSpec],
    *,
    restitution: float = 0.0,
) -> ImpactResult:
    """The paper's inert impact, batched: all ``contacts`` bilateral, no slip.

    Parameters
    ----------
    qs : array_like, shape (B, nq)
    vs : array_like, shape (B, nv)
    contacts : sequence of ContactSpec
    restitution : float
        Global ``e`` of :func:`heelstrike.core.impact.impact` (0: the paper).

    Returns
    -------
    ImpactResult
        With leading shape ``(B,)``.
    """
    Ms, As = mass_matrices_and_jacobians(robot, qs, contacts)
    v_all = real_array(vs, "velocities").reshape(-1, robot.nv)
    return impact(Ms, As, v_all, restitution=restitution)
