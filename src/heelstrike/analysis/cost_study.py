"""Design study: what a real powered gait costs, over foot radius and step length (or speed).

For every actuation model, foot radius ``R`` and target step length ``L`` (or speed), the
level-ground periodic gait of :func:`heelstrike.analysis.powered.find_powered_gait` is found
and its energy books stored: actuator work and collision loss per step (equal on a periodic
gait, eq. 14-15 of Font & Kövecses 2008), ``eta = T_c / L`` (eq. 16) and the cost of transport
``W_act / (m g L)``. Gaits are continued along the grid (Newton starts from the neighbouring
gaits), so the grid should be ordered and reasonably fine. Several gaits can share a target
(e.g. push-off gaits with a long, cheap and a short, costly stance at the same speed), and
continuation can follow a costly branch (it did near McGeer's wheel, ``R = l``): at every grid
point fresh searches from several seeds are run as well, and a deflated search beside the gaits
found (a stable gait 1 % from an unstable one, issue 32). The gait kept is the first in the one
order of gaits (:func:`~heelstrike.analysis._gait_order.gait_order`): the cheapest stable gait,
else the cheapest unstable one (``stable`` says which; ``branch`` whether it came from
continuation or a fresh search, ``gaits_found`` how many distinct gaits were met), an ordinary
step before a multi-swing gait (``leg_crossings``: its swing foot passes through the ground
away from mid-stance, outside the scuffing convention).

The paper's own measure is evaluated alongside: ``eta`` of the heel strike alone with the
*imposed* pre-impact velocities of the paper (``q3_dot = 1 rad/s``, ``q4_dot = 0``) at the
impact angle that gives the same step length, ``L = 2 (l - R) sin q3 + 2 R q3``; and with the
real gait's own pre-impact velocities this is exactly the gait's ``eta``.

Described walkers (``model``, a walker file with a foot radius parameter ``R``: the shipped
compass, kneed and torso walkers) are studied the same way with
:func:`~heelstrike.analysis.powered.find_model_powered_gait`: push-off actuation plus the posture
law the file declares, or a hip law on a walker whose one actuated joint is its hip (compass,
kneed), the cost of transport with the walker's own scale (total mass, gravity,
leg length). Their energy book per step is ``push_off_work + torque_work = collision_loss`` (the
paper's impact-only measure is for the compass gait only and is not evaluated for them).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from heelstrike._typing import FloatArray
from heelstrike.analysis._gait_order import gait_order, ordered_gaits
from heelstrike.analysis._memory import require_budget
from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.heel_strike import heel_strike_study
from heelstrike.analysis.powered import (
    ACTUATIONS,
    BOOKS_FLOOR,
    PoweredGaitNotFoundError,
    _augmented,
    _count_distinct,
    _fresh_gaits,
    _other_gaits,
    _same_gait,
    _seed_walker,
    _solver,
    actuation_family,
    check_model_actuation,
    family_simulator,
    impact_angle_for_step_length,
)
from heelstrike.models.base import check_backend_name
from heelstrike.models.compass import CompassGait

__all__ = [
    "BRANCH_NOTE",
    "GAIT_VARIABLES",
    "STUDY_BYTES_PER_POINT",
    "cheapest_gaits",
    "check_study_memory",
    "cost_study",
    "paper_eta",
]

#: Memory (bytes) a study needs per (actuation, radius, target) point, an upper estimate: the
#: gait variables (about 200 B), the failure message (512 B of UTF-8 in a row, up to 2 KiB as
#: a str in the dataset), the continuation seed and the figures' arrays.
STUDY_BYTES_PER_POINT = 4096

#: Gait quantities stored per (actuation, radius, target) and their units.
GAIT_VARIABLES: dict[str, tuple[str, str]] = {
    "cost_of_transport": ("1", "W_act / (m_total g L_S), W_act the net actuator work per step"),
    "eta": ("J/m", "collision loss per metre T_c / L_S (eq. 16)"),
    "actuator_work": ("J", "actuator work per step"),
    "push_off_work": ("J", "work of the push-off impulse per step"),
    "torque_work": ("J", "work of the torque law (hip or posture) per step"),
    "collision_loss": ("J", "collision loss per step T_c (eq. 15)"),
    "work_per_metre": ("J/m", "actuator work per metre W_act / L_S"),
    "period": ("s", "step duration"),
    "step_length": ("m", "step length L_S"),
    "speed": ("m/s", "mean speed"),
    "impact_angle": ("rad", "stance angle q3 at heel strike"),
    "parameter": ("", "actuation parameter found by Newton (its unit: parameter_unit)"),
    "spectral_radius": ("1", "largest Floquet multiplier modulus"),
    "stable": ("1", "1 if stable, 0 if unstable, NaN where no gait or where stability is "
               "undecided (McGeer's wheel, R = l: a multiplier of 1)"),
    "energy_balance_error": ("J", "W_act - T_c - change of mechanical energy"),
    "leg_crossings": ("1", "times the swing leg crosses the stance leg in a step (1: an "
                      "ordinary step; more: a multi-swing gait, kept only where no other)"),
    # the torque law's gains as used (NaN where the law has none: the push-off alone)
    "gain": ("s/rad", "energy-tracking gain k of the hip law (hip-energy)"),
    "kp": ("N m/rad", "stiffness of the torque law (hip-pd, a posture law)"),
    "kd": ("N m s/rad", "damping of the torque law (hip-pd, a posture law)"),
    "max_torque": ("N m", "torque limit of the hip law"),
}



def paper_eta(walker: CompassGait, step_length: float) -> tuple[float, float]:
    """Paper's impact-only ``(eta, T_c)`` at the step length ``L`` (J/m, J).

    Imposed pre-impact velocities ``q3_dot = 1 rad/s``, ``q4_dot = 0`` (paper, Figs. 2-3).
    """
    q3 = impact_angle_for_step_length(walker, step_length)
    if not np.isfinite(q3):
        return float("nan"), float("nan")
    st = heel_strike_study(walker, q3)
    return float(st.eta), float(st.energy_lost)


def _row(g: Gait) -> dict[str, float]:
    """The study's variables of one powered gait; ``stable`` is NaN where its stability is
    undecided (:attr:`~heelstrike.analysis.gaits.Gait.stability_undecided`: McGeer's wheel, a
    neutral family, a multiplier of 1, whose flags would alternate 1, 0)."""
    a = g.actuation
    if a is None:
        raise ValueError("the cost study's gaits are powered (a passive gait has no actuation)")
    return {
        "cost_of_transport": g.cost_of_transport,
        "eta": g.eta,
        "actuator_work": g.actuator_work,
        "push_off_work": a.push_off_work,
        "torque_work": a.torque_work,
        "collision_loss": g.collision_loss,
        "work_per_metre": g.actuator_work / g.step_length,
        "period": g.period,
        "step_length": g.step_length,
        "speed": g.speed,
        "impact_angle": g.impact_angle,
        "parameter": a.parameter,
        "spectral_radius": float(np.max(np.abs(g.multipliers))),
        "stable": np.nan if g.stability_undecided else float(g.stable),
        "energy_balance_error": g.energy_balance_error,
        "leg_crossings": np.nan if g.leg_crossings is None else float(g.leg_crossings),
        **{k: a.gains.get(k, np.nan) for k in ("gain", "kp", "kd", "max_torque")},
    }


def cost_study(
    radii: ArrayLike,
    targets: ArrayLike,
    *,
    target: str = "step_length",
    actuations: Sequence[str] = ("pushoff",),
    walker: CompassGait | None = None,
    model: Any | None = None,
    backend: str | None = None,
    actuation_options: dict[str, float] | None = None,
    radius_step: float = 0.05,
    progress: bool = False,
    store: str | os.PathLike[str] | None = None,
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
    model : BuiltWalker, optional
        A described walker with a foot radius parameter ``R`` (m) instead of the compass gait
        (:func:`~heelstrike.analysis.powered.find_model_powered_gait`: the push-off with its
        posture law, or the hip laws where
        :func:`~heelstrike.analysis.powered.check_model_actuation` admits them); its other
        parameters are kept.
    backend : {"compiled", "scipy"} or None
        Step simulator (:func:`~heelstrike.analysis.powered.family_simulator`). None (default):
        compiled where its kernels run the actuation and walker (push-off, the hip laws, a
        model's posture law), else the scipy reference (McGeer's wheel ``R = l``); the
        ``backend`` variable records which ran.
    actuation_options : dict, optional
        Gains and torque limit of the hip laws for
        :func:`~heelstrike.analysis.powered.actuation_family` (default: the walker's
        :func:`~heelstrike.dynamics.actuation.default_gains`).
    radius_step : float
        Largest radius increment (m) of the continuation between grid radii.
    progress : bool
        Show a progress bar.
    store : path, optional
        Directory of resumable Zarr stores (:func:`~heelstrike.analysis.sweep.sweep`), one per
        actuation and radius row (``<store>/<actuation>/radius_<i>.zarr``; a row continues from
        the gaits of the previous one, so a row is the unit of resuming): finished rows are
        kept, and an interrupted study with the same arguments resumes after them.
    **kwargs
        Passed to :func:`~heelstrike.analysis.powered.find_powered_gait`.

    Returns
    -------
    xarray.Dataset
        Dimensions ``actuation`` x ``radius`` x ``step_length`` (or ``speed``) with the
        :data:`GAIT_VARIABLES` but the target itself (NaN where no gait was found),
        ``found`` (1 where a gait was found, else 0), every gait found listed over one more
        dimension ``gait`` (``LISTED_VARIABLES`` as ``gait_<name>``, in the one order of
        gaits: the kept one first, unstable ones marked by ``gait_stable`` 0), ``failure``
        messages, ``backend`` (per
        actuation and radius: the step simulator that ran, ``"compiled"`` or ``"scipy"``), and
        the paper's impact-only ``eta_paper`` and ``collision_loss_paper`` over ``radius`` x
        target (only for the compass gait and ``target="step_length"``).

    Raises
    ------
    MemoryError
        The grid would not fit in the available memory (:data:`STUDY_BYTES_PER_POINT` a
        point), before any computing.
    ValueError
        Bad target or actuation, ``backend="compiled"`` with McGeer's wheel; with ``model``:
        no parameter ``R``, a radius the walker file rejects, a hip law on a walker with other
        actuated joints, ``actuation_options`` with the push-off alone, or ``walker`` given.
    """
    if target not in ("step_length", "speed"):
        raise ValueError("target must be 'step_length' or 'speed'")
    for name in actuations:
        if name not in ACTUATIONS:
            raise ValueError(f"unknown actuation {name!r}: choose from {', '.join(ACTUATIONS)}")
    base = walker if walker is not None else CompassGait()
    R = np.asarray(radii, dtype=float).ravel()
    T = np.asarray(targets, dtype=float).ravel()
    check_study_memory(len(actuations), R.size, T.size)
    if model is not None:
        backend = backend or "compiled"
        _check_model(model, R, actuations, actuation_options, walker, backend)
        backends = [[backend] * R.size for _ in actuations]
    else:  # the step simulator of each actuation and radius (ValueError: compiled with a hip
        # law, or with McGeer's wheel, which the generated kernel does not walk)
        backends = [
            ["scipy" if family_simulator(base.replace(foot_radius=float(r)), actuation_family(
                act, **(actuation_options or {})), backend) is None else "compiled" for r in R]
            for act in actuations
        ]
    if store is not None:
        _check_store_folder(Path(store))
    shape = (len(actuations), R.size, T.size)
    data = {k: np.full(shape, np.nan) for k in GAIT_VARIABLES}
    branch = np.full(shape, np.nan)
    n_found = np.zeros(shape, dtype=np.int64)
    listed = {k: np.full((*shape, LISTED_GAITS), np.nan) for k in LISTED_VARIABLES}
    failure = np.full(shape, "", dtype=object)
    total = shape[0] * shape[1] * shape[2]
    bar: Any = None
    if progress:
        from heelstrike._progress import progress_bar

        bar = progress_bar(total=total, desc="cost study", delay=0.0, leave=True)
    for a, act in enumerate(actuations):
        previous: tuple[tuple[float, ...], ...] = ((),) * T.size
        for i in range(R.size):
            func = functools.partial(
                _study_row, actuation=act,
                actuation_options=tuple(sorted((actuation_options or {}).items())),
                walker=base, radii=tuple(map(float, R)), i=i, previous=previous, kind=target,
                radius_step=float(radius_step), options=tuple(sorted(kwargs.items())),
                model=model, backend=backends[a][i],
                model_key="" if model is None else _model_key(model),
            )
            row = _run_row(func, T, target,
                           None if store is None else Path(store) / act / f"radius_{i:03d}.zarr")
            for k in GAIT_VARIABLES:
                data[k][a, i] = row[k]
            failure[a, i] = [_decode(b) for b in row["failure"]]
            branch[a, i] = row["branch"]
            n_found[a, i] = row["gaits_found"]
            for k in LISTED_VARIABLES:
                listed[k][a, i] = row[f"gait_{k}"]
            previous = tuple(tuple(map(float, x[:n])) for x, n in
                             zip(row["seed"], row["seed_size"], strict=True))
            if bar is not None:
                bar.update(T.size)
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
    ds["found"] = (dims, np.isfinite(data["cost_of_transport"]).astype(np.int8), {
        "units": "1", "long_name": "1 where a periodic gait was found, 0 where none"})
    ds["failure"] = (dims, failure.astype(str))
    ds["branch"] = (dims, branch, {
        "units": "1", "long_name": "how the kept (cheapest stable) gait was found",
        "flag_values": "0 1", "flag_meanings": "continuation fresh_search"})
    ds["gaits_found"] = (dims, n_found, {
        "units": "1", "long_name": "distinct periodic gaits found meeting the target"})
    for k, (unit, meaning) in LISTED_VARIABLES.items():
        ds[f"gait_{k}"] = ((*dims, "gait"), listed[k], {"units": unit, "long_name": meaning})
    ds["backend"] = (("actuation", "radius"), np.asarray(backends, dtype=str), {
        "long_name": "step simulator of the gaits (compiled or scipy)"})
    ds["parameter_unit"] = (("actuation",), np.asarray(
        [actuation_family(a).parameter_unit for a in actuations], dtype=str), {
        "long_name": "unit of the actuation parameter (N s: impulse, J: target energy, "
                     "rad: amplitude)"})
    if target == "step_length" and model is None:
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
        target=target, branch_note=BRANCH_NOTE,
        # the integrator's round-off of a step's energy: actuator work at or below it is none
        work_floor_J=BOOKS_FLOOR,
    )
    if model is None:
        ds.attrs.update(
            hip_mass=float(base.hip_mass), leg_mass=float(base.leg_mass),
            leg_length=float(base.leg_length), leg_com_from_hip=float(base.leg_com_from_hip),
            leg_inertia=float(base.leg_inertia), gravity=float(base.gravity),
        )
    else:
        scale = model.scale
        ds.attrs.update(
            model=str(model.description.name), backend=backend,
            total_mass=float(scale.total_mass), gravity=float(scale.gravity),
            leg_length=float(scale.leg_length),
            **{f"param_{k}": float(v) for k, v in sorted(model.parameters.items()) if k != "R"},
        )
    return ds


def cheapest_gaits(ds: xr.Dataset) -> list[dict[str, Any]]:
    """The cheapest gait of a cost study per actuation, and the cheapest stable one if it differs.

    Parameters
    ----------
    ds : xarray.Dataset
        A result of :func:`cost_study` (dimensions ``actuation``, ``radius`` and the target,
        ``ds.attrs["target"]``: ``step_length`` or ``speed``).

    Returns
    -------
    list of dict
        One row per actuation with at least one gait found (in the order of ``ds.actuation``),
        followed, when that gait is not stable, by a row for the cheapest stable gait of the
        same actuation if there is one. Keys: ``actuation``; ``which`` (``"cheapest"`` or
        ``"cheapest stable"``); ``radius`` (m); ``target`` (``"step_length"`` or ``"speed"``)
        and ``target_value`` (m or m/s); ``parameter`` and ``parameter_unit`` (the actuation
        parameter found by Newton); ``cost_of_transport`` (1); ``eta`` (J/m);
        ``spectral_radius`` (1); ``stable`` (True, False, or None where undecided: the
        dataset's ``stable`` is NaN); ``found`` and ``points`` (gaits found of grid points,
        this actuation).
    """
    target = str(ds.attrs["target"])
    rows: list[dict[str, Any]] = []
    for act in ds["actuation"].values:
        sub = ds.sel(actuation=act)
        cot = np.asarray(sub["cost_of_transport"].values, dtype=float)
        stable = np.asarray(sub["stable"].values, dtype=float)
        finite = np.isfinite(cot)
        if not finite.any():
            continue
        picks = [("cheapest", finite)]
        best = np.unravel_index(np.argmin(np.where(finite, cot, np.inf)), cot.shape)
        if stable[best] != 1.0 and (finite & (stable == 1.0)).any():
            picks.append(("cheapest stable", finite & (stable == 1.0)))
        for which, mask in picks:
            i, j = np.unravel_index(np.argmin(np.where(mask, cot, np.inf)), cot.shape)
            flag = float(stable[i, j])
            rows.append({
                "actuation": str(act), "which": which,
                "radius": float(sub["radius"].values[i]),
                "target": target, "target_value": float(sub[target].values[j]),
                "parameter": float(sub["parameter"].values[i, j]),
                "parameter_unit": str(sub["parameter_unit"].values),
                "cost_of_transport": float(cot[i, j]), "eta": float(sub["eta"].values[i, j]),
                "spectral_radius": float(sub["spectral_radius"].values[i, j]),
                "stable": None if not np.isfinite(flag) else bool(flag == 1.0),
                "found": int(finite.sum()), "points": int(cot.size),
            })
    return rows


def check_study_memory(n_actuations: int, n_radii: int, n_targets: int) -> None:
    """Raise ``MemoryError`` if a study of this size would not fit in the available memory
    (:data:`STUDY_BYTES_PER_POINT` a point); :func:`cost_study` checks it before computing."""
    require_budget(f"a {n_actuations}x{n_radii}x{n_targets} cost study",
                   n_actuations * n_radii * n_targets, bytes_per_point=STUDY_BYTES_PER_POINT,
                   hint="give fewer radii or targets (COUNT)")


def _check_model(
    model: Any, radii: FloatArray, actuations: Sequence[str],
    actuation_options: dict[str, float] | None, walker: CompassGait | None, backend: str,
) -> None:
    """Refuse what the described-walker study does not support (one-line messages)."""
    name = str(model.description.name)
    if walker is not None:
        raise ValueError("give either walker (the compass gait) or model, not both")
    for actuation in actuations:
        check_model_actuation(model, actuation)
    if actuation_options and set(actuations) == {"pushoff"}:
        raise ValueError("actuation_options set the hip laws, not the push-off (a posture "
                         "law's gains are declared in the walker file)")
    check_backend_name(backend)
    if "R" not in model.parameters:
        raise ValueError(f"model {name!r} has no foot radius parameter 'R' (its parameters: "
                         f"{', '.join(sorted(model.parameters))})")
    leg = float(model.scale.leg_length)
    for r in radii:
        if not 0.0 <= float(r) <= leg:
            raise ValueError(f"foot radius R = {float(r):g} m outside [0, {leg:g}] m "
                             f"(the leg length of model {name!r})")
        model.replace(R=float(r))  # the walker file's constraints (e.g. R <= l)


def _model_key(model: Any) -> str:
    """What identifies a described walker in a resumable store: its file's content and values."""
    desc = model.description
    key = "None" if desc is None else desc.structure_key()
    return f"{model!r}|{key}"


#: How each entry of the study was chosen (also on stdout and in the figures).
BRANCH_NOTE = (
    "Several periodic gaits can meet one target; each entry is the cheapest (least actuator "
    "work) stable gait of all gaits found there, else, where none is stable, the cheapest "
    "unstable one ('stable' 0): continuation from the neighbouring grid points, fresh "
    "searches from several seeds and deflated searches beside the gaits found ('branch': 0 "
    "continuation, 1 fresh search; 'gaits_found'); a gait whose legs cross more than once a "
    "step only where no other was found ('leg_crossings')."
)

_SEED_WIDTH = 16  # longest continuation seed (fixed point and actuation parameter) stored

#: Gaits listed per grid point (dimension ``gait``), in the one order of gaits: the kept one
#: first, then the others found there.
LISTED_GAITS = 8

#: What the study lists of every gait found at a grid point (``gait_<name>``) and its units.
LISTED_VARIABLES: dict[str, tuple[str, str]] = {
    "actuator_work": ("J", "actuator work per step of each gait found, in the one order of "
                           "gaits (the kept one first; NaN past the last)"),
    "spectral_radius": ("1", "largest Floquet multiplier modulus of each gait found"),
    "stable": ("1", "1 if that gait is stable, 0 if unstable, NaN past the last or where "
               "stability is undecided (McGeer's wheel)"),
    "leg_crossings": ("1", "times the swing leg crosses the stance leg in a step, each gait"),
}
_FAILURE_BYTES = 512  # failure messages are stored as UTF-8, NUL-padded, truncated


def _decode(raw: NDArray[np.uint8]) -> str:
    return bytes(np.asarray(raw, dtype=np.uint8)).rstrip(b"\0").decode("utf-8", errors="ignore")


def _check_store_folder(path: Path) -> None:
    """Refuse a ``store`` that is not a cost study's: a file, or a folder holding anything but
    its actuations' folders (``<store>/<actuation>/radius_<i>.zarr``). The study wrote its rows
    into any folder, next to what it held (QA sweep 13), where ``basin`` and ``map`` refuse a
    folder that is not a sweep store."""
    from heelstrike.analysis.sweep import SweepError

    if not path.exists():
        return
    if not path.is_dir():
        raise SweepError(f"{str(path)!r} exists and is a file, not a heelstrike cost-study "
                         "store: remove it or choose another store")
    foreign = sorted(p.name for p in path.iterdir() if p.name not in ACTUATIONS)
    if foreign:
        shown = ", ".join(repr(n) for n in foreign[:3]) + (", ..." if len(foreign) > 3 else "")
        raise SweepError(f"{str(path)!r} exists and is not a heelstrike cost-study store (it "
                         f"holds {shown}): remove it or choose another store")


def _run_row(
    func: Any, targets: FloatArray, kind: str, store: Path | None
) -> dict[str, NDArray[Any]]:
    """One radius row: directly, or as a one-chunk sweep kept in (and resumed from) ``store``."""
    if store is None:
        return {k: np.asarray(v) for k, v in func(target=targets).items()}
    from heelstrike.analysis.sweep import sweep

    ds = sweep(func, {"target": targets}, chunks=targets.size, store=store, scheduler="sync",
               progress=False, units={"target": "m" if kind == "step_length" else "m s-1"}
               | {k: "1" for k in (*GAIT_VARIABLES, "failure", "seed", "seed_size", "branch",
                                   "gaits_found", *(f"gait_{k}" for k in LISTED_VARIABLES))})
    return {str(k): np.asarray(ds[k].values) for k in ds.data_vars}


def _study_row(
    target: FloatArray,
    *,
    actuation: str,
    actuation_options: tuple[tuple[str, float], ...],
    walker: CompassGait,
    radii: tuple[float, ...],
    i: int,
    previous: tuple[tuple[float, ...], ...],
    kind: str,
    radius_step: float,
    options: tuple[tuple[str, Any], ...],
    model: Any | None = None,
    backend: str = "compiled",
    model_key: str = "",
) -> dict[str, NDArray[Any]]:
    """Gaits of radius row ``i`` over every target (a sweep function of the ``target`` grid).

    ``previous`` holds the continuation seeds of row ``i - 1`` per target (empty: none). Returns
    the :data:`GAIT_VARIABLES`, the row's own seeds (``seed``, NaN-padded, and ``seed_size``)
    and ``failure`` messages (UTF-8 bytes), each of shape ``(J, ...)``. With ``model`` (a
    described walker; ``model_key`` identifies it in a store) the gaits are those of
    :func:`~heelstrike.analysis.powered.find_model_powered_gait` on ``backend``.
    """
    del model_key  # only part of the sweep's fingerprint
    T = np.asarray(target, dtype=float).ravel()
    R = np.asarray(radii, dtype=float)
    r = float(R[i])
    base = walker
    kwargs = dict(options)
    family = actuation_family(actuation, **dict(actuation_options))
    solve = _solver(base, model, actuation, dict(actuation_options), backend)

    found: dict[tuple[int, int], FloatArray] = {
        (i - 1, j): np.asarray(x, dtype=float) for j, x in enumerate(previous) if len(x)
    }
    out = {k: np.full(T.size, np.nan) for k in GAIT_VARIABLES}
    failure = np.zeros((T.size, _FAILURE_BYTES), dtype=np.uint8)
    seed = np.full((T.size, _SEED_WIDTH), np.nan)
    seed_size = np.zeros(T.size, dtype=np.int64)
    branch = np.full(T.size, np.nan)
    n_found = np.zeros(T.size, dtype=np.int64)
    listed = {k: np.full((T.size, LISTED_GAITS), np.nan) for k in LISTED_VARIABLES}
    for j, v in enumerate(T):
        speed = float(v) if kind == "speed" else None
        length = float(v) if kind == "step_length" else None
        # Newton from each neighbour (previous radius, previous target); where gaits
        # coexist keep the one needing the least work; seed search if none converges
        gaits: list[Gait] = []
        for key in ((i - 1, j), (i, j - 1)):
            if key not in found:
                continue
            # radius steps larger than ``radius_step`` are bridged by intermediate
            # radii so that the continuation stays on one branch
            r_from = float(R[key[0]])
            n_sub = max(1, int(np.ceil(abs(r - r_from) / radius_step - 1e-9)))
            x = found[key]
            try:
                for r_sub in np.linspace(r_from, r, n_sub + 1)[1:]:
                    g_sub = solve(float(r_sub), guess=x, speed=speed, step_length=length,
                                  fallback=False, **kwargs)
                    x = _augmented(g_sub)
                gaits.append(g_sub)
            except (PoweredGaitNotFoundError, ValueError):
                pass
        n_continued = len(gaits)
        # fresh searches too (issue 11.8): continuation may sit on a costlier branch
        fresh, exc_fresh = _fresh_gaits(solve, r, _seed_walker(base, model, r), family,
                                        speed, length, kwargs)
        gaits += fresh
        # and the gaits beside those (issue 32: a stable gait 1 % from an unstable one)
        gaits += _other_gaits(solve, r, _seed_walker(base, model, r), gaits, speed, length,
                              kwargs)
        if not gaits and exc_fresh is not None:
            msg = str(exc_fresh).encode()[:_FAILURE_BYTES]
            failure[j, :len(msg)] = np.frombuffer(msg, dtype=np.uint8)
        if gaits:
            # the one order of gaits: the cheapest stable ordinary step, else the cheapest
            # unstable one; a multi-swing gait (its swing foot through the ground away from
            # mid-stance: QA sweep 6) only where no other meets the target
            # (McGeer's wheel: stability undecided, the cheapest)
            best = min(range(len(gaits)), key=lambda k: gait_order(gaits[k]))
            g = gaits[best]
            if g.residual > float(kwargs.get("tol", 1e-9)):
                # a fresh start's looser tolerance: polish it so that its energy book closes
                # (the compass gait's too, QA sweep 12: its books were open by 6.5e-8 J; where
                # Newton stalls at the integrator's noise floor, near the wheel, it is kept)
                try:
                    g = solve(r, guess=_augmented(g), speed=speed,
                              step_length=length, fallback=False, **kwargs)
                except (PoweredGaitNotFoundError, ValueError):
                    pass
            branch[j] = 0.0 if best < n_continued else 1.0
            n_found[j] = _count_distinct(gaits)
            for k, val in _row(g).items():
                out[k][j] = val
            _list_gaits(listed, j, g, [gaits[k] for k in range(len(gaits)) if k != best])
            found[(i, j)] = _augmented(g)
            n = min(found[(i, j)].size, _SEED_WIDTH)
            seed[j, :n], seed_size[j] = found[(i, j)][:n], n
    rows: dict[str, NDArray[Any]] = dict(out)
    return rows | {"failure": failure, "seed": seed, "seed_size": seed_size,
                   "branch": branch, "gaits_found": n_found} | {
        f"gait_{k}": val for k, val in listed.items()}


def _list_gaits(
    listed: dict[str, FloatArray], j: int, kept: Gait, others: list[Gait],
) -> None:
    """Fill row ``j`` of the ``listed`` arrays (``LISTED_VARIABLES``): the ``kept`` gait,
    then the distinct ``others`` in the one order of gaits (McGeer's wheel, its stability
    undecided: cheapest first), at most ``LISTED_GAITS``."""
    distinct: list[Gait] = [kept]
    for g in ordered_gaits(others):
        if all(not _same_gait(g, d) for d in distinct):
            distinct.append(g)
    for n, g in enumerate(distinct[:LISTED_GAITS]):
        row = _row(g)
        for k in LISTED_VARIABLES:
            listed[k][j, n] = row[k]
