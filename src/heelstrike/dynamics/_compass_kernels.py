"""The numba functions of the compass-gait kernel (the model: :mod:`heelstrike.dynamics.compiled`).

One source, compiled two ways: by numba's JIT (``cache=True``; the ``prange``-parallel ensemble
and, without the ahead-of-time tier, everything) and ahead of time into an extension module
that later processes load without numba (:mod:`heelstrike.dynamics._aot`; the serial entry
points :data:`SERIAL`, with the signatures of :data:`heelstrike.dynamics.compiled.AOT_EXPORTS`).
The Python API, the parameter layout and the status and event codes are in
:mod:`heelstrike.dynamics.compiled`, which imports this module only when it needs numba.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit, prange

from heelstrike._caching import tolerate_numba_cache_errors
from heelstrike._typing import FloatArray, IntArray
from heelstrike.core.fast import serial_and_parallel
from heelstrike.dynamics import _dp5 as dp5
from heelstrike.dynamics._aot import track_numba_compiles
from heelstrike.dynamics.compiled import (
    _EV_BACK1,
    _EV_BACK2,
    _EV_FAIL,
    _EV_FWD,
    _EV_MID,
    _EV_NONE,
    _EV_NORMAL,
    _EV_STRIKE,
    COMPLETED,
    FELL_BACKWARD,
    FELL_FORWARD,
    INTEGRATION_FAILED,
    LOST_CONTACT,
    NO_HEEL_STRIKE,
    TRAILING_FOOT_STAYS,
)
from heelstrike.models import _contact
from heelstrike.models.compass_fast import strike

tolerate_numba_cache_errors()  # numba's cache unwritable (full disk): run uncached

track_numba_compiles()  # a search's time limit does not count compiling (see _aot)

# The one lift rule (heelstrike.models._contact), compiled for the kernels of both modules.
lifts_jit: Any = njit(cache=True, nogil=True, inline="always")(_contact.lifts)
lift_velocity_scale_jit: Any = njit(cache=True, nogil=True, inline="always")(
    _contact.lift_velocity_scale
)
_lifts, _lift_scale = lifts_jit, lift_velocity_scale_jit
# The one definition of step length (heelstrike.models._contact), compiled.
_step_length: Any = njit(cache=True, nogil=True, inline="always")(_contact.step_length)

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


#: The DP5 drivers (:func:`heelstrike.dynamics._dp5.integrator`) of ``_rhs``; ``ctx`` is ``p``.
_ode = dp5.integrator(_rhs, _event_value)


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
        if kinds[j] == _EV_NORMAL and g_old[j] <= 0.0:
            return _EV_NORMAL, t, h  # contact already lost: no sign change to detect
    if not h > 0.0:
        h = _ode.start_step(p, y, k, ktry, tmp, rtol, atol, math.inf)
    n_steps = 0
    while True:
        if t >= t_limit:
            return _EV_NONE, t, h
        n_steps += 1
        if n_steps > 2_000_000:
            return _EV_FAIL, t, h
        h_min = dp5.min_step(t)
        if h < h_min:
            return _EV_FAIL, t, h
        hh = min(h, t_limit - t)
        # --- attempt a step
        while True:
            _ode.step(p, y, hh, k, tmp, ynew, True)
            en = dp5.error_norm(y, ynew, tmp, rtol, atol)
            if en <= 1.0:
                break
            hh *= dp5.shrink_factor(en)
            if hh < h_min:
                return _EV_FAIL, t, hh
        h_next = hh * dp5.grow_factor(en)
        # --- events over [t, t + hh]
        for j in range(n_ev):
            g_new[j] = _event_value(p, ynew, kinds[j])
        if dp5.any_crossed(g_old, g_new, dirs, n_ev):
            best, tau = _ode.first_event(p, y, hh, t, k, ktry, tmp, ynew, ytry, kinds, dirs,
                                         n_ev, g_old, g_new)
            return kinds[best], t + tau, h_next
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

    The impact is :func:`heelstrike.models.compass_fast.strike` (the one compass impact kernel)
    at the located heel strike ``q4 = -2 q3``, with the stance foot rolling
    (``q1_dot = -R q3_dot``, ``q2_dot = 0``). Returns ``(T, T_c)`` (J); NaNs for a degenerate
    walker.
    """
    _, T, Tc, _, qp[0], qp[1], qp[2], qp[3], _, _ = strike(
        y[0], p[4], -p[4] * y[2], 0.0, y[2], y[3], p[0], p[1], p[2], p[3], p[5], 0.0)
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
            # contact points along the ground relative to the step's first stance contact:
            # the stance foot rolled by -R (q3 - q3_start), the striking foot is at
            # x_stance - s sin q3 + s sin(q3 + q4) (CompassGait.positions)
            x_stance = -p[4] * (y[0] - q3_start)
            rec_length[n] = _step_length(
                0.0, x_stance - s * math.sin(y[0]) + s * math.sin(y[0] + y[1])
            )
        if not _lifts(qp[1], _lift_scale(p[2], y[2:4])):
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


def _ensemble(
    P: FloatArray, Y: FloatArray, order: IntArray, steps: int, rtol: float, atol: float,
    max_duration: float, target: FloatArray, stop_tol: float, status: IntArray,
    taken: IntArray, elapsed: FloatArray, angle: FloatArray, time: FloatArray, tc: FloatArray,
    length: FloatArray, record: bool,
) -> None:
    """Walk walkers ``order[j]`` (rows of ``P``, ``Y``) with :func:`_walk_one`; ``prange``."""
    for j in prange(order.shape[0]):
        i = order[j]
        r = i if record else 0
        st, n, t = _walk_one(
            P[i], Y[i], steps, rtol, atol, max_duration, target, stop_tol,
            angle[r], time[r], tc[r], length[r], record,
        )
        status[i] = st
        taken[i] = n
        elapsed[i] = t


_ensemble_serial, _ensemble_parallel = serial_and_parallel(_ensemble, nogil=True)


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
    h = _ode.start_step(p, y, k, np.empty((1, 4)), tmp, rtol, atol, math.inf)
    t = 0.0
    n = 0
    while t < t_end and n < out.shape[0]:
        hh = min(h, t_end - t)
        _ode.step(p, y, hh, k, tmp, ynew, True)
        en = dp5.error_norm(y, ynew, tmp, rtol, atol)
        if en <= 1.0:
            t += hh
            for r in range(4):
                y[r] = ynew[r]
                k[0, r] = k[6, r]
                out[n, r] = y[r]
            n += 1
            h = hh * dp5.grow_factor(en)
        else:
            h = hh * dp5.shrink_factor(en)
    return n


#: The serial entry points by name (numba dispatchers): what the ahead-of-time module exports
#: (:data:`heelstrike.dynamics.compiled.AOT_EXPORTS`) and what is called when it is off.
SERIAL: dict[str, Any] = {
    "ensemble": _ensemble_serial,
    "integrate_phase": _integrate_phase,
    "impact": _impact,
    "phase_status": _phase_status,
    "integrate_plain": _integrate_plain,
    "dynamics": _dynamics,
}
