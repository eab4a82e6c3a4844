"""Map of stable passive gaits over foot radius and slope, with period doubling marked.

For every foot radius the period-one gait is followed along the slope by natural-parameter
continuation (Newton's method on the compiled Poincare map
:func:`~heelstrike.dynamics.compiled.step_map_compiled`, central-difference Jacobian). Each
radius's branch starts from an *anchor* gait at the slope of the grid closest to 3 deg, obtained
by continuation in the radius from the point-foot gait (found by the automatic attractor search).
At every point the Floquet multipliers give the spectral radius and stability; where the most
negative real multiplier crosses -1 between two slopes the period-doubling slope is refined by
bisection. Radii are evaluated with :func:`heelstrike.analysis.sweep.sweep` (Dask threads, one
radius per chunk).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis.limit_cycle import (
    GaitNotFoundError,
    _most_negative_real,
    find_limit_cycle,
    refine_period_doubling,
)
from heelstrike.dynamics.compiled import COMPLETED, ensemble_walk
from heelstrike.models.compass import CompassGait

if TYPE_CHECKING:
    import xarray as xr

    from heelstrike.analysis.limit_cycle import BifurcationDiagram, Continuation
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
    def most_negative_real(self) -> float:
        """Most negative real multiplier (NaN if none is real; the rule of
        :func:`~heelstrike.analysis.limit_cycle.refine_period_doubling`)."""
        m = _most_negative_real(self.multipliers)
        return float("nan") if m is None else float(m)


def _map_many(
    walker: CompassGait, Z: FloatArray, slope: float, rtol: float, atol: float
) -> tuple[FloatArray, Any]:
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
) -> list[NewtonGait | str]:
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

    Returns
    -------
    list of NewtonGait or str
        Per guess, the converged gait or the reason it failed.
    """
    from heelstrike.analysis.newton import NewtonStatus, newton_solve

    Z = np.atleast_2d(np.asarray(guesses, dtype=float)).reshape(-1, 3)
    sol = newton_solve(lambda X: _map_many(walker, X, slope, rtol, atol)[0] - X, Z, tol=tol,
                       max_iter=max_iter, fd_step=fd_step, deadline=deadline)
    out: list[NewtonGait | str] = [sol.message(k) for k in range(Z.shape[0])]
    done = np.flatnonzero(sol.converged)
    if done.size == 0:
        return out
    _, res = _map_many(walker, sol.x[done], slope, rtol, atol)  # the step of each gait
    for j, k in enumerate(done):
        jac = sol.jacobian[k] + np.eye(3)  # DP = D(P - id) + I
        if not np.all(np.isfinite(jac)):
            out[k] = NewtonStatus.JACOBIAN_FAILED.message
            continue
        mult = np.linalg.eigvals(jac).astype(complex)
        out[k] = NewtonGait(
            z=sol.x[k].copy(),
            multipliers=mult[np.argsort(-np.abs(mult), kind="stable")],
            period=float(res.step_time[j, 0]),
            step_length=float(res.step_length[j, 0]),
            collision_loss=float(res.collision_loss[j, 0]),
            impact_angle=float(res.impact_angle[j, 0]),
            residual=float(sol.residual_norm[k]),
            iterations=int(sol.iterations[k]),
        )
    return out


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
) -> NewtonGait:
    """Newton's method for ``P(z) = z`` on the compiled map, from ``guess`` (one start of
    :func:`newton_gaits`).

    Raises
    ------
    GaitNotFoundError
        If a step fails or Newton does not converge.
    """
    (result,) = newton_gaits(
        walker,
        slope,
        np.asarray(guess, dtype=float).reshape(1, 3),
        tol=tol,
        max_iter=max_iter,
        fd_step=fd_step,
        rtol=rtol,
        atol=atol,
    )
    if isinstance(result, str):
        raise GaitNotFoundError(result)
    return result


_OUTPUTS = ("spectral_radius", "period", "step_length", "collision_loss", "impact_angle")
#: Units of the map's per-gait variables (compass and described walkers alike).
_UNITS = {"spectral_radius": "1", "period": "s", "step_length": "m", "collision_loss": "J",
          "impact_angle": "rad", "most_negative_real_multiplier": "1"}


def _check_slopes(slopes: FloatArray) -> None:
    if slopes.size < 1 or np.any(np.diff(slopes) <= 0) or slopes[0] <= 0:
        raise ValueError("slopes must be positive and increasing")


def _anchor_index(slopes: FloatArray) -> int:
    """The anchor slope of a map: the grid slope closest to 3 deg."""
    return int(np.argmin(np.abs(slopes - np.deg2rad(3.0))))


def _add_derived(ds: xr.Dataset) -> None:
    """``speed``, ``stable`` and ``gait_found`` of a map dataset, from its gait variables."""
    ds["speed"] = (ds["step_length"] / ds["period"]).assign_attrs(units="m s-1")
    ds["stable"] = (ds["spectral_radius"] < 1.0).assign_attrs(
        long_name="all Floquet multipliers inside the unit circle")
    ds["gait_found"] = ds["spectral_radius"].notnull().assign_attrs(
        long_name="a period-one gait was found (else every output is NaN)")


def _branch(
    walker: CompassGait,
    slopes: FloatArray,
    anchor_index: int,
    anchor: FloatArray,
    rtol: float,
    atol: float,
) -> tuple[dict[str, FloatArray], FloatArray, FloatArray, float]:
    """Continue the gait of one walker along ``slopes`` both ways from the anchor.

    Returns per-slope outputs, fixed points (S, 3), most negative real multiplier (S,) and the
    refined period-doubling slope (NaN if none in range).
    """
    S = slopes.size
    out = {k: np.full(S, np.nan) for k in _OUTPUTS}
    fixed = np.full((S, 3), np.nan)
    mnr = np.full(S, np.nan)
    gaits: dict[int, NewtonGait] = {}
    for direction in (1, -1):
        z = anchor
        rng = range(anchor_index, S) if direction == 1 else range(anchor_index - 1, -1, -1)
        for i in rng:
            try:
                g = newton_gait(walker, float(slopes[i]), z, rtol=rtol, atol=atol)
            except GaitNotFoundError:
                break  # the branch ends (fold or failure): leave the rest NaN
            gaits[i] = g
            z = g.z
            fixed[i] = g.z
            mnr[i] = g.most_negative_real
            out["spectral_radius"][i] = g.spectral_radius
            out["period"][i] = g.period
            out["step_length"][i] = g.step_length
            out["collision_loss"][i] = g.collision_loss
            out["impact_angle"][i] = g.impact_angle
    pd = float("nan")
    for i in range(S - 1):
        a, b = mnr[i], mnr[i + 1]
        if np.isfinite(a) and np.isfinite(b) and (a + 1.0) * (b + 1.0) < 0.0:
            pd = _refine_period_doubling(
                walker, float(slopes[i]), float(slopes[i + 1]), gaits[i], a, rtol, atol
            )
            break
    return out, fixed, mnr, pd


def _refine_period_doubling(
    walker: CompassGait,
    s0: float,
    s1: float,
    g0: NewtonGait,
    m0: float,
    rtol: float,
    atol: float,
) -> float:
    """:func:`~heelstrike.analysis.limit_cycle.refine_period_doubling` on the compiled map."""

    def solve(slope: float, z: FloatArray) -> tuple[float, FloatArray]:
        g = newton_gait(walker, slope, z, rtol=rtol, atol=atol)
        return g.most_negative_real, g.z

    return refine_period_doubling(solve, s0, s1, m0, g0.z)


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
    anchor_index: int,
    rtol: float,
    atol: float,
) -> dict[str, FloatArray]:
    """Sweep function: every radius of the chunk, all slopes (see the sweep contract)."""
    radii = np.asarray(foot_radius, dtype=float)[:, 0]
    slopes = np.asarray(slope, dtype=float)[0, :]
    table = {a[0]: np.array(a[1:]) for a in anchors}
    R_, S_ = radii.size, slopes.size
    res: dict[str, FloatArray] = {k: np.full((R_, S_), np.nan) for k in _OUTPUTS}
    res["fixed_point"] = np.full((R_, S_, 3), np.nan)
    res["most_negative_real_multiplier"] = np.full((R_, S_), np.nan)
    res["period_doubling_slope"] = np.full((R_, S_), np.nan)
    for j, R in enumerate(radii):
        anchor = table.get(float(R))
        if anchor is None or not np.all(np.isfinite(anchor)):
            continue
        w = CompassGait(foot_radius=float(R), **dict(walker))
        out, fixed, mnr, pd = _branch(w, slopes, anchor_index, anchor, rtol, atol)
        for k in _OUTPUTS:
            res[k][j] = out[k]
        res["fixed_point"][j] = fixed
        res["most_negative_real_multiplier"][j] = mnr
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
        (rad), ``fixed_point`` (+ ``section`` dim), ``most_negative_real_multiplier``; over
        ``foot_radius``: ``period_doubling_slope`` (rad, NaN if none in range). NaN where no
        period-one gait was found, and ``gait_found`` (bool) False there.
    """

    dataset: xr.Dataset

    @property
    def period_doubling_slope(self) -> FloatArray:
        """Period-doubling slope per radius (rad), shape (n_radius,)."""
        return np.asarray(self.dataset["period_doubling_slope"].values)


def _direct(walker: CompassGait, slope: float, rtol: float, atol: float) -> FloatArray:
    """The preferred gait of the automatic search at one radius, or NaNs if there is none."""
    try:
        return find_limit_cycle(walker, slope=slope, method="compiled", rtol=rtol,
                                atol=atol).fixed_point
    except GaitNotFoundError:
        return np.full(3, np.nan)


def _anchors(
    walker: CompassGait, radii: FloatArray, slope: float, guess: ArrayLike | None,
    rtol: float, atol: float,
) -> list[FloatArray]:
    """Gaits at ``slope`` for every radius (NaNs where none is found), by continuation in the
    radius in sorted order, from the point foot's preferred gait (or from ``guess`` at the
    smallest radius). Where the continuation breaks, the automatic search is run at that radius
    and the continuation restarts from what it finds; radii without a gait get NaNs and never
    abort the map."""
    order = np.argsort(radii)
    if guess is None:
        R_prev = 0.0
        z = _direct(walker.replace(foot_radius=0.0), slope, rtol, atol)
    else:
        R_prev = float(radii[order[0]])
        try:
            z = newton_gait(walker.replace(foot_radius=R_prev), slope, guess,
                            rtol=rtol, atol=atol).z
        except GaitNotFoundError:
            z = np.full(3, np.nan)
    out: list[FloatArray] = [np.full(3, np.nan)] * radii.size
    for k in order:
        R = float(radii[k])
        zk = np.full(3, np.nan)
        if np.all(np.isfinite(z)):
            # sub-steps of at most 0.05 m in the radius keep Newton in its basin
            n_sub = max(1, int(np.ceil(abs(R - R_prev) / 0.05)))
            try:
                zc = z
                for Rs in np.linspace(R_prev, R, n_sub + 1)[1:]:
                    zc = newton_gait(walker.replace(foot_radius=float(Rs)), slope, zc,
                                     rtol=rtol, atol=atol).z
                zk = zc
            except GaitNotFoundError:
                pass
        if not np.all(np.isfinite(zk)):
            zk = _direct(walker.replace(foot_radius=R), slope, rtol, atol)
        out[k] = zk
        if np.all(np.isfinite(zk)):
            z, R_prev = zk, R
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
        Section point near the gait of the smallest radius at the anchor slope (the grid slope
        closest to 3 deg); automatic search if omitted.
    rtol, atol : float
        Integrator tolerances of the compiled map.
    store : path, optional
        Zarr store of the sweep (resumable).
    scheduler : str, optional
        Dask scheduler of :func:`~heelstrike.analysis.sweep.sweep` (default threads).
    progress : bool
        Progress bar over radii.

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
    anchor_index = _anchor_index(S)
    anchors = _anchors(walker, R, float(S[anchor_index]), guess, rtol, atol)
    func = functools.partial(
        _map_chunk,
        walker=tuple(sorted(_walker_kwargs(walker).items())),
        anchors=tuple((float(r), *map(float, a)) for r, a in zip(R, anchors, strict=True)),
        anchor_index=anchor_index,
        rtol=float(rtol),
        atol=float(atol),
    )
    ds = sweep(
        func,
        {"foot_radius": R, "slope": S},
        chunks={"foot_radius": 1},
        store=None if store is None else str(store),
        scheduler=scheduler,
        progress=progress,
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
    ds.attrs.update(
        {f"walker_{k}": v for k, v in _walker_kwargs(walker).items()}
        | {"anchor_slope": float(S[anchor_index]), "rtol": rtol, "atol": atol}
    )
    return GaitMap(dataset=ds)


# -- described walkers (TOML models) -------------------------------------------------------------
def _model_multiplier(
    walker: BuiltWalker, backend: str, slope: float, guess: FloatArray
) -> tuple[float, FloatArray]:
    """Most negative real multiplier and fixed point of a described walker's gait at a slope
    (the ``solve`` of :func:`~heelstrike.analysis.limit_cycle.refine_period_doubling`)."""
    from heelstrike.analysis.model_gaits import find_model_gait

    try:
        g = find_model_gait(walker, slope=slope, guess=guess, backend=backend)
    except ValueError as exc:
        raise GaitNotFoundError(str(exc)) from exc
    mnr = _most_negative_real(np.asarray(g.cycle.multipliers))
    return (np.nan if mnr is None else mnr), np.asarray(g.cycle.fixed_point, dtype=float)


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

    For every parameter value (in the given order) the gait at the anchor slope (the grid slope
    closest to 3 deg) is found with :func:`~heelstrike.analysis.model_gaits.find_model_gait`,
    from the previous value's anchor gait (or the automatic search for the first one or after a
    failure); the branch is then continued up and down the slopes, each Newton solve starting
    from the neighbouring slope's fixed point.

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
        negative real multiplier crosses -1 between two grid slopes, located by
        :func:`~heelstrike.analysis.limit_cycle.refine_period_doubling` (the one definition;
        NaN if none in range).

    Raises
    ------
    ValueError
        Unknown parameter, or slopes not positive and increasing.
    """
    import sys

    import xarray as xr

    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.phased import PhasedWalker

    w0 = PhasedWalker.from_built(walker)
    if parameter not in w0.params:
        raise ValueError(f"unknown parameter {parameter!r}; known: {sorted(w0.params)}")
    P = np.asarray(values, dtype=float).ravel()
    S = np.asarray(slopes, dtype=float).ravel()
    if P.size < 1 or S.size < 1:
        raise ValueError("values and slopes must not be empty")
    _check_slopes(S)
    d = len(w0.section_names)
    shape = (P.size, S.size)
    out = {k: np.full(shape, np.nan) for k in _UNITS}
    fixed = np.full((*shape, d), np.nan)
    pd = np.full(P.size, np.nan)
    anchor = _anchor_index(S)
    prev_anchor: FloatArray | None = None
    for i, value in enumerate(P):
        try:
            w = w0.replace(**{parameter: float(value)})
        except ValueError:  # the description's constraints exclude this value: no gait
            prev_anchor = None
            continue

        def solve(
            j: int, guess: FloatArray | None, w: PhasedWalker = w, i: int = i
        ) -> FloatArray | None:
            try:
                g = find_model_gait(w, slope=float(S[j]), guess=guess, backend=backend)
            except (GaitNotFoundError, ValueError):
                return None
            mnr = _most_negative_real(np.asarray(g.cycle.multipliers))
            out["spectral_radius"][i, j] = float(np.max(np.abs(g.cycle.multipliers)))
            out["period"][i, j] = g.cycle.period
            out["step_length"][i, j] = g.cycle.step_length
            out["collision_loss"][i, j] = g.collision_loss
            out["impact_angle"][i, j] = g.cycle.impact_angle
            out["most_negative_real_multiplier"][i, j] = np.nan if mnr is None else mnr
            fixed[i, j] = g.cycle.fixed_point
            return np.asarray(g.cycle.fixed_point, dtype=float)

        z = solve(anchor, prev_anchor)
        if z is None and prev_anchor is not None:
            z = solve(anchor, None)
        prev_anchor = z
        for direction in (1, -1):
            guess = z
            j = anchor + direction
            while guess is not None and 0 <= j < S.size:
                guess = solve(j, guess)
                j += direction
        m = out["most_negative_real_multiplier"][i]
        for j in range(S.size - 1):
            if m[j] > -1.0 >= m[j + 1]:
                pd[i] = refine_period_doubling(functools.partial(_model_multiplier, w, backend),
                                               float(S[j]), float(S[j + 1]), float(m[j]),
                                               fixed[i, j])
                break
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
                     "anchor_slope": float(S[anchor])}
                    | {f"param_{k}": float(np.asarray(v)) for k, v in w0.params.items()
                       if k != parameter})
    return GaitMap(dataset=ds)


def compass_bifurcation(
    walker: CompassGait,
    slopes: ArrayLike,
    *,
    transient: int = 50,
    record: int = 16,
    continuation_points: int = 12,
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
    marks the period-doubling slopes, all on one ``backend``. :func:`model_bifurcation` is the
    same for a described walker.

    Parameters
    ----------
    walker : CompassGait
    slopes : array_like, shape (K,)
        Increasing slopes (rad), > 0.
    transient, record : int
        Steps discarded and recorded per slope.
    continuation_points : int
        Slopes of the branch.
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
        If there is no gait at the first slope.
    ValueError
        Unknown backend.
    """
    from heelstrike.dynamics.backends import simulator as backend_simulator

    simulator = backend_simulator(walker, backend)  # ValueError: unknown or unsupported backend
    sl = np.asarray(slopes, dtype=float).ravel()
    # the gait at the first slope (its fixed point seeds the walks and the branch): the
    # automatic search, with Newton on the chosen backend's map
    first = find_limit_cycle(walker, slope=float(sl[0]), progress=progress,
                             method="compiled" if backend == "compiled" else "scipy")
    return _diagram_and_branch(
        walker, sl, first.fixed_point, simulator, transient=transient, record=record,
        continuation_points=continuation_points, progress=progress, walk_tolerances={},
        branch_tolerances={"rtol": 1e-10, "atol": 1e-10},
    )


def _diagram_and_branch(
    walker: Any, slopes: FloatArray, z0: ArrayLike, simulator: Any, *, transient: int,
    record: int, continuation_points: int, progress: bool, walk_tolerances: dict[str, Any],
    branch_tolerances: dict[str, Any],
) -> tuple[BifurcationDiagram, Continuation]:
    """The brute-force diagram and the continued period-one branch over ``slopes``, both from
    the fixed point ``z0`` at the first slope, on ``simulator`` (the bifurcation functions'
    shared part)."""
    from heelstrike.analysis.limit_cycle import bifurcation_diagram, continue_limit_cycle

    diagram = bifurcation_diagram(walker, slopes, guess=z0, transient=transient, record=record,
                                  progress=progress, simulator=simulator, **walk_tolerances)
    branch = continue_limit_cycle(
        walker, "slope", np.linspace(slopes[0], slopes[-1], max(int(continuation_points), 1)),
        guess=z0, progress=progress, simulator=simulator, **branch_tolerances,
    )
    return diagram, branch


def model_bifurcation(
    walker: BuiltWalker,
    slopes: ArrayLike,
    *,
    transient: int = 50,
    record: int = 16,
    continuation_points: int = 12,
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

    Parameters
    ----------
    walker : BuiltWalker
    slopes : array_like, shape (K,)
        Increasing slopes (rad), > 0.
    transient, record : int
        Steps discarded and recorded per slope.
    continuation_points : int
        Slopes of the branch, evenly spaced over the same range.
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
        If there is no gait at the first slope.
    """
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.backends import simulator as backend_simulator
    from heelstrike.dynamics.phased import PhasedWalker

    w = PhasedWalker.from_built(walker)
    simulator = backend_simulator(w, backend)  # ValueError: unknown or unsupported backend
    sl = np.asarray(slopes, dtype=float).ravel()
    _check_slopes(sl)
    first = find_model_gait(w, slope=float(sl[0]), backend=backend)
    # the branch: each gait by Newton from the previous fixed point with find_model_gait's
    # tolerances
    return _diagram_and_branch(
        w, sl, first.cycle.fixed_point, simulator, transient=transient, record=record,
        continuation_points=continuation_points, progress=False,
        walk_tolerances={"rtol": rtol, "atol": atol},
        branch_tolerances={"tol": 1e-10, "max_iter": 20, "rtol": 1e-11, "atol": 1e-11},
    )
