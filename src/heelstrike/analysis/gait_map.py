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
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from heelstrike.analysis.limit_cycle import GaitNotFoundError, find_limit_cycle
from heelstrike.dynamics.compiled import COMPLETED, ensemble_walk
from heelstrike.models.compass import CompassGait

FloatArray = NDArray[np.float64]

__all__ = ["GaitMap", "NewtonGait", "gait_map", "newton_gait"]


@dataclass(frozen=True, kw_only=True)
class NewtonGait:
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
    """

    z: FloatArray
    multipliers: NDArray[np.complex128]
    period: float
    step_length: float
    collision_loss: float
    impact_angle: float
    residual: float

    @property
    def spectral_radius(self) -> float:
        """Largest multiplier modulus."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def most_negative_real(self) -> float:
        """Most negative real multiplier (NaN if none is real)."""
        m = self.multipliers
        real = m.real[np.abs(m.imag) < 1e-9 * np.maximum(1.0, np.abs(m))]
        return float(real.min()) if real.size else float("nan")


def _map_many(
    walker: CompassGait, Z: FloatArray, slope: float, rtol: float, atol: float
) -> tuple[FloatArray, Any]:
    res = ensemble_walk(walker, Z, slope, steps=1, rtol=rtol, atol=atol, parallel=False)
    out = np.where((res.status == COMPLETED)[:, None], res.z, np.nan)
    return out, res


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
    """Newton's method for ``P(z) = z`` on the compiled map, from ``guess``.

    Every iteration maps ``z`` and its 6 central-difference neighbours in one ensemble call.

    Raises
    ------
    GaitNotFoundError
        If a step fails or Newton does not converge.
    """
    z = np.asarray(guess, dtype=float).reshape(3).copy()
    eye = np.eye(3)

    def evaluate(z: FloatArray) -> tuple[FloatArray, FloatArray, Any]:
        dz = fd_step * np.maximum(1.0, np.abs(z))
        Z = np.vstack((z, z + eye * dz, z - eye * dz))
        out, res = _map_many(walker, Z, slope, rtol, atol)
        jac = (out[1:4] - out[4:7]).T / (2.0 * dz)
        return out[0], jac, res

    for it in range(max_iter + 1):
        Pz, jac, res = evaluate(z)
        if not np.all(np.isfinite(Pz)):
            raise GaitNotFoundError(f"the walker fails to take a step from {np.round(z, 6)}")
        F = Pz - z
        residual = float(np.linalg.norm(F))
        if residual < tol:
            if not np.all(np.isfinite(jac)):
                raise GaitNotFoundError("a step failed while estimating the Jacobian")
            mult = np.linalg.eigvals(jac).astype(complex)
            mult = mult[np.argsort(-np.abs(mult), kind="stable")]
            return NewtonGait(
                z=z,
                multipliers=mult,
                period=float(res.step_time[0, 0]),
                step_length=float(res.step_length[0, 0]),
                collision_loss=float(res.collision_loss[0, 0]),
                impact_angle=float(res.impact_angle[0, 0]),
                residual=residual,
            )
        if it == max_iter or not np.all(np.isfinite(jac)):
            break
        try:
            dz = np.linalg.solve(jac - eye, -F)
        except np.linalg.LinAlgError as exc:
            raise GaitNotFoundError("singular Newton system") from exc
        lam = 1.0
        while lam > 1e-3:
            trial, _ = _map_many(walker, (z + lam * dz)[None, :], slope, rtol, atol)
            if np.all(np.isfinite(trial)):
                break
            lam *= 0.5
        z = z + lam * dz
    raise GaitNotFoundError(f"Newton did not converge in {max_iter} iterations")


_OUTPUTS = ("spectral_radius", "period", "step_length", "collision_loss", "impact_angle")


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
                walker, float(slopes[i]), float(slopes[i + 1]), gaits[i], a, b, rtol, atol
            )
            break
    return out, fixed, mnr, pd


def _refine_period_doubling(
    walker: CompassGait,
    s0: float,
    s1: float,
    g0: NewtonGait,
    m0: float,
    m1: float,
    rtol: float,
    atol: float,
    iterations: int = 12,
) -> float:
    """Bisection on the slope for ``lambda_min = -1``, continuing the gait from ``g0``."""
    lo, hi, flo = s0, s1, m0 + 1.0
    z = g0.z
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        try:
            g = newton_gait(walker, mid, z, rtol=rtol, atol=atol)
        except GaitNotFoundError:
            break
        f = g.most_negative_real + 1.0
        if not np.isfinite(f):
            break
        if f * flo > 0.0:
            lo, flo, z = mid, f, g.z
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _walker_kwargs(walker: CompassGait) -> dict[str, float]:
    return {
        "hip_mass": float(walker.hip_mass),
        "leg_mass": float(walker.leg_mass),
        "leg_length": float(walker.leg_length),
        "leg_com_from_hip": float(walker.leg_com_from_hip),
        "leg_inertia": float(walker.leg_inertia),
        "gravity": float(walker.gravity),
    }


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
class GaitMap:
    """The stable-gait map.

    Attributes
    ----------
    dataset : xarray.Dataset
        Over ``foot_radius`` (m) x ``slope`` (rad): ``spectral_radius``, ``stable``, ``period``
        (s), ``step_length`` (m), ``speed`` (m/s), ``collision_loss`` (J), ``impact_angle``
        (rad), ``fixed_point`` (+ ``section`` dim), ``most_negative_real_multiplier``; over
        ``foot_radius``: ``period_doubling_slope`` (rad, NaN if none in range). NaN where no
        period-one gait was found.
    """

    dataset: xr.Dataset

    @property
    def period_doubling_slope(self) -> FloatArray:
        """Period-doubling slope per radius (rad), shape (n_radius,)."""
        return np.asarray(self.dataset["period_doubling_slope"].values)


def _anchors(
    walker: CompassGait, radii: FloatArray, slope: float, guess: ArrayLike | None,
    rtol: float, atol: float,
) -> list[FloatArray]:
    """Gaits at ``slope`` for every radius, by continuation in the radius (sorted order)."""
    order = np.argsort(radii)
    base = walker.replace(foot_radius=float(radii[order[0]]))
    if guess is None:
        z = find_limit_cycle(base, slope=slope, method="compiled", rtol=rtol, atol=atol).fixed_point
    else:
        z = newton_gait(base, slope, guess, rtol=rtol, atol=atol).z
    out: list[FloatArray] = [np.full(3, np.nan)] * radii.size
    R_prev = float(radii[order[0]])
    for k in order:
        R = float(radii[k])
        # sub-steps of at most 0.05 m in the radius keep Newton in its basin
        n_sub = max(1, int(np.ceil(abs(R - R_prev) / 0.05)))
        try:
            for Rs in np.linspace(R_prev, R, n_sub + 1)[1:]:
                z = newton_gait(walker.replace(foot_radius=float(Rs)), slope, z,
                                rtol=rtol, atol=atol).z
        except GaitNotFoundError:
            break
        out[k] = z
        R_prev = R
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
    if np.any(np.diff(S) <= 0) or S[0] <= 0:
        raise ValueError("slopes must be positive and increasing")
    if np.any(R < 0) or np.any(R > float(walker.leg_length)):
        raise ValueError("radii must satisfy 0 <= R <= leg_length")
    anchor_index = int(np.argmin(np.abs(S - np.deg2rad(3.0))))
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
        units={
            "spectral_radius": "1",
            "period": "s",
            "step_length": "m",
            "collision_loss": "J",
            "impact_angle": "rad",
            "fixed_point": "1",
            "most_negative_real_multiplier": "1",
            "period_doubling_slope": "rad",
        },
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
    ds["speed"] = (ds["step_length"] / ds["period"]).assign_attrs(units="m s-1")
    ds["stable"] = (ds["spectral_radius"] < 1.0).assign_attrs(
        long_name="all Floquet multipliers inside the unit circle"
    )
    ds.attrs.update(
        {f"walker_{k}": v for k, v in _walker_kwargs(walker).items()}
        | {"anchor_slope": float(S[anchor_index]), "rtol": rtol, "atol": atol}
    )
    return GaitMap(dataset=ds)
