"""The one natural-parameter continuation of gaits, with step control.

Every continuation of heelstrike runs :func:`follow`: the gait maps (slope, foot radius, a
described walker's parameter), the described walkers' search from the walker file's own gait,
:func:`~heelstrike.analysis.limit_cycle.continue_limit_cycle` (the bifurcation branch) and the
powered searches (slope and target). A caller supplies ``solve(value, guess, max_iter)``, its
Newton corrector at one parameter value; :func:`follow` predicts (secant through the last two
accepted points), corrects, and controls the sub-step, so the gaits reached at the targets are
those of one branch whatever the targets are.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from heelstrike._typing import FloatArray
from heelstrike.analysis.limit_cycle import GaitNotFoundError

__all__ = [
    "MAX_JUMP",
    "MIN_STEP_FRACTION",
    "PARAMETER_STEP",
    "SLOPE_STEP",
    "SLOW_ITER",
    "STEP_MAX_ITER",
    "Point",
    "Solve",
    "follow",
    "follow_both_ways",
]

#: The maps' step control: the largest sub-step along the slope (rad; the grid's slopes are
#: reached through sub-steps no longer than this whatever the grid), the smallest sub-step as a
#: fraction of the largest (below it the branch ends: a fold or a lost gait), the Newton
#: iterations allowed per sub-step, the iterations above which the next sub-step is halved, and
#: the largest corrector distance ``|z - z_predicted|`` (section units, rad and rad/s) of an
#: accepted sub-step (a larger one is a jump to another gait family). The smallest sub-step is
#: 1/1024 of the largest (0.00024 deg of slope): near McGeer's wheel the gaits change fast
#: with the slope (at R = 0.9 m the impact angle goes from 15 to 41 deg between 0.01 and
#: 0.107 deg), and with 1/32 the first sub-step's jump ended the branch there, so the map
#: said "no gait" where a stable one exists (QA sweep 13); at a true fold the five more
#: halvings cost a few failed Newton solves.
SLOPE_STEP = float(np.deg2rad(0.25))
MIN_STEP_FRACTION = 1.0 / 1024.0
STEP_MAX_ITER = 10
SLOW_ITER = 5
MAX_JUMP = 0.05
#: Iterations at or below which an accepted sub-step doubles the next one.
FAST_ITER = 3
#: Largest sub-step of a continuation in a described walker's parameter, relative to
#: ``max(1, |base value|, max |values|)`` (SI units).
PARAMETER_STEP = 0.05


@dataclass(frozen=True, kw_only=True)
class Point:
    """An accepted point of a continuation.

    Attributes
    ----------
    value : float
        The parameter value.
    z : ndarray, shape (d,)
        The solution there (a fixed point on the section, possibly with extra unknowns).
    mnr : float
        Smallest real Floquet multiplier (NaN if none is real, or not computed).
    gait : object
        The solver's own result at this point.
    """

    value: float
    z: FloatArray
    mnr: float
    gait: Any


#: ``solve(value, guess, max_iter) -> (gait, solution, Newton iterations, smallest real
#: multiplier)``; raises one of ``follow``'s ``failures`` where it finds no solution.
Solve = Callable[[float, FloatArray, int], tuple[Any, FloatArray, int, float]]


def follow(
    solve: Solve,
    start: Point,
    targets: Sequence[float],
    h_max: float,
    *,
    h_min: float | None = None,
    first_step: float | None = None,
    max_iter: int = STEP_MAX_ITER,
    fast_iter: int | None = FAST_ITER,
    slow_iter: int | None = SLOW_ITER,
    max_jump: float = MAX_JUMP,
    bound: Callable[[FloatArray], FloatArray] | None = None,
    failures: tuple[type[BaseException], ...] = (GaitNotFoundError,),
    reach_tol: float = 1e-12,
) -> tuple[list[Point | None], list[Point]]:
    """Natural-parameter continuation from ``start`` through ``targets`` with step control.

    ``targets`` are reached in order. Sub-steps are at most ``h_max``; each is predicted by the
    secant through the last two accepted points (the last point for the first sub-step;
    ``bound`` is applied to secant predictions) and corrected by ``solve``. A sub-step is
    retried at half the length when ``solve`` raises one of ``failures``, returns a non-finite
    solution, or lands farther than ``max_jump`` from the prediction. After an accepted
    sub-step the next one doubles (up to ``h_max``) if ``solve`` took at most ``fast_iter``
    iterations (always if None), halves if it took more than ``slow_iter`` (never if None), and
    keeps its length otherwise. The branch ends where the sub-step would fall below ``h_min``.

    Parameters
    ----------
    solve : Solve
        The corrector at one value; called with ``max_iter``.
    start : Point
        The first point (already solved).
    targets : sequence of float
        Values to reach, in order.
    h_max : float
        Largest sub-step (parameter units), > 0.
    h_min : float, optional
        Smallest sub-step (default ``h_max * MIN_STEP_FRACTION``).
    first_step : float, optional
        Length of the first sub-step (default ``h_max``).
    max_iter : int
        Newton iterations allowed per sub-step.
    fast_iter, slow_iter : int or None
        The step-length rule above.
    max_jump : float
        Largest accepted ``|solution - prediction|`` (Euclidean norm).
    bound : callable, optional
        ``bound(prediction) -> prediction``: e.g. a lower bound on a parameter unknown.
    failures : tuple of exception types
        What ``solve`` raises where it finds no solution (a failed sub-step); other exceptions
        propagate.
    reach_tol : float
        A target counts as reached within ``reach_tol * max(1, |target|)`` (0: exactly).

    Returns
    -------
    (list of Point or None, list of Point)
        Per target its point (None past the end of the branch); every accepted point in order,
        ``start`` first.
    """
    path = [start]
    out: list[Point | None] = [None] * len(targets)
    h = h_max if first_step is None else first_step
    h_min = h_max * MIN_STEP_FRACTION if h_min is None else h_min
    for k, t in enumerate(targets):
        while True:
            cur = path[-1]
            rem = float(t) - cur.value
            if abs(rem) <= reach_tol * max(1.0, abs(float(t))):
                out[k] = cur
                break
            clipped = abs(rem) <= h  # the sub-step ends on the target
            v = float(t) if clipped else cur.value + math.copysign(h, rem)
            pred = cur.z.copy()  # solve may work in place on its guess
            if len(path) >= 2 and path[-2].value != cur.value:
                prev = path[-2]
                pred = cur.z + (cur.z - prev.z) * ((v - cur.value) / (cur.value - prev.value))
                if bound is not None:
                    pred = bound(pred)
            try:
                gait, z, it, mnr = solve(v, pred, max_iter)
                ok = bool(np.all(np.isfinite(z))) and float(np.linalg.norm(z - pred)) <= max_jump
            except failures:
                ok = False
            if not ok:
                h = 0.5 * abs(v - cur.value)
                if h < h_min:
                    return out, path
                continue
            path.append(Point(value=v, z=np.asarray(z, dtype=float), mnr=mnr, gait=gait))
            # the next sub-step from this one's length as intended (h, not v - value, which
            # carries round-off), or the clipped length
            length = abs(rem) if clipped else h
            if fast_iter is None or it <= fast_iter:
                h = min(h_max, 2.0 * length)
            elif slow_iter is not None and it > slow_iter:
                h = 0.5 * length
            else:
                h = length
            h = max(h, h_min)
    return out, path


def follow_both_ways(
    solve: Solve, start: Point, targets: FloatArray, h_max: float
) -> tuple[list[Point | None], list[Point]]:
    """:func:`follow` from ``start`` up and down through ``targets`` (any order); returns per
    target its point (None where the branch does not reach) and every accepted point sorted by
    value."""
    T = np.asarray(targets, dtype=float)
    up = [i for i in np.argsort(T, kind="stable") if T[i] >= start.value]
    down = [i for i in np.argsort(-T, kind="stable") if T[i] < start.value]
    out: list[Point | None] = [None] * T.size
    points = [start]
    for idx in (up, down):
        if not idx:
            continue
        got, path = follow(solve, start, [float(T[i]) for i in idx], h_max)
        for i, g in zip(idx, got, strict=True):
            out[i] = g
        points += path[1:]
    return out, sorted(points, key=lambda p: p.value)
