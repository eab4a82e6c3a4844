"""Impact algebra for inert (inelastic, no-slip) constraints.

Implements the Lagrangian impulse-momentum framework of Font & Kövecses (2008), eqs. (2)-(13),
for any number of generalized coordinates ``n`` and constraint rows ``k``, batched over leading
axes. Nothing here knows about walkers.

Conventions
-----------
``M``: mass matrix, shape ``(..., n, n)``, symmetric positive definite.
``A``: constraint Jacobian, shape ``(..., k, n)``, full row rank ``k <= n``.
``q_dot``: generalized velocities, shape ``(..., n)``.
Leading axes of the three broadcast against each other.

The impact equations are

.. math::

    M (\\dot q^+ - \\dot q^-) = A^T \\lambda, \\qquad A \\dot q^+ = -e\\, A \\dot q^-,

so that with :math:`W = A M^{-1} A^T` and the constrained projector
:math:`P_c = M^{-1} A^T W^{-1} A` (eq. 6), :math:`\\lambda = -(1 + e) W^{-1} A \\dot q^-` and
:math:`\\dot q^+ = \\dot q^- - (1 + e) P_c \\dot q^-`; for ``e = 0`` (the paper)
:math:`\\dot q^+ = P_a \\dot q^-` (eq. 13). All solves use LU/Cholesky factorizations;
``M`` is never inverted explicitly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ImpactInputError",
    "ImpactResult",
    "admissible_projector",
    "constrained_projector",
    "decompose_impulse",
    "decompose_velocity",
    "impact",
    "kinetic_energy",
]

FloatArray = NDArray[np.float64]


class ImpactInputError(ValueError):
    """Raised when the inputs of the impact algebra are malformed or physically invalid."""


def _as_float(name: str, x: ArrayLike, min_ndim: int) -> FloatArray:
    arr = np.asarray(x, dtype=float)
    if arr.ndim < min_ndim:
        raise ImpactInputError(
            f"{name} must have at least {min_ndim} dimensions, got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ImpactInputError(f"{name} contains non-finite values (nan or inf)")
    return arr


def _validate(
    M: ArrayLike, A: ArrayLike, q_dot: ArrayLike | None = None, check: bool = True
) -> tuple[FloatArray, FloatArray, FloatArray | None]:
    M_ = _as_float("M", M, 2)
    A_ = _as_float("A", A, 2)
    n = M_.shape[-1]
    if M_.shape[-2] != n:
        raise ImpactInputError(f"M must be square in its last two axes, got shape {M_.shape}")
    k = A_.shape[-2]
    if A_.shape[-1] != n:
        raise ImpactInputError(
            f"A has {A_.shape[-1]} columns but M is {n}x{n}: shapes {A_.shape} and {M_.shape}"
        )
    if k < 1 or k > n:
        raise ImpactInputError(f"A must have between 1 and n={n} rows, got {k}")
    qd: FloatArray | None = None
    if q_dot is not None:
        qd = _as_float("q_dot", q_dot, 1)
        if qd.shape[-1] != n:
            raise ImpactInputError(
                f"q_dot has length {qd.shape[-1]} in its last axis, expected n={n}"
            )
    try:
        np.broadcast_shapes(
            M_.shape[:-2], A_.shape[:-2], *(() if qd is None else (qd.shape[:-1],))
        )
    except ValueError as exc:
        raise ImpactInputError(
            f"leading (batch) axes do not broadcast: M {M_.shape}, A {A_.shape}"
            + ("" if qd is None else f", q_dot {qd.shape}")
        ) from exc
    if check:
        scale = np.max(np.abs(M_), axis=(-2, -1), keepdims=True)
        if not np.all(np.abs(M_ - np.swapaxes(M_, -1, -2)) <= 1e-10 * scale + 1e-300):
            raise ImpactInputError("M is not symmetric")
        try:
            np.linalg.cholesky(M_)
        except np.linalg.LinAlgError as exc:
            raise ImpactInputError("M is not positive definite") from exc
        sv = np.linalg.svd(A_, compute_uv=False)
        if np.any(sv[..., -1] <= 1e-12 * max(n, k) * np.maximum(sv[..., 0], 1e-300)):
            raise ImpactInputError(f"A is rank deficient (fewer than k={k} independent rows)")
    return M_, A_, qd


def _minv_at(M: FloatArray, A: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Return ``X = M^-1 A^T`` (..., n, k) and ``W = A M^-1 A^T`` (..., k, k) by LU solves."""
    At = np.swapaxes(A, -1, -2)
    shape = np.broadcast_shapes(M.shape[:-2], At.shape[:-2])
    X = np.linalg.solve(
        np.broadcast_to(M, (*shape, *M.shape[-2:])), np.broadcast_to(At, (*shape, *At.shape[-2:]))
    )
    W = A @ X
    W = 0.5 * (W + np.swapaxes(W, -1, -2))
    return X, W


def constrained_projector(M: ArrayLike, A: ArrayLike, *, check: bool = True) -> FloatArray:
    """Projector onto the space of constrained motion, eq. (6).

    :math:`P_c = M^{-1} A^T (A M^{-1} A^T)^{-1} A`.

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Mass matrix (kg, kg m, kg m^2 entries), symmetric positive definite.
    A : array_like, shape (..., k, n)
        Constraint Jacobian of the inert constraints, full row rank.
    check : bool
        Validate symmetry, positive definiteness and rank (default True).

    Returns
    -------
    ndarray, shape (..., n, n)
        ``P_c``; idempotent and mass-orthogonal to ``P_a = I - P_c``.
    """
    M_, A_, _ = _validate(M, A, None, check)
    X, W = _minv_at(M_, A_)
    return np.asarray(X @ np.linalg.solve(W, A_))


def admissible_projector(M: ArrayLike, A: ArrayLike, *, check: bool = True) -> FloatArray:
    """Projector onto the space of admissible motion, eq. (7): ``P_a = I - P_c``.

    Parameters and shapes as :func:`constrained_projector`.
    """
    P_c = constrained_projector(M, A, check=check)
    return np.eye(P_c.shape[-1]) - P_c


def kinetic_energy(M: ArrayLike, q_dot: ArrayLike) -> FloatArray:
    """Kinetic energy ``T = 1/2 q_dot^T M q_dot`` (J), eq. (1); shape ``(...)``."""
    M_ = np.asarray(M, dtype=float)
    v = np.asarray(q_dot, dtype=float)
    return np.asarray(0.5 * np.einsum("...i,...ij,...j->...", v, M_, v))


def decompose_velocity(
    P_c: ArrayLike, q_dot: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Split velocities into constrained and admissible parts, eq. (8).

    Returns ``(v_c, v_a)`` with ``v_c = P_c q_dot`` and ``v_a = q_dot - v_c``, shape (..., n).
    """
    P = np.asarray(P_c, dtype=float)
    v = np.asarray(q_dot, dtype=float)
    v_c = np.einsum("...ij,...j->...i", P, v)
    return v_c, v - v_c


def decompose_impulse(P_c: ArrayLike, f: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Split generalized impulses, eq. (9): ``f_c = P_c^T f``, ``f_a = P_a^T f = f - f_c``.

    Returns ``(f_c, f_a)``, shape (..., n), in N s (or N m s for angular coordinates).
    """
    P = np.asarray(P_c, dtype=float)
    f_ = np.asarray(f, dtype=float)
    f_c = np.einsum("...ji,...j->...i", P, f_)
    return f_c, f_ - f_c


@dataclass(frozen=True, kw_only=True)
class ImpactResult:
    """Everything the impact algebra says about one (batched) collision.

    All arrays share the broadcast leading shape ``(...)`` of the inputs.

    Attributes
    ----------
    constrained_projector, admissible_projector : ndarray, shape (..., n, n)
        ``P_c`` (eq. 6) and ``P_a`` (eq. 7).
    velocity_pre : ndarray, shape (..., n)
        Pre-impact generalized velocities ``q_dot-``.
    velocity_constrained, velocity_admissible : ndarray, shape (..., n)
        ``v_c = P_c q_dot-`` and ``v_a = P_a q_dot-`` (eq. 8).
    velocity_post : ndarray, shape (..., n)
        ``q_dot+ = q_dot- - (1 + e) P_c q_dot-``; ``P_a q_dot-`` for ``e = 0`` (eq. 13).
    constraint_impulse : ndarray, shape (..., k)
        ``lambda`` with ``M (q_dot+ - q_dot-) = A^T lambda`` (N s per constraint row).
    generalized_impulse : ndarray, shape (..., n)
        ``f = A^T lambda`` (eq. 2).
    kinetic_energy, kinetic_energy_constrained, kinetic_energy_admissible : ndarray, shape (...)
        ``T``, ``T_c``, ``T_a`` before impact (J), eq. (10).
    kinetic_energy_post : ndarray, shape (...)
        ``T+`` (J).
    energy_lost : ndarray, shape (...)
        ``T- - T+ = (1 - e^2) T_c`` (J); equals ``|W_col|`` of eq. (15).
    restitution : float
        Coefficient ``e`` applied to the constrained part.
    """

    constrained_projector: FloatArray
    admissible_projector: FloatArray
    velocity_pre: FloatArray
    velocity_constrained: FloatArray
    velocity_admissible: FloatArray
    velocity_post: FloatArray
    constraint_impulse: FloatArray
    generalized_impulse: FloatArray
    kinetic_energy: FloatArray
    kinetic_energy_constrained: FloatArray
    kinetic_energy_admissible: FloatArray
    kinetic_energy_post: FloatArray
    energy_lost: FloatArray
    restitution: float


def impact(
    M: ArrayLike,
    A: ArrayLike,
    q_dot: ArrayLike,
    *,
    restitution: float = 0.0,
    check: bool = True,
) -> ImpactResult:
    """Resolve a collision with inert constraints ``A`` (paper eqs. 2-13).

    Parameters
    ----------
    M : array_like, shape (..., n, n)
        Mass matrix at the impact configuration; symmetric positive definite.
    A : array_like, shape (..., k, n)
        Jacobian of the constraints that become active (e.g. the striking foot's, eq. 4-5).
    q_dot : array_like, shape (..., n)
        Pre-impact generalized velocities ``q_dot-``.
    restitution : float, optional
        Coefficient ``e`` in [0, 1] applied to the constrained velocity:
        ``A q_dot+ = -e A q_dot-``. ``e = 0`` (default) is the paper's inert impact.
    check : bool, optional
        Validate shapes, finiteness, symmetry and definiteness of ``M`` and rank of ``A``.

    Returns
    -------
    ImpactResult
        Projectors, decomposed velocities, impulses and energies.

    Raises
    ------
    ImpactInputError
        On wrong shapes, non-finite values, ``M`` not SPD, ``A`` rank deficient, or
        ``restitution`` outside [0, 1].
    """
    e = float(restitution)
    if not (np.isfinite(e) and 0.0 <= e <= 1.0):
        raise ImpactInputError(f"restitution must lie in [0, 1], got {restitution!r}")
    M_, A_, qd = _validate(M, A, q_dot, check)
    assert qd is not None
    X, W = _minv_at(M_, A_)
    Aqd = np.einsum("...ij,...j->...i", A_, qd)
    mu = np.linalg.solve(W, Aqd[..., None])[..., 0]  # W^-1 A q_dot-
    v_c = np.einsum("...ij,...j->...i", X, mu)  # P_c q_dot- = M^-1 A^T W^-1 A q_dot-
    shape = np.broadcast_shapes(v_c.shape, qd.shape)
    qd_b = np.broadcast_to(qd, shape)
    v_a = qd_b - v_c
    P_c = X @ np.linalg.solve(W, np.broadcast_to(A_, (*X.shape[:-2], *A_.shape[-2:])))
    P_a = np.eye(P_c.shape[-1]) - P_c
    lam = -(1.0 + e) * mu
    f = np.einsum("...ji,...j->...i", A_, lam)
    q_plus = qd_b - (1.0 + e) * v_c
    T = kinetic_energy(M_, qd_b)
    T_c = kinetic_energy(M_, v_c)
    T_a = kinetic_energy(M_, v_a)
    T_plus = kinetic_energy(M_, q_plus)
    return ImpactResult(
        constrained_projector=P_c,
        admissible_projector=P_a,
        velocity_pre=qd_b,
        velocity_constrained=v_c,
        velocity_admissible=v_a,
        velocity_post=q_plus,
        constraint_impulse=lam,
        generalized_impulse=f,
        kinetic_energy=T,
        kinetic_energy_constrained=T_c,
        kinetic_energy_admissible=T_a,
        kinetic_energy_post=T_plus,
        energy_lost=(1.0 - e * e) * T_c,
        restitution=e,
    )
