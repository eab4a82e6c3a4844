"""Compiled, batched impact algebra for two constraint rows and four coordinates.

The reference implementation :func:`heelstrike.core.impact.impact` handles any ``n`` and ``k`` with
batched LAPACK calls on per-item ``(n, n)`` matrices. Planar bipeds with a single foot striking
are the case ``k = 2``, ``n = 4`` (the compass gait of the paper), which this module solves with a
numba kernel: a 4x4 Cholesky factorization ``M = L L^T`` written out inline, then

.. math::

    Y = L^{-1} A^T,\\quad W = Y^T Y = A M^{-1} A^T,\\quad
    \\mu = W^{-1} A \\dot q^-,\\quad v_c = L^{-T} Y \\mu = P_c \\dot q^-,

so that ``q_dot+ = q_dot- - (1 + e) v_c``, ``lambda = -(1 + e) mu`` and
``T_c = 1/2 mu^T W mu = 1/2 |Y mu|^2`` (eqs. 6-13 of Font & Kövecses 2008). No projector is
formed. Results equal the reference path to rounding (``tests/test_fast_impact.py``).

The kernel runs ``prange``-parallel when called from the main thread and serially from any other
thread (e.g. a Dask worker thread in :func:`heelstrike.analysis.sweep.sweep`), so that chunk-level
and item-level parallelism do not oversubscribe the cores.
"""

from __future__ import annotations

import math
import threading
from typing import Any, NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from heelstrike.core.impact import ImpactInputError

__all__ = ["FastImpactResult", "impact_2x4", "use_parallel"]

FloatArray = NDArray[np.float64]

#: Status codes written by the kernels, per item.
STATUS_OK = 0
STATUS_NOT_FINITE = 1
STATUS_NOT_SPD = 2
STATUS_RANK_DEFICIENT = 3


class FastImpactResult(NamedTuple):
    """Result of :func:`impact_2x4`; field names follow :class:`~heelstrike.core.ImpactResult`.

    ``(...)`` is the broadcast batch shape of the inputs.

    Attributes
    ----------
    kinetic_energy : ndarray, shape (...)
        Pre-impact kinetic energy ``T`` (J), eq. (10).
    kinetic_energy_constrained : ndarray, shape (...)
        ``T_c = 1/2 (P_c q_dot-)^T M (P_c q_dot-)`` (J).
    kinetic_energy_admissible : ndarray, shape (...)
        ``T_a = 1/2 (P_a q_dot-)^T M (P_a q_dot-)`` (J).
    velocity_post : ndarray, shape (..., 4)
        ``q_dot+`` (m/s, rad/s).
    constraint_impulse : ndarray, shape (..., 2)
        ``lambda`` with ``M (q_dot+ - q_dot-) = A^T lambda`` (N s).
    energy_lost : ndarray, shape (...)
        ``(1 - e^2) T_c`` (J).
    """

    kinetic_energy: FloatArray
    kinetic_energy_constrained: FloatArray
    kinetic_energy_admissible: FloatArray
    velocity_post: FloatArray
    constraint_impulse: FloatArray
    energy_lost: FloatArray


def use_parallel(parallel: bool | None) -> bool:
    """Resolve the ``parallel`` option of the fast kernels.

    ``None`` means: parallel on the main thread, serial on any other thread.
    """
    if parallel is None:
        return threading.current_thread() is threading.main_thread()
    return bool(parallel)


def _solve_2x4(
    M: FloatArray,
    A: FloatArray,
    qd: FloatArray,
    e: float,
    qp: FloatArray,
    lam: FloatArray,
) -> tuple[int, float, float, float]:
    """Resolve one impact: ``M`` (4, 4), ``A`` (2, 4), ``qd`` (4,).

    Writes ``q_dot+`` into ``qp`` (4,) and ``lambda`` into ``lam`` (2,); returns
    ``(status, T, T_c, T_a)``. Inputs are assumed finite.
    """
    # Cholesky M = L L^T (lower triangle of M is used).
    L = np.zeros((4, 4))
    for j in range(4):
        d = M[j, j]
        for p in range(j):
            d -= L[j, p] * L[j, p]
        if not d > 0.0:
            return STATUS_NOT_SPD, 0.0, 0.0, 0.0
        L[j, j] = math.sqrt(d)
        for r in range(j + 1, 4):
            s = M[r, j]
            for p in range(j):
                s -= L[r, p] * L[j, p]
            L[r, j] = s / L[j, j]
    # Y = L^-1 A^T (4 x 2), forward substitution.
    Y = np.empty((4, 2))
    for c in range(2):
        for r in range(4):
            s = A[c, r]
            for p in range(r):
                s -= L[r, p] * Y[p, c]
            Y[r, c] = s / L[r, r]
    W00 = Y[0, 0] * Y[0, 0] + Y[1, 0] * Y[1, 0] + Y[2, 0] * Y[2, 0] + Y[3, 0] * Y[3, 0]
    W01 = Y[0, 0] * Y[0, 1] + Y[1, 0] * Y[1, 1] + Y[2, 0] * Y[2, 1] + Y[3, 0] * Y[3, 1]
    W11 = Y[0, 1] * Y[0, 1] + Y[1, 1] * Y[1, 1] + Y[2, 1] * Y[2, 1] + Y[3, 1] * Y[3, 1]
    det = W00 * W11 - W01 * W01
    if not det > 1e-24 * W00 * W11:
        return STATUS_RANK_DEFICIENT, 0.0, 0.0, 0.0
    b0 = A[0, 0] * qd[0] + A[0, 1] * qd[1] + A[0, 2] * qd[2] + A[0, 3] * qd[3]
    b1 = A[1, 0] * qd[0] + A[1, 1] * qd[1] + A[1, 2] * qd[2] + A[1, 3] * qd[3]
    mu0 = (W11 * b0 - W01 * b1) / det
    mu1 = (W00 * b1 - W01 * b0) / det
    # z = Y mu = L^T v_c; v_c by back substitution with L^T.
    z = np.empty(4)
    for r in range(4):
        z[r] = Y[r, 0] * mu0 + Y[r, 1] * mu1
    vc = np.empty(4)
    for r in range(3, -1, -1):
        s = z[r]
        for p in range(r + 1, 4):
            s -= L[p, r] * vc[p]
        vc[r] = s / L[r, r]
    # T = 1/2 |L^T qd|^2, T_a = 1/2 |L^T (qd - vc)|^2, T_c = 1/2 |z|^2.
    t = 0.0
    ta = 0.0
    tc = 0.0
    for r in range(4):
        u = 0.0
        ua = 0.0
        for p in range(r, 4):
            u += L[p, r] * qd[p]
            ua += L[p, r] * (qd[p] - vc[p])
        t += u * u
        ta += ua * ua
        tc += z[r] * z[r]
    for r in range(4):
        qp[r] = qd[r] - (1.0 + e) * vc[r]
    lam[0] = -(1.0 + e) * mu0
    lam[1] = -(1.0 + e) * mu1
    return STATUS_OK, 0.5 * t, 0.5 * tc, 0.5 * ta


solve_2x4 = njit(inline="always", fastmath=False, cache=True)(_solve_2x4)


def _impact_2x4_body(
    M: FloatArray,
    A: FloatArray,
    qd: FloatArray,
    e: float,
    T: FloatArray,
    Tc: FloatArray,
    Ta: FloatArray,
    qp: FloatArray,
    lam: FloatArray,
    status: NDArray[np.uint8],
    i: int,
) -> None:
    """Resolve item ``i``; ``M`` (N, 4, 4), ``A`` (N, 2, 4), ``qd`` (N, 4). Writes outputs."""
    for r in range(4):
        if not math.isfinite(qd[i, r]):
            status[i] = STATUS_NOT_FINITE
            return
        for c in range(4):
            if not math.isfinite(M[i, r, c]):
                status[i] = STATUS_NOT_FINITE
                return
        for c in range(2):
            if not math.isfinite(A[i, c, r]):
                status[i] = STATUS_NOT_FINITE
                return
    code, t, tc, ta = solve_2x4(M[i], A[i], qd[i], e, qp[i], lam[i])
    status[i] = code
    T[i] = t
    Tc[i] = tc
    Ta[i] = ta


_body = njit(inline="always", fastmath=False, cache=True)(_impact_2x4_body)


@njit(parallel=True, fastmath=False, cache=True)
def _kernel_parallel(M, A, qd, e, T, Tc, Ta, qp, lam, status):  # type: ignore[no-untyped-def]
    for i in prange(M.shape[0]):
        _body(M, A, qd, e, T, Tc, Ta, qp, lam, status, i)


@njit(parallel=False, fastmath=False, cache=True)
def _kernel_serial(M, A, qd, e, T, Tc, Ta, qp, lam, status):  # type: ignore[no-untyped-def]
    for i in range(M.shape[0]):
        _body(M, A, qd, e, T, Tc, Ta, qp, lam, status, i)


def raise_for_status(status: NDArray[np.uint8], messages: dict[int, str]) -> None:
    """Raise :class:`ImpactInputError` for the first item whose status is not OK."""
    bad = np.flatnonzero(status)
    if bad.size:
        first = int(bad[0])
        code = int(status[first])
        raise ImpactInputError(
            f"{messages.get(code, f'status {code}')} (flat batch index {first}; "
            f"{bad.size} bad item(s) in total)"
        )


def impact_2x4(
    M: ArrayLike,
    A: ArrayLike,
    q_dot: ArrayLike,
    *,
    restitution: float = 0.0,
    parallel: bool | None = None,
) -> FastImpactResult:
    """Batched impact with ``k = 2`` inert constraints on ``n = 4`` coordinates (compiled).

    Same physics and conventions as :func:`heelstrike.core.impact.impact`, without projectors.

    Parameters
    ----------
    M : array_like, shape (..., 4, 4)
        Mass matrices, symmetric positive definite (only the lower triangle is read).
    A : array_like, shape (..., 2, 4)
        Constraint Jacobians, full row rank.
    q_dot : array_like, shape (..., 4)
        Pre-impact velocities.
    restitution : float, optional
        Coefficient ``e`` in [0, 1] (default 0, the paper's inert impact).
    parallel : bool or None, optional
        Run the item loop in parallel threads; ``None`` (default) does so only on the main
        thread (see :func:`use_parallel`).

    Returns
    -------
    FastImpactResult
        Energies (...), ``q_dot+`` (..., 4), ``lambda`` (..., 2).

    Raises
    ------
    ImpactInputError
        Wrong shapes, non-finite entries, ``M`` not positive definite, ``A`` rank deficient, or
        ``restitution`` outside [0, 1].
    """
    e = float(restitution)
    if not (np.isfinite(e) and 0.0 <= e <= 1.0):
        raise ImpactInputError(f"restitution must lie in [0, 1], got {restitution!r}")
    M_ = np.asarray(M, dtype=float)
    A_ = np.asarray(A, dtype=float)
    v = np.asarray(q_dot, dtype=float)
    if M_.ndim < 2 or M_.shape[-2:] != (4, 4):
        raise ImpactInputError(f"M must have shape (..., 4, 4), got {M_.shape}")
    if A_.ndim < 2 or A_.shape[-2:] != (2, 4):
        raise ImpactInputError(f"A must have shape (..., 2, 4), got {A_.shape}")
    if v.ndim < 1 or v.shape[-1] != 4:
        raise ImpactInputError(f"q_dot must have shape (..., 4), got {v.shape}")
    try:
        batch = np.broadcast_shapes(M_.shape[:-2], A_.shape[:-2], v.shape[:-1])
    except ValueError as exc:
        raise ImpactInputError(
            f"leading (batch) axes do not broadcast: M {M_.shape}, A {A_.shape}, "
            f"q_dot {v.shape}"
        ) from exc
    n = int(np.prod(batch, dtype=np.int64))
    Mf = np.ascontiguousarray(np.broadcast_to(M_, (*batch, 4, 4))).reshape(n, 4, 4)
    Af = np.ascontiguousarray(np.broadcast_to(A_, (*batch, 2, 4))).reshape(n, 2, 4)
    vf = np.ascontiguousarray(np.broadcast_to(v, (*batch, 4))).reshape(n, 4)
    T = np.empty(n)
    Tc = np.empty(n)
    Ta = np.empty(n)
    qp = np.empty((n, 4))
    lam = np.empty((n, 2))
    status = np.zeros(n, dtype=np.uint8)
    kernel: Any = _kernel_parallel if use_parallel(parallel) else _kernel_serial
    kernel(Mf, Af, vf, e, T, Tc, Ta, qp, lam, status)
    raise_for_status(
        status,
        {
            STATUS_NOT_FINITE: "M, A or q_dot contains non-finite values (nan or inf)",
            STATUS_NOT_SPD: "M is not positive definite",
            STATUS_RANK_DEFICIENT: "A is rank deficient (fewer than k=2 independent rows)",
        },
    )
    Tc_ = Tc.reshape(batch)
    return FastImpactResult(
        kinetic_energy=T.reshape(batch),
        kinetic_energy_constrained=Tc_,
        kinetic_energy_admissible=Ta.reshape(batch),
        velocity_post=qp.reshape((*batch, 4)),
        constraint_impulse=lam.reshape((*batch, 2)),
        energy_lost=(1.0 - e * e) * Tc_,
    )
