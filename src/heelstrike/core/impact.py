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
:math:`\\dot q^+ = P_a \\dot q^-` (eq. 13).

Numerics: ``M`` is scaled to unit diagonal (so that results and checks do not depend on units
or on an overall scale), factorized by Cholesky, and ``L^-1 A^T`` by QR; energies are computed
as sums of squares (``T_c = 1/2 |R^-T A q_dot|^2``), never as differences or as
``v^T M v`` of large vectors. Neither ``M^-1`` nor ``W`` is formed, so results stay accurate
for condition numbers of the scaled ``M`` up to about 1e14, and of ``M`` itself far beyond
when the ill-conditioning comes from units or scales. ``M`` that is singular to working
precision (scaled condition number above about ``1 / (n eps)``) or indefinite is rejected with
:class:`ImpactInputError` stating the condition number.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core._scalars import python_scalars

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
        if not np.all(np.abs(M_ - np.swapaxes(M_, -1, -2)) <= 1e-10 * scale):
            raise ImpactInputError("M is not symmetric")
        _check_definite(M_)
        _check_rank(A_)
    return M_, A_, qd


#: ``M`` is rejected as singular when, after symmetric diagonal scaling to unit diagonal, its
#: smallest eigenvalue is below ``SINGULAR_RTOL * n`` times its largest one, i.e. when its
#: condition number exceeds ``1 / (n * SINGULAR_RTOL)`` (about 1e15 for ``n = 4``): such a
#: matrix is within rounding of a singular one and the impact is not determined by it.
SINGULAR_RTOL = float(np.finfo(float).eps)


def _diag_scale(M: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Return ``(s, M~)`` with ``s = sqrt(diag M)`` (..., n) and ``M~ = M / (s s^T)``.

    Raises :class:`ImpactInputError` if a diagonal entry is not positive.
    """
    d = np.diagonal(M, axis1=-2, axis2=-1)
    if not np.all(d > 0):
        bad = float(d[~(d > 0)].flat[0])
        raise ImpactInputError(
            f"M is not positive definite: a diagonal entry is {bad:.6g} (must be > 0)"
        )
    s = np.sqrt(d)
    return s, (M / s[..., :, None]) / s[..., None, :]


def _check_definite(M: FloatArray) -> None:
    """Raise unless ``M`` is positive definite and not singular to working precision.

    Scale-free: ``M`` and ``c M`` (any ``c > 0``), and ``D M D`` for positive diagonal ``D``
    (a change of units of the coordinates), pass or fail together.
    """
    _, Mt = _diag_scale(M)
    ev = np.linalg.eigvalsh(Mt)
    n = M.shape[-1]
    lo, hi = ev[..., 0], ev[..., -1]
    tol = n * SINGULAR_RTOL * hi
    if np.any(lo < -tol):
        i = np.unravel_index(int(np.argmin(lo / hi)), lo.shape)
        raise ImpactInputError(
            "M is not positive definite: it is indefinite (after scaling to unit diagonal its "
            f"eigenvalues range from {float(lo[i]):.3g} to {float(hi[i]):.3g})"
        )
    if np.any(lo <= tol):
        i = np.unravel_index(int(np.argmin(lo / hi)), lo.shape)
        cond = float(hi[i] / lo[i]) if lo[i] > 0 else float("inf")
        raise ImpactInputError(
            f"M is not positive definite: it is singular to working precision (condition "
            f"number {cond:.3g} after scaling to unit diagonal; the limit is "
            f"{1.0 / (n * SINGULAR_RTOL):.3g})"
        )


def _row_norms(A: FloatArray) -> FloatArray:
    """Euclidean norms of the rows of ``A`` (..., k), without overflow or underflow."""
    amax = np.max(np.abs(A), axis=-1)
    safe = np.where(amax > 0, amax, 1.0)
    return np.asarray(amax * np.linalg.norm(A / safe[..., None], axis=-1))


def _check_rank(A: FloatArray) -> None:
    """Raise unless ``A`` has full row rank; scale-free (rows are normalized first)."""
    k, n = A.shape[-2:]
    norms = _row_norms(A)
    if not np.all(norms > 0):
        raise ImpactInputError(f"A is rank deficient (fewer than k={k} independent rows)")
    sv = np.linalg.svd(A / norms[..., None], compute_uv=False)
    if np.any(sv[..., -1] <= 1e-12 * max(n, k) * sv[..., 0]):
        raise ImpactInputError(f"A is rank deficient (fewer than k={k} independent rows)")


@dataclass(frozen=True)
class _Solved:
    """Intermediate results of :func:`_solve` (batch shape ``(...)`` broadcast)."""

    s: FloatArray  # (..., n) sqrt(diag M)
    L: FloatArray  # (..., n, n) Cholesky factor of the scaled M~
    Q: FloatArray  # (..., n, k) orthonormal basis of L^-1 A~^T
    mu: FloatArray  # (..., k) W^-1 A q_dot
    z: FloatArray  # (..., n) L^T P~_c q~  (|z|^2 = 2 T_c)
    u: FloatArray  # (..., n) L^T q~       (|u|^2 = 2 T)
    v_c: FloatArray  # (..., n) P_c q_dot
    qd: FloatArray  # (..., n) q_dot broadcast


def _factor_cholesky(F: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(s, L)`` from a mass factor ``F`` (``M = F^T F``) without forming ``M``: ``s`` the
    column norms of ``F`` (``sqrt(diag M)``) and ``L = R^T`` from ``F D^-1 = Q R``, with a
    positive diagonal, so that ``M~ = D^-1 M D^-1 = L L^T``."""
    s = _row_norms(np.swapaxes(F, -1, -2))
    if not np.all(s > 0):
        raise ImpactInputError("mass_factor has a zero column: M is singular")
    R = np.linalg.qr(F / s[..., None, :], mode="r")
    d = np.diagonal(R, axis1=-2, axis2=-1)
    sign = np.where(d < 0, -1.0, 1.0)
    return s, np.swapaxes(R * sign[..., :, None], -1, -2)


def _check_factor(F: FloatArray) -> None:
    """Raise unless the mass factor has full column rank to working precision (scale-free)."""
    n = F.shape[-1]
    if F.shape[-2] < n:
        raise ImpactInputError(
            f"mass_factor must have at least n={n} rows (M = F^T F), got shape {F.shape}"
        )
    s = _row_norms(np.swapaxes(F, -1, -2))
    if not np.all(s > 0):
        raise ImpactInputError("mass_factor has a zero column: M is singular")
    sv = np.linalg.svd(F / s[..., None, :], compute_uv=False)
    lo, hi = sv[..., -1], sv[..., 0]
    if np.any(lo <= n * SINGULAR_RTOL * hi):
        i = np.unravel_index(int(np.argmin(lo / hi)), lo.shape)
        cond = float(hi[i] / lo[i]) if lo[i] > 0 else float("inf")
        raise ImpactInputError(
            f"M = F^T F is singular to working precision (condition number of the factor "
            f"{cond:.3g} after scaling its columns; the limit is "
            f"{1.0 / (n * SINGULAR_RTOL):.3g})"
        )


def _solve(
    M: FloatArray, A: FloatArray, qd: FloatArray, factor: FloatArray | None = None
) -> _Solved:
    """Cholesky/QR solution of the impact equations; never forms ``M^-1`` or ``W``.

    With ``D = diag(sqrt(diag M))``, ``M~ = D^-1 M D^-1 = L L^T``, ``A~ = A D^-1`` with unit
    rows (row scales ``r``), ``q~ = D q_dot`` and ``L^-1 A~^T = Q R``:
    ``W = diag(r) R^T R diag(r)``, ``w = R^-T A~ q~``, ``2 T_c = |w|^2``, ``z = Q w = L^T D v_c``,
    ``P~_c = L^-T Q Q^T L^T``. Energies are sums of squares, so no cancellation occurs.
    """
    batch = np.broadcast_shapes(M.shape[:-2], A.shape[:-2], qd.shape[:-1])
    n, k = M.shape[-1], A.shape[-2]
    M = np.broadcast_to(M, (*batch, n, n))
    A = np.broadcast_to(A, (*batch, k, n))
    qd = np.broadcast_to(qd, (*batch, n))
    if factor is not None:
        F = np.broadcast_to(factor, (*batch, *factor.shape[-2:]))
        s, L = _factor_cholesky(F)
        if not np.all(np.diagonal(L, axis1=-2, axis2=-1) > 0):
            raise ImpactInputError("M = F^T F is singular (the factor is rank deficient)")
    else:
        s, Mt = _diag_scale(M)
        try:
            L = np.asarray(np.linalg.cholesky(Mt), dtype=float)
        except np.linalg.LinAlgError as exc:
            raise ImpactInputError("M is not positive definite") from exc
    At = A / s[..., None, :]
    r = _row_norms(At)
    if not np.all(r > 0):
        raise ImpactInputError(f"A is rank deficient (fewer than k={k} independent rows)")
    Ah = At / r[..., None]
    qt = qd * s
    Y = np.linalg.solve(L, np.swapaxes(Ah, -1, -2))
    Q, R = np.linalg.qr(Y)
    b = np.einsum("...ij,...j->...i", Ah, qt)
    try:
        w = np.linalg.solve(np.swapaxes(R, -1, -2), b[..., None])[..., 0]
        mu_h = np.linalg.solve(R, w[..., None])[..., 0]
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError(
            f"A is rank deficient (fewer than k={k} independent rows)"
        ) from exc
    z = np.einsum("...ij,...j->...i", Q, w)
    v_ct = np.linalg.solve(np.swapaxes(L, -1, -2), z[..., None])[..., 0]
    u = np.einsum("...ji,...j->...i", L, qt)
    return _Solved(
        s=s, L=np.asarray(L, dtype=float), Q=Q, mu=mu_h / r, z=z, u=u, v_c=v_ct / s, qd=qd
    )


def _projector(S: _Solved) -> FloatArray:
    """``P_c = D^-1 L^-T Q Q^T L^T D``, shape (..., n, n)."""
    LT = np.swapaxes(S.L, -1, -2)
    Pt = np.linalg.solve(LT, S.Q @ (np.swapaxes(S.Q, -1, -2) @ LT))
    return np.asarray((Pt / S.s[..., :, None]) * S.s[..., None, :])


def _half_sq(x: FloatArray) -> FloatArray:
    return np.asarray(0.5 * np.einsum("...i,...i->...", x, x))


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
    return _projector(_solve(M_, A_, np.zeros(M_.shape[-1])))


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
class ImpactResult(ResultDictMixin):
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

    The energies of one collision (batch shape ``()``) are Python floats.
    """

    constrained_projector: FloatArray
    admissible_projector: FloatArray
    velocity_pre: FloatArray
    velocity_constrained: FloatArray
    velocity_admissible: FloatArray
    velocity_post: FloatArray
    constraint_impulse: FloatArray
    generalized_impulse: FloatArray
    kinetic_energy: FloatArray | float
    kinetic_energy_constrained: FloatArray | float
    kinetic_energy_admissible: FloatArray | float
    kinetic_energy_post: FloatArray | float
    energy_lost: FloatArray | float
    restitution: float

    def __post_init__(self) -> None:
        # One collision (batch shape ()): the energies are Python floats.
        python_scalars(self, _SCALAR_FIELDS)


_SCALAR_FIELDS = (
    "kinetic_energy",
    "kinetic_energy_constrained",
    "kinetic_energy_admissible",
    "kinetic_energy_post",
    "energy_lost",
)


def impact(
    M: ArrayLike | None,
    A: ArrayLike,
    q_dot: ArrayLike,
    *,
    restitution: float = 0.0,
    check: bool = True,
    mass_factor: ArrayLike | None = None,
) -> ImpactResult:
    """Resolve a collision with inert constraints ``A`` (paper eqs. 2-13).

    Parameters
    ----------
    M : array_like, shape (..., n, n), or None
        Mass matrix at the impact configuration; symmetric positive definite. None if
        ``mass_factor`` is given.
    A : array_like, shape (..., k, n)
        Jacobian of the constraints that become active (e.g. the striking foot's, eq. 4-5).
    q_dot : array_like, shape (..., n)
        Pre-impact generalized velocities ``q_dot-``.
    restitution : float, optional
        Coefficient ``e`` in [0, 1] applied to the constrained velocity:
        ``A q_dot+ = -e A q_dot-``. ``e = 0`` (default) is the paper's inert impact.
    check : bool, optional
        Validate shapes, finiteness, symmetry and definiteness of ``M`` and rank of ``A``.
    mass_factor : array_like, shape (..., p, n), optional
        ``F`` with ``M = F^T F`` (``p >= n``), e.g. the stacked ``sqrt(m_i) J_i`` of the bodies'
        point Jacobians, instead of ``M``. ``M`` is then never formed, so that accuracy depends
        on the condition number of ``F`` (the square root of that of ``M``): a mass matrix that
        is singular to working precision only because it is formed (e.g. a leg whose centre of
        mass is 1e-9 m from the hip) is resolved accurately.

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
    F: FloatArray | None = None
    if mass_factor is not None:
        if M is not None:
            raise ImpactInputError("give M or mass_factor, not both")
        F = _as_float("mass_factor", mass_factor, 2)
        M_ = np.swapaxes(F, -1, -2) @ F
        M_, A_, qd = _validate(M_, A, q_dot, False)
        if check:
            _check_factor(F)
            _check_rank(A_)
    elif M is None:
        raise ImpactInputError("M is required (or give mass_factor)")
    else:
        M_, A_, qd = _validate(M, A, q_dot, check)
    assert qd is not None
    S = _solve(M_, A_, qd, F)
    P_c = _projector(S)
    P_a = np.eye(P_c.shape[-1]) - P_c
    v_c = S.v_c
    v_a = S.qd - v_c
    lam = -(1.0 + e) * S.mu
    f = np.einsum("...ji,...j->...i", np.broadcast_to(A_, (*lam.shape[:-1], *A_.shape[-2:])), lam)
    q_plus = S.qd - (1.0 + e) * v_c
    T = _half_sq(S.u)
    T_c = _half_sq(S.z)
    T_a = _half_sq(S.u - S.z)
    T_plus = _half_sq(S.u - (1.0 + e) * S.z)
    qd_b = S.qd
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
