"""Map of stable passive gaits over foot radius and slope, with period doubling marked.

For every foot radius the period-one gait is followed along the slope by natural-parameter
continuation (Newton's method on the compiled Poincare map
:func:`~heelstrike.dynamics.compiled.step_map_compiled`, central-difference Jacobian) with step
control: secant-predicted sub-steps of at most 0.25 deg between the grid's slopes, halved when
Newton fails, is slow or lands far from the prediction (``follow``), so the branch, and
the gaits at the grid's slopes, do not depend on the grid. Each radius's branch starts from an
*anchor* gait at 3 deg (or the nearest end of the slope range), obtained by continuation in the
radius from the point-foot gait (found by the automatic attractor search). At every point the
Floquet multipliers give the spectral radius and stability; where the smallest real
multiplier crosses -1 between two continuation points (grid slopes or sub-steps) the
period-doubling slope is refined by bisection. Radii are evaluated with
:func:`heelstrike.analysis.sweep.sweep` (Dask threads, one radius per chunk).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis._continuation import (
    PARAMETER_STEP,
    SLOPE_STEP,
    Point,
    Solve,
    follow,
    follow_both_ways,
)
from heelstrike.analysis._defaults import BIFURCATION_RECORD, BIFURCATION_TRANSIENT
from heelstrike.analysis._gait_order import first_gait, stable_radius
from heelstrike.analysis.limit_cycle import (
    GaitNotFoundError,
    _smallest_real,
    find_limit_cycle,
    refine_period_doubling,
)
from heelstrike.analysis.newton import NewtonSolution, floquet_multipliers
from heelstrike.dynamics.compiled import COMPLETED, ensemble_walk
from heelstrike.models.base import check_backend_name
from heelstrike.models.compass import CompassGait
from heelstrike.status import SolveStatus

if TYPE_CHECKING:
    import xarray as xr

    from heelstrike.analysis.limit_cycle import (
        BifurcationDiagram,
        Continuation,
        Gait,
    )
    from heelstrike.dynamics.phased import PhasedWalker
    from heelstrike.models.builder import BuiltWalker


__all__ = [
    "GaitMap",
    "NewtonGait",
    "compass_bifurcation",
    "gait_map",
    "model_bifurcation",
    "model_gait_map",
    "newton_gait",
    "newton_gaits",
]


@dataclass(frozen=True, kw_only=True)
class NewtonGait(ResultDictMixin):
    """A period-one gait found on the compiled map.

    Attributes
    ----------
    z : ndarray, shape (3,)
        Fixed point ``(q3, q3_dot, q4_dot)`` (rad, rad/s).
    multipliers : ndarray of complex, shape (3,)
        Floquet multipliers, largest modulus first.
    period, step_length, collision_loss, impact_angle : float
        Step duration (s), step length (m), ``T_c`` (J), ``q3`` at heel strike (rad).
    residual : float
        ``|P(z) - z|``.
    iterations : int
        Newton iterations, counted as maps of an iterate (1: the guess was already periodic).
    """

    z: FloatArray
    multipliers: NDArray[np.complex128]
    period: float
    step_length: float
    collision_loss: float
    impact_angle: float
    residual: float
    iterations: int = 0

    @property
    def spectral_radius(self) -> float:
        """Largest multiplier modulus."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def smallest_real(self) -> float:
        """Smallest real multiplier (NaN if none is real; the rule of
        :func:`~heelstrike.analysis.limit_cycle.refine_period_doubling`)."""
        m = _smallest_real(self.multipliers)
        return float("nan") if m is None else float(m)


@dataclass(frozen=True, kw_only=True)
class _Steps:
    """One step from each of ``B`` section points: the fields of
    :class:`~heelstrike.dynamics.compiled.EnsembleResult` the map reads, shapes (B, 1)."""

    step_time: FloatArray
    step_length: FloatArray
    collision_loss: FloatArray
    impact_angle: FloatArray


def _scipy_steps(
    walker: CompassGait, Z: FloatArray, slope: float, rtol: float, atol: float
) -> tuple[FloatArray, _Steps]:
    """``P`` at every row of ``Z`` on the scipy reference (rows of NaN where the step fails)
    and the step of each row."""
    from heelstrike.dynamics.hybrid import simulate

    out = np.full_like(Z, np.nan)
    cols = {k: np.full((Z.shape[0], 1), np.nan)
            for k in ("step_time", "step_length", "collision_loss", "impact_angle")}
    for i, z in enumerate(Z):
        q, qd = walker.section_to_state(z)
        walk = simulate(walker, q, qd, slope=slope, steps=1, rtol=rtol, atol=atol)
        if not walk.ok:
            continue
        rec = walk.impacts[0]
        out[i] = walker.state_to_section(walk.final_q, walk.final_q_dot)
        cols["step_time"][i, 0] = rec.time
        cols["step_length"][i, 0] = rec.step_length
        cols["collision_loss"][i, 0] = rec.kinetic_energy_constrained
        cols["impact_angle"][i, 0] = rec.impact_angle
    return out, _Steps(**cols)


def _map_many(
    walker: CompassGait, Z: FloatArray, slope: float, rtol: float, atol: float,
    backend: str = "compiled",
) -> tuple[FloatArray, Any]:
    """``P`` at every row of ``Z`` (NaN rows where the step fails) and the steps: one compiled
    ensemble call, or the scipy reference row by row."""
    if backend == "scipy":
        return _scipy_steps(walker, Z, slope, rtol, atol)
    check_backend_name(backend)
    res = ensemble_walk(walker, Z, slope, steps=1, rtol=rtol, atol=atol, parallel=False)
    out = np.where((res.status == COMPLETED)[:, None], res.z, np.nan)
    return out, res


def newton_gaits(
    walker: CompassGait,
    slope: float,
    guesses: ArrayLike,
    *,
    tol: float = 1e-10,
    max_iter: int = 20,
    fd_step: float = 1e-6,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    deadline: float | None = None,
    backend: str = "compiled",
) -> list[NewtonGait | SolveStatus]:
    """Newton's method for ``P(z) = z`` on the compiled map, from many guesses at once.

    Runs the one Newton engine (:func:`~heelstrike.analysis.newton.newton_solve`) on
    ``P(z) - z``. All unconverged iterates advance together: each iteration maps every iterate
    and its 6 central-difference neighbours in one ensemble call, and the damped line search
    (halving until the walker takes a step) evaluates every pending trial point in one call per
    halving.

    Parameters
    ----------
    walker : CompassGait
        The walker (scalar parameters).
    slope : float
        Slope (rad).
    guesses : array_like, shape (K, 3) or (3,)
        Starting section points ``(q3, q3_dot, q4_dot)`` (rad, rad/s).
    tol : float
        Convergence bound on ``|P(z) - z|``.
    max_iter : int
        Newton iterations per guess.
    fd_step : float
        Relative central-difference step of the Jacobian.
    rtol, atol : float
        Integrator tolerances.
    deadline : float, optional
        ``time.monotonic()`` value after which unconverged guesses are given up.
    backend : {"compiled", "scipy"}
        The map: the compiled ensemble (default) or the scipy reference, row by row.

    Returns
    -------
    list of NewtonGait or SolveStatus
        Per guess, the converged gait or how its start failed (its ``message`` says it).
    """
    return _newton_gaits(walker, slope, guesses, tol=tol, max_iter=max_iter, fd_step=fd_step,
                         rtol=rtol, atol=atol, deadline=deadline, backend=backend)[0]


def _newton_gaits(
    walker: CompassGait, slope: float, guesses: ArrayLike, *, tol: float, max_iter: int,
    fd_step: float, rtol: float, atol: float, deadline: float | None, backend: str,
) -> tuple[list[NewtonGait | SolveStatus], NewtonSolution]:
    """:func:`newton_gaits`, and the Newton solution it ran (its per-start messages)."""
    from heelstrike.analysis.newton import newton_solve

    Z = np.atleast_2d(np.asarray(guesses, dtype=float)).reshape(-1, 3)
    sol = newton_solve(lambda X: _map_many(walker, X, slope, rtol, atol, backend)[0] - X, Z,
                       tol=tol, max_iter=max_iter, fd_step=fd_step, deadline=deadline)
    out: list[NewtonGait | SolveStatus] = list(sol.status)
    done = np.flatnonzero(sol.converged)
    if done.size == 0:
        return out, sol
    _, res = _map_many(walker, sol.x[done], slope, rtol, atol, backend)  # each gait's step
    for j, k in enumerate(done):
        jac = sol.jacobian[k] + np.eye(3)  # DP = D(P - id) + I
        if not np.all(np.isfinite(jac)):
            out[k] = SolveStatus.JACOBIAN_FAILED
            continue
        out[k] = NewtonGait(
            z=sol.x[k].copy(),
            multipliers=floquet_multipliers(jac),
            period=float(res.step_time[j, 0]),
            step_length=float(res.step_length[j, 0]),
            collision_loss=float(res.collision_loss[j, 0]),
            impact_angle=float(res.impact_angle[j, 0]),
            residual=float(sol.residual_norm[k]),
            iterations=int(sol.iterations[k]),
        )
    return out, sol


def newton_gait(
    walker: CompassGait,
    slope: float,
    guess: ArrayLike,
    *,
    tol: float = 1e-10,
    max_iter: int = 20,
    fd_step: float = 1e-6,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    backend: str = "compiled",
) -> NewtonGait:
    """Newton's method for ``P(z) = z`` on the compiled map (or ``backend="scipy"``: the
    reference), from ``guess`` (one start of :func:`newton_gaits`).

    Raises
    ------
    GaitNotFoundError
        If a step fails or Newton does not converge.
    """
    (result,), sol = _newton_gaits(
        walker, slope, np.asarray(guess, dtype=float).reshape(1, 3), tol=tol,
        max_iter=max_iter, fd_step=fd_step, rtol=rtol, atol=atol, deadline=None,
        backend=backend,
    )
    if isinstance(result, SolveStatus):
        raise GaitNotFoundError(sol.message(0, walker.section_labels)
                                if sol.status[0] is result else result.message)
    return result


_OUTPUTS = ("spectral_radius", "period", "step_length", "collision_loss", "impact_angle")
#: Units of the map's per-gait variables (compass and described walkers alike).
_UNITS = {"spectral_radius": "1", "period": "s", "step_length": "m", "collision_loss": "J",
          "impact_angle": "rad", "smallest_real_multiplier": "1"}


def _check_slopes(slopes: FloatArray) -> None:
    if slopes.size < 1 or np.any(np.diff(slopes) <= 0) or slopes[0] <= 0:
        raise ValueError("slopes must be positive and increasing")


def _anchor_slope(slopes: FloatArray) -> float:
    """The anchor slope of a map (rad): 3 deg, or the end of the slope range nearest to it.

    It depends on the range only, not on the grid inside it, so maps over the same range
    continue the same branches."""
    return float(np.clip(np.deg2rad(3.0), slopes[0], slopes[-1]))


def _add_derived(ds: xr.Dataset) -> None:
    """``speed``, ``stable`` and ``gait_found`` of a map dataset, from its gait variables."""
    ds["speed"] = (ds["step_length"] / ds["period"]).assign_attrs(units="m s-1")
    ds["stable"] = stable_radius(ds["spectral_radius"]).assign_attrs(
        long_name="a stable gait was found: all Floquet multipliers inside the unit circle "
                  "(false also where no gait was found: see gait_found)", units="1")
    ds["smallest_real_multiplier"].attrs["long_name"] = (
        "smallest real Floquet multiplier (it crosses -1 at a period doubling; positive when "
        "no real multiplier is negative; NaN if none is real)")
    ds["gait_found"] = ds["spectral_radius"].notnull().assign_attrs(
        long_name="a period-one gait was found (else every gait variable is NaN and stable "
                  "is false)", units="1")


#: Largest sub-step of the continuation in the compass walker's foot radius (m).
_RADIUS_STEP = 0.05
#: Absolute precision (rad) of the period-doubling slope refined between two sub-steps.
_PD_TOL = 1e-9


def _pd_bracket(
    points: Sequence[Point], any_sign: bool = True
) -> tuple[Point, Point] | None:
    """The first pair of consecutive continuation points (by increasing value) between which the
    smallest real multiplier crosses -1 (with ``any_sign`` False: from above -1 to -1 or
    below), or None."""
    for a, b in itertools.pairwise(points):
        fa, fb = a.mnr + 1.0, b.mnr + 1.0
        if not (np.isfinite(fa) and np.isfinite(fb)):
            continue
        if (fa * fb < 0.0) if any_sign else (fa > 0.0 >= fb):
            return a, b
    return None


def _pd_iterations(lo: float, hi: float) -> int:
    """Bisection halvings that shrink the bracket ``[lo, hi]`` below ``_PD_TOL``."""
    return max(12, int(np.ceil(np.log2(max(abs(hi - lo), _PD_TOL) / _PD_TOL))))


def _branch(
    walker: CompassGait,
    slopes: FloatArray,
    anchor_slope: float,
    anchor: FloatArray,
    rtol: float,
    atol: float,
    backend: str = "compiled",
) -> tuple[dict[str, FloatArray], FloatArray, FloatArray, float]:
    """Continue the gait of one walker from the anchor (its fixed point at ``anchor_slope``)
    up and down through ``slopes`` (``follow``: sub-steps of at most ``SLOPE_STEP``, so
    the branch does not depend on the grid).

    Returns per-slope outputs, fixed points (S, 3), smallest real multiplier (S,) and the
    refined period-doubling slope: the first crossing of -1 between any two continuation points,
    grid slopes or sub-steps (NaN if none in range).
    """
    S = slopes.size
    out = {k: np.full(S, np.nan) for k in _OUTPUTS}
    fixed = np.full((S, 3), np.nan)
    mnr = np.full(S, np.nan)

    def solve(slope: float, z: FloatArray, max_iter: int) -> tuple[Any, FloatArray, int, float]:
        g = newton_gait(walker, slope, z, rtol=rtol, atol=atol, max_iter=max_iter,
                        backend=backend)
        return g, g.z, g.iterations, g.smallest_real

    try:
        g0, z0, _, m0 = solve(anchor_slope, anchor, 20)
        start = Point(value=anchor_slope, z=z0, mnr=m0, gait=g0)
    except GaitNotFoundError:
        return out, fixed, mnr, float("nan")
    got, points = follow_both_ways(solve, start, slopes, SLOPE_STEP)
    for i, p in enumerate(got):
        if p is None:
            continue  # the branch ends (fold or failure) before this slope: NaN
        g = p.gait
        fixed[i] = g.z
        mnr[i] = g.smallest_real
        out["spectral_radius"][i] = g.spectral_radius
        out["period"][i] = g.period
        out["step_length"][i] = g.step_length
        out["collision_loss"][i] = g.collision_loss
        out["impact_angle"][i] = g.impact_angle
    pd = float("nan")
    bracket = _pd_bracket([p for p in points if slopes[0] <= p.value <= slopes[-1]])
    if bracket is not None:
        a, b = bracket
        pd = _refine_period_doubling(walker, a.value, b.value, a.gait, a.mnr, rtol, atol,
                                     backend)
    return out, fixed, mnr, pd


def _refine_period_doubling(
    walker: CompassGait,
    s0: float,
    s1: float,
    g0: NewtonGait,
    m0: float,
    rtol: float,
    atol: float,
    backend: str = "compiled",
) -> float:
    """:func:`~heelstrike.analysis.limit_cycle.refine_period_doubling` on the map of
    ``backend``, to ``_PD_TOL``."""

    def solve(slope: float, z: FloatArray) -> tuple[float, FloatArray]:
        g = newton_gait(walker, slope, z, rtol=rtol, atol=atol, backend=backend)
        return g.smallest_real, g.z

    return refine_period_doubling(solve, s0, s1, m0, g0.z, iterations=_pd_iterations(s0, s1))


def _walker_kwargs(walker: CompassGait) -> dict[str, float]:
    """The walker's named parameters (:attr:`~heelstrike.models.base.PlanarWalker.parameters`)
    except the foot radius, which the map sweeps."""
    return {k: float(v) for k, v in walker.parameters.items() if k != "foot_radius"}


def _map_chunk(
    foot_radius: FloatArray,
    slope: FloatArray,
    *,
    walker: tuple[tuple[str, float], ...],
    anchors: tuple[tuple[float, ...], ...],
    rtol: float,
    atol: float,
    backend: str = "compiled",
) -> dict[str, FloatArray]:
    """Sweep function: every radius of the chunk, all slopes (see the sweep contract);
    ``anchors`` holds ``(radius, anchor slope, fixed point...)`` per radius."""
    radii = np.asarray(foot_radius, dtype=float)[:, 0]
    slopes = np.asarray(slope, dtype=float)[0, :]
    table = {a[0]: (a[1], np.array(a[2:])) for a in anchors}
    R_, S_ = radii.size, slopes.size
    res: dict[str, FloatArray] = {k: np.full((R_, S_), np.nan) for k in _OUTPUTS}
    res["fixed_point"] = np.full((R_, S_, 3), np.nan)
    res["smallest_real_multiplier"] = np.full((R_, S_), np.nan)
    res["period_doubling_slope"] = np.full((R_, S_), np.nan)
    for j, R in enumerate(radii):
        entry = table.get(float(R))
        if entry is None or not np.all(np.isfinite(entry[1])):
            continue
        w = CompassGait(foot_radius=float(R), **dict(walker))
        out, fixed, mnr, pd = _branch(w, slopes, entry[0], entry[1], rtol, atol, backend)
        for k in _OUTPUTS:
            res[k][j] = out[k]
        res["fixed_point"][j] = fixed
        res["smallest_real_multiplier"][j] = mnr
        res["period_doubling_slope"][j] = pd
    return res


@dataclass(frozen=True, kw_only=True)
class GaitMap(ResultDictMixin):
    """The stable-gait map.

    Attributes
    ----------
    dataset : xarray.Dataset
        Over ``foot_radius`` (m) x ``slope`` (rad): ``spectral_radius``, ``stable``, ``period``
        (s), ``step_length`` (m), ``speed`` (m/s), ``collision_loss`` (J), ``impact_angle``
        (rad), ``fixed_point`` (+ ``section`` dim), ``smallest_real_multiplier``; over
        ``foot_radius``: ``period_doubling_slope`` (rad, NaN if none in range). NaN where no
        period-one gait was found, and ``gait_found`` (bool) False there.
    hanging_cells : int
        Described walkers (:func:`model_gait_map`): the number of cells whose gait carries a
        link described upright hanging
        (:attr:`~heelstrike.analysis.gaits.Gait.hanging_links`); 0 otherwise.
    hanging_links : tuple of str
        The links those gaits carry hanging (sorted; empty if none).
    upright_links : tuple of str
        The walker's links described upright
        (:func:`~heelstrike.analysis.model_gaits.upright_links`): with no hanging cell, every
        gait of the map carries them upright.
    """

    dataset: xr.Dataset
    hanging_cells: int = 0
    hanging_links: tuple[str, ...] = ()
    upright_links: tuple[str, ...] = ()

    @property
    def period_doubling_slope(self) -> FloatArray:
        """Period-doubling slope per radius (rad), shape (n_radius,)."""
        return np.asarray(self.dataset["period_doubling_slope"].values)


def _direct(walker: CompassGait, slope: float, rtol: float, atol: float,
            backend: str = "compiled") -> FloatArray:
    """The preferred gait of the automatic search at one radius, or NaNs if there is none."""
    try:
        return find_limit_cycle(walker, slope=slope, method=backend, rtol=rtol,
                                atol=atol).fixed_point
    except GaitNotFoundError:
        return np.full(3, np.nan)


def _fallback_slopes(slopes: FloatArray, anchor_slope: float) -> list[float]:
    """Further anchor slopes (rad) for a branch without a gait at ``anchor_slope``: about every
    1 deg of the range (the range only, not the grid), nearest to ``anchor_slope`` first, the
    anchor slope itself excluded."""
    n_fb = max(2, int(np.ceil((slopes[-1] - slopes[0]) / np.deg2rad(1.0))) + 1)
    return [float(s) for s in sorted(np.linspace(slopes[0], slopes[-1], n_fb),
                                     key=lambda s: abs(s - anchor_slope))
            if abs(s - anchor_slope) > 1e-12]


def _anchors(
    walker: CompassGait, radii: FloatArray, slopes: FloatArray, guess: ArrayLike | None,
    rtol: float, atol: float, backend: str = "compiled",
) -> list[tuple[float, FloatArray]]:
    """An anchor (slope, gait) for every radius (NaNs where none is found).

    At the anchor slope :func:`_anchor_slope`: by continuation in the radius in sorted order
    (``follow``, sub-steps of at most 0.05 m) from the point foot's preferred gait (or from
    ``guess`` at the smallest radius). Where the continuation breaks, the automatic search is
    run at that radius and the continuation restarts from what it finds. A radius with no gait
    found at the anchor slope is searched at the :func:`_fallback_slopes` (large feet have
    gaits on shallow slopes only); radii without a gait get NaNs and never abort the map."""
    order = np.argsort(radii)
    slope = _anchor_slope(slopes)

    def solve(R: float, z: FloatArray, max_iter: int) -> tuple[Any, FloatArray, int, float]:
        g = newton_gait(walker.replace(foot_radius=R), slope, z, rtol=rtol, atol=atol,
                        max_iter=max_iter, backend=backend)
        return g, g.z, g.iterations, g.smallest_real

    if guess is None:
        R_prev = 0.0
        z = _direct(walker.replace(foot_radius=0.0), slope, rtol, atol, backend)
    else:
        R_prev = float(radii[order[0]])
        try:
            z = newton_gait(walker.replace(foot_radius=R_prev), slope, guess,
                            rtol=rtol, atol=atol, backend=backend).z
        except GaitNotFoundError:
            z = np.full(3, np.nan)
    out: list[tuple[float, FloatArray]] = [(slope, np.full(3, np.nan))] * radii.size
    for k in order:
        R = float(radii[k])
        zk = np.full(3, np.nan)
        if np.all(np.isfinite(z)):
            # continuation in the radius with step control (sub-steps of at most 0.05 m)
            (got,), _ = follow(solve, Point(value=R_prev, z=z, mnr=np.nan, gait=None), [R],
                                _RADIUS_STEP)
            if got is not None:
                zk = got.z
        if not np.all(np.isfinite(zk)):
            zk = _direct(walker.replace(foot_radius=R), slope, rtol, atol, backend)
        out[k] = (slope, zk)
        if np.all(np.isfinite(zk)):
            z, R_prev = zk, R
            continue
        for s in _fallback_slopes(slopes, slope):
            zs = _direct(walker.replace(foot_radius=R), s, rtol, atol, backend)
            if np.all(np.isfinite(zs)):
                out[k] = (s, zs)
                break
    return out


def gait_map(
    walker: CompassGait,
    radii: ArrayLike,
    slopes: ArrayLike,
    *,
    guess: ArrayLike | None = None,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    store: str | Path | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    backend: str = "compiled",
) -> GaitMap:
    """Period-one gaits, their stability and period doubling over (foot radius, slope).

    Parameters
    ----------
    walker : CompassGait
        Scalar-parameter walker (its ``foot_radius`` is replaced by ``radii``).
    radii : array_like, shape (K,)
        Foot radii (m), ``0 <= R <= l``.
    slopes : array_like, shape (S,)
        Increasing slopes (rad), > 0.
    guess : array_like, shape (3,), optional
        Section point near the gait of the smallest radius at the anchor slope (3 deg, or the
        nearest end of the slope range); automatic search if omitted.
    rtol, atol : float
        Integrator tolerances of the compiled map.
    store : path, optional
        Zarr store of the sweep (resumable).
    scheduler : str, optional
        Dask scheduler of :func:`~heelstrike.analysis.sweep.sweep` (default threads).
    progress : bool
        Progress bar over radii.
    backend : {"compiled", "scipy"}
        The step map: the compiled compass ensemble (default) or the scipy reference (the same
        continuation; about a hundred times slower).

    Returns
    -------
    GaitMap
    """
    from heelstrike.analysis.sweep import sweep

    R = np.asarray(radii, dtype=float).ravel()
    S = np.asarray(slopes, dtype=float).ravel()
    if R.size < 1 or S.size < 1:
        raise ValueError("radii and slopes must not be empty")
    _check_slopes(S)
    if np.any(R < 0) or np.any(R > float(walker.leg_length)):
        raise ValueError("radii must satisfy 0 <= R <= leg_length")
    anchor_slope = _anchor_slope(S)
    check_backend_name(backend)
    anchors = _anchors(walker, R, S, guess, rtol, atol, backend)
    func = functools.partial(
        _map_chunk,
        walker=tuple(sorted(_walker_kwargs(walker).items())),
        anchors=tuple((float(r), float(s), *map(float, a))
                      for r, (s, a) in zip(R, anchors, strict=True)),
        rtol=float(rtol),
        atol=float(atol),
        backend=backend,
    )
    ds = sweep(
        func,
        {"foot_radius": R, "slope": S},
        chunks={"foot_radius": 1},
        store=None if store is None else str(store),
        scheduler=scheduler,
        progress="gait map" if progress else False,
        units={**_UNITS, "fixed_point": "rad, rad s-1, rad s-1", "period_doubling_slope": "rad"},
        output_dims={"fixed_point": ("section",)},
    ).load()
    pd = ds["period_doubling_slope"].isel(slope=0, drop=True)
    ds = ds.drop_vars("period_doubling_slope")
    ds["period_doubling_slope"] = pd.assign_attrs(
        units="rad", long_name="slope where a multiplier crosses -1 (period doubling)"
    )
    ds = ds.assign_coords(section=["q3", "q3_dot", "q4_dot"])
    ds["fixed_point"].attrs.update(
        long_name="post-impact fixed point (q3 rad, q3_dot rad/s, q4_dot rad/s)"
    )
    _add_derived(ds)
    from heelstrike.analysis.sweep import _attribute_units

    ds.attrs.update(
        {f"walker_{k}": v for k, v in _walker_kwargs(walker).items()}
        | {"anchor_slope": anchor_slope, "rtol": rtol, "atol": atol, "backend": backend}
    )
    ds.attrs.update(_attribute_units(ds.attrs, {"anchor_slope": "rad", "rtol": "1",
                                                "atol": "1"}))
    return GaitMap(dataset=ds)


# -- described walkers (TOML models) -------------------------------------------------------------
def _model_multiplier(
    walker: BuiltWalker, backend: str, slope: float, guess: FloatArray
) -> tuple[float, FloatArray]:
    """Smallest real multiplier and fixed point of a described walker's gait at a slope
    (the ``solve`` of :func:`~heelstrike.analysis.limit_cycle.refine_period_doubling`)."""
    from heelstrike.analysis.model_gaits import find_model_gait

    try:
        g = find_model_gait(walker, slope=slope, guess=guess, backend=backend)
    except ValueError as exc:
        raise GaitNotFoundError(str(exc)) from exc
    mnr = _smallest_real(np.asarray(g.multipliers))
    return (np.nan if mnr is None else mnr), np.asarray(g.fixed_point, dtype=float)


def model_gait_map(
    walker: BuiltWalker,
    parameter: str,
    values: ArrayLike,
    slopes: ArrayLike,
    *,
    backend: str = "compiled",
    progress: bool = False,
) -> GaitMap:
    """Period-one gaits of a described walker over (one parameter, slope), by continuation.

    Every gait is found by Newton's method
    (:func:`~heelstrike.analysis.model_gaits.find_model_gait`) within a natural-parameter
    continuation with step control (as :func:`gait_map`: sub-steps, halved when Newton fails,
    is slow or lands far from the secant prediction), so the gaits at the grid points do not
    depend on the grid. The anchors: the walker's own gait at the anchor slope (3 deg, or the
    nearest end of the slope range; automatic search) is continued in the parameter, up and
    down from the walker's value, to every value. Where that breaks, the value's gait is
    continued in the parameter from the previous value's branch at other slopes, else found by
    the automatic search at the anchor slope and then about every 1 deg of the range. Each
    value's branch is then continued up and down the slopes from its anchor.

    Parameters
    ----------
    walker : BuiltWalker
        Base walker (its other parameter values are kept).
    parameter : str
        Name of the swept description parameter (SI units).
    values : array_like, shape (K,)
        Its values.
    slopes : array_like, shape (S,)
        Increasing slopes (rad), > 0.
    backend : {"compiled", "scipy"}
        Step simulator of ``find_model_gait``.
    progress : bool
        One line per parameter value on stderr.

    Returns
    -------
    GaitMap
        Dataset over ``(parameter, slope)`` with the variables of :func:`gait_map` (the
        ``fixed_point`` over the walker's ``section`` names; ``collision_loss`` the sum of
        ``T_c`` over the step's impacts) and ``period_doubling_slope`` per value: where the most
        negative real multiplier crosses -1 (from above) between two continuation points, grid
        slopes or sub-steps, located by
        :func:`~heelstrike.analysis.limit_cycle.refine_period_doubling` (the one definition;
        NaN if none in range).

    Raises
    ------
    ValueError
        Unknown parameter, a value the walker's description rejects (e.g. the kneed walker's
        ``R <= a1 + b1``), or slopes not positive and increasing.
    """
    import sys

    import xarray as xr

    from heelstrike.analysis.model_gaits import find_model_gait, upright_links
    from heelstrike.dynamics.phased import PhasedWalker

    w0 = PhasedWalker.from_built(walker)
    if parameter not in w0.parameters:
        raise ValueError(f"unknown parameter {parameter!r}; known: {sorted(w0.parameters)}")
    P = np.asarray(values, dtype=float).ravel()
    S = np.asarray(slopes, dtype=float).ravel()
    if P.size < 1 or S.size < 1:
        raise ValueError("values and slopes must not be empty")
    _check_slopes(S)
    walkers: list[PhasedWalker] = []
    for value in P:
        try:
            walkers.append(w0.replace(**{parameter: float(value)}))
        except ValueError as exc:  # refused, never drawn as "no gait"
            raise ValueError(f"{parameter} = {value:g} is not admitted by the walker "
                             f"{w0.description.name!r}: {exc}") from exc
    d = len(w0.section_names)
    shape = (P.size, S.size)
    out = {k: np.full(shape, np.nan) for k in _UNITS}
    fixed = np.full((*shape, d), np.nan)
    hanging: dict[tuple[int, int], tuple[str, ...]] = {}  # cell -> links its gait hangs
    pd = np.full(P.size, np.nan)
    s_a = _anchor_slope(S)
    # further anchor slopes where the branch has no gait at s_a: about every 1 deg of the range
    # (the range only, not the grid), nearest to s_a first
    n_fb = max(2, int(np.ceil((S[-1] - S[0]) / np.deg2rad(1.0))) + 1)
    fallback = sorted(np.linspace(S[0], S[-1], n_fb), key=lambda s: abs(s - s_a))
    base = float(w0.parameters[parameter])
    h_param = PARAMETER_STEP * max(1.0, abs(base), float(np.max(np.abs(P))))

    def gait_of(w: PhasedWalker, slope: float, guess: FloatArray | None,
                max_iter: int = 20) -> tuple[Any, FloatArray, int, float]:
        try:
            g = find_model_gait(w, slope=slope, guess=guess, backend=backend, max_iter=max_iter)
        except ValueError as exc:
            raise GaitNotFoundError(str(exc)) from exc
        m = _smallest_real(np.asarray(g.multipliers))
        return (g, np.asarray(g.fixed_point, dtype=float), int(g.iterations),
                float("nan") if m is None else float(m))

    def point(value: float, found: tuple[Any, FloatArray, int, float]) -> Point:
        return Point(value=value, z=found[1], mnr=found[3], gait=found[0])

    def in_parameter(slope: float) -> Solve:
        return lambda v, z, it: gait_of(w0.replace(**{parameter: v}), slope, z, it)

    def search(w: PhasedWalker, slope: float) -> Point | None:
        try:
            return point(slope, gait_of(w, slope, None))
        except GaitNotFoundError:
            return None

    # the anchor chain starts from the walker's own gait at s_a (automatic search) and follows
    # the parameter up and down from its value, so every map over the same ranges continues the
    # same branches
    first = search(w0, s_a)
    chain0 = None if first is None else Point(value=base, z=first.z, mnr=first.mnr,
                                               gait=first.gait)
    order = [i for i in np.argsort(P, kind="stable") if P[i] >= base]
    order_down = [i for i in np.argsort(-P, kind="stable") if P[i] < base]
    for idx in (order, order_down):
        chain = chain0  # the last gait at s_a, as a point in the parameter
        prev: tuple[float, list[Point]] | None = None  # the last value's slope branch
        for i in idx:
            value, w = float(P[i]), walkers[i]
            start: Point | None = None
            if chain is not None:  # 1. continuation in the parameter at s_a
                (got,), _ = follow(in_parameter(s_a), chain, [value], h_param)
                if got is not None:
                    chain, start = got, Point(value=s_a, z=got.z, mnr=got.mnr, gait=got.gait)
            if start is None and prev is not None:
                # 2. from the last value's gaits at the other anchor slopes
                tried: list[float] = []
                for s in fallback:
                    near = prev[1][int(np.argmin([abs(q.value - s) for q in prev[1]]))]
                    if near.value in tried or len(tried) >= 3:
                        continue
                    tried.append(near.value)
                    pt = Point(value=prev[0], z=near.z, mnr=near.mnr, gait=near.gait)
                    (got,), _ = follow(in_parameter(near.value), pt, [value], h_param)
                    if got is not None:
                        start = Point(value=near.value, z=got.z, mnr=got.mnr, gait=got.gait)
                        break
            if start is None:  # 3. the automatic search, at s_a then at the other slopes
                for s in fallback if s_a in fallback else [s_a, *fallback]:
                    start = search(w, float(s))
                    if start is not None:
                        if start.value == s_a:
                            chain = Point(value=value, z=start.z, mnr=start.mnr,
                                           gait=start.gait)
                        break
            if start is None:
                prev = None
                continue

            def solve(s: float, z: FloatArray, it: int, w: PhasedWalker = w
                      ) -> tuple[Any, FloatArray, int, float]:
                return gait_of(w, s, z, it)

            got_s, points = follow_both_ways(solve, start, S, SLOPE_STEP)
            for j, at in enumerate(got_s):
                if at is None:
                    continue
                g = at.gait
                out["spectral_radius"][i, j] = float(np.max(np.abs(g.multipliers)))
                out["period"][i, j] = g.period
                out["step_length"][i, j] = g.step_length
                out["collision_loss"][i, j] = g.collision_loss
                out["impact_angle"][i, j] = g.impact_angle
                out["smallest_real_multiplier"][i, j] = at.mnr
                fixed[i, j] = g.fixed_point
                hanging[i, j] = g.hanging_links
            prev = (value, points)
            bracket = _pd_bracket(points, any_sign=False)
            if bracket is not None:
                a, b = bracket
                pd[i] = refine_period_doubling(
                    functools.partial(_model_multiplier, w, backend), a.value, b.value, a.mnr,
                    a.z, iterations=_pd_iterations(a.value, b.value))
            if progress:
                print(f"heelstrike: {parameter} = {value:g}: gaits at "
                      f"{int(np.isfinite(out['period'][i]).sum())}/{S.size} slopes",
                      file=sys.stderr)
    from heelstrike.models.description import parameter_units

    unit = parameter_units(w0.description).get(parameter, "SI units")
    dims = (parameter, "slope")
    ds = xr.Dataset(
        {k: (dims, v, {"units": _UNITS[k]}) for k, v in out.items()},
        coords={
            parameter: (parameter, P, {"long_name": f"walker parameter {parameter}",
                                       "units": unit, "label": f"{parameter} ({unit})"}),
            "slope": ("slope", S, {"units": "rad"}),
            "section": ("section", list(w0.section_names)),
        },
    )
    ds["fixed_point"] = ((*dims, "section"), fixed, {
        "units": ", ".join("rad s-1" if n.endswith("_dot") else "rad" for n in w0.section_names),
        "long_name": "post-heel-strike fixed point (section coordinates: rad, rad/s)"})
    ds["period_doubling_slope"] = ((parameter,), pd, {
        "units": "rad", "long_name": "slope where a multiplier crosses -1 (period doubling)"})
    _add_derived(ds)
    ds.attrs.update({"model": w0.description.name, "parameter": parameter, "backend": backend,
                     "anchor_slope": s_a}
                    | {f"param_{k}": float(np.asarray(v)) for k, v in w0.parameters.items()
                       if k != parameter})
    return GaitMap(dataset=ds, hanging_cells=sum(1 for h in hanging.values() if h),
                   hanging_links=tuple(sorted({n for h in hanging.values() for n in h})),
                   upright_links=upright_links(w0))


#: Most slopes of the coarse scan for the first gait of a bifurcation range (when there is no
#: gait at its first slope; never more than the range's slopes), and the width (rad) to which
#: the start of the gait family is bisected.
_ONSET_SCAN_POINTS = 12
_ONSET_TOL = 1e-5


def _first_gait(
    auto: Callable[[float], Gait],
    near: Callable[[float, FloatArray], Gait],
    start: float,
    stop: float,
    points: int,
) -> list[tuple[float, Gait]]:
    """The first slope of ``[start, stop]`` (rad) with a gait, and that gait.

    ``auto(slope)`` is the walker's automatic gait search and ``near(slope, z)`` Newton from
    ``z``; both raise :class:`GaitNotFoundError`. If ``auto`` finds a stable gait at ``start``,
    that is the answer, as is an unstable one whose family continues (``near``) to the next
    scanned slope (past a period doubling). Otherwise ``auto`` scans ``points`` slopes evenly
    spaced over the range for the first stable gait, the gait is continued down the scan
    (``near``) while it exists, and the slope where its family starts is bisected to
    ``_ONSET_TOL`` between the last slope without it and the first with it: the returned slope
    has a gait (the one returned), ``_ONSET_TOL`` below it the family has none. If the scan
    finds no stable gait, the unstable gait at ``start`` is the answer, else the first gait of
    the scan.

    Returns
    -------
    list of (float, Gait)
        The gaits of the family found on the way, by increasing slope (rad): the first is the
        answer, the others (none if there is a gait at ``start``) lead away from it.

    Raises
    ------
    GaitNotFoundError
        If ``auto`` finds no gait at any scanned slope.
    """
    scan = np.linspace(start, stop, max(points, 2))
    at_start: Gait | None = None
    try:
        at_start = auto(start)
        if at_start.stable:
            return [(start, at_start)]
        near(float(scan[1]), at_start.fixed_point)  # its family goes on into the range
        return [(start, at_start)]
    except GaitNotFoundError:
        pass
    # an unstable gait at the start whose family ends before the next scanned slope is kept
    # only if no stable gait turns up further on (the kneed walker below 2.16 deg: a
    # long-period unstable gait, where the stable family has not started)
    first: tuple[int, Gait] | None = None if at_start is None else (0, at_start)
    for k in range(1, scan.size):
        try:
            cycle = auto(float(scan[k]))
        except GaitNotFoundError:
            continue
        if cycle.stable:
            first = (k, cycle)
            break
        if first is None:
            first = (k, cycle)  # unstable: kept unless a stable gait turns up further on
    if first is None:
        raise GaitNotFoundError(
            f"no gait found from {np.degrees(start):g} to {np.degrees(stop):g} deg: the "
            f"automatic gait search found none at any of {scan.size} slopes evenly spaced over "
            "the range")
    k, cycle = first
    family = [(float(scan[k]), cycle)]
    # continue the gait down the scan while its family exists (the automatic search may have
    # missed it there)
    while k > 0:
        try:
            cycle = near(float(scan[k - 1]), cycle.fixed_point)
        except GaitNotFoundError:
            break
        k -= 1
        family.insert(0, (float(scan[k]), cycle))
    if k == 0:
        return family
    lo, hi = float(scan[k - 1]), float(scan[k])  # no gait of the family at lo
    while hi - lo > _ONSET_TOL:
        mid = 0.5 * (lo + hi)
        try:
            cycle, hi = near(mid, cycle.fixed_point), mid
            family.insert(0, (mid, cycle))
        except GaitNotFoundError:
            lo = mid
    return family


def compass_bifurcation(
    walker: CompassGait,
    slopes: ArrayLike,
    *,
    transient: int = BIFURCATION_TRANSIENT,
    record: int = BIFURCATION_RECORD,
    continuation_points: int | None = 12,
    progress: bool = False,
    backend: str = "compiled",
) -> tuple[BifurcationDiagram, Continuation]:
    """Slope bifurcation diagram of the compass gait and its period-one branch.

    The gait at the first slope (:func:`~heelstrike.analysis.limit_cycle.find_limit_cycle`)
    seeds the brute-force diagram
    (:func:`~heelstrike.analysis.limit_cycle.bifurcation_diagram`: ``transient`` steps
    discarded, ``record`` impact angles and step periods kept per slope) and the continuation of
    the period-one gait over ``continuation_points`` slopes evenly spaced over the same range
    (:func:`~heelstrike.analysis.limit_cycle.continue_limit_cycle`, tolerances 1e-10), which
    marks the period-doubling slopes, all on one ``backend``. With ``continuation_points=None``
    the branch is continued over the diagram's slopes and refined where it curves, so that
    straight lines between its gaits follow it (what ``heelstrike bifurcation`` draws).
    :func:`model_bifurcation` is the same for a described walker.

    If there is no gait at the first slope, the range starts where the walker's gaits start:
    the automatic search scans min(12, K) slopes evenly spaced over the range for the first
    stable gait (else the first gait), and the slope where that gait's family begins is
    bisected to 1e-5 rad (Newton from the neighbouring gait). The branch then starts at that
    slope (``branch.values[0]``) and the diagram's rows below it are NaN (no gait there).

    Parameters
    ----------
    walker : CompassGait
    slopes : array_like, shape (K,)
        Increasing slopes (rad), > 0.
    transient, record : int
        Steps discarded and recorded per slope.
    continuation_points : int or None
        Slopes of the branch, evenly spaced over the range; None: the slopes of the diagram
        (from the onset), with gaits added between them where straight segments would miss
        the branch by more than 0.2 % of its span in impact angle or period (halving a segment
        at most 8 times).
    progress : bool
        Report progress on stderr.
    backend : {"compiled", "scipy"}
        Step simulator of the walks and of the branch's Poincare map: the compass kernel
        (batched map) or the scipy reference.

    Returns
    -------
    (BifurcationDiagram, Continuation)

    Raises
    ------
    GaitNotFoundError
        If the automatic search finds no gait at any of the scanned slopes.
    ValueError
        Unknown backend.
    """
    from heelstrike.dynamics.backends import simulator as backend_simulator

    simulator = backend_simulator(walker, backend)  # ValueError: unknown or unsupported backend
    sl = np.asarray(slopes, dtype=float).ravel()
    method = "compiled" if backend == "compiled" else "scipy"
    # the first gait of the range (its fixed point seeds the walks and the branch): the
    # automatic search, with Newton on the chosen backend's map
    family = _first_gait(
        lambda s: find_limit_cycle(walker, slope=s, progress=progress, method=method),
        lambda s, z: find_limit_cycle(walker, slope=s, guess=z, method=method),
        float(sl[0]), float(sl[-1]), min(_ONSET_SCAN_POINTS, sl.size),
    )
    return _diagram_and_branch(
        walker, sl, family, simulator, transient=transient, record=record,
        continuation_points=continuation_points, progress=progress, walk_tolerances={},
        branch_tolerances={"rtol": 1e-10, "atol": 1e-10},
    )


def _nearest_gait(family: list[tuple[float, Gait]], slope: float) -> FloatArray:
    """Fixed point of the ``family`` gait (``(slope, gait)`` pairs) whose slope is nearest."""
    at = np.array([s for s, _ in family])
    return family[int(np.argmin(np.abs(at - slope)))][1].fixed_point


def _diagram_and_branch(
    walker: Any, slopes: FloatArray, family: list[tuple[float, Gait]], simulator: Any, *,
    transient: int, record: int, continuation_points: int | None, progress: bool,
    walk_tolerances: dict[str, Any], branch_tolerances: dict[str, Any],
) -> tuple[BifurcationDiagram, Continuation]:
    """The brute-force diagram over ``slopes`` and the continued period-one branch from the
    first gait of the range to its last slope, on ``simulator`` (the bifurcation functions'
    shared part).

    The branch's slopes: ``continuation_points`` evenly spaced from the onset to the last
    slope, or (None) the onset and every slope of the diagram above it, refined where the
    branch curves (:func:`_refine_branch`).

    ``family`` is :func:`_first_gait`'s answer: its first gait, at the onset slope, starts the
    branch; the diagram's rows of slopes below the onset are NaN. The walks start from the
    family's gait nearest the first slope walked, and (when the onset was searched for) the
    branch beyond the onset from the family's gait nearest its second slope: near a fold, where
    families usually start, Newton from the onset gait could land on the fold's other branch.
    """
    from heelstrike.analysis.limit_cycle import (
        BifurcationDiagram,
        bifurcation_diagram,
    )

    onset, z0 = family[0][0], family[0][1].fixed_point
    branch = _continued_branch(walker, slopes, family, simulator, onset=onset, z0=z0,
                               continuation_points=continuation_points, progress=progress,
                               branch_tolerances=branch_tolerances)

    def restart(slope: float, z: FloatArray) -> FloatArray:
        # A walk that fell: the period-one gait at its slope, preferably a stable one. Newton
        # from the last state that walked can land on another, unstable gait when the grid is
        # coarse (QA sweep 10: `--slope-range 1deg:6deg:6` fell at 2-6 deg through a stable
        # branch), so Newton from the continued branch's gait nearest the slope comes first.
        starts = [z]
        if branch.cycles:
            starts.insert(0, branch.cycles[int(np.argmin(np.abs(branch.values - slope)))]
                          .fixed_point)
        found: list[Gait] = []
        for start in starts:
            try:
                found.append(find_limit_cycle(walker, slope=slope, guess=start,
                                              simulator=simulator, **branch_tolerances))
            except GaitNotFoundError:
                continue
            if found[-1].stable:
                break
        if not found:
            raise GaitNotFoundError(f"no period-one gait at slope {slope:g} rad")
        return first_gait(found).fixed_point

    k0 = int(np.searchsorted(slopes, onset))  # the first slope of the grid with a gait
    diagram = bifurcation_diagram(walker, slopes[k0:],
                                  guess=_nearest_gait(family, float(slopes[k0])),
                                  transient=transient, record=record, progress=progress,
                                  simulator=simulator, restart=restart, **walk_tolerances)
    if k0 > 0:  # no gait below the onset: nothing to walk or draw there
        def pad(a: FloatArray) -> FloatArray:
            return np.concatenate([np.full((k0, a.shape[1]), np.nan), a])

        diagram = BifurcationDiagram(slopes=slopes, impact_angles=pad(diagram.impact_angles),
                                     periods=pad(diagram.periods),
                                     statuses=("",) * k0 + diagram.statuses)
    return diagram, branch


def _continued_branch(
    walker: Any, slopes: FloatArray, family: list[tuple[float, Gait]], simulator: Any, *,
    onset: float, z0: FloatArray, continuation_points: int | None, progress: bool,
    branch_tolerances: dict[str, Any],
) -> Continuation:
    """The period-one branch continued from the ``onset`` gait ``z0`` over ``slopes`` (see
    :func:`_diagram_and_branch`)."""
    from heelstrike.analysis.limit_cycle import Continuation, continue_limit_cycle

    if continuation_points is None:  # the diagram's slopes: the line meets every column of dots
        values = np.concatenate([[onset], slopes[slopes > onset]])
    else:
        values = np.linspace(onset, slopes[-1], max(int(continuation_points), 1))
    kw = {"progress": progress, "simulator": simulator, **branch_tolerances}

    def gait_at(v: float, z: FloatArray) -> Gait:
        return find_limit_cycle(walker, slope=v, guess=z, simulator=simulator,
                                **branch_tolerances)

    def refined(c: Continuation) -> Continuation:
        return c if continuation_points is not None else _refine_branch(c, gait_at)

    if len(family) == 1 or values.size == 1:
        return refined(continue_limit_cycle(walker, "slope", values, guess=z0, **kw))
    head = continue_limit_cycle(walker, "slope", values[:1], guess=z0, **kw)
    rest = continue_limit_cycle(walker, "slope", values[1:],
                                guess=_nearest_gait(family, float(values[1])), **kw)
    if not head.cycles:
        return head
    pd = list(rest.period_doubling)
    if rest.cycles and float(rest.values[0]) == float(values[1]):
        # a period doubling between the onset and the next slope
        ma = _smallest_real(head.cycles[0].multipliers)
        mb = _smallest_real(rest.cycles[0].multipliers)
        if ma is not None and mb is not None and (ma + 1.0) * (mb + 1.0) < 0:

            def solve(v: float, z: FloatArray) -> tuple[float, FloatArray]:
                c = find_limit_cycle(walker, slope=v, guess=z, simulator=simulator,
                                     **branch_tolerances)
                m = _smallest_real(c.multipliers)
                return (np.nan if m is None else m), c.fixed_point

            pd.insert(0, refine_period_doubling(solve, onset, float(values[1]), ma, z0))
    branch = Continuation(
        parameter="slope", values=np.concatenate([head.values, rest.values]),
        cycles=head.cycles + rest.cycles, period_doubling=np.asarray(pd), stopped=rest.stopped,
    )
    return refined(branch)


#: Largest miss of the branch's drawn polyline (straight segments between its gaits), as a
#: fraction of the branch's span in impact angle and in period: :func:`_refine_branch` adds
#: gaits until no segment's midpoint misses the branch by more (0.2 %: under a pixel of the
#: figure's axes).
_BRANCH_TOL = 2e-3
#: Halvings of a segment of the diagram's slope grid at most (near a fold, where the branch
#: starts, it behaves as a square root of the slope: each halving divides the miss by sqrt 2).
_BRANCH_DEPTH = 8
#: Gaits added at most per gait of the branch (a bound on the cost, should the misses not shrink
#: by halving, e.g. at a kink of the branch), plus 16.
_BRANCH_EXTRA = 4


def _chord_miss(a: Gait, m: Gait, b: Gait, scale: FloatArray) -> float:
    """The miss of the chord from ``a`` to ``b`` at the gait ``m`` halfway (in slope), in
    ``scale`` units of impact angle and period (the larger of the two)."""
    mid = 0.5 * (np.array([a.impact_angle, a.period]) + np.array([b.impact_angle, b.period]))
    return float(np.max(np.abs(np.array([m.impact_angle, m.period]) - mid) / scale))


def _refine_branch(
    branch: Continuation, gait_at: Callable[[float, FloatArray], Gait], *,
    tol: float = _BRANCH_TOL, depth: int = _BRANCH_DEPTH,
) -> Continuation:
    """The branch with gaits added where straight segments between its gaits would miss it.

    A segment is halved (``gait_at(slope, z)``: Newton from the mean of its ends' fixed
    points) where the second differences of the impact angle or the period over the
    neighbouring gaits predict a miss above ``tol / 4`` of the branch's span, and the halves
    again while the gait found halfway misses the chord by more than ``tol`` of the span, at
    most ``depth`` times, and at most ``4 K + 16`` gaits are added to a branch of ``K``. A gait
    not found, or farther from that mean than the ends are from each other (another branch),
    ends the segment's refinement. The period doublings are kept.

    Parameters
    ----------
    branch : Continuation
        A period-one branch in the slope, by increasing slope.
    gait_at : callable
        ``gait_at(slope, z) -> Gait`` from the section point ``z``; may raise
        :class:`~heelstrike.analysis.limit_cycle.GaitNotFoundError`.
    tol : float
        Largest miss, as a fraction of the branch's span in impact angle and in period.
    depth : int
        Largest number of halvings of a segment.

    Returns
    -------
    Continuation
    """
    from heelstrike.analysis.limit_cycle import Continuation

    x = np.asarray(branch.values, dtype=float)
    cycles = list(branch.cycles)
    if x.size < 2:
        return branch
    y = np.array([[c.impact_angle, c.period] for c in cycles])
    scale = np.ptp(y, axis=0)
    scale = np.where(scale > 0, scale, np.maximum(np.abs(y).max(axis=0), 1e-12))
    # predicted miss of each segment: |second divided difference| h^2 / 4 over the triples
    # that contain it (the chord of a parabola misses it by |y''| h^2 / 8 at the middle)
    predicted = np.zeros(x.size - 1)
    for i in range(1, x.size - 1):
        d2 = ((y[i + 1] - y[i]) / (x[i + 1] - x[i]) - (y[i] - y[i - 1]) / (x[i] - x[i - 1])) \
            / (x[i + 1] - x[i - 1])
        for k in (i - 1, i):
            miss = float(np.max(np.abs(d2) * (x[k + 1] - x[k]) ** 2 / 4 / scale))
            predicted[k] = max(predicted[k], miss)

    budget = [_BRANCH_EXTRA * x.size + 16]  # gaits that may still be added

    def between(a: float, ca: Gait, b: float, cb: Gait, level: int
                ) -> list[tuple[float, Gait]]:
        if budget[0] <= 0:
            return []
        budget[0] -= 1
        m = 0.5 * (a + b)
        guess = 0.5 * (ca.fixed_point + cb.fixed_point)
        try:
            cm = gait_at(m, guess)
        except GaitNotFoundError:
            return []
        if np.linalg.norm(cm.fixed_point - guess) > np.linalg.norm(cb.fixed_point
                                                                   - ca.fixed_point):
            return []  # Newton went to another branch
        if level <= 1 or _chord_miss(ca, cm, cb, scale) <= tol:
            return [(m, cm)]
        return [*between(a, ca, m, cm, level - 1), (m, cm), *between(m, cm, b, cb, level - 1)]

    xs: list[float] = [float(x[0])]
    out: list[Gait] = [cycles[0]]
    for k in range(x.size - 1):
        if predicted[k] > tol / 4 or x.size == 2:
            for v, c in between(float(x[k]), cycles[k], float(x[k + 1]), cycles[k + 1], depth):
                xs.append(v)
                out.append(c)
        xs.append(float(x[k + 1]))
        out.append(cycles[k + 1])
    return Continuation(parameter=branch.parameter, values=np.asarray(xs), cycles=tuple(out),
                        period_doubling=branch.period_doubling, stopped=branch.stopped)


def model_bifurcation(
    walker: BuiltWalker,
    slopes: ArrayLike,
    *,
    transient: int = BIFURCATION_TRANSIENT,
    record: int = BIFURCATION_RECORD,
    continuation_points: int | None = 12,
    backend: str = "compiled",
    rtol: float = 1e-9,
    atol: float = 1e-10,
) -> tuple[BifurcationDiagram, Continuation]:
    """Slope bifurcation diagram of a described walker and its period-one branch.

    Brute force as :func:`~heelstrike.analysis.limit_cycle.bifurcation_diagram` (Goswami et al.
    1998): from the gait at the first slope, each slope's walk starts from the previous slope's
    last post-impact state, takes ``transient`` steps, and the next ``record`` impact angles
    (stance angle ``q[2]`` at heel strike, rad) and step durations (s) are kept. The branch:
    :func:`~heelstrike.analysis.limit_cycle.continue_limit_cycle` over ``continuation_points``
    slopes (each gait from the previous fixed point, with
    :func:`~heelstrike.analysis.model_gaits.find_model_gait`'s tolerances; it stops at the
    first slope without a gait), with the slopes where a real multiplier crosses -1
    (:func:`~heelstrike.analysis.limit_cycle.refine_period_doubling`).

    If there is no gait at the first slope (:func:`find_model_gait`'s automatic search), the
    range starts where the walker's gaits start, as in :func:`compass_bifurcation`: the branch
    starts at the first slope of the range with a gait (``branch.values[0]``, bisected to
    1e-5 rad) and the diagram's rows below it are NaN.

    Parameters
    ----------
    walker : BuiltWalker
    slopes : array_like, shape (K,)
        Increasing slopes (rad), > 0.
    transient, record : int
        Steps discarded and recorded per slope.
    continuation_points : int or None
        Slopes of the branch, evenly spaced over the same range; None: the diagram's slopes,
        refined where the branch curves (as :func:`compass_bifurcation`).
    backend : {"compiled", "scipy"}
        Step simulator.
    rtol, atol : float
        Integrator tolerances of the brute-force walks.

    Returns
    -------
    (BifurcationDiagram, Continuation)

    Raises
    ------
    GaitNotFoundError
        If the automatic search finds no gait at any of the scanned slopes.
    """
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.backends import simulator as backend_simulator
    from heelstrike.dynamics.phased import PhasedWalker

    w = PhasedWalker.from_built(walker)
    simulator = backend_simulator(w, backend)  # ValueError: unknown or unsupported backend
    sl = np.asarray(slopes, dtype=float).ravel()
    _check_slopes(sl)
    family = _first_gait(
        lambda s: find_model_gait(w, slope=s, backend=backend),
        lambda s, z: find_model_gait(w, slope=s, guess=z, backend=backend),
        float(sl[0]), float(sl[-1]), min(_ONSET_SCAN_POINTS, sl.size),
    )
    # the branch: each gait by Newton from the previous fixed point with find_model_gait's
    # tolerances
    return _diagram_and_branch(
        w, sl, family, simulator, transient=transient, record=record,
        continuation_points=continuation_points, progress=False,
        walk_tolerances={"rtol": rtol, "atol": atol},
        branch_tolerances={"tol": 1e-10, "max_iter": 20, "rtol": 1e-11, "atol": 1e-11},
    )
