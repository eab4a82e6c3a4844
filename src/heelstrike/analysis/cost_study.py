"""Design study: what a real powered gait costs, over foot radius and step length (or speed).

For every actuation model, foot radius ``R`` and target step length ``L`` (or speed), the
level-ground periodic gait of :func:`heelstrike.analysis.powered.find_powered_gait` is found
and its energy books stored: actuator work and collision loss per step (equal on a periodic
gait, eq. 14-15 of Font & Kövecses 2008), ``eta = T_c / L`` (eq. 16) and the cost of transport
``W_act / (m g L)``. Gaits are continued along the grid (Newton starts from the neighbouring
gaits), so the grid should be ordered and reasonably fine. Several gaits can share a target
(e.g. push-off gaits with a long, cheap and a short, costly stance at the same speed); where
both neighbours lead to different gaits the cheaper one is kept, but the study does not search
for every branch.

The paper's own measure is evaluated alongside: ``eta`` of the heel strike alone with the
*imposed* pre-impact velocities of the paper (``q3_dot = 1 rad/s``, ``q4_dot = 0``) at the
impact angle that gives the same step length, ``L = 2 (l - R) sin q3 + 2 R q3``; and with the
real gait's own pre-impact velocities this is exactly the gait's ``eta``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from heelstrike.analysis.heel_strike import heel_strike_study
from heelstrike.analysis.powered import (
    ACTUATIONS,
    PoweredGait,
    PoweredGaitNotFoundError,
    actuation_family,
    find_powered_gait,
)
from heelstrike.models.compass import CompassGait

FloatArray = NDArray[np.float64]

__all__ = [
    "GAIT_VARIABLES",
    "cost_study",
    "impact_angle_for_step_length",
    "paper_eta",
    "save_study",
]

#: Gait quantities stored per (actuation, radius, target) and their units.
GAIT_VARIABLES: dict[str, tuple[str, str]] = {
    "cost_of_transport": ("1", "W_act / (m_total g L_S)"),
    "eta": ("J/m", "collision loss per metre T_c / L_S (eq. 16)"),
    "actuator_work": ("J", "actuator work per step"),
    "collision_loss": ("J", "collision loss per step T_c (eq. 15)"),
    "work_per_metre": ("J/m", "actuator work per metre W_act / L_S"),
    "period": ("s", "step duration"),
    "step_length": ("m", "step length L_S"),
    "speed": ("m/s", "mean speed"),
    "impact_angle": ("rad", "stance angle q3 at heel strike"),
    "parameter": ("", "actuation parameter found by Newton"),
    "spectral_radius": ("1", "largest Floquet multiplier modulus"),
    "stable": ("1", "1 if stable, 0 if unstable, NaN where no gait"),
    "energy_balance_error": ("J", "W_act - T_c - change of mechanical energy"),
}


def impact_angle_for_step_length(walker: CompassGait, step_length: float) -> float:
    """``q3`` (rad) with ``2 (l - R) sin q3 + 2 R q3 = L`` (increasing on [0, pi/2])."""
    l, R = float(walker.leg_length), float(walker.foot_radius)

    def f(q3: float) -> float:
        return 2 * (l - R) * np.sin(q3) + 2 * R * q3 - step_length

    if f(np.pi / 2) < 0:
        return float("nan")
    return float(brentq(f, 0.0, np.pi / 2, xtol=1e-14))


def paper_eta(walker: CompassGait, step_length: float) -> tuple[float, float]:
    """Paper's impact-only ``(eta, T_c)`` at the step length ``L`` (J/m, J).

    Imposed pre-impact velocities ``q3_dot = 1 rad/s``, ``q4_dot = 0`` (paper, Figs. 2-3).
    """
    q3 = impact_angle_for_step_length(walker, step_length)
    if not np.isfinite(q3):
        return float("nan"), float("nan")
    st = heel_strike_study(walker, q3)
    return float(st.eta), float(st.energy_lost)


def _row(g: PoweredGait) -> dict[str, float]:
    return {
        "cost_of_transport": g.cost_of_transport,
        "eta": g.eta,
        "actuator_work": g.actuator_work,
        "collision_loss": g.collision_loss,
        "work_per_metre": g.actuator_work / g.step_length,
        "period": g.period,
        "step_length": g.step_length,
        "speed": g.speed,
        "impact_angle": g.impact_angle,
        "parameter": g.parameter,
        "spectral_radius": float(np.max(np.abs(g.multipliers))),
        "stable": float(g.stable),
        "energy_balance_error": g.energy_balance_error,
    }


def cost_study(
    radii: ArrayLike,
    targets: ArrayLike,
    *,
    target: str = "step_length",
    actuations: Sequence[str] = ("pushoff",),
    walker: CompassGait | None = None,
    actuation_options: dict[str, float] | None = None,
    radius_step: float = 0.05,
    progress: bool = False,
    **kwargs: Any,
) -> xr.Dataset:
    """Cost of transport and energy books over foot radius x step length (or speed).

    Parameters
    ----------
    radii : array_like, shape (K,)
        Foot radii ``R`` (m), ``0 <= R <= l``.
    targets : array_like, shape (J,)
        Step lengths (m) or speeds (m/s).
    target : {"step_length", "speed"}
        What ``targets`` are.
    actuations : sequence of str
        Actuation models (:data:`heelstrike.analysis.powered.ACTUATIONS`).
    walker : CompassGait, optional
        Other parameters of the walker (paper defaults).
    actuation_options : dict, optional
        Gains and torque limit for :func:`~heelstrike.analysis.powered.actuation_family`.
    radius_step : float
        Largest radius increment (m) of the continuation between grid radii.
    progress : bool
        Show a progress bar.
    **kwargs
        Passed to :func:`~heelstrike.analysis.powered.find_powered_gait`.

    Returns
    -------
    xarray.Dataset
        Dimensions ``actuation`` x ``radius`` x ``step_length`` (or ``speed``) with the
        :data:`GAIT_VARIABLES` but the target itself (NaN where no gait was found),
        ``failure`` messages, and the paper's impact-only ``eta_paper`` and
        ``collision_loss_paper`` over ``radius`` x target (only for ``target="step_length"``).
    """
    if target not in ("step_length", "speed"):
        raise ValueError("target must be 'step_length' or 'speed'")
    for name in actuations:
        if name not in ACTUATIONS:
            raise ValueError(f"unknown actuation {name!r}: choose from {', '.join(ACTUATIONS)}")
    base = walker if walker is not None else CompassGait()
    R = np.asarray(radii, dtype=float).ravel()
    T = np.asarray(targets, dtype=float).ravel()
    shape = (len(actuations), R.size, T.size)
    data = {k: np.full(shape, np.nan) for k in GAIT_VARIABLES}
    failure = np.full(shape, "", dtype=object)
    total = shape[0] * shape[1] * shape[2]
    bar: Any = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, desc="cost study")
    for a, act in enumerate(actuations):
        family = actuation_family(act, **(actuation_options or {}))
        found: dict[tuple[int, int], FloatArray] = {}
        for i, r in enumerate(R):
            w = base.replace(foot_radius=float(r))
            for j, v in enumerate(T):
                speed = float(v) if target == "speed" else None
                length = float(v) if target == "step_length" else None
                # Newton from each neighbour (previous radius, previous target); where gaits
                # coexist keep the one needing the least work; seed search if none converges
                gaits: list[PoweredGait] = []
                for key in ((i - 1, j), (i, j - 1)):
                    if key not in found:
                        continue
                    # radius steps larger than ``radius_step`` are bridged by intermediate
                    # radii so that the continuation stays on one branch
                    r_from = float(R[key[0]])
                    n_sub = max(1, int(np.ceil(abs(float(r) - r_from) / radius_step - 1e-9)))
                    x = found[key]
                    try:
                        for r_sub in np.linspace(r_from, float(r), n_sub + 1)[1:]:
                            g_sub = find_powered_gait(
                                base.replace(foot_radius=float(r_sub)), actuation=family,
                                guess=x, speed=speed, step_length=length, fallback=False,
                                **kwargs)
                            x = np.append(g_sub.fixed_point, g_sub.parameter)
                        gaits.append(g_sub)
                    except (PoweredGaitNotFoundError, ValueError):
                        pass
                if not gaits:
                    try:
                        gaits.append(find_powered_gait(
                            w, actuation=family, speed=speed, step_length=length, **kwargs))
                    except (PoweredGaitNotFoundError, ValueError) as exc:
                        failure[a, i, j] = str(exc)
                if gaits:
                    g = min(gaits, key=lambda x: x.actuator_work)
                    for k, val in _row(g).items():
                        data[k][a, i, j] = val
                    found[(i, j)] = np.append(g.fixed_point, g.parameter)
                if bar is not None:
                    bar.update(1)
    if bar is not None:
        bar.close()
    dims = ("actuation", "radius", target)
    coords = {
        "actuation": list(actuations),
        "radius": ("radius", R, {"units": "m", "long_name": "foot radius R"}),
        target: (target, T, {"units": "m" if target == "step_length" else "m/s"}),
    }
    # the gait's own step length (or speed) equals the target coordinate to solver tolerance
    ds = xr.Dataset(
        {k: (dims, v, {"units": GAIT_VARIABLES[k][0], "long_name": GAIT_VARIABLES[k][1]})
         for k, v in data.items() if k != target},
        coords=coords,
    )
    ds["failure"] = (dims, failure.astype(str))
    if target == "step_length":
        eta_p = np.full((R.size, T.size), np.nan)
        tc_p = np.full((R.size, T.size), np.nan)
        for i, r in enumerate(R):
            w = base.replace(foot_radius=float(r))
            for j, v in enumerate(T):
                eta_p[i, j], tc_p[i, j] = paper_eta(w, float(v))
        ds["eta_paper"] = (("radius", target), eta_p, {
            "units": "J/m",
            "long_name": "paper's impact-only eta, imposed q3_dot = 1 rad/s, q4_dot = 0"})
        ds["collision_loss_paper"] = (("radius", target), tc_p, {
            "units": "J", "long_name": "paper's impact-only T_c, imposed velocities"})
    ds.attrs.update(
        title="heelstrike cost-of-transport study (level ground, periodic powered gaits)",
        hip_mass=float(base.hip_mass), leg_mass=float(base.leg_mass),
        leg_length=float(base.leg_length), leg_com_from_hip=float(base.leg_com_from_hip),
        leg_inertia=float(base.leg_inertia), gravity=float(base.gravity), target=target,
        branch_note=(
            "Several periodic gaits can meet one target; each entry is the gait reached by "
            "continuation in foot radius from its neighbour, keeping the cheaper one found, "
            "not a search of every branch. Near R = l the cheap push-off branch's largest "
            "multiplier tends to 1 and continuation may land on a costlier branch."
        ),
    )
    return ds


def save_study(ds: xr.Dataset, path: str | Path) -> Path:
    """Write the study to netCDF (``path``) and return the path."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(p)
    return p
