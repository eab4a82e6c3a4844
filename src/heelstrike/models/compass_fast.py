"""Compiled closed-form heel strike of the compass gait (millions of impacts per second).

Same physics as ``core.impact(walker.mass_matrix(q), walker.contact_jacobian(q, "left"), q_dot)``
at the heel-strike configuration ``q4 = -2 q3`` of :func:`heel_strike_state`, without building
per-item matrices. With ``s = l - R``, ``c = cos q3``, ``S = sin q3``, ``mt = mH + 2 m``,
``k = mH s + m (2 s - b)`` and ``cos q4 = c^2 - S^2``, the mass matrix of
:meth:`CompassGait.mass_matrix` is

.. code-block:: text

    M = [[ mt,           0,            -c (k - m b),   m b c        ],
         [ 0,            mt,           -S (k + m b),  -m b S        ],
         [ .,            .,  mH s^2 + m (s-b)^2 + m (s^2 + b^2 - 2 s b cos q4) + 2 I,
                                                       m (b^2 - s b cos q4) + I ],
         [ .,            .,            .,              m b^2 + I    ]]

and the striking foot's Jacobian (eq. 5) is ``A = [I_2 | C]`` with
``C = [[R, s c + R], [-2 s S, -s S]]``. Each item is then solved without projectors (eqs.
6-13 of the paper), with every matrix entry a scalar: ``M = L L^T``
(Cholesky, written out; ``L10 = 0``), ``Y = L^-1 A^T``, ``W = Y^T Y = A M^-1 A^T`` (2x2),
``mu = W^-1 A q_dot-``, ``z = Y mu = L^T v_c``, ``v_c = P_c q_dot-`` by back substitution, and

.. code-block:: text

    T = |L^T q_dot-|^2 / 2,   T_c = |z|^2 / 2,   T_a = |L^T q_dot- - z|^2 / 2,
    q_dot+ = q_dot- - (1 + e) v_c,   lambda = -(1 + e) mu.

(An ``M``-orthogonal projection onto the null space of ``A``, a single 2x2 solve, is cheaper
still but loses up to ten times more digits on badly conditioned walkers, so it is not used.)
Agreement with the reference is to rounding: about ``1e-15 cond(M)`` relative
(``tests/test_fast_impact.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from heelstrike._caching import tolerate_numba_cache_errors
from heelstrike._typing import FloatArray
from heelstrike.core.fast import FastImpactResult, batched_impact, serial_and_parallel
from heelstrike.core.impact import ImpactInputError
from heelstrike.models.compass import CompassGait
from heelstrike.status import SolveStatus

tolerate_numba_cache_errors()  # numba's cache unwritable (full disk): run uncached

__all__ = ["HeelStrikeImpact", "heel_strike_impact"]


# Status codes the kernel writes: the codes of :class:`~heelstrike.status.SolveStatus` (plain
# ints, compile-time constants for numba).
_OK = SolveStatus.CONVERGED.code
_NOT_FINITE = SolveStatus.NOT_FINITE.code
_BAD_MASS = SolveStatus.BAD_MASS.code
_BAD_LENGTH = SolveStatus.BAD_LENGTH.code
_BAD_COM = SolveStatus.BAD_COM.code
_BAD_RADIUS = SolveStatus.BAD_RADIUS.code
_BAD_INERTIA = SolveStatus.BAD_INERTIA.code
_SINGULAR = SolveStatus.SINGULAR_MASS_MATRIX.code

# Order of the per-item inputs in the kernel's argument list.
_INPUTS = (
    "impact_angle",
    "foot_radius",
    "q1_dot",
    "q2_dot",
    "q3_dot",
    "q4_dot",
    "hip_mass",
    "leg_mass",
    "leg_length",
    "leg_com_from_hip",
    "leg_inertia",
)


class HeelStrikeImpact(FastImpactResult):
    """Heel-strike impact of the compass gait: the fields of
    :class:`~heelstrike.core.fast.FastImpactResult`, each of the broadcast input shape (...)
    (``T_c`` and ``T_a`` of eq. 10; ``lambda``: tangential and normal impulse on the striking
    foot), and the trailing foot's ``q2_dot_post``."""

    __slots__ = ()

    @property
    def q2_dot_post(self) -> FloatArray:
        """``q2_dot+`` (m/s), shape (...): the trailing foot lifts off iff it is > 0."""
        return np.asarray(self.velocity_post[..., 1])


def _at(a: FloatArray, i: int) -> float:
    """``a[i]``, or ``a[0]`` for a broadcast scalar (``len(a) == 1``)."""
    return float(a[i]) if a.shape[0] > 1 else float(a[0])


_at_nb = njit(inline="always", cache=True)(_at)


#: What :func:`strike` returns: ``(status, T, T_c, T_a, q_dot+ (4), lambda (2))``.
_StrikeTuple = tuple[int, float, float, float, float, float, float, float, float, float]


def _failed(status: int) -> _StrikeTuple:
    nan = math.nan
    return (status, nan, nan, nan, nan, nan, nan, nan, nan, nan)


_failed_nb = njit(inline="always", cache=True)(_failed)


def _strike(
    q3: float, R: float, w1: float, w2: float, w3: float, w4: float, mH: float, m: float,
    ll: float, b: float, inertia: float, e: float,
) -> _StrikeTuple:
    """One heel strike of the compass gait with circular feet at the symmetric configuration
    ``q4 = -2 q3`` (eqs. 5-13), written out: the one compass impact of the compiled code.

    Returns ``(status, T, T_c, T_a, q1_dot+, q2_dot+, q3_dot+, q4_dot+, lambda_t, lambda_n)``
    (J, m/s, rad/s, N s); a status other than ``_OK`` comes with NaNs.
    """
    if not (
        math.isfinite(q3)
        and math.isfinite(R)
        and math.isfinite(w1)
        and math.isfinite(w2)
        and math.isfinite(w3)
        and math.isfinite(w4)
        and math.isfinite(mH)
        and math.isfinite(m)
        and math.isfinite(ll)
        and math.isfinite(b)
        and math.isfinite(inertia)
    ):
        return _failed_nb(_NOT_FINITE)
    if not (mH > 0.0 and m > 0.0):
        return _failed_nb(_BAD_MASS)
    if not ll > 0.0:
        return _failed_nb(_BAD_LENGTH)
    if not (b > 0.0 and b < ll):
        return _failed_nb(_BAD_COM)
    if not (R >= 0.0 and R <= ll):
        return _failed_nb(_BAD_RADIUS)
    if not inertia >= 0.0:
        return _failed_nb(_BAD_INERTIA)
    s = ll - R
    c = math.cos(q3)
    sn = math.sin(q3)
    c4 = c * c - sn * sn
    mt = mH + 2.0 * m
    k = mH * s + m * (2.0 * s - b)
    mb = m * b
    # Mass matrix (symmetric; M01 = 0, M00 = M11 = mt).
    m02 = -c * (k - mb)
    m12 = -sn * (k + mb)
    m03 = mb * c
    m13 = -mb * sn
    m22 = (
        mH * s * s
        + m * (s - b) * (s - b)
        + m * (s * s + b * b - 2.0 * s * b * c4)
        + 2.0 * inertia
    )
    m23 = m * (b * b - s * b * c4) + inertia
    m33 = m * b * b + inertia
    # Striking foot's Jacobian A = [I | C] (eq. 5).
    a02 = R
    a03 = s * c + R
    a12 = -2.0 * s * sn
    a13 = -s * sn
    # Cholesky M = L L^T, written out (M10 = 0).
    L00 = math.sqrt(mt)
    L11 = math.sqrt(mt)
    L20 = m02 / L00
    L30 = m03 / L00
    L21 = m12 / L11
    L31 = m13 / L11
    d2 = m22 - L20 * L20 - L21 * L21
    if not d2 > 0.0:
        return _failed_nb(_SINGULAR)
    L22 = math.sqrt(d2)
    L32 = (m23 - L30 * L20 - L31 * L21) / L22
    d3 = m33 - L30 * L30 - L31 * L31 - L32 * L32
    if not d3 > 0.0:
        return _failed_nb(_SINGULAR)
    L33 = math.sqrt(d3)
    # Y = L^-1 A^T: column 0 from A's row (1, 0, a02, a03), column 1 from (0, 1, a12, a13).
    y00 = 1.0 / L00
    y10 = 0.0
    y20 = (a02 - L20 * y00) / L22
    y30 = (a03 - L30 * y00 - L32 * y20) / L33
    y01 = 0.0
    y11 = 1.0 / L11
    y21 = (a12 - L21 * y11) / L22
    y31 = (a13 - L31 * y11 - L32 * y21) / L33
    W00 = y00 * y00 + y20 * y20 + y30 * y30
    W01 = y20 * y21 + y30 * y31
    W11 = y11 * y11 + y21 * y21 + y31 * y31
    det = W00 * W11 - W01 * W01
    if not det > 1e-24 * W00 * W11:
        return _failed_nb(_SINGULAR)
    # mu = W^-1 A q_dot-.
    b0 = w1 + a02 * w3 + a03 * w4
    b1 = w2 + a12 * w3 + a13 * w4
    mu0 = (W11 * b0 - W01 * b1) / det
    mu1 = (W00 * b1 - W01 * b0) / det
    # z = Y mu = L^T v_c; back substitution for v_c = P_c q_dot-.
    z0 = y00 * mu0 + y01 * mu1
    z1 = y10 * mu0 + y11 * mu1
    z2 = y20 * mu0 + y21 * mu1
    z3 = y30 * mu0 + y31 * mu1
    v3 = z3 / L33
    v2 = (z2 - L32 * v3) / L22
    v1 = (z1 - L21 * v2 - L31 * v3) / L11
    v0 = (z0 - L20 * v2 - L30 * v3) / L00
    # Energies from L^T q_dot- and L^T (q_dot- - v_c).
    t0 = L00 * w1 + L20 * w3 + L30 * w4
    t1 = L11 * w2 + L21 * w3 + L31 * w4
    t2 = L22 * w3 + L32 * w4
    t3 = L33 * w4
    u0 = t0 - z0
    u1 = t1 - z1
    u2 = t2 - z2
    u3 = t3 - z3
    g = 1.0 + e
    return (
        _OK,
        0.5 * (t0 * t0 + t1 * t1 + t2 * t2 + t3 * t3),
        0.5 * (z0 * z0 + z1 * z1 + z2 * z2 + z3 * z3),
        0.5 * (u0 * u0 + u1 * u1 + u2 * u2 + u3 * u3),
        w1 - g * v0,
        w2 - g * v1,
        w3 - g * v2,
        w4 - g * v3,
        -g * mu0,
        -g * mu1,
    )


#: :func:`_strike` compiled (inlined into its callers); also what the compiled walk uses.
strike = njit(inline="always", cache=True)(_strike)


def _heel_strike_body(
    q3a: FloatArray, Ra: FloatArray, w1a: FloatArray, w2a: FloatArray, w3a: FloatArray,
    w4a: FloatArray, mHa: FloatArray, ma: FloatArray, la: FloatArray, ba: FloatArray,
    Ia: FloatArray, rolling: bool, e: float, T: FloatArray, Tc: FloatArray, Ta: FloatArray,
    qp: FloatArray, lam: FloatArray, status: NDArray[np.uint8], i: int,
) -> None:
    """Resolve item ``i``. Each input is a 1-D array of the batch length, or of length 1 for a
    broadcast scalar (inputs in ``_INPUTS`` order)."""
    q3 = _at_nb(q3a, i)
    R = _at_nb(Ra, i)
    w3 = _at_nb(w3a, i)
    w1 = -R * w3 if rolling else _at_nb(w1a, i)
    w2 = _at_nb(w2a, i)
    w4 = _at_nb(w4a, i)
    mH = _at_nb(mHa, i)
    m = _at_nb(ma, i)
    ll = _at_nb(la, i)
    b = _at_nb(ba, i)
    inertia = _at_nb(Ia, i)
    st, t, tc, ta, p0, p1, p2, p3, l0, l1 = strike(q3, R, w1, w2, w3, w4, mH, m, ll, b,
                                                   inertia, e)
    status[i] = st
    if st != _OK:
        return
    T[i], Tc[i], Ta[i] = t, tc, ta
    qp[i, 0], qp[i, 1], qp[i, 2], qp[i, 3] = p0, p1, p2, p3
    lam[i, 0], lam[i, 1] = l0, l1


_body = njit(inline="always", fastmath=False, cache=True)(_heel_strike_body)


def _heel_strike_kernel(
    q3: FloatArray, R: FloatArray, w1: FloatArray, w2: FloatArray, w3: FloatArray,
    w4: FloatArray, mH: FloatArray, m: FloatArray, ll: FloatArray, b: FloatArray,
    inertia: FloatArray, rolling: bool, e: float, T: FloatArray, Tc: FloatArray,
    Ta: FloatArray, qp: FloatArray, lam: FloatArray, status: NDArray[np.uint8],
) -> None:
    """Every item of the batch (:func:`_heel_strike_body`)."""
    for i in prange(T.shape[0]):
        _body(q3, R, w1, w2, w3, w4, mH, m, ll, b, inertia, rolling, e, T, Tc, Ta, qp, lam,
              status, i)


_KERNELS = serial_and_parallel(_heel_strike_kernel)


def heel_strike_impact(
    impact_angle: ArrayLike,
    *,
    walker: CompassGait | None = None,
    foot_radius: ArrayLike | None = None,
    hip_mass: ArrayLike | None = None,
    leg_mass: ArrayLike | None = None,
    leg_length: ArrayLike | None = None,
    leg_com_from_hip: ArrayLike | None = None,
    leg_inertia: ArrayLike | None = None,
    q3_dot: ArrayLike = 1.0,
    q4_dot: ArrayLike = 0.0,
    q1_dot: ArrayLike | None = None,
    q2_dot: ArrayLike = 0.0,
    restitution: float = 0.0,
    parallel: bool | None = None,
) -> HeelStrikeImpact:
    """Heel strike of the compass gait at ``q4 = -2 q3``, compiled and batched.

    Equals ``impact(walker.mass_matrix(q), walker.contact_jacobian(q, "left"), q_dot)`` for
    ``q, q_dot`` from :func:`~heelstrike.models.compass.heel_strike_state` (to rounding), at
    tens of millions of impacts per second. Every array argument broadcasts against the others.

    Parameters
    ----------
    impact_angle : array_like, shape (...)
        ``q3`` at impact (rad); the left foot strikes with ``q4 = -2 q3``.
    walker : CompassGait, optional
        Source of the walker parameters not given explicitly (default: the paper's walker).
        Its parameters may be arrays.
    foot_radius, hip_mass, leg_mass, leg_length, leg_com_from_hip, leg_inertia : array_like
        Override the walker's ``R`` (m), ``mH`` (kg), ``m`` (kg), ``l`` (m), ``b`` (m) and leg
        inertia (kg m^2). Gravity does not enter an impact.
    q3_dot, q4_dot : array_like
        Pre-impact angular velocities (rad/s); the paper uses 1 and 0.
    q1_dot : array_like or None
        Pre-impact ``q1_dot`` (m/s); ``None`` (default) means the stance foot rolls,
        ``q1_dot = -R q3_dot``.
    q2_dot : array_like
        Pre-impact ``q2_dot`` (m/s), 0 for a stance foot on the ground.
    restitution : float
        Coefficient ``e`` in [0, 1] of the constrained velocity (default 0, the paper).
    parallel : bool or None
        Parallel item loop; ``None`` means only on the main thread.

    Returns
    -------
    HeelStrikeImpact
        ``T``, ``T_c``, ``T_a`` (J), ``q_dot+`` (..., 4), ``lambda`` (..., 2) (N s),
        ``q2_dot_post`` (m/s).

    Raises
    ------
    ImpactInputError
        Non-finite inputs, invalid walker parameters, inputs that do not broadcast, or
        ``restitution`` outside [0, 1].
    """
    e = float(restitution)
    if not (np.isfinite(e) and 0.0 <= e <= 1.0):
        raise ImpactInputError(f"restitution must lie in [0, 1], got {restitution!r}")
    w = CompassGait() if walker is None else walker
    given: dict[str, ArrayLike | None] = {
        "impact_angle": impact_angle,
        "foot_radius": w.foot_radius if foot_radius is None else foot_radius,
        "q1_dot": 0.0 if q1_dot is None else q1_dot,
        "q2_dot": q2_dot,
        "q3_dot": q3_dot,
        "q4_dot": q4_dot,
        "hip_mass": w.hip_mass if hip_mass is None else hip_mass,
        "leg_mass": w.leg_mass if leg_mass is None else leg_mass,
        "leg_length": w.leg_length if leg_length is None else leg_length,
        "leg_com_from_hip": w.leg_com_from_hip if leg_com_from_hip is None else leg_com_from_hip,
        "leg_inertia": w.leg_inertia if leg_inertia is None else leg_inertia,
    }
    arrays = [np.asarray(given[name], dtype=float) for name in _INPUTS]
    try:
        batch = np.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError as exc:
        shapes = ", ".join(f"{n} {a.shape}" for n, a in zip(_INPUTS, arrays, strict=True))
        raise ImpactInputError(f"inputs do not broadcast: {shapes}") from exc
    # 1-D kernel inputs: scalars stay length 1; full-shape contiguous arrays are not copied.
    flat = [
        a.reshape(1) if a.size == 1 else np.ascontiguousarray(np.broadcast_to(a, batch)).ravel()
        for a in arrays
    ]
    return HeelStrikeImpact._make(
        batched_impact(_KERNELS, (*flat, q1_dot is None), batch, e, parallel,
                       lambda _: SolveStatus.messages_by_code())
    )
