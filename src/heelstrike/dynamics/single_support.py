"""Single-support dynamics: the stance foot rolls without slipping on a slope.

In floating-base coordinates ``q`` (see :mod:`heelstrike.models.base`) the stance foot's rolling
constraint ``A_R q_dot = 0`` with ``A_R = [[1, 0, R, 0...], [0, 1, 0, 0...]]`` is integrable:
``q1 = c - R q3`` and ``q2 = R``. The free coordinates ``theta = q[2:]`` (less any locked joints)
therefore parametrise single support with a *constant* basis ``J`` of the null space of ``A_R``,
``q_dot = J theta_dot``, and Lagrange's equations reduce to

.. math:: J^T M(q) J \\, \\ddot\\theta = J^T (B u - h(q, \\dot q)),

the same ``M`` and ``h`` as the impact and flight models (one source of truth). The contact force
``lambda`` (tangential, normal, N) follows from the constrained form
``M q_ddot + h = B u + A_R^T lambda + E^T mu`` (``E``: the rows of the locked joints, ``mu``
their holding torques): the locked joints act on no base coordinate and ``A_R``'s first two
columns are the identity, so the base rows give ``lambda = (M q_ddot + h - B u)[:2]``, Newton's
law for the whole walker (rate of its linear momentum less its weight), with the single-support
accelerations ``q_ddot = J theta_ddot``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._typing import FloatArray
from heelstrike.models.base import PlanarWalker

__all__ = ["SingleSupport", "TorqueLaw", "solve_small"]


class TorqueLaw(Protocol):
    """An actuator law ``u = law(t, q, q_dot)``: torques (N m), shape ``(n_u,)``.

    ``t`` is the time since the start of the current step (s); ``q``, ``q_dot`` the walker's
    full state in floating-base coordinates with the current stance foot as the "right" foot.
    """

    def __call__(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray: ...


@dataclass(frozen=True, kw_only=True, eq=False)
class SingleSupport:
    """Single-support phase of a walker on a slope.

    Parameters
    ----------
    walker : PlanarWalker
        The walker model (``M``, ``h``, Jacobians).
    slope : float
        Ground slope ``gamma`` (rad), descending towards ``-x`` (the walking direction).
    torque : TorqueLaw or None
        Actuator law for the walker's actuated joints (``B`` of the walker); None: passive.
    locked : tuple of int
        Indices of joint coordinates (``>= 3``) held fixed (e.g. locked knees).
    """

    walker: PlanarWalker
    slope: float = 0.0
    torque: TorqueLaw | Callable[[float, FloatArray, FloatArray], FloatArray] | None = None
    locked: tuple[int, ...] = ()
    _free: tuple[int, ...] = field(init=False, repr=False)
    _basis: FloatArray = field(init=False, repr=False)
    _basis_t: FloatArray = field(init=False, repr=False)
    _reduce: FloatArray = field(init=False, repr=False)
    _radius: float = field(init=False, repr=False)
    _actuation: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = self.walker.n_coordinates
        for i in self.locked:
            if not 3 <= i < n:
                raise ValueError(f"locked coordinate index {i} must be in [3, {n})")
        free = tuple(i for i in range(2, n) if i not in self.locked)
        R = float(np.asarray(self.walker.foot_radii[0]))
        J = np.zeros((n, len(free)))
        for col, i in enumerate(free):
            J[i, col] = 1.0
        J[0, 0] = -R  # q1_dot = -R q3_dot (rolling)
        object.__setattr__(self, "_free", free)
        object.__setattr__(self, "_basis", J)
        # Constant data of the hot path (rhs), fixed once per phase.
        object.__setattr__(self, "_basis_t", np.ascontiguousarray(J.T))
        # vec(J^T M J) = (J^T kron J^T) vec(M): the reduced mass matrix in one product
        object.__setattr__(self, "_reduce", np.kron(J.T, J.T))
        object.__setattr__(self, "_radius", R)
        object.__setattr__(
            self, "_actuation", np.asarray(self.walker.actuation_matrix(), dtype=float)
        )
        if not np.isfinite(self.slope):
            raise ValueError("slope must be finite (rad)")
        object.__setattr__(self, "slope", float(self.slope))

    @property
    def free_coordinates(self) -> tuple[int, ...]:
        """Indices of ``q`` integrated as ``theta`` (the stance angle first)."""
        return self._free

    # -- state maps --------------------------------------------------------------------------
    def pack(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Integrator state ``(theta, theta_dot)`` of a full state; shape (2 m,)."""
        q_, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        idx = list(self._free)
        return np.concatenate((q_[..., idx], qd[..., idx]), axis=-1)

    def unpack(self, x: ArrayLike, q_ref: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Full ``(q, q_dot)`` from ``x = (theta, theta_dot)`` and a reference ``q_ref``.

        ``q_ref`` fixes the locked joints and the rolling offset ``c = q1 + R q3``.
        """
        x_ = np.asarray(x, dtype=float)
        ref = np.asarray(q_ref, dtype=float)
        m = len(self._free)
        if x_.ndim == 1 and ref.ndim == 1:
            return self._unpack_one(x_, ref)
        theta, theta_dot = x_[..., :m], x_[..., m : 2 * m]
        J = self._basis
        q = np.broadcast_to(ref, (*theta.shape[:-1], ref.shape[-1])).copy()
        q[..., list(self._free)] = theta
        R = -J[0, 0]
        q[..., 0] = ref[..., 0] + R * ref[..., 2] - R * theta[..., 0]
        q[..., 1] = R
        q_dot = np.einsum("ij,...j->...i", J, theta_dot)
        return q, q_dot

    def _unpack_one(self, x: FloatArray, ref: FloatArray) -> tuple[FloatArray, FloatArray]:
        """:meth:`unpack` of one state (``x`` (>= 2 m,), ``ref`` (n,)), without broadcasting."""
        m = len(self._free)
        R = self._radius
        qv = ref.tolist()
        xv = x.tolist()
        q0 = qv[0] + R * qv[2] - R * xv[0]
        qdv = [0.0] * len(qv)
        for k, i in enumerate(self._free):
            qv[i] = xv[k]
            qdv[i] = xv[m + k]
        qv[0], qv[1] = q0, R
        qdv[0] = -R * xv[m]
        return np.array(qv), np.array(qdv)

    # -- dynamics ----------------------------------------------------------------------------
    def _u(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray:
        n_u = self._actuation.shape[1]
        if self.torque is None:
            return np.zeros((*q.shape[:-1], n_u))
        return np.asarray(self.torque(t, q, q_dot), dtype=float)

    def generalized_actuation(self, t: float, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """``B u`` (..., n): actuator torques as generalized forces."""
        q_, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        return np.asarray(np.einsum("ij,...j->...i", self._actuation, self._u(t, q_, qd)))

    def reduced_mass_matrix(self, q: ArrayLike) -> FloatArray:
        """``J^T M(q) J``, shape (..., m, m)."""
        J = self._basis
        return np.asarray(J.T @ self.walker.mass_matrix(q) @ J)

    def reduced_forcing(self, t: float, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """``J^T (B u - h)``, shape (..., m): right-hand side of the reduced equations."""
        h = self.walker.bias_forces(q, q_dot, self.slope)
        f = self.generalized_actuation(t, q, q_dot) - h
        return np.asarray(np.einsum("ij,...i->...j", self._basis, f))

    def accelerations(self, t: float, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Full ``q_ddot = J theta_ddot`` (..., n) in single support."""
        Mr = self.reduced_mass_matrix(q)
        Fr = self.reduced_forcing(t, q, q_dot)
        theta_dd = np.linalg.solve(Mr, Fr[..., None])[..., 0]
        return np.asarray(np.einsum("ij,...j->...i", self._basis, theta_dd))

    def ground_reaction(self, t: float, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Contact force on the stance foot ``lambda = (tangential, normal)`` (N), (..., 2).

        The base rows of ``M q_ddot + h = B u + A^T lambda + E^T mu``:
        ``lambda = (M q_ddot + h - B u)[:2]`` with the single-support accelerations
        ``q_ddot = J theta_ddot`` (see the module docstring). The holding torques ``mu`` of the
        locked joints (a locked knee) are part of the balance: the unlocked formula
        ``(A M^-1 A^T)^-1 A M^-1 (h - B u)`` would let those joints accelerate.
        """
        return self._balance(t, q, q_dot, rows=2)

    def constraint_forces(self, t: float, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Generalized constraint forces ``A^T lambda + E^T mu = M q_ddot + h - B u``, (..., n).

        The base rows are :meth:`ground_reaction` (N); the row of a locked joint is the torque
        (N m) its lock exerts to hold it (the stance foot's contact acts on the base rows and
        the root link only); the free joints' rows are zero to round-off.
        """
        return self._balance(t, q, q_dot, rows=None)

    def _balance(self, t: float, q: ArrayLike, q_dot: ArrayLike, rows: int | None) -> FloatArray:
        """``(M q_ddot + h - B u)[..., :rows]`` with the single-support accelerations."""
        q_, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        M, f = self.walker.dynamics_terms(q_, qd, self.slope)
        if self.torque is not None:
            f = f - self.generalized_actuation(t, q_, qd)
        J = self._basis
        k = M.shape[-1] if rows is None else rows
        if q_.ndim == 1:  # one state (an event function's case): the small solve in closed form
            Mr = (self._reduce @ M.reshape(-1)).reshape(J.shape[1], J.shape[1])
            q_dd = J @ solve_small(Mr, -(self._basis_t @ f))
            return np.asarray(M[:k] @ q_dd + f[:k])
        Mr = np.einsum("ai,...ij,jb->...ab", J.T, M, J)
        theta_dd = np.linalg.solve(Mr, -np.einsum("ai,...i->...a", J.T, f)[..., None])[..., 0]
        q_dd = np.einsum("ij,...j->...i", J, theta_dd)
        return np.asarray(np.einsum("...ij,...j->...i", M[..., :k, :], q_dd) + f[..., :k])

    def actuator_power(self, t: float, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Mechanical power of the actuators ``(B u) . q_dot`` (W), shape (...)."""
        qd = np.asarray(q_dot, dtype=float)
        return np.asarray(np.sum(self.generalized_actuation(t, q, qd) * qd, axis=-1))

    def rhs(self, t: float, x: FloatArray, q_ref: FloatArray) -> FloatArray:
        """Time derivative of ``(theta, theta_dot, W_act)`` for ``solve_ivp``.

        The last entry integrates the actuator work (J) along the motion. This is the hot path
        of every scipy simulation: ``x`` (2 m + 1,) and ``q_ref`` (n,) are taken as valid
        (checked where a phase starts), ``M`` and ``h`` come from one
        :meth:`~heelstrike.models.base.PlanarWalker.dynamics_terms` call and the reduced
        system is solved directly (:func:`solve_small`).
        """
        m = len(self._free)
        q, q_dot = self._unpack_one(x, q_ref)
        M, h = self.walker.dynamics_terms(q, q_dot, self.slope)
        out = np.empty(2 * m + 1)
        if self.torque is None:
            f = -h
            out[2 * m] = 0.0
        else:
            u = np.asarray(self.torque(t, q, q_dot), dtype=float)
            Bu = self._actuation @ u
            f = Bu - h
            out[2 * m] = Bu @ q_dot
        out[:m] = x[m : 2 * m]
        Mr = (self._reduce @ M.reshape(-1)).reshape(m, m)
        out[m : 2 * m] = solve_small(Mr, self._basis_t @ f)
        return out


def solve_small(A: FloatArray, b: FloatArray) -> FloatArray:
    """Solve one small symmetric positive-definite system ``A y = b`` (m <= 2 in closed form).

    Parameters
    ----------
    A : ndarray, shape (m, m)
        A reduced mass matrix (symmetric positive definite).
    b : ndarray, shape (m,)

    Returns
    -------
    ndarray, shape (m,)
    """
    m = b.shape[0]
    if m == 1:
        return b / A[0, 0]
    if m == 2:
        (a, c), (_, d) = A.tolist()
        b0, b1 = b.tolist()
        det = a * d - c * c
        return np.array(((d * b0 - c * b1) / det, (a * b1 - c * b0) / det))
    return np.asarray(np.linalg.solve(A, b))
