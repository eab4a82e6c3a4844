"""Tables of a simulated walk: energy, impacts (heel and knee strikes), one step's kinematics
and ground reaction, the phase portrait and a strobe of stick figures.

Each function turns a :class:`~heelstrike.dynamics.hybrid.WalkResult` into a
:class:`pandas.DataFrame` in SI units, one column per quantity with its unit in the name
(``t_s``, ``kinetic_J``, ``normal_N``). :mod:`heelstrike.plots.gait` draws these tables and
:mod:`heelstrike.outputs` writes them (through :func:`heelstrike.io.write_csv`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from heelstrike._frames import slope_to_world
from heelstrike._typing import FloatArray
from heelstrike.dynamics.hybrid import (
    ImpactKind,
    PhasedWalkResult,
    WalkResult,
    ground_reaction,
)
from heelstrike.models.base import PlanarWalker
from heelstrike.models.compass import CompassGait

__all__ = [
    "WalkResult",
    "model_phase_portrait_table",
    "model_strobe_table",
    "model_walk_frames",
    "phase_portrait_table",
    "resample_walk",
    "step_table",
    "strobe_table",
    "walk_energy_table",
    "walk_frames",
    "walk_impact_table",
]


def _check_walk(walk: WalkResult, step: int | None = None) -> None:
    """Raise :class:`ValueError` if ``walk`` has no samples (or none in step ``step``)."""
    if walk.t.size == 0:
        raise ValueError("the walk has no samples")
    if step is not None and not np.any(walk.step == step):
        raise ValueError(f"the walk has no samples in step {step} (steps 0..{walk.step.max()})")


def _walker_of_step(walker: PlanarWalker, step: int) -> PlanarWalker:
    """The walker that takes step ``step`` of a walk started by ``walker``: itself, or for a
    walker whose legs differ the walker after its leg swap on odd steps
    (:meth:`~heelstrike.models.base.PlanarWalker.after_swap`)."""
    return walker if step % 2 == 0 else walker.after_swap()


def _sample_energies(walker: PlanarWalker, walk: WalkResult) -> tuple[FloatArray, FloatArray]:
    """Kinetic and potential energy (J) of every sample of ``walk``, each with the walker
    taking the sample's step, shapes (N,)."""
    q, qd = walk.q, walk.q_dot
    T = np.array(walker.kinetic_energy(q, qd), dtype=float)
    U = np.array(walker.potential_energy(q, walk.slope), dtype=float)
    other = walker.after_swap()
    if other is not walker:
        odd = np.asarray(walk.step) % 2 == 1
        T[odd] = other.kinetic_energy(q[odd], qd[odd])
        U[odd] = other.potential_energy(q[odd], walk.slope)
    return T, U


def walk_energy_table(walker: PlanarWalker, walk: WalkResult) -> pd.DataFrame:
    """Kinetic, potential and total mechanical energy at every sample of a walk.

    Parameters
    ----------
    walker : PlanarWalker
        The walker the walk was simulated with (a :class:`~heelstrike.models.CompassGait` or a
        described walker).
    walk : WalkResult
        A passive walk (:func:`heelstrike.dynamics.simulate`).

    Returns
    -------
    pandas.DataFrame
        One row per sample, columns ``t_s`` (s), ``step``, ``kinetic_J``, ``potential_J``,
        ``total_J`` (J). The potential energy is the walker's
        :meth:`~heelstrike.models.CompassGait.potential_energy` on the walk's slope. At a heel
        strike two rows share the impact time: the last sample of a step (just before the
        impact) and the first of the next (just after it, legs relabelled). For a walker whose
        legs differ the odd steps' energies are those of the walker after the leg swap (the
        walker that takes them).
    """
    _check_walk(walk)
    T, U = _sample_energies(walker, walk)
    return pd.DataFrame(
        {"t_s": walk.t, "step": walk.step, "kinetic_J": T, "potential_J": U,
         "total_J": T + U}
    )


def walk_impact_table(walker: PlanarWalker, walk: WalkResult) -> pd.DataFrame:
    """Mechanical energy just before and just after every impact of a walk, in time order.

    Every impact the walk records: its heel strikes and, for a described walker with knees
    (a :class:`~heelstrike.dynamics.hybrid.PhasedWalkResult`), its knee strikes
    (:attr:`~heelstrike.dynamics.hybrid.PhasedWalkResult.events`). Consecutive rows chain: the
    total after one impact is the total before the next, up to the integrator's energy drift
    in between (the walk is passive and conservative between impacts).

    Parameters
    ----------
    walker : PlanarWalker
        The walker the walk was simulated with (a :class:`~heelstrike.models.CompassGait` or a
        described walker).
    walk : WalkResult
        A passive walk.

    Returns
    -------
    pandas.DataFrame
        One row per impact, in time order: ``step`` (the step it belongs to: a heel strike
        ends it, a knee strike falls within it), ``kind`` (``"heel_strike"`` or
        ``"knee_strike"``, the ``ImpactKind`` of the
        impact), ``time_s`` (s), ``impact_angle_rad`` (the stance leg's angle ``q3`` at the
        impact, rad), ``total_before_J`` and ``total_after_J`` (J, from the walk's samples on
        either side of the impact; after the last impact, if no sample follows it, from the
        walk's final state), ``drop_J`` (their difference) and ``T_c_J``, the constrained
        kinetic energy of the impact (paper eq. 10), which an inert impact destroys:
        ``drop_J`` equals it.

    Raises
    ------
    ValueError
        If the walk has no samples, or its samples do not split into one stretch per impact.
    """
    _check_walk(walk)
    T_s, U_s = _sample_energies(walker, walk)
    E = T_s + U_s
    impacts = _impacts(walk)
    # the samples split into stretches between impacts: a heel strike starts a new step, a
    # knee strike a new phase of the same step (both sides of an impact are sampled)
    change = walk.step[1:] != walk.step[:-1]
    if isinstance(walk, PhasedWalkResult) and len(walk.phase) == walk.t.size:
        change |= np.asarray(walk.phase)[1:] != np.asarray(walk.phase)[:-1]
    last = np.nonzero(change)[0]  # last sample before each impact that samples follow
    if last.size not in (len(impacts), len(impacts) - 1):
        raise ValueError(f"the walk's samples split into {last.size + 1} stretches, which do "
                         f"not match its {len(impacts)} impacts")
    rows = []
    for i, (kind, step, time, angle, T_c) in enumerate(impacts):
        if i < last.size:
            before, after = float(E[last[i]]), float(E[last[i] + 1])
        else:  # nothing sampled after the walk's last impact
            before = float(E[-1])
            # after a heel strike with its leg swap the final state is the next step's
            swapped = kind == "heel_strike" and walk.ok
            final = _walker_of_step(walker, step + 1 if swapped else step)
            after = float(final.mechanical_energy(walk.final_q, walk.final_q_dot, walk.slope))
        rows.append(
            {
                "step": step,
                "kind": kind,
                "time_s": time,
                "impact_angle_rad": angle,
                "total_before_J": before,
                "total_after_J": after,
                "drop_J": before - after,
                "T_c_J": T_c,
            }
        )
    cols = ["step", "kind", "time_s", "impact_angle_rad", "total_before_J", "total_after_J",
            "drop_J", "T_c_J"]
    return pd.DataFrame(rows, columns=cols)


def _impacts(walk: WalkResult) -> list[tuple[ImpactKind, int, float, float, float]]:
    """``(kind, step, time, stance angle, T_c)`` of every impact of ``walk``, in time order:
    the events of a phased walk (knee strikes too), else its heel strikes."""
    events = walk.events if isinstance(walk, PhasedWalkResult) else ()
    if len(events) >= len(walk.impacts) and events:
        out = [(e.kind, int(e.step), float(e.time), float(e.q[2]),
                float(e.kinetic_energy_constrained)) for e in events]
    else:
        heel: ImpactKind = "heel_strike"
        out = [(heel, int(r.step), float(r.time), float(r.impact_angle),
                float(r.kinetic_energy_constrained)) for r in walk.impacts]
    return sorted(out, key=lambda row: row[2])  # stable: simultaneous impacts keep their order


def step_table(walker: PlanarWalker, walk: WalkResult, step: int = 0) -> pd.DataFrame:
    """Joint angles, rates and the stance foot's ground reaction over one step of a walk.

    Parameters
    ----------
    walker : PlanarWalker
        The compass gait or a described walker.
    walk : WalkResult
        A passive walk.
    step : int
        Which step (0-based).

    Returns
    -------
    pandas.DataFrame
        One row per sample of the step: ``t_s`` (time since the step began, s), for every
        angle coordinate ``q[2:]`` its angle ``<name>_rad`` (the stance link from the slope's
        normal, then the joints, each relative to its parent link), ``swing_rad`` (the swing
        leg's absolute angle, :meth:`~heelstrike.models.base.PlanarWalker.swing_leg_angle`),
        the rates ``<name>_dot_rad_s`` (rad/s), ``tangential_N`` and ``normal_N`` (force of the
        ground on the stance foot along and normal to the slope, N) and ``required_friction``
        (``|tangential| / normal``, the smallest Coulomb coefficient that prevents slipping)
        from :func:`heelstrike.dynamics.hybrid.ground_reaction`. The compass gait's columns are
        ``q3_rad``, ``q4_rad``, ``swing_rad`` (``q3 + q4``), ``q3_dot_rad_s``, ``q4_dot_rad_s``.
    """
    _check_walk(walk, step)
    sel = walk.step == step
    gr = ground_reaction(walker, walk)
    q, qd = walk.q[sel], walk.q_dot[sel]
    t = walk.t[sel]
    names = walker.coordinate_names
    columns: dict[str, Any] = {"t_s": t - t[0]}
    columns.update({f"{names[i]}_rad": q[:, i] for i in range(2, len(names))})
    columns["swing_rad"] = walker.swing_leg_angle(q)
    columns.update({f"{names[i]}_dot_rad_s": qd[:, i] for i in range(2, len(names))})
    columns.update({"tangential_N": gr.tangential[sel], "normal_N": gr.normal[sel],
                    "required_friction": gr.required_friction[sel]})
    return pd.DataFrame(columns)


def phase_portrait_table(walk: WalkResult) -> pd.DataFrame:
    """Leg angles and angular rates at every sample of a walk (the phase portrait's data).

    Returns
    -------
    pandas.DataFrame
        Columns ``t_s`` (s), ``step``, ``q3_rad``, ``q3_dot_rad_s`` (stance leg) and
        ``swing_rad``, ``swing_dot_rad_s`` (swing leg's absolute angle ``q3 + q4`` and its rate).
    """
    _check_walk(walk)
    q, qd = walk.q, walk.q_dot
    return pd.DataFrame(
        {
            "t_s": walk.t,
            "step": walk.step,
            "q3_rad": q[:, 2],
            "q3_dot_rad_s": qd[:, 2],
            "swing_rad": q[:, 2] + q[:, 3],
            "swing_dot_rad_s": qd[:, 2] + qd[:, 3],
        }
    )


def _strobe_samples(walk: WalkResult, step: int, frames: int) -> tuple[NDArray[np.int_], float]:
    """Indices of the samples nearest ``frames`` evenly spaced instants of step ``step`` (the
    last: the sample just before its impact) and the step's start time (s)."""
    if frames < 2:
        raise ValueError(f"frames must be >= 2, got {frames}")
    _check_walk(walk, step)
    ids = np.nonzero(walk.step == step)[0]
    t = walk.t[ids]
    want = np.linspace(t[0], t[-1], frames)
    return ids[np.clip(np.searchsorted(t, want), 0, ids.size - 1)], float(t[0])


def strobe_table(
    walker: CompassGait, walk: WalkResult, step: int = 0, frames: int = 7
) -> pd.DataFrame:
    """Positions of the walker at ``frames`` evenly spaced instants of one step.

    Returns
    -------
    pandas.DataFrame
        One row per frame, world frame (x along the horizontal, y up; m): ``t_s`` (time since
        the step began, s), ``hip_x_m``, ``hip_y_m``, ``stance_foot_x_m``, ``stance_foot_y_m``,
        ``swing_foot_x_m``, ``swing_foot_y_m`` (centres of the foot arcs), ``stance_rad`` and
        ``swing_rad`` (leg angles from the slope's normal) and ``stance_leg`` (which physical
        leg stands: 0 or 1). The last frame is the instant of heel strike.
    """
    pick, t0 = _strobe_samples(walk, step, frames)
    return _compass_positions(walker, walk, pick, t0)


def _compass_positions(
    walker: CompassGait, walk: WalkResult, pick: NDArray[np.int_], t0: float
) -> pd.DataFrame:
    """:func:`strobe_table`'s columns at the samples ``pick``, ``t_s`` counted from ``t0``."""
    q = walk.q[pick]
    pos = walker.positions(q)
    hip = slope_to_world(pos.hip, walk.slope)
    st = slope_to_world(pos.right_foot_centre, walk.slope)
    sw = slope_to_world(pos.left_foot_centre, walk.slope)
    return pd.DataFrame(
        {
            "t_s": walk.t[pick] - t0,
            "hip_x_m": hip[:, 0], "hip_y_m": hip[:, 1],
            "stance_foot_x_m": st[:, 0], "stance_foot_y_m": st[:, 1],
            "swing_foot_x_m": sw[:, 0], "swing_foot_y_m": sw[:, 1],
            "stance_rad": q[:, 2], "swing_rad": walker.swing_leg_angle(q),
            "stance_leg": walk.stance_leg[pick],
        }
    )


def resample_walk(walk: WalkResult, fps: float) -> tuple[FloatArray, NDArray[np.int_]]:
    """Indices of ``walk`` samples nearest to a uniform frame clock at ``fps`` frames/s.

    Returns
    -------
    times : ndarray, shape (F,)
        The clock's ticks (s), from the walk's first sample to its last.
    indices : ndarray of int, shape (F,)
        The first sample at or after each tick (the last sample for a last tick past the
        walk's end, by less than half a frame).
    """
    if walk.t.size == 0:
        raise ValueError("the walk has no samples")
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number of frames per second, got {fps}")
    times = np.arange(walk.t[0], walk.t[-1] + 0.5 / fps, 1.0 / fps)
    return times, np.clip(np.searchsorted(walk.t, times), 0, walk.t.size - 1)


def walk_frames(walker: CompassGait, walk: WalkResult, fps: float = 30.0) -> pd.DataFrame:
    """The compass gait's positions at the frames of an animation of its walk.

    Parameters
    ----------
    walker : CompassGait
    walk : WalkResult
    fps : float
        Frames per second of walk time; each frame shows the first sample at or after its tick
        (:func:`resample_walk`).

    Returns
    -------
    pandas.DataFrame
        One row per frame: :func:`strobe_table`'s columns, ``t_s`` the sample's time in the
        walk (s), and ``step`` (0-based).
    """
    _, pick = resample_walk(walk, fps)
    table = _compass_positions(walker, walk, pick, 0.0)
    table.insert(1, "step", walk.step[pick])
    return table


def model_phase_portrait_table(walker: Any, walk: WalkResult) -> pd.DataFrame:
    """:func:`phase_portrait_table` of a described walker's walk.

    ``q3_rad``, ``q3_dot_rad_s``: the stance (root) link's angle ``q[2]`` and rate;
    ``swing_rad``, ``swing_dot_rad_s``: the absolute angle and rate of the link hanging from the
    hip joint (the swing thigh or leg). Angles are linear in ``q``, so rates are the same map of
    ``q_dot``.

    Parameters
    ----------
    walker : BuiltWalker
        With a joint named ``hip``.
    walk : WalkResult
        Its walk (``simulate_phased`` or ``simulate_phased_compiled``).
    """
    _check_walk(walk)
    q, qd = walk.q, walk.q_dot
    return pd.DataFrame(
        {
            "t_s": walk.t,
            "step": walk.step,
            "q3_rad": q[:, 2],
            "q3_dot_rad_s": qd[:, 2],
            "swing_rad": walker.swing_leg_angle(q),
            "swing_dot_rad_s": walker.swing_leg_angle(qd),
        }
    )


def _link_sides(walker: Any) -> dict[str, int | None]:
    """Side of every link of a described walker: 0 on the stance side, 1 on the swing side
    (the link hanging from the hip joint and its descendants), None for a link without a mirror
    (a torso)."""
    links = walker.description.links
    swing = {links[walker.joint_index("hip") - 2].name}
    for lk in links:  # tree order: parents first
        if lk.parent in swing:
            swing.add(lk.name)
    return {lk.name: None if lk.mirror is None else int(lk.name in swing) for lk in links}


def model_strobe_table(
    walker: Any, walk: WalkResult, step: int = 0, frames: int = 7
) -> pd.DataFrame:
    """:func:`strobe_table` of a described walker: its own links, feet and point masses at
    ``frames`` evenly spaced instants of one step.

    Parameters
    ----------
    walker : BuiltWalker
        With a joint named ``hip`` (the swing side hangs from it).
    walk : WalkResult
        Its walk.
    step : int
        Which step (0-based).
    frames : int
        Number of instants (>= 2); the last is the sample just before the step's heel strike.

    Returns
    -------
    pandas.DataFrame
        One row per frame and drawn element, world frame (x along the horizontal, y up; m):
        ``frame`` (0-based), ``t_s`` (time since the step began, s), ``element`` (``"link"``,
        ``"foot"`` or ``"mass"``), ``name`` (the link's, foot's or point mass's name in the
        walker file), ``leg`` (the physical leg a link or foot belongs to, 0: the initial
        stance leg, 1: the other; -1 for a link of neither leg, e.g. a torso, and for the
        point masses),
        ``x0_m``, ``y0_m``, ``x1_m``, ``y1_m`` and ``radius_m``. A link runs from its proximal
        point ``(x0, y0)`` to its distal point ``(x1, y1)``; a foot is the arc of radius
        ``radius_m`` about its centre ``(x0, y0)``, ``(x1, y1)`` the arc's point on the axis of
        the foot's link (the foot's end of the leg); a point mass sits at ``(x0, y0)`` (equal
        to ``(x1, y1)``).
    """
    pick, t0 = _strobe_samples(walk, step, frames)
    return _model_elements(walker, walk, pick, t0)


def model_walk_frames(walker: Any, walk: WalkResult, fps: float = 30.0) -> pd.DataFrame:
    """A described walker's links, feet and point masses at the frames of an animation.

    Parameters
    ----------
    walker : BuiltWalker
        With a joint named ``hip``.
    walk : WalkResult
        Its walk.
    fps : float
        Frames per second of walk time (:func:`resample_walk`).

    Returns
    -------
    pandas.DataFrame
        :func:`model_strobe_table`'s rows and columns, one frame per tick, ``t_s`` the sample's
        time in the walk (s), and ``step`` (0-based) after ``t_s``.
    """
    _, pick = resample_walk(walk, fps)
    table = _model_elements(walker, walk, pick, 0.0)
    table.insert(2, "step", walk.step[pick][table["frame"].to_numpy()])
    return table


def _model_elements(
    walker: Any, walk: WalkResult, pick: NDArray[np.int_], t0: float
) -> pd.DataFrame:
    """:func:`model_strobe_table`'s rows at the samples ``pick``, ``t_s`` counted from ``t0``."""
    pos = {k: slope_to_world(np.asarray(v), walk.slope)
           for k, v in walker.positions(walk.q[pick]).items()}
    desc = walker.description
    links = {lk.name: lk for lk in desc.links}
    sides = _link_sides(walker)
    stance = np.asarray(walk.stance_leg[pick], dtype=int)
    t = walk.t[pick] - t0
    radii = [float(np.asarray(r)) for r in walker.foot_radii]

    def leg(side: int | None, f: int) -> int:
        return -1 if side is None else int(stance[f] if side == 0 else 1 - stance[f])

    rows: list[dict[str, Any]] = []
    for f in range(pick.size):
        head = {"frame": f, "t_s": float(t[f])}
        for lk in desc.links:
            a, b = pos[f"{lk.name}.proximal"][f], pos[f"{lk.name}.distal"][f]
            rows.append({**head, "element": "link", "name": lk.name,
                         "leg": leg(sides[lk.name], f), "x0_m": a[0], "y0_m": a[1],
                         "x1_m": b[0], "y1_m": b[1], "radius_m": 0.0})
        for foot, r in zip(desc.feet, radii, strict=True):
            lk = links[foot.link]
            c = pos[f"{foot.name}_foot.centre"][f]
            prox, dist = pos[f"{lk.name}.proximal"][f], pos[f"{lk.name}.distal"][f]
            # the root link's foot is at its proximal end, any other link's at its distal end
            end, other = (prox, dist) if lk.parent is None else (dist, prox)
            axis = (end - other) / np.linalg.norm(end - other)
            tip = c + r * axis
            rows.append({**head, "element": "foot", "name": f"{foot.name}_foot",
                         "leg": leg(sides[lk.name], f), "x0_m": c[0], "y0_m": c[1],
                         "x1_m": tip[0], "y1_m": tip[1], "radius_m": r})
        for pm in desc.point_masses:
            if pm.name in pos:
                m = pos[pm.name][f]
                rows.append({**head, "element": "mass", "name": pm.name, "leg": -1,
                             "x0_m": m[0], "y0_m": m[1], "x1_m": m[0], "y1_m": m[1],
                             "radius_m": 0.0})
    cols = ["frame", "t_s", "element", "name", "leg", "x0_m", "y0_m", "x1_m", "y1_m",
            "radius_m"]
    return pd.DataFrame(rows, columns=cols)
