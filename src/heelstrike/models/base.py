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
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
Foot = Literal["right", "left"]

__all__ = ["Foot", "PlanarWalker", "WalkerScale", "gravity_vector"]


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

    @property
    def scale(self) -> WalkerScale:
        """``(total mass, gravity, leg length)`` of the walker (kg, m/s^2, m).

        The default derives them from the model itself, so that it holds for every walker:
        ``g`` is the weight per unit mass, ``(V(y = 1 m) - V(y = 0)) / m`` on level ground (the
        potential energy is linear in the height ``q[1]``), and ``l`` the distance from the hip
        (joint ``"hip"``, else coordinate 3) to the swing foot's lowest point with every joint
        straight: half the rise of the swing foot's arc centre when the hip turns by pi, plus
        the foot radius. Walkers with these as parameters override it.
        """
        m = np.asarray(self.total_mass, dtype=float)
        n = self.n_coordinates
        names = self.coordinate_names
        hip = names.index("hip") if "hip" in names else 3
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

    def heel_strike_function(self, q: ArrayLike) -> FloatArray:
        """Smooth function that crosses zero upwards when the swing foot strikes ahead.

        Used as the terminal event of single support once the stance leg has passed the
        vertical. The default is minus the swing foot's clearance; walkers override it with a
        form free of the mid-stance scuffing root (see :class:`~heelstrike.models.CompassGait`).
        """
        return np.asarray(-self.foot_clearance(q, "left"))

    def section_to_state(self, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Map Poincare-section coordinates ``z`` (just after heel strike) to ``(q, q_dot)``.

        The stance foot's contact point is placed at ``x = 0``.
        """
        raise NotImplementedError(f"{type(self).__name__} defines no Poincare section")

    def state_to_section(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Inverse of :meth:`section_to_state` (position along the ground is dropped)."""
        raise NotImplementedError(f"{type(self).__name__} defines no Poincare section")

    @property
    def section_names(self) -> tuple[str, ...]:
        """Names of the Poincare-section coordinates."""
        raise NotImplementedError(f"{type(self).__name__} defines no Poincare section")

    def kinetic_energy(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Kinetic energy ``1/2 q_dot^T M q_dot`` (J), shape (...)."""
        v = np.asarray(q_dot, dtype=float)
        return np.asarray(0.5 * np.einsum("...i,...ij,...j->...", v, self.mass_matrix(q), v))

    def mechanical_energy(
        self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0
    ) -> FloatArray:
        """Kinetic plus potential energy (J), shape (...)."""
        return self.kinetic_energy(q, q_dot) + self.potential_energy(q, slope)
