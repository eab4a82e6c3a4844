"""The compass-gait biped with circular feet of Font & Kövecses (2008).

Frame and coordinates (4 DOF in flight), the paper's (Fig. 1): ``x`` along the ground, walking
towards ``-x``, ``y`` along the ground normal; angles from the ground normal, counter-clockwise
positive; on a slope ``gamma`` (downhill towards ``-x``) gravity is ``g (-sin gamma, -cos gamma)``
in this frame. The right leg is the stance leg (its foot rolls on the ground without slipping):

- ``q1, q2``: position of ``P_R``, the centre of the right foot's arc;
- ``q3``: absolute angle of the right leg from the ground normal (counter-clockwise positive);
- ``q4``: angle of the left leg relative to the right one.

With ``e(theta) = (-sin theta, cos theta)`` and ``s = l - R``: hip ``H = P_R + s e(q3)``, left arc
centre ``P_L = H - s e(q3 + q4)``, leg centres of mass ``H - b e(leg angle)``.

The mass matrix is assembled by hand from the point Jacobians,
``M = sum_i m_i J_i^T J_i + I (w_R w_R^T + w_L w_L^T)``; ``tests/`` check it against an
independent sympy Lagrangian derivation. Every function broadcasts over leading axes of ``q`` and
over array-valued parameters (e.g. a grid of foot radii). The shipped walker file
``walkers/compass.toml`` describes the same walker with the same coordinates (the conventions of
walker files: :doc:`/walker_files`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass, fields, replace
from types import MappingProxyType
from typing import Any, ClassVar, NamedTuple, final

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import tuple_dict
from heelstrike._typing import FloatArray
from heelstrike.models.base import (
    CompiledKernel,
    Foot,
    ParameterValue,
    PlanarWalker,
    WalkerScale,
    gravity_vector,
)

__all__ = ["DESCRIBED_PARAMETERS", "CompassGait", "CompassPositions", "heel_strike_state"]

#: The compass gait's parameters (field names) and their names in the shipped walker file
#: ``compass.toml`` (:meth:`CompassGait.as_described`).
DESCRIBED_PARAMETERS: Mapping[str, str] = MappingProxyType({
    "hip_mass": "mH", "leg_mass": "m", "leg_length": "l", "leg_com_from_hip": "b",
    "foot_radius": "R", "leg_inertia": "I", "gravity": "g",
})


class WalkerParameterError(ValueError):
    """Raised when walker parameters are physically invalid."""


class _Columns(NamedTuple):
    """Unit leg vectors and non-trivial point-Jacobian columns (``(x, y)`` pairs), see
    :meth:`CompassGait._jacobian_columns`."""

    e3: tuple[Any, Any]
    e34: tuple[Any, Any]
    s: Any
    H3: tuple[Any, Any]
    R3: tuple[Any, Any]
    L3: tuple[Any, Any]
    L4: tuple[Any, Any]
    #: Computed for one state on Python floats (every entry a ``float``).
    scalar: bool


class CompassPositions(NamedTuple):
    """Positions (m) of the compass gait's points, each of shape (..., 2)."""

    hip: FloatArray
    right_foot_centre: FloatArray
    left_foot_centre: FloatArray
    right_contact: FloatArray
    left_contact: FloatArray
    right_leg_com: FloatArray
    left_leg_com: FloatArray

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain Python (:func:`~heelstrike._results.tuple_dict`)."""
        return tuple_dict(self)


def _e(theta: FloatArray) -> FloatArray:
    """Unit vector up a leg at absolute angle ``theta``: ``(-sin, cos)``, shape (..., 2)."""
    return np.stack((-np.sin(theta), np.cos(theta)), axis=-1)


def _de(theta: FloatArray) -> FloatArray:
    """Derivative of :func:`_e`: ``(-cos, -sin)``, shape (..., 2)."""
    return np.stack((-np.cos(theta), -np.sin(theta)), axis=-1)


def _q(q: ArrayLike, n: int = 4, name: str = "q") -> FloatArray:
    arr = np.asarray(q, dtype=float)
    if arr.ndim < 1 or arr.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}), got {arr.shape}")
    return arr


@final
@dataclass(frozen=True, kw_only=True, eq=False)
class CompassGait(PlanarWalker):
    """Compass-gait biped with circular feet (paper Fig. 1).

    Defaults are the paper's values: ``mH = 2 m = 10 kg``, ``a = b = 0.5 m``, ``l = 1 m``.
    Any parameter may be an array; arrays broadcast with the leading axes of states.

    Parameters
    ----------
    hip_mass : float
        Hip point mass ``mH`` (kg), > 0.
    leg_mass : float
        Mass ``m`` of each leg (kg), > 0.
    leg_length : float
        Leg length ``l`` from hip to the foot's lowest point (m), > 0.
    leg_com_from_hip : float
        Distance ``b`` from the hip to a leg's centre of mass (m), ``0 < b < l``.
    foot_radius : float
        Foot arc radius ``R`` (m), ``0 <= R <= l``; the arc centre lies on the leg at ``l - R``
        from the hip. ``R = 0`` is the point-foot compass gait, ``R = l`` McGeer's wheel.
    leg_inertia : float
        Moment of inertia of each leg about its centre of mass (kg m^2), >= 0 (default 0:
        point-mass legs, as in the paper).
    gravity : float
        Gravitational acceleration ``g`` (m/s^2), > 0.
    """

    hip_mass: Any = 10.0
    leg_mass: Any = 5.0
    leg_length: Any = 1.0
    leg_com_from_hip: Any = 0.5
    foot_radius: Any = 0.0
    leg_inertia: Any = 0.0
    gravity: Any = 9.81

    coordinate_names = ("q1", "q2", "q3", "q4")
    #: Every parameter is a scalar (set per instance): one state runs on Python floats.
    _scalar: ClassVar[bool] = False

    def __post_init__(self) -> None:
        for f in fields(self):
            val = np.asarray(getattr(self, f.name), dtype=float)
            if not np.all(np.isfinite(val)):
                raise WalkerParameterError(f"{f.name} must be finite, got {val}")
            object.__setattr__(self, f.name, float(val) if val.ndim == 0 else val)
        # (holds, rule, the fields it involves): every failed rule is reported, with the values
        # of its fields only (QA sweep 9: one rule was named, with all seven values)
        checks = [
            (np.all(np.asarray(self.hip_mass) > 0), "hip_mass must be > 0 (kg)", ("hip_mass",)),
            (np.all(np.asarray(self.leg_mass) > 0), "leg_mass must be > 0 (kg)", ("leg_mass",)),
            (np.all(np.asarray(self.leg_length) > 0), "leg_length must be > 0 (m)",
             ("leg_length",)),
            (np.all(np.asarray(self.gravity) > 0), "gravity must be > 0 (m/s^2)", ("gravity",)),
            (np.all(np.asarray(self.leg_inertia) >= 0), "leg_inertia must be >= 0 (kg m^2)",
             ("leg_inertia",)),
            (
                np.all((self.leg_com_from_hip > 0) & (self.leg_com_from_hip < self.leg_length)),
                "leg_com_from_hip must satisfy 0 < b < leg_length (m)",
                ("leg_length", "leg_com_from_hip"),
            ),
            (
                np.all((self.foot_radius >= 0) & (self.foot_radius <= self.leg_length)),
                "foot_radius must satisfy 0 <= R <= leg_length (m)",
                ("leg_length", "foot_radius"),
            ),
        ]
        failed = [(msg, names) for ok, msg, names in checks if not ok]
        if failed:
            involved = {name for _, names in failed for name in names}
            raise WalkerParameterError(
                f"{'; '.join(msg for msg, _ in failed)}; got {self._values_text(involved)}"
            )
        # One state of a walker with scalar parameters: the dynamics run on Python floats.
        object.__setattr__(
            self, "_scalar", all(isinstance(getattr(self, f.name), float) for f in fields(self))
        )

    def _values_text(self, names: Collection[str]) -> str:
        """The values of the parameters ``names`` (field order), for messages (arrays by their
        range)."""

        def one(v: Any) -> str:
            a = np.asarray(v, dtype=float)
            if a.ndim == 0 or a.min() == a.max():  # one value, however broadcast
                return f"{float(a.flat[0]):.12g}"
            return f"{a.min():.12g}..{a.max():.12g}"

        return ", ".join(f"{f.name} = {one(getattr(self, f.name))}" for f in fields(self)
                         if f.name in names)

    # -- the walker contract -------------------------------------------------------------------
    def replace(self, **changes: Any) -> CompassGait:
        """Return a copy with some parameters changed (validated again)."""
        return replace(self, **changes)

    @property
    def parameters(self) -> Mapping[str, ParameterValue]:
        """The seven parameters by field name (``hip_mass`` ... ``gravity``, SI units)."""
        return MappingProxyType({f.name: getattr(self, f.name) for f in fields(self)})

    @property
    def parameter_shape(self) -> tuple[int, ...]:
        """Broadcast shape of the parameters: ``()`` when every one is a float."""
        return () if self._scalar else super().parameter_shape

    @property
    def compiled_kernel(self) -> CompiledKernel | None:
        """``"compass"``: the hand-written kernel of :mod:`heelstrike.dynamics.compiled`.

        None for a subclass that declares another step (its own
        :meth:`~heelstrike.models.base.PlanarWalker.step_schedule` or
        :meth:`heel_strike_function`): the kernel runs the compass gait's schedule only, so such
        a walker runs on the scipy reference only.
        """
        standard = (
            type(self).step_schedule is CompassGait.step_schedule
            and type(self).heel_strike_function is CompassGait.heel_strike_function
        )
        return "compass" if standard else None

    def as_described(self) -> PlanarWalker | None:
        """This walker as the shipped description ``compass.toml`` with the same parameter
        values (``mH, m, l, b, R, I, g``): the same equations (its conformance tests check them
        to round-off) and the same coordinates ``q``. None for a subclass with its own step
        (no :attr:`compiled_kernel`), a batch of walkers, or a description that cannot walk
        (:meth:`~heelstrike.models.builder.BuiltWalker.check_heel_strike_detectable`: McGeer's
        wheel ``R = l``, where both foot arcs are one circle about the hip and the description's
        heel-strike guard, the swing foot's clearance, is round-off; this walker's guard
        ``2 q3 + q4`` is not). Built once per parameter values (the result is frozen).
        """
        if self.compiled_kernel is None or self.is_batched:
            return None
        return _described_compass(tuple(float(getattr(self, field))
                                        for field in DESCRIBED_PARAMETERS))

    @property
    def powered_speed(self) -> float | None:
        """0.5 m/s: the compass gait's declared target speed for a powered gait.

        The default of ``heelstrike powered`` without ``--model``; inside the level push-off,
        energy-tracking and swing-leg PD gaits at ``R = 0`` and ``0.3 m`` with the default gains
        (``walkers/compass.toml`` declares the same in its ``[powered]`` table).
        """
        return 0.5

    @property
    def total_mass(self) -> FloatArray:
        return np.asarray(self.hip_mass + 2.0 * self.leg_mass)

    @property
    def scale(self) -> WalkerScale:
        """``(mH + 2 m, g, l)`` (kg, m/s^2, m)."""
        return WalkerScale(
            total_mass=self.total_mass,
            gravity=np.asarray(self.gravity, dtype=float),
            leg_length=np.asarray(self.leg_length, dtype=float),
        )

    @property
    def foot_radii(self) -> tuple[FloatArray, FloatArray]:
        R = np.asarray(self.foot_radius, dtype=float)
        return R, R

    def _p(self, name: str, q: FloatArray) -> FloatArray:
        """Parameter broadcast to the leading shape of ``q``."""
        return np.asarray(getattr(self, name), dtype=float)

    # -- kinematics ---------------------------------------------------------------------------
    def positions(self, q: ArrayLike) -> CompassPositions:
        """Positions of hip, foot centres, contact points and leg centres of mass (m)."""
        q_ = _q(q)
        l, b, R = (self._p(k, q_) for k in ("leg_length", "leg_com_from_hip", "foot_radius"))
        s = (l - R)[..., None]
        P_R = q_[..., 0:2]
        e3, e34 = _e(q_[..., 2]), _e(q_[..., 2] + q_[..., 3])
        H = P_R + s * e3
        P_L = H - s * e34
        down = np.stack(np.broadcast_arrays(np.zeros_like(R), -R), axis=-1)
        return CompassPositions(
            hip=H,
            right_foot_centre=np.broadcast_to(P_R, H.shape),
            left_foot_centre=P_L,
            right_contact=P_R + down,
            left_contact=P_L + down,
            right_leg_com=H - b[..., None] * e3,
            left_leg_com=H - b[..., None] * e34,
        )

    def contact_point(self, q: ArrayLike, foot: Foot) -> FloatArray:
        pos = self.positions(q)
        return pos.right_contact if _foot(foot) == "right" else pos.left_contact

    def foot_clearance(self, q: ArrayLike, foot: Foot) -> FloatArray:
        return np.asarray(self.contact_point(q, foot)[..., 1])

    # -- dynamics -----------------------------------------------------------------------------
    def _jacobian_columns(self, q: FloatArray) -> _Columns:
        """The non-trivial columns of the point Jacobians of the hip and the legs' centres of mass.

        Every point Jacobian is ``[I_2, c3, c4]``; ``c4`` vanishes for the hip and the right
        leg. Each column is an ``(x, y)`` pair of arrays (or scalars) broadcast like ``q[..., 0]``
        and the parameters, so one state costs scalar arithmetic only.
        """
        l, b, R = self.leg_length, self.leg_com_from_hip, self.foot_radius
        s = l - R
        scalar = q.ndim == 1 and self._scalar
        q3: Any
        q34: Any
        if scalar:
            q3 = float(q[2])
            q34 = q3 + float(q[3])
            c3, s3 = math.cos(q3), math.sin(q3)
            c34, s34 = math.cos(q34), math.sin(q34)
        else:
            q3 = q[..., 2]
            q34 = q3 + q[..., 3]
            c3, s3, c34, s34 = np.cos(q3), np.sin(q3), np.cos(q34), np.sin(q34)
        # _de(theta) = (-cos theta, -sin theta)
        de3 = (-c3, -s3)
        de34 = (-c34, -s34)
        cL4 = (-b * de34[0], -b * de34[1])
        return _Columns(
            e3=(-s3, c3),
            e34=(-s34, c34),
            s=s,
            H3=(s * de3[0], s * de3[1]),
            R3=((s - b) * de3[0], (s - b) * de3[1]),
            L3=(s * de3[0] + cL4[0], s * de3[1] + cL4[1]),
            L4=cL4,
            scalar=scalar,
        )

    def _mass_from(self, c: _Columns, lead: tuple[int, ...]) -> FloatArray:
        """``M = sum_i m_i J_i^T J_i + I (w_R w_R^T + w_L w_L^T)`` from the Jacobian columns."""
        mH, m, inertia = self.hip_mass, self.leg_mass, self.leg_inertia
        H3, R3, L3, L4 = c.H3, c.R3, c.L3, c.L4
        total = mH + 2.0 * m
        col2 = (mH * H3[0] + m * (R3[0] + L3[0]), mH * H3[1] + m * (R3[1] + L3[1]))
        col3 = (m * L4[0], m * L4[1])
        m22 = (
            mH * (H3[0] * H3[0] + H3[1] * H3[1])
            + m * (R3[0] * R3[0] + R3[1] * R3[1] + L3[0] * L3[0] + L3[1] * L3[1])
            + 2.0 * inertia
        )
        m23 = m * (L3[0] * L4[0] + L3[1] * L4[1]) + inertia
        m33 = m * (L4[0] * L4[0] + L4[1] * L4[1]) + inertia
        if c.scalar and lead == ():
            return np.array(
                (
                    (total, 0.0, col2[0], col3[0]),
                    (0.0, total, col2[1], col3[1]),
                    (col2[0], col2[1], m22, m23),
                    (col3[0], col3[1], m23, m33),
                )
            )
        entries = (total, *col2, *col3, m22, m23, m33)
        M = np.empty((*np.broadcast_shapes(lead, *(np.shape(e) for e in entries)), 4, 4))
        M[..., 0, 0] = total
        M[..., 1, 1] = total
        M[..., 0, 1] = 0.0
        M[..., 1, 0] = 0.0
        for i in (0, 1):
            M[..., i, 2] = M[..., 2, i] = col2[i]
            M[..., i, 3] = M[..., 3, i] = col3[i]
        M[..., 2, 2] = m22
        M[..., 2, 3] = M[..., 3, 2] = m23
        M[..., 3, 3] = m33
        return M

    def _bias_from(
        self, c: _Columns, q_dot: FloatArray, slope: ArrayLike, lead: tuple[int, ...]
    ) -> FloatArray:
        """``h = sum_i m_i J_i^T (a_i - g)`` from the Jacobian columns (see :meth:`bias_forces`)."""
        mH, m, b = self.hip_mass, self.leg_mass, self.leg_com_from_hip
        scalar = c.scalar and lead == () and (isinstance(slope, float) or np.ndim(slope) == 0)
        if scalar:
            w3: Any = float(q_dot[2])
            w34: Any = w3 + float(q_dot[3])
            gam = float(slope)  # type: ignore[arg-type]
            g = (-self.gravity * math.sin(gam), -self.gravity * math.cos(gam))
        else:
            w3 = q_dot[..., 2]
            w34 = w3 + q_dot[..., 3]
            gam_ = np.asarray(slope, dtype=float)
            g = (-self.gravity * np.sin(gam_), -self.gravity * np.cos(gam_))
        s, e3, e34 = c.s, c.e3, c.e34
        k3, k34 = w3 * w3, w34 * w34
        # f_i = a_i - g: velocity-product acceleration of each point less gravity
        f_H = (-s * e3[0] * k3 - g[0], -s * e3[1] * k3 - g[1])
        f_R = (-(s - b) * e3[0] * k3 - g[0], -(s - b) * e3[1] * k3 - g[1])
        f_L = (
            -s * e3[0] * k3 + b * e34[0] * k34 - g[0],
            -s * e3[1] * k3 + b * e34[1] * k34 - g[1],
        )
        H3, R3, L3, L4 = c.H3, c.R3, c.L3, c.L4
        h01 = (mH * f_H[0] + m * (f_R[0] + f_L[0]), mH * f_H[1] + m * (f_R[1] + f_L[1]))
        h2 = mH * (H3[0] * f_H[0] + H3[1] * f_H[1]) + m * (
            R3[0] * f_R[0] + R3[1] * f_R[1] + L3[0] * f_L[0] + L3[1] * f_L[1]
        )
        h3 = m * (L4[0] * f_L[0] + L4[1] * f_L[1])
        if scalar:
            return np.array((h01[0], h01[1], h2, h3))
        entries = (*h01, h2, h3)
        h = np.empty((*np.broadcast_shapes(lead, *(np.shape(e) for e in entries)), 4))
        for i, e in enumerate(entries):
            h[..., i] = e
        return h

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """Mass matrix ``M(q)`` of eq. (1), shape (..., 4, 4).

        ``M = mH J_H^T J_H + m (J_R^T J_R + J_L^T J_L) + I (w_R w_R^T + w_L w_L^T)`` with
        ``w_R = (0, 0, 1, 0)``, ``w_L = (0, 0, 1, 1)`` the legs' angular-velocity rows; the
        products are assembled from the Jacobians' columns (``J_i = [I_2, c3, c4]``).
        """
        q_ = _q(q)
        return self._mass_from(self._jacobian_columns(q_), q_.shape[:-1])

    def bias_forces(self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0) -> FloatArray:
        """``h = C(q, q_dot) q_dot + dV/dq`` so that ``M q_ddot + h = Q``, shape (..., 4).

        For a point ``r = P_R + sum_k c_k e(theta_k)`` the velocity-product acceleration is
        ``-sum_k c_k e(theta_k) theta_dot_k^2``; ``h = sum_i m_i J_i^T (a_i - g)``.
        """
        q_, qd = _q(q), _q(q_dot, name="q_dot")
        lead = np.broadcast_shapes(q_.shape[:-1], qd.shape[:-1])
        return self._bias_from(self._jacobian_columns(q_), qd, slope, lead)

    def dynamics_terms(
        self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0
    ) -> tuple[FloatArray, FloatArray]:
        """``(M(q), h(q, q_dot))`` with the point Jacobians built once.

        Equal to ``(mass_matrix(q), bias_forces(q, q_dot, slope))``; shapes (..., 4, 4) and
        (..., 4).
        """
        q_, qd = _q(q), _q(q_dot, name="q_dot")
        c = self._jacobian_columns(q_)
        one = q_.ndim == 1 and qd.ndim == 1
        lead = () if one else np.broadcast_shapes(q_.shape[:-1], qd.shape[:-1])
        return self._mass_from(c, lead), self._bias_from(c, qd, slope, lead)

    def mechanical_energy(
        self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0
    ) -> FloatArray:
        """Kinetic plus potential energy (J), shape (...).

        One state of a walker with float parameters on level ground is evaluated in plain
        floats (what torque laws evaluated inside the integrator need); it equals the generic
        ``1/2 q_dot^T M q_dot + V`` to round-off, which the tests check.
        """
        if (
            self._scalar
            and np.shape(q) == (4,)
            and np.shape(q_dot) == (4,)
            and np.ndim(slope) == 0
            and float(slope) == 0.0  # type: ignore[arg-type]
        ):
            return np.asarray(self._level_energy(np.asarray(q, float), np.asarray(q_dot, float)))
        return super().mechanical_energy(q, q_dot, slope)

    def _level_energy(self, q: FloatArray, qd: FloatArray) -> float:
        """``T + V`` of one state on level ground in plain floats (float parameters)."""
        mH, m, I, g = self.hip_mass, self.leg_mass, self.leg_inertia, self.gravity
        b = self.leg_com_from_hip
        s = self.leg_length - self.foot_radius
        y0, q3, q4 = float(q[1]), float(q[2]), float(q[3])
        vx, vy, w3, w4 = (float(v) for v in qd)
        w34 = w3 + w4
        c3, s3, c34, s34 = math.cos(q3), math.sin(q3), math.cos(q3 + q4), math.sin(q3 + q4)
        # e(t) = (-sin t, cos t), de/dt = (-cos t, -sin t) t_dot
        hx, hy = vx - s * c3 * w3, vy - s * s3 * w3
        rx, ry = vx - (s - b) * c3 * w3, vy - (s - b) * s3 * w3
        lx, ly = hx + b * c34 * w34, hy + b * s34 * w34
        T = 0.5 * mH * (hx * hx + hy * hy) + 0.5 * m * (rx * rx + ry * ry + lx * lx + ly * ly)
        T += 0.5 * I * (w3 * w3 + w34 * w34)
        yH = y0 + s * c3
        V = g * (mH * yH + m * (yH - b * c3) + m * (yH - b * c34))
        return float(T + V)

    def potential_energy(self, q: ArrayLike, slope: ArrayLike = 0.0) -> FloatArray:
        pos = self.positions(q)
        g = gravity_vector(self.gravity, slope)
        mH, m = np.asarray(self.hip_mass), np.asarray(self.leg_mass)

        def dot(r: FloatArray) -> FloatArray:
            return np.asarray(np.sum(r * g, axis=-1))

        legs = dot(pos.right_leg_com) + dot(pos.left_leg_com)
        return np.asarray(-(mH * dot(pos.hip) + m * legs))

    def contact_jacobian(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Rolling-contact Jacobian, eqs. (4)-(5) of the paper, valid for any configuration.

        Right foot: ``[[1, 0, R, 0], [0, 1, 0, 0]]``. Left foot: the velocity of ``P_L`` plus
        ``R (q3_dot + q4_dot)`` in x; at ``q4 = -2 q3`` it reduces to eq. (5).
        """
        q_ = _q(q)
        R = self._p("foot_radius", q_)
        shape = np.broadcast_shapes(q_.shape[:-1], R.shape)
        A = np.zeros((*shape, 2, 4))
        A[..., 0, 0] = 1.0
        A[..., 1, 1] = 1.0
        if _foot(foot) == "right":
            A[..., 0, 2] = R
            return A
        s = self._p("leg_length", q_) - R
        q3, q34 = q_[..., 2], q_[..., 2] + q_[..., 3]
        A[..., 0, 2] = -s * np.cos(q3) + s * np.cos(q34) + R
        A[..., 0, 3] = s * np.cos(q34) + R
        A[..., 1, 2] = -s * np.sin(q3) + s * np.sin(q34)
        A[..., 1, 3] = s * np.sin(q34)
        return A

    def contact_jacobian_rate(self, q: ArrayLike, q_dot: ArrayLike, foot: Foot) -> FloatArray:
        q_, qd = _q(q), _q(q_dot, name="q_dot")
        R = self._p("foot_radius", q_)
        shape = np.broadcast_shapes(q_.shape[:-1], qd.shape[:-1], R.shape)
        if _foot(foot) == "right":
            return np.zeros((*shape, 2))
        s = (self._p("leg_length", q_) - R)[..., None]
        w3 = qd[..., 2][..., None]
        w34 = (qd[..., 2] + qd[..., 3])[..., None]
        e3, e34 = _e(q_[..., 2]), _e(q_[..., 2] + q_[..., 3])
        return np.asarray(np.broadcast_to(-s * e3 * w3**2 + s * e34 * w34**2, (*shape, 2)))

    def swap_legs(self, q: ArrayLike, q_dot: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Relabel so that the left foot becomes the "right" (stance) foot.

        ``q1, q2 <- P_L``, ``q3 <- q3 + q4``, ``q4 <- -q4``; velocities by the chain rule.
        """
        q_, qd = _q(q), _q(q_dot, name="q_dot")
        pos = self.positions(q_)
        s = (self._p("leg_length", q_) - self._p("foot_radius", q_))[..., None]
        w3 = qd[..., 2][..., None]
        w34 = (qd[..., 2] + qd[..., 3])[..., None]
        vL = qd[..., 0:2] + s * (_de(q_[..., 2]) * w3 - _de(q_[..., 2] + q_[..., 3]) * w34)
        lead_q = pos.left_foot_centre.shape[:-1]
        q_new = np.concatenate(
            (
                pos.left_foot_centre,
                np.broadcast_to((q_[..., 2] + q_[..., 3])[..., None], (*lead_q, 1)),
                np.broadcast_to(-q_[..., 3:4], (*lead_q, 1)),
            ),
            axis=-1,
        )
        lead = np.broadcast_shapes(vL.shape[:-1], qd.shape[:-1])
        qd_new = np.concatenate(
            (
                np.broadcast_to(vL, (*lead, 2)),
                np.broadcast_to((qd[..., 2] + qd[..., 3])[..., None], (*lead, 1)),
                np.broadcast_to(-qd[..., 3:4], (*lead, 1)),
            ),
            axis=-1,
        )
        return q_new, qd_new

    def heel_strike_function(self, q: ArrayLike) -> FloatArray:
        """``2 q3 + q4``: zero when the legs are symmetric, rising through zero at heel strike.

        With the stance foot rolling (``q2 = R``) the swing foot's clearance is
        ``2 (l - R) sin((2 q3 + q4)/2) sin(q4/2)``; this drops the ``sin(q4/2)`` factor, whose
        root is the mid-stance scuffing of the swing foot that the compass-gait convention
        ignores. Once ``q3 > 0`` an upward crossing means the swing foot lands ahead.
        """
        q_ = _q(q)
        return np.asarray(2.0 * q_[..., 2] + q_[..., 3])

    @property
    def section_names(self) -> tuple[str, ...]:
        return ("q3", "q3_dot", "q4_dot")

    def section_to_state(self, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """``z = (q3, q3_dot, q4_dot)`` just after heel strike: ``q4 = -2 q3``, foot rolling."""
        z_ = _q(z, 3, "z")
        R = np.asarray(self.foot_radius, dtype=float)
        q3, w3, w4 = np.broadcast_arrays(z_[..., 0], z_[..., 1], z_[..., 2])
        Rb = np.broadcast_to(R, q3.shape)
        q = np.stack((np.zeros_like(q3), Rb, q3, -2.0 * q3), axis=-1)
        q_dot = np.stack((-Rb * w3, np.zeros_like(q3), w3, w4), axis=-1)
        return q, q_dot

    def state_to_section(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        q_, qd = _q(q), _q(q_dot, name="q_dot")
        return np.stack(np.broadcast_arrays(q_[..., 2], qd[..., 2], qd[..., 3]), axis=-1)

    def actuation_matrix(self) -> FloatArray:
        """Hip torque (on the left leg, reaction on the right) acts on ``q4``: ``B = e4``."""
        return np.array([[0.0], [0.0], [0.0], [1.0]])


def _foot(foot: str) -> str:
    if foot not in ("right", "left"):
        raise ValueError(f"foot must be 'right' or 'left', got {foot!r}")
    return foot


def heel_strike_state(
    walker: CompassGait,
    impact_angle: ArrayLike,
    *,
    q3_dot: ArrayLike = 1.0,
    q4_dot: ArrayLike = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """Pre-impact state of the paper's heel-strike study (Font & Kövecses 2008, Figs. 2-3).

    Right foot on the ground and rolling (``q2 = R``, ``q1_dot = -R q3_dot``, ``q2_dot = 0``),
    legs symmetric (``q4 = -2 q3``), ``q1 = 0``.

    Parameters
    ----------
    walker : CompassGait
        The walker (its ``foot_radius`` may be an array).
    impact_angle : array_like
        ``q3`` at impact (rad).
    q3_dot, q4_dot : array_like
        Pre-impact angular velocities (rad/s); the paper uses 1 and 0.

    Returns
    -------
    q, q_dot : ndarray, shape (..., 4)
        Broadcast over ``impact_angle``, the velocities and the walker's parameters.
    """
    q3 = np.asarray(impact_angle, dtype=float)
    w3 = np.asarray(q3_dot, dtype=float)
    w4 = np.asarray(q4_dot, dtype=float)
    R = np.asarray(walker.foot_radius, dtype=float)
    q3, w3, w4, R = np.broadcast_arrays(q3, w3, w4, R)
    q = np.stack((np.zeros_like(q3), R, q3, -2.0 * q3), axis=-1)
    q_dot = np.stack((-R * w3, np.zeros_like(q3), w3, w4), axis=-1)
    return q, q_dot


@functools.lru_cache(maxsize=64)
def _described_compass(values: tuple[float, ...]) -> PlanarWalker | None:
    """``compass.toml`` with these values of :data:`DESCRIBED_PARAMETERS` (in its order), or
    None if the description cannot walk with them (see :meth:`CompassGait.as_described`)."""
    from heelstrike.models.builder import load_walker

    params: dict[str, Any] = dict(zip(DESCRIBED_PARAMETERS.values(), values, strict=True))
    walker = load_walker("compass", **params)
    try:
        walker.check_heel_strike_detectable()
    except ValueError:
        return None
    return walker
