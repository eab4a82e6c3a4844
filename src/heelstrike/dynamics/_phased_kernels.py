"""The numba functions of the described walkers' kernel.

The model is described in :mod:`heelstrike.dynamics.compiled_phased`.

One source, compiled two ways: by numba's JIT, once for all walkers (the generated functions
arrive as first-class function arguments; ``cache=True``), and, per walker, ahead of time into
an extension module with that walker's generated functions bound (:func:`bound_functions`,
:mod:`heelstrike.dynamics._aot`), which later processes load without numba. The Python API,
the float-configuration and impact-row layouts and the status and event codes are in
:mod:`heelstrike.dynamics.compiled_phased`, which imports this module only when it needs numba.
"""

from __future__ import annotations

import contextlib
import math
import threading
import types
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit
from numba import types as nbt
from numba.core import cgutils
from numba.core.errors import NumbaExperimentalFeatureWarning
from numba.extending import intrinsic

from heelstrike._caching import tolerate_numba_cache_errors
from heelstrike._typing import FloatArray, IntArray
from heelstrike.dynamics import _dp5 as dp5
from heelstrike.dynamics._compass_kernels import lift_velocity_scale_jit, lifts_jit
from heelstrike.dynamics.compiled import (
    COMPLETED,
    FELL_BACKWARD,
    FELL_FORWARD,
    INTEGRATION_FAILED,
    LOST_CONTACT,
    NO_HEEL_STRIKE,
    TRAILING_FOOT_STAYS,
)
from heelstrike.dynamics.compiled_phased import (
    _C_EREF,
    _C_GAIN,
    _C_GUARD,
    _C_KD,
    _C_KP,
    _C_LAW,
    _C_LEG,
    _C_MU,
    _C_PUSH,
    _C_RST,
    _C_RSW,
    _C_SLOPE,
    _C_TANG,
    _C_THR,
    _C_TJ,
    _C_TRAIL,
    _C_UMAX,
    _EV_ARMED,
    _EV_BACK,
    _EV_FAIL,
    _EV_FLEXED,
    _EV_FWD,
    _EV_KNEE,
    _EV_LOST,
    _EV_NONE,
    _EV_SLIP,
    _EV_STRIKE,
    _I_HEAD,
    _KIND_HEEL,
    _KIND_KNEE,
    _LAW_ENERGY,
    _LAW_POSTURE,
    _MODE_GRAZE,
    _MODE_PENETRATING,
    _MODE_SEPARATE,
    _NO_CONSISTENT_ASSIGNMENT,
    _NO_SWAP,
    SLIPPED,
)
from heelstrike.models import _contact
from heelstrike.models._codegen_numba import NumbaModel, signatures
from heelstrike.models._contact import CONTACT_TOLERANCE

tolerate_numba_cache_errors()  # numba's cache unwritable (full disk): run uncached

#: The graze rule (:func:`heelstrike.models._contact.grazes`), compiled.
grazes_jit: Any = njit(cache=True, nogil=True, inline="always")(_contact.grazes)

_SIGNATURES = signatures()
_DYN_T = nbt.FunctionType(_SIGNATURES["dynamics"])
_CON_T = nbt.FunctionType(_SIGNATURES["contacts"])
_SWP_T = nbt.FunctionType(_SIGNATURES["swap"])
_GRD_T = nbt.FunctionType(_SIGNATURES["heel_strike_guard"])


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


#: :func:`_gauss` inlined into the right-hand side (every array crossing a call costs two
#: atomic reference-count updates: ~20% of ``_rhs``)
_gauss_inline: Any = njit(cache=True, nogil=True, inline="always")(_gauss.py_func)


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


_EPS = float(np.finfo(np.float64).eps)


def _borrow_typer(typingctx: Any, arr: Any) -> Any:
    """A view of ``arr`` without a memory-info pointer: passing it costs no atomic reference
    counting (``NRT_incref``/``NRT_decref`` on every array crossing a call were ~60% of the
    kernel's time). The caller must keep ``arr`` itself alive while the view is used, and no
    view may be returned or stored. Built from numba internals (``make_array``, ``cgutils``):
    checked with the numba version pinned in ``.ci/constraints.txt``
    (``tests/test_kernel_work_arrays.py``: runs are bit-identical, serial and threaded)."""
    if not isinstance(arr, nbt.Array):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        out = context.make_array(signature.args[0])(context, builder, value=args[0])
        out.meminfo = cgutils.get_null_value(out.meminfo.type)
        out.parent = cgutils.get_null_value(out.parent.type)
        return out._getvalue()

    return arr(arr), codegen


_borrow: Any = intrinsic(_borrow_typer)


@njit(cache=True, nogil=True)
def independent_rows(A: FloatArray, k: int) -> bool:
    """Whether the first ``k`` rows of ``A`` (shape (>= k, n)) are linearly independent.

    numpy's ``matrix_rank`` rule: every singular value of ``A[:k]`` above
    ``max(k, n) eps sigma_max``. The singular values are the row norms after one-sided Jacobi
    rotations of the rows (Hestenes; accurate to round-off for these few short rows), so the
    kernel calls no LAPACK (whose bindings numba loads from scipy at run time).
    """
    n = A.shape[1]
    if k == 0:
        return True
    if k > n:
        return False
    U = A[:k].copy()
    for _ in range(64):  # sweeps; converges quadratically, a handful suffice
        rotated = False
        for i in range(k - 1):
            for j in range(i + 1, k):
                a = 0.0
                b = 0.0
                c = 0.0
                for m in range(n):
                    a += U[i, m] * U[i, m]
                    b += U[j, m] * U[j, m]
                    c += U[i, m] * U[j, m]
                if abs(c) <= _EPS * math.sqrt(a * b):
                    continue  # orthogonal to working precision (or a zero row)
                rotated = True
                zeta = (b - a) / (2.0 * c)
                t = (1.0 if zeta >= 0.0 else -1.0) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                cs = 1.0 / math.sqrt(1.0 + t * t)
                sn = cs * t
                for m in range(n):
                    ui = U[i, m]
                    uj = U[j, m]
                    U[i, m] = cs * ui - sn * uj
                    U[j, m] = sn * ui + cs * uj
        if not rotated:
            break
    smax = 0.0
    smin = math.inf
    for i in range(k):
        sq = 0.0
        for m in range(n):
            sq += U[i, m] * U[i, m]
        sv = math.sqrt(sq)
        smax = max(smax, sv)
        smin = min(smin, sv)
    return smin > smax * max(k, n) * _EPS


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
@njit(cache=True, nogil=True, inline="always")
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


@njit(cache=True, nogil=True, inline="always")
def _forces(
    dyn: Any, p: FloatArray, cfg: FloatArray, q: FloatArray, qd: FloatArray, M: FloatArray,
    h: FloatArray,
) -> float:
    """``M``, ``h`` and the actuator torque ``u`` of the joint law; ``h <- h - B u``.

    The law (``cfg[_C_LAW]``, see :mod:`heelstrike.dynamics.compiled_phased`) acts across
    joint ``j = cfg[_C_TJ]`` (none if ``j < 0``), saturated at ``cfg[_C_UMAX]``: the posture
    law ``-kp (q_2 + q_j - ref) - kd (q_2_dot + q_j_dot)`` (torso), the joint PD law
    ``-kp (q_j - ref) - kd q_j_dot`` (swing-leg PD) or energy tracking
    ``-k (T + V - E_ref) q_j_dot`` (``V`` returned by the generated ``dynamics``).
    Returns the actuator power ``(B u) . q_dot`` (W).
    """
    V = dyn(q, qd, p, cfg[_C_SLOPE], M, h)
    tj = int(cfg[_C_TJ])
    if tj < 0:
        return 0.0
    law = int(cfg[_C_LAW])
    if law == _LAW_POSTURE:
        u = -cfg[_C_KP] * (q[2] + q[tj] - cfg[_C_TANG]) - cfg[_C_KD] * (qd[2] + qd[tj])
    elif law == _LAW_ENERGY:
        u = -cfg[_C_GAIN] * (_quad(M, qd) + V - cfg[_C_EREF]) * qd[tj]
    else:
        u = -cfg[_C_KP] * (q[tj] - cfg[_C_TANG]) - cfg[_C_KD] * qd[tj]
    umax = cfg[_C_UMAX]
    if u > umax:
        u = umax
    elif u < -umax:
        u = -umax
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
    _gauss_inline(Mr, Fr, m, 1)
    for a in range(m):
        dx[a] = x[m + a]
        dx[m + a] = Fr[a, 0]
    dx[2 * m] = power


@njit(cache=True, nogil=True)
def _event_work(n: int) -> Any:
    """Work space of :func:`_event_value`: ``(q, qd, M, h, A, rate, c, dx, Mr, Fr, W, b)``."""
    return (np.empty(n), np.empty(n), np.empty((n, n)), np.empty(n), np.empty((2, 2, n)),
            np.empty((2, 2)), np.empty((2, 2)), np.empty(2 * n + 1), np.empty((n, n)),
            np.empty((n, 1)), np.empty((2, 2)), np.empty((2, 1)))


@njit(cache=True, nogil=True)
def _reaction(
    dyn: Any, con: Any, p: FloatArray, cfg: FloatArray, free: IntArray, qref: FloatArray,
    x: FloatArray, ew: Any,
) -> tuple[float, float]:
    """Ground force on the stance foot ``(tangential, normal)`` (N) at the reduced state ``x``.

    The base rows of ``M q_ddot + h - B u = A^T lambda + E^T mu``, as
    :meth:`heelstrike.dynamics.single_support.SingleSupport.ground_reaction`:
    ``A[:, :2]^T lambda = (M q_ddot + h - B u)[:2]`` with the single-support accelerations
    ``q_ddot = J theta_ddot`` of :func:`_rhs`, so that the holding torques ``mu`` of the locked
    joints are part of the balance.
    """
    q, qd, M, h, A, rate, c = ew[0], ew[1], ew[2], ew[3], ew[4], ew[5], ew[6]
    dx, Mr, Fr, W, b = ew[7], ew[8], ew[9], ew[10], ew[11]
    _rhs(dyn, p, cfg, free, qref, x, dx, q, qd, M, h, Mr, Fr)  # h is h - B u here
    m = free.shape[0]
    R = cfg[_C_RST]
    for r in range(2):  # (M q_ddot + h - B u)[r]: q_ddot[0] = -R theta_dd[0], q_ddot[1] = 0
        s = h[r] - R * M[r, 0] * dx[m]
        for a in range(m):
            s += M[r, free[a]] * dx[m + a]
        b[r, 0] = s
    con(q, qd, p, A, rate, c)
    for r in range(2):
        for j in range(2):
            W[r, j] = A[0, j, r]
    _gauss(W, b, 2, 1)
    return b[0, 0], b[1, 0]


@njit(cache=True, nogil=True)
def _event_value(
    kind: int, dyn: Any, con: Any, gua: Any, p: FloatArray, cfg: FloatArray, free: IntArray,
    qref: FloatArray, swing_idx: IntArray, lockv: FloatArray, x: FloatArray, ew: Any,
) -> float:
    """The witness of event ``kind`` at the reduced state ``x``.

    The heel strike's (``_EV_STRIKE``) is minus the swing foot's clearance, or, for a walker
    declaring its guard (``cfg[_C_GUARD] == 1``), the declared guard ``gua(q, p)``; its arming
    (``_EV_ARMED``) is then the stance angle (the compass gait's midstance) instead of
    ``min(stance angle, swing foot ahead, clearance)``.
    """
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
    q, qd = ew[0], ew[1]
    _unpack(x, free, qref, cfg[_C_RST], q, qd)
    if cfg[_C_GUARD] != 0.0 and (kind == _EV_ARMED or kind == _EV_STRIKE):
        return float(x[0]) if kind == _EV_ARMED else gua(q, p)
    if kind == _EV_ARMED or kind == _EV_STRIKE:
        A, rate, c = ew[4], ew[5], ew[6]
        con(q, qd, p, A, rate, c)
        clearance = c[1, 1] - cfg[_C_RSW]
        if kind == _EV_STRIKE:
            return -clearance
        return min(x[0], min(c[0, 0] - c[1, 0], clearance))
    lam_t, lam_n = _reaction(dyn, con, p, cfg, free, qref, x, ew)
    if kind == _EV_LOST:
        return lam_n
    return cfg[_C_MU] * lam_n - abs(lam_t)


# ---------------------------------------------------------------------------------------------
# integrator: the drivers of heelstrike.dynamics._dp5 (starting step, event location) with the
# context tuple ``(dyn, con, p, cfg, free, qref, swing_idx, lockv, q, qd, M, h, Mr, Fr, ew, gua)``
# ---------------------------------------------------------------------------------------------
@njit(nogil=True, inline="always")
def _ctx_rhs(ctx: Any, x: FloatArray, dx: FloatArray) -> None:
    dyn, _, p, cfg, free, qref, _, _, q, qd, M, h, Mr, Fr, _, _ = ctx
    _rhs(dyn, p, cfg, free, qref, x, dx, q, qd, M, h, Mr, Fr)


@njit(nogil=True, inline="always")
def _ctx_event(ctx: Any, x: FloatArray, kind: int) -> float:
    dyn, con, p, cfg, free, qref, swing_idx, lockv = ctx[:8]
    return _event_value(kind, dyn, con, ctx[15], p, cfg, free, qref, swing_idx, lockv, x,
                        ctx[14])


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
    _unpack(x, free, qref, R, S[ns, 5:5 + n], S[ns, 5 + n:5 + 2 * n])  # into the row
    S[ns, 0] = t
    S[ns, 1] = x[2 * free.shape[0]]
    S[ns, 2] = step
    S[ns, 3] = leg
    S[ns, 4] = phase
    return S, ns + 1


@njit(cache=True, nogil=True)
def _same_row(S: FloatArray, i: int, j: int) -> bool:
    """Whether sample rows ``i`` and ``j`` of ``S`` are equal in every column."""
    for c in range(S.shape[1]):
        if S[i, c] != S[j, c]:
            return False
    return True


@njit(cache=True, nogil=True)
def _segment(
    dyn: Any, con: Any, gua: Any, p: FloatArray, cfg: FloatArray, free: IntArray, qref: FloatArray,
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
    if ns > 1 and _same_row(S, ns - 1, ns - 2):
        ns -= 1  # the previous segment ended here (same step, phase, state): list it once
    if t_limit <= t:
        return _EV_NONE, t, S, ns
    qo = np.empty(n)
    qdo = np.empty(n)
    Mo = np.empty((n, n))
    hvo = np.empty(n)
    Mro = np.empty((m, m))
    Fro = np.empty((m, 1))
    ewo = _event_work(n)
    ko = np.empty((7, d))
    ktryo = np.empty((7, d))
    wo = np.empty((5, d))
    go = np.empty((2, n_ev))
    ew = (_borrow(ewo[0]), _borrow(ewo[1]), _borrow(ewo[2]), _borrow(ewo[3]), _borrow(ewo[4]),
          _borrow(ewo[5]), _borrow(ewo[6]), _borrow(ewo[7]), _borrow(ewo[8]), _borrow(ewo[9]),
          _borrow(ewo[10]), _borrow(ewo[11]))
    # the owners stay referenced (``keep``) while the borrowed views are in use
    keep = (qo, qdo, Mo, hvo, Mro, Fro, ewo, ko, ktryo, wo, go)
    return _integrate(
        dyn, con, gua, _borrow(p), _borrow(cfg), _borrow(free), _borrow(qref), _borrow(swing_idx),
        _borrow(lockv), _borrow(y), t, t_limit, _borrow(kinds), _borrow(dirs), rtol, atol,
        max_step, S, ns, step, leg, phase, _borrow(qo), _borrow(qdo), _borrow(Mo), _borrow(hvo),
        _borrow(Mro), _borrow(Fro), ew, _borrow(ko), _borrow(ktryo), _borrow(wo), _borrow(go),
        keep,
    )


@njit(cache=True, nogil=True)
def _integrate(
    dyn: Any, con: Any, gua: Any, p: FloatArray, cfg: FloatArray, free: IntArray, qref: FloatArray,
    swing_idx: IntArray, lockv: FloatArray, y: FloatArray, t: float, t_limit: float,
    kinds: IntArray, dirs: IntArray, rtol: float, atol: float, max_step: float, S: FloatArray,
    ns: int, step: int, leg: int, phase: int, q: FloatArray, qd: FloatArray, M: FloatArray,
    hv: FloatArray, Mr: FloatArray, Fr: FloatArray, ew: Any, k: FloatArray, ktry: FloatArray,
    w: FloatArray, g: FloatArray, keep: Any,
) -> tuple[int, float, FloatArray, int]:
    """The body of :func:`_segment` on borrowed work arrays (see :func:`_borrow`)."""
    d = y.shape[0]
    R = cfg[_C_RST]
    n_ev = kinds.shape[0]
    ctx = (dyn, con, p, cfg, free, qref, swing_idx, lockv, q, qd, M, hv, Mr, Fr, ew, gua)
    tmp = w[0]
    ynew = w[1]
    ytry = w[2]
    g_old = g[0]
    g_new = g[1]
    _rhs(dyn, p, cfg, free, qref, y, k[0], q, qd, M, hv, Mr, Fr)
    for j in range(n_ev):
        g_old[j] = _event_value(kinds[j], dyn, con, gua, p, cfg, free, qref, swing_idx, lockv,
                                y, ew)
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
            g_new[j] = _event_value(kinds[j], dyn, con, gua, p, cfg, free, qref, swing_idx,
                                    lockv, ynew, ew)
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
    _DYN_T, _CON_T, _SWP_T, _GRD_T, _F[:, ::1], _F[:, ::1], _F[::1], _F[::1], nbt.int64,
    nbt.int64[::1], nbt.int64[::1], _F[:, ::1], _F, _F, _F, _F,
)


def _walk_py(
    dyn: Any, con: Any, swp: Any, gua: Any, P: FloatArray, CFG: FloatArray, q0: FloatArray,
    qd0: FloatArray, steps: int, stance_locks: IntArray, swing_locks: IntArray,
    LOCKV: FloatArray, max_duration: float, rtol: float, atol: float, max_step: float,
) -> tuple[int, FloatArray, int, FloatArray, int, FloatArray, FloatArray, FloatArray]:
    """The whole phased walk (see the module docstring).

    ``P``, ``CFG`` and ``LOCKV`` (shapes (s, n_p), (s, n_cfg), (s, n)) hold the parameter
    values, float configuration and lock angles of the ``s`` walkers of a period (``s = 1``,
    or 2 for a walker whose legs differ: the walker and the walker after its leg swap, which
    share the generated functions): step ``k`` is taken with row ``k mod s``.

    Returns ``(status, samples, n_samples, impacts, n_impacts, step_starts, q, q_dot)``;
    ``step_starts`` rows are ``(t, work, q)`` at the start of every step.
    """
    n = q0.shape[0]
    period = P.shape[0]
    p = P[0]
    cfg = CFG[0]
    lockv = LOCKV[0]
    friction = not math.isnan(cfg[_C_MU])  # the same for every walker of the period
    declared = cfg[_C_GUARD] != 0.0  # the walker's declared heel-strike guard
    graze_rule = cfg[_C_TRAIL] != 0.0  # its trailing foot may lift or graze (the projector)
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
    ew = _event_work(n)
    for kstep in range(steps):
        p = P[kstep % period]  # the walker taking this step
        cfg = CFG[kstep % period]
        lockv = LOCKV[kstep % period]
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
                ev, t, S, ns = _segment(dyn, con, gua, p, cfg, free, qref, swing_idx, lockv, y,
                                        t, t_limit, kinds, dirs, rtol, atol, max_step, S, ns,
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
            want, rearming = _EV_ARMED, False
            while True:
                qref = q.copy()
                y = np.empty(2 * free.shape[0] + 1)
                _pack(q, qd, free, work, y)
                if want == _EV_ARMED and not rearming:
                    armed = _event_value(_EV_ARMED, dyn, con, gua, p, cfg, free, qref, none_idx,
                                         lockv, y, ew)
                    # armed at the start: skipped (a declared guard's midstance at q_2 >= 0)
                    if armed > 0.0 or (declared and armed == 0.0):
                        want = _EV_STRIKE
                        continue
                rearming = False
                kinds, dirs = _kinds(want, friction)
                ev, t, S, ns = _segment(dyn, con, gua, p, cfg, free, qref, none_idx, lockv, y,
                                        t, t_limit, kinds, dirs, rtol, atol, max_step, S, ns,
                                        kstep, leg, 1)
                _unpack(y, free, qref, cfg[_C_RST], q, qd)
                work = y[2 * free.shape[0]]
                ended = _outcome(ev, want)
                if ended >= 0:
                    break
                if want == _EV_ARMED:
                    want = _EV_STRIKE
                    continue
                con(q, qd, p, Ac, rate, cc)
                if declared:
                    # a declared guard's crossing with the swing foot off the ground is no
                    # heel strike (BuiltWalker._declared_strike_phase): arm it anew
                    if abs(cc[1, 1] - cfg[_C_RSW]) <= CONTACT_TOLERANCE * cfg[_C_LEG]:
                        break
                # a heel strike only with the swing foot ahead (BuiltWalker.strike_not_ahead);
                # level with or behind the stance foot, arm the strike anew (QA sweep 11, #4)
                elif cc[0, 0] - cc[1, 0] > CONTACT_TOLERANCE * (cfg[_C_LEG] - cfg[_C_RSW]):
                    break
                want, rearming = _EV_ARMED, True
        if ended >= 0:
            status = ended
            break
        # -- heel strike: leading foot bilateral, trailing foot by complementarity ------------
        _forces(dyn, p, cfg, q, qd, M, hv)
        con(q, qd, p, Ac, rate, cc)
        push_work = 0.0
        if not math.isnan(cfg[_C_PUSH]):
            # push-off impulse p e(q2) at the trailing contact, the locked joints held:
            # M dq_dot = A_R^T p e(q2) + L^T lambda, L dq_dot = 0, i.e. dq_dot = P_a M^-1 f
            # (heelstrike.dynamics.actuation.push_off_velocity_change)
            ex = -cfg[_C_PUSH] * math.sin(q[2])
            ey = cfg[_C_PUSH] * math.cos(q[2])
            dq = np.empty((n, 1))
            for i in range(n):
                dq[i, 0] = Ac[0, 0, i] * ex + Ac[0, 1, i] * ey
            _gauss(M.copy(), dq, n, 1)
            if nl > 0:
                lock_rows = np.zeros((nl, n))
                for c in range(nl):
                    lock_rows[c, all_locks[c]] = 1.0
                free_dq = dq[:, 0].copy()
                _impact(M, lock_rows, nl, free_dq, v_c, lam)
                for i in range(n):
                    dq[i, 0] = free_dq[i] - v_c[i]
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
            if graze_rule:
                # the projector with the striking foot's (and lock) rows only; the trailing
                # foot's mode by the sign of its normal velocity (hybrid.simulate's rule)
                _impact(M, rows, kb, qd, v_c, lam)
                vn = 0.0
                for i in range(n):
                    vn += Ac[0, 1, i] * (qd[i] - v_c[i])
                scale = lift_velocity_scale_jit(cfg[_C_LEG], qd[2:])
                mode = _MODE_SEPARATE if vn >= 0.0 else _MODE_PENETRATING
                if grazes_jit(vn, scale):
                    mode = _MODE_GRAZE
                break
            if trial == 1:
                rows[kb] = Ac[0, 1]
                rows[kb + 1] = Ac[0, 0]
                k_rows = kb + 2
            elif trial == 2:
                rows[kb] = Ac[0, 1]
                k_rows = kb + 1
            if not independent_rows(rows, k_rows):
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
        if mode != _MODE_GRAZE and (
                mode != _MODE_SEPARATE
                or not lifts_jit(vn, lift_velocity_scale_jit(cfg[_C_LEG], qd[2:]))):
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
        lockv = LOCKV[(kstep + 1) % period]  # the next step's walker's lock angles
        for c in range(nl):
            q[all_locks[c]] = lockv[all_locks[c]]
            qd[all_locks[c]] = 0.0
        leg = 1 - leg
    return status, S, ns, Imp, ni, starts, q, qd


#: The walk kernel's dispatcher; compiled for ``_WALK_SIG`` only (see :func:`_walk_kernel`), and
#: called with that signature by the ensemble kernel.
_WALK_JIT: Any = njit(cache=True, nogil=True)(_walk_py)
_KERNEL: list[Any] = []
#: Held while a JIT kernel is compiled (re-entrant: the ensemble kernel compiles the walk's).
_COMPILE_LOCK = threading.RLock()


def _walk_kernel() -> Any:
    """``_walk_py`` compiled for first-class function arguments (once; numba disk cache).

    Without a numba cache (first use) the compilation is announced with an estimate, followed
    and reported on stderr (:func:`heelstrike._firstuse.first_use`).
    """
    with _COMPILE_LOCK:
        if not _KERNEL:
            _compile_walk_kernel()
    return _KERNEL[0]


def _compile_walk_kernel() -> None:
    disp: Any = _WALK_JIT
    try:
        cached = Path(disp._cache._cache_file._index_path).is_file()
    except AttributeError:  # pragma: no cover - numba internals moved: stay quiet
        cached = True
    with _announced(disp, "the walk kernel of every described walker", quiet=cached):
        with warnings.catch_warnings():  # first-class function types are numba's "experimental"
            warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)
            disp.compile(_WALK_SIG)
    disp.disable_compile()  # the generated functions convert to the compiled signature
    _KERNEL.append(disp)


def _announced(disp: Any, what: str, *, quiet: bool, kind: str = "jit-kernel") -> Any:
    """:func:`heelstrike._firstuse.first_use` for a JIT kernel of this module (size: the lines
    of the modules it compiles; the cache: numba's for this module)."""
    from heelstrike._firstuse import first_use
    from heelstrike.dynamics._aot import _source_lines

    if quiet:  # loaded from numba's cache: no build, no probe
        return contextlib.nullcontext()
    cache = getattr(getattr(disp, "_cache", None), "_cache_path", None) or "numba's cache"
    size = _source_lines((__name__, "heelstrike.dynamics._dp5", "heelstrike.models._contact"))
    return first_use(f"{what}, compiled by numba's JIT", kind=kind, size=size,
                     cache=cache, built=f"{disp.py_func.__name__} (numba JIT)", quiet=quiet)


# ---------------------------------------------------------------------------------------------
# ensembles: many walkers (initial states) in one compiled call
# ---------------------------------------------------------------------------------------------
@njit(cache=True, nogil=True)
def _rows_from(A: FloatArray, r: int) -> FloatArray:
    """``A``'s rows rolled to start at row ``r`` (``A[(r + j) mod s]``, C order)."""
    s = A.shape[0]
    out = np.empty_like(A)
    for j in range(s):
        out[j] = A[(r + j) % s]
    return out


def _ensemble_py(
    dyn: Any, con: Any, swp: Any, gua: Any, P: FloatArray, CFG: FloatArray, Q0: FloatArray,
    QD0: FloatArray, steps: int, stance_locks: IntArray, swing_locks: IntArray,
    LOCKV: FloatArray, max_duration: float, rtol: float, atol: float, max_step: float,
    sec_q: IntArray, sec_v: IntArray, target: FloatArray, stop_tol: float, i0: int, i1: int,
    status: IntArray, taken: IntArray, Qf: FloatArray, QDf: FloatArray,
) -> None:
    """Walk walkers ``i0 <= i < i1`` (rows of ``Q0``, ``QD0``) for up to ``steps`` steps.

    Every step is one call of the walk kernel (``steps = 1``) from the previous post-impact
    state, step ``k`` with row ``k mod s`` of ``P``, ``CFG`` and ``LOCKV`` (the ``s`` walkers
    of a period, as :func:`_walk_py`), so a walker can stop on arrival near ``target`` (section
    norm ``< stop_tol`` after whole periods, ``k mod s = 0``; no stop if ``stop_tol <= 0``).
    Writes ``status``, heel strikes ``taken`` and the final state.
    """
    nq = sec_q.shape[0]
    nv = sec_v.shape[0]
    period = P.shape[0]
    for i in range(i0, i1):
        q = Q0[i].copy()
        qd = QD0[i].copy()
        st = COMPLETED
        k = 0
        while k < steps:
            r = k % period
            Pk = P if r == 0 else _rows_from(P, r)
            CFGk = CFG if r == 0 else _rows_from(CFG, r)
            LOCKVk = LOCKV if r == 0 else _rows_from(LOCKV, r)
            s, _S, _ns, Imp, ni, _starts, qn, qdn = _WALK_JIT(
                dyn, con, swp, gua, Pk, CFGk, q, qd, 1, stance_locks, swing_locks, LOCKVk,
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
            if stop_tol > 0.0 and k % period == 0:
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
    _DYN_T, _CON_T, _SWP_T, _GRD_T, _F[:, ::1], _F[:, ::1], _F[:, ::1], _F[:, ::1], nbt.int64,
    nbt.int64[::1], nbt.int64[::1], _F[:, ::1], _F, _F, _F, _F, nbt.int64[::1], nbt.int64[::1],
    _F[::1], _F, nbt.int64, nbt.int64, nbt.int64[::1], nbt.int64[::1], _F[:, ::1], _F[:, ::1],
)
_ENS_KERNEL: list[Any] = []


def _ensemble_kernel() -> Any:
    """``_ensemble_py`` compiled for first-class function arguments (once; numba disk cache)."""
    with _COMPILE_LOCK:  # threads of one ensemble may ask at once
        if not _ENS_KERNEL:
            _walk_kernel()
            disp: Any = njit(cache=True, nogil=True)(_ensemble_py)
            try:
                cached = Path(disp._cache._cache_file._index_path).is_file()
            except AttributeError:  # pragma: no cover - numba internals moved: stay quiet
                cached = True
            with _announced(disp, "the ensemble kernel of every described walker",
                            quiet=cached, kind="jit-ensemble"), warnings.catch_warnings():
                warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)
                disp.compile(_ENS_SIG)
            disp.disable_compile()
            _ENS_KERNEL.append(disp)
    return _ENS_KERNEL[0]


# ---------------------------------------------------------------------------------------------
# one walker's kernels
# ---------------------------------------------------------------------------------------------
def _uncached_namespace() -> dict[str, Any]:
    """This module's numba functions recompiled without numba's disk cache, calling each other.

    A kernel with a walker's generated functions bound specialises every function they are
    passed to on that walker's types; cached, those specialisations would go into this
    module's numba cache, whose index then names the walker's generated module, which other
    processes cannot import. The copies share one globals dict, so they call each other, never
    the cached originals (the DP5 drivers are rebuilt on the copies).
    """
    ns = dict(globals())
    for name, obj in globals().items():
        py_func = getattr(obj, "py_func", None)
        if isinstance(py_func, types.FunctionType) and py_func.__module__ == __name__:
            options = {k: v for k, v in obj.targetoptions.items() if k != "cache"}
            copy = types.FunctionType(py_func.__code__, ns, py_func.__name__,
                                      py_func.__defaults__, py_func.__closure__)
            ns[name] = njit(**options)(copy)
    ns["_ensemble_py"] = types.FunctionType(_ensemble_py.__code__, ns, "_ensemble_py")
    ns["_ode"] = dp5.integrator(ns["_ctx_rhs"], ns["_ctx_event"])
    return ns


def bound_functions(model: NumbaModel) -> dict[str, Any]:
    """The walk and ensemble kernels with one walker's generated functions bound.

    For the ahead-of-time build (an exported function takes arrays and numbers only): the
    walker's ``dynamics``, ``contacts``, ``swap`` and ``heel_strike_guard`` are constants of
    uncached compiles of ``_walk_py`` and ``_ensemble_py`` (:func:`_uncached_namespace`; their
    code unchanged). Arguments and results are those of the JIT kernels without the four
    functions
    (:data:`heelstrike.dynamics.compiled_phased.AOT_EXPORTS`).
    """
    dyn, con, swp, gua = model.dynamics, model.contacts, model.swap, model.heel_strike_guard
    ns = _uncached_namespace()
    walk = ns["_WALK_JIT"]
    ensemble = njit(nogil=True)(ns["_ensemble_py"])

    def walk_bound(
        P: FloatArray, CFG: FloatArray, q0: FloatArray, qd0: FloatArray, steps: int,
        stance_locks: IntArray, swing_locks: IntArray, LOCKV: FloatArray, max_duration: float,
        rtol: float, atol: float, max_step: float,
    ) -> Any:
        return walk(dyn, con, swp, gua, P, CFG, q0, qd0, steps, stance_locks, swing_locks, LOCKV,
                    max_duration, rtol, atol, max_step)

    def ensemble_bound(
        P: FloatArray, CFG: FloatArray, Q0: FloatArray, QD0: FloatArray, steps: int,
        stance_locks: IntArray, swing_locks: IntArray, LOCKV: FloatArray, max_duration: float,
        rtol: float, atol: float, max_step: float, sec_q: IntArray, sec_v: IntArray,
        target: FloatArray, stop_tol: float, i0: int, i1: int, status: IntArray,
        taken: IntArray, Qf: FloatArray, QDf: FloatArray,
    ) -> None:
        ensemble(dyn, con, swp, gua, P, CFG, Q0, QD0, steps, stance_locks, swing_locks, LOCKV,
                 max_duration, rtol, atol, max_step, sec_q, sec_v, target, stop_tol, i0, i1,
                 status, taken, Qf, QDf)

    return {"walk": walk_bound, "ensemble": ensemble_bound}


class JitBound:
    """One walker's kernels through numba's JIT: ``walk`` and ``ensemble`` with the arguments
    of :func:`bound_functions`' (the generated functions passed first, to the one compile for
    all walkers)."""

    def __init__(self, model: NumbaModel) -> None:
        self.functions = (model.dynamics, model.contacts, model.swap, model.heel_strike_guard)

    def walk(self, *args: Any) -> Any:
        return _walk_kernel()(*self.functions, *args)

    def ensemble(self, *args: Any) -> None:
        _ensemble_kernel()(*self.functions, *args)
