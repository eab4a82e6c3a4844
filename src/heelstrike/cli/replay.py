"""Command line for ``heelstrike robot replay FILE --model MODEL``: impacts along a recorded
motion (:func:`heelstrike.robots.replay.replay`). Parses, calls and renders, nothing more."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from heelstrike.cli._common import writable_dir
from heelstrike.cli._render import print_json

__all__ = ["add_replay_command"]

_TOUCHDOWN_UNITS: dict[str, Any] = {
    "time": "s", "index_pre": "1", "index_post": "1", "time_pre": "s", "time_post": "s",
    "strike": None, "keep": None, "T": "J", "T_c": "J", "T_a": "J", "T_plus": "J",
    "predicted_loss": "J", "T_c_contact": "J", "T_after": "J", "recorded_loss": "J",
    "mechanical_loss": "J", "normal_velocity_pre": "m/s", "normal_velocity_post": "m/s",
    "predicted_normal_velocity": "m/s", "effective_restitution": "1", "admissible": None,
    "note": None,
}


#: :data:`heelstrike.robots.replay.DEFAULT_WINDOW` (s) and ``DEFAULT_CLEARANCE`` (m), repeated
#: here so that building the parser imports no robot code (a test checks they agree).
DEFAULT_WINDOW = 0.01
DEFAULT_CLEARANCE = 1e-3


def add_replay_command(rsub: Any) -> None:
    """Register ``heelstrike robot replay`` on the ``robot`` subcommands ``rsub``."""
    p = rsub.add_parser(
        "replay", help="touchdowns of a recorded motion against the rigid-impact prediction",
        description="Find the touchdowns of a recorded motion (a contact's height crossing "
        "z = 0 downward) and compare, at each, the rigid impact predicted from the last sample "
        "before it (T_c, T_a, the share of T_c per contact; the touching contacts strike with "
        "--friction and --restitution, those already on the ground are kept) with what the "
        "record did over --window seconds: recorded_loss = T_before - T_after (kinetic), "
        "mechanical_loss the same with the gravitational potential, and each striking "
        "contact's effective restitution -u_after/u_before (vertical velocity). FILE is a log "
        "(.npz or HDF5 .h5/.hdf5 with arrays t (N,), q (N, nq), v (N, nv), FILE.h5#GROUP for a "
        "group's, needing the 'hdf5' extra; or .csv with columns t, q_0.., v_0..; "
        "SI units; --convention says whose q/v) or an MJCF (.xml) that MuJoCo simulates for "
        "--duration seconds from its first keyframe or its default state (needs the 'mujoco' "
        "extra).")
    p.add_argument("file", metavar="FILE",
                   help="trajectory log (.npz, .h5/.hdf5[#GROUP], .csv) or MJCF (.xml)")
    p.add_argument("--model", default=None, metavar="MODEL",
                   help="the robot: a shipped name, a .urdf or an .xml (MJCF) file (default: "
                   "FILE when FILE is an MJCF)")
    p.add_argument("--contact", action="append", default=None, required=True,
                   metavar="FRAME:point|flat|arc:RADIUS",
                   help="a contact to watch (repeatable); FRAME:arc:RADIUS for a sphere or a "
                   "rounded heel of that radius (m) centred at the frame")
    p.add_argument("--convention", choices=("pinocchio", "mujoco"), default="pinocchio",
                   help="a log's q/v: Pinocchio's (quaternion x,y,z,w; base velocity in the base "
                   "frame) or MuJoCo's qpos/qvel (w,x,y,z; linear velocity in the world frame)")
    p.add_argument("--duration", type=float, default=1.0, metavar="S",
                   help="MJCF FILE: simulated time (s, default 1)")
    p.add_argument("--timestep", type=float, default=None, metavar="S",
                   help="MJCF FILE: MuJoCo's timestep (s, default the file's)")
    p.add_argument("--window", type=float, default=DEFAULT_WINDOW, metavar="S",
                   help=f"contact transient over which the recorded loss is measured (s, "
                   f"default {DEFAULT_WINDOW:g})")
    p.add_argument("--clearance", type=float, default=DEFAULT_CLEARANCE, metavar="M",
                   help=f"lift that ends a contact's stay on the ground (m, default "
                   f"{DEFAULT_CLEARANCE:g})")
    p.add_argument("--signal", choices=("height", "mujoco"), default="height",
                   help="a touchdown is the contact point crossing z = 0 (default), or, for an "
                   "MJCF FILE, the geom named like the frame entering MuJoCo's contact list")
    p.add_argument("--friction", type=float, default=math.inf, metavar="MU",
                   help="Coulomb coefficient of the striking contacts (default inf)")
    p.add_argument("--restitution", type=float, default=0.0, metavar="E",
                   help="Newton restitution of the striking contacts (default 0)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="write replay.png (energy over time, touchdowns, losses), "
                   "touchdowns.csv and, for an MJCF FILE, trajectory.npz into DIR")
    p.set_defaults(func=_run_robot_replay)


def _robot(model: str) -> Any:
    from heelstrike.robots import load_mjcf, load_robot, load_urdf

    suffix = Path(model).suffix.lower()
    if suffix == ".urdf":
        return load_urdf(model)
    if suffix == ".xml":
        return load_mjcf(model)
    return load_robot(model)


def _run_robot_replay(args: argparse.Namespace) -> int:
    from heelstrike.robots import parse_contact
    from heelstrike.robots.replay import mujoco_rollout, read_trajectory, replay

    for option, value in (("--window", args.window), ("--duration", args.duration)):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{option} must be > 0 s, got {value!r}")
    is_mjcf = Path(args.file).suffix.lower() == ".xml"
    model = args.model if args.model is not None else (args.file if is_mjcf else None)
    if model is None:
        raise ValueError("a log needs --model MODEL (a shipped name, a .urdf or an .xml)")
    if args.out is not None:
        writable_dir(args.out)
    contacts = [parse_contact(c) for c in args.contact]
    robot = _robot(model)
    if is_mjcf:
        traj = mujoco_rollout(args.file, duration=args.duration, robot=robot,
                              keyframe=0 if _has_keyframe(args.file) else None,
                              timestep=args.timestep)
    else:
        traj = read_trajectory(args.file, robot, convention=args.convention)
    result = replay(robot, traj, contacts, window=args.window, friction=args.friction,
                    restitution=args.restitution, clearance=args.clearance,
                    signal=args.signal)
    written = _write(result, traj, args.out, is_mjcf) if args.out is not None else []
    if args.json:
        summary = {**result.to_dict(), "written": [str(p) for p in written]}
        print_json(summary, {"robot": None, "source": None, "contacts": None, "window": "s",
                       "friction": "1", "restitution": "1", "samples": "1",
                       "touchdowns": _TOUCHDOWN_UNITS, "written": None})
        return 0
    print(f"replay of '{robot.name}' ({traj.source}): {traj.time.size} samples, "
          f"{len(result.touchdowns)} touchdown(s), window {args.window:g} s")
    print(f"  {'time (s)':>10}  {'contacts':<24} {'T (J)':>10} {'T_c pred (J)':>12} "
          f"{'rec loss (J)':>12} {'mech loss (J)':>13}  e_eff")
    for d in result.touchdowns:
        names = ",".join(d.strike) + (f" (+{','.join(d.keep)})" if d.keep else "")
        e = " ".join("n/a" if not math.isfinite(x) else f"{x:.3f}"
                     for x in d.effective_restitution)
        print(f"  {d.time:>10.5f}  {names:<24} {d.T:>10.5g} {d.T_c:>12.5g} "
              f"{d.recorded_loss:>12.5g} {d.mechanical_loss:>13.5g}  {e}")
    for d in result.touchdowns:
        if d.note:
            print(f"heelstrike: note: touchdown at {d.time:.5f} s: {d.note}", file=sys.stderr)
    for p in written:
        print(f"wrote {p}")
    return 0


def _has_keyframe(path: str) -> bool:
    try:
        return "<key" in Path(path).read_text(errors="replace")
    except OSError:
        return False


def _write(result: Any, traj: Any, out: Path, is_mjcf: bool) -> list[Path]:
    from heelstrike.io import write_csv
    from heelstrike.outputs import _metadata
    from heelstrike.plots.replay import plot_replay
    from heelstrike.robots.replay import write_trajectory

    out.mkdir(parents=True, exist_ok=True)
    fig = plot_replay(result)
    png = out / "replay.png"
    fig.savefig(png, dpi=130, metadata=_metadata("png"))
    paths = [png, write_csv(result.table(), out / "touchdowns.csv")]
    if is_mjcf:
        paths.append(write_trajectory(traj, out / "trajectory.npz"))
    return paths
