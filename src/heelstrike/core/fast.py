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
import types
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import tuple_dict
from heelstrike._typing import FloatArray
from heelstrike.core._parallel import use_parallel
from heelstrike.core.impact import ImpactInputError

__all__ = ["FastImpactResult", "impact_2x4", "use_parallel"]


#: Status codes written by the kernels, per item.
STATUS_OK = 0
STATUS_NOT_FINITE = 1
STATUS_NOT_SPD = 2
STATUS_RANK_DEFICIENT = 3
STATUS_SINGULAR = 4

#: Items whose mass matrix, scaled to unit diagonal, has a 1-norm condition number at or above
#: this are rejected as singular to working precision (cf. ``heelstrike.core.impact``).
SINGULAR_COND = 1.0 / (4.0 * float(np.finfo(float).eps))


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

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain Python (:func:`~heelstrike._results.tuple_dict`)."""
        return tuple_dict(self)


def serial_and_parallel(py_func: Callable[..., None], **options: Any) -> tuple[Any, Any]:
    """Compile a batch kernel twice with numba: ``(serial, parallel)``.

    ``py_func`` loops over its items with ``numba.prange``, which is ``range`` in the serial
    compile and a parallel loop in the ``parallel=True`` one; ``options`` go to both ``njit``
    calls (``cache=True`` is added). Each compile gets its own copy of the function, named
    ``<name>_serial`` / ``<name>_parallel``: numba keys its disk cache by a function's name and
    bytecode but not by the compile options, so two compiles of one function would load each
    other's cached code (the parallel kernel running serially, or worse).
    """

    def named(suffix: str) -> Callable[..., None]:
        f = types.FunctionType(py_func.__code__, py_func.__globals__, py_func.__name__ + suffix,
                               py_func.__defaults__, py_func.__closure__)
        f.__qualname__ = py_func.__qualname__ + suffix
        f.__doc__ = py_func.__doc__
        return f

    serial = njit(cache=True, **options)(named("_serial"))
    parallel = njit(cache=True, parallel=True, **options)(named("_parallel"))
    return serial, parallel


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
    # Scale to unit diagonal: M~ = D^-1 M D^-1, A~ = A D^-1 (rows then normalized to unit
    # length, scales rs), q~ = D qd. Makes the checks and the accuracy independent of units.
    sc = np.empty(4)
    for j in range(4):
        if not M[j, j] > 0.0:
            return STATUS_NOT_SPD, 0.0, 0.0, 0.0
        sc[j] = math.sqrt(M[j, j])
    At = np.empty((2, 4))
    rs = np.empty(2)
    for c in range(2):
        amax = 0.0
        for r in range(4):
            At[c, r] = A[c, r] / sc[r]
            amax = max(amax, abs(At[c, r]))
        if not amax > 0.0:
            return STATUS_RANK_DEFICIENT, 0.0, 0.0, 0.0
        nrm = 0.0
        for r in range(4):
            nrm += (At[c, r] / amax) ** 2
        rs[c] = amax * math.sqrt(nrm)
        for r in range(4):
            At[c, r] /= rs[c]
    qt = np.empty(4)
    for r in range(4):
        qt[r] = qd[r] * sc[r]
    # Cholesky M~ = L L^T (lower triangle of M is used).
    L = np.zeros((4, 4))
    for j in range(4):
        d = M[j, j] / (sc[j] * sc[j])
        for p in range(j):
            d -= L[j, p] * L[j, p]
        if not d > 0.0:
            return STATUS_NOT_SPD, 0.0, 0.0, 0.0
        L[j, j] = math.sqrt(d)
        for r in range(j + 1, 4):
            s = M[r, j] / (sc[r] * sc[j])
            for p in range(j):
                s -= L[r, p] * L[j, p]
            L[r, j] = s / L[j, j]
    # Singular to working precision: 1-norm condition estimate of M~ via L^-1.
    Li = np.zeros((4, 4))
    for c in range(4):
        for r in range(c, 4):
            s = 1.0 if r == c else 0.0
            for p in range(c, r):
                s -= L[r, p] * Li[p, c]
            Li[r, c] = s / L[r, r]
    n1 = 0.0
    ni = 0.0
    for c in range(4):
        col = 0.0
        coli = 0.0
        for r in range(4):
            col += abs(M[r, c]) / (sc[r] * sc[c])
            mi = 0.0
            for p in range(max(r, c), 4):
                mi += Li[p, r] * Li[p, c]
            coli += abs(mi)
        n1 = max(n1, col)
        ni = max(ni, coli)
    if not n1 * ni < SINGULAR_COND:
        return STATUS_SINGULAR, 0.0, 0.0, 0.0
    # Y = L^-1 A~^T (4 x 2), forward substitution.
    Y = np.empty((4, 2))
    for c in range(2):
        for r in range(4):
            s = At[c, r]
            for p in range(r):
                s -= L[r, p] * Y[p, c]
            Y[r, c] = s / L[r, r]
    # Y = Q R (2 columns, Gram-Schmidt with one re-orthogonalization): W = R^T R without
    # forming it; w = R^-T b, mu = R^-1 w, z = Q w = Y mu, 2 T_c = |w|^2.
    r00 = math.sqrt(Y[0, 0] ** 2 + Y[1, 0] ** 2 + Y[2, 0] ** 2 + Y[3, 0] ** 2)
    ny1 = math.sqrt(Y[0, 1] ** 2 + Y[1, 1] ** 2 + Y[2, 1] ** 2 + Y[3, 1] ** 2)
    if not (r00 > 0.0 and ny1 > 0.0):
        return STATUS_RANK_DEFICIENT, 0.0, 0.0, 0.0
    q0 = np.empty(4)
    q1 = np.empty(4)
    for r in range(4):
        q0[r] = Y[r, 0] / r00
        q1[r] = Y[r, 1]
    r01 = 0.0
    for _ in range(2):
        c = q0[0] * q1[0] + q0[1] * q1[1] + q0[2] * q1[2] + q0[3] * q1[3]
        r01 += c
        for r in range(4):
            q1[r] -= c * q0[r]
    r11 = math.sqrt(q1[0] ** 2 + q1[1] ** 2 + q1[2] ** 2 + q1[3] ** 2)
    if not r11 > 1e-12 * ny1:
        return STATUS_RANK_DEFICIENT, 0.0, 0.0, 0.0
    for r in range(4):
        q1[r] /= r11
    b0 = At[0, 0] * qt[0] + At[0, 1] * qt[1] + At[0, 2] * qt[2] + At[0, 3] * qt[3]
    b1 = At[1, 0] * qt[0] + At[1, 1] * qt[1] + At[1, 2] * qt[2] + At[1, 3] * qt[3]
    w0 = b0 / r00
    w1 = (b1 - r01 * w0) / r11
    mu1 = w1 / r11
    mu0 = (w0 - r01 * mu1) / r00
    # z = Q w = L^T v_c; v_c by back substitution with L^T.
    z = np.empty(4)
    for r in range(4):
        z[r] = q0[r] * w0 + q1[r] * w1
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
            u += L[p, r] * qt[p]
            ua += L[p, r] * (qt[p] - vc[p])
        t += u * u
        ta += ua * ua
        tc += z[r] * z[r]
    for r in range(4):
        qp[r] = qd[r] - (1.0 + e) * vc[r] / sc[r]
    lam[0] = -(1.0 + e) * mu0 / rs[0]
    lam[1] = -(1.0 + e) * mu1 / rs[1]
    return STATUS_OK, 0.5 * t, 0.5 * tc, 0.5 * ta


solve_2x4 = njit(inline="always", fastmath=False, cache=True)(_solve_2x4)


def _impact_2x4_body(
    M: FloatArray, A: FloatArray, qd: FloatArray, e: float, T: FloatArray, Tc: FloatArray,
    Ta: FloatArray, qp: FloatArray, lam: FloatArray, status: NDArray[np.uint8], i: int,
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


def _impact_2x4_kernel(
    M: FloatArray, A: FloatArray, qd: FloatArray, e: float, T: FloatArray, Tc: FloatArray,
    Ta: FloatArray, qp: FloatArray, lam: FloatArray, status: NDArray[np.uint8],
) -> None:
    """Every item of the batch (:func:`_impact_2x4_body`)."""
    for i in prange(M.shape[0]):
        _body(M, A, qd, e, T, Tc, Ta, qp, lam, status, i)


_KERNELS = serial_and_parallel(_impact_2x4_kernel)


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


def batched_impact(
    kernels: tuple[Any, Any],
    args: tuple[Any, ...],
    batch: tuple[int, ...],
    e: float,
    parallel: bool | None,
    messages: Callable[[NDArray[np.uint8]], dict[int, str]],
) -> FastImpactResult:
    """Run a ``(serial, parallel)`` impact kernel pair (:func:`serial_and_parallel`) on a batch.

    The kernel is called as ``kernel(*args, e, T, Tc, Ta, q_dot+, lambda, status)`` on flat
    outputs of ``prod(batch)`` items; a status other than 0 raises :class:`ImpactInputError`
    with ``messages(status)[code]``.
    """
    n = int(np.prod(batch, dtype=np.int64))
    T = np.empty(n)
    Tc = np.empty(n)
    Ta = np.empty(n)
    qp = np.empty((n, 4))
    lam = np.empty((n, 2))
    status = np.zeros(n, dtype=np.uint8)
    kernel = kernels[1] if use_parallel(parallel) else kernels[0]
    kernel(*args, e, T, Tc, Ta, qp, lam, status)
    raise_for_status(status, messages(status))
    Tc_ = Tc.reshape(batch)
    return FastImpactResult(
        kinetic_energy=T.reshape(batch),
        kinetic_energy_constrained=Tc_,
        kinetic_energy_admissible=Ta.reshape(batch),
        velocity_post=qp.reshape((*batch, 4)),
        constraint_impulse=lam.reshape((*batch, 2)),
        energy_lost=(1.0 - e * e) * Tc_,
    )


def _cond_note(M: FloatArray, status: NDArray[np.uint8], code: int) -> str:
    """Why the first item with ``status == code`` was refused: indefinite or singular to working
    precision, with the condition number of ``M`` scaled to unit diagonal; ``""`` if none."""
    bad = np.flatnonzero(status == code)
    if not bad.size:
        return ""
    Mi = M[int(bad[0])]
    d = np.diagonal(Mi)
    if not np.all(d > 0):
        return f": a diagonal entry is {float(d[~(d > 0)][0]):.6g} (must be > 0)"
    s = np.sqrt(d)
    Mt = (Mi / s[:, None]) / s[None, :]
    ev = np.linalg.eigvalsh(0.5 * (Mt + Mt.T))
    if ev[0] < -4.0 * float(np.finfo(float).eps) * ev[-1]:
        return (
            f": it is indefinite (after scaling to unit diagonal its eigenvalues range from "
            f"{ev[0]:.3g} to {ev[-1]:.3g})"
        )
    cond = float(ev[-1] / ev[0]) if ev[0] > 0 else float("inf")
    return (
        f": it is singular to working precision (condition number {cond:.3g} after scaling "
        f"to unit diagonal; the limit is about {SINGULAR_COND:.3g})"
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
        thread (see :func:`heelstrike.core._parallel.use_parallel`).

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

    def messages(status: NDArray[np.uint8]) -> dict[int, str]:
        return {
            STATUS_NOT_FINITE: "M, A or q_dot contains non-finite values (nan or inf)",
            STATUS_NOT_SPD: "M is not positive definite" + _cond_note(Mf, status, STATUS_NOT_SPD),
            STATUS_RANK_DEFICIENT: "A is rank deficient (fewer than k=2 independent rows)",
            STATUS_SINGULAR: "M is not positive definite" + _cond_note(Mf, status, STATUS_SINGULAR),
        }

    return batched_impact(_KERNELS, (Mf, Af, vf), batch, e, parallel, messages)
