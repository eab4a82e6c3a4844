"""Contacts of a robot with flat ground (world ``z`` up) and its impact with per-contact laws.

A contact is a frame of the robot and a type:

``point`` (3 rows)
    the frame origin's linear velocity ``(x, y, z)``; normal row ``z``, tangential ``x, y``.
``arc`` (3 rows, radius ``R``)
    an arc heel: the material point a distance ``R`` below the frame origin along the ground
    normal, ``v + omega x (-R e_z)``; the frame sits at the arc's centre. ``R = 0`` is ``point``.
``flat`` (a support polygon; kept: 6 bilateral rows)
    a sole: its support polygon, the corners ``(x, y)`` of a rectangle in the sole frame's own
    ``x, y`` plane (``sole = (x_min, x_max, y_min, y_max)`` m, default 0.2 m x 0.1 m centred on
    the frame, which must lie on the sole's surface). Striking, each corner is a unilateral
    point contact (3 rows ``x, y, z`` of its velocity, ``v + omega x r``) with its own Coulomb
    friction (a pyramid cone, ``|lambda_x|, |lambda_y| <= mu lambda_z``) and restitution, solved
    exactly with every active set (:func:`heelstrike.core.complementarity.
    solve_point_contacts`): heel and toe strikes, edge landings, toe-off and the flat landing
    are the same law. The four corners are rank deficient (12 rows, rank 6): ``q_dot+`` and
    ``T_c`` are unique, the corner impulses are the smallest active set's. Kept, a flat sole
    is the bilateral contact below (it stays flat), and says so when one of its corners would
    have to pull (centre of pressure outside the polygon: :attr:`RobotImpact.tilting`).
``flat-bilateral`` (6 rows)
    a sole held flat: the frame's linear and angular velocity ``(x, y, z, wx, wy, wz)``;
    normal rows ``z, wx, wy`` (the principal one is ``z``), tangential rows ``x, y, wz`` (the
    twist weighted by ``1 / torsion_radius`` in the pyramid friction cone). Striking, it is resolved
    all rows or none with restitution on all three normal rows, so in a heel-first landing
    with ``e > 0`` it reverses the tilt too and can drive the toe into the ground: strike
    with ``flat`` unless the sole really lands flat.

All rows come from the frame Jacobian in ``LOCAL_WORLD_ALIGNED`` (origin at the frame, axes of
the world), so impulses are world-aligned forces (N s) and moments about the frame origin
(N m s). The impact laws are :mod:`heelstrike.core.contact_laws` (which knows no robot) and
:func:`heelstrike.core.impact.impact` for the batched inert (paper) law with its projectors.

Speed: one ``crba`` and one ``computeJointJacobians`` per configuration, then one frame Jacobian
per contact, on the robot's reused ``Data``. With only persistent contacts (the paper's inert
law) :func:`robot_impact`, :func:`inert_energy_split` and :func:`inert_energy_split_batch` solve
on the kinematic tree in one compiled call per configuration or per chunk
(``heelstrike.robots._inert_kernel``: Pinocchio's tree-sparse factorisation of ``M``, the
Delassus matrix of the rows, a small dense Cholesky factorisation; the two lean ones need no
``computeJointJacobians``: ``crba`` in the world convention leaves the joint Jacobians); the
complementarity solver runs only when a striking contact's friction, restitution or separation
has to be decided.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.complementarity import RestitutionLaw
from heelstrike.core.contact_laws import (
    ContactImpact,
    ContactLaw,
    ContactRows,
    InertImpactBatch,
    InertLayout,
    _check_rank_reference,
    resolve_contact_impact,
)
from heelstrike.core.impact import ImpactInputError, ImpactResult, impact
from heelstrike.robots.loading import Robot, RobotError, _pin, real_array

__all__ = [
    "DEFAULT_SOLE",
    "ContactKind",
    "ContactSpec",
    "RobotImpact",
    "centre_of_pressure",
    "contact_heights",
    "contact_jacobian",
    "ground_admissible",
    "inert_energy_split",
    "inert_energy_split_batch",
    "inert_impact_batch",
    "mass_matrices_and_jacobians",
    "parse_contact",
    "robot_impact",
    "robot_matrices",
]

ContactKind = Literal["point", "flat", "flat-bilateral", "arc"]
_ROWS = {"point": 3, "arc": 3, "flat": 6, "flat-bilateral": 6}
_FLAT = ("flat", "flat-bilateral")

#: Default support polygon of a sole, ``(x_min, x_max, y_min, y_max)`` (m) in the sole frame:
#: a 0.2 m x 0.1 m rectangle centred on the frame (``FRAME:flat:HX,HY`` or
#: ``FRAME:flat:XMIN,XMAX,YMIN,YMAX`` give the robot's own).
DEFAULT_SOLE = (-0.1, 0.1, -0.05, 0.05)


@dataclass(frozen=True, kw_only=True)
class ContactSpec:
    """A contact of a robot frame with the ground.

    Parameters
    ----------
    frame : str
        Frame name in the robot model.
    kind : {"point", "flat", "flat-bilateral", "arc"}
        Contact type (module doc).
    radius : float
        Arc heel radius (m), ``kind="arc"`` only, >= 0.
    torsion_radius : float
        Flat contacts: radius (m) of the torsional friction limit, ``|tau_z| <= rho mu f_z``
        on the cone's boundary, > 0.
    sole : tuple of 4 float
        Flat contacts: the support polygon, ``(x_min, x_max, y_min, y_max)`` (m) in the sole
        frame, ``x_min < x_max``, ``y_min < y_max``.
    """

    frame: str
    kind: ContactKind = "point"
    radius: float = 0.0
    torsion_radius: float = 0.05
    sole: tuple[float, float, float, float] = DEFAULT_SOLE

    def __post_init__(self) -> None:
        if self.kind not in _ROWS:
            raise RobotError(
                f"contact type must be point, flat, flat-bilateral or arc, got {self.kind!r}")
        sole = tuple(float(x) for x in self.sole)
        if len(sole) != 4 or not all(np.isfinite(sole)) or not (
                sole[0] < sole[1] and sole[2] < sole[3]):
            raise RobotError(f"sole must be (x_min, x_max, y_min, y_max) with x_min < x_max and "
                             f"y_min < y_max (m), got {self.sole!r}")
        object.__setattr__(self, "sole", sole)
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
        """Normal row indices (principal first) of the 6 or 3 rows."""
        return (2, 3, 4) if self.kind in _FLAT else (2,)

    @property
    def tangential(self) -> tuple[int, ...]:
        """Tangential row indices."""
        return (0, 1, 5) if self.kind in _FLAT else (0, 1)

    @property
    def tangential_weights(self) -> tuple[float, ...]:
        """Weights of the tangential rows in the friction norm."""
        return (1.0, 1.0, 1.0 / self.torsion_radius) if self.kind in _FLAT else (1.0, 1.0)

    @property
    def corners(self) -> tuple[tuple[float, float], ...]:
        """Support polygon corners ``(x, y)`` (m, sole frame): heel right, toe right, toe left,
        heel left (``x`` forward, ``y`` left)."""
        x0, x1, y0, y1 = self.sole
        return ((x0, y0), (x1, y0), (x1, y1), (x0, y1))


def parse_contact(text: str) -> ContactSpec:
    """Parse ``FRAME:point``, ``FRAME:flat[:SOLE]``, ``FRAME:flat-bilateral[:SOLE]`` or
    ``FRAME:arc:RADIUS`` (m).

    ``SOLE`` is ``HX,HY`` (half length and half width, m, a rectangle centred on the frame)
    or ``XMIN,XMAX,YMIN,YMAX`` (m, sole frame); default :data:`DEFAULT_SOLE`.

    The type is read from the end, so a frame name may itself hold colons
    (``base:foot:point`` is the frame ``base:foot``).

    Raises
    ------
    RobotError
        On a malformed specification.
    """
    if not isinstance(text, str):
        raise RobotError(f"a contact is a text FRAME:point|flat|flat-bilateral|arc:RADIUS, got "
                         f"{type(text).__name__}")
    frame, _, kind = text.rpartition(":")
    if kind in ("point", "flat", "flat-bilateral") and frame:
        return ContactSpec(frame=frame, kind=kind)  # type: ignore[arg-type]
    frame, _, typ = frame.rpartition(":")
    if typ in _FLAT and frame:
        try:
            dims = [float(x) for x in kind.split(",")]
        except ValueError:
            raise RobotError(f"invalid sole size in contact {text!r}") from None
        if len(dims) == 2 and dims[0] > 0 and dims[1] > 0:
            sole = (-dims[0], dims[0], -dims[1], dims[1])
        elif len(dims) == 4:
            sole = (dims[0], dims[1], dims[2], dims[3])
        else:
            raise RobotError(f"invalid sole size in contact {text!r}: give HX,HY (half length, "
                             "half width, > 0 m) or XMIN,XMAX,YMIN,YMAX (m)")
        return ContactSpec(frame=frame, kind=typ, sole=sole)  # type: ignore[arg-type]
    if typ == "arc" and frame:
        try:
            radius = float(kind)
        except ValueError:
            raise RobotError(f"invalid arc radius in contact {text!r}") from None
        return ContactSpec(frame=frame, kind="arc", radius=radius)
    raise RobotError(f"invalid contact {text!r}: use FRAME:point, FRAME:flat[:HX,HY], "
                     "FRAME:flat-bilateral or FRAME:arc:RADIUS (the type is read from the end, "
                     "so FRAME may hold colons)")


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
    if spec.kind in _FLAT:
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


def _inert_library() -> Any:
    """The inert kernel's ahead-of-time library (:mod:`heelstrike.dynamics._aot`): built once
    into heelstrike's cache, it loads without numba, so a new process does not pay numba's
    import and cache loading (about 1 s) for one robot impact."""
    lib = _AOT.get("library")
    if lib is None:
        from heelstrike.dynamics._aot import AotExport, AotLibrary

        def functions() -> dict[str, Any]:
            from heelstrike.robots import _inert_kernel as kernel

            return {"inert_item": kernel.inert_item, "inert_batch": kernel.inert_batch}

        lib = _AOT["library"] = AotLibrary(
            name="robot_inert",
            exports=(
                AotExport(name="inert_item", args=("f8[:,::1]", "f8[:,::1]", "f8[::1]",
                                                   "i8[::1]", "f8[::1]", "f8[::1]", "b1", "i8"),
                          returns="i8"),
                AotExport(name="inert_batch", args=("f8[:,:,::1]", "f8[:,:,::1]", "f8[:,::1]",
                                                    "i8[::1]", "f8[::1]", "f8[:,::1]",
                                                    "i8[::1]", "b1"),
                          returns="void"),
            ),
            functions=functions,
            source_modules=("heelstrike.robots._inert_kernel", "heelstrike.robots._inert_tree"),
            kind="aot-robot",
            what="the robots' inert impact kernel, compiled ahead of time",
        )
    return lib


_AOT: dict[str, Any] = {}


def _inert_kernels() -> tuple[Any, Any]:
    """``(inert_item, inert_batch)``: the ahead-of-time module's functions (their C-order
    arguments are guaranteed by :class:`_InertPath`, so they are called unchecked), or numba's
    JIT when the tier is off or cannot build."""
    funcs = _AOT.get("functions")
    if funcs is None:
        from heelstrike.dynamics._aot import load_library

        aot = load_library(_inert_library())
        if aot is not None:
            funcs = (aot.module.inert_item, aot.module.inert_batch)
        else:
            from heelstrike.robots import _inert_kernel as kernel

            funcs = (kernel.inert_item, kernel.inert_batch)
        _AOT["functions"] = funcs
    return funcs


class _InertPath:
    """The compiled inert impact (:mod:`heelstrike.robots._inert_kernel`) of a fixed list of
    kept contacts: the robot's tree as dof arrays, the rows' nesting order, reused work space.

    One per robot and contact list (:func:`_inert_path`), like the robot's ``Data``: not
    thread-safe.
    """

    def __init__(self, robot: Robot, contacts: tuple[ContactSpec, ...]) -> None:
        from heelstrike.robots import _inert_tree as kernel

        pin = _pin()
        model = robot.model
        self.plan = plan = _row_plan(robot, contacts)
        lay = plan.layout
        n, k, groups = robot.nv, lay.k, len(lay.bounds) - 1
        tree = ([int(p) for p in model.parents], [int(j.idx_v) for j in model.joints],
                [int(j.nv) for j in model.joints])
        parents, nvsub = kernel.tree_arrays(*tree, n)
        chains = []
        for c in contacts:  # a contact's rows are zero off the dofs that move its body
            dofs = kernel.chain(*tree, int(model.frames[robot.frame_id(c.frame)].parentJoint))
            chains += [dofs] * c.rows
        self.tree = kernel.tree_layout(parents, nvsub, lay.order, lay.bounds, chains)
        self.n, self.k, self.m = n, k, len(lay.rows)
        self.work = np.zeros(kernel.work_size(n, k))
        self.out = np.empty(kernel.out_size(n, k, groups))
        self.A = np.empty((k, n))
        self.item, self.batch = _inert_kernels()
        self.model, self.data = model, robot.data
        self.crba = pin.crba
        # crba in the WORLD convention also leaves the joint Jacobians in data.J (Pinocchio
        # >= 3), so no computeJointJacobians is needed before the frame Jacobians.
        convention = getattr(pin, "Convention", None)
        self.crba_args: tuple[Any, ...] = (convention.WORLD,) if convention else ()
        self.jacobians = None if convention else pin.computeJointJacobians
        o = n + k + groups
        self.cols: dict[str, Any] = {"velocity_post": slice(0, n), "impulse": slice(n, n + k),
                     "T_c_normal": slice(n + k, n + k + self.m),
                     "T_c_tangential": slice(n + k + self.m, o),
                     "T": o, "T_post": o + 1, "T_c": o + 2, "energy_lost": o + 3,
                     "u_pre": slice(o + 4, o + 4 + k), "u_post": slice(o + 4 + k, o + 4 + 2 * k),
                     "generalized": slice(o + 4 + 2 * k, o + 4 + 2 * k + n)}
        cols = self.cols
        self.single_cols = (cols["velocity_post"], cols["impulse"], cols["T_c_normal"],
                            cols["T_c_tangential"], o)

    def assemble(self, q: FloatArray, A: FloatArray) -> FloatArray:
        """``crba`` at a checked ``q`` (returns Pinocchio's ``M``, upper triangle filled) and
        the contact rows into ``A`` (k, nv)."""
        M = self.crba(self.model, self.data, q, *self.crba_args)
        if self.jacobians is not None:  # pragma: no cover - Pinocchio without conventions
            self.jacobians(self.model, self.data, q)
        self.plan.fill(self.data, A)
        return np.ascontiguousarray(M)

    def raise_for(self, status: int, rows: Any, where: str = "") -> None:
        """Raise the reference path's error for a kernel status; run the reference rank test
        on ``rows()`` (k, nv) where the certificate did not hold (status 3)."""
        if status == 1:
            raise ImpactInputError(f"M is not positive definite{where}")
        if status == 2:
            raise ImpactInputError(f"contact rows are rank deficient (redundant contacts?){where}")
        if status == 3:
            try:
                _check_rank_reference(rows())
            except ImpactInputError as exc:
                raise ImpactInputError(f"{exc}{where}") from None

    def contact_impact(self, v: FloatArray) -> ContactImpact:
        """The last single solve as :class:`ContactImpact` (copies of the outputs)."""
        out, c = self.out.copy(), self.cols
        u_pre, u_post, slices = out[c["u_pre"]], out[c["u_post"]], self.plan.layout.slices
        T, T_post = float(out[c["T"]]), float(out[c["T_post"]])
        return ContactImpact(
            velocity_pre=v, velocity_post=out[c["velocity_post"]], impulse=out[c["impulse"]],
            generalized_impulse=out[c["generalized"]],
            modes=tuple("stick" for _ in range(self.m)),
            contact_velocity_pre=tuple(u_pre[sl] for sl in slices),
            contact_velocity_post=tuple(u_post[sl] for sl in slices),
            T=T, T_c=float(out[c["T_c"]]), T_a=T_post, T_post=T_post,
            energy_lost=float(out[c["energy_lost"]]),
            T_c_normal=out[c["T_c_normal"]], T_c_tangential=out[c["T_c_tangential"]])

    def single(self, v: FloatArray) -> InertImpactBatch:
        """The last single solve as :class:`InertImpactBatch` of one state (a copy)."""
        out = self.out.copy()
        vp, lam, nrm, tan, o = self.single_cols
        T_post = out[o + 1]
        return InertImpactBatch(
            velocity_pre=v, velocity_post=out[vp], impulse=out[lam], T=out[o], T_c=out[o + 2],
            T_a=T_post, T_post=T_post, energy_lost=out[o + 3], T_c_normal=out[nrm],
            T_c_tangential=out[tan])

    def split(self, out: FloatArray, v: FloatArray) -> InertImpactBatch:
        """Outputs (..., width) as :class:`InertImpactBatch` (views of ``out``)."""
        c = self.cols
        T_post = out[..., c["T_post"]]
        return InertImpactBatch(
            velocity_pre=v, velocity_post=out[..., c["velocity_post"]],
            impulse=out[..., c["impulse"]], T=out[..., c["T"]], T_c=out[..., c["T_c"]],
            T_a=T_post, T_post=T_post, energy_lost=out[..., c["energy_lost"]],
            T_c_normal=out[..., c["T_c_normal"]], T_c_tangential=out[..., c["T_c_tangential"]])


def _inert_path(robot: Robot, contacts: tuple[ContactSpec, ...]) -> _InertPath:
    """The compiled inert path of ``contacts``, kept on the robot (as :func:`_row_plan`)."""
    paths = robot.cache.setdefault("inert_paths", {})
    path = paths.get(contacts)
    if path is None:
        if len(paths) >= 32:
            paths.clear()
        path = paths[contacts] = _InertPath(robot, contacts)
    return path


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
        The solution of :func:`heelstrike.core.contact_laws.resolve_contact_impact`, whose
        contacts are the rows actually resolved: a striking ``flat`` sole is its corners.
    M : ndarray, shape (nv, nv)
        Mass matrix at impact.
    jacobians : tuple of ndarray
        Rows of every contact, shape (k_i, nv); a striking sole's are its corners' rows
        (3 per corner, in :attr:`corner_order`).
    members : tuple of tuple of int
        Per contact, the indices of its rows' contacts in ``result`` (one, or a sole's
        corners); empty: one each, in order.
    corner_order : tuple of tuple of int
        Per contact, the order of its corners (indices into :attr:`ContactSpec.corners`):
        the nesting order of the energy split, the corner approaching the ground fastest
        first (ties by index), so that where corners' rows are redundant the energy goes to
        the corners that strike hardest; empty for other contacts.
    corner_offsets : tuple of ndarray
        Per contact, its corners' offsets from the frame origin (m, world axes), shape
        (corners, 3) in :attr:`corner_order`; empty (0, 3) for other contacts.
    tilting : tuple of str
        Kept ``flat``/``flat-bilateral`` soles whose centre of pressure lies outside their
        support polygon: holding them flat needs a corner to pull (they would tilt).
    """

    contacts: tuple[ContactSpec, ...]
    bilateral: tuple[bool, ...]
    result: ContactImpact
    M: FloatArray
    jacobians: tuple[FloatArray, ...]
    members: tuple[tuple[int, ...], ...] = ()
    corner_order: tuple[tuple[int, ...], ...] = ()
    corner_offsets: tuple[FloatArray, ...] = ()
    tilting: tuple[str, ...] = ()

    def _members(self) -> tuple[tuple[int, ...], ...]:
        return self.members or tuple((i,) for i in range(len(self.contacts)))

    def _offsets(self) -> list[int]:
        out = [0]
        for u in self.result.contact_velocity_pre:
            out.append(out[-1] + u.shape[0])
        return out

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
        offs = self._offsets()
        for c, kept, mem in zip(self.contacts, self.bilateral, self._members(), strict=True):
            if not kept:
                continue
            lam_n = float(lam[offs[mem[0]] + c.normal[0]])
            if not bool(ground_admissible(lam_n, kept=True, scale=scale)):
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

    def _patch_item(self, i: int, item: dict[str, Any]) -> None:
        """Fill a striking sole's entry: sums over its corners and a ``corners`` list."""
        r = self.result
        offs = self._offsets()
        spec = self.contacts[i]
        force, moment = np.zeros(3), np.zeros(3)
        corners = []
        modes = []
        for j, idx, off in zip(self._members()[i], self.corner_order[i],
                               self.corner_offsets[i], strict=True):
            lam = r.impulse[offs[j]:offs[j] + 3]
            force += lam
            moment += np.cross(off, lam)
            u_pre, u_post = r.contact_velocity_pre[j], r.contact_velocity_post[j]
            modes.append(r.modes[j])
            corners.append({
                "corner": [float(x) for x in spec.corners[idx]],
                "mode": r.modes[j],
                "T_c_normal": float(r.T_c_normal[j]),
                "T_c_tangential": float(r.T_c_tangential[j]),
                "force_impulse": [float(x) for x in lam],
                "normal_velocity_pre": float(u_pre[2]),
                "normal_velocity_post": float(u_post[2]),
                "slip_speed_post": float(np.hypot(u_post[0], u_post[1])),
            })
        mem = list(self._members()[i])
        item["mode"] = ("separate" if all(m == "separate" for m in modes)
                        else "slip" if "slip" in modes else "stick")
        item["T_c_normal"] = float(r.T_c_normal[mem].sum())
        item["T_c_tangential"] = float(r.T_c_tangential[mem].sum())
        item["force_impulse"] = [float(x) for x in force]
        item["moment_impulse"] = [float(x) for x in moment]
        item["centre_of_pressure"] = centre_of_pressure(np.concatenate((force, moment)))
        item["normal_velocity_pre"] = min(c["normal_velocity_pre"] for c in corners)
        item["normal_velocity_post"] = min(c["normal_velocity_post"] for c in corners)
        item["slip_speed_post"] = max((c["slip_speed_post"] for c in corners
                                       if c["mode"] != "separate"), default=0.0)
        item["corners"] = corners

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: ``T``, ``T_c``, ``T_a``, ``qdot_plus``, ``impulse``, ``contacts``.

        Also ``loss_beyond_T_c`` (J, :attr:`loss_beyond_T_c`), ``admissible`` (no kept contact
        pulls on the ground), ``pulling_contacts`` (``frame``, ``normal_impulse`` in N s, of
        :meth:`pulling_contacts`), ``tilting_contacts`` (:attr:`tilting`), and the outcome
        count of the law: ``restitution_law``, ``outcomes`` (distinct ``q_dot+`` found),
        ``unique`` (true/false when every active set was examined, null when not, unless
        normal impulses alone stop the robot: true, ``q_dot+ = 0``),
        ``active_sets`` (their number: the bound on ``outcomes``; 0 when not counted),
        ``solutions`` (``q_dot+`` of every outcome found, the one reported first),
        ``impulse_unique`` (whether the impulses are determined too: false where contacts are
        redundant, e.g. two soles of one body; null when not examined, unless that stop
        certificate exhibits two impulses: false), ``velocity_range``
        (componentwise smallest and largest ``q_dot+`` over the outcomes; null entries where
        a continuum of outcomes is unbounded) and ``kkt_residual`` (the returned outcome's
        certificate: largest relative violation of the law, 0 when nothing was decided).

        Per contact: ``frame``, ``type``, ``role`` (strike/keep), ``mode``, ``T_c_normal``,
        ``T_c_tangential`` (J), ``force_impulse`` (N s, world axes), ``moment_impulse`` (N m s
        about the frame origin, flat contacts), ``centre_of_pressure`` (m, flat contacts:
        :func:`centre_of_pressure`), ``normal_velocity_pre``/``_post`` and
        ``slip_speed_post`` (m/s, of the contact point; for a striking sole the lowest corner
        normal velocity and the fastest slipping corner) and, for a striking sole, ``corners``
        (each corner's ``corner`` position in the sole frame (m), ``mode``, energies,
        ``force_impulse`` and velocities).
        """
        r = self.result
        pulling = self.pulling_contacts()
        contacts = []
        offs = self._offsets()
        for i, (c, mem) in enumerate(zip(self.contacts, self._members(), strict=True)):
            item: dict[str, Any] = {
                "frame": c.frame,
                "type": c.kind,
                "role": "keep" if self.bilateral[i] else "strike",
            }
            if self.corner_order and self.corner_order[i]:
                self._patch_item(i, item)
                contacts.append(item)
                continue
            j = mem[0]
            lam = r.impulse[offs[j]:offs[j + 1]]
            u_pre, u_post = r.contact_velocity_pre[j], r.contact_velocity_post[j]
            item.update({
                "mode": r.modes[j],
                "T_c_normal": float(r.T_c_normal[j]),
                "T_c_tangential": float(r.T_c_tangential[j]),
                "force_impulse": [float(x) for x in lam[:3]],
            })
            if c.kind in _FLAT:
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
            "tilting_contacts": list(self.tilting),
            "restitution_law": r.restitution_law,
            "outcomes": r.outcomes,
            "unique": r.unique,
            "impulse_unique": r.impulse_unique,
            "active_sets": r.active_sets,
            "solutions": [[float(x) for x in s] for s in (r.solutions or (r.velocity_post,))],
            "velocity_range": [[float(x) if np.isfinite(x) else None for x in row] for row in (
                r.velocity_range if r.velocity_range is not None
                else (r.velocity_post, r.velocity_post))],
            "kkt_residual": r.kkt_residual,
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
    restitution_law: RestitutionLaw = "newton",
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
        Unilateral contacts with ``friction`` and ``restitution`` (their lift is decided); a
        ``flat`` sole is its support polygon, each corner a unilateral point contact.
        None (only ``keep``): every contact kept, the paper's inert impact.
    keep : sequence of ContactSpec
        Persistent bilateral inert contacts (a ``flat`` sole: 6 rows, held flat).
    friction : float
        Coulomb coefficient of the striking contacts (``inf``: an unbounded cone; a contact
        then slips only where sticking would need the ground to pull, a Painlevé-type case).
        Every striking contact uses the pyramid ``|lambda_x|, |lambda_y| <= mu lambda_z``
        (a ``flat-bilateral`` sole also ``|tau_z| <= rho mu lambda_z``), solved exactly
        with every active set (``result.unique``, ``result.impulse_unique``).
    restitution : float
        Coefficient ``e`` of the striking contacts' normal rows, in [0, 1].
    restitution_law : {"newton", "energetic"}
        Newton's kinematic law ``u_n+ = -e u_n-`` (can gain energy with sticking friction:
        Kane's paradox), or the energetic law that cannot
        (:func:`heelstrike.core.complementarity.solve_point_contacts`; with ``e = 0`` the two
        are the same). Either way every active set is examined when there are few enough
        (``result.unique``, ``result.solutions``).

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
    flats = [i for i, sp in enumerate(specs) if sp.kind in _FLAT]
    rot: dict[int, FloatArray] = {}
    if flats:  # the soles' placements (their frames' ids are the row plan's)
        place = _pin().updateFramePlacement
        rot = {i: np.array(place(robot.model, robot.data, plan.items[i][0]).rotation)
               for i in flats}
    try:
        if any(not J.any() for J in jacs):  # a frame that does not move: no contact at all
            raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")
        if not strike:
            # Only persistent contacts: the paper's inert law, solved directly on the tree.
            if plan.k > robot.nv:
                raise ImpactInputError(f"{plan.k} contact rows exceed the {robot.nv} "
                                       "coordinates")
            path = _inert_path(robot, specs)
            path.raise_for(path.item(np.ascontiguousarray(M), A, np.ascontiguousarray(v_),
                                     path.tree, path.work, path.out, True, 5), lambda: A)
            res = path.contact_impact(v_)
            return RobotImpact(contacts=specs, bilateral=bil, result=res, M=M, jacobians=jacs,
                               tilting=_tilting(specs, bil, res, rot, ((i,) for i in
                                                                     range(len(specs))), M))
        rows: list[ContactRows] = []
        members: list[tuple[int, ...]] = []
        orders: list[tuple[int, ...]] = []
        offsets: list[FloatArray] = []
        out_jacs: list[FloatArray] = []
        for i, (J, sp, b) in enumerate(zip(jacs, specs, bil, strict=True)):
            if sp.kind == "flat" and not b:
                offs = np.array([rot[i] @ np.array([x, y, 0.0]) for x, y in sp.corners])
                Jc = [J[:3] - _skew(r) @ J[3:] for r in offs]
                order = tuple(sorted(range(len(Jc)), key=lambda k: (float(Jc[k][2] @ v_), k)))
                members.append(tuple(range(len(rows), len(rows) + len(order))))
                rows += [ContactRows(jacobian=Jc[k], normal=(2,), tangential=(0, 1), law=law,
                                     name=f"{sp.frame} corner {k}") for k in order]
                orders.append(order)
                offsets.append(offs[list(order)])
                out_jacs.append(np.vstack([Jc[k] for k in order]))
                continue
            members.append((len(rows),))
            rows.append(ContactRows(jacobian=J, normal=sp.normal, tangential=sp.tangential,
                                    tangential_weights=sp.tangential_weights, bilateral=b,
                                    law=law, name=sp.frame))
            orders.append(())
            offsets.append(np.zeros((0, 3)))
            out_jacs.append(J)
        res = resolve_contact_impact(M, v_, rows, restitution_law=restitution_law)
    except ImpactInputError as exc:
        raise ImpactInputError(f"{exc}{_why(robot, M, jacs, specs, str(exc))}") from None
    return RobotImpact(contacts=specs, bilateral=bil, result=res, M=M,
                       jacobians=tuple(out_jacs), members=tuple(members),
                       corner_order=tuple(orders), corner_offsets=tuple(offsets),
                       tilting=_tilting(specs, bil, res, rot, members, M))


def _tilting(specs: Sequence[ContactSpec], bil: Sequence[bool], res: ContactImpact,
             rot: dict[int, FloatArray], members: Iterable[tuple[int, ...]],
             M: FloatArray) -> tuple[str, ...]:
    """Kept flat soles that push on the ground but whose centre of pressure lies outside
    their support polygon (to 1e-9 m, in the sole frame).

    Non-negative corner forces can make a flat sole's normal impulse (``F_z`` and the tilt
    moments) exactly when ``F_z >= 0`` and the centre of pressure lies in the polygon;
    otherwise a corner would have to pull. A sole whose ``F_z`` pulls is
    :meth:`RobotImpact.pulling_contacts`' and one with a round-off ``F_z`` (below 1e-9 of the
    momentum scale ``sqrt(2 T m)``) pushes nowhere: neither is listed.
    """
    offs = [0]
    for u in res.contact_velocity_pre:
        offs.append(offs[-1] + u.shape[0])
    momentum = float(np.sqrt(2.0 * max(float(res.T), 0.0)
                             * (float(M.diagonal().max()) if M.size else 0.0)))
    out = []
    for i, (sp, b, mem) in enumerate(zip(specs, bil, members, strict=True)):
        if not (b and sp.kind in _FLAT):
            continue
        lam = res.impulse[offs[mem[0]]:offs[mem[0]] + 6]
        cop = centre_of_pressure(lam)
        if cop is None or lam[2] <= 1e-9 * momentum:
            continue
        x, y, _ = rot[i].T @ np.array([cop[0], cop[1], 0.0])
        x0, x1, y0, y1 = sp.sole
        tol = 1e-9
        if not (x0 - tol <= x <= x1 + tol and y0 - tol <= y <= y1 + tol):
            out.append(sp.frame)
    return tuple(out)


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


def inert_energy_split(
    robot: Robot,
    q: ArrayLike,
    v: ArrayLike,
    contacts: Sequence[ContactSpec],
    *,
    check: bool = True,
) -> InertImpactBatch:
    """The paper's inert impact with the energy split at one state: all ``contacts`` bilateral.

    The numbers of :func:`robot_impact` with ``keep=contacts`` (and no strike), without its
    report (no ``RobotImpact``: no ``M``, rows, contact velocities or tilting soles): one
    ``crba`` (which leaves the joint Jacobians in the reused ``Data``), one frame Jacobian per
    contact, then one compiled call on the kinematic tree (``heelstrike.robots._inert_kernel``,
    compiled ahead of time on first use): Pinocchio's tree-sparse factorisation
    ``M = U D U^T`` (its ``cholesky::decompose`` algorithm), the Delassus
    matrix ``W = A M^-1 A^T`` with the rows in the nesting order of the split, ``W = L L^T``,
    ``y = L^-1 A q_dot-``, ``lambda = -L^-T y``, ``q_dot+ = q_dot- + M^-1 A^T lambda``,
    ``T_c = 1/2 |y|^2`` (nested normal/tangential shares: the squares of ``y``'s segments),
    ``T_a = T+ = 1/2 q_dot+^T M q_dot+``.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (nq,)
        Configuration at impact.
    v : array_like, shape (nv,)
        Pre-impact velocity ``v-`` (m/s, rad/s).
    contacts : sequence of ContactSpec
        Persistent contacts (bilateral, inert), in report order.
    check : bool
        Validate the state (:meth:`~heelstrike.robots.Robot.check_state`: real, finite, base
        near the origin, unit blocks normalised) and certify the rank of the rows, with the
        reference rank test where the certificate does not hold (default True). With False,
        ``q`` and ``v`` must be float arrays of sizes ``nq`` and ``nv`` (checked) with unit
        quaternions (not checked); a non-positive-definite ``M`` or rank-deficient rows still
        raise.

    Returns
    -------
    InertImpactBatch
        With no leading shape: ``velocity_post`` (nv,), ``impulse`` (k,) in contact order,
        ``T``, ``T_c``, ``T_a``, ``T_post``, ``energy_lost`` numpy scalars (J),
        ``T_c_normal``, ``T_c_tangential`` (contacts,) (J).

    Raises
    ------
    RobotError
        On a bad state or contact list.
    ImpactInputError
        ``M`` not positive definite or rank-deficient rows (e.g. one sole given twice).
    """
    last = robot.cache.get("inert_last")
    if last is not None and contacts is last[0]:  # the same tuple again (immutable)
        path = last[1]
    else:
        specs = _contact_specs("contacts", contacts)
        if not specs:
            raise RobotError("give at least one contact")
        path = _inert_path(robot, specs)
        if type(contacts) is tuple:
            robot.cache["inert_last"] = (contacts, path)
    if check:
        q_, v_ = robot.check_state(q, v)
        v_ = np.ascontiguousarray(v_)
        if path.k > path.n:
            raise ImpactInputError(f"{path.k} contact rows exceed the {path.n} coordinates")
    else:
        q_ = np.asarray(q, dtype=float)
        v_ = np.ascontiguousarray(v, dtype=float)
        if v_.shape != (path.n,) or q_.shape != (robot.model.nq,) or path.k > path.n:
            raise RobotError(f"q and v must have nq={robot.model.nq} and nv={path.n} entries "
                             f"(and at most nv contact rows), got {q_.shape}, {v_.shape}")
    A = path.A
    M = path.assemble(q_, A)
    status = path.item(M, A, v_, path.tree, path.work, path.out, bool(check), 5)
    if status:
        path.raise_for(status, lambda: A)
    return path.single(v_)


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

    The numbers of :func:`inert_energy_split` (and of :func:`robot_impact` with
    ``keep=contacts``) for every configuration, chunk by chunk: Pinocchio fills the mass
    matrices (``crba``) and contact rows of a chunk (one ``Data`` reused), then one compiled
    call solves the chunk on the kinematic tree (``heelstrike.robots._inert_kernel``).

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
        Certify the rank of every configuration's rows, with the reference rank test where the
        certificate does not hold (default True); the states are always checked
        (:meth:`~heelstrike.robots.Robot.check_states`), and a non-positive-definite ``M`` or
        rank-deficient rows always raise.

    Returns
    -------
    InertImpactBatch
        Arrays with leading shape ``(B,)``; impulses in contact order.

    Raises
    ------
    RobotError
        On bad states or contacts.
    ImpactInputError
        For the first configuration whose ``M`` is not positive definite or whose rows are
        rank deficient (named).
    """
    specs = _contact_specs("contacts", contacts)
    if not specs:
        raise RobotError("give at least one contact")
    q_all = robot.check_states(qs)
    v_all = real_array(vs, "velocities")
    if v_all.shape != (q_all.shape[0], robot.nv):
        raise RobotError(
            f"velocities must be (B={q_all.shape[0]}, nv={robot.nv}), got {v_all.shape}"
        )
    if not np.all(np.isfinite(v_all)):
        raise RobotError("q and v must be finite")
    v_all = np.ascontiguousarray(v_all)
    path = _inert_path(robot, specs)
    if path.k > path.n:
        raise ImpactInputError(f"{path.k} contact rows exceed the {path.n} coordinates")
    B = q_all.shape[0]
    size = max(1, min(int(chunk), B))
    Ms = np.empty((size, robot.nv, robot.nv))
    As = np.empty((size, path.k, robot.nv))
    out = np.empty((B, path.out.shape[0]))
    status = np.zeros(B, dtype=np.int64)
    crba, model, data, args = path.crba, path.model, path.data, path.crba_args
    fill, jacobians = path.plan.fill, path.jacobians
    for i in range(0, B, size):
        q_c = q_all[i:i + size]
        for b, q in enumerate(q_c):
            Ms[b] = crba(model, data, q, *args)
            if jacobians is not None:  # pragma: no cover - Pinocchio without conventions
                jacobians(model, data, q)
            fill(data, As[b])
        path.batch(Ms, As, v_all[i:i + size], path.tree, path.work, out[i:i + size],
                   status[i:i + size], bool(check))
    for bad in np.flatnonzero(status):
        i = int(bad)

        def rows(i: int = i) -> FloatArray:
            A = np.empty((path.k, path.n))
            path.assemble(q_all[i], A)
            return A

        path.raise_for(int(status[i]), rows, f" (configuration {i})")
    return path.split(out, v_all)


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
