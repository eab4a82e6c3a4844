"""Abstract interface every planar walker model implements.

A walker is described in *floating-base* coordinates ``q`` (length ``n``): ``q[0], q[1]`` are the
(x, y) position of the centre of the stance ("right", index 0) foot's arc in a frame aligned with
the ground (x along the ground, y normal to it), ``q[2]`` the absolute angle of the stance leg
from the ground normal (counter-clockwise positive) and the remaining entries relative joint
angles. Positive stance-leg angular velocity rolls the walker towards ``-x``: walking direction
is ``-x`` throughout the package. Gravity may be tilted by a slope angle ``slope`` (rad); the
ground then descends towards ``-x`` (downhill walking).

The equations of motion have the form (PyDy/sympy.physics.mechanics naming)

.. math:: M(q) \\ddot q + h(q, \\dot q) = B u + A^T \\lambda,

with ``h`` the Coriolis, centrifugal and gravity terms (:meth:`PlanarWalker.bias_forces`).

The walker contract
-------------------
Code above :mod:`heelstrike.models` asks a walker what it is through this interface only (never
by its class): :attr:`PlanarWalker.parameters` (the named parameter vector, with
:meth:`PlanarWalker.replace`), :attr:`PlanarWalker.parameter_shape` and
:attr:`PlanarWalker.is_batched`, :attr:`PlanarWalker.scale`, :attr:`PlanarWalker.description`,
the hybrid schedule of a step (:meth:`PlanarWalker.step_schedule`: phases, guards and resets
as data, run by the one loop :func:`heelstrike.dynamics.hybrid.simulate`), the Poincare section
(:attr:`PlanarWalker.has_poincare_section`,
:meth:`PlanarWalker.section_to_state`, ...) and the simulation backends it runs on
(:attr:`PlanarWalker.compiled_kernel`, :attr:`PlanarWalker.backends`,
:meth:`PlanarWalker.supports`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._typing import FloatArray
from heelstrike.models import _contact
from heelstrike.models._contact import step_length as _step_length
from heelstrike.models.schedule import (
    Guard,
    Phase,
    Stage,
    StepSchedule,
    fell_backward_rate,
    fell_forward,
)

if TYPE_CHECKING:
    from heelstrike.models.builder import GeneratedModel
    from heelstrike.models.description import WalkerDescription

Foot = Literal["right", "left"]
#: A simulation backend: ``"scipy"`` (the reference integrator, every walker) or ``"compiled"``.
Backend = Literal["scipy", "compiled"]
#: The names of the simulation backends, as :data:`Backend` lists them.
BACKEND_NAMES: tuple[str, ...] = get_args(Backend)


def check_backend_name(backend: object, what: str = "backend") -> None:
    """Raise ``ValueError`` unless ``backend`` is one of :data:`BACKEND_NAMES`.

    Parameters
    ----------
    backend : object
        The name given.
    what : str
        The argument's name in the message (``"backend"`` or ``"method"``).
    """
    if backend not in BACKEND_NAMES:
        raise ValueError(f"{what} must be 'scipy' or 'compiled', got {backend!r}")

#: Which compiled kernel simulates a walker: ``"compass"`` (the hand-written compass-gait kernel
#: of :mod:`heelstrike.dynamics.compiled`) or ``"generated"`` (the kernel generated from a
#: walker description, :mod:`heelstrike.dynamics.compiled_phased`).
CompiledKernel = Literal["compass", "generated"]
#: A parameter value: a float, or an array for a batch of walkers (broadcast with states).
ParameterValue = float | FloatArray

__all__ = [
    "BACKEND_NAMES",
    "Backend",
    "CompiledKernel",
    "Foot",
    "ParameterValue",
    "PlanarWalker",
    "WalkerScale",
    "check_backend_name",
    "gravity_vector",
    "is_mcgeer_wheel",
    "section_unit",
]


def is_mcgeer_wheel(foot_radius: ArrayLike, leg_length: ArrayLike) -> NDArray[np.bool_]:
    """Whether a foot radius makes McGeer's synthetic wheel: ``R = l`` (to 1e-12 relative).

    The one definition of the degenerate walker whose two feet are arcs of one circle about
    the hip: after any heel strike the trailing foot's lift velocity is exactly zero (it
    neither lifts nor presses), and the paper's heel strike with imposed velocities
    (``q4_dot = 0``, Figs. 2-3) loses nothing (``T_c = 0``; a swing leg moving relative to the
    stance leg does lose energy).

    Parameters
    ----------
    foot_radius, leg_length : array_like
        ``R`` and ``l`` (m), broadcasting together.

    Returns
    -------
    ndarray of bool
        Their broadcast shape.
    """
    return np.asarray(np.isclose(foot_radius, leg_length, rtol=1e-12, atol=0.0), dtype=bool)


def section_unit(name: str) -> str:
    """The unit of a Poincare-section coordinate, by the naming rule of
    :attr:`PlanarWalker.section_names`: ``"rad/s"`` for a rate (``"<coordinate>_dot"``),
    else ``"rad"``."""
    return "rad/s" if name.endswith("_dot") else "rad"


@dataclass(frozen=True, kw_only=True)
class WalkerScale:
    """The scales of a walker: what dimensionless results (cost of transport, Froude numbers,
    default gains) are made with.

    Attributes
    ----------
    total_mass : ndarray, shape (...)
        Total mass ``m`` (kg).
    gravity : ndarray, shape (...)
        Gravitational acceleration ``g`` (m/s^2).
    leg_length : ndarray, shape (...)
        Leg length ``l`` (m): hip to the foot's lowest point with the leg straight.
    """

    total_mass: FloatArray
    gravity: FloatArray
    leg_length: FloatArray

    def __iter__(self) -> Any:
        return iter((self.total_mass, self.gravity, self.leg_length))


def gravity_vector(gravity: ArrayLike, slope: ArrayLike = 0.0) -> FloatArray:
    """Gravity in the ground-aligned frame for a slope descending towards ``-x``.

    Parameters
    ----------
    gravity : array_like
        Magnitude ``g`` (m/s^2).
    slope : array_like
        Slope angle ``gamma`` (rad), >= 0 for downhill walking towards ``-x``.

    Returns
    -------
    ndarray, shape (..., 2)
        ``g (-sin gamma, -cos gamma)`` (m/s^2).
    """
    g = np.asarray(gravity, dtype=float)
    gam = np.asarray(slope, dtype=float)
    return np.stack(np.broadcast_arrays(-g * np.sin(gam), -g * np.cos(gam)), axis=-1)


class PlanarWalker(ABC):
    """Abstract planar biped in floating-base coordinates (see module docstring)."""

    #: Names of the generalized coordinates, in order.
    coordinate_names: tuple[str, ...]

    @property
    def n_coordinates(self) -> int:
        """Number of generalized coordinates ``n`` in flight."""
        return len(self.coordinate_names)

    @property
    @abstractmethod
    def total_mass(self) -> FloatArray:
        """Total mass (kg)."""

    @property
    @abstractmethod
    def foot_radii(self) -> tuple[FloatArray, FloatArray]:
        """Foot arc radii (m) of the stance ("right") and swing ("left") foot."""

    @abstractmethod
    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """Mass matrix ``M(q)``, shape (..., n, n)."""

    @abstractmethod
    def bias_forces(self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0) -> FloatArray:
        """Velocity-product and gravity terms ``h`` in ``M q_ddot + h = Q``, shape (..., n)."""

    def dynamics_terms(
        self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0
    ) -> tuple[FloatArray, FloatArray]:
        """``(M(q), h(q, q_dot))`` in one call, shapes (..., n, n) and (..., n).

        What a right-hand side evaluation needs; equal to ``(mass_matrix(q),
        bias_forces(q, q_dot, slope))``. Walkers override it to share the kinematics (point
        Jacobians) between the two terms.
        """
        return self.mass_matrix(q), self.bias_forces(q, q_dot, slope)

    @abstractmethod
    def potential_energy(self, q: ArrayLike, slope: ArrayLike = 0.0) -> FloatArray:
        """Gravitational potential energy (J), zero at the ground frame origin, shape (...)."""

    @abstractmethod
    def contact_jacobian(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Rolling-contact Jacobian of a foot on the ground, shape (..., 2, n).

        Rows: tangential (x) and normal (y) velocity of the foot's material contact point.
        """

    @abstractmethod
    def contact_jacobian_rate(self, q: ArrayLike, q_dot: ArrayLike, foot: Foot) -> FloatArray:
        """``A_dot q_dot`` for the foot's contact Jacobian, shape (..., 2)."""

    @abstractmethod
    def foot_clearance(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Height (m) of the foot arc's lowest point above the ground, shape (...)."""

    @abstractmethod
    def contact_point(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Ground point below the foot's arc centre (x, y) (m), shape (..., 2)."""

    @abstractmethod
    def swap_legs(self, q: ArrayLike, q_dot: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Relabel the state so that the left (striking) foot becomes the stance foot."""

    @abstractmethod
    def actuation_matrix(self) -> FloatArray:
        """Matrix ``B`` (n, n_u) mapping actuator torques to generalized forces."""

    def replace(self, **params: Any) -> PlanarWalker:
        """A copy with some named parameters changed (validated again)."""
        raise NotImplementedError(f"{type(self).__name__} has no named parameters to replace")

    def after_swap(self) -> PlanarWalker:
        """The walker that takes the next step, after the heel strike's leg swap.

        The walker itself (the default) when the swap is a symmetry: both legs alike, one step
        is the period. A walker whose legs differ (an amputee with a prosthetic leg) is
        another parameter set after the swap (the swing leg's parameters now the stance
        leg's), and ``w.after_swap().after_swap()`` is ``w`` again.
        """
        return self

    @property
    def steps_per_period(self) -> int:
        """Steps of the walker's periodic gait on the Poincare section: 1 when the leg swap is
        a symmetry (:meth:`after_swap` is the walker itself), else 2 (the stride: a step on
        each leg; the Poincare map is the stride map)."""
        return 1 if self.after_swap() is self else 2

    # -- the walker contract: what analyses may ask ------------------------------------------
    @property
    def parameters(self) -> Mapping[str, ParameterValue]:
        """The named parameter vector: a read-only mapping ``name -> value`` (SI units).

        Values are floats, or arrays for a batch of walkers (see :attr:`parameter_shape`);
        :meth:`replace` takes the same names. The default is empty (no named parameters).
        """
        return MappingProxyType({})

    @property
    def parameter_shape(self) -> tuple[int, ...]:
        """Broadcast shape of the parameter values: ``()`` for one walker, else the batch's."""
        return tuple(np.broadcast_shapes(*(np.shape(v) for v in self.parameters.values())))

    @property
    def is_batched(self) -> bool:
        """True if some parameter is an array (a batch of walkers), False for one walker."""
        return self.parameter_shape != ()

    @property
    def description(self) -> WalkerDescription | None:
        """The description the walker was built from, or None (a hand-written model)."""
        return None

    def as_described(self) -> PlanarWalker | None:
        """The same walker built from a description, or None (the default: there is none).

        A hand-written walker whose equations a shipped walker file also states returns that
        walker with its parameter values (e.g. the compass gait's ``compass.toml``). The compiled
        backend runs it on the kernel generated from the description where the walker's own
        kernel cannot: push-off, a friction limit, dense samples (:mod:`heelstrike.dynamics`).
        """
        return None

    @property
    def generated_model(self) -> GeneratedModel | None:
        """The walker's own generated equations (a described walker's), or None (the default:
        a hand-written walker; its :meth:`as_described` twin may have them)."""
        return None

    @property
    def profile_ranges(self) -> tuple[tuple[float, float] | None, tuple[float, float] | None]:
        """``(phi_min, phi_max)`` (rad) over which the stance and the swing foot's roll-over
        profile is given, None for a foot defined at every contact angle (an arc or a point:
        the default). A walker file's ``[[foot]] phi_range`` sets it."""
        return (None, None)

    def profile_margin(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """How far (rad) a foot's contact angle is inside its profile's range, shape (...):
        negative beyond it; ``+inf`` for a foot defined at every angle (the default)."""
        return np.full(np.shape(np.asarray(q, dtype=float))[:-1], np.inf)

    def profile_excursion(self, q: ArrayLike, tol: float = 1e-9) -> str | None:
        """Which foot's contact angle is at or beyond its profile's range at ``q`` (shape
        (n,)), in words, or None (the default: no foot has a range). The message of a walk
        ending in ``off_profile``."""
        return None

    @property
    def section_solved_coordinate(self) -> int | None:
        """The coordinate the Poincare section solves for from the others (a described
        walker's touchdown configuration: the hip, placing the swing foot on the ground), or
        None (the default: the section fixes every coordinate explicitly, e.g. the compass
        gait's affine ``q4 = -2 q3``)."""
        return None

    @property
    def powered_speed(self) -> float | None:
        """The walker's declared target mean speed (m/s) for a powered gait on level ground.

        What ``heelstrike powered`` seeks when given neither ``--speed`` nor ``--step-length``:
        a speed inside the walker's family of push-off gaits, declared by the walker (a walker
        file's ``[powered] speed``), never assumed by the caller. None (the default): the
        walker declares none.
        """
        return None

    @property
    def compiled_kernel(self) -> CompiledKernel | None:
        """Which compiled kernel simulates this walker (:data:`CompiledKernel`), or None.

        The default is None: only the scipy reference backend.
        """
        return None

    @property
    def backends(self) -> tuple[Backend, ...]:
        """The simulation backends this walker runs on: ``"scipy"`` always, then
        ``"compiled"`` if it has a :attr:`compiled_kernel`."""
        return ("scipy", "compiled") if self.compiled_kernel is not None else ("scipy",)

    def supports(self, backend: str) -> bool:
        """Whether the walker runs on a simulation backend (``"scipy"`` or ``"compiled"``)."""
        return backend in self.backends

    def step_length(self, q_start: ArrayLike, q_impact: ArrayLike) -> FloatArray:
        """The length of a step (m): the one definition every simulation backend reports.

        :func:`heelstrike.models._contact.step_length` of the stance ("right") foot's contact
        point at the start of the step and the striking ("left") foot's at heel strike (the
        stance foot's rolled arc included; pre-swap labels).

        Parameters
        ----------
        q_start : array_like, shape (..., n)
            Configuration at the start of the step (stance foot labelled "right").
        q_impact : array_like, shape (..., n)
            Configuration at heel strike, same labels.

        Returns
        -------
        ndarray, shape (...)
            Step length along the ground (m), positive walking towards ``-x``.
        """
        x_start = np.asarray(self.contact_point(q_start, "right")[..., 0], dtype=float)
        x_impact = np.asarray(self.contact_point(q_impact, "left")[..., 0], dtype=float)
        return np.asarray(_step_length(x_start, x_impact))  # type: ignore[arg-type]

    def swing_leg_angle(self, q: ArrayLike) -> FloatArray:
        """Absolute angle (rad) of the link hanging from the hip: the swing leg (or thigh).

        Measured as the stance angle ``q[2]``; linear in ``q``, so the same map of ``q_dot``
        gives its rate. Here the compass gait's ``q3 + q4`` (the hip angle is relative to the
        stance leg); a described walker adds up its chain of links.

        Parameters
        ----------
        q : array_like, shape (..., n)

        Returns
        -------
        ndarray, shape (...)
        """
        q_ = np.asarray(q, dtype=float)
        return np.asarray(q_[..., 2] + q_[..., self.hip_joint])

    def trailing_foot_presses(self, q: ArrayLike, q_dot: ArrayLike) -> NDArray[np.bool_]:
        """Whether the trailing foot of a step's start is on the ground and moving into it.

        A state just after a heel strike (the start of a step) has its trailing ("left") foot
        on the ground, ``|clearance| <= CONTACT_TOLERANCE l``, and lifting, or grazing for
        McGeer's wheel (:mod:`heelstrike.models._contact`). A start for which this returns True
        is the state after no heel strike: the foot would sink into the ground.

        Parameters
        ----------
        q, q_dot : array_like, shape (..., n)
            States with the stance foot labelled "right" (rad, m; rad/s, m/s).

        Returns
        -------
        ndarray of bool, shape (...)
            Trailing foot touching the ground with normal velocity
            ``v_n < -LIFT_TOLERANCE l sum_j |q_j_dot|``
            (:func:`~heelstrike.models._contact.presses`).
        """
        q_, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        leg = float(np.asarray(self.scale.leg_length))
        touching = np.abs(self.foot_clearance(q_, "left")) <= _contact.CONTACT_TOLERANCE * leg
        normal_velocity = np.einsum("...j,...j->...", self.contact_jacobian(q_, "left")[..., 1, :],
                                    qd)
        scale = leg * np.sum(np.abs(qd[..., 2:]), axis=-1)
        return np.asarray(touching & _contact.presses(normal_velocity, scale))

    @property
    def has_poincare_section(self) -> bool:
        """Whether the walker defines a Poincare section (:meth:`section_to_state`,
        :meth:`state_to_section`, :attr:`section_names`): True when it overrides them."""
        return type(self).section_to_state is not PlanarWalker.section_to_state

    @property
    def n_section_angles(self) -> int:
        """Number of leading angle coordinates (rad) of the Poincare section.

        :attr:`section_names` lists the angles first, then the rates (rad/s), named
        ``"<coordinate>_dot"``; every angle's rate is in the section (e.g. the compass gait's
        ``("q3", "q3_dot", "q4_dot")`` has one angle).
        """
        names = self.section_names
        return sum(f"{name}_dot" in names for name in names)

    @property
    def hip_joint(self) -> int:
        """Coordinate index of the hip: the joint named ``"hip"``, else coordinate 3 (the
        compass gait's inter-leg angle ``q4``, relative to the stance leg).

        The one definition of where the hip is: the hip torque laws
        (:mod:`heelstrike.dynamics.actuation`) act across it and :attr:`scale` measures the
        leg length from it.
        """
        names = self.coordinate_names
        return names.index("hip") if "hip" in names else 3

    @property
    def scale(self) -> WalkerScale:
        """``(total mass, gravity, leg length)`` of the walker (kg, m/s^2, m).

        The default derives them from the model itself, so that it holds for every walker:
        ``g`` is the weight per unit mass, ``(V(y = 1 m) - V(y = 0)) / m`` on level ground (the
        potential energy is linear in the height ``q[1]``), and ``l`` the distance from the hip
        (:attr:`hip_joint`) to the swing foot's lowest point with every joint
        straight: half the rise of the swing foot's arc centre when the hip turns by pi, plus
        the foot radius. Walkers with these as parameters override it.
        """
        m = np.asarray(self.total_mass, dtype=float)
        n = self.n_coordinates
        hip = self.hip_joint
        r_stance, r_swing = (np.asarray(r, dtype=float) for r in self.foot_radii)
        q0 = np.zeros((*np.broadcast_shapes(m.shape, r_stance.shape), n))
        q0[..., 1] = r_stance
        q_up = q0.copy()
        q_up[..., 1] += 1.0
        g = (self.potential_energy(q_up) - self.potential_energy(q0)) / m
        q_flip = q0.copy()
        q_flip[..., hip] = np.pi
        rise = self.foot_clearance(q_flip, "left") - self.foot_clearance(q0, "left")
        return WalkerScale(
            total_mass=m, gravity=np.asarray(g), leg_length=np.asarray(0.5 * rise + r_swing)
        )

    @property
    def is_wheel(self) -> bool:
        """Whether the walker is McGeer's synthetic wheel: its stance foot radius is its leg
        length (:func:`is_mcgeer_wheel` of ``foot_radii[0]`` and ``scale.leg_length``; for a
        batched walker, every member)."""
        return bool(np.all(is_mcgeer_wheel(self.foot_radii[0], self.scale.leg_length)))

    def heel_strike_function(self, q: ArrayLike) -> FloatArray:
        """Smooth function that crosses zero upwards when the swing foot strikes ahead.

        Used as the terminal event of single support once the stance leg has passed the
        vertical. The default is minus the swing foot's clearance; walkers override it with a
        form free of the mid-stance scuffing root (see :class:`~heelstrike.models.CompassGait`).
        """
        return np.asarray(-self.foot_clearance(q, "left"))

    def step_schedule(self, *, knee_flex_threshold: float = 1e-6) -> StepSchedule:
        """The hybrid schedule of one step (:mod:`heelstrike.models.schedule`).

        The default, the classical compass-gait step (Goswami et al. 1998; Garcia et al. 1998):
        one phase, first until the stance leg passes the vertical (``q3`` rising through 0;
        skipped if ``q3 >= 0`` at the start; ``q3_dot`` falling through 0 first is a fall
        backward), then until :meth:`heel_strike_function` rises through zero (``q3`` falling
        through 0 is a fall backward, ``q3`` reaching ``pi/2`` a fall forward). The heel strike
        is the paper's projector with the striking foot's rows (eq. 13), then the trailing foot
        must lift. Scuffing of the swing foot near mid-stance is ignored.

        Parameters
        ----------
        knee_flex_threshold : float
            Unused here (no lockable joints); see :class:`~heelstrike.models.BuiltWalker`.
        """
        midstance = Stage(
            until=Guard(name="midstance", function=lambda q, qd: float(q[2]), direction=1),
            failures=(fell_backward_rate(),),
            skip=lambda q, qd: bool(q[2] >= 0.0),
        )
        strike = Stage(
            until=Guard(
                name="heel_strike",
                function=lambda q, qd: float(self.heel_strike_function(q)),
                direction=1,
            ),
            failures=(
                Guard(name="fell_backward", function=lambda q, qd: float(q[2]), direction=-1),
                fell_forward(),
            ),
        )
        return StepSchedule(
            phases=(Phase(name="locked_swing", locked=(), stages=(midstance, strike),
                          reset="heel_strike"),),
            trailing_foot="lift_rule",
        )

    def section_to_state(self, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Map Poincare-section coordinates ``z`` (just after heel strike) to ``(q, q_dot)``.

        The stance foot's contact point is placed at ``x = 0``.
        """
        raise NotImplementedError(f"{type(self).__name__} defines no Poincare section")

    def section_point(
        self, stance_angle: float, stance_rate: float, swing_rate: float
    ) -> FloatArray:
        """A point of the Poincare section laid out from the compass gait's three numbers.

        The one layout every gait search seeds with: the first section angle is
        ``stance_angle`` (rad; the stance leg just after heel strike, < 0), the first two rates
        ``stance_rate`` and ``swing_rate`` (rad/s); further section angles (e.g. a torso joint
        relative to the stance leg) are ``-stance_angle`` and their rates ``-stance_rate``:
        the further links start upright, not turning. For the compass gait this is
        ``(q3, q3_dot, q4_dot)`` itself.

        Returns
        -------
        ndarray, shape (d,)
            In the order of :attr:`section_names`.
        """
        d = len(self.section_names)
        n_ang = self.n_section_angles
        z = np.zeros(d)
        z[0], z[n_ang], z[n_ang + 1] = stance_angle, stance_rate, swing_rate
        z[1:n_ang] = -stance_angle
        z[n_ang + 2 :] = -stance_rate
        return z

    def state_to_section(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Inverse of :meth:`section_to_state` (position along the ground is dropped)."""
        raise NotImplementedError(f"{type(self).__name__} defines no Poincare section")

    @property
    def section_names(self) -> tuple[str, ...]:
        """Names of the Poincare-section coordinates: angles (rad), then rates named
        ``"<coordinate>_dot"`` (rad/s)."""
        raise NotImplementedError(f"{type(self).__name__} defines no Poincare section")

    @property
    def section_labels(self) -> tuple[tuple[str, str], ...]:
        """:attr:`section_names` with their units (:func:`section_unit`),
        ``(("q3", "rad"), ("q3_dot", "rad/s"), ...)``: for reports and messages."""
        return tuple((n, section_unit(n)) for n in self.section_names)

    def kinetic_energy(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Kinetic energy ``1/2 q_dot^T M q_dot`` (J), shape (...)."""
        v = np.asarray(q_dot, dtype=float)
        return np.asarray(0.5 * np.einsum("...i,...ij,...j->...", v, self.mass_matrix(q), v))

    def mechanical_energy(
        self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0
    ) -> FloatArray:
        """Kinetic plus potential energy (J), shape (...)."""
        return self.kinetic_energy(q, q_dot) + self.potential_energy(q, slope)
