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
- **Integrator.** Dormand-Prince 5(4) of :mod:`heelstrike.dynamics._dp5` (shared with the
  described walkers' kernel) with scipy's error norm (RMS of
  ``err / (atol + rtol max(|y|, |y_new|))``) and step-size control.
- **Events.** The two phases of a step and their terminal events are those of ``simulate``
  (mid-stance, falls, lost contact, heel strike ``2 q3 + q4`` rising through 0), detected by a
  sign change over an accepted step with the same direction rules as ``solve_ivp`` (a phase
  that starts with a normal force ``<= 0`` ends at once with lost contact). The event
  time is located by the Illinois method on the *exact* Runge-Kutta step of length ``tau`` from
  the step's start (each trial is a fresh DP5 step), to ``|d tau| < 1e-13 s``; the earliest
  event of a step ends the phase.
- **Impact and swap.** ``q_dot+ = P_a q_dot-`` with the full 4x4 ``M`` and the left foot's
  Jacobian ``A_L`` (Cholesky solves), ``T_c = 1/2 mu^T (A M^-1 A^T) mu``; the trailing foot must
  lift (``q2_dot+ > LIFT_TOLERANCE l (|q3_dot-| + |q4_dot-|)``, the rule of
  :mod:`heelstrike.models._contact` compiled); then ``q3 <- q3 + q4``, ``q4 <- -q4`` and the
  velocities alike.

Status codes are :attr:`WalkStatus.code <heelstrike.dynamics.hybrid.WalkStatus>` (module-level
constants below, compile-time constants for numba; :meth:`WalkStatus.from_code` converts back).
``tests/test_compiled.py`` checks everything against ``simulate``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray, IntArray
from heelstrike.core.fast import serial_and_parallel, use_parallel
from heelstrike.dynamics import _dp5 as dp5
from heelstrike.dynamics.hybrid import ImpactRecord, WalkResult, WalkStatus
from heelstrike.models import _contact
from heelstrike.models.base import PlanarWalker
from heelstrike.models.compass import CompassGait
from heelstrike.models.compass_fast import strike

__all__ = [
    "STATUS_NAMES",
    "CompiledStep",
    "EnsembleResult",
    "check_compiled_compass",
    "ensemble_walk",
    "reduced_dynamics_compiled",
    "simulate_compiled",
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

# The one lift rule (heelstrike.models._contact), compiled for the kernels of both modules.
lifts_jit: Any = njit(cache=True, nogil=True, inline="always")(_contact.lifts)
lift_velocity_scale_jit: Any = njit(cache=True, nogil=True, inline="always")(
    _contact.lift_velocity_scale
)
_lifts, _lift_scale = lifts_jit, lift_velocity_scale_jit
# The one definition of step length (heelstrike.models._contact), compiled.
_step_length: Any = njit(cache=True, nogil=True, inline="always")(_contact.step_length)

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


# ---------------------------------------------------------------------------------------------
# Python API
# ---------------------------------------------------------------------------------------------
def walker_parameters(walker: PlanarWalker, slope: ArrayLike = 0.0) -> FloatArray:
    """Parameter rows ``(mH, m, l, b, R, I, g, slope)`` broadcast over array-valued fields.

    Parameters
    ----------
    walker : PlanarWalker
        A walker simulated by this module's kernel (``walker.compiled_kernel == "compass"``:
        the :class:`~heelstrike.models.CompassGait`); any parameter may be an array (e.g. a
        grid of foot radii).
    slope : array_like
        Slope (rad), broadcast with the walker's parameters.

    Returns
    -------
    ndarray, shape (..., 8)
        SI units (kg, kg, m, m, m, kg m^2, m/s^2, rad).

    Raises
    ------
    TypeError
        If ``walker`` is not a walker or its compiled kernel is not the compass-gait one.
    """
    if not isinstance(walker, PlanarWalker) or walker.compiled_kernel != "compass":
        raise TypeError("the compiled path supports the CompassGait walker only")
    params = walker.parameters
    vals = [np.asarray(params[n], dtype=float) for n in PARAMETER_NAMES[:-1]]
    vals.append(np.asarray(slope, dtype=float))
    b = np.broadcast_arrays(*vals)
    return np.ascontiguousarray(np.stack(b, axis=-1))


class EnsembleStatus:
    """What the ensemble results of both compiled kernels offer on their ``status`` codes."""

    status: IntArray

    @property
    def status_names(self) -> NDArray[np.str_]:
        """Status of every walker as a ``WalkStatus`` value string, shape (N,)."""
        return np.asarray(STATUS_NAMES)[self.status]

    @property
    def ok(self) -> NDArray[np.bool_]:
        """Walkers that completed every requested step (or stopped on arrival), shape (N,)."""
        return np.asarray(self.status == COMPLETED)


@dataclass(frozen=True, kw_only=True)
class EnsembleResult(EnsembleStatus, ResultDictMixin):
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
    P = np.array(np.broadcast_to(P, (n, 8)))  # a writable copy: one numba specialisation
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
    if use_parallel(parallel) and n > 1:
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


def check_compiled_compass(
    torque: Any = None, push_off: Any = None, friction: float | None = None,
    restitution: float = 0.0,
) -> None:
    """Raise ``ValueError`` unless the compass kernel supports this actuation and contact.

    The kernel walks the *passive* compass gait with an inert heel strike: no torque law, no
    push-off, no friction limit (``slipped``) and ``restitution = 0``.
    """
    unsupported = [
        name
        for name, given in (
            ("torque", torque is not None),
            ("push_off", push_off is not None),
            ("friction", friction is not None),
            ("restitution", float(restitution) != 0.0),
        )
        if given
    ]
    if unsupported:
        raise ValueError(
            "the compiled compass-gait kernel walks the passive walker with an inert impact "
            f"only ({', '.join(unsupported)} given); use backend='scipy'"
        )


def simulate_compiled(
    walker: PlanarWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    slope: float = 0.0,
    steps: int = 1,
    torque: None = None,
    push_off: None = None,
    friction: None = None,
    restitution: float = 0.0,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
) -> WalkResult:
    """Compiled :func:`~heelstrike.dynamics.hybrid.simulate` of one passive compass gait.

    The steps are this module's kernel, phase by phase (the integrator, events, impact and
    swap of :func:`ensemble_walk`, so impacts equal :func:`step_map_compiled`'s); the impact
    records are completed from the walker contract (impulse, trailing-foot velocity, energies,
    :meth:`~heelstrike.models.base.PlanarWalker.step_length`).

    Parameters
    ----------
    walker : PlanarWalker
        A scalar-parameter walker with ``compiled_kernel == "compass"``.
    q0, q_dot0 : array_like, shape (4,)
        Initial state, stance foot on the ground (``q2 = R``) and rolling.
    slope : float
        Ground slope (rad).
    steps : int
        Number of heel strikes to simulate.
    torque, push_off, friction : None
        Not supported (passive walking only; :func:`check_compiled_compass`).
    restitution : float
        Must be 0 (the inert impact).
    max_step_duration : float
        Time bound of one step (s).
    rtol, atol : float
        Integrator (DP5) tolerances.
    max_step : float
        Must be ``inf``: the kernel's steps are set by the tolerances alone (a cap on the step
        asks for dense samples: use the scipy backend).

    Returns
    -------
    WalkResult
        Samples are the phase boundaries only: the start of every step, mid-stance and the
        state just before heel strike (use the scipy backend for dense trajectories).

    Raises
    ------
    ValueError
        On an invalid initial state, batched parameters or unsupported actuation.
    """
    check_compiled_compass(torque, push_off, friction, restitution)
    if steps < 1:
        raise ValueError("steps must be >= 1")
    if np.isfinite(max_step):
        raise ValueError("the compiled compass kernel takes no max_step (it records the phase "
                         "boundaries only); use backend='scipy' for dense samples")
    p = walker_parameters(walker, slope)
    if p.shape != (8,):
        raise ValueError("the compiled compass kernel walks one walker (scalar parameters)")
    q = np.array(q0, dtype=float)
    qd = np.array(q_dot0, dtype=float)
    if q.shape != (4,) or qd.shape != (4,):
        raise ValueError("q0 and q_dot0 must have shape (4,)")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        raise ValueError("initial state must be finite")
    R = float(p[4])
    if abs(q[1] - R) > 1e-9 or np.max(np.abs(walker.contact_jacobian(q, "right") @ qd)) > 1e-9:
        raise ValueError(
            "initial state must have the stance foot on the ground (q2 = R) and rolling "
            "without slip (q1_dot = -R q3_dot, q2_dot = 0)"
        )
    leg_length = float(walker.scale.leg_length)
    k = np.empty((7, 4))
    qp = np.empty(4)
    y = np.array([q[2], q[3], qd[2], qd[3]])
    t, h = 0.0, 0.0
    ts: list[float] = []
    qs: list[FloatArray] = []
    qds: list[FloatArray] = []
    legs: list[int] = []
    step_ids: list[int] = []
    impacts: list[ImpactRecord] = []
    stance = 0
    status = WalkStatus.COMPLETED

    def full(x_start: float, q3_start: float) -> tuple[FloatArray, FloatArray]:
        """Floating-base state of the reduced ``y`` (stance foot rolled from the start)."""
        qq = np.array([x_start - R * (y[0] - q3_start), R, y[0], y[1]])
        return qq, np.array([-R * y[2], 0.0, y[2], y[3]])

    def sample(tt: float, qq: FloatArray, vv: FloatArray, step: int) -> None:
        ts.append(tt)
        qs.append(qq)
        qds.append(vv)
        legs.append(stance)
        step_ids.append(step)

    for n in range(steps):
        t_step, q_start, q3_start = t, q.copy(), float(y[0])
        sample(t, q, qd, n)
        t_limit = t_step + max_step_duration
        ev = _EV_MID
        if y[0] < 0.0:
            ev, t, h = _integrate_phase(p, y, t, t_limit, 1, h, rtol, atol, k)
            q, qd = full(q_start[0], q3_start)
            sample(t, q, qd, n)
        if ev == _EV_MID:
            ev, t, h = _integrate_phase(p, y, t, t_limit, 2, h, rtol, atol, k)
            q, qd = full(q_start[0], q3_start)
            sample(t, q, qd, n)
        if ev != _EV_STRIKE:
            status = WalkStatus.from_code(_phase_status(ev))
            break
        T, Tc = _impact(p, y, qp)
        qd_plus = qp.copy()
        M = walker.mass_matrix(q)
        A_L = walker.contact_jacobian(q, "left")
        impulse = np.linalg.solve(A_L @ A_L.T, A_L @ (M @ (qd_plus - qd)))
        v_trailing = float((walker.contact_jacobian(q, "right") @ qd_plus)[1])
        impacts.append(
            ImpactRecord(
                step=n, time=t, q=q.copy(), q_dot_minus=qd.copy(), q_dot_plus=qd_plus.copy(),
                impact_angle=float(q[2]), kinetic_energy=float(T),
                kinetic_energy_constrained=float(Tc), kinetic_energy_admissible=float(T - Tc),
                energy_lost=float(Tc), impulse=impulse,
                step_length=float(walker.step_length(q_start, q)),
                trailing_normal_velocity=v_trailing,
                potential_energy_released=float(walker.potential_energy(q_start, slope))
                - float(walker.potential_energy(q, slope)),
                actuator_work=0.0, push_off_work=0.0, step_duration=t - t_step,
            )
        )
        if not _contact.lifts(v_trailing, _contact.lift_velocity_scale(leg_length, qd[2:])):
            status = WalkStatus.TRAILING_FOOT_STAYS
            qd = qd_plus
            break
        q, qd = (np.asarray(a, dtype=float) for a in walker.swap_legs(q, qd_plus))
        y[:] = q[2], q[3], qd[2], qd[3]
        stance = 1 - stance
    return WalkResult(
        status=status,
        message=status.message,
        t=np.asarray(ts),
        q=np.asarray(qs),
        q_dot=np.asarray(qds),
        stance_leg=np.asarray(legs, dtype=np.int_),
        step=np.asarray(step_ids, dtype=np.int_),
        actuator_work=np.zeros(len(ts)),
        impacts=tuple(impacts),
        final_q=np.asarray(q),
        final_q_dot=np.asarray(qd),
        slope=float(slope),
    )
