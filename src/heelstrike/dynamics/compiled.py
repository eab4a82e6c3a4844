"""Compiled passive walking of the circular-feet compass gait: one walker or whole ensembles.

This module re-implements, in numba-compiled code, exactly the hybrid model of
:func:`heelstrike.dynamics.hybrid.simulate` for the passive :class:`~heelstrike.models.CompassGait`
on a slope (no torque, no push-off, inert impact):

- **Single support.** The stance foot rolls (``q1 = c - R q3``, ``q2 = R``); the free coordinates
  ``theta = (q3, q4)`` obey ``J^T M J theta_dd = -J^T h`` with the constant null-space basis ``J``
  of :class:`~heelstrike.dynamics.single_support.SingleSupport`. The 2x2 reduced mass matrix and
  forcing are written in closed form from the same point Jacobians as
  :meth:`CompassGait.mass_matrix` / :meth:`CompassGait.bias_forces`: with ``s = l - R``,
  ``e(t) = (-sin t, cos t)`` and the reduced Jacobians (columns ``q3_dot``, ``q4_dot``)

  - hip ``j_H = [(-R - s cos q3, 0), (-s sin q3, 0)]``,
  - stance-leg centre of mass ``j_R = [(-R - (s - b) cos q3, 0), (-(s - b) sin q3, 0)]``,
  - swing-leg centre of mass ``j_L = j_H + b [(cos q34, cos q34), (sin q34, sin q34)]``,

  ``J^T M J = sum m_i j_i^T j_i + I [[2, 1], [1, 1]]`` and
  ``-J^T h = -sum m_i j_i^T (a_i - g)`` where ``a_i`` are the velocity-product accelerations
  (``a_H = -s e(q3) q3_dot^2``, ``a_R = -(s - b) e(q3) q3_dot^2``,
  ``a_L = a_H + b e(q34) q34_dot^2``) and ``g = g (-sin gamma, -cos gamma)``. The ground
  reaction is Newton's law for the whole walker, ``lambda = sum m_i (j_i theta_dd + a_i) - m g``.
- **Integrator.** Dormand-Prince 5(4) with scipy's error norm (RMS of
  ``err / (atol + rtol max(|y|, |y_new|))``) and step-size control.
- **Events.** The two phases of a step and their terminal events are those of ``simulate``
  (mid-stance, falls, lost contact, heel strike ``2 q3 + q4`` rising through 0), detected by a
  sign change over an accepted step with the same direction rules as ``solve_ivp``. The event
  time is located by the Illinois method on the *exact* Runge-Kutta step of length ``tau`` from
  the step's start (each trial is a fresh DP5 step), to ``|d tau| < 1e-13 s``; the earliest
  event of a step ends the phase.
- **Impact and swap.** ``q_dot+ = P_a q_dot-`` with the full 4x4 ``M`` and the left foot's
  Jacobian ``A_L`` (Cholesky solves), ``T_c = 1/2 mu^T (A M^-1 A^T) mu``; the trailing foot must
  lift (``q2_dot+ > 1e-12 m/s``); then ``q3 <- q3 + q4``, ``q4 <- -q4`` and the velocities alike.

Status codes are :attr:`WalkStatus.code <heelstrike.dynamics.hybrid.WalkStatus>` (module-level
constants below, compile-time constants for numba; :meth:`WalkStatus.from_code` converts back).
``tests/test_compiled.py`` checks everything against ``simulate``.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from heelstrike.dynamics.hybrid import WalkStatus
from heelstrike.models.compass import CompassGait

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "STATUS_NAMES",
    "CompiledStep",
    "EnsembleResult",
    "ensemble_walk",
    "reduced_dynamics_compiled",
    "single_support_compiled",
    "step_map_compiled",
    "walker_parameters",
]

#: Status names indexed by the integer codes written by the kernels (``WalkStatus.code``).
STATUS_NAMES: tuple[str, ...] = WalkStatus.names_by_code()
# Kernel status codes: plain ints taken from the enum (numba freezes globals at compile time).
COMPLETED = WalkStatus.COMPLETED.code
FELL_FORWARD = WalkStatus.FELL_FORWARD.code
FELL_BACKWARD = WalkStatus.FELL_BACKWARD.code
TRAILING_FOOT_STAYS = WalkStatus.TRAILING_FOOT_STAYS.code
LOST_CONTACT = WalkStatus.LOST_CONTACT.code
NO_HEEL_STRIKE = WalkStatus.NO_HEEL_STRIKE.code
INTEGRATION_FAILED = WalkStatus.INTEGRATION_FAILED.code

#: Layout of a row of the parameter array: mH, m, l, b, R, I, g, slope.
PARAMETER_NAMES: tuple[str, ...] = (
    "hip_mass",
    "leg_mass",
    "leg_length",
    "leg_com_from_hip",
    "foot_radius",
    "leg_inertia",
    "gravity",
    "slope",
)

# Event kinds. Phase 1 (before mid-stance): MID, BACK1, NORMAL; phase 2: STRIKE, BACK2, FWD,
# NORMAL (the order of ``_step_events`` in hybrid.py).
_EV_MID = 0
_EV_BACK1 = 1
_EV_NORMAL = 2
_EV_STRIKE = 3
_EV_BACK2 = 4
_EV_FWD = 5
_EV_NONE = -1  # time limit reached
_EV_FAIL = -2  # integrator failure

# Dormand-Prince 5(4) tableau.
_C2, _C3, _C4, _C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
_A21 = 1.0 / 5.0
_A31, _A32 = 3.0 / 40.0, 9.0 / 40.0
_A41, _A42, _A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_A51, _A52, _A53, _A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_A61, _A62, _A63, _A64, _A65 = (
    9017.0 / 3168.0,
    -355.0 / 33.0,
    46732.0 / 5247.0,
    49.0 / 176.0,
    -5103.0 / 18656.0,
)
_B1, _B3, _B4, _B5, _B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
_E1, _E3, _E4, _E5, _E6, _E7 = (
    71.0 / 57600.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
)


# ---------------------------------------------------------------------------------------------
# Dynamics (numba functions are typed for readers; numba ignores the annotations).
# ---------------------------------------------------------------------------------------------
@njit(cache=True, nogil=True)
def _dynamics(p: FloatArray, y: FloatArray) -> tuple[float, float, float, float]:
    """Reduced accelerations and ground reaction: ``(q3_dd, q4_dd, lambda_t, lambda_n)``."""
    mH, m, l, b, R, inertia, g, gam = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    q3, q4, w3, w4 = y[0], y[1], y[2], y[3]
    s = l - R
    c3, s3 = math.cos(q3), math.sin(q3)
    c34, s34 = math.cos(q3 + q4), math.sin(q3 + q4)
    w34 = w3 + w4
    gx, gy = -g * math.sin(gam), -g * math.cos(gam)
    # reduced Jacobians (x, y rows; q3, q4 columns)
    hx3, hy3 = -R - s * c3, -s * s3
    rx3, ry3 = -R - (s - b) * c3, -(s - b) * s3
    lx3, ly3 = hx3 + b * c34, hy3 + b * s34
    lx4, ly4 = b * c34, b * s34
    # velocity-product accelerations
    w3s, w34s = w3 * w3, w34 * w34
    ahx, ahy = s * s3 * w3s, -s * c3 * w3s
    arx, ary = (s - b) * s3 * w3s, -(s - b) * c3 * w3s
    alx, aly = ahx - b * s34 * w34s, ahy + b * c34 * w34s
    # reduced mass matrix
    m11 = mH * (hx3 * hx3 + hy3 * hy3) + m * (rx3 * rx3 + ry3 * ry3 + lx3 * lx3 + ly3 * ly3)
    m12 = m * (lx3 * lx4 + ly3 * ly4)
    m22 = m * (lx4 * lx4 + ly4 * ly4)
    m11 += 2.0 * inertia
    m12 += inertia
    m22 += inertia
    # reduced forcing -J^T h
    fhx, fhy = ahx - gx, ahy - gy
    frx, fry = arx - gx, ary - gy
    flx, fly = alx - gx, aly - gy
    f1 = -(mH * (hx3 * fhx + hy3 * fhy) + m * (rx3 * frx + ry3 * fry + lx3 * flx + ly3 * fly))
    f2 = -(m * (lx4 * flx + ly4 * fly))
    det = m11 * m22 - m12 * m12
    a3 = (m22 * f1 - m12 * f2) / det
    a4 = (m11 * f2 - m12 * f1) / det
    # ground reaction (Newton's law for the centre of mass)
    lam_t = (
        mH * (hx3 * a3 + ahx)
        + m * (rx3 * a3 + arx)
        + m * (lx3 * a3 + lx4 * a4 + alx)
        - (mH + 2.0 * m) * gx
    )
    lam_n = (
        mH * (hy3 * a3 + ahy)
        + m * (ry3 * a3 + ary)
        + m * (ly3 * a3 + ly4 * a4 + aly)
        - (mH + 2.0 * m) * gy
    )
    return a3, a4, lam_t, lam_n


@njit(cache=True, nogil=True)
def _rhs(p: FloatArray, y: FloatArray, dy: FloatArray) -> None:
    a3, a4, _, _ = _dynamics(p, y)
    dy[0] = y[2]
    dy[1] = y[3]
    dy[2] = a3
    dy[3] = a4


@njit(cache=True, nogil=True)
def _dp5(
    p: FloatArray,
    y: FloatArray,
    h: float,
    k: FloatArray,
    tmp: FloatArray,
    ynew: FloatArray,
    full: bool,
) -> float:
    """One DP5 step of size ``h`` from ``y`` with ``k[0] = f(y)``; writes ``ynew``.

    With ``full`` the FSAL stage ``k[6] = f(ynew)`` is evaluated and the error estimate's
    components are left in ``tmp``; returns 0.
    """
    for i in range(4):
        tmp[i] = y[i] + h * _A21 * k[0, i]
    _rhs(p, tmp, k[1])
    for i in range(4):
        tmp[i] = y[i] + h * (_A31 * k[0, i] + _A32 * k[1, i])
    _rhs(p, tmp, k[2])
    for i in range(4):
        tmp[i] = y[i] + h * (_A41 * k[0, i] + _A42 * k[1, i] + _A43 * k[2, i])
    _rhs(p, tmp, k[3])
    for i in range(4):
        tmp[i] = y[i] + h * (
            _A51 * k[0, i] + _A52 * k[1, i] + _A53 * k[2, i] + _A54 * k[3, i]
        )
    _rhs(p, tmp, k[4])
    for i in range(4):
        tmp[i] = y[i] + h * (
            _A61 * k[0, i] + _A62 * k[1, i] + _A63 * k[2, i] + _A64 * k[3, i] + _A65 * k[4, i]
        )
    _rhs(p, tmp, k[5])
    for i in range(4):
        ynew[i] = y[i] + h * (
            _B1 * k[0, i] + _B3 * k[2, i] + _B4 * k[3, i] + _B5 * k[4, i] + _B6 * k[5, i]
        )
    if full:
        _rhs(p, ynew, k[6])
        for i in range(4):
            tmp[i] = h * (
                _E1 * k[0, i]
                + _E3 * k[2, i]
                + _E4 * k[3, i]
                + _E5 * k[4, i]
                + _E6 * k[5, i]
                + _E7 * k[6, i]
            )
    return 0.0


@njit(cache=True, nogil=True)
def _event_value(p: FloatArray, y: FloatArray, kind: int) -> float:
    if kind == _EV_MID or kind == _EV_BACK2:
        return y[0]
    if kind == _EV_BACK1:
        return y[2]
    if kind == _EV_STRIKE:
        return 2.0 * y[0] + y[1]
    if kind == _EV_FWD:
        return y[0] - 0.5 * math.pi
    _, _, _, lam_n = _dynamics(p, y)
    return lam_n


@njit(cache=True, nogil=True)
def _crossed(g0: float, g1: float, direction: int) -> bool:
    """``solve_ivp``'s rule: up ``g0 <= 0 <= g1``, down ``g0 >= 0 >= g1``."""
    if direction > 0:
        return g0 <= 0.0 and g1 >= 0.0
    return g0 >= 0.0 and g1 <= 0.0


@njit(cache=True, nogil=True)
def _error_norm(
    y: FloatArray, ynew: FloatArray, err: FloatArray, rtol: float, atol: float
) -> float:
    acc = 0.0
    for i in range(4):
        sc = atol + rtol * max(abs(y[i]), abs(ynew[i]))
        r = err[i] / sc
        acc += r * r
    return math.sqrt(acc / 4.0)


@njit(cache=True, nogil=True)
def _initial_step(p: FloatArray, y: FloatArray, f0: FloatArray, rtol: float, atol: float) -> float:
    """Hairer's starting step for a 5th-order method (as ``solve_ivp``)."""
    d0 = 0.0
    d1 = 0.0
    for i in range(4):
        sc = atol + abs(y[i]) * rtol
        d0 += (y[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    d0 = math.sqrt(d0 / 4.0)
    d1 = math.sqrt(d1 / 4.0)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    y1 = np.empty(4)
    f1 = np.empty(4)
    for i in range(4):
        y1[i] = y[i] + h0 * f0[i]
    _rhs(p, y1, f1)
    d2 = 0.0
    for i in range(4):
        sc = atol + abs(y[i]) * rtol
        d2 += ((f1[i] - f0[i]) / sc) ** 2
    d2 = math.sqrt(d2 / 4.0) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 5.0)
    return min(100.0 * h0, h1)


@njit(cache=True, nogil=True)
def _integrate_phase(
    p: FloatArray,
    y: FloatArray,
    t: float,
    t_limit: float,
    phase: int,
    h: float,
    rtol: float,
    atol: float,
    k: FloatArray,
) -> tuple[int, float, float]:
    """Integrate one phase from ``(t, y)``; ``y`` is overwritten with the final state.

    Returns ``(event kind or _EV_NONE / _EV_FAIL, final time, step size to continue with)``.
    """
    if phase == 1:
        kinds = (_EV_MID, _EV_BACK1, _EV_NORMAL, -9)
        dirs = (1, -1, -1, 0)
        n_ev = 3
    else:
        kinds = (_EV_STRIKE, _EV_BACK2, _EV_FWD, _EV_NORMAL)
        dirs = (1, -1, 1, -1)
        n_ev = 4
    tmp = np.empty(4)
    ynew = np.empty(4)
    ytry = np.empty(4)
    ktry = np.empty((7, 4))
    g_old = np.empty(4)
    g_new = np.empty(4)
    _rhs(p, y, k[0])
    for j in range(n_ev):
        g_old[j] = _event_value(p, y, kinds[j])
    if not h > 0.0:
        h = _initial_step(p, y, k[0], rtol, atol)
    h_min_rel = 1e-14
    n_steps = 0
    while True:
        if t >= t_limit:
            return _EV_NONE, t, h
        n_steps += 1
        if n_steps > 2_000_000:
            return _EV_FAIL, t, h
        h_min = h_min_rel * max(1.0, abs(t))
        if h < h_min:
            return _EV_FAIL, t, h
        hh = min(h, t_limit - t)
        # --- attempt a step
        while True:
            _dp5(p, y, hh, k, tmp, ynew, True)
            en = _error_norm(y, ynew, tmp, rtol, atol)
            if not math.isfinite(en):
                en = 1e10
            if en <= 1.0:
                fac = 10.0 if en == 0.0 else min(10.0, 0.9 * en ** -0.2)
                break
            hh *= max(0.2, 0.9 * en ** -0.2)
            if hh < h_min:
                return _EV_FAIL, t, hh
        h_next = hh * fac if en <= 1.0 else hh
        # --- events over [t, t + hh]
        best = -1
        best_tau = hh
        for j in range(n_ev):
            g_new[j] = _event_value(p, ynew, kinds[j])
        for j in range(n_ev):
            if not _crossed(g_old[j], g_new[j], dirs[j]):
                continue
            # Illinois on the exact RK step of length tau
            lo, flo = 0.0, g_old[j]
            hi, fhi = hh, g_new[j]
            root = hi
            if flo == 0.0:
                root = 0.0
            elif fhi != 0.0:
                side = 0
                for _ in range(200):
                    c = (lo * fhi - hi * flo) / (fhi - flo)
                    if not (lo < c < hi):
                        c = 0.5 * (lo + hi)
                    for r in range(4):
                        ktry[0, r] = k[0, r]
                    _dp5(p, y, c, ktry, tmp, ytry, False)
                    fc = _event_value(p, ytry, kinds[j])
                    root = c
                    if fc == 0.0:
                        break
                    if (fc > 0.0) == (fhi > 0.0):
                        hi, fhi = c, fc
                        if side == -1:
                            flo *= 0.5
                        side = -1
                    else:
                        lo, flo = c, fc
                        if side == 1:
                            fhi *= 0.5
                        side = 1
                    if hi - lo <= 1e-13 + 4e-16 * abs(t):
                        root = hi if abs(fhi) < abs(flo) else lo
                        break
            if best < 0 or root < best_tau:
                best = j
                best_tau = root
        if best >= 0:
            if best_tau == 0.0:
                pass  # y unchanged
            elif best_tau == hh:
                for r in range(4):
                    y[r] = ynew[r]
            else:
                for r in range(4):
                    ktry[0, r] = k[0, r]
                _dp5(p, y, best_tau, ktry, tmp, ytry, False)
                for r in range(4):
                    y[r] = ytry[r]
            return kinds[best], t + best_tau, h_next
        # --- accept
        t = t + hh
        for r in range(4):
            y[r] = ynew[r]
            k[0, r] = k[6, r]
        for j in range(n_ev):
            g_old[j] = g_new[j]
        h = h_next


@njit(cache=True, nogil=True)
def _impact(p: FloatArray, y: FloatArray, qp: FloatArray) -> tuple[float, float]:
    """Heel strike of the left foot at reduced state ``y``; writes ``q_dot+`` (4,) into ``qp``.

    Returns ``(T, T_c)`` (J).
    """
    mH, m, l, b, R, inertia = p[0], p[1], p[2], p[3], p[4], p[5]
    s = l - R
    q3, q34 = y[0], y[0] + y[1]
    c3, s3 = math.cos(q3), math.sin(q3)
    c34, s34 = math.cos(q34), math.sin(q34)
    # columns 3, 4 of the point Jacobians (columns 1, 2 are the identity)
    hx3, hy3 = -s * c3, -s * s3
    rx3, ry3 = -(s - b) * c3, -(s - b) * s3
    lx3, ly3 = hx3 + b * c34, hy3 + b * s34
    lx4, ly4 = b * c34, b * s34
    mt = mH + 2.0 * m
    M = np.zeros((4, 4))
    M[0, 0] = mt
    M[1, 1] = mt
    M[0, 2] = mH * hx3 + m * (rx3 + lx3)
    M[1, 2] = mH * hy3 + m * (ry3 + ly3)
    M[0, 3] = m * lx4
    M[1, 3] = m * ly4
    M[2, 2] = mH * (hx3 * hx3 + hy3 * hy3) + m * (rx3 * rx3 + ry3 * ry3 + lx3 * lx3 + ly3 * ly3)
    M[2, 3] = m * (lx3 * lx4 + ly3 * ly4)
    M[3, 3] = m * (lx4 * lx4 + ly4 * ly4)
    M[2, 2] += 2.0 * inertia
    M[2, 3] += inertia
    M[3, 3] += inertia
    for i in range(4):
        for j in range(i):
            M[i, j] = M[j, i]
    A = np.zeros((2, 4))
    A[0, 0] = 1.0
    A[1, 1] = 1.0
    A[0, 2] = -s * c3 + s * c34 + R
    A[0, 3] = s * c34 + R
    A[1, 2] = -s * s3 + s * s34
    A[1, 3] = s * s34
    qd = np.empty(4)
    qd[0] = -R * y[2]
    qd[1] = 0.0
    qd[2] = y[2]
    qd[3] = y[3]
    # Cholesky M = L L^T
    L = np.zeros((4, 4))
    for j in range(4):
        d = M[j, j]
        for r in range(j):
            d -= L[j, r] * L[j, r]
        L[j, j] = math.sqrt(d)
        for i in range(j + 1, 4):
            acc = M[i, j]
            for r in range(j):
                acc -= L[i, r] * L[j, r]
            L[i, j] = acc / L[j, j]
    # X = M^-1 A^T (4 x 2)
    X = np.empty((4, 2))
    z = np.empty(4)
    for c in range(2):
        for i in range(4):
            acc = A[c, i]
            for r in range(i):
                acc -= L[i, r] * z[r]
            z[i] = acc / L[i, i]
        for i in range(3, -1, -1):
            acc = z[i]
            for r in range(i + 1, 4):
                acc -= L[r, i] * X[r, c]
            X[i, c] = acc / L[i, i]
    W00 = A[0, 0] * X[0, 0] + A[0, 1] * X[1, 0] + A[0, 2] * X[2, 0] + A[0, 3] * X[3, 0]
    W01 = A[0, 0] * X[0, 1] + A[0, 1] * X[1, 1] + A[0, 2] * X[2, 1] + A[0, 3] * X[3, 1]
    W11 = A[1, 0] * X[0, 1] + A[1, 1] * X[1, 1] + A[1, 2] * X[2, 1] + A[1, 3] * X[3, 1]
    b0 = A[0, 0] * qd[0] + A[0, 1] * qd[1] + A[0, 2] * qd[2] + A[0, 3] * qd[3]
    b1 = A[1, 0] * qd[0] + A[1, 1] * qd[1] + A[1, 2] * qd[2] + A[1, 3] * qd[3]
    det = W00 * W11 - W01 * W01
    mu0 = (W11 * b0 - W01 * b1) / det
    mu1 = (W00 * b1 - W01 * b0) / det
    for i in range(4):
        qp[i] = qd[i] - (X[i, 0] * mu0 + X[i, 1] * mu1)
    T = 0.0
    for i in range(4):
        for j in range(4):
            T += 0.5 * qd[i] * M[i, j] * qd[j]
    Tc = 0.5 * (mu0 * (W00 * mu0 + W01 * mu1) + mu1 * (W01 * mu0 + W11 * mu1))
    return T, Tc


@njit(cache=True, nogil=True)
def _walk_one(
    p: FloatArray,
    y: FloatArray,
    steps: int,
    rtol: float,
    atol: float,
    max_duration: float,
    target: FloatArray,
    stop_tol: float,
    rec_angle: FloatArray,
    rec_time: FloatArray,
    rec_tc: FloatArray,
    rec_length: FloatArray,
    record: bool,
) -> tuple[int, int, float]:
    """Walk one walker from the full reduced state ``y = (q3, q4, q3_dot, q4_dot)``.

    ``y`` is overwritten with the final state (post-swap after a completed step, pre-impact after
    a fall, post-impact without swap if the trailing foot stays). Returns
    ``(status, heel strikes taken, elapsed time)``. With ``stop_tol > 0`` the walk stops early
    (status completed) once the post-impact section state is within ``stop_tol`` of ``target``.
    """
    k = np.empty((7, 4))
    qp = np.empty(4)
    t = 0.0
    h = 0.0
    for n in range(steps):
        t_step = t
        q3_start = y[0]
        _, _, _, lam_n = _dynamics(p, y)
        if lam_n <= 0.0:
            return LOST_CONTACT, n, t
        t_limit = t_step + max_duration
        if y[0] < 0.0:
            ev, t, h = _integrate_phase(p, y, t, t_limit, 1, h, rtol, atol, k)
            if ev != _EV_MID:
                return _phase_status(ev), n, t
        ev, t, h = _integrate_phase(p, y, t, t_limit, 2, h, rtol, atol, k)
        if ev != _EV_STRIKE:
            return _phase_status(ev), n, t
        _, Tc = _impact(p, y, qp)
        if record:
            s = p[2] - p[4]
            rec_angle[n] = y[0]
            rec_time[n] = t - t_step
            rec_tc[n] = Tc
            rec_length[n] = p[4] * (y[0] - q3_start) + s * math.sin(y[0]) - s * math.sin(
                y[0] + y[1]
            )
        if not qp[1] > 1e-12:
            y[2] = qp[2]
            y[3] = qp[3]
            return TRAILING_FOOT_STAYS, n + 1, t
        q3n = y[0] + y[1]
        y[1] = -y[1]
        y[0] = q3n
        y[2] = qp[2] + qp[3]
        y[3] = -qp[3]
        if stop_tol > 0.0:
            d = (y[0] - target[0]) ** 2 + (y[2] - target[1]) ** 2 + (y[3] - target[2]) ** 2
            if math.sqrt(d) < stop_tol:
                return COMPLETED, n + 1, t
    return COMPLETED, steps, t


@njit(cache=True, nogil=True)
def _phase_status(ev: int) -> int:
    if ev == _EV_BACK1 or ev == _EV_BACK2:
        return FELL_BACKWARD
    if ev == _EV_FWD:
        return FELL_FORWARD
    if ev == _EV_NORMAL:
        return LOST_CONTACT
    if ev == _EV_NONE:
        return NO_HEEL_STRIKE
    return INTEGRATION_FAILED


@njit(cache=True, nogil=True)
def _run(
    i: int,
    P: FloatArray,
    Y: FloatArray,
    steps: int,
    rtol: float,
    atol: float,
    max_duration: float,
    target: FloatArray,
    stop_tol: float,
    status: IntArray,
    taken: IntArray,
    elapsed: FloatArray,
    angle: FloatArray,
    time: FloatArray,
    tc: FloatArray,
    length: FloatArray,
    record: bool,
) -> None:
    r = i if record else 0
    st, n, t = _walk_one(
        P[i], Y[i], steps, rtol, atol, max_duration, target, stop_tol,
        angle[r], time[r], tc[r], length[r], record,
    )
    status[i] = st
    taken[i] = n
    elapsed[i] = t


@njit(cache=True, nogil=True, parallel=True)
def _ensemble_parallel(
    P: FloatArray,
    Y: FloatArray,
    order: IntArray,
    steps: int,
    rtol: float,
    atol: float,
    max_duration: float,
    target: FloatArray,
    stop_tol: float,
    status: IntArray,
    taken: IntArray,
    elapsed: FloatArray,
    angle: FloatArray,
    time: FloatArray,
    tc: FloatArray,
    length: FloatArray,
    record: bool,
) -> None:
    for j in prange(order.shape[0]):
        _run(order[j], P, Y, steps, rtol, atol, max_duration, target, stop_tol,
             status, taken, elapsed, angle, time, tc, length, record)


@njit(cache=True, nogil=True)
def _ensemble_serial(
    P: FloatArray,
    Y: FloatArray,
    order: IntArray,
    steps: int,
    rtol: float,
    atol: float,
    max_duration: float,
    target: FloatArray,
    stop_tol: float,
    status: IntArray,
    taken: IntArray,
    elapsed: FloatArray,
    angle: FloatArray,
    time: FloatArray,
    tc: FloatArray,
    length: FloatArray,
    record: bool,
) -> None:
    for j in range(order.shape[0]):
        _run(order[j], P, Y, steps, rtol, atol, max_duration, target, stop_tol,
             status, taken, elapsed, angle, time, tc, length, record)


@njit(cache=True, nogil=True)
def _integrate_plain(
    p: FloatArray, y: FloatArray, t_end: float, rtol: float, atol: float, out: FloatArray
) -> int:
    """Integrate single support without events to ``t_end``, storing ``y`` at every step in
    ``out`` (rows); returns the number of rows written."""
    k = np.empty((7, 4))
    tmp = np.empty(4)
    ynew = np.empty(4)
    _rhs(p, y, k[0])
    h = _initial_step(p, y, k[0], rtol, atol)
    t = 0.0
    n = 0
    while t < t_end and n < out.shape[0]:
        hh = min(h, t_end - t)
        _dp5(p, y, hh, k, tmp, ynew, True)
        en = _error_norm(y, ynew, tmp, rtol, atol)
        if en <= 1.0:
            t += hh
            for r in range(4):
                y[r] = ynew[r]
                k[0, r] = k[6, r]
                out[n, r] = y[r]
            n += 1
            h = hh * (10.0 if en == 0.0 else min(10.0, 0.9 * en ** -0.2))
        else:
            h = hh * max(0.2, 0.9 * en ** -0.2)
    return n


# ---------------------------------------------------------------------------------------------
# Python API
# ---------------------------------------------------------------------------------------------
def walker_parameters(walker: CompassGait, slope: ArrayLike = 0.0) -> FloatArray:
    """Parameter rows ``(mH, m, l, b, R, I, g, slope)`` broadcast over array-valued fields.

    Parameters
    ----------
    walker : CompassGait
        The walker; any field may be an array (e.g. a grid of foot radii).
    slope : array_like
        Slope (rad), broadcast with the walker's fields.

    Returns
    -------
    ndarray, shape (..., 8)
        SI units (kg, kg, m, m, m, kg m^2, m/s^2, rad).
    """
    if not isinstance(walker, CompassGait):
        raise TypeError("the compiled path supports the CompassGait walker only")
    vals = [np.asarray(getattr(walker, n), dtype=float) for n in PARAMETER_NAMES[:-1]]
    vals.append(np.asarray(slope, dtype=float))
    b = np.broadcast_arrays(*vals)
    return np.ascontiguousarray(np.stack(b, axis=-1))


def _use_parallel(parallel: bool | None) -> bool:
    if parallel is None:
        return threading.current_thread() is threading.main_thread()
    return bool(parallel)


@dataclass(frozen=True, kw_only=True)
class EnsembleResult:
    """Outcome of :func:`ensemble_walk` for ``N`` walkers and up to ``S`` steps.

    Attributes
    ----------
    z : ndarray, shape (N, 3)
        Final section coordinates ``(q3, q3_dot, q4_dot)`` (rad, rad/s): just after the last heel
        strike for a completed walk; for a failed walk the state where it failed (``q3``,
        ``q3_dot``, ``q4_dot`` of the reduced state, pre-swap).
    state : ndarray, shape (N, 4)
        Final reduced state ``(q3, q4, q3_dot, q4_dot)`` (rad, rad/s).
    status : ndarray of int, shape (N,)
        Status codes, names in :data:`STATUS_NAMES` (``WalkStatus`` values).
    steps : ndarray of int, shape (N,)
        Heel strikes taken (``WalkResult.n_steps``): with status ``trailing_foot_stays`` the
        last one is counted although the legs were not swapped.
    time : ndarray, shape (N,)
        Simulated time at the end (s).
    impact_angle, step_time, collision_loss, step_length : ndarray, shape (N, S) or None
        Per step: ``q3`` at heel strike (rad), step duration (s), ``T_c`` (J) and step length
        along the ground (m); NaN after the walk ended. None unless recorded. A step whose
        impact left the trailing foot on the ground is recorded too (as in ``simulate``).
    """

    z: FloatArray
    state: FloatArray
    status: IntArray
    steps: IntArray
    time: FloatArray
    impact_angle: FloatArray | None
    step_time: FloatArray | None
    collision_loss: FloatArray | None
    step_length: FloatArray | None

    @property
    def status_names(self) -> NDArray[np.str_]:
        """Status of every walker as a ``WalkStatus`` value string, shape (N,)."""
        return np.asarray(STATUS_NAMES)[self.status]

    @property
    def ok(self) -> NDArray[np.bool_]:
        """Walkers that completed every requested step, shape (N,)."""
        return np.asarray(self.status == COMPLETED)


def ensemble_walk(
    walker: CompassGait,
    z0: ArrayLike,
    slope: ArrayLike = 0.0,
    *,
    steps: int = 1,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step_duration: float = 5.0,
    record: bool = True,
    stop_near: tuple[ArrayLike, float] | None = None,
    parallel: bool | None = None,
    initial_state: ArrayLike | None = None,
) -> EnsembleResult:
    """Walk a whole ensemble of passive compass gaits for ``steps`` steps in one compiled call.

    Walker ``i`` has the parameters of row ``i`` of ``walker_parameters(walker, slope)``
    broadcast with the initial states, so ``walker`` fields and ``slope`` may be arrays of
    length ``N`` (or scalars).

    Parameters
    ----------
    walker : CompassGait
        Walker(s); fields broadcast with ``slope`` and ``z0``'s leading axis.
    z0 : array_like, shape (N, 3) or (3,)
        Post-impact section coordinates ``(q3, q3_dot, q4_dot)`` (rad, rad/s), ``q4 = -2 q3``.
    slope : array_like, shape (N,) or ()
        Slope (rad).
    steps : int
        Number of heel strikes to take.
    rtol, atol : float
        Integrator tolerances (DP5, scipy's error norm).
    max_step_duration : float
        Time bound of one step (s); exceeding it is ``no_heel_strike``.
    record : bool
        Record the per-step impact angles, durations, ``T_c`` and step lengths.
    stop_near : (array_like of shape (3,), float), optional
        ``(z_target, tol)``: stop a walker (status completed) as soon as its post-impact state is
        within ``tol`` of ``z_target`` (Euclidean norm in section coordinates).
    parallel : bool, optional
        Run walkers on all cores with ``numba.prange``; default: parallel on the main thread,
        serial on other threads (e.g. Dask workers).
    initial_state : array_like, shape (N, 4), optional
        Full reduced states ``(q3, q4, q3_dot, q4_dot)`` to start from instead of ``z0`` (which is
        then ignored); e.g. to continue a walk.

    Returns
    -------
    EnsembleResult
    """
    if steps < 1:
        raise ValueError("steps must be >= 1")
    if initial_state is not None:
        Y0 = np.atleast_2d(np.asarray(initial_state, dtype=float))
        if Y0.shape[-1] != 4:
            raise ValueError(f"initial_state must have shape (N, 4), got {Y0.shape}")
    else:
        z = np.atleast_2d(np.asarray(z0, dtype=float))
        if z.shape[-1] != 3 or z.ndim != 2:
            raise ValueError(f"z0 must have shape (N, 3) or (3,), got {np.shape(z0)}")
        Y0 = np.stack((z[:, 0], -2.0 * z[:, 0], z[:, 1], z[:, 2]), axis=-1)
    P = walker_parameters(walker, slope)
    if P.ndim > 2:
        raise ValueError("walker parameters and slope must be scalars or 1-D arrays")
    n = max(Y0.shape[0], P.shape[0] if P.ndim == 2 else 1)
    P = np.ascontiguousarray(np.broadcast_to(P, (n, 8)))
    Y = np.ascontiguousarray(np.broadcast_to(Y0, (n, 4))).copy()
    if not (np.all(np.isfinite(P)) and np.all(np.isfinite(Y))):
        raise ValueError("initial states and parameters must be finite")
    target = np.zeros(3)
    stop_tol = 0.0
    if stop_near is not None:
        target = np.asarray(stop_near[0], dtype=float).reshape(3).copy()
        stop_tol = float(stop_near[1])
    status = np.zeros(n, dtype=np.int64)
    taken = np.zeros(n, dtype=np.int64)
    elapsed = np.zeros(n)
    shape = (n, steps) if record else (1, steps)
    angle = np.full(shape, np.nan)
    time = np.full(shape, np.nan)
    tc = np.full(shape, np.nan)
    length = np.full(shape, np.nan)
    args: tuple[Any, ...] = (
        steps, float(rtol), float(atol), float(max_step_duration), target, stop_tol,
        status, taken, elapsed, angle, time, tc, length, bool(record),
    )
    if _use_parallel(parallel) and n > 1:
        # a fixed shuffle balances the static prange split (falls are much cheaper than walks)
        order = np.random.default_rng(0).permutation(n).astype(np.int64)
        _ensemble_parallel(P, Y, order, *args)
    else:
        _ensemble_serial(P, Y, np.arange(n, dtype=np.int64), *args)
    zf = np.stack((Y[:, 0], Y[:, 2], Y[:, 3]), axis=-1)
    return EnsembleResult(
        z=zf,
        state=Y,
        status=status,
        steps=taken,
        time=elapsed,
        impact_angle=angle if record else None,
        step_time=time if record else None,
        collision_loss=tc if record else None,
        step_length=length if record else None,
    )


class CompiledStep(NamedTuple):
    """One step of the compiled Poincare map (:func:`step_map_compiled`).

    Attributes
    ----------
    z : ndarray, shape (3,)
        Post-impact section coordinates after the leg swap (rad, rad/s); NaN if the step failed.
    step_time : float
        Duration of the step (s); NaN if it failed.
    impact_angle : float
        ``q3`` at heel strike (rad).
    collision_loss : float
        ``T_c`` at heel strike (J).
    step_length : float
        Distance along the ground between the stance and the striking contact points (m).
    status : WalkStatus
        How the step ended.
    """

    z: FloatArray
    step_time: float
    impact_angle: float
    collision_loss: float
    step_length: float
    status: WalkStatus


def step_map_compiled(
    walker: CompassGait,
    z: ArrayLike,
    slope: float,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step_duration: float = 5.0,
) -> CompiledStep:
    """The compiled step-to-step (Poincare) map of the passive walker.

    Parameters
    ----------
    walker : CompassGait
        Scalar-parameter walker.
    z : array_like, shape (3,)
        Post-impact section coordinates ``(q3, q3_dot, q4_dot)`` (rad, rad/s).
    slope : float
        Slope (rad).
    rtol, atol : float
        Integrator tolerances.
    max_step_duration : float
        Time bound of the step (s).

    Returns
    -------
    CompiledStep
    """
    res = ensemble_walk(
        walker, np.asarray(z, dtype=float).reshape(1, 3), slope, steps=1, rtol=rtol,
        atol=atol, max_step_duration=max_step_duration, parallel=False,
    )
    assert res.impact_angle is not None and res.step_time is not None
    assert res.collision_loss is not None and res.step_length is not None
    status = WalkStatus.from_code(int(res.status[0]))
    ok = status is WalkStatus.COMPLETED
    return CompiledStep(
        z=res.z[0] if ok else np.full(3, np.nan),
        step_time=float(res.step_time[0, 0]) if ok else math.nan,
        impact_angle=float(res.impact_angle[0, 0]),
        collision_loss=float(res.collision_loss[0, 0]),
        step_length=float(res.step_length[0, 0]),
        status=status,
    )


def reduced_dynamics_compiled(
    walker: CompassGait, state: ArrayLike, slope: float = 0.0
) -> tuple[FloatArray, FloatArray]:
    """Compiled single-support accelerations and ground reaction at reduced states.

    Parameters
    ----------
    walker : CompassGait
        Scalar-parameter walker.
    state : array_like, shape (N, 4)
        ``(q3, q4, q3_dot, q4_dot)`` (rad, rad/s).
    slope : float
        Slope (rad).

    Returns
    -------
    accelerations : ndarray, shape (N, 2)
        ``(q3_ddot, q4_ddot)`` (rad/s^2).
    reaction : ndarray, shape (N, 2)
        Ground force on the stance foot, (tangential, normal) (N).
    """
    p = walker_parameters(walker, slope)
    Y = np.atleast_2d(np.asarray(state, dtype=float))
    acc = np.empty((Y.shape[0], 2))
    lam = np.empty((Y.shape[0], 2))
    for i, y in enumerate(Y):
        a3, a4, lt, ln = _dynamics(p, np.ascontiguousarray(y))
        acc[i] = a3, a4
        lam[i] = lt, ln
    return acc, lam


def single_support_compiled(
    walker: CompassGait,
    state: ArrayLike,
    slope: float,
    duration: float,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_samples: int = 100_000,
) -> FloatArray:
    """Integrate single support (no events) with the compiled DP5 and return every step.

    Parameters
    ----------
    walker : CompassGait
        Scalar-parameter walker.
    state : array_like, shape (4,)
        Initial ``(q3, q4, q3_dot, q4_dot)`` (rad, rad/s).
    slope : float
        Slope (rad).
    duration : float
        Time to integrate (s).
    rtol, atol : float
        Tolerances.
    max_samples : int
        Largest number of integrator steps stored.

    Returns
    -------
    ndarray, shape (K, 4)
        The state after every accepted step (the last at ``duration`` unless truncated).
    """
    p = walker_parameters(walker, slope)
    y = np.asarray(state, dtype=float).reshape(4).copy()
    out = np.empty((max_samples, 4))
    n = _integrate_plain(p, y, float(duration), float(rtol), float(atol), out)
    return out[:n].copy()
