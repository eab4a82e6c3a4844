"""Impacts along recorded motions: touchdowns of a trajectory against the rigid prediction.

A recorded trajectory (:class:`Trajectory`: time, ``q`` and ``v`` at every sample, in
Pinocchio's conventions) comes from a MuJoCo rollout (:func:`mujoco_rollout`, the optional
``mujoco`` package) or from a CSV/NPZ log (:func:`read_trajectory`). :func:`replay` finds its
touchdowns (a contact point's height crossing the ground downward between two samples), and at
each one compares the rigid impact that :func:`heelstrike.robots.robot_impact` predicts from
the last sample before it (``v+``, ``T_c``, ``T_a``, the share of ``T_c`` per contact) with what
the recorded motion did across the contact transient (kinetic energy lost over a stated window,
effective restitution of each striking contact's normal velocity).

The two conventions. Pinocchio's (heelstrike's): ``q`` holds the root free flyer as position
(m) and unit quaternion ``(x, y, z, w)``, then the joints; ``v`` holds the base's linear
velocity (m/s) and angular velocity (rad/s) **both in the base's own frame**, then the joint
rates.

MuJoCo's: ``qpos`` holds the free joint's position (m) and quaternion ``(w, x, y, z)``; ``qvel``
holds the free joint's linear velocity **in the world frame** and its angular velocity **in the
body's frame**. A ball joint's quaternion is ``(w, x, y, z)`` in MuJoCo and ``(x, y, z, w)`` in
Pinocchio (both with local angular velocity); hinges and slides are the same numbers.
:func:`mujoco_to_pinocchio` maps one to the other: the quaternions reordered, the base's linear
velocity rotated into the base frame (``R^T v_world``), and the root placement Pinocchio's MJCF
parser gives the free flyer undone (so that the base frame lands where MuJoCo has it).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._optional import require
from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.impact import ImpactInputError
from heelstrike.robots.contacts import (
    ContactSpec,
    contact_heights,
    robot_impact,
    robot_matrices,
)
from heelstrike.robots.loading import Robot, RobotError, _pin

__all__ = [
    "APPROACH_SPEED",
    "DEFAULT_CLEARANCE",
    "DEFAULT_WINDOW",
    "ReplayResult",
    "Touchdown",
    "Trajectory",
    "contact_height_history",
    "detect_touchdowns",
    "kinetic_energy",
    "mujoco_rollout",
    "mujoco_to_pinocchio",
    "potential_energy",
    "read_trajectory",
    "replay",
    "write_trajectory",
]

Convention = Literal["pinocchio", "mujoco"]
Signal = Literal["height", "mujoco"]

#: Default length (s) of the contact transient over which the recorded loss is measured.
DEFAULT_WINDOW = 0.01
#: Default lift (m) above the ground that ends a contact's stay on it (:func:`detect_touchdowns`).
DEFAULT_CLEARANCE = 1e-3
#: Approach speed (m/s) below which a striking contact's effective restitution is not defined.
APPROACH_SPEED = 1e-6


@dataclass(frozen=True, kw_only=True)
class Trajectory(ResultDictMixin):
    """A recorded motion in Pinocchio's conventions.

    Attributes
    ----------
    time : ndarray, shape (N,)
        Sample times (s), increasing.
    q : ndarray, shape (N, nq)
        Configurations (base position in m, quaternion ``x, y, z, w``, joint angles in rad).
    v : ndarray, shape (N, nv)
        Velocities (base linear in m/s and angular in rad/s in the base frame, joint rates).
    source : str
        Where it came from (a file, or ``"mujoco:<MJCF>"``).
    reference_kinetic : ndarray, shape (N,) or None
        The recorder's own kinetic energy (J) of each sample (a MuJoCo rollout: MuJoCo's
        ``mj_energyVel``), None for a log.
    contact_geoms : tuple of str
        Names of the geoms whose contacts were recorded (a MuJoCo rollout: every named geom
        of a body other than the world), empty for a log.
    touching : ndarray of bool, shape (N, len(contact_geoms)) or None
        Whether each of those geoms is in MuJoCo's contact list at each sample.
    """

    time: FloatArray
    q: FloatArray
    v: FloatArray
    source: str = ""
    reference_kinetic: FloatArray | None = None
    contact_geoms: tuple[str, ...] = ()
    touching: NDArray[np.bool_] | None = None

    def __post_init__(self) -> None:
        for name in ("time", "q", "v"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))
        t = self.time
        if t.ndim != 1 or t.size < 2:
            raise RobotError(f"a trajectory needs at least 2 samples, got {t.size}")
        if self.q.ndim != 2 or self.v.ndim != 2 or self.q.shape[0] != t.size \
                or self.v.shape[0] != t.size:
            raise RobotError(f"time, q and v must have one row per sample ({t.size}), got "
                             f"q {self.q.shape} and v {self.v.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(self.q))
                and np.all(np.isfinite(self.v))):
            raise RobotError("a trajectory's time, q and v must be finite")
        if np.any(np.diff(t) <= 0.0):
            raise RobotError("a trajectory's time must increase strictly")


def _quat_wxyz_to_matrix(wxyz: FloatArray) -> FloatArray:
    """Rotation matrices (N, 3, 3) of quaternions (N, 4) ``(w, x, y, z)`` (normalised here)."""
    qn = wxyz / np.linalg.norm(wxyz, axis=1, keepdims=True)
    w, x, y, z = qn.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], axis=1)


def mujoco_to_pinocchio(
    robot: Robot, qpos: ArrayLike, qvel: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Map MuJoCo states to Pinocchio's conventions (module doc), joint by joint.

    The joints must come in the same order in both models with the same sizes (what
    Pinocchio's MJCF parser builds from the file MuJoCo reads: :func:`mujoco_rollout` checks
    the names). A root free flyer whose joint placement is not the identity (Pinocchio's MJCF
    parser puts the root body's ``pos``/``quat`` there) has ``q`` set so that the base frame
    is the world pose MuJoCo's ``qpos`` gives.

    Parameters
    ----------
    robot : Robot
    qpos : array_like, shape (N, nq) or (nq,)
        MuJoCo positions: free joint ``(x, y, z)`` (m) and ``(w, x, y, z)``, ball joints
        ``(w, x, y, z)``, hinges (rad) and slides (m).
    qvel : array_like, shape (N, nv) or (nv,)
        MuJoCo velocities: free joint linear velocity in the world frame (m/s) and angular
        velocity in the body frame (rad/s), then the joint rates.

    Returns
    -------
    q : ndarray, shape (N, nq) or (nq,)
    v : ndarray, shape (N, nv) or (nv,)

    Raises
    ------
    RobotError
        Wrong sizes, or a joint that MJCF does not have (an unbounded revolute's
        ``(cos, sin)`` pair, a planar joint).
    """
    pin = _pin()
    qp = np.asarray(qpos, dtype=float)
    qv = np.asarray(qvel, dtype=float)
    single = qp.ndim == 1
    qp, qv = np.atleast_2d(qp), np.atleast_2d(qv)
    model = robot.model
    if qp.shape[1] != robot.nq or qv.shape[1] != robot.nv or qp.shape[0] != qv.shape[0]:
        raise RobotError(f"MuJoCo states must be (N, nq={robot.nq}) and (N, nv={robot.nv}), "
                         f"got {qp.shape} and {qv.shape}")
    q, v = qp.copy(), qv.copy()
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        kind, iq, iv = joint.shortname(), int(joint.idx_q), int(joint.idx_v)
        if kind == "JointModelFreeFlyer":
            R = _quat_wxyz_to_matrix(qp[:, iq + 3:iq + 7])
            pos = qp[:, iq:iq + 3]
            place = model.jointPlacements[jid]
            Rp, p = np.asarray(place.rotation), np.asarray(place.translation)
            Rj = np.einsum("ji,njk->nik", Rp, R)  # Rp^T R: the joint's own rotation
            q[:, iq:iq + 3] = (pos - p) @ Rp
            q[:, iq + 3:iq + 7] = [pin.Quaternion(Rn).coeffs() for Rn in Rj]
            v[:, iv:iv + 3] = np.einsum("nji,nj->ni", R, qv[:, iv:iv + 3])  # R^T v_world
        elif kind == "JointModelSpherical":
            q[:, iq:iq + 3], q[:, iq + 3] = qp[:, iq + 1:iq + 4], qp[:, iq]
        elif int(joint.nq) != int(joint.nv):
            raise RobotError(f"joint {str(model.names[jid])!r} ({kind}) has no MuJoCo "
                             "counterpart: give the log in Pinocchio's conventions")
    return (q[0], v[0]) if single else (q, v)


def _mujoco() -> Any:
    return require("mujoco", "a MuJoCo rollout", extra="mujoco")


def mujoco_rollout(
    mjcf: str | Path,
    *,
    duration: float,
    robot: Robot | None = None,
    qpos: ArrayLike | None = None,
    qvel: ArrayLike | None = None,
    keyframe: int | None = None,
    timestep: float | None = None,
    every: int = 1,
) -> Trajectory:
    """Simulate an MJCF with MuJoCo itself and record its motion in Pinocchio's conventions.

    MuJoCo (its own contacts, solver, integrator and timestep, unactuated: ``ctrl`` stays 0)
    runs from the initial state for ``duration`` seconds; every ``every``-th state is
    recorded with MuJoCo's kinetic energy (``mj_energyVel``, energy flag enabled) and which
    named geoms (of bodies other than the world) are in its contact list (within their
    ``margin``), then mapped by :func:`mujoco_to_pinocchio`. The Pinocchio model must
    reproduce MuJoCo's: its joints are matched by name and the kinetic energies of the mapped
    states must agree to 1e-6 (relative), else :class:`RobotError` says where they part.

    Parameters
    ----------
    mjcf : str or Path
        The MJCF file (root body with a ``<freejoint/>``).
    duration : float
        Simulated time (s), > 0.
    robot : Robot, optional
        The same file loaded by :func:`heelstrike.robots.load_mjcf` (loaded here if None).
    qpos : array_like, shape (nq,), optional
        Initial MuJoCo positions (default: the keyframe, else the model's ``qpos0``).
    qvel : array_like, shape (nv,), optional
        Initial MuJoCo velocities (default: the keyframe's, else zero).
    keyframe : int, optional
        Index of a ``<key>`` of the file to start from.
    timestep : float, optional
        Overrides the file's ``<option timestep>`` (s).
    every : int
        Record one state in ``every`` steps (>= 1).

    Returns
    -------
    Trajectory
        With ``reference_kinetic`` MuJoCo's kinetic energy (J) of each sample.

    Raises
    ------
    heelstrike._optional.MissingExtraError
        Without the ``mujoco`` package (one line naming the install).
    RobotError
        A file MuJoCo refuses, bad sizes, or a model Pinocchio reads differently.
    """
    mujoco = _mujoco()
    from heelstrike.robots.loading import load_mjcf

    if not (math.isfinite(duration) and duration > 0.0):
        raise RobotError(f"duration must be > 0 s, got {duration!r}")
    if every < 1:
        raise RobotError(f"every must be >= 1, got {every!r}")
    try:
        mm = mujoco.MjModel.from_xml_path(str(mjcf))
    except ValueError as exc:
        raise RobotError(f"{mjcf}: MuJoCo cannot load it ({str(exc).splitlines()[0]})") from None
    robot = load_mjcf(mjcf) if robot is None else robot
    if (mm.nq, mm.nv) != (robot.nq, robot.nv):
        raise RobotError(f"{mjcf}: MuJoCo has nq={mm.nq}, nv={mm.nv}, Pinocchio "
                         f"nq={robot.nq}, nv={robot.nv}")
    _check_joint_order(mujoco, mm, robot)
    if timestep is not None:
        if not (math.isfinite(timestep) and timestep > 0.0):
            raise RobotError(f"timestep must be > 0 s, got {timestep!r}")
        mm.opt.timestep = timestep
    mm.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    data = mujoco.MjData(mm)
    if keyframe is not None:
        if not 0 <= keyframe < mm.nkey:
            raise RobotError(f"{mjcf} has {mm.nkey} keyframe(s), no keyframe {keyframe}")
        mujoco.mj_resetDataKeyframe(mm, data, keyframe)
    for name, value, size, target in (("qpos", qpos, mm.nq, data.qpos),
                                      ("qvel", qvel, mm.nv, data.qvel)):
        if value is not None:
            arr = np.asarray(value, dtype=float).reshape(-1)
            if arr.shape != (size,) or not np.all(np.isfinite(arr)):
                raise RobotError(f"{name} must be {size} finite numbers, got {arr.shape}")
            target[:] = arr
    steps = math.ceil(duration / mm.opt.timestep - 1e-9)
    n = steps // every + 1
    t, qp, qv, ke = np.empty(n), np.empty((n, mm.nq)), np.empty((n, mm.nv)), np.empty(n)
    geoms = [(g, name) for g in range(mm.ngeom)
             if (name := mujoco.mj_id2name(mm, mujoco.mjtObj.mjOBJ_GEOM, g))
             and int(mm.geom_bodyid[g]) != 0]
    column = np.full(mm.ngeom, -1)
    column[[g for g, _ in geoms]] = np.arange(len(geoms))
    touching = np.zeros((n, len(geoms)), dtype=bool)
    for k in range(n):
        mujoco.mj_forward(mm, data)
        t[k], qp[k], qv[k], ke[k] = data.time, data.qpos, data.qvel, data.energy[1]
        listed = column[np.asarray(data.contact.geom[:data.ncon], dtype=int).reshape(-1)]
        touching[k, listed[listed >= 0]] = True
        if k < n - 1:
            for _ in range(every):
                mujoco.mj_step(mm, data)
    q, v = mujoco_to_pinocchio(robot, qp, qv)
    traj = Trajectory(time=t, q=q, v=v, source=f"mujoco:{mjcf}", reference_kinetic=ke,
                      contact_geoms=tuple(name for _, name in geoms), touching=touching)
    T = kinetic_energy(robot, traj)
    bad = np.abs(T - ke) > 1e-6 * np.maximum(np.abs(ke), 1e-9)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise RobotError(f"{mjcf}: Pinocchio's kinetic energy {T[i]:.9g} J differs from "
                         f"MuJoCo's {ke[i]:.9g} J at t = {t[i]:g} s: the two parsers read "
                         "the model differently")
    return traj


def _check_joint_order(mujoco: Any, mm: Any, robot: Robot) -> None:
    """Pinocchio's joints are MuJoCo's, in the same order (by name where MuJoCo names them)."""
    model = robot.model
    names = [mujoco.mj_id2name(mm, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(mm.njnt)]
    pin_names = [str(model.names[j]) for j in range(1, model.njoints)]
    if len(names) != len(pin_names):
        raise RobotError(f"MuJoCo has {len(names)} joints, Pinocchio {len(pin_names)} "
                         "(a body with several joints: not supported in a replay)")
    for j, (a, b) in enumerate(zip(names, pin_names, strict=True)):
        same_place = int(mm.jnt_qposadr[j]) == int(model.joints[j + 1].idx_q)
        if (a and a != b) or not same_place:
            raise RobotError(f"joint {j}: MuJoCo's {a!r} is not Pinocchio's {b!r} at the same "
                             "place of q")


def kinetic_energy(robot: Robot, traj: Trajectory) -> FloatArray:
    """``1/2 v^T M(q) v`` (J) of every sample of ``traj``, shape (N,)."""
    pin = _pin()
    data = robot.model.createData()
    q_all = robot.check_states(traj.q)
    return np.array([pin.computeKineticEnergy(robot.model, data, q, v)
                     for q, v in zip(q_all, traj.v, strict=True)])


def potential_energy(robot: Robot, traj: Trajectory) -> FloatArray:
    """Gravitational potential ``-m g^T c`` (J, Pinocchio's ``model.gravity``) per sample (N,)."""
    pin = _pin()
    data = robot.model.createData()
    return np.array([pin.computePotentialEnergy(robot.model, data, q)
                     for q in robot.check_states(traj.q)])


def read_trajectory(
    path: str | Path, robot: Robot, *, convention: Convention = "pinocchio"
) -> Trajectory:
    """Read a log: NPZ with arrays ``t`` (N,), ``q`` (N, nq), ``v`` (N, nv), HDF5 or CSV.

    An HDF5 file (``.h5``, ``.hdf5``; needs the ``hdf5`` extra, h5py) holds the same three
    datasets ``t``, ``q``, ``v`` at its root, or in the group named after ``#`` in the path
    (``log.h5#/run3``). The CSV has a header row and one row per sample: a column ``t`` (s),
    then ``q_0`` ... ``q_{nq-1}``, then ``v_0`` ... ``v_{nv-1}`` (by name; other columns are
    ignored). Units: s, m, rad, m/s, rad/s (SI).

    Parameters
    ----------
    path : str or Path
        ``.npz``, ``.h5``/``.hdf5`` (optionally ``FILE#GROUP``) or ``.csv`` file.
    robot : Robot
        The robot the log records (sizes checked).
    convention : {"pinocchio", "mujoco"}
        Pinocchio's ``q``/``v`` (module doc), or MuJoCo's ``qpos``/``qvel`` mapped by
        :func:`mujoco_to_pinocchio`.

    Returns
    -------
    Trajectory

    Raises
    ------
    RobotError
        A missing file or array/column, wrong sizes, non-finite values.
    """
    p, group = _split_group(path)
    if not p.is_file():
        raise RobotError(f"trajectory file {str(p)!r} does not exist")
    if group is not None and p.suffix.lower() not in _HDF5:
        raise RobotError(f"{p}: a group ({group!r}) can be named only in an HDF5 file")
    if convention not in ("pinocchio", "mujoco"):
        raise RobotError(f"convention must be 'pinocchio' or 'mujoco', got {convention!r}")
    nq, nv = robot.nq, robot.nv
    if p.suffix.lower() == ".npz":
        try:
            with np.load(p, allow_pickle=False) as z:
                missing = [k for k in ("t", "q", "v") if k not in z.files]
                if missing:
                    raise RobotError(f"{p}: no array {', '.join(missing)} (needs t, q, v)")
                t, q, v = (np.asarray(z[k], dtype=float) for k in ("t", "q", "v"))
        except (OSError, ValueError) as exc:
            raise RobotError(f"{p}: not an NPZ file ({exc})") from None
    elif p.suffix.lower() in _HDF5:
        t, q, v = _read_hdf5(p, group)
    elif p.suffix.lower() == ".csv":
        import pandas as pd

        try:
            frame = pd.read_csv(p)
        except (OSError, ValueError) as exc:
            raise RobotError(f"{p}: not a CSV table ({exc})") from None
        cols = ["t", *(f"q_{i}" for i in range(nq)), *(f"v_{i}" for i in range(nv))]
        missing = [c for c in cols if c not in frame.columns]
        if missing:
            raise RobotError(f"{p}: no column {', '.join(missing[:4])}"
                             f"{' ...' if len(missing) > 4 else ''} (needs t, q_0..q_{nq - 1}, "
                             f"v_0..v_{nv - 1})")
        try:
            arr = frame[cols].to_numpy(dtype=float)
        except ValueError:
            raise RobotError(f"{p}: non-numeric entries") from None
        t, q, v = arr[:, 0], arr[:, 1:1 + nq], arr[:, 1 + nq:]
    else:
        raise RobotError(f"{p}: a trajectory is a .npz, .h5/.hdf5 or .csv file")
    if q.ndim != 2 or q.shape[1] != nq or v.ndim != 2 or v.shape[1] != nv:
        raise RobotError(f"{p}: q must be (N, nq={nq}) and v (N, nv={nv}), got {q.shape} "
                         f"and {v.shape}")
    if convention == "mujoco":
        q, v = mujoco_to_pinocchio(robot, q, v)
    if t.ndim != 1:
        raise RobotError(f"{p}: t must be one row of sample times (N,), got shape {t.shape}")
    source = str(p) if group is None else f"{p}#{group}"
    return Trajectory(time=t, q=q, v=v, source=source)


_HDF5 = (".h5", ".hdf5")


def _split_group(path: str | Path) -> tuple[Path, str | None]:
    """``"log.h5#/run3"`` -> ``(Path("log.h5"), "/run3")``; a path without ``#`` has no group."""
    text = str(path)
    at = text.find("#")
    while at >= 0:  # the first '#' after an HDF5 file's name: a group's name may hold '#'
        if Path(text[:at]).suffix.lower() in _HDF5:
            return Path(text[:at]), text[at + 1:] or "/"
        at = text.find("#", at + 1)
    return Path(text), None


def _read_hdf5(p: Path, group: str | None) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The datasets ``t``, ``q``, ``v`` of HDF5 file ``p`` (in ``group``, default the root)."""
    h5py = require("h5py", "reading an HDF5 log", extra="hdf5")
    where = group or "/"
    try:
        with h5py.File(p, "r") as f:
            if where not in f or not isinstance(f[where], h5py.Group):
                groups: list[str] = []
                f.visit(lambda name: groups.append("/" + name)
                        if isinstance(f[name], h5py.Group) else None)
                raise RobotError(f"{p}: no group {where!r} (groups: "
                                 f"{', '.join(['/', *groups][:8])})")
            g = f[where]
            missing = [k for k in ("t", "q", "v")
                       if k not in g or not isinstance(g[k], h5py.Dataset)]
            if missing:
                found = sorted(k for k in g if isinstance(g[k], h5py.Dataset))
                raise RobotError(f"{p}{'' if where == '/' else '#' + where}: no dataset "
                                 f"{', '.join(missing)} (needs t, q, v; found "
                                 f"{', '.join(found) or 'none'})")
            kinds = {k: g[k].dtype.kind for k in ("t", "q", "v")}
            wrong = [f"{k} ({g[k].dtype})" for k, kind in kinds.items() if kind not in "biuf"]
            if wrong:
                raise RobotError(f"{p}: t, q, v must be real numbers; {', '.join(wrong)} "
                                 "is not")
            t, q, v = (np.asarray(g[k][()], dtype=float) for k in ("t", "q", "v"))
    except OSError as exc:
        raise RobotError(f"{p}: not an HDF5 file ({exc})") from None
    return t, q, v


def write_trajectory(traj: Trajectory, path: str | Path) -> Path:
    """Write ``traj`` as :func:`read_trajectory` reads it (``.npz``, ``.h5``/``.hdf5`` or
    ``.csv``, Pinocchio's conventions); returns the path."""
    p = Path(path)
    if p.suffix.lower() == ".npz":
        np.savez(p, t=traj.time, q=traj.q, v=traj.v)
        return p
    if p.suffix.lower() in _HDF5:
        h5py = require("h5py", "writing an HDF5 log", extra="hdf5")
        with h5py.File(p, "w") as f:
            for key, arr in (("t", traj.time), ("q", traj.q), ("v", traj.v)):
                f.create_dataset(key, data=np.asarray(arr, dtype=float))
        return p
    if p.suffix.lower() != ".csv":
        raise RobotError(f"{p}: a trajectory is written as .npz, .h5/.hdf5 or .csv")
    from heelstrike.io import write_csv

    cols: dict[str, Any] = {"t": traj.time}
    cols.update({f"q_{i}": traj.q[:, i] for i in range(traj.q.shape[1])})
    cols.update({f"v_{i}": traj.v[:, i] for i in range(traj.v.shape[1])})
    return write_csv(cols, p)


def contact_height_history(
    robot: Robot, traj: Trajectory, contacts: Sequence[ContactSpec]
) -> FloatArray:
    """Height (m) of each contact point above ``z = 0`` at every sample, shape (N, contacts)
    (:func:`heelstrike.robots.contact_heights`: an arc's lowest point)."""
    return np.array([contact_heights(robot, q, contacts) for q in traj.q])


def detect_touchdowns(
    heights: ArrayLike, *, ground: float = 0.0, clearance: float = DEFAULT_CLEARANCE,
    touching: ArrayLike | None = None,
) -> list[tuple[int, tuple[int, ...], tuple[int, ...]]]:
    """Samples where contacts touch down, and which contacts are on the ground then.

    A contact is *down* at a sample when its height is at or below ``ground`` (or, given
    ``touching``, when it is in the simulator's contact list). It touches down between samples
    ``k`` and ``k + 1`` when it is not down at ``k`` and down at ``k + 1``, and it has risen
    above ``ground + clearance`` (and, given ``touching``, left the list) since its last
    touchdown, or was not down at the first sample: a soft contact's chatter around the
    ground, a sphere rolling on it or a contact list that flickers is not a new touchdown. A
    contact is on the ground from its touchdown until it rises so (and from the start if it
    starts down).

    Parameters
    ----------
    heights : array_like, shape (N, contacts)
        Contact heights (m), e.g. :func:`contact_height_history`.
    ground : float
        Ground height (m).
    clearance : float
        Lift (m) above ``ground`` that ends a contact's stay on the ground, >= 0.
    touching : array_like of bool, shape (N, contacts), optional
        The simulator's contact flags (:attr:`Trajectory.touching`) as the *down* signal.

    Returns
    -------
    list of (int, tuple of int, tuple of int)
        ``(k, striking, on_ground)``: the last sample before the touchdown (the pre-impact
        state), the indices of the contacts that touch down between it and the next one, and
        those on the ground at ``k`` (kept in the prediction).
    """
    h = np.asarray(heights, dtype=float)
    if not (math.isfinite(clearance) and clearance >= 0.0):
        raise RobotError(f"clearance must be >= 0 m, got {clearance!r}")
    clear = h > ground + clearance
    if touching is None:
        down = h <= ground
    else:
        down = np.asarray(touching, dtype=bool)
        if down.shape != h.shape:
            raise RobotError(f"touching must be {h.shape} like the heights, got {down.shape}")
        clear &= ~down
    armed = ~down[0]
    events = []
    for k in range(h.shape[0] - 1):
        armed |= clear[k]
        hit = armed & ~down[k] & down[k + 1]
        if hit.any():
            events.append((k, tuple(int(c) for c in np.flatnonzero(hit)),
                           tuple(int(c) for c in np.flatnonzero(~armed))))
            armed &= ~hit
    return events


@dataclass(frozen=True, kw_only=True)
class Touchdown(ResultDictMixin):
    """One touchdown of a recorded motion: the rigid prediction and what the record did.

    Attributes
    ----------
    time : float
        Touchdown time (s): the first striking contact's zero crossing, interpolated linearly
        between the two samples around it.
    index_pre, index_post : int
        The samples before the touchdown (pre-impact state) and at the end of the window
        (post-transient state).
    time_pre, time_post : float
        Their times (s); ``time_post - time_pre`` is the window actually used (>= the stated
        window, shorter only where the next touchdown or the record's end comes first).
    strike, keep : tuple of str
        Frames of the contacts that touch down (unilateral in the prediction, with the stated
        friction and restitution) and of those already on the ground (kept, bilateral, inert).
    T, T_c, T_a, T_plus, predicted_loss : float
        Prediction (J): kinetic energy at the pre-impact sample, its constrained and
        admissible parts (``T = T_c + T_a``), the kinetic energy after the rigid impact and
        ``T - T_plus``.
    T_c_contact : tuple of float
        Each contact's share of ``T_c`` (J, normal plus tangential; strike then keep order,
        nested shares that add up to ``T_c``).
    T_after, recorded_loss : float
        Recorded kinetic energy at ``index_post`` (J) and ``T - T_after``, the kinetic energy
        the motion lost across the window.
    mechanical_loss : float
        ``(T + V)`` at ``index_pre`` minus ``(T + V)`` at ``index_post`` (J), ``V`` the
        gravitational potential: the recorded loss without gravity's work over the window
        (actuators' work and the energy stored in a soft contact's penetration remain in it).
    normal_velocity_pre, normal_velocity_post, predicted_normal_velocity : tuple of float
        Vertical velocity (m/s) of each striking contact point: recorded before, recorded at
        the window's end, and the rigid prediction after the impact.
    effective_restitution : tuple of float
        ``-u_post / u_pre`` of each striking contact's recorded normal velocity (NaN when it
        did not approach the ground faster than :data:`APPROACH_SPEED`).
    admissible : bool
        No kept contact pulls on the ground in the prediction
        (:meth:`heelstrike.robots.RobotImpact.pulling_contacts`).
    note : str
        Empty, or why the prediction is not to be trusted: the kept contacts that pull, or
        the impact law's refusal (the predicted numbers are then NaN, e.g. two points of one
        rigid body, whose rows are rank deficient).
    """

    time: float
    index_pre: int
    index_post: int
    time_pre: float
    time_post: float
    strike: tuple[str, ...]
    keep: tuple[str, ...]
    T: float
    T_c: float
    T_a: float
    T_plus: float
    predicted_loss: float
    T_c_contact: tuple[float, ...]
    T_after: float
    recorded_loss: float
    mechanical_loss: float
    normal_velocity_pre: tuple[float, ...]
    normal_velocity_post: tuple[float, ...]
    predicted_normal_velocity: tuple[float, ...]
    effective_restitution: tuple[float, ...]
    admissible: bool = True
    note: str = ""


@dataclass(frozen=True, kw_only=True)
class ReplayResult(ResultDictMixin):
    """The touchdowns of a recorded motion (:func:`replay`).

    Attributes
    ----------
    robot : str
        The robot's name.
    source : str
        The trajectory's source.
    contacts : tuple of ContactSpec
        The contacts watched.
    window : float
        Stated transient window (s).
    friction, restitution : float
        Law of the striking contacts in the prediction.
    time : ndarray, shape (N,)
        Sample times (s).
    kinetic, potential : ndarray, shape (N,)
        Kinetic energy ``1/2 v^T M v`` and gravitational potential (J) of every sample.
    heights : ndarray, shape (N, contacts)
        Contact heights (m).
    touchdowns : tuple of Touchdown
    """

    robot: str
    source: str
    contacts: tuple[ContactSpec, ...]
    window: float
    friction: float
    restitution: float
    time: FloatArray = field(repr=False)
    kinetic: FloatArray = field(repr=False)
    potential: FloatArray = field(repr=False)
    heights: FloatArray = field(repr=False)
    touchdowns: tuple[Touchdown, ...]

    def table(self) -> dict[str, list[Any]]:
        """One row per touchdown, columns with units in their names (CSV-ready)."""
        rows = self.touchdowns
        return {
            "time_s": [d.time for d in rows],
            "strike": [" ".join(d.strike) for d in rows],
            "keep": [" ".join(d.keep) for d in rows],
            "window_s": [d.time_post - d.time_pre for d in rows],
            "T_J": [d.T for d in rows],
            "T_c_J": [d.T_c for d in rows],
            "T_a_J": [d.T_a for d in rows],
            "predicted_loss_J": [d.predicted_loss for d in rows],
            "recorded_loss_J": [d.recorded_loss for d in rows],
            "mechanical_loss_J": [d.mechanical_loss for d in rows],
            "effective_restitution": [" ".join(f"{e:.6g}" for e in d.effective_restitution)
                                      for d in rows],
            "admissible": [d.admissible for d in rows],
            "note": [d.note for d in rows],
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: settings and the touchdowns (no per-sample arrays; NaN
        numbers, e.g. a restitution or a refused prediction, as None, an unbounded friction
        cone as ``"friction": None``)."""
        out = [_plain(d) for d in self.touchdowns]
        return {
            "robot": self.robot, "source": self.source,
            "contacts": [f"{c.frame}:{c.kind}" + (f":{c.radius:g}" if c.kind == "arc" else "")
                         for c in self.contacts],
            "window": self.window,
            "friction": self.friction if math.isfinite(self.friction) else None,
            "restitution": self.restitution,
            "samples": int(self.time.size), "touchdowns": out,
        }


def _finite_or_none(x: Any) -> Any:
    return None if isinstance(x, float) and not math.isfinite(x) else x


def _plain(d: Touchdown) -> dict[str, Any]:
    from dataclasses import fields

    out: dict[str, Any] = {}
    for f in fields(d):
        value = getattr(d, f.name)
        if isinstance(value, tuple):
            value = [_finite_or_none(x) for x in value]
        out[f.name] = _finite_or_none(value)
    return out


def replay(
    robot: Robot,
    traj: Trajectory,
    contacts: Sequence[ContactSpec],
    *,
    window: float = DEFAULT_WINDOW,
    friction: float = float("inf"),
    restitution: float = 0.0,
    ground: float = 0.0,
    clearance: float = DEFAULT_CLEARANCE,
    signal: Signal = "height",
) -> ReplayResult:
    """Touchdowns of a recorded motion against the rigid-impact prediction.

    A touchdown is a contact point's height (:func:`contact_height_history`) crossing
    ``ground`` downward between samples ``k`` and ``k + 1`` (:func:`detect_touchdowns`);
    sample ``k`` is the pre-impact state. The prediction is
    :func:`heelstrike.robots.robot_impact` there, with the crossing contacts striking
    (``friction``, ``restitution``) and the contacts on the ground kept (bilateral, inert).
    The record is read from sample ``k`` to the first sample at least ``window`` seconds
    later (or the sample before the next touchdown, or the last sample, if earlier):
    ``recorded_loss = T[k] - T[post]`` exactly, ``mechanical_loss`` the same with the
    gravitational potential added, and each striking contact's effective restitution
    ``-u_n[post] / u_n[k]`` (vertical velocity of the contact point).

    Parameters
    ----------
    robot : Robot
    traj : Trajectory
        The recorded motion (Pinocchio's conventions).
    contacts : sequence of ContactSpec
        The contacts to watch (frames of ``robot``; an ``arc`` is a sphere or a rounded heel
        of that radius).
    window : float
        Length of the contact transient (s), > 0: long enough for the simulated or real
        contact to finish its compression (a soft contact's few time constants), short next
        to the motion's own time scale.
    friction, restitution : float
        Coulomb coefficient and Newton restitution of the striking contacts in the prediction.
    ground : float
        Ground height (m); the prediction's ground is ``z = 0``, so keep 0 unless the record's
        ground lies elsewhere by a small offset (penetration of a soft contact).
    clearance : float
        Lift (m) that ends a contact's stay on the ground (:func:`detect_touchdowns`).
    signal : {"height", "mujoco"}
        What a touchdown is: the contact point's height crossing ``ground`` (default), or,
        for a MuJoCo rollout, the geom named like the contact's frame entering MuJoCo's
        contact list (on the ground until it has left the list and risen ``clearance``
        above ``ground``; the touchdown time is then the first sample in the list).

    Returns
    -------
    ReplayResult
    """
    if not contacts:
        raise RobotError("give at least one contact to watch")
    if not (math.isfinite(window) and window > 0.0):
        raise RobotError(f"window must be > 0 s, got {window!r}")
    for c in contacts:
        robot.frame_id(c.frame)
    specs = tuple(contacts)
    t = np.asarray(traj.time, dtype=float)
    T = kinetic_energy(robot, traj)
    V = potential_energy(robot, traj)
    h = contact_height_history(robot, traj, specs)
    if signal == "height":
        found = detect_touchdowns(h, ground=ground, clearance=clearance)
    elif signal == "mujoco":
        found = detect_touchdowns(h, ground=ground, clearance=clearance,
                                  touching=_touching(traj, specs))
    else:
        raise RobotError(f"signal must be 'height' or 'mujoco', got {signal!r}")
    out = []
    for n, (k, crossing, on_ground) in enumerate(found):
        limit = found[n + 1][0] if n + 1 < len(found) else t.size - 1
        later = np.flatnonzero(t >= t[k] + window * (1.0 - 1e-9))
        post = int(min(later[0] if later.size else t.size - 1, limit))
        post = max(post, k + 1)
        strike = tuple(specs[c] for c in crossing)
        keep = tuple(specs[i] for i in on_ground)
        pred = _predict(robot, traj.q[k], traj.v[k], strike, keep, friction, restitution)
        _, A_pre = robot_matrices(robot, traj.q[k], strike)
        _, A_post = robot_matrices(robot, traj.q[post], strike)
        rows = np.cumsum([0, *(s.rows for s in strike)])[:-1] + 2  # each contact's z row
        u_pre = (A_pre @ traj.v[k])[rows]
        u_post = (A_post @ traj.v[post])[rows]
        with np.errstate(divide="ignore", invalid="ignore"):
            e_eff = np.where(u_pre < -APPROACH_SPEED, -u_post / u_pre, np.nan)
        c0 = crossing[0]
        h0, h1 = h[k, c0], h[k + 1, c0]
        t_cross = float(t[k] + (t[k + 1] - t[k]) * (h0 - ground) / (h0 - h1)) \
            if signal == "height" else float(t[k + 1])
        out.append(Touchdown(
            time=t_cross, index_pre=int(k), index_post=post, time_pre=float(t[k]),
            time_post=float(t[post]), strike=tuple(s.frame for s in strike),
            keep=tuple(s.frame for s in keep), **pred,
            T_after=float(T[post]), recorded_loss=float(T[k] - T[post]),
            mechanical_loss=float(T[k] + V[k] - T[post] - V[post]),
            normal_velocity_pre=tuple(float(x) for x in u_pre),
            normal_velocity_post=tuple(float(x) for x in u_post),
            effective_restitution=tuple(float(x) for x in e_eff)))
    return ReplayResult(robot=robot.name, source=traj.source, contacts=specs, window=window,
                        friction=friction, restitution=restitution, time=t, kinetic=T,
                        potential=V, heights=h, touchdowns=tuple(out))


def _predict(robot: Robot, q: FloatArray, v: FloatArray, strike: tuple[ContactSpec, ...],
             keep: tuple[ContactSpec, ...], friction: float, restitution: float
             ) -> dict[str, Any]:
    """The prediction's fields of a :class:`Touchdown`: NaN, with the reason in ``note``,
    where the impact law refuses the contacts (e.g. rank-deficient rows)."""
    try:
        impact = robot_impact(robot, q, v, strike=strike, keep=keep, friction=friction,
                              restitution=restitution)
    except ImpactInputError as exc:
        nan = float("nan")
        return {"T": nan, "T_c": nan, "T_a": nan, "T_plus": nan, "predicted_loss": nan,
                "T_c_contact": (nan,) * (len(strike) + len(keep)),
                "predicted_normal_velocity": (nan,) * len(strike), "admissible": False,
                "note": f"no prediction: {exc}"}
    res = impact.result
    pulling = impact.pulling_contacts()
    return {
        "T": float(res.T), "T_c": float(res.T_c), "T_a": float(res.T_a),
        "T_plus": float(res.T_post), "predicted_loss": float(res.energy_lost),
        "T_c_contact": tuple(float(a + b) for a, b in zip(res.T_c_normal, res.T_c_tangential,
                                                          strict=True)),
        "predicted_normal_velocity": tuple(float(res.contact_velocity_post[i][2])
                                           for i in range(len(strike))),
        "admissible": not pulling,
        "note": "" if not pulling else "kept contact(s) pull on the ground: " + ", ".join(
            f"{f} ({lam:.4g} N s)" for f, lam in pulling),
    }


def _touching(traj: Trajectory, specs: Sequence[ContactSpec]) -> NDArray[np.bool_]:
    """MuJoCo's contact flags (N, contacts) of the geoms named like the contacts' frames."""
    if traj.touching is None:
        raise RobotError("signal 'mujoco' needs a MuJoCo rollout (its contact list); a log "
                         "has none: use signal 'height'")
    missing = [c.frame for c in specs if c.frame not in traj.contact_geoms]
    if missing:
        raise RobotError(f"no geom named {', '.join(map(repr, missing))} in the rollout's "
                         f"contact list (named geoms: {', '.join(traj.contact_geoms) or 'none'})"
                         ": name the foot geom like its site")
    return traj.touching[:, [traj.contact_geoms.index(c.frame) for c in specs]]
