"""Command line for robots: ``heelstrike robot list|info|state`` and ``heelstrike impact --robot``.

Parses and calls :mod:`heelstrike.robots`, nothing more. Errors are raised as
:class:`RobotCliError` (a ``ValueError``), which :func:`heelstrike.cli.main` prints as one line
``heelstrike: error: ...`` with exit status 2. Pinocchio is imported only when a robot command
runs, so the rest of the command line works without ``heelstrike[robots]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import textwrap
from pathlib import Path
from typing import Any

from heelstrike.cli._render import json_text, print_json, printable
from heelstrike.io import write_text

__all__ = [
    "RobotCliError",
    "add_robot_command",
    "add_robot_impact_options",
    "robot_requested",
    "run_robot_impact",
]


class RobotCliError(ValueError):
    """Bad robot input on the command line (one line, exit status 2)."""


_LIST_UNITS: dict[str, Any] = {
    "name": None, "nq": "1", "nv": "1", "mass": "kg", "source": None, "feet": None,
    "foot_contact": None,
}


def _joint_units(model: Any) -> tuple[list[str], list[str]]:
    """Units of the entries of ``q`` and ``v`` in Pinocchio's conventions, joint by joint (a
    composite joint, e.g. an MJCF body with a hinge and a slide, by its parts)."""
    q_units: list[str] = []
    v_units: list[str] = []
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        parts = (joint.extract().joints if joint.shortname() == "JointModelComposite"
                 else [joint])
        for part in parts:
            qu, vu = _one_joint_units(part.shortname(), int(part.nq), int(part.nv))
            q_units += qu
            v_units += vu
    return q_units, v_units


def _one_joint_units(kind: str, nq: int, nv: int) -> tuple[list[str], list[str]]:
    """The units of one (non-composite) joint's ``q`` and ``v`` entries."""
    if kind == "JointModelFreeFlyer":
        return ["m"] * 3 + ["1"] * 4, ["m/s"] * 3 + ["rad/s"] * 3  # position, unit quaternion
    if kind == "JointModelTranslation" or (
        kind.startswith("JointModelP") and kind != "JointModelPlanar"
    ):
        return ["m"] * nq, ["m/s"] * nv
    if kind == "JointModelPlanar":
        return ["m", "m", "1", "1"], ["m/s", "m/s", "rad/s"]
    # revolute (cos/sin pairs for unbounded ones), spherical (quaternion)
    return (["rad"] if nq == nv == 1 else ["1"]) * nq, ["rad/s"] * nv


def _print(text: str = "", *, file: Any = None) -> None:
    """:func:`print` one line (or block) of text output, control characters escaped."""
    print(printable(text), file=file)


def _joules(value: float) -> str:
    """An energy (J) with 6 decimals, or in exponent form outside 1e-6..1e7 J (where fixed
    decimals would print zeros or hundreds of digits)."""
    return f"{value:.6f}" if value == 0.0 or 1e-6 <= abs(value) < 1e7 else f"{value:.6e}"


def add_robot_command(sub: Any) -> None:
    """Register ``heelstrike robot list [--json]``, ``robot info NAME`` and ``robot state NAME``."""
    p = sub.add_parser(
        "robot",
        help="robots shipped offline (example-robot-data, needs heelstrike[robots])",
        description="List the robots shipped with heelstrike[robots], describe one, or write "
        "a gait-like pre-impact state of one for 'heelstrike impact --state'.",
    )
    rsub = p.add_subparsers(dest="robot_command", required=True, parser_class=type(p))
    pl = rsub.add_parser("list", help="list shipped robots (name, nq, nv, mass, source)")
    pl.add_argument("--json", action="store_true", help="print one JSON object")
    pl.set_defaults(func=_run_robot_list)
    pi = rsub.add_parser(
        "info", help="describe one robot: sizes, mass, feet, frames",
        description="Sizes, mass, feet, joints and frames of a shipped robot (NAME) or of your "
        "own robot file (--urdf FILE or --mjcf FILE): the frame names 'impact --strike/--keep' "
        "take.")
    _add_robot_source(pi, "robot")
    pi.add_argument("--json", action="store_true", help="print one JSON object")
    pi.set_defaults(func=_run_robot_info)
    ps = rsub.add_parser(
        "state", help="write a gait-like pre-impact STATE.json for 'impact --state'",
        description="Gait-like pre-impact state of a shipped biped (heelstrike.robots.states."
        "gait_state): both soles flat on the ground, the leading one STEP_LENGTH ahead and "
        "descending at STRIKE_SPEED, the trailing one at rest, the base moving forward; the "
        "velocity of least kinetic energy with these. Written as {\"q\": [...], \"v\": [...], "
        "...} in Pinocchio's conventions, the file 'heelstrike impact --robot NAME --state' reads. "
        "Your own biped: --urdf FILE or --mjcf FILE with --feet LEFT,RIGHT (its sole frames; "
        "the inverse kinematics starts from its neutral configuration).")
    _add_robot_source(ps, "biped")
    ps.add_argument("--feet", default=None, metavar="LEFT,RIGHT",
                    help="with --urdf/--mjcf: the left and right sole (or foot) frames")
    ps.add_argument("--foot-contact", choices=("flat", "point"), default=None,
                    help="the feet's contact type: flat soles (6 rows each) or points (3 rows "
                    "each); default: the shipped robot's own (talos, g1 flat; bolt point), "
                    "flat for --urdf/--mjcf")
    ps.add_argument("--step-length", type=float, default=0.3, metavar="M",
                    help="distance between the soles along x (m, default 0.3)")
    ps.add_argument("--strike-speed", type=float, default=0.3, metavar="M/S",
                    help="downward speed of the leading sole (m/s, > 0, default 0.3)")
    ps.add_argument("--forward-speed", type=float, default=0.5, metavar="M/S",
                    help="forward speed of the base (m/s, default 0.5)")
    ps.add_argument("--swing-forward-speed", type=float, default=0.0, metavar="M/S",
                    help="forward speed of the leading sole (m/s, default 0)")
    ps.add_argument("--leading", choices=("left", "right"), default="left",
                    help="striking foot (default left)")
    ps.add_argument("--out", type=Path, default=None, metavar="FILE",
                    help="write the state here (default: print it on stdout)")
    ps.add_argument("--json", action="store_true",
                    help="with --out: print one JSON object describing what was written")
    ps.set_defaults(func=_run_robot_state)
    from heelstrike.cli.replay import add_replay_command

    add_replay_command(rsub)


def _run_robot_list(args: argparse.Namespace) -> int:
    from heelstrike.robots import list_robots

    robots = list_robots()
    if args.json:
        print_json({"robots": [{k: r[k] for k in _LIST_UNITS} for r in robots]},
                    {"robots": dict(_LIST_UNITS)})
        return 0
    _print(f"{'name':<8} {'nq':>4} {'nv':>4} {'mass (kg)':>10}  source")
    for r in robots:
        _print(f"{r['name']:<8} {r['nq']:>4} {r['nv']:>4} {r['mass']:>10.3f}  {r['source']}")
    return 0


def _add_robot_source(p: argparse.ArgumentParser, what: str) -> None:
    """``NAME`` (a shipped robot), or ``--urdf FILE`` / ``--mjcf FILE`` (one is given)."""
    p.add_argument("name", nargs="?", default=None,
                   help="robot name (see 'heelstrike robot list')")
    p.add_argument("--urdf", default=None, metavar="FILE", help=f"a URDF {what} instead")
    p.add_argument("--mjcf", default=None, metavar="FILE", help=f"an MJCF {what} instead")


def _load(name: str | None, urdf: str | None, mjcf: str | None,
          feet: tuple[str, str] | None = None, foot_contact: str = "flat") -> Any:
    """The shipped robot ``name``, else the URDF file, else the MJCF file (one is given), the
    files with the feet frames ``feet``."""
    from heelstrike.robots import load_mjcf, load_robot, load_urdf

    if name is not None:
        return load_robot(name)
    if urdf is not None:
        return load_urdf(urdf, feet=feet, foot_contact=foot_contact)
    return load_mjcf(str(mjcf), feet=feet, foot_contact=foot_contact)


def _run_robot_info(args: argparse.Namespace) -> int:
    if sum(v is not None for v in (args.name, args.urdf, args.mjcf)) != 1:
        raise RobotCliError("give one of NAME, --urdf FILE, --mjcf FILE")
    r = _load(args.name, args.urdf, args.mjcf)
    model = r.model
    joints = [str(model.names[j]) for j in range(1, model.njoints)]
    frames = [str(f.name) for f in model.frames]
    info = {
        "name": r.name, "nq": r.nq, "nv": r.nv, "mass": r.mass, "source": r.source,
        "feet": list(r.feet), "foot_contact": r.foot_contact,
        "reference_q": [float(x) for x in r.reference_q], "joints": joints, "frames": frames,
    }
    if args.json:
        q_units, _ = _joint_units(model)
        print_json(info, {**_LIST_UNITS, "reference_q": q_units, "joints": None,
                           "frames": None})
        return 0
    _print(f"{r.name}: nq={r.nq} nv={r.nv} mass={r.mass:.3f} kg")
    _print(f"  source  {r.source}")
    _print(f"  feet    {', '.join(r.feet) if any(r.feet) else 'not known (a robot file)'}"
          f"{f' ({r.foot_contact} contact)' if any(r.feet) else ''}")
    _print(f"  joints  {len(joints)} (root: {joints[0]}, free flyer)")
    _print(f"  frames  {len(frames)}:")
    _print(textwrap.fill(", ".join(frames), width=96, initial_indent="    ",
                        subsequent_indent="    ", break_on_hyphens=False))
    return 0


def _run_robot_state(args: argparse.Namespace) -> int:
    from heelstrike.robots.loading import _with_feet
    from heelstrike.robots.states import gait_state

    for option, value in (("--step-length", args.step_length),
                          ("--strike-speed", args.strike_speed),
                          ("--forward-speed", args.forward_speed),
                          ("--swing-forward-speed", args.swing_forward_speed)):
        if not math.isfinite(value):
            raise RobotCliError(f"{option} must be finite, got {value!r}")
    if args.step_length < 0.0:
        raise RobotCliError(f"--step-length must be >= 0 m, got {args.step_length!r}")
    if args.strike_speed <= 0.0:
        raise RobotCliError(f"--strike-speed must be > 0 m/s, got {args.strike_speed!r}")
    if args.json and args.out is None:
        raise RobotCliError("--json needs --out (without --out the state itself is printed)")
    if args.out is not None and not args.out.parent.is_dir():
        raise RobotCliError(f"cannot write {str(args.out)!r}: no directory "
                            f"{str(args.out.parent)!r}")
    if sum(v is not None for v in (args.name, args.urdf, args.mjcf)) != 1:
        raise RobotCliError("give one of NAME, --urdf FILE, --mjcf FILE")
    feet = None
    if args.name is None:
        if args.feet is None or len(args.feet.split(",")) != 2:
            raise RobotCliError("a robot file needs --feet LEFT,RIGHT: its left and right sole "
                                "frames ('heelstrike robot info --urdf FILE' lists the frames)")
        left, right = (f.strip() for f in args.feet.split(","))
        feet = (left, right)
    elif args.feet is not None:
        raise RobotCliError(f"--feet is for --urdf/--mjcf: robot {args.name!r} has its own")
    robot = _load(args.name, args.urdf, args.mjcf, feet, args.foot_contact or "flat")
    if args.foot_contact is not None and args.foot_contact != robot.foot_contact:
        robot = _with_feet(robot, robot.feet, args.foot_contact)  # the option, honoured
    q, v = gait_state(robot, args.step_length, args.strike_speed,
                      forward_speed=args.forward_speed,
                      swing_forward_speed=args.swing_forward_speed, leading=args.leading)
    _require_finite_state(robot, q, v)
    violations = _limit_violations(robot, q)
    lead, trail = robot.feet if args.leading == "left" else robot.feet[::-1]
    q_units, v_units = _joint_units(robot.model)
    state = {
        "robot": robot.name, "q": [float(x) for x in q], "v": [float(x) for x in v],
        "leading_foot": lead, "trailing_foot": trail, "foot_contact": robot.foot_contact,
        "step_length": args.step_length, "strike_speed": args.strike_speed,
        "forward_speed": args.forward_speed, "swing_forward_speed": args.swing_forward_speed,
        "joint_limit_violations": violations,
    }
    units = {"robot": None, "q": q_units, "v": v_units, "leading_foot": None,
             "trailing_foot": None, "foot_contact": None, "step_length": "m",
             "strike_speed": "m/s", "forward_speed": "m/s", "swing_forward_speed": "m/s",
             "joint_limit_violations": _violation_units(violations)}
    _note_limit_violations(violations, f"robot state {robot.name}")
    if args.out is None:
        print_json(state, units)
        return 0
    text = json_text({**state, "units": units})
    try:
        write_text(text + "\n", args.out)
    except OSError as exc:
        raise RobotCliError(f"cannot write {str(args.out)!r}: {exc.strerror or exc}") from None
    if args.json:
        print_json({"out": str(args.out), "robot": robot.name, "nq": robot.nq, "nv": robot.nv,
                     "leading_foot": lead, "trailing_foot": trail,
                     "joint_limit_violations": violations},
                    {"out": None, "robot": None, "nq": "1", "nv": "1", "leading_foot": None,
                     "trailing_foot": None,
                     "joint_limit_violations": _violation_units(violations)})
        return 0
    _print(f"wrote {args.out}: {robot.name} (nq={robot.nq}, nv={robot.nv}), leading foot "
          f"{lead} {args.step_length:g} m ahead of {trail}, descending at "
          f"{args.strike_speed:g} m/s")
    return 0


def _require_finite_state(robot: Any, q: Any, v: Any) -> None:
    """Refuse a state whose coordinates or kinetic energy ``1/2 v^T M v`` are not finite."""
    import numpy as np

    with np.errstate(all="ignore"):
        ok = bool(np.all(np.isfinite(q)) and np.all(np.isfinite(v)))
        if ok:
            vv = np.asarray(v, dtype=float)
            ok = math.isfinite(0.5 * float(vv @ robot.mass_matrix(q) @ vv))
    if not ok:
        raise RobotCliError("the state is not finite (its kinetic energy overflows): use "
                            "smaller speeds")


def _limit_violations(robot: Any, q: Any) -> list[dict[str, Any]]:
    """:func:`heelstrike.robots.states.joint_limit_violations` as JSON-ready objects."""
    from heelstrike.robots.states import joint_limit_violations

    return [x.to_dict() for x in joint_limit_violations(robot, q)]


def _violation_units(violations: list[dict[str, Any]]) -> dict[str, Any]:
    """Units of the ``joint_limit_violations`` entries (rad; m when all are prismatic)."""
    units = {x["unit"] for x in violations}
    u = units.pop() if len(units) == 1 else ("rad" if not units else None)  # mixed: see "unit"
    return {"joint": None, "position": u, "lower": u, "upper": u, "unit": None}


def _note_limit_violations(violations: list[dict[str, Any]], where: str) -> None:
    """One ``heelstrike: note:`` line on stderr per joint outside its limits."""
    for x in violations:
        _print(f"heelstrike: note: {where}: joint {x['joint']!r} at {x['position']:.3f} "
              f"{x['unit']} is outside its limits [{x['lower']:.3f}, {x['upper']:.3f}] "
              f"{x['unit']}: the robot cannot reach this pose", file=sys.stderr)


def add_robot_impact_options(p: argparse.ArgumentParser) -> None:
    """Add ``--robot/--urdf/--mjcf``, ``--strike``, ``--keep`` and ``--friction`` to ``impact``."""
    g = p.add_argument_group(
        "robots (heelstrike[robots]; --state is then a STATE.json file)",
        "Energy books: T = T_c + T_a, and energy_lost = T - T_plus. energy_lost equals T_c for "
        "sticking inert contacts; a slipping contact's friction also dissipates admissible "
        "energy, loss_beyond_T_c = energy_lost - T_c = T_a - T_plus (with --restitution the "
        "rebound's returned energy is subtracted too). admissible is false, with a note on "
        "stderr, when a --keep contact pulls on the ground (negative normal impulse): pass it "
        "as --strike (complementarity decides whether it lifts) or drop it. A striking "
        "FRAME:flat sole is its support polygon (FRAME:flat:HX,HY or :XMIN,XMAX,YMIN,YMAX, m, "
        "sole frame; default 0.2 m x 0.1 m centred), each corner a unilateral contact with "
        "its own friction (a pyramid cone) and restitution: heel, toe, edge and flat landings "
        "alike; its corners are listed in --json. FRAME:flat-bilateral is the 6-row contact "
        "held flat (kept: also FRAME:flat), and tilting_contacts names the kept soles whose "
        "centre of pressure leaves the polygon (a corner would pull). Where the law admits "
        "several outcomes, outcomes/unique/solutions say so (every active set is examined when "
        "there are few enough; otherwise unique is null and active_sets bounds them); "
        "impulse_unique is false where the impulses' split between redundant contacts (two "
        "soles of one body) is not determined. "
        "STATE.json holds q and v in Pinocchio's conventions: the base's linear and angular "
        "velocity in the base's own frame (not the world's), then the joint rates. Each "
        "contact's T_c_normal and T_c_tangential are nested shares in contact order (the "
        "--strike then --keep order given): their sum, T_c, does not depend on it, the shares "
        "of contacts that couple through the mass matrix do; a sole's corners come in the "
        "order of their approach speed (fastest first), so where corners' rows repeat one "
        "another the energy goes to those that strike hardest (the sole's total does not "
        "depend on that order).")
    g.add_argument("--robot", default=None, metavar="NAME",
                   help="a shipped robot (see 'heelstrike robot list')")
    g.add_argument("--urdf", default=None, metavar="FILE", help="a URDF robot (floating base)")
    g.add_argument("--mjcf", default=None, metavar="FILE", help="an MJCF robot (floating base)")
    g.add_argument("--strike", action="append", default=None,
                   metavar="FRAME:point|flat[:HX,HY]|flat-bilateral|arc:RADIUS",
                   help="striking contact (repeatable; FRAME:arc:RADIUS: an arc heel of radius "
                   "RADIUS m whose centre is the frame's origin, the contact point RADIUS below "
                   "it along the ground normal; the type is read after the last colon, so a "
                   "FRAME with colons is given as it is: base:foot:point); "
                   "unilateral, with --friction and --restitution, its lift is decided")
    g.add_argument("--keep", action="append", default=None,
                   metavar="FRAME:point|flat|flat-bilateral|arc:RADIUS",
                   help="persistent contact (repeatable): bilateral and inert, stays fixed; "
                   "with --keep contacts only, the paper's inert impact")
    g.add_argument("--friction", type=float, default=math.inf, metavar="MU",
                   help="Coulomb coefficient of the striking contacts (default inf: an "
                   "unbounded cone; a contact then slips only where sticking would need the "
                   "ground to pull, and says so)")
    g.add_argument("--restitution-law", choices=("newton", "energetic"), default="newton",
                   help="newton (default): u_n+ = -e u_n- at each striking contact, which can "
                   "gain energy with sticking friction (Kane's paradox); energetic: a "
                   "compression phase (e = 0), then a rebound returning at most e^2 of the "
                   "energy absorbed, which never gains energy (the same as newton for e = 0)")


def robot_requested(args: argparse.Namespace) -> bool:
    """Whether ``impact`` was called for a robot."""
    return any(getattr(args, k, None) is not None for k in ("robot", "urdf", "mjcf"))


#: Largest state file read (bytes): a state of 1,000 joints takes about 60 KB.
STATE_FILE_BYTES = 1 << 20


def _read_state(path: str, nq: int, nv: int) -> tuple[list[float], list[float]]:
    from heelstrike.io import InputFileError, read_regular_file

    try:
        data = read_regular_file(path, what="state file", max_bytes=STATE_FILE_BYTES)
    except InputFileError as exc:
        raise RobotCliError(str(exc)) from None
    try:
        obj = json.loads(data)
    except UnicodeDecodeError:
        raise RobotCliError(f"state file {path!r} is not JSON: not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise RobotCliError(f"state file {path!r} is not JSON: {exc.msg}") from None
    if not isinstance(obj, dict) or "q" not in obj or "v" not in obj:
        raise RobotCliError(f'state file {path!r} must be {{"q": [...], "v": [...]}}')
    out = []
    for key, n in (("q", nq), ("v", nv)):
        vals = obj[key]
        if not isinstance(vals, list) or not all(
            isinstance(x, int | float) and not isinstance(x, bool) for x in vals
        ):
            raise RobotCliError(f"state file {path!r}: {key!r} must be a list of numbers")
        if len(vals) != n:
            raise RobotCliError(
                f"state file {path!r}: {key!r} has {len(vals)} entries, the robot needs {n}"
            )
        out.append([float(x) for x in vals])
    return out[0], out[1]


def _note_normalised_blocks(robot: Any, q: list[float], where: str) -> None:
    """Say on stderr which unit blocks of ``q`` (the base quaternion, a continuous joint's
    ``(cos, sin)`` pair, ...: :attr:`Robot.unit_blocks`) are not unit vectors to round-off:
    the robot functions normalise them (:meth:`Robot.check_state`), so the pose computed is
    each block divided by its norm."""
    for block, norm in robot.normalised_blocks(q):
        _print(f"heelstrike: note: {where}: {block.describe()} has norm {norm:.9g}; it is "
              "normalised", file=sys.stderr)


def _note_separating_strikes(contacts: list[dict[str, Any]]) -> None:
    """Say on stderr which ``--strike`` contacts strike nothing: moving away from the ground
    before the impact (normal velocity above round-off) and separate after it."""
    scale = max((abs(c["normal_velocity_pre"]) for c in contacts), default=0.0)
    for c in contacts:
        u = c["normal_velocity_pre"]
        if c["role"] == "strike" and c["mode"] == "separate" and u > 1e-9 * max(scale, 1.0):
            _print(f"heelstrike: note: the striking contact {c['frame']} moves away from the "
                  f"ground before the impact (normal velocity {u:+.4g} m/s) and stays separate: "
                  "it strikes nothing (no impulse, no share of T_c)", file=sys.stderr)


def _note_outcomes(d: dict[str, Any], keep_text: dict[str, str]) -> None:
    """Say on stderr when the law has several outcomes and which kept soles would tilt (a
    corner pulls). Too many active sets to examine is said by the output itself (``unique``
    null and ``active_sets`` in --json, the line ``unique not checked`` in the text)."""
    if d["unique"] is False:
        _print(f"heelstrike: note: the contact law admits {d['outcomes']} outcomes (every one of "
              f"its {d['active_sets']} active sets examined); the one with the fewest sliding "
              "and active contacts is reported, all are in --json 'solutions'",
              file=sys.stderr)
    for frame in d["tilting_contacts"]:
        _print(f"heelstrike: note: the kept sole {frame} is held flat although one of its "
              "corners would have to pull (centre of pressure outside its support polygon): "
              f"pass it as --strike {frame}:flat (a "
              "support polygon) to let it tilt", file=sys.stderr)


def run_robot_impact(args: argparse.Namespace) -> int:
    """``heelstrike impact --robot NAME | --urdf FILE | --mjcf FILE --state STATE.json ...``."""
    import numpy as np

    from heelstrike.cli._render import require_finite
    from heelstrike.robots import parse_contact, robot_impact
    from heelstrike.robots.contacts import GROUND_GAP_TOLERANCE, contact_heights

    given = [k for k in ("robot", "urdf", "mjcf") if getattr(args, k, None) is not None]
    if len(given) > 1:
        raise RobotCliError(f"give only one of --robot, --urdf, --mjcf (got {', '.join(given)})")
    if getattr(args, "model", None) is not None or getattr(args, "angle", None) is not None:
        raise RobotCliError("--model and --angle do not apply to robots")
    if args.state is None:
        raise RobotCliError("robots need --state STATE.json with {\"q\": [...], \"v\": [...]}")
    if not args.strike and not args.keep:
        raise RobotCliError("robots need at least one --strike or --keep "
                            "FRAME:point|flat|arc:RADIUS")
    if not args.strike and (math.isfinite(args.friction) or args.restitution != 0.0
                            or getattr(args, "restitution_law", "newton") != "newton"):
        raise RobotCliError("--friction, --restitution and --restitution-law set the laws of "
                            "--strike contacts; "
                            "an impact with --keep contacts only is inert (the paper's law): "
                            "give a --strike or drop them")
    strike = [parse_contact(s) for s in (args.strike or [])]
    keep = [parse_contact(s) for s in (args.keep or [])]
    robot = _load(args.robot, args.urdf, args.mjcf)
    for c in (*strike, *keep):
        robot.frame_id(c.frame)
    q, v = _read_state(args.state, robot.nq, robot.nv)
    violations = _limit_violations(robot, q)
    with np.errstate(all="ignore"):  # overflow is refused below, as one error line
        res = robot_impact(robot, q, v, strike=strike, keep=keep, friction=args.friction,
                           restitution=args.restitution,
                           restitution_law=getattr(args, "restitution_law", "newton"))
        d = res.to_dict()
    d = {"robot": robot.name, "nq": robot.nq, "nv": robot.nv, **d}
    require_finite(d)
    _note_limit_violations(violations, f"state {args.state}")
    _note_normalised_blocks(robot, q, f"state {args.state}")
    if robot.ignored_couplings:
        tags = ", ".join(f"<{t}>" for t in robot.ignored_couplings)
        _print(f"heelstrike: note: {robot.source} has {tags} elements, which the model does not "
              "hold (Pinocchio's parser drops them): the joints they couple move independently "
              "in this impact", file=sys.stderr)
    keep_text = dict(zip([c.frame for c in keep], args.keep or [], strict=True))
    for frame, lam_n in res.pulling_contacts():
        _print(f"heelstrike: note: the kept contact {frame} pulls on the ground (normal impulse "
              f"{lam_n:.4g} N s < 0), so this impact is not admissible: pass it as --strike "
              f"{keep_text.get(frame, frame)} (complementarity then decides whether it lifts) "
              "or drop it", file=sys.stderr)
    _note_separating_strikes(d["contacts"])
    _note_outcomes(d, keep_text)
    for c, z in zip((*strike, *keep), contact_heights(robot, q, (*strike, *keep)), strict=True):
        if abs(z) > GROUND_GAP_TOLERANCE:  # QA sweep 9: computed as touching, silently
            _print(f"heelstrike: note: contact {c.frame} is {abs(z) * 1e3:.3g} mm "
                  f"{'above' if z > 0 else 'below'} the ground (z = 0) in state {args.state}; "
                  "the impact is computed as if it touched there", file=sys.stderr)
    if d["T_plus"] > d["T"] + 1e-9 * max(d["T"], 1e-300):
        _print(f"heelstrike: note: the impact adds {d['T_plus'] - d['T']:.6g} J of kinetic "
              f"energy (T_plus {d['T_plus']:.6g} J > T {d['T']:.6g} J): Newton's restitution "
              "with sticking friction can do so (Kane's paradox); the numbers follow that law, "
              "not an energetic bound (--restitution-law energetic cannot gain energy)",
              file=sys.stderr)
    if math.isinf(args.friction):
        for c in d["contacts"]:
            if c["role"] == "strike" and c["mode"] == "slip":
                _print(f"heelstrike: note: {c['frame']} slips although friction is unbounded: "
                      "sticking would need the ground to pull (a Painleve-type case), so the "
                      "contact slides with a vanishing normal impulse", file=sys.stderr)
    if args.json:
        _, v_units = _joint_units(robot.model)
        impulse_units = [u for J in res.result.contact_velocity_pre
                         for u in ["N s"] * 3 + ["N m s"] * (J.shape[0] - 3)]
        contact_units = {
            "frame": None, "type": None, "role": None, "mode": None, "T_c_normal": "J",
            "T_c_tangential": "J", "force_impulse": "N s", "moment_impulse": "N m s",
            "centre_of_pressure": "m",
            "normal_velocity_pre": "m/s", "normal_velocity_post": "m/s",
            "slip_speed_post": "m/s",
            "corners": {"corner": "m", "mode": None, "T_c_normal": "J", "T_c_tangential": "J",
                        "force_impulse": "N s", "normal_velocity_pre": "m/s",
                        "normal_velocity_post": "m/s", "slip_speed_post": "m/s"},
        }
        units = {
            "robot": None, "nq": "1", "nv": "1", "T": "J", "T_c": "J", "T_a": "J",
            "T_plus": "J", "energy_lost": "J", "loss_beyond_T_c": "J", "qdot_plus": v_units,
            "impulse": impulse_units, "contacts": contact_units, "admissible": None,
            "pulling_contacts": {"frame": None, "normal_impulse": "N s"},
            "tilting_contacts": None, "restitution_law": None, "outcomes": "1",
            "unique": None, "active_sets": "1", "solutions": v_units,
            "impulse_unique": None, "velocity_range": v_units, "kkt_residual": "1",
        }
        print_json(d, {k: units[k] for k in d})
        return 0
    _print(f"impact of '{robot.name}' (nq={robot.nq}, nv={robot.nv})")
    extra = d["loss_beyond_T_c"]
    extra_shown = abs(extra) > 1e-9 * max(d["T"], 1e-300)  # beyond round-off
    for key in ("T", "T_c", "T_a", "T_plus", "energy_lost", "loss_beyond_T_c"):
        value = d[key] if key != "loss_beyond_T_c" or extra_shown else 0.0
        _print(f"  {key:<15} {_joules(value):>12} J")
    for c in d["contacts"]:
        _print(f"  {c['role']:<6} {c['frame']:<24} {c['type']:<5} {c['mode']:<8} "
              f"T_c normal {_joules(c['T_c_normal'])} J, "
              f"tangential {_joules(c['T_c_tangential'])} J")
        for k in c.get("corners", []):
            x, y = k["corner"]
            _print(f"         corner ({x:+.3f}, {y:+.3f}) m {k['mode']:<8} normal velocity "
                  f"{k['normal_velocity_pre']:+.4f} -> {k['normal_velocity_post']:+.4f} m/s")
        if c.get("centre_of_pressure") is not None:
            x, y = c["centre_of_pressure"]
            _print(f"         centre of pressure ({x:+.4f}, {y:+.4f}) m from the frame origin "
                  "(world x, y; the sole is taken as unbounded: check it lies on the sole)")
    if extra_shown:
        slipping = [c["frame"] for c in d["contacts"] if c["mode"] == "slip"]
        causes = []
        if slipping:
            causes.append(f"friction at the slipping {', '.join(slipping)} dissipates "
                          "admissible energy (its tangential rows are not in T_c)")
        if args.restitution > 0.0:
            causes.append(f"restitution e = {args.restitution:g} returns energy")
        _print(f"  energy_lost - T_c = {extra:+.6f} J (the energy lost is not T_c here): "
              f"{' and '.join(causes) or 'see impact --help'}")
    _print(f"  admissible      {'yes' if d['admissible'] else 'no (a kept contact pulls)'}")
    unique = {True: "yes", False: f"no ({d['outcomes']} outcomes)",
              None: f"not checked ({d['active_sets']} active sets)"}[d["unique"]]
    if d["active_sets"]:
        _print(f"  unique          {unique} ({d['restitution_law']} restitution)")
    return 0
