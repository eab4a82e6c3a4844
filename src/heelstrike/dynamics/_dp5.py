"""The Dormand-Prince 5(4) scheme of both compiled kernels, written once.

:mod:`heelstrike.dynamics.compiled` (the paper's compass gait) and
:mod:`heelstrike.dynamics.compiled_phased` (described walkers) integrate single support with this
pair and ``solve_ivp``'s conventions. A step of size ``h`` from ``y`` with stages ``k`` (shape
(7, d), ``k[0] = f(y)``) is ``stage(y, h, k, s, tmp); k[s] = f(tmp)`` for ``s = 1..5``,
:func:`solution`, ``k[6] = f(ynew)`` (FSAL) and :func:`error_estimate`; then scipy's
:func:`error_norm` and step control (:func:`grow_factor`, :func:`shrink_factor`).
:func:`initial_step_first` / :func:`initial_step` are Hairer's starting step, split around the
caller's ``f1 = f(y + h0 f0)``. An event's sign change over an accepted step is :func:`crossed`
(``solve_ivp``'s rule); its time is located by the Illinois method (:func:`secant_point`,
:func:`illinois_update`, :func:`bracket_closed`) on the exact Runge-Kutta step of trial length
``tau`` from the step's start (no dense output). :func:`integrator` compiles the step, the
starting step and the event location for one right-hand side.

The expressions keep the kernels' former operation order (results are bit for bit the same);
numba inlines the small functions (``inline="always"``).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from numba import njit

from heelstrike._caching import tolerate_numba_cache_errors
from heelstrike._typing import FloatArray

tolerate_numba_cache_errors()  # numba's cache unwritable (full disk): run uncached

# Dormand-Prince 5(4) tableau (autonomous: no nodes): stage weights A, 5th-order weights B
# (B2 = B7 = 0) and error weights E = B - B* (E2 = 0).
A21 = 1.0 / 5.0
A31, A32 = 3.0 / 40.0, 9.0 / 40.0
A41, A42, A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
A51, A52, A53, A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
A61, A62, A63, A64, A65 = (
    9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0,
)
B1, B3, B4, B5, B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
E1, E3, E4, E5, E6, E7 = (
    71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0,
    -1.0 / 40.0,
)

#: Safety factor, smallest and largest step-size factor of the step control (as scipy).
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
#: Smallest step relative to ``max(1, |t|)`` (s) before the integration is declared failed.
MIN_STEP_RELATIVE = 1e-14
#: Largest Illinois bracket (s) when locating an event: ``1e-13 + 4e-16 |t|``.
EVENT_TIME_TOL = 1e-13

_jit = njit(cache=True, nogil=True, inline="always")


# Numba functions are typed for readers; numba ignores the annotations.
@_jit
def stage(y: FloatArray, h: float, k: FloatArray, s: int, out: FloatArray) -> None:
    """Argument of stage ``s`` (1..5): ``out = y + h sum_j A[s, j] k[j]``, shape (d,)."""
    d = y.shape[0]
    if s == 1:
        for i in range(d):
            out[i] = y[i] + h * A21 * k[0, i]
    elif s == 2:
        for i in range(d):
            out[i] = y[i] + h * (A31 * k[0, i] + A32 * k[1, i])
    elif s == 3:
        for i in range(d):
            out[i] = y[i] + h * (A41 * k[0, i] + A42 * k[1, i] + A43 * k[2, i])
    elif s == 4:
        for i in range(d):
            out[i] = y[i] + h * (A51 * k[0, i] + A52 * k[1, i] + A53 * k[2, i] + A54 * k[3, i])
    else:
        for i in range(d):
            out[i] = y[i] + h * (
                A61 * k[0, i] + A62 * k[1, i] + A63 * k[2, i] + A64 * k[3, i] + A65 * k[4, i]
            )


@_jit
def solution(y: FloatArray, h: float, k: FloatArray, out: FloatArray) -> None:
    """The 5th-order solution ``out = y + h sum_j B[j] k[j]`` (stages 0..5), shape (d,)."""
    for i in range(y.shape[0]):
        out[i] = y[i] + h * (
            B1 * k[0, i] + B3 * k[2, i] + B4 * k[3, i] + B5 * k[4, i] + B6 * k[5, i]
        )


@_jit
def error_estimate(h: float, k: FloatArray, out: FloatArray) -> None:
    """Local error estimate ``out = h sum_j E[j] k[j]`` (needs the FSAL stage ``k[6]``)."""
    for i in range(out.shape[0]):
        out[i] = h * (
            E1 * k[0, i] + E3 * k[2, i] + E4 * k[3, i] + E5 * k[4, i] + E6 * k[5, i]
            + E7 * k[6, i]
        )


@_jit
def error_norm(
    y: FloatArray, ynew: FloatArray, err: FloatArray, rtol: float, atol: float
) -> float:
    """scipy's RMS error norm of ``err / (atol + rtol max(|y|, |y_new|))``; 1e10 if not finite."""
    d = y.shape[0]
    acc = 0.0
    for i in range(d):
        sc = atol + rtol * max(abs(y[i]), abs(ynew[i]))
        r = err[i] / sc
        acc += r * r
    en = math.sqrt(acc / d)
    if not math.isfinite(en):
        return 1e10
    return en


@_jit
def grow_factor(en: float) -> float:
    """Step-size factor after an accepted step with error norm ``en <= 1``."""
    return MAX_FACTOR if en == 0.0 else min(MAX_FACTOR, SAFETY * en**-0.2)


@_jit
def shrink_factor(en: float) -> float:
    """Step-size factor after a rejected step with error norm ``en > 1``."""
    return max(MIN_FACTOR, SAFETY * en**-0.2)


@_jit
def min_step(t: float) -> float:
    """Smallest step (s) at time ``t`` before the integration is declared failed."""
    return MIN_STEP_RELATIVE * max(1.0, abs(t))


@_jit
def initial_step_first(
    y: FloatArray, f0: FloatArray, rtol: float, atol: float
) -> tuple[float, float]:
    """First half of Hairer's starting step: ``(h0, d1)``; the caller evaluates
    ``f1 = f(y + h0 f0)`` (after any clamping of ``h0``) and calls :func:`initial_step`."""
    d = y.shape[0]
    d0 = 0.0
    d1 = 0.0
    for i in range(d):
        sc = atol + abs(y[i]) * rtol
        d0 += (y[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    d0 = math.sqrt(d0 / d)
    d1 = math.sqrt(d1 / d)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    return h0, d1


@_jit
def initial_step(
    y: FloatArray, f0: FloatArray, f1: FloatArray, h0: float, d1: float, rtol: float,
    atol: float,
) -> float:
    """Hairer's starting step for a 5th-order method (as ``solve_ivp``), in s.

    ``h0``, ``d1`` from :func:`initial_step_first`, ``f1 = f(y + h0 f0)``.
    """
    d = y.shape[0]
    d2 = 0.0
    for i in range(d):
        sc = atol + abs(y[i]) * rtol
        d2 += ((f1[i] - f0[i]) / sc) ** 2
    d2 = math.sqrt(d2 / d) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 5.0)
    return min(100.0 * h0, h1)


@_jit
def crossed(g0: float, g1: float, direction: int) -> bool:
    """``solve_ivp``'s rule: up ``g0 <= 0 <= g1``, down ``g0 >= 0 >= g1``."""
    if direction > 0:
        return g0 <= 0.0 and g1 >= 0.0
    return g0 >= 0.0 and g1 <= 0.0


@_jit
def any_crossed(g_old: FloatArray, g_new: FloatArray, dirs: Any, n_ev: int) -> bool:
    """Whether any of the first ``n_ev`` events crossed (:func:`crossed`) over a step."""
    for j in range(n_ev):
        if crossed(g_old[j], g_new[j], dirs[j]):
            return True
    return False


@_jit
def secant_point(lo: float, flo: float, hi: float, fhi: float) -> float:
    """Next trial of the Illinois method in the bracket ``[lo, hi]`` (bisection fallback)."""
    c = (lo * fhi - hi * flo) / (fhi - flo)
    if not (lo < c < hi):
        c = 0.5 * (lo + hi)
    return c


@_jit
def illinois_update(
    lo: float, flo: float, hi: float, fhi: float, side: int, c: float, fc: float
) -> tuple[float, float, float, float, int]:
    """Shrink the bracket with the trial ``(c, fc)``, halving a retained end's value (Illinois).

    Returns the new ``(lo, flo, hi, fhi, side)``.
    """
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
    return lo, flo, hi, fhi, side


@_jit
def bracket_closed(lo: float, hi: float, t: float) -> bool:
    """The event bracket ``[lo, hi]`` (step-relative times, s) is small enough at time ``t``."""
    return hi - lo <= EVENT_TIME_TOL + 4e-16 * abs(t)


class Integrator(NamedTuple):
    """The DP5 drivers of one right-hand side (numba functions, :func:`integrator`).

    - ``step(ctx, y, h, k, tmp, ynew, full)``: one step of size ``h`` (s) from ``y`` with
      ``k[0] = f(y)``; writes ``ynew`` and, with ``full``, ``k[6] = f(ynew)`` (FSAL) and the
      error estimate's components into ``tmp``.
    - ``start_step(ctx, y, k, ktry, tmp, rtol, atol, max_step)``: Hairer's starting step (s),
      its first trial and the result clamped to ``max_step``; ``ktry[0]``, ``tmp``: work space.
    - ``first_event(ctx, y, hh, t, k, ktry, tmp, ynew, ytry, kinds, dirs, n_ev, g_old, g_new)
      -> (j, tau)``: of the events ``kinds[:n_ev]`` whose values crossed from ``g_old`` (at
      ``y``, time ``t``) to ``g_new`` (at ``ynew``, after the accepted step ``hh``; call it
      only if :func:`any_crossed`), the earliest, ``kinds[j]`` at ``t + tau``, each located by
      the Illinois method on the exact step; ``y`` is overwritten with the state there.
    """

    step: Any
    start_step: Any
    first_event: Any


def integrator(rhs: Any, event: Any) -> Integrator:
    """Compile the DP5 drivers for one right-hand side and its events.

    ``rhs(ctx, y, dy)`` writes ``f(y)`` into ``dy`` and ``event(ctx, y, kind)`` returns the
    value of event ``kind`` at ``y`` (numba functions; ``ctx`` is whatever the caller passes
    through). The drivers call them directly (closure constants, not function arguments, which
    would keep the kernels that call the drivers out of numba's disk cache); they are compiled
    into, and cached with, those kernels.
    """
    gen = njit(nogil=True)

    @gen
    def step(
        ctx: Any, y: FloatArray, h: float, k: FloatArray, tmp: FloatArray, ynew: FloatArray,
        full: bool,
    ) -> None:
        stage(y, h, k, 1, tmp)  # stage numbers as literals: numba folds the stage's branch
        rhs(ctx, tmp, k[1])
        stage(y, h, k, 2, tmp)
        rhs(ctx, tmp, k[2])
        stage(y, h, k, 3, tmp)
        rhs(ctx, tmp, k[3])
        stage(y, h, k, 4, tmp)
        rhs(ctx, tmp, k[4])
        stage(y, h, k, 5, tmp)
        rhs(ctx, tmp, k[5])
        solution(y, h, k, ynew)
        if full:
            rhs(ctx, ynew, k[6])
            error_estimate(h, k, tmp)

    @gen
    def start_step(
        ctx: Any, y: FloatArray, k: FloatArray, ktry: FloatArray, tmp: FloatArray, rtol: float,
        atol: float, max_step: float,
    ) -> float:
        h0, d1 = initial_step_first(y, k[0], rtol, atol)
        h0 = min(h0, max_step)
        for i in range(y.shape[0]):
            tmp[i] = y[i] + h0 * k[0, i]
        rhs(ctx, tmp, ktry[0])
        return min(initial_step(y, k[0], ktry[0], h0, d1, rtol, atol), max_step)

    @gen
    def locate(
        ctx: Any, y: FloatArray, hh: float, t: float, kind: int, g0: float, g1: float,
        k: FloatArray, ktry: FloatArray, tmp: FloatArray, ytry: FloatArray,
    ) -> float:
        """Time (s from ``t``) where event ``kind`` goes from ``g0`` at ``y`` to ``g1`` after
        the step of size ``hh``: Illinois on the exact RK step of trial length."""
        lo, flo = 0.0, g0
        hi, fhi = hh, g1
        if flo == 0.0:
            return 0.0
        root = hi
        if fhi == 0.0:
            return root
        side = 0
        for _ in range(200):
            c = secant_point(lo, flo, hi, fhi)
            for r in range(y.shape[0]):
                ktry[0, r] = k[0, r]
            step(ctx, y, c, ktry, tmp, ytry, False)
            fc = event(ctx, ytry, kind)
            root = c
            if fc == 0.0:
                break
            lo, flo, hi, fhi, side = illinois_update(lo, flo, hi, fhi, side, c, fc)
            if bracket_closed(lo, hi, t):
                root = hi if abs(fhi) < abs(flo) else lo
                break
        return root

    @gen
    def first_event(
        ctx: Any, y: FloatArray, hh: float, t: float, k: FloatArray, ktry: FloatArray,
        tmp: FloatArray, ynew: FloatArray, ytry: FloatArray, kinds: Any, dirs: Any, n_ev: int,
        g_old: FloatArray, g_new: FloatArray,
    ) -> tuple[int, float]:
        best = -1
        best_tau = hh
        for j in range(n_ev):
            if crossed(g_old[j], g_new[j], dirs[j]):
                root = locate(ctx, y, hh, t, kinds[j], g_old[j], g_new[j], k, ktry, tmp, ytry)
                if best < 0 or root < best_tau:
                    best = j
                    best_tau = root
        if best >= 0:
            d = y.shape[0]
            if best_tau == hh:
                for r in range(d):
                    y[r] = ynew[r]
            elif best_tau > 0.0:
                for r in range(d):
                    ktry[0, r] = k[0, r]
                step(ctx, y, best_tau, ktry, tmp, ytry, False)
                for r in range(d):
                    y[r] = ytry[r]
        return best, best_tau

    return Integrator(step=step, start_step=start_step, first_event=first_event)
