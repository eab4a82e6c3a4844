"""Compiled (numba) phased simulation of any described walker: the ``"compiled"`` backend.

The same hybrid model as :func:`heelstrike.dynamics.phased.simulate_phased`, step for step:

- *knee swing* (walkers with lockable joints): stance knee locked, swing knee free; first until
  the swing knee has flexed past ``knee_flex_threshold``, then until it straightens to its lock
  angle (**knee strike**: an inert impact with ``A = [A_R; lock rows]``);
- *locked swing*: all lockable joints locked; first until the heel strike is *armed* (stance
  angle > 0, swing foot ahead and above the ground), then until the swing foot's clearance
  falls through zero;
- **heel strike**: bilateral rows ``[A_L; lock rows]``, the trailing foot a unilateral
  candidate whose mode (separate, stick, slip fallback) is decided by enumerating the active
  sets in the order of :func:`heelstrike.core.complementarity.resolve_impact`; the walk ends
  with ``trailing_foot_stays`` unless it separates with ``v_n > LIFT_TOLERANCE l sum |q_dot-|``
  (the rule of :mod:`heelstrike.models._contact`, compiled); then the legs are
  relabelled (``swap``) and the locks reset exactly.

Each continuous stretch uses the terminal events of ``simulate_phased`` (``lost_contact``,
``fell_forward``, ``fell_backward`` and, with a friction coefficient, ``slipped``) with
``solve_ivp``'s crossing rules; a stretch that starts with the contact already lost (normal
force or friction margin ``<= 0``) ends at once with that status. The right-hand side is the
reduced single-support dynamics ``J^T M J theta_dd = J^T (B u - h)`` with ``M``, ``h``, the
contact Jacobians and the swap generated from the walker's sympy expressions
(:mod:`heelstrike.models._codegen_numba`). The integrator is the Dormand-Prince 5(4) scheme of
:mod:`heelstrike.dynamics._dp5`, shared with :mod:`heelstrike.dynamics.compiled` (scipy's error
norm and step control; an event's time is located by the Illinois method on the exact
Runge-Kutta step, to ``1e-13 s``), for any number of free coordinates.

Actuation: passive or :class:`~heelstrike.dynamics.phased.TorsoPD` torques and the
:class:`~heelstrike.dynamics.actuation.PushOff` impulse (all evaluated in the kernel); other
torque laws and push-off models need the ``"scipy"`` backend.

The kernel takes the generated functions as first-class function arguments, so it is compiled
(and disk-cached by numba) once for every walker; samples are the states after every accepted
integrator step (not scipy's), impacts and statuses are the same as the scipy reference's
(``tests/test_backend_conformance.py``).
"""

from __future__ import annotations

import itertools
import math
import os
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit
from numba import types as nbt
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray, IntArray
from heelstrike.core.fast import use_parallel
from heelstrike.core.impact import ImpactInputError
from heelstrike.dynamics import _dp5 as dp5
from heelstrike.dynamics._compass_kernels import lift_velocity_scale_jit, lifts_jit
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.compiled import STATUS_NAMES, EnsembleStatus
from heelstrike.dynamics.hybrid import ImpactRecord, WalkStatus
from heelstrike.dynamics.phased import (
    ImpactKind,
    PhasedImpact,
    PhasedWalker,
    PhasedWalkResult,
    TorsoPD,
    check_initial_state,
    stance_and_swing_locks,
)
from heelstrike.models._codegen_numba import (
    CONTACTS_SIG,
    DYNAMICS_SIG,
    SWAP_SIG,
    NumbaModel,
    build_numba,
)
from heelstrike.models.builder import BuiltWalker

__all__ = [
    "STATUS_NAMES",
    "PhasedEnsembleResult",
    "check_compiled_actuation",
    "ensemble_walk_phased",
    "numba_model",
    "section_states",
    "simulate_phased_compiled",
]

# Kernel status codes: plain ints taken from the enum (numba freezes globals at compile time).
COMPLETED = WalkStatus.COMPLETED.code
FELL_FORWARD = WalkStatus.FELL_FORWARD.code
FELL_BACKWARD = WalkStatus.FELL_BACKWARD.code
TRAILING_FOOT_STAYS = WalkStatus.TRAILING_FOOT_STAYS.code
LOST_CONTACT = WalkStatus.LOST_CONTACT.code
SLIPPED = WalkStatus.SLIPPED.code
NO_HEEL_STRIKE = WalkStatus.NO_HEEL_STRIKE.code
INTEGRATION_FAILED = WalkStatus.INTEGRATION_FAILED.code
_NO_CONSISTENT_ASSIGNMENT = WalkStatus.NO_CONSISTENT_ASSIGNMENT.code
_NO_SWAP = WalkStatus.NO_LEG_SWAP.code

# event kinds
_EV_FLEXED, _EV_KNEE, _EV_ARMED, _EV_STRIKE = 0, 1, 2, 3
_EV_LOST, _EV_FWD, _EV_BACK, _EV_SLIP = 4, 5, 6, 7
_EV_NONE = -1  # time limit reached
_EV_FAIL = -2  # integrator failure

# float configuration: slope, stance foot radius, swing foot radius, knee flex threshold,
# friction coefficient (nan: none), torso joint (-1: passive), torso angle, kp, kd, push-off
# impulse (nan: none), leg length of the walker's scale (the lift rule's velocity scale)
_C_SLOPE, _C_RST, _C_RSW, _C_THR, _C_MU, _C_TJ, _C_TANG, _C_KP, _C_KD, _C_PUSH, _C_LEG = range(11)

# impact row layout: kind, step, time, T, T_c, T_a, v_trail, mode, rows, work, push-off work,
# then q, q_dot-, q_dot+ and the impulses (n each)
_I_HEAD = 11
_KIND_KNEE, _KIND_HEEL = 0.0, 1.0
_MODES = ("separate", "stick", "slip")

_DYN_T = nbt.FunctionType(DYNAMICS_SIG)
_CON_T = nbt.FunctionType(CONTACTS_SIG)
_SWP_T = nbt.FunctionType(SWAP_SIG)


# ---------------------------------------------------------------------------------------------
# small dense linear algebra (n <= ~10)
# ---------------------------------------------------------------------------------------------
@njit(cache=True, nogil=True)
def _gauss(A: FloatArray, B: FloatArray, k: int, r: int) -> None:
    """Solve ``A[:k, :k] X = B[:k, :r]`` in place (partial pivoting); ``A`` is destroyed."""
    for col in range(k):
        piv = col
        big = abs(A[col, col])
        for i in range(col + 1, k):
            if abs(A[i, col]) > big:
                big = abs(A[i, col])
                piv = i
        if piv != col:
            for j in range(k):
                A[col, j], A[piv, j] = A[piv, j], A[col, j]
            for j in range(r):
                B[col, j], B[piv, j] = B[piv, j], B[col, j]
        d = A[col, col]
        for i in range(col + 1, k):
            f = A[i, col] / d
            if f != 0.0:
                for j in range(col, k):
                    A[i, j] -= f * A[col, j]
                for j in range(r):
                    B[i, j] -= f * B[col, j]
    for i in range(k - 1, -1, -1):
        for j in range(r):
            s = B[i, j]
            for c in range(i + 1, k):
                s -= A[i, c] * B[c, j]
            B[i, j] = s / A[i, i]


@njit(cache=True, nogil=True)
def _impact(
    M: FloatArray, A: FloatArray, k: int, qd: FloatArray, v_c: FloatArray, lam: FloatArray
) -> None:
    """Inert impact with rows ``A[:k]``: ``v_c = P_c q_dot-`` and impulses ``lam`` (k)."""
    n = qd.shape[0]
    Mc = M.copy()
    X = np.empty((n, k))
    for i in range(n):
        for j in range(k):
            X[i, j] = A[j, i]
    _gauss(Mc, X, n, k)  # X = M^-1 A^T
    W = np.empty((k, k))
    mu = np.empty((k, 1))
    for i in range(k):
        s = 0.0
        for c in range(n):
            s += A[i, c] * qd[c]
        mu[i, 0] = s
        for j in range(k):
            s = 0.0
            for c in range(n):
                s += A[i, c] * X[c, j]
            W[i, j] = s
    _gauss(W, mu, k, 1)
    for i in range(n):
        s = 0.0
        for j in range(k):
            s += X[i, j] * mu[j, 0]
        v_c[i] = s
    for j in range(k):
        lam[j] = -mu[j, 0]


@njit(cache=True, nogil=True)
def _quad(M: FloatArray, v: FloatArray) -> float:
    n = v.shape[0]
    s = 0.0
    for i in range(n):
        for j in range(n):
            s += v[i] * M[i, j] * v[j]
    return 0.5 * s


# ---------------------------------------------------------------------------------------------
# single support
# ---------------------------------------------------------------------------------------------
@njit(cache=True, nogil=True)
def _unpack(
    x: FloatArray, free: IntArray, qref: FloatArray, R: float, q: FloatArray, qd: FloatArray
) -> None:
    m = free.shape[0]
    for i in range(q.shape[0]):
        q[i] = qref[i]
        qd[i] = 0.0
    for a in range(m):
        q[free[a]] = x[a]
        qd[free[a]] = x[m + a]
    q[0] = qref[0] + R * qref[2] - R * x[0]
    q[1] = R
    qd[0] = -R * x[m]


@njit(cache=True, nogil=True)
def _pack(q: FloatArray, qd: FloatArray, free: IntArray, work: float, x: FloatArray) -> None:
    m = free.shape[0]
    for a in range(m):
        x[a] = q[free[a]]
        x[m + a] = qd[free[a]]
    x[2 * m] = work


@njit(cache=True, nogil=True)
def _forces(
    dyn: Any, p: FloatArray, cfg: FloatArray, q: FloatArray, qd: FloatArray, M: FloatArray,
    h: FloatArray,
) -> float:
    """``M``, ``h`` and the actuator torque ``u`` of the torso law; ``h <- h - B u``.

    Returns the actuator power ``(B u) . q_dot`` (W).
    """
    dyn(q, qd, p, cfg[_C_SLOPE], M, h)
    tj = int(cfg[_C_TJ])
    if tj < 0:
        return 0.0
    u = -cfg[_C_KP] * (q[2] + q[tj] - cfg[_C_TANG]) - cfg[_C_KD] * (qd[2] + qd[tj])
    h[tj] -= u
    return u * qd[tj]


@njit(cache=True, nogil=True)
def _rhs(
    dyn: Any, p: FloatArray, cfg: FloatArray, free: IntArray, qref: FloatArray, x: FloatArray,
    dx: FloatArray, q: FloatArray, qd: FloatArray, M: FloatArray, h: FloatArray,
    Mr: FloatArray, Fr: FloatArray,
) -> None:
    """``d/dt (theta, theta_dot, W_act)``: ``J^T M J theta_dd = J^T (B u - h)``."""
    m = free.shape[0]
    R = cfg[_C_RST]
    _unpack(x, free, qref, R, q, qd)
    power = _forces(dyn, p, cfg, q, qd, M, h)
    for a in range(m):
        ia = free[a]
        f = -h[ia]
        if a == 0:
            f += R * h[0]
        Fr[a, 0] = f
        for b in range(m):
            ib = free[b]
            v = M[ia, ib]
            if a == 0:
                v -= R * M[0, ib]
            if b == 0:
                v -= R * M[ia, 0]
            if a == 0 and b == 0:
                v += R * R * M[0, 0]
            Mr[a, b] = v
    _gauss(Mr, Fr, m, 1)
    for a in range(m):
        dx[a] = x[m + a]
        dx[m + a] = Fr[a, 0]
    dx[2 * m] = power


@njit(cache=True, nogil=True)
def _reaction(
    dyn: Any, con: Any, p: FloatArray, cfg: FloatArray, q: FloatArray, qd: FloatArray,
) -> tuple[float, float]:
    """Ground force on the stance foot ``(A M^-1 A^T)^-1 A M^-1 (h - B u)`` (N)."""
    n = q.shape[0]
    M = np.empty((n, n))
    h = np.empty(n)
    A = np.empty((2, 2, n))
    rate = np.empty((2, 2))
    c = np.empty((2, 2))
    _forces(dyn, p, cfg, q, qd, M, h)
    con(q, qd, p, A, rate, c)
    X = np.empty((n, 3))
    for i in range(n):
        X[i, 0] = A[0, 0, i]
        X[i, 1] = A[0, 1, i]
        X[i, 2] = h[i]
    _gauss(M, X, n, 3)
    W = np.empty((2, 2))
    b = np.empty((2, 1))
    for r in range(2):
        for j in range(3):
            s = 0.0
            for i in range(n):
                s += A[0, r, i] * X[i, j]
            if j < 2:
                W[r, j] = s
            else:
                b[r, 0] = s
    _gauss(W, b, 2, 1)
    return b[0, 0], b[1, 0]


@njit(cache=True, nogil=True)
def _event_value(
    kind: int, dyn: Any, con: Any, p: FloatArray, cfg: FloatArray, free: IntArray,
    qref: FloatArray, swing_idx: IntArray, lockv: FloatArray, x: FloatArray,
) -> float:
    m = free.shape[0]
    if kind == _EV_FWD:
        return x[0] - 0.5 * math.pi
    if kind == _EV_BACK:
        return float(x[m]) if x[0] < 0.0 else 1.0 + float(x[0])
    if kind == _EV_FLEXED or kind == _EV_KNEE:
        g = math.inf
        for i in range(swing_idx.shape[0]):
            a = swing_idx[i]
            g = min(g, x[a] - lockv[free[a]])
        return g - cfg[_C_THR] if kind == _EV_FLEXED else g
    n = qref.shape[0]
    q = np.empty(n)
    qd = np.empty(n)
    _unpack(x, free, qref, cfg[_C_RST], q, qd)
    if kind == _EV_ARMED or kind == _EV_STRIKE:
        A = np.empty((2, 2, n))
        rate = np.empty((2, 2))
        c = np.empty((2, 2))
        con(q, qd, p, A, rate, c)
        clearance = c[1, 1] - cfg[_C_RSW]
        if kind == _EV_STRIKE:
            return -clearance
        return min(x[0], min(c[0, 0] - c[1, 0], clearance))
    lam_t, lam_n = _reaction(dyn, con, p, cfg, q, qd)
    if kind == _EV_LOST:
        return lam_n
    return cfg[_C_MU] * lam_n - abs(lam_t)


# ---------------------------------------------------------------------------------------------
# integrator: the drivers of heelstrike.dynamics._dp5 (starting step, event location) with the
# context tuple ``(dyn, con, p, cfg, free, qref, swing_idx, lockv, q, qd, M, h, Mr, Fr)``
# ---------------------------------------------------------------------------------------------
@njit(nogil=True, inline="always")
def _ctx_rhs(ctx: Any, x: FloatArray, dx: FloatArray) -> None:
    dyn, _, p, cfg, free, qref, _, _, q, qd, M, h, Mr, Fr = ctx
    _rhs(dyn, p, cfg, free, qref, x, dx, q, qd, M, h, Mr, Fr)


@njit(nogil=True, inline="always")
def _ctx_event(ctx: Any, x: FloatArray, kind: int) -> float:
    dyn, con, p, cfg, free, qref, swing_idx, lockv = ctx[:8]
    return _event_value(kind, dyn, con, p, cfg, free, qref, swing_idx, lockv, x)


_ode = dp5.integrator(_ctx_rhs, _ctx_event)


@njit(cache=True, nogil=True)
def _dp5(
    dyn: Any, p: FloatArray, cfg: FloatArray, free: IntArray, qref: FloatArray, y: FloatArray,
    hh: float, k: FloatArray, tmp: FloatArray, ynew: FloatArray, full: bool, q: FloatArray,
    qd: FloatArray, M: FloatArray, h: FloatArray, Mr: FloatArray, Fr: FloatArray,
) -> None:
    """One DP5 step (:mod:`heelstrike.dynamics._dp5`) from ``y`` with ``k[0] = f(y)``; writes
    ``ynew`` and, with ``full``, ``k[6] = f(ynew)`` and the error estimate in ``tmp``.

    ``_ode.step`` with the context's members as arguments: the hot path of :func:`_segment`,
    where passing the context tuple made the kneed walker's kernel ~15% slower.
    """
    dp5.stage(y, hh, k, 1, tmp)  # stage numbers as literals: numba folds the stage's branch
    _rhs(dyn, p, cfg, free, qref, tmp, k[1], q, qd, M, h, Mr, Fr)
    dp5.stage(y, hh, k, 2, tmp)
    _rhs(dyn, p, cfg, free, qref, tmp, k[2], q, qd, M, h, Mr, Fr)
    dp5.stage(y, hh, k, 3, tmp)
    _rhs(dyn, p, cfg, free, qref, tmp, k[3], q, qd, M, h, Mr, Fr)
    dp5.stage(y, hh, k, 4, tmp)
    _rhs(dyn, p, cfg, free, qref, tmp, k[4], q, qd, M, h, Mr, Fr)
    dp5.stage(y, hh, k, 5, tmp)
    _rhs(dyn, p, cfg, free, qref, tmp, k[5], q, qd, M, h, Mr, Fr)
    dp5.solution(y, hh, k, ynew)
    if full:
        _rhs(dyn, p, cfg, free, qref, ynew, k[6], q, qd, M, h, Mr, Fr)
        dp5.error_estimate(hh, k, tmp)


@njit(cache=True, nogil=True)
def _push(
    S: FloatArray, ns: int, t: float, x: FloatArray, free: IntArray, qref: FloatArray, R: float,
    step: int, leg: int, phase: int,
) -> tuple[FloatArray, int]:
    """Append a sample row ``(t, work, step, leg, phase, q, q_dot)``; grows ``S`` if full."""
    n = qref.shape[0]
    if ns == S.shape[0]:
        S2 = np.empty((2 * S.shape[0], S.shape[1]))
        S2[:ns] = S[:ns]
        S = S2
    q = np.empty(n)
    qd = np.empty(n)
    _unpack(x, free, qref, R, q, qd)
    S[ns, 0] = t
    S[ns, 1] = x[2 * free.shape[0]]
    S[ns, 2] = step
    S[ns, 3] = leg
    S[ns, 4] = phase
    for i in range(n):
        S[ns, 5 + i] = q[i]
        S[ns, 5 + n + i] = qd[i]
    return S, ns + 1


@njit(cache=True, nogil=True)
def _segment(
    dyn: Any, con: Any, p: FloatArray, cfg: FloatArray, free: IntArray, qref: FloatArray,
    swing_idx: IntArray, lockv: FloatArray, y: FloatArray, t: float, t_limit: float,
    kinds: IntArray, dirs: IntArray, rtol: float, atol: float, max_step: float, S: FloatArray,
    ns: int, step: int, leg: int, phase: int,
) -> tuple[int, float, FloatArray, int]:
    """Integrate from ``(t, y)`` to the first terminal event or ``t_limit``.

    ``y`` is overwritten with the final state; every accepted step is appended to ``S``.
    Returns ``(event kind or _EV_NONE / _EV_FAIL, final time, S, number of samples)``.
    """
    d = y.shape[0]
    n = qref.shape[0]
    m = free.shape[0]
    R = cfg[_C_RST]
    n_ev = kinds.shape[0]
    S, ns = _push(S, ns, t, y, free, qref, R, step, leg, phase)
    if t_limit <= t:
        return _EV_NONE, t, S, ns
    q = np.empty(n)
    qd = np.empty(n)
    M = np.empty((n, n))
    hv = np.empty(n)
    Mr = np.empty((m, m))
    Fr = np.empty((m, 1))
    ctx = (dyn, con, p, cfg, free, qref, swing_idx, lockv, q, qd, M, hv, Mr, Fr)
    k = np.empty((7, d))
    ktry = np.empty((7, d))
    tmp = np.empty(d)
    ynew = np.empty(d)
    ytry = np.empty(d)
    g_old = np.empty(n_ev)
    g_new = np.empty(n_ev)
    _rhs(dyn, p, cfg, free, qref, y, k[0], q, qd, M, hv, Mr, Fr)
    for j in range(n_ev):
        g_old[j] = _event_value(kinds[j], dyn, con, p, cfg, free, qref, swing_idx, lockv, y)
    for j in range(n_ev):
        # contact already lost at the start: no sign change to detect (hybrid.CONTACT_EVENTS)
        if (kinds[j] == _EV_LOST or kinds[j] == _EV_SLIP) and g_old[j] <= 0.0:
            return kinds[j], t, S, ns
    # Hairer's starting step (as solve_ivp), its first trial clamped to max_step
    hstep = _ode.start_step(ctx, y, k, ktry, tmp, rtol, atol, max_step)
    n_steps = 0
    while True:
        if t >= t_limit:
            return _EV_NONE, t, S, ns
        n_steps += 1
        if n_steps > 2_000_000:
            return _EV_FAIL, t, S, ns
        h_min = dp5.min_step(t)
        if hstep < h_min:
            return _EV_FAIL, t, S, ns
        hh = min(hstep, t_limit - t, max_step)
        while True:
            _dp5(dyn, p, cfg, free, qref, y, hh, k, tmp, ynew, True, q, qd, M, hv, Mr, Fr)
            en = dp5.error_norm(y, ynew, tmp, rtol, atol)
            if en <= 1.0:
                break
            hh *= dp5.shrink_factor(en)
            if hh < h_min:
                return _EV_FAIL, t, S, ns
        h_next = min(hh * dp5.grow_factor(en), max_step)
        for j in range(n_ev):
            g_new[j] = _event_value(kinds[j], dyn, con, p, cfg, free, qref, swing_idx, lockv,
                                    ynew)
        if dp5.any_crossed(g_old, g_new, dirs, n_ev):
            best, tau = _ode.first_event(ctx, y, hh, t, k, ktry, tmp, ynew, ytry, kinds, dirs,
                                         n_ev, g_old, g_new)
            t = t + tau
            S, ns = _push(S, ns, t, y, free, qref, R, step, leg, phase)
            return kinds[best], t, S, ns
        t = t + hh
        for r in range(d):
            y[r] = ynew[r]
            k[0, r] = k[6, r]
        for j in range(n_ev):
            g_old[j] = g_new[j]
        hstep = h_next
        S, ns = _push(S, ns, t, y, free, qref, R, step, leg, phase)


@njit(cache=True, nogil=True)
def _outcome(ev: int, want: int) -> int:
    """Status code ending the walk after a segment, or -1 if it ended with ``want``."""
    if ev == want:
        return -1
    if ev == _EV_FAIL:
        return INTEGRATION_FAILED
    if ev == _EV_NONE:
        return NO_HEEL_STRIKE
    if ev == _EV_FWD:
        return FELL_FORWARD
    if ev == _EV_BACK:
        return FELL_BACKWARD
    if ev == _EV_LOST:
        return LOST_CONTACT
    if ev == _EV_SLIP:
        return SLIPPED
    return INTEGRATION_FAILED


@njit(cache=True, nogil=True)
def _kinds(want: int, friction: bool) -> tuple[IntArray, IntArray]:
    """Events of a segment in ``simulate_phased``'s order and their directions."""
    ne = 5 if friction else 4
    kinds = np.empty(ne, dtype=np.int64)
    dirs = np.empty(ne, dtype=np.int64)
    kinds[0] = want
    dirs[0] = -1 if want == _EV_KNEE else 1
    kinds[1], dirs[1] = _EV_LOST, -1
    kinds[2], dirs[2] = _EV_FWD, 1
    kinds[3], dirs[3] = _EV_BACK, -1
    if friction:
        kinds[4], dirs[4] = _EV_SLIP, -1
    return kinds, dirs


@njit(cache=True, nogil=True)
def _free_coordinates(n: int, locked: IntArray) -> IntArray:
    out = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(2, n):
        ok = True
        for j in range(locked.shape[0]):
            if locked[j] == i:
                ok = False
        if ok:
            out[m] = i
            m += 1
    return out[:m].copy()


@njit(cache=True, nogil=True)
def _record_impact(
    I: FloatArray, ni: int, kind: float, step: int, t: float, M: FloatArray, q: FloatArray,
    qd: FloatArray, v_c: FloatArray, lam: FloatArray, rows: int, v_trail: float, mode: int,
    work: float, push_work: float,
) -> int:
    n = q.shape[0]
    va = qd - v_c
    I[ni, 0] = kind
    I[ni, 1] = step
    I[ni, 2] = t
    I[ni, 3] = _quad(M, qd)
    I[ni, 4] = _quad(M, v_c)
    I[ni, 5] = _quad(M, va)
    I[ni, 6] = v_trail
    I[ni, 7] = mode
    I[ni, 8] = rows
    I[ni, 9] = work
    I[ni, 10] = push_work
    for i in range(n):
        I[ni, _I_HEAD + i] = q[i]
        I[ni, _I_HEAD + n + i] = qd[i]
        I[ni, _I_HEAD + 2 * n + i] = qd[i] - v_c[i]
        I[ni, _I_HEAD + 3 * n + i] = lam[i] if i < rows else np.nan
    return ni + 1


_F = nbt.float64
_WALK_SIG = (
    _DYN_T, _CON_T, _SWP_T, _F[::1], _F[::1], _F[::1], _F[::1], nbt.int64, nbt.int64[::1],
    nbt.int64[::1], _F[::1], _F, _F, _F, _F,
)


def _walk_py(
    dyn: Any, con: Any, swp: Any, p: FloatArray, cfg: FloatArray, q0: FloatArray,
    qd0: FloatArray, steps: int, stance_locks: IntArray, swing_locks: IntArray,
    lockv: FloatArray, max_duration: float, rtol: float, atol: float, max_step: float,
) -> tuple[int, FloatArray, int, FloatArray, int, FloatArray, FloatArray, FloatArray]:
    """The whole phased walk (see the module docstring).

    Returns ``(status, samples, n_samples, impacts, n_impacts, step_starts, q, q_dot)``;
    ``step_starts`` rows are ``(t, work, q)`` at the start of every step.
    """
    n = q0.shape[0]
    friction = not math.isnan(cfg[_C_MU])
    nsl = stance_locks.shape[0]
    nwl = swing_locks.shape[0]
    all_locks = np.empty(nsl + nwl, dtype=np.int64)
    all_locks[:nsl] = stance_locks
    all_locks[nsl:] = swing_locks
    nl = nsl + nwl
    q = q0.copy()
    qd = qd0.copy()
    S = np.empty((1024, 5 + 2 * n))
    ns = 0
    Imp = np.full((2 * steps, _I_HEAD + 4 * n), np.nan)
    ni = 0
    starts = np.full((steps, 2 + n), np.nan)
    M = np.empty((n, n))
    hv = np.empty(n)
    Ac = np.empty((2, 2, n))
    rate = np.empty((2, 2))
    cc = np.empty((2, 2))
    v_c = np.empty(n)
    lam = np.empty(n + 2)
    t = 0.0
    work = 0.0
    leg = 0
    status = COMPLETED
    free_knee = _free_coordinates(n, stance_locks)
    free_lock = _free_coordinates(n, all_locks)
    swing_idx = np.empty(nwl, dtype=np.int64)
    for c in range(nwl):
        for a in range(free_knee.shape[0]):
            if free_knee[a] == swing_locks[c]:
                swing_idx[c] = a
    none_idx = np.empty(0, dtype=np.int64)
    for kstep in range(steps):
        t_step = t
        starts[kstep, 0] = t
        starts[kstep, 1] = work
        starts[kstep, 2:] = q
        t_limit = t_step + max_duration
        ended = -1
        # -- knee swing ---------------------------------------------------------------------
        if nwl > 0:
            free = free_knee
            for want in (_EV_FLEXED, _EV_KNEE):
                qref = q.copy()
                y = np.empty(2 * free.shape[0] + 1)
                _pack(q, qd, free, work, y)
                kinds, dirs = _kinds(want, friction)
                ev, t, S, ns = _segment(dyn, con, p, cfg, free, qref, swing_idx, lockv, y, t,
                                        t_limit, kinds, dirs, rtol, atol, max_step, S, ns,
                                        kstep, leg, 0)
                _unpack(y, free, qref, cfg[_C_RST], q, qd)
                work = y[2 * free.shape[0]]
                ended = _outcome(ev, want)
                if ended >= 0:
                    break
            if ended < 0:
                for c in range(nwl):
                    q[swing_locks[c]] = lockv[swing_locks[c]]
                _forces(dyn, p, cfg, q, qd, M, hv)
                con(q, qd, p, Ac, rate, cc)
                rows = np.zeros((2 + nl, n))
                rows[0] = Ac[0, 0]
                rows[1] = Ac[0, 1]
                for c in range(nl):
                    rows[2 + c, all_locks[c]] = 1.0
                _impact(M, rows, 2 + nl, qd, v_c, lam)
                v_post = qd - v_c
                vn = 0.0
                for i in range(n):
                    vn += Ac[0, 1, i] * v_post[i]
                ni = _record_impact(Imp, ni, _KIND_KNEE, kstep, t, M, q, qd, v_c, lam, 2 + nl,
                                    vn, 1, work, 0.0)
                qd = v_post
        # -- locked swing -------------------------------------------------------------------
        if ended < 0:
            free = free_lock
            for want in (_EV_ARMED, _EV_STRIKE):
                qref = q.copy()
                y = np.empty(2 * free.shape[0] + 1)
                _pack(q, qd, free, work, y)
                if want == _EV_ARMED and _event_value(_EV_ARMED, dyn, con, p, cfg, free, qref,
                                                      none_idx, lockv, y) > 0.0:
                    continue
                kinds, dirs = _kinds(want, friction)
                ev, t, S, ns = _segment(dyn, con, p, cfg, free, qref, none_idx, lockv, y, t,
                                        t_limit, kinds, dirs, rtol, atol, max_step, S, ns,
                                        kstep, leg, 1)
                _unpack(y, free, qref, cfg[_C_RST], q, qd)
                work = y[2 * free.shape[0]]
                ended = _outcome(ev, want)
                if ended >= 0:
                    break
        if ended >= 0:
            status = ended
            break
        # -- heel strike: leading foot bilateral, trailing foot by complementarity ------------
        _forces(dyn, p, cfg, q, qd, M, hv)
        con(q, qd, p, Ac, rate, cc)
        push_work = 0.0
        if not math.isnan(cfg[_C_PUSH]):
            # push-off impulse p e(q2) at the trailing contact: M dq_dot = A_R^T p e(q2)
            ex = -cfg[_C_PUSH] * math.sin(q[2])
            ey = cfg[_C_PUSH] * math.cos(q[2])
            dq = np.empty((n, 1))
            for i in range(n):
                dq[i, 0] = Ac[0, 0, i] * ex + Ac[0, 1, i] * ey
            _gauss(M.copy(), dq, n, 1)
            T0 = _quad(M, qd)
            qd = qd + dq[:, 0]
            push_work = _quad(M, qd) - T0
            work += push_work
        kb = 2 + nl
        rows = np.zeros((kb + 2, n))
        rows[0] = Ac[1, 0]
        rows[1] = Ac[1, 1]
        for c in range(nl):
            rows[2 + c, all_locks[c]] = 1.0
        trM = 0.0
        for i in range(n):
            trM += M[i, i]
        v_scale = math.sqrt(2.0 * _quad(M, qd) / max(trM / n, 1e-300)) + 1e-300
        tol = 1e-10
        mode = -1
        k_rows = kb
        for trial in (0, 1, 2):  # separate, stick, then the slip fallback
            k_rows = kb
            if trial == 1:
                rows[kb] = Ac[0, 1]
                rows[kb + 1] = Ac[0, 0]
                k_rows = kb + 2
            elif trial == 2:
                rows[kb] = Ac[0, 1]
                k_rows = kb + 1
            if k_rows > n or np.linalg.matrix_rank(rows[:k_rows].copy()) < k_rows:
                continue
            _impact(M, rows, k_rows, qd, v_c, lam)
            lam_scale = 0.0
            for r in range(k_rows):
                lam_scale = max(lam_scale, abs(lam[r]))
            lam_scale += 1e-300
            vn = 0.0
            for i in range(n):
                vn += Ac[0, 1, i] * (qd[i] - v_c[i])
            if trial == 0:
                if vn < -tol * max(v_scale, 1.0):
                    continue
            elif lam[kb] < -tol * max(lam_scale, 1.0):
                continue
            mode = trial
            break
        if mode < 0:
            status = _NO_CONSISTENT_ASSIGNMENT
            break
        v_post = qd - v_c
        vn = 0.0
        for i in range(n):
            vn += Ac[0, 1, i] * v_post[i]
        ni = _record_impact(Imp, ni, _KIND_HEEL, kstep, t, M, q, qd, v_c, lam, k_rows, vn, mode,
                            work, push_work)
        if mode != 0 or not lifts_jit(vn, lift_velocity_scale_jit(cfg[_C_LEG], qd[2:])):
            status = TRAILING_FOOT_STAYS
            qd = v_post
            break
        qn = np.empty(n)
        qdn = np.empty(n)
        if swp(q, v_post, p, qn, qdn) != 1.0:
            status = _NO_SWAP
            qd = v_post
            break
        q = qn
        qd = qdn
        for c in range(nl):
            q[all_locks[c]] = lockv[all_locks[c]]
            qd[all_locks[c]] = 0.0
        leg = 1 - leg
    return status, S, ns, Imp, ni, starts, q, qd


#: The walk kernel's dispatcher; compiled for ``_WALK_SIG`` only (see :func:`_walk_kernel`), and
#: called with that signature by the ensemble kernel.
_WALK_JIT: Any = njit(cache=True, nogil=True)(_walk_py)
_KERNEL: list[Any] = []


def _walk_kernel() -> Any:
    """``_walk_py`` compiled for first-class function arguments (once; numba disk cache).

    Without a numba cache (first use) the compilation takes a minute or two; a one-line note
    says so on stderr.
    """
    if not _KERNEL:
        disp: Any = _WALK_JIT
        try:
            cached = Path(disp._cache._cache_file._index_path).is_file()
        except AttributeError:  # pragma: no cover - numba internals moved: stay quiet
            cached = True
        if not cached:
            print("heelstrike: compiling the simulation kernel (first use only, cached "
                  "afterwards; this takes a minute or two)", file=sys.stderr, flush=True)
        disp.compile(_WALK_SIG)
        disp.disable_compile()  # the generated functions convert to the compiled signature
        _KERNEL.append(disp)
    return _KERNEL[0]


# ---------------------------------------------------------------------------------------------
# Python API
# ---------------------------------------------------------------------------------------------
def numba_model(walker: BuiltWalker) -> NumbaModel:
    """The numba functions generated for a walker's structure (built and cached on demand)."""
    return build_numba(walker.description)


def check_compiled_actuation(walker: BuiltWalker, torque: Any, push_off: Any) -> None:
    """Raise ``ValueError`` unless the compiled backend supports this actuation.

    Supported: passive (``torque=None``) or a :class:`~heelstrike.dynamics.phased.TorsoPD`
    torque on a walker with a ``torso`` joint, and no push-off or a
    :class:`~heelstrike.dynamics.actuation.PushOff`.
    """
    if push_off is not None and type(push_off) is not PushOff:
        raise ValueError(
            "the compiled backend supports the PushOff impulse only; use backend='scipy'"
        )
    if torque is not None and not (
        type(torque) is TorsoPD and "torso" in walker.coordinate_names
    ):
        raise ValueError(
            "the compiled backend supports passive walking and TorsoPD torques only; "
            "use backend='scipy' for other torque laws"
        )


def _locks(walker: BuiltWalker) -> tuple[tuple[int, ...], tuple[int, ...], FloatArray]:
    """``(stance locks, swing locks, lock angle of every coordinate (rad, 0 if none))``."""
    stance_locks, swing_locks = stance_and_swing_locks(walker)
    lockv = np.zeros(walker.n_coordinates)
    for j, a in zip(walker.lockable_joints, walker.lock_angles, strict=True):
        lockv[j] = float(a)
    return stance_locks, swing_locks, lockv


def _configuration(
    walker: BuiltWalker, slope: float, torque: TorsoPD | None, push_off: PushOff | None,
    friction: float | None, knee_flex_threshold: float,
) -> tuple[FloatArray, FloatArray]:
    """The kernel's parameter values ``p`` and float configuration ``cfg`` (``_C_*``)."""
    values = [np.asarray(walker.params[k], dtype=float) for k in walker.description.param_names]
    if any(v.ndim != 0 for v in values):
        raise ValueError("the compiled backend needs scalar parameter values (one walker)")
    tj, tang, kp, kd = -1.0, 0.0, 0.0, 0.0
    if isinstance(torque, TorsoPD):
        tj = float(walker.joint_index("torso"))
        tang, kp, kd = float(torque.angle), float(torque.kp), float(torque.kd)
    cfg = np.array(
        [slope, float(np.asarray(walker.foot_radii[0])), float(np.asarray(walker.foot_radii[1])),
         knee_flex_threshold, math.nan if friction is None else float(friction), tj, tang, kp,
         kd, math.nan if push_off is None else float(push_off.impulse),
         float(walker.scale.leg_length)],
        dtype=float,
    )
    return np.array([float(v) for v in values]), cfg


def simulate_phased_compiled(
    walker: BuiltWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    slope: float = 0.0,
    steps: int = 1,
    torque: TorsoPD | None = None,
    push_off: PushOff | None = None,
    friction: float | None = None,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
    knee_flex_threshold: float = 1e-6,
) -> PhasedWalkResult:
    """Compiled :func:`~heelstrike.dynamics.phased.simulate_phased` (same arguments and result).

    Parameters
    ----------
    walker : BuiltWalker
        Any described walker (scalar parameters).
    q0, q_dot0 : array_like, shape (n,)
        State just after a heel strike (stance foot rolling, lockable joints locked).
    slope : float
        Ground slope (rad).
    steps : int
        Number of heel strikes to simulate.
    torque : TorsoPD, optional
        Torso posture law (evaluated in the kernel); None: passive.
    push_off : PushOff, optional
        Push-off impulse just before each heel strike (evaluated in the kernel).
    friction : float, optional
        Coulomb coefficient of the stance foot (``slipped`` event).
    max_step_duration : float
        Time bound of one step (s).
    rtol, atol, max_step : float
        Integrator (DP5) settings.
    knee_flex_threshold : float
        The swing knee must flex past this angle (rad) before its strike is looked for.

    Returns
    -------
    PhasedWalkResult
        Samples are the states after every accepted integrator step.

    Raises
    ------
    ValueError
        On an invalid initial state, or actuation this backend does not support.
    NotImplementedError
        If a step ends in a heel strike and the walker declares no mirrors (no leg swap).
    """
    q, qd = check_initial_state(walker, q0, q_dot0, steps)
    check_compiled_actuation(walker, torque, push_off)
    stance_locks, swing_locks, lockv = _locks(walker)
    p, cfg = _configuration(walker, slope, torque, push_off, friction, knee_flex_threshold)
    model = numba_model(walker)
    status, S, ns, Imp, ni, starts, qf, qdf = _walk_kernel()(
        model.dynamics, model.contacts, model.swap, p, cfg, q, qd, int(steps),
        np.asarray(stance_locks, dtype=np.int64), np.asarray(swing_locks, dtype=np.int64),
        lockv, float(max_step_duration), float(rtol), float(atol), float(max_step),
    )
    if status == _NO_CONSISTENT_ASSIGNMENT:
        raise ImpactInputError(WalkStatus.NO_CONSISTENT_ASSIGNMENT.message)
    if status == _NO_SWAP:
        raise NotImplementedError(
            f"walker {walker.description.name!r}: {WalkStatus.NO_LEG_SWAP.message}"
        )
    return _result(walker, int(status), S[:ns], Imp[:ni], starts, qf, qdf, float(slope),
                   stance_locks + swing_locks)


def _result(
    walker: BuiltWalker, status: int, S: FloatArray, Imp: FloatArray, starts: FloatArray,
    qf: FloatArray, qdf: FloatArray, slope: float, all_locks: tuple[int, ...],
) -> PhasedWalkResult:
    n = walker.n_coordinates
    A_lock = walker.lock_jacobian(all_locks) if all_locks else np.zeros((0, n))
    events: list[PhasedImpact] = []
    records: list[ImpactRecord] = []
    for row in Imp:
        kind: ImpactKind = "knee_strike" if row[0] == _KIND_KNEE else "heel_strike"
        k = int(row[1])
        t = float(row[2])
        nrows = int(row[8])
        q = row[_I_HEAD : _I_HEAD + n].copy()
        qdm = row[_I_HEAD + n : _I_HEAD + 2 * n].copy()
        qdp = row[_I_HEAD + 2 * n : _I_HEAD + 3 * n].copy()
        lam = row[_I_HEAD + 3 * n : _I_HEAD + 3 * n + nrows].copy()
        mode = _MODES[int(row[7])]
        if kind == "knee_strike":
            rows = np.vstack((walker.contact_jacobian(q, "right"), A_lock))
        else:
            A_R = walker.contact_jacobian(q, "right")
            extra = {"separate": A_R[:0], "stick": A_R[::-1], "slip": A_R[1:]}[mode]
            rows = np.vstack((walker.contact_jacobian(q, "left"), A_lock, extra))
        T, T_c, T_a = float(row[3]), float(row[4]), float(row[5])
        v_trail = float(row[6])
        events.append(
            PhasedImpact(
                kind=kind, step=k, time=t, q=q, q_dot_minus=qdm, q_dot_plus=qdp, rows=rows,
                kinetic_energy=T, kinetic_energy_constrained=T_c, kinetic_energy_admissible=T_a,
                energy_lost=T_c, impulse=lam, lock_rows=A_lock.copy(),
                lock_velocity_post=A_lock @ qdp, trailing_normal_velocity=v_trail,
                trailing_mode=mode,
            )
        )
        if kind == "heel_strike":
            t0, w0 = float(starts[k, 0]), float(starts[k, 1])
            q_start = starts[k, 2:]
            records.append(
                ImpactRecord(
                    step=k, time=t, q=q, q_dot_minus=qdm, q_dot_plus=qdp,
                    impact_angle=float(q[2]), kinetic_energy=T,
                    kinetic_energy_constrained=T_c, kinetic_energy_admissible=T_a,
                    energy_lost=T_c, impulse=lam[:2].copy(),
                    step_length=float(walker.step_length(q_start, q)),
                    trailing_normal_velocity=v_trail,
                    potential_energy_released=float(walker.potential_energy(q_start, slope))
                    - float(walker.potential_energy(q, slope)),
                    actuator_work=float(row[9]) - w0, push_off_work=float(row[10]),
                    step_duration=t - t0,
                )
            )
    st = WalkStatus.from_code(status)
    q_all = np.ascontiguousarray(S[:, 5 : 5 + n])
    qd_all = np.ascontiguousarray(S[:, 5 + n : 5 + 2 * n])
    return PhasedWalkResult(
        status=st,
        message=st.message,
        t=S[:, 0].copy(),
        q=q_all,
        q_dot=qd_all,
        stance_leg=S[:, 3].astype(np.int_),
        step=S[:, 2].astype(np.int_),
        actuator_work=S[:, 1].copy(),
        impacts=tuple(records),
        final_q=np.asarray(qf),
        final_q_dot=np.asarray(qdf),
        slope=slope,
        events=tuple(events),
        phase=np.where(S[:, 4] == 0, "knee_swing", "locked_swing"),
        mechanical_energy=np.asarray(walker.mechanical_energy(q_all, qd_all, slope)),
    )


# ---------------------------------------------------------------------------------------------
# ensembles: many walkers (initial states) in one compiled call
# ---------------------------------------------------------------------------------------------
def _ensemble_py(
    dyn: Any, con: Any, swp: Any, p: FloatArray, cfg: FloatArray, Q0: FloatArray,
    QD0: FloatArray, steps: int, stance_locks: IntArray, swing_locks: IntArray,
    lockv: FloatArray, max_duration: float, rtol: float, atol: float, max_step: float,
    sec_q: IntArray, sec_v: IntArray, target: FloatArray, stop_tol: float, i0: int, i1: int,
    status: IntArray, taken: IntArray, Qf: FloatArray, QDf: FloatArray,
) -> None:
    """Walk walkers ``i0 <= i < i1`` (rows of ``Q0``, ``QD0``) for up to ``steps`` steps.

    Every step is one call of the walk kernel (``steps = 1``) from the previous post-impact
    state, so a walker can stop on arrival near ``target`` (section norm ``< stop_tol``; no
    stop if ``stop_tol <= 0``). Writes ``status``, heel strikes ``taken`` and the final state.
    """
    nq = sec_q.shape[0]
    nv = sec_v.shape[0]
    for i in range(i0, i1):
        q = Q0[i].copy()
        qd = QD0[i].copy()
        st = COMPLETED
        k = 0
        while k < steps:
            s, _S, _ns, Imp, ni, _starts, qn, qdn = _WALK_JIT(
                dyn, con, swp, p, cfg, q, qd, 1, stance_locks, swing_locks, lockv,
                max_duration, rtol, atol, max_step,
            )
            for r in range(ni):
                if Imp[r, 0] == _KIND_HEEL:
                    k += 1
            q = qn
            qd = qdn
            if s != COMPLETED:
                st = s
                break
            if stop_tol > 0.0:
                d2 = 0.0
                for a in range(nq):
                    d2 += (q[sec_q[a]] - target[a]) ** 2
                for a in range(nv):
                    d2 += (qd[sec_v[a]] - target[nq + a]) ** 2
                if math.sqrt(d2) < stop_tol:
                    break
        status[i] = st
        taken[i] = k
        Qf[i] = q
        QDf[i] = qd


_ENS_SIG = (
    _DYN_T, _CON_T, _SWP_T, _F[::1], _F[::1], _F[:, ::1], _F[:, ::1], nbt.int64,
    nbt.int64[::1], nbt.int64[::1], _F[::1], _F, _F, _F, _F, nbt.int64[::1], nbt.int64[::1],
    _F[::1], _F, nbt.int64, nbt.int64, nbt.int64[::1], nbt.int64[::1], _F[:, ::1], _F[:, ::1],
)
_ENS_KERNEL: list[Any] = []


def _ensemble_kernel() -> Any:
    """``_ensemble_py`` compiled for first-class function arguments (once; numba disk cache)."""
    if not _ENS_KERNEL:
        _walk_kernel()
        disp: Any = njit(cache=True, nogil=True)(_ensemble_py)
        disp.compile(_ENS_SIG)
        disp.disable_compile()
        _ENS_KERNEL.append(disp)
    return _ENS_KERNEL[0]


@dataclass(frozen=True, kw_only=True)
class PhasedEnsembleResult(EnsembleStatus, ResultDictMixin):
    """Outcome of :func:`ensemble_walk_phased` for ``N`` walkers (initial states).

    Attributes
    ----------
    status : ndarray of int, shape (N,)
        Status codes, names in :data:`STATUS_NAMES` (the ``WalkStatus`` values, as returned by
        :func:`~heelstrike.dynamics.phased.simulate_phased`).
    steps : ndarray of int, shape (N,)
        Heel strikes taken (``PhasedWalkResult.n_steps``; a heel strike that left the trailing
        foot on the ground counts).
    q, q_dot : ndarray, shape (N, n)
        Final state (m, rad, m/s, rad/s): just after the last heel strike and leg swap for a
        completed walk; where the walk ended otherwise (``final_q`` / ``final_q_dot`` of
        ``simulate_phased``).
    z : ndarray, shape (N, d)
        Section coordinates of the final state (``PhasedWalker.section_names``; rad, rad/s).
    section_names : tuple of str
        Names of the ``d`` section coordinates.
    """

    status: IntArray
    steps: IntArray
    q: FloatArray
    q_dot: FloatArray
    z: FloatArray
    section_names: tuple[str, ...]


def section_states(walker: BuiltWalker, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Post-heel-strike states of many section points (``PhasedWalker.section_to_state``).

    The touchdown configuration (a Newton solve) is computed once per distinct angle part of
    ``z``, so a grid with few distinct angles is cheap.

    Parameters
    ----------
    walker : BuiltWalker
    z : array_like, shape (N, d) or (d,)
        Section coordinates (rad, rad/s).

    Returns
    -------
    q, q_dot : ndarray, shape (N, n)
    """
    w = PhasedWalker.from_built(walker)
    Z = np.atleast_2d(np.asarray(z, dtype=float))
    d = len(w.section_names)
    if Z.ndim != 2 or Z.shape[1] != d:
        raise ValueError(f"z must have shape (N, {d}) or ({d},): {w.section_names}")
    nq = d - len(w._section_v)
    angles, inverse = np.unique(Z[:, :nq], axis=0, return_inverse=True)
    q_by_angle = np.array([w.section_to_state(np.concatenate((a, np.zeros(d - nq))))[0]
                           for a in angles])
    Q = q_by_angle[np.asarray(inverse).ravel()]
    QD = np.zeros_like(Q)
    QD[:, list(w._section_v)] = Z[:, nq:]
    R = float(np.asarray(w.foot_radii[0]))
    QD[:, 0] = -R * QD[:, 2]
    return Q, QD


def ensemble_walk_phased(
    walker: BuiltWalker,
    z0: ArrayLike | None = None,
    *,
    states: tuple[ArrayLike, ArrayLike] | None = None,
    slope: float = 0.0,
    steps: int = 1,
    torque: TorsoPD | None = None,
    push_off: PushOff | None = None,
    friction: float | None = None,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
    knee_flex_threshold: float = 1e-6,
    stop_near: tuple[ArrayLike, float] | None = None,
    parallel: bool | None = None,
) -> PhasedEnsembleResult:
    """Walk ``N`` initial states of one described walker for ``steps`` steps, compiled.

    Every walker is :func:`simulate_phased_compiled` (the same kernel, step by step from the
    previous post-impact state, so a walk can stop on arrival), all in one compiled call per
    thread; no samples or impact records are kept.

    Parameters
    ----------
    walker : BuiltWalker
        Any described walker with scalar parameters.
    z0 : array_like, shape (N, d) or (d,), optional
        Post-heel-strike section points (``PhasedWalker.section_names``; rad, rad/s).
    states : (array_like, array_like), optional
        ``(q0, q_dot0)``, each shape (N, n): full post-impact states instead of ``z0`` (stance
        foot on the ground and rolling, lockable joints locked with zero rate).
    slope : float
        Ground slope (rad).
    steps : int
        Largest number of heel strikes per walker.
    torque, push_off, friction, max_step_duration, rtol, atol, max_step, knee_flex_threshold
        As :func:`simulate_phased_compiled`.
    stop_near : (array_like of shape (d,), float), optional
        ``(z_target, tol)``: a walker stops (status completed) as soon as its post-impact
        section point is within ``tol`` of ``z_target`` (Euclidean norm).
    parallel : bool, optional
        Split the walkers over ``os.cpu_count()`` threads (the kernel releases the GIL);
        default: parallel on the main thread, serial on other threads (e.g. Dask workers).

    Returns
    -------
    PhasedEnsembleResult

    Raises
    ------
    ValueError
        Neither or both of ``z0`` and ``states``, bad shapes, invalid initial states, or
        actuation the compiled backend does not support.
    ImpactInputError
        If a heel strike has no consistent contact assignment (as ``simulate_phased``).
    NotImplementedError
        If the walker declares no mirrors (no leg swap).
    """
    if steps < 1:
        raise ValueError("steps must be >= 1")
    if (z0 is None) == (states is None):
        raise ValueError("give exactly one of z0 (section points) and states=(q0, q_dot0)")
    check_compiled_actuation(walker, torque, push_off)
    w = PhasedWalker.from_built(walker)
    n = w.n_coordinates
    R = float(np.asarray(w.foot_radii[0]))
    stance_locks, swing_locks, lockv = _locks(w)
    if states is not None:
        Q = np.array(np.atleast_2d(np.asarray(states[0], dtype=float)))
        QD = np.array(np.atleast_2d(np.asarray(states[1], dtype=float)))
        if Q.ndim != 2 or Q.shape[1] != n or QD.shape != Q.shape:
            raise ValueError(f"states must be two arrays of shape (N, {n})")
        _check_post_impact(w, Q, QD, lockv, R)
    else:
        Q, QD = section_states(w, z0)  # type: ignore[arg-type]
    if not (np.all(np.isfinite(Q)) and np.all(np.isfinite(QD))):
        raise ValueError("initial states must be finite")
    p, cfg = _configuration(w, slope, torque, push_off, friction, knee_flex_threshold)
    d = len(w.section_names)
    target = np.zeros(d)
    stop_tol = 0.0
    if stop_near is not None:
        target = np.asarray(stop_near[0], dtype=float).reshape(d).copy()
        stop_tol = float(stop_near[1])
    model = numba_model(w)
    N = Q.shape[0]
    status = np.zeros(N, dtype=np.int64)
    taken = np.zeros(N, dtype=np.int64)
    Qf = np.zeros((N, n))
    QDf = np.zeros((N, n))
    Q = np.ascontiguousarray(Q)
    QD = np.ascontiguousarray(QD)
    kernel = _ensemble_kernel()
    common: tuple[Any, ...] = (
        model.dynamics, model.contacts, model.swap, p, cfg, Q, QD, int(steps),
        np.asarray(stance_locks, dtype=np.int64), np.asarray(swing_locks, dtype=np.int64),
        lockv, float(max_step_duration), float(rtol), float(atol), float(max_step),
        np.asarray(w._section_q, dtype=np.int64), np.asarray(w._section_v, dtype=np.int64),
        target, stop_tol,
    )
    outs = (status, taken, Qf, QDf)
    n_threads = min(os.cpu_count() or 1, N)
    if n_threads > 1 and use_parallel(parallel):
        # interleaved blocks balance falls (cheap) against long walks
        order = np.random.default_rng(0).permutation(N)
        Qs, QDs = np.ascontiguousarray(Q[order]), np.ascontiguousarray(QD[order])
        sub: list[Any] = [np.empty_like(a) for a in outs]
        bounds = np.linspace(0, N, n_threads + 1).astype(np.int64)

        def block(lo: int, hi: int) -> None:
            kernel(*common[:5], Qs, QDs, *common[7:], lo, hi, *sub)

        with ThreadPoolExecutor(n_threads) as pool:
            futures = [pool.submit(block, int(lo), int(hi))
                       for lo, hi in itertools.pairwise(bounds)]
            for f in futures:
                f.result()
        for a, b in zip(outs, sub, strict=True):
            a[order] = b
    else:
        kernel(*common, 0, N, *outs)
    if np.any(status == _NO_SWAP):
        raise NotImplementedError(
            f"walker {w.description.name!r}: {WalkStatus.NO_LEG_SWAP.message}"
        )
    if np.any(status == _NO_CONSISTENT_ASSIGNMENT):
        i = int(np.flatnonzero(status == _NO_CONSISTENT_ASSIGNMENT)[0])
        raise ImpactInputError(f"walker {i}: {WalkStatus.NO_CONSISTENT_ASSIGNMENT.message}")
    return PhasedEnsembleResult(
        status=status, steps=taken, q=Qf, q_dot=QDf, z=w.state_to_section(Qf, QDf),
        section_names=w.section_names,
    )


def _check_post_impact(
    walker: BuiltWalker, Q: FloatArray, QD: FloatArray, lockv: FloatArray, R: float
) -> None:
    """Raise ``ValueError`` unless every row is a post-heel-strike state (as the single walk)."""
    for i in range(Q.shape[0]):
        q, qd = Q[i], QD[i]
        if abs(q[1] - R) > 1e-9 or np.max(
            np.abs(walker.contact_jacobian(q, "right") @ qd)
        ) > 1e-9:
            raise ValueError(
                f"state {i} must have the stance foot on the ground (y = R) and rolling "
                "without slip (A_R q_dot = 0)"
            )
        for j in walker.lockable_joints:
            if abs(q[j] - lockv[j]) > 1e-9 or abs(qd[j]) > 1e-9:
                raise ValueError(
                    f"state {i} must have {walker.coordinate_names[j]} locked at {lockv[j]} "
                    "rad with zero rate (the state just after a heel strike)"
                )
