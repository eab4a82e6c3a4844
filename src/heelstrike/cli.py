"""Command-line interface: ``heelstrike <command> ...``. It parses and calls, nothing more.

Conventions shared by every command:

- angles accept a ``deg`` or ``rad`` suffix (``20deg``, ``0.3rad``); bare numbers are radians;
- lengths are metres, masses kilograms, times seconds;
- ``--json`` prints exactly one JSON object on stdout, or nothing: a non-finite result is an
  error;
- with ``--model``, a compass-gait option sets the model's parameter of the same name (``--radius``
  sets ``R``) or is refused; no option is silently ignored;
- outputs, frame rates and memory are checked before computing;
- every failure (bad input, unwritable output, out of memory, an unexpected error) exits with
  status 2 and a one-line ``heelstrike: error: ...`` message on stderr; ``HEELSTRIKE_DEBUG=1``
  adds the traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

from heelstrike import cli_robot
from heelstrike._optional import MissingExtraError

__all__ = ["main", "parse_angle", "parse_range"]


class CliError(Exception):
    """A user-facing error: printed as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        raise CliError(message)


def parse_angle(text: str) -> float:
    """Parse ``'20deg'``, ``'0.3rad'`` or ``'0.3'`` (radians) into radians."""
    t = str(text).strip().lower()
    factor = 1.0
    if t.endswith("deg"):
        t, factor = t[:-3], math.pi / 180.0
    elif t.endswith("rad"):
        t = t[:-3]
    try:
        value = float(t) * factor
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"invalid angle {text!r}: use e.g. 20deg, 0.35rad or 0.35 (radians)"
        ) from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"invalid angle {text!r}: must be finite")
    return value


def parse_range(
    text: str, convert: Callable[[str], float] = float
) -> tuple[float, float, int | None]:
    """Parse ``'start:stop'`` or ``'start:stop:count'`` (count points, inclusive)."""
    parts = str(text).split(":")
    if len(parts) not in (2, 3):
        raise argparse.ArgumentTypeError(
            f"invalid range {text!r}: use START:STOP or START:STOP:COUNT"
        )
    try:
        start, stop = convert(parts[0]), convert(parts[1])
        count = int(parts[2]) if len(parts) == 3 else None
    except (ValueError, argparse.ArgumentTypeError) as exc:
        raise argparse.ArgumentTypeError(f"invalid range {text!r}: {exc}") from None
    if count is not None and count < 1:
        raise argparse.ArgumentTypeError(f"invalid range {text!r}: COUNT must be >= 1")
    return start, stop, count


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


class _Explicit(argparse.Action):
    """Store the value and record the option's ``dest`` in ``namespace.explicit``: options given
    on the command line are told from defaults, so that none is silently ignored."""

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
        values: Any, option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        namespace.explicit = {*vars(namespace).get("explicit", ()), self.dest}


def _explicit(args: argparse.Namespace) -> set[str]:
    """``dest`` names of the :class:`_Explicit` options given on the command line."""
    return set(vars(args).get("explicit", ()))


#: Compass-gait options (``dest``) and the description parameter each one sets with ``--model``
#: (the names of the shipped compass and torso walkers).
_COMPASS_PARAMS = {"radius": "R", "hip_mass": "mH", "leg_mass": "m", "leg_length": "l",
                   "com_from_hip": "b", "leg_inertia": "I", "gravity": "g"}


def _add_walker_options(p: argparse.ArgumentParser) -> None:
    """Options for every parameter of the paper's compass gait (SI units)."""
    g = p.add_argument_group(
        "walker parameters (paper defaults; with --model they set the model's R, mH, m, l, b, "
        "I, g)"
    )
    g.add_argument("--radius", type=float, default=0.0, action=_Explicit,
                   help="foot radius R (m), 0 <= R <= l")
    g.add_argument("--hip-mass", type=float, default=10.0, action=_Explicit,
                   help="hip mass mH (kg)")
    g.add_argument("--leg-mass", type=float, default=5.0, action=_Explicit,
                   help="mass of each leg m (kg)")
    g.add_argument("--leg-length", type=float, default=1.0, action=_Explicit,
                   help="leg length l (m)")
    g.add_argument("--com-from-hip", type=float, default=0.5, action=_Explicit,
                   help="hip to leg centre of mass b (m)")
    g.add_argument("--leg-inertia", type=float, default=0.0, action=_Explicit,
                   help="leg inertia about its COM (kg m^2)")
    g.add_argument("--gravity", type=float, default=9.81, action=_Explicit,
                   help="gravity g (m/s^2)")


def _walker_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.models.compass import CompassGait

    if vars(args).get("param"):
        raise CliError("--param needs --model (the compass gait takes --radius, --hip-mass, ...)")
    return CompassGait(
        hip_mass=args.hip_mass,
        leg_mass=args.leg_mass,
        leg_length=args.leg_length,
        leg_com_from_hip=args.com_from_hip,
        foot_radius=args.radius,
        leg_inertia=args.leg_inertia,
        gravity=args.gravity,
    )


def _add_model_options(p: argparse.ArgumentParser) -> None:
    """``--model`` (a TOML description or shipped name) and repeatable ``--param NAME=VALUE``."""
    g = p.add_argument_group("described walker (overrides the compass-gait options)")
    g.add_argument("--model", default=None, metavar="FILE_OR_NAME",
                   help="walker description: a .toml file or a shipped name "
                   "(compass, kneed, torso)")
    g.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="set a description parameter (SI units), repeatable, e.g. R=0.2")


def _model_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.dynamics.phased import load_phased_walker

    params: dict[str, float] = {}
    for item in args.param:
        name, sep, value = item.partition("=")
        try:
            if not sep or not name.strip():
                raise ValueError
            params[name.strip()] = float(value)
        except ValueError:
            raise CliError(f"invalid --param {item!r}: use NAME=VALUE, e.g. R=0.2") from None
    model = str(args.model)
    if os.path.exists(model) and not os.path.isfile(model):
        raise CliError(f"--model {model!r} is not a regular file")
    try:
        walker = load_phased_walker(model)
    except OSError as exc:
        raise CliError(f"cannot read model {model!r}: {exc.strerror or exc}") from exc
    known = walker.params
    for dest in sorted(_explicit(args) & set(_COMPASS_PARAMS)):
        name, option = _COMPASS_PARAMS[dest], "--" + dest.replace("_", "-")
        if name not in known:
            raise CliError(
                f"{option} sets the compass parameter {name!r}, which model "
                f"{walker.description.name!r} does not have (its parameters: "
                f"{', '.join(sorted(known))}); use --param NAME=VALUE"
            )
        if name in params:
            raise CliError(f"{option} and --param {name}=... both set {name!r}: give it once")
        params[name] = float(getattr(args, dest))
    return walker.replace(**params) if params else walker


def _parse_floats(text: str, option: str, n: int | None = None) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise CliError(f"invalid {option} {text!r}: use comma-separated numbers") from None
    if not all(math.isfinite(v) for v in vals):
        raise CliError(f"invalid {option} {text!r}: the numbers must be finite")
    if n is not None and len(vals) != n:
        raise CliError(f"invalid {option} {text!r}: expected {n} comma-separated numbers")
    return vals


def _nonfinite(obj: Any, path: str = "") -> list[str]:
    """Paths of the non-finite numbers in a JSON-ready object (``T_c``, ``qdot_plus[1]``)."""
    if isinstance(obj, float):
        return [] if math.isfinite(obj) else [path or "value"]
    if isinstance(obj, dict):
        return [p for k, v in obj.items() for p in _nonfinite(v, f"{path}.{k}" if path else k)]
    if isinstance(obj, list | tuple):
        return [p for i, v in enumerate(obj) for p in _nonfinite(v, f"{path}[{i}]")]
    return []


def _require_finite(obj: Any) -> None:
    """Refuse a result holding inf or NaN (overflow or a degenerate input)."""
    bad = _nonfinite(obj)
    if bad:
        shown = ", ".join(bad[:4]) + (f" and {len(bad) - 4} more" if len(bad) > 4 else "")
        raise CliError(f"the result is not finite ({shown}): the input overflows or is "
                       "degenerate; use smaller velocities or other parameters")


def _print_json(obj: Any) -> None:
    """Print one whole JSON object on stdout, or nothing (the text is built before writing).

    A ``units`` map for the object's keys is added (:func:`heelstrike._units.json_units`).
    """
    from heelstrike._units import json_units

    _require_finite(obj)
    if isinstance(obj, dict) and "units" not in obj:
        obj = {**obj, "units": json_units(obj)}
    text = json.dumps(obj, allow_nan=False) + "\n"
    sys.stdout.write(text)
    sys.stdout.flush()


def _writable_dir(path: str | os.PathLike[str], option: str = "--out") -> Any:
    """Create the directory ``path`` if needed and check that a file can be written in it,
    before any computing; returns it as a :class:`~pathlib.Path`."""
    import tempfile
    from pathlib import Path

    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        raise CliError(f"cannot write to {option} {str(path)!r}: {exc.strerror or exc}") from None
    return out


# ---------------------------------------------------------------------------------------------
# Commands. Each command has an ``_add_<name>(subparsers)`` that registers its parser and sets
# ``func`` to a ``_run_<name>(args) -> int``. Keep the bodies thin: parse, call the library,
# print.
# ---------------------------------------------------------------------------------------------

_COMMANDS: list[Callable[[Any], None]] = []


def _command(add: Callable[[Any], None]) -> Callable[[Any], None]:
    _COMMANDS.append(add)
    return add


# -- heel strike and the paper's figures (issue 2) ---------------------------------------------
@_command
def _add_reproduce(sub: Any) -> None:
    p = sub.add_parser(
        "reproduce",
        help="reproduce the paper's Figs. 2, 3a and 3b",
        description="Write Figs. 2, 3a and 3b of Font & Kövecses (2008) as PNG and PDF, with "
        "one CSV of data per figure, and print the paths written (one per line).",
    )
    p.add_argument("--out", default="figures", help="output directory (default: figures)")
    p.set_defaults(func=_run_reproduce)


def _run_reproduce(args: argparse.Namespace) -> int:
    from heelstrike.plots.paper import reproduce_paper

    try:
        paths = reproduce_paper(args.out)
    except OSError as exc:
        raise CliError(f"cannot write to {args.out!r}: {exc.strerror or exc}") from exc
    for path in paths:
        print(path)
    return 0


@_command
def _add_impact(sub: Any) -> None:
    p = sub.add_parser(
        "impact",
        help="energy decomposition of one heel strike",
        description="Decompose the pre-impact kinetic energy of a heel strike of the "
        "circular-feet compass gait into the constrained part T_c (lost) and the admissible "
        "part T_a (kept), with the post-impact velocities, the ground impulse and the loss per "
        "metre eta = T_c / L_S (Font & Kövecses 2008, eqs. 5-16).",
    )
    _add_walker_options(p)
    _add_model_options(p)
    p.add_argument("--angle", type=parse_angle, default=None,
                   help="impact angle q3, 0 < q3 < 90deg, e.g. 20deg (required unless --state)")
    p.add_argument("--state", default=None, metavar="Q1,...,QN",
                   help="with --model: full pre-impact configuration (m, rad) instead of --angle; "
                   "with --robot/--urdf/--mjcf: a STATE.json file {\"q\": [...], \"v\": [...]}")
    p.add_argument("--velocity", default=None, metavar="QD1,...,QDN",
                   help="with --model and --state: pre-impact velocities (m/s, rad/s); default: "
                   "stance rate --q3dot, foot rolling, joints at rest")
    p.add_argument("--q3dot", type=float, default=1.0, action=_Explicit,
                   help="pre-impact stance-leg rate q3_dot (rad/s, default 1)")
    p.add_argument("--q4dot", type=float, default=0.0, action=_Explicit,
                   help="pre-impact inter-leg rate q4_dot (rad/s, default 0; with --model the "
                   "rate of its 'hip' joint)")
    p.add_argument("--restitution", type=float, default=0.0, action=_Explicit,
                   help="restitution e of the constrained velocity, 0 <= e <= 1 (default 0; "
                   "compass gait, and robots' striking contacts (normal rows))")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    cli_robot.add_robot_impact_options(p)  # issue 10: --robot/--urdf/--mjcf, --strike, --keep
    p.set_defaults(func=_run_impact)


def _check_rates(args: argparse.Namespace) -> None:
    for option, value in (("--q3dot", args.q3dot), ("--q4dot", args.q4dot)):
        if not math.isfinite(value):
            raise CliError(f"{option} must be finite, got {value:g}")


def _run_impact_model(args: argparse.Namespace) -> int:
    from heelstrike.analysis.heel_strike import check_heel_strike_state
    from heelstrike.analysis.model_gaits import model_heel_strike, symmetric_heel_strike_state

    given = _explicit(args)
    if args.state is not None and args.angle is not None:
        raise CliError("give --angle (symmetric heel strike) or --state, not both")
    if args.velocity is not None and given & {"q3dot", "q4dot"}:
        raise CliError("--velocity sets every pre-impact rate: drop --q3dot/--q4dot")
    if "restitution" in given and args.restitution != 0.0:
        raise CliError("--restitution applies to the compass gait only (without --model); "
                       "a described walker's heel strike is inert (e = 0)")
    _check_rates(args)
    walker = _model_from_args(args)
    n = walker.n_coordinates
    if "q4dot" in given and "hip" not in walker.coordinate_names:
        raise CliError(f"--q4dot is the rate of the 'hip' joint, which model "
                       f"{walker.description.name!r} does not have; use --velocity")
    if args.state is not None:
        q = _parse_floats(args.state, "--state", n)
        try:
            check_heel_strike_state(walker, q)
        except ValueError as exc:
            raise CliError(f"--state: {exc}") from None
        if args.velocity is not None:
            qd = _parse_floats(args.velocity, "--velocity", n)
        else:
            R = float(walker.foot_radii[0])
            qd = [0.0] * n
            qd[2], qd[0] = args.q3dot, -R * args.q3dot
    else:
        if args.angle is None:
            raise CliError("give --angle (symmetric heel strike) or --state with --model")
        if not 0.0 < args.angle < math.pi / 2:
            raise CliError(f"--angle must satisfy 0 < angle < 90deg, got "
                           f"{math.degrees(args.angle):g} deg")
        q_, qd_ = symmetric_heel_strike_state(walker, args.angle, stance_rate=args.q3dot)
        q, qd = list(q_), list(qd_)
        if args.velocity is not None:
            qd = _parse_floats(args.velocity, "--velocity", n)
    if args.velocity is None and "q4dot" in given:
        qd[walker.coordinate_names.index("hip")] = args.q4dot
    s = model_heel_strike(walker, q, qd)
    d = s.to_dict()
    d["model"] = walker.description.name
    d["coordinates"] = list(walker.coordinate_names)
    _require_finite(d)
    if args.json:
        _print_json(d)
        return 0
    print(f"heel strike of '{d['model']}' ({', '.join(d['coordinates'])})")
    for key, unit in (("T", "J"), ("T_c", "J"), ("T_a", "J"), ("T_plus", "J"),
                      ("step_length", "m"), ("eta", "J/m")):
        print(f"  {key:<12} {d[key]:12.6f} {unit}")
    print(f"  trailing foot lifts  {'yes' if d['trailing_foot_lifts'] else 'no'}")
    return 0


def _run_impact(args: argparse.Namespace) -> int:
    from heelstrike.analysis.heel_strike import heel_strike_study

    given = _explicit(args)
    if cli_robot.robot_requested(args):
        ignored = [f"--{d.replace('_', '-')}" for d in sorted(given & {*_COMPASS_PARAMS,
                                                                      "q3dot", "q4dot"})]
        ignored += [o for o, v in (("--model", args.model), ("--param", args.param),
                                   ("--angle", args.angle), ("--velocity", args.velocity)) if v]
        if ignored:
            raise CliError(f"a robot (--robot/--urdf/--mjcf) does not take {', '.join(ignored)}; "
                           "it takes --state STATE.json, --strike, --keep, --friction and "
                           "--restitution")
        return cli_robot.run_robot_impact(args)
    unused = [o for o, v in (("--strike", args.strike), ("--keep", args.keep)) if v]
    unused += ["--friction"] if math.isfinite(args.friction) else []
    if unused:
        raise CliError(f"{', '.join(unused)}: only for a robot (--robot/--urdf/--mjcf)")
    if args.model is not None:
        return _run_impact_model(args)
    for option, value in (("--state", args.state), ("--velocity", args.velocity)):
        if value is not None:
            raise CliError(f"{option} needs --model (e.g. --model compass) or a robot; the "
                           "compass gait takes --angle, --q3dot and --q4dot")
    _check_rates(args)
    if args.angle is None:
        raise CliError("--angle is required (e.g. --angle 20deg)")
    if not 0.0 < args.angle < math.pi / 2:
        raise CliError(
            f"--angle must satisfy 0 < q3 < 90deg (leading foot ahead), got "
            f"{math.degrees(args.angle):g} deg"
        )
    walker = _walker_from_args(args)
    s = heel_strike_study(walker, args.angle, q3_dot=args.q3dot, q4_dot=args.q4dot,
                          restitution=args.restitution)
    d: dict[str, Any] = {
        "T": float(s.kinetic_energy),
        "T_c": float(s.kinetic_energy_constrained),
        "T_a": float(s.kinetic_energy_admissible),
        "eta": float(s.eta),
        "step_length": float(s.step_length),
        "qdot_plus": [float(v) for v in s.velocity_post],
        "impulse": [float(v) for v in s.constraint_impulse],
        "trailing_foot_lifts": bool(s.trailing_foot_lifts),
        "qdot_minus": [float(v) for v in s.velocity_pre],
        "T_plus": float(s.kinetic_energy_post),
        "energy_lost": float(s.energy_lost),
        "radius": float(s.foot_radius),
        "impact_angle": float(s.impact_angle),
        "restitution": float(s.restitution),
        "degenerate_wheel": bool(s.degenerate_wheel),
    }
    _require_finite(d)
    if args.json:
        _print_json(d)
        return 0
    T = d["T"]
    share = (lambda x: f"({100.0 * x / T:5.1f} % of T)") if T > 0 else (lambda x: "")
    print(f"heel strike: R = {d['radius']:g} m, q3 = {math.degrees(args.angle):g} deg, "
          f"q3_dot- = {args.q3dot:g} rad/s, q4_dot- = {args.q4dot:g} rad/s, "
          f"e = {args.restitution:g}")
    print(f"  kinetic energy before   T      {T:12.6f} J")
    print(f"  constrained part        T_c    {d['T_c']:12.6f} J  {share(d['T_c'])}")
    print(f"  admissible part         T_a    {d['T_a']:12.6f} J  {share(d['T_a'])}")
    print(f"  energy lost             |W|    {d['energy_lost']:12.6f} J")
    print(f"  kinetic energy after    T+     {d['T_plus']:12.6f} J")
    print(f"  step length             L_S    {d['step_length']:12.6f} m")
    print(f"  loss per metre          eta    {d['eta']:12.6f} J/m")
    print("  velocities                       before        after")
    units = ("m/s", "m/s", "rad/s", "rad/s")
    for i, unit in enumerate(units):
        name = f"q{i + 1}_dot ({unit})"
        print(f"    {name:<28}{d['qdot_minus'][i]:12.6f} {d['qdot_plus'][i]:12.6f}")
    lx, ly = d["impulse"]
    print(f"  ground impulse on the striking foot (x, y)  {lx:.6f}, {ly:.6f} N s")
    if d["degenerate_wheel"]:
        verdict = "no: R = l, McGeer's wheel (degenerate, q2_dot+ = 0)"
    else:
        verdict = "yes" if d["trailing_foot_lifts"] else "no (impact not admissible)"
    print(f"  trailing foot lifts     {verdict}")
    return 0


# -- gaits (issue 3) ---------------------------------------------------------------------------
def _parse_guess(text: str | None) -> list[float] | None:
    if text is None:
        return None
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise CliError(f"invalid --guess {text!r}: use Q3,Q3DOT,Q4DOT (rad, rad/s)") from None
    if len(vals) != 3:
        raise CliError(f"invalid --guess {text!r}: expected 3 comma-separated numbers")
    return vals


@_command
def _add_gait(sub: Any) -> None:
    p = sub.add_parser(
        "gait",
        help="find a passive limit cycle on a slope",
        description="Find the passive period-one gait of the circular-feet compass gait on a "
        "slope, its stability (Floquet multipliers) and energetics.",
    )
    _add_walker_options(p)
    _add_model_options(p)
    p.add_argument("--slope", type=parse_angle, default=parse_angle("3deg"),
                   help="slope angle, e.g. 3deg (default 3deg)")
    p.add_argument("--guess", default=None,
                   help="post-impact Q3,Q3DOT,Q4DOT to start Newton from (rad, rad/s); "
                   "write --guess=-0.27,1.09,-0.72 when Q3 is negative (with --model: the "
                   "walker's section coordinates)")
    p.add_argument("--backend", choices=("compiled", "scipy"), default="compiled",
                   help="step simulator: compiled numba kernels (default; generated from "
                   "the walker file with --model) or the scipy reference")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_gait)


def _run_gait_model(args: argparse.Namespace) -> int:
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.analysis.model_gaits import find_model_gait

    walker = _model_from_args(args)
    guess = None
    if args.guess is not None:
        guess = _parse_floats(args.guess, "--guess", len(walker.section_names))
    try:
        gait = find_model_gait(walker, slope=args.slope, guess=guess, backend=args.backend)
    except GaitNotFoundError as exc:
        raise CliError(f"no gait found at slope {math.degrees(args.slope):g} deg: {exc}") from exc
    d = gait.to_dict()
    d["model"] = walker.description.name
    if args.json:
        _print_json(d)
        return 0
    c = gait.cycle
    fp = ", ".join(f"{k} = {v:.6f}" for k, v in d["fixed_point"].items())
    print(f"passive gait of '{d['model']}', slope = {math.degrees(args.slope):g} deg")
    print(f"  fixed point (just after heel strike): {fp}")
    print(f"  period          {c.period:10.5f} s")
    print(f"  step length     {c.step_length:10.5f} m")
    print(f"  speed           {c.speed:10.5f} m/s")
    print(f"  |multipliers|   {', '.join(f'{abs(m):.4f}' for m in c.multipliers)}")
    print(f"  stable          {'yes' if c.stable else 'no'}")
    for imp in d["impacts"]:
        print(f"  {imp['kind']:<15} T_c = {imp['T_c']:.6f} J")
    print(f"  collision loss  {gait.collision_loss:10.5f} J/step (sum of T_c)")
    print(f"  energy released {gait.potential_energy_released:10.5f} J/step (gravity)")
    print(f"  eta             {gait.eta:10.5f} J/m")
    return 0


def _gait_summary(c: Any) -> dict[str, Any]:
    """One entry of ``gaits`` in ``gait --json``."""
    return {
        "q": [float(v) for v in c.q],
        "q_dot": [float(v) for v in c.q_dot],
        "fixed_point": {k: float(v) for k, v in zip(c.section_names, c.fixed_point, strict=True)},
        "period": float(c.period),
        "step_length": float(c.step_length),
        "speed": float(c.speed),
        "impact_angle": float(c.impact_angle),
        "multipliers": [float(abs(m)) for m in c.multipliers],
        "stable": bool(c.stable),
        "collision_loss": float(c.collision_loss),
    }


def _run_gait(args: argparse.Namespace) -> int:
    from heelstrike.analysis.limit_cycle import (
        GaitNotFoundError,
        find_limit_cycle,
        find_limit_cycles,
    )

    if not args.slope > 0:
        raise CliError(
            f"no gait found at slope {math.degrees(args.slope):g} deg: a passive walker needs "
            "a downhill slope > 0 (the energy lost at heel strike must come from gravity); "
            "e.g. --slope 3deg, or see 'heelstrike powered' for level ground"
        )
    if args.model is not None:
        return _run_gait_model(args)
    walker = _walker_from_args(args)
    guess = _parse_guess(args.guess)
    try:
        if guess is None:
            gaits = find_limit_cycles(
                walker, slope=args.slope, method=args.backend, progress=True
            )
        else:
            gaits = (find_limit_cycle(walker, slope=args.slope, guess=guess,
                                      method=args.backend),)
    except GaitNotFoundError as exc:
        raise CliError(f"no gait found at slope {math.degrees(args.slope):g} deg: {exc}") from exc
    cycle = gaits[0]
    d = cycle.to_dict()
    d["gaits"] = [_gait_summary(c) for c in gaits]
    if args.json:
        _print_json(d)
        return 0
    if len(gaits) > 1:
        print(f"{len(gaits)} period-one gaits found (the first, "
              f"{'the most attracting stable one' if cycle.stable else 'the least unstable'}, "
              "is shown in detail):")
        for i, c in enumerate(gaits):
            print(f"  [{i}] step length {c.step_length:.5f} m, period {c.period:.5f} s, "
                  f"|multipliers| {', '.join(f'{abs(m):.4f}' for m in c.multipliers)}, "
                  f"{'stable' if c.stable else 'unstable'}")
    fp = ", ".join(f"{k} = {v:.6f}" for k, v in d["fixed_point"].items())
    mult = ", ".join(f"{abs(m):.4f}" for m in cycle.multipliers)
    print(f"passive gait, R = {args.radius:g} m, slope = {math.degrees(args.slope):g} deg")
    print(f"  fixed point (just after impact): {fp}")
    print(f"  period          {cycle.period:10.5f} s")
    print(f"  step length     {cycle.step_length:10.5f} m")
    print(f"  speed           {cycle.speed:10.5f} m/s")
    print(f"  impact angle    {cycle.impact_angle:10.5f} rad "
          f"({math.degrees(cycle.impact_angle):.3f} deg)")
    print(f"  |multipliers|   {mult}")
    print(f"  stable          {'yes' if cycle.stable else 'no'}")
    print(f"  collision loss  {cycle.collision_loss:10.5f} J/step (T_c)")
    print(f"  energy released {cycle.potential_energy_released:10.5f} J/step (gravity)")
    print(f"  eta             {cycle.eta:10.5f} J/m")
    return 0


@_command
def _add_walk(sub: Any) -> None:
    p = sub.add_parser(
        "walk",
        help="simulate steps and animate the walker",
        description="Simulate the passive walker from its limit cycle (or --guess) and write "
        "an animation (.gif, or .mp4 where ffmpeg exists). With --out DIR, also write figures "
        "and their CSV data into DIR: a stick-figure strobe of one step, the phase portrait, "
        "joint angles and ground reaction over a step, and the energy over the walk. With "
        "--model: the animation, phase portrait, energy and impacts (the strobe and step "
        "figures are drawn for the compass gait only).",
    )
    _add_walker_options(p)
    _add_model_options(p)
    p.add_argument("--backend", choices=("compiled", "scipy"), default=None,
                   help="step simulator with --model: compiled (default; generated from the "
                   "walker file) or the scipy reference; the compass gait without --model "
                   "walks on the scipy reference")
    p.add_argument("--slope", type=parse_angle, default=parse_angle("3deg"),
                   help="slope angle (default 3deg)")
    p.add_argument("--steps", type=_positive_int, default=6, help="number of steps (default 6)")
    p.add_argument("--guess", default=None,
                   help="start from this post-impact Q3,Q3DOT,Q4DOT instead of the limit cycle "
                   "(with --model: the walker's section coordinates)")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--out", default="walk.gif",
                   help="output file (.gif or .mp4), or a directory for walk.gif plus the "
                   "figures (PNG) and their data (CSV)")
    p.set_defaults(func=_run_walk)


def _walk_model(args: argparse.Namespace, out: Any, to_dir: bool) -> int:
    """``walk --model``: the walk from the gait (or --guess), animation and figures."""
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.phased import simulate_phased
    from heelstrike.plots.gait import (
        COMPASS_ONLY_WALK_FIGURES,
        animate_model_walk,
        write_model_walk_figures,
    )

    walker = _model_from_args(args)
    backend = args.backend or "compiled"
    if args.guess is not None:
        z = _parse_floats(args.guess, "--guess", len(walker.section_names))
    else:
        try:
            z = list(find_model_gait(walker, slope=args.slope, backend=backend)
                     .cycle.fixed_point)
        except GaitNotFoundError as exc:
            raise CliError(f"no gait found to start from: {exc}") from exc
    q, qd = walker.section_to_state(z)
    if backend == "compiled":
        from heelstrike.dynamics.compiled_phased import simulate_phased_compiled as simulate
    else:
        simulate = simulate_phased
    walk = simulate(walker, q, qd, slope=args.slope, steps=args.steps, rtol=1e-9, atol=1e-9,
                    max_step=0.5 / args.fps)
    path = animate_model_walk(walker, walk, out / "walk.gif" if to_dir else out, fps=args.fps)
    print(f"{walk.n_steps} steps, status: {walk.status.value} ({walk.message})")
    print(path)
    if to_dir:
        for p in write_model_walk_figures(walker, walk, out):
            print(p)
        print(f"heelstrike: the {' and '.join(COMPASS_ONLY_WALK_FIGURES)} figures are drawn for "
              "the compass gait only (without --model); not written", file=sys.stderr)
    return 0 if walk.ok else 1


def _run_walk(args: argparse.Namespace) -> int:
    from pathlib import Path

    from heelstrike.analysis.limit_cycle import GaitNotFoundError, PoincareMap, find_limit_cycle
    from heelstrike.plots.gait import animate_walk, write_walk_figures

    if args.model is None and args.backend == "compiled":
        raise CliError("the compass walk (without --model) runs on the scipy reference; for "
                       "the compiled backend use --model compass")
    walker = None if args.model is not None else _walker_from_args(args)
    if not (math.isfinite(args.fps) and 0 < args.fps <= 240):
        raise CliError(f"--fps must satisfy 0 < fps <= 240 (frames per second), got {args.fps:g}")
    out = Path(args.out)
    to_dir = out.is_dir() or out.suffix == ""  # a directory: walk.gif, figures and CSVs
    if not to_dir and out.suffix.lower() not in (".gif", ".mp4"):
        raise CliError(f"--out must be a .gif or .mp4 file or a directory, got {args.out!r}")
    if to_dir and out.exists() and not out.is_dir():
        raise CliError(f"--out {args.out!r} exists and is not a directory")
    if not to_dir and out.suffix.lower() == ".mp4":
        import shutil

        if shutil.which("ffmpeg") is None:
            raise CliError("writing .mp4 needs ffmpeg on the PATH; use a .gif file instead")
    if not to_dir and out.is_dir():
        raise CliError(f"--out {args.out!r} is a directory")
    _writable_dir(out if to_dir else out.parent)
    if walker is None:
        return _walk_model(args, out, to_dir)
    z = _parse_guess(args.guess)
    if z is None:
        try:
            z = list(find_limit_cycle(walker, slope=args.slope).fixed_point)
        except GaitNotFoundError as exc:
            raise CliError(f"no gait found to start from: {exc}") from exc
    walk = PoincareMap(walker=walker, slope=args.slope, rtol=1e-9, atol=1e-9,
                       max_step=0.5 / args.fps).walk(z, args.steps)
    path = animate_walk(walker, walk, out / "walk.gif" if to_dir else out, fps=args.fps)
    print(f"{walk.n_steps} steps, status: {walk.status.value} ({walk.message})")
    print(path)
    if to_dir:
        for p in write_walk_figures(walker, walk, out):
            print(p)
    return 0 if walk.ok else 1


@_command
def _add_bifurcation(sub: Any) -> None:
    p = sub.add_parser(
        "bifurcation",
        help="period-doubling diagram over the slope",
        description="Steady-state impact angles and step periods against the slope (brute "
        "force, as Goswami et al. 1998) with the period-one branch and its period doublings.",
    )
    _add_walker_options(p)
    _add_model_options(p)
    p.add_argument("--backend", choices=("compiled", "scipy"), default="compiled",
                   help="step simulator with --model: compiled (default) or the scipy "
                   "reference (the compass diagram's pipeline is fixed)")
    p.add_argument("--slope-range", default="0.5deg:6deg",
                   type=lambda t: parse_range(t, parse_angle),
                   help="START:STOP[:COUNT] slopes, e.g. 0.5deg:6deg:56 (default count 45)")
    p.add_argument("--transient", type=_positive_int, default=50, help="steps discarded")
    p.add_argument("--record", type=_positive_int, default=16, help="steps recorded")
    p.add_argument("--out", default="bifurcation", help="output directory")
    p.set_defaults(func=_run_bifurcation)


def _run_bifurcation(args: argparse.Namespace) -> int:
    from pathlib import Path

    from heelstrike.plots.gait import write_bifurcation

    if args.model is None and args.backend != "compiled":
        raise CliError("--backend scipy is not supported by the compass bifurcation diagram "
                       "yet (its pipeline is fixed); use --model compass --backend scipy")
    walker = _walker_from_args(args) if args.model is None else _model_from_args(args)
    start, stop, count = args.slope_range
    if not 0 < start < stop:
        raise CliError("--slope-range needs 0 < START < STOP")
    _writable_dir(args.out)
    if args.model is not None:
        from heelstrike.analysis.limit_cycle import GaitNotFoundError
        from heelstrike.plots.gait import write_model_bifurcation

        try:
            paths = write_model_bifurcation(
                walker, start, stop, count or 45, Path(args.out), transient=args.transient,
                record=args.record, backend=args.backend,
            )
        except GaitNotFoundError as exc:
            raise CliError(f"no gait found at slope {math.degrees(start):g} deg: {exc}") from exc
        for path in paths:
            print(path)
        return 0
    paths = write_bifurcation(
        walker, start, stop, count or 45, Path(args.out), transient=args.transient,
        record=args.record, progress=True,
    )
    for path in paths:
        print(path)
    return 0


# -- resumable runs (issue 11, item 15) ---------------------------------------------------------
def _add_store_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--store", metavar="DIR", default=None,
                   help="keep every finished chunk in this Zarr directory as it is computed; "
                   "after an interruption (Ctrl-C) the same command resumes from it")


def _run_with_store(store: str | None, compute: Callable[[], Any]) -> Any:
    """Run ``compute()``; with a store, report its progress on stderr and map store errors."""
    if store is None:
        return compute()
    import logging

    from heelstrike.analysis.sweep import (
        SweepError,
        SweepStoreLockedError,
        SweepStoreMismatchError,
    )

    logger = logging.getLogger("heelstrike.analysis.sweep")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("heelstrike: %(message)s"))
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    try:
        return compute()
    except SweepStoreMismatchError as exc:
        raise CliError(
            f"--store {store!r} holds results of a different computation (differs in: "
            f"{', '.join(exc.differs)}); remove it or choose another directory"
        ) from exc
    except SweepStoreLockedError as exc:
        raise CliError(
            f"--store {store!r} is in use by another heelstrike run; wait for it to finish or "
            "choose another directory"
        ) from exc
    except SweepError as exc:
        raise CliError(str(exc)) from exc
    except KeyboardInterrupt:
        print(f"heelstrike: finished chunks are kept in {store!r}; run the same command "
              "again to resume", file=sys.stderr)
        raise
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)


# -- basin of attraction and stable-gait map (issue 6) ------------------------------------------
def _parse_grid(text: str) -> tuple[int, int]:
    parts = str(text).lower().split("x")
    try:
        if len(parts) != 2:
            raise ValueError
        n1, n2 = int(parts[0]), int(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid grid {text!r}: use e.g. 400x400") from None
    if n1 < 1 or n2 < 1:
        raise argparse.ArgumentTypeError(f"invalid grid {text!r}: sizes must be >= 1")
    return n1, n2


@_command
def _add_basin(sub: Any) -> None:
    p = sub.add_parser(
        "basin",
        help="basin of attraction of the passive gait",
        description="Basin of attraction (Schwab & Wisse 2001) of the passive period-one gait on "
        "the post-impact (q3, q3_dot) slice through the fixed point (q4_dot at its fixed-point "
        "value), computed with the compiled ensemble. With --model: the slice of the walker's "
        "post-heel-strike section spanned by the stance angle and its rate, the other section "
        "coordinates held at the fixed point. Writes basin.png and basin.nc.",
    )
    _add_walker_options(p)
    _add_model_options(p)
    p.add_argument("--backend", choices=("compiled", "scipy"), default="compiled",
                   help="step simulator: the compiled ensemble (default) or, with --model, "
                   "the scipy reference (slow)")
    p.add_argument("--slope", type=parse_angle, default=parse_angle("3deg"),
                   help="slope angle (default 3deg)")
    p.add_argument("--grid", type=_parse_grid, default=None,
                   help="N_Q3xN_Q3DOT grid points (default 400x400; 100x100 with --model)")
    p.add_argument("--q3-range", type=lambda t: parse_range(t, parse_angle),
                   default=None, help="Q3MIN:Q3MAX post-impact stance angles (default "
                   "-0.5:-0.05 rad; with --model the stance angle, default -0.25:+0.2 rad about "
                   "the fixed point); write --q3-range=-0.5:-0.05")
    p.add_argument("--q3dot-range", type=parse_range, default=None,
                   help="MIN:MAX post-impact stance velocities in rad/s (default 0.3:2.3; with "
                   "--model -0.9:+1.1 about the fixed point)")
    p.add_argument("--steps", type=_positive_int, default=60,
                   help="largest number of steps per initial state (default 60)")
    p.add_argument("--tol", type=float, default=1e-3,
                   help="convergence radius around the fixed point (default 1e-3)")
    p.add_argument("--out", default="basin", help="output directory (default ./basin)")
    _add_store_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_basin)


def _run_basin_model(args: argparse.Namespace) -> int:
    from heelstrike.analysis import basin as basin_module
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.plots.gait import write_basin

    walker = _model_from_args(args)
    grid = args.grid or (100, 100)
    ranges = None
    if args.q3_range is not None or args.q3dot_range is not None:
        if args.q3_range is None or args.q3dot_range is None:
            raise CliError("with --model give both --q3-range and --q3dot-range, or neither "
                           "(default: a window about the fixed point)")
        ranges = (args.q3_range[:2], args.q3dot_range[:2])
        if not (ranges[0][0] < ranges[0][1] and ranges[1][0] < ranges[1][1]):
            raise CliError("--q3-range and --q3dot-range need MIN < MAX")
    if not args.tol > 0:
        raise CliError("--tol must be > 0")
    _writable_dir(args.out)
    try:
        basin = _run_with_store(args.store, lambda: basin_module.model_basin_of_attraction(
            walker, args.slope, grid=grid, ranges=ranges, steps=args.steps, tol=args.tol,
            backend=args.backend, progress=not args.json and sys.stderr.isatty(),
            store=args.store,
        ))
    except GaitNotFoundError as exc:
        raise CliError(f"no gait found at slope {math.degrees(args.slope):g} deg: {exc}") from exc
    png, nc = write_basin(basin, args.out)
    names = walker.section_names
    ia, ib = basin.axes
    if args.json:
        _print_json({
            "model": walker.description.name,
            "converging_fraction": basin.converging_fraction,
            "fractions": basin.fractions(),
            "fixed_point": dict(zip(names, map(float, basin.fixed_point), strict=True)),
            "grid": list(grid),
            "steps": args.steps,
            "slope": args.slope,
            "elapsed": basin.elapsed,
            "figure": str(png),
            "data": str(nc),
        })
        return 0
    fp = ", ".join(f"{k} = {v:.6f}" for k, v in zip(names, basin.fixed_point, strict=True))
    print(f"basin of attraction of '{walker.description.name}', slope = "
          f"{math.degrees(args.slope):g} deg, grid {grid[0]}x{grid[1]} over ({names[ia]}, "
          f"{names[ib]}), up to {args.steps} steps")
    print(f"  {'fixed point':20s} {fp}")
    print(f"  {'converging':20s} {100 * basin.converging_fraction:.3f} % of the grid")
    for name, frac in basin.fractions().items():
        if frac > 0 and name != "converged":
            print(f"  {name.replace('_', ' '):20s} {100 * frac:.3f} %")
    print(f"  {'ensemble time':20s} {basin.elapsed:.1f} s ({basin.walker_steps} walker-steps)")
    print(png)
    print(nc)
    return 0


def _run_basin(args: argparse.Namespace) -> int:
    from heelstrike.analysis.basin import basin_of_attraction
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.plots.gait import write_basin

    if args.model is not None:
        return _run_basin_model(args)
    if args.backend != "compiled":
        raise CliError("the compass basin runs on the compiled ensemble only; for the scipy "
                       "reference use --model compass --backend scipy")
    walker = _walker_from_args(args)
    a0, a1, _ = args.q3_range or (-0.5, -0.05, None)
    b0, b1, _ = args.q3dot_range or (0.3, 2.3, None)
    args.grid = args.grid or (400, 400)
    if not (a0 < a1 and b0 < b1):
        raise CliError("--q3-range and --q3dot-range need MIN < MAX")
    if not args.tol > 0:
        raise CliError("--tol must be > 0")
    _writable_dir(args.out)
    try:
        basin = _run_with_store(args.store, lambda: basin_of_attraction(
            walker, args.slope, grid=args.grid, ranges=((a0, a1), (b0, b1)), steps=args.steps,
            tol=args.tol, progress=not args.json and sys.stderr.isatty(), store=args.store,
        ))
    except GaitNotFoundError as exc:
        raise CliError(f"no gait found at slope {math.degrees(args.slope):g} deg: {exc}") from exc
    png, nc = write_basin(basin, args.out)
    if args.json:
        _print_json({
            "converging_fraction": basin.converging_fraction,
            "fractions": basin.fractions(),
            "fixed_point": dict(zip(("q3", "q3_dot", "q4_dot"),
                                    map(float, basin.fixed_point), strict=True)),
            "grid": list(args.grid),
            "steps": args.steps,
            "slope": args.slope,
            "elapsed": basin.elapsed,
            "figure": str(png),
            "data": str(nc),
        })
        return 0
    print(f"basin of attraction, R = {args.radius:g} m, slope = {math.degrees(args.slope):g} deg, "
          f"grid {args.grid[0]}x{args.grid[1]}, up to {args.steps} steps")
    print(f"  {'fixed point':20s} q3 = {basin.fixed_point[0]:.6f} rad, q3_dot = "
          f"{basin.fixed_point[1]:.6f} rad/s, q4_dot = {basin.fixed_point[2]:.6f} rad/s")
    print(f"  {'converging':20s} {100 * basin.converging_fraction:.3f} % of the grid")
    for name, frac in basin.fractions().items():
        if frac > 0 and name != "converged":
            print(f"  {name.replace('_', ' '):20s} {100 * frac:.3f} %")
    print(f"  {'ensemble time':20s} {basin.elapsed:.1f} s")
    print(png)
    print(nc)
    return 0


@_command
def _add_map(sub: Any) -> None:
    p = sub.add_parser(
        "map",
        help="stable passive gaits over foot radius and slope",
        description="Period-one passive gaits over (foot radius, slope): spectral radius, "
        "stability and the period-doubling slope per radius (continuation along the slope with "
        "the compiled step map). Writes gait_map.png and gait_map.nc.",
        conflict_handler="resolve",  # --radius below replaces the walker option by a range
    )
    _add_walker_options(p)
    _add_model_options(p)
    p.add_argument("--backend", choices=("compiled", "scipy"), default="compiled",
                   help="step simulator: compiled (default) or, with --model, the scipy "
                   "reference")
    p.add_argument("--radius", type=parse_range, default=None,
                   help="START:STOP[:COUNT] foot radii in m (default 0:0.6:7; with --model "
                   "the walker's parameter R)")
    p.add_argument("--x", type=_sweep, default=None, metavar="NAME:START:STOP:COUNT",
                   help="with --model: the swept walker parameter instead of --radius, e.g. "
                   "R:0:0.2:5 (SI units)")
    p.add_argument("--slope", type=lambda t: parse_range(t, parse_angle),
                   default=(math.radians(1.0), math.radians(6.0), 21),
                   help="START:STOP[:COUNT] slopes, e.g. 1deg:6deg:21 (default)")
    p.add_argument("--out", default="gait_map", help="output directory (default ./gait_map)")
    _add_store_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_map)


def _run_map_model(args: argparse.Namespace) -> int:
    import warnings

    import numpy as np

    from heelstrike.analysis.gait_map import model_gait_map
    from heelstrike.plots.gait import write_gait_map

    walker = _model_from_args(args)
    if args.store is not None:
        raise CliError("--store is not supported with --model yet (the map is not chunked)")
    if args.x is not None and args.radius is not None:
        raise CliError("give --x NAME:START:STOP:COUNT or --radius, not both")
    if args.x is not None:
        name, x0, x1, nx = args.x
    elif "R" in walker.params:
        name, (x0, x1, nx) = "R", args.radius or (0.0, 0.6, 7)
    else:
        raise CliError(f"model {walker.description.name!r} has no parameter 'R': give the swept "
                       f"parameter with --x NAME:START:STOP:COUNT (its parameters: "
                       f"{', '.join(sorted(walker.params))})")
    if name not in walker.params:
        raise CliError(f"unknown parameter {name!r} of model {walker.description.name!r} (its "
                       f"parameters: {', '.join(sorted(walker.params))})")
    s0, s1, ns = args.slope
    if not 0 < s0 < s1:
        raise CliError("--slope needs 0 < START < STOP")
    values = np.linspace(x0, x1, nx or 7)
    slopes = np.linspace(s0, s1, ns or 21)
    _writable_dir(args.out)
    gmap = model_gait_map(walker, name, values, slopes, backend=args.backend,
                          progress=not args.json and sys.stderr.isatty())
    with warnings.catch_warnings():  # all-NaN rows (values without a gait) are expected
        warnings.simplefilter("ignore", RuntimeWarning)
        png, nc = write_gait_map(gmap, args.out)
    ds = gmap.dataset
    pd = [None if not np.isfinite(v) else float(v) for v in gmap.period_doubling_slope]
    stable = ds["stable"].values
    found = ds["gait_found"].values
    if args.json:
        _print_json({
            "model": walker.description.name,
            "parameter_name": name,
            "slope": slopes.tolist(),
            "stable_fraction": float(np.mean(stable)),
            "period_doubling_slope": pd,
            "gait_found_fraction": float(np.mean(found)),
            "gait_found": found.tolist(),
            "figure": str(png),
            "data": str(nc),
        })
        return 0
    print(f"stable passive gaits of '{walker.description.name}': {int(stable.sum())} of "
          f"{stable.size} ({name}, slope) points; no gait found at {int((~found).sum())} (NaN "
          "in the data, blank in the figure)")
    for v, p, row, frow in zip(values, pd, stable, found, strict=True):
        pd_text = "none in range" if p is None else f"{math.degrees(p):.3f} deg"
        print(f"  {name} = {v:8.4g}: stable at {int(row.sum()):3d}/{row.size} slopes, "
              f"no gait at {int((~frow).sum()):3d}, period doubling {pd_text}")
    print(png)
    print(nc)
    return 0


def _run_map(args: argparse.Namespace) -> int:
    import warnings

    import numpy as np

    from heelstrike.analysis.gait_map import gait_map
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.plots.gait import write_gait_map

    if args.model is not None:
        return _run_map_model(args)
    if args.x is not None:
        raise CliError("--x needs --model (the compass gait's map sweeps --radius)")
    if args.backend != "compiled":
        raise CliError("the compass map runs on the compiled step map only; for the scipy "
                       "reference use --model compass --backend scipy")
    r0, r1, nr = args.radius or (0.0, 0.6, 7)
    s0, s1, ns = args.slope
    if not 0 <= r0 <= r1 <= args.leg_length:
        raise CliError("--radius needs 0 <= START <= STOP <= leg length")
    if not 0 < s0 < s1:
        raise CliError("--slope needs 0 < START < STOP")
    radii = np.linspace(r0, r1, nr or 7)
    slopes = np.linspace(s0, s1, ns or 21)
    base = _walker_from_args(argparse.Namespace(**{**vars(args), "radius": float(radii[0])}))
    _writable_dir(args.out)
    try:
        gmap = _run_with_store(args.store, lambda: gait_map(
            base, radii, slopes, progress=not args.json and sys.stderr.isatty(),
            store=args.store))
    except GaitNotFoundError as exc:
        raise CliError(f"no starting gait found: {exc}") from exc
    with warnings.catch_warnings():  # all-NaN rows (radii without a gait) are expected
        warnings.simplefilter("ignore", RuntimeWarning)
        png, nc = write_gait_map(gmap, args.out)
    ds = gmap.dataset
    pd = [None if not np.isfinite(v) else float(v) for v in gmap.period_doubling_slope]
    stable = ds["stable"].values
    found = ds["gait_found"].values
    if args.json:
        _print_json({
            "foot_radius": radii.tolist(),
            "slope": slopes.tolist(),
            "stable_fraction": float(np.mean(stable)),
            "period_doubling_slope": pd,
            "gait_found_fraction": float(np.mean(found)),
            "gait_found": found.tolist(),
            "figure": str(png),
            "data": str(nc),
        })
        return 0
    print(f"stable passive gaits: {int(stable.sum())} of {stable.size} (R, slope) points; "
          f"no gait found at {int((~found).sum())} (NaN in the data, blank in the figure)")
    for R, v, row, frow in zip(radii, pd, stable, found, strict=True):
        pd_text = "none in range" if v is None else f"{math.degrees(v):.3f} deg"
        print(f"  R = {R:6.3f} m: stable at {int(row.sum()):3d}/{row.size} slopes, "
              f"no gait at {int((~frow).sum()):3d}, period doubling {pd_text}")
    print(png)
    print(nc)
    return 0


# -- described walkers: heel-strike maps over two swept quantities (issue 5) ---------------------
def _sweep(text: str) -> tuple[str, float, float, int]:
    name, sep, rest = text.partition(":")
    if not sep or not name:
        raise argparse.ArgumentTypeError(
            f"invalid sweep {text!r}: use NAME:START:STOP:COUNT (NAME a parameter or 'angle')"
        )
    conv = parse_angle if name == "angle" else float
    start, stop, count = parse_range(rest, conv)
    if count is None:
        raise argparse.ArgumentTypeError(f"invalid sweep {text!r}: COUNT is required")
    return name, start, stop, count


@_command
def _add_impact_map(sub: Any) -> None:
    p = sub.add_parser(
        "impact-map",
        help="map T_c, T_a and eta at heel strike over two swept quantities",
        description="For a described walker, sweep two description parameters (or one and "
        "the impact angle, NAME 'angle') and map the constrained and admissible kinetic "
        "energies and the loss per metre at a symmetric heel strike (stance rate --q3dot, "
        "joints at rest). Writes impact_map.png and impact_map.csv and prints their paths.",
    )
    _add_model_options(p)
    p.add_argument("--x", type=_sweep, required=True, metavar="NAME:START:STOP:COUNT")
    p.add_argument("--y", type=_sweep, required=True, metavar="NAME:START:STOP:COUNT")
    p.add_argument("--angle", type=parse_angle, default=parse_angle("20deg"),
                   help="impact angle when not swept (default 20deg)")
    p.add_argument("--q3dot", type=float, default=1.0, help="stance rate (rad/s, default 1)")
    p.add_argument("--out", default="impact_map", help="output directory")
    p.set_defaults(func=_run_impact_map)


def _run_impact_map(args: argparse.Namespace) -> int:
    import numpy as np

    from heelstrike.analysis.model_gaits import ANGLE, impact_map
    from heelstrike.models.description import parameter_units
    from heelstrike.plots.models import write_impact_map

    if args.model is None:
        raise CliError("--model is required (a .toml file or compass, kneed, torso)")
    if not math.isfinite(args.q3dot):
        raise CliError(f"--q3dot must be finite, got {args.q3dot:g}")
    walker = _model_from_args(args)
    axes = [(n, np.linspace(a, b, c)) for n, a, b, c in (args.x, args.y)]
    if axes[0][0] == axes[1][0]:
        raise CliError(f"--x and --y must sweep different quantities, both are {axes[0][0]!r}")
    swept_angle = any(name == ANGLE for name, _ in axes)
    for option, (name, values) in zip(("--x", "--y"), axes, strict=True):
        if name == ANGLE:
            if not np.all((values > 0) & (values < math.pi / 2)):
                raise CliError(f"{option}: the impact angle must satisfy 0 < angle < 90deg")
            continue
        if name not in walker.params:
            raise CliError(f"{option}: {name!r} is not a parameter of model "
                           f"{walker.description.name!r} (its parameters: "
                           f"{', '.join(sorted(walker.params))}; or {ANGLE!r})")
        for v in values:
            try:
                walker.replace(**{name: float(v)})
            except ValueError as exc:
                raise CliError(f"{option}: {name} = {v:g} is not a valid "
                               f"{walker.description.name!r} walker: {exc}") from None
    if not swept_angle and not 0.0 < args.angle < math.pi / 2:
        raise CliError(f"--angle must satisfy 0 < angle < 90deg, got "
                       f"{math.degrees(args.angle):g} deg")
    out = _writable_dir(args.out)
    m = impact_map(walker, axes[0], axes[1], angle=args.angle, stance_rate=args.q3dot)
    bad = ~np.isfinite(m.T_c) | ~np.isfinite(m.T_a) | ~np.isfinite(m.eta)
    if np.any(bad):
        i, j = (int(k[0]) for k in np.nonzero(bad))
        point = {m.x_name: float(m.x[j]), m.y_name: float(m.y[i])}
        reason = "overflow or no symmetric heel strike"
        try:
            walker.replace(**{k: v for k, v in point.items() if k != ANGLE})
        except ValueError as exc:
            reason = _one_line(exc)
        raise CliError(
            f"{int(bad.sum())} of {bad.size} grid points have no valid heel strike, e.g. "
            f"{', '.join(f'{k} = {v:g}' for k, v in point.items())}: {reason}; "
            "narrow --x/--y"
        )
    paths = write_impact_map(m, out, units=parameter_units(walker.description))
    for path in paths:
        print(path)
    return 0


# -- powered walking on level ground (issue 4) -------------------------------------------------
_ACTUATIONS = ("pushoff", "hip-energy", "hip-pd")


def _add_actuation_options(p: argparse.ArgumentParser) -> None:
    # defaults (None) come from heelstrike.dynamics.actuation.DEFAULT_*, which explain them
    g = p.add_argument_group("actuation (defaults: heelstrike.dynamics.actuation)")
    g.add_argument("--gain", type=float, default=None,
                   help="energy-tracking gain k of hip-energy (s/rad, default 3)")
    g.add_argument("--kp", type=float, default=None,
                   help="hip-pd stiffness (N m/rad, default 50)")
    g.add_argument("--kd", type=float, default=None,
                   help="hip-pd damping (N m s/rad, default 5)")
    g.add_argument("--max-torque", type=float, default=None,
                   help="hip torque limit (N m, default 50)")


def _actuation_options(args: argparse.Namespace) -> dict[str, float]:
    """The actuation options given on the command line (the library supplies the rest)."""
    opts = {k: float(getattr(args, k)) for k in ("gain", "kp", "kd", "max_torque")
            if getattr(args, k) is not None}
    if "max_torque" in opts and not opts["max_torque"] > 0:
        raise CliError("--max-torque must be > 0 (N m)")
    if "gain" in opts and not opts["gain"] > 0:
        raise CliError("--gain must be > 0 (s/rad)")
    for k in ("kp", "kd"):
        if k in opts and not opts[k] >= 0:
            raise CliError(f"--{k} must be >= 0")
    return opts


def _family_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.analysis.powered import actuation_family

    return actuation_family(args.actuation, **_actuation_options(args))


@_command
def _add_powered(sub: Any) -> None:
    p = sub.add_parser(
        "powered",
        help="periodic powered gait on level ground and its energy books",
        description="Find the level-ground periodic gait of a powered compass gait with a "
        "target speed or step length: push-off impulse (pushoff), energy-tracking hip torque "
        "(hip-energy) or swing-leg PD (hip-pd). Prints the energy books per step: on a "
        "periodic gait the actuator work equals the collision loss T_c (paper eqs. 14-15). "
        "With --model: push-off (the impulse is found) plus the posture law the walker file "
        "declares ([control.torso], e.g. --model torso).",
    )
    _add_walker_options(p)
    _add_model_options(p)
    p.add_argument("--backend", choices=("compiled", "scipy"), default=None,
                   help="step simulator with --model: compiled (default; generated from the "
                   "walker file) or the scipy reference; the compass gait without --model "
                   "runs on the scipy reference")
    tgt = p.add_mutually_exclusive_group()
    tgt.add_argument("--speed", type=float, default=None, help="target mean speed (m/s)")
    tgt.add_argument("--step-length", type=float, default=None, help="target step length (m)")
    p.add_argument("--actuation", choices=_ACTUATIONS, default="pushoff",
                   help="actuation model (default pushoff)")
    _add_actuation_options(p)
    p.add_argument("--out", default=None, metavar="DIR",
                   help="also write the period's energy books: DIR/powered_energy.png and "
                   "its data DIR/powered_energy.csv")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_powered)


def _run_powered(args: argparse.Namespace) -> int:
    from heelstrike.analysis.powered import (
        DEFAULT_TIME_LIMIT,
        PoweredGaitNotFoundError,
        find_model_powered_gait,
        find_powered_gait,
    )

    if args.model is None and args.backend == "compiled":
        raise CliError("the compass powered search (without --model) runs on the scipy "
                       "reference; for the compiled backend use --model compass")
    if args.model is not None:
        if args.actuation != "pushoff":
            raise CliError(f"--actuation {args.actuation} is not supported with --model (only "
                           "pushoff, with the posture law the walker file declares)")
        given = [f"--{k.replace('_', '-')}" for k in ("gain", "kp", "kd", "max_torque")
                 if getattr(args, k) is not None]
        if given:
            raise CliError(f"{', '.join(given)} set(s) the compass hip laws, not used with "
                           "--model (the posture law's gains are declared in the walker file)")
    walker = _walker_from_args(args) if args.model is None else _model_from_args(args)
    if args.speed is None and args.step_length is None:
        args.speed = 0.5
    target, value = (
        ("speed", args.speed) if args.speed is not None else ("step_length", args.step_length)
    )
    if not (math.isfinite(value) and value > 0):
        raise CliError(f"--{target.replace('_', '-')} must be > 0, got {value:g}")
    radius = float(walker.foot_radii[0]) if args.model is not None else args.radius
    out = None if args.out is None else _writable_dir(args.out)
    try:
        if args.model is None:
            gait = find_powered_gait(walker, actuation=_family_from_args(args), progress=True,
                                     time_limit=DEFAULT_TIME_LIMIT, **{target: value})
        else:
            gait = find_model_powered_gait(walker, backend=args.backend or "compiled",
                                           progress=True, time_limit=DEFAULT_TIME_LIMIT,
                                           **{target: value})
    except PoweredGaitNotFoundError as exc:
        raise CliError(
            f"no {args.actuation} gait found with {target.replace('_', ' ')} {value:g} "
            f"at R = {radius:g} m: {exc}"
        ) from exc
    d = gait.to_dict()
    if out is not None:
        from heelstrike.analysis.powered import energy_book_tables
        from heelstrike.plots.gait import energy_figure

        energy, impacts = energy_book_tables(walker, gait)
        name = gait.model or "compass gait"
        fig = energy_figure(energy, impacts, title=(
            f"{name}, powered gait at {gait.speed:.3g} m/s: {gait.torque_joint} torque "
            f"{gait.torque_work:+.4f} J over the step,\npush-off {gait.push_off_work:+.4f} J "
            f"(jump at heel strike), heel strike -T_c = {-gait.collision_loss:.4f} J"))
        png, csv = out / "powered_energy.png", out / "powered_energy.csv"
        fig.savefig(png)
        energy.to_csv(csv, index=False)
        print(f"{png}\n{csv}", file=sys.stderr if args.json else sys.stdout)
    if args.json:
        _print_json(d)
        return 0
    fp = ", ".join(f"{k} = {v:.6f}" for k, v in d["fixed_point"].items())
    mult = ", ".join(f"{abs(m):.4f}" for m in gait.multipliers)
    label = args.actuation if gait.model is None else \
        f"{args.actuation}, model {gait.model}, {args.backend or 'compiled'} backend"
    print(f"powered gait ({label}), R = {radius:g} m, level ground")
    print(f"  {gait.parameter_name:15s} {gait.parameter:10.5f} {gait.parameter_unit}")
    print(f"  fixed point (just after impact): {fp}")
    print(f"  period          {gait.period:10.5f} s")
    print(f"  step length     {gait.step_length:10.5f} m")
    print(f"  speed           {gait.speed:10.5f} m/s")
    print(f"  |multipliers|   {mult}")
    print(f"  stable          {'yes' if gait.stable else 'no'}")
    print("  energy books per step")
    print(f"    actuator work   {gait.actuator_work:12.6f} J (push-off "
          f"{gait.push_off_work:.6f} J, {gait.torque_joint} {gait.torque_work:.6f} J)")
    print(f"    collision loss  {gait.collision_loss:12.6f} J (T_c)")
    print(f"    change of T + V {gait.energy_change:12.3e} J")
    print(f"    imbalance       {gait.energy_balance_error:12.3e} J")
    print(f"  cost of transport {gait.cost_of_transport:10.6f}")
    print(f"  eta             {gait.eta:10.6f} J/m")
    if gait.trailing_foot_grazes:
        print("  note: R = l (McGeer's wheel): the trailing foot's lift velocity is exactly 0; "
              "both contacts are the same point, so the step was accepted")
    return 0


@_command
def _add_study(sub: Any) -> None:
    p = sub.add_parser(
        "study",
        help="design studies (cost: cost of transport over foot radius x step length)",
        description="Design studies of powered walkers on level ground.",
    )
    ssub = p.add_subparsers(dest="study", required=True, parser_class=_Parser)
    c = ssub.add_parser(
        "cost",
        help="cost of transport over foot radius x step length (or speed)",
        description="Periodic level-ground gaits over foot radius x step length (or speed) "
        "for each actuation model; writes cost_study.nc and figures, including the paper's "
        "impact-only eta against the actuator work per metre of the real gaits. With --model "
        "(a walker file with a foot radius parameter R, e.g. compass, kneed, torso): push-off "
        "plus the posture law the file declares.",
        conflict_handler="resolve",
    )
    _add_walker_options(c)  # its --radius is replaced by the range below
    _add_model_options(c)
    c.add_argument("--backend", choices=("compiled", "scipy"), default=None,
                   help="step simulator with --model: compiled (default; generated from the "
                   "walker file) or the scipy reference; the compass gait without --model "
                   "runs on the scipy reference")
    c.add_argument("--radius", dest="radii", type=parse_range, default=(0.0, 0.9, 4),
                   help="foot radii START:STOP:COUNT (m), default 0:0.9:4")
    tgt = c.add_mutually_exclusive_group()
    tgt.add_argument("--step-length", dest="lengths", type=parse_range, default=None,
                     help="step lengths START:STOP:COUNT (m), default 0.3:0.6:4")
    tgt.add_argument("--speed", dest="speeds", type=parse_range, default=None,
                     help="speeds START:STOP:COUNT (m/s)")
    c.add_argument("--actuation", action="append", choices=_ACTUATIONS, default=None,
                   help="actuation model, repeatable (default pushoff)")
    _add_actuation_options(c)
    c.add_argument("--out", default="cost_study", help="output directory")
    _add_store_option(c)
    c.set_defaults(func=_run_study, radius=0.0)


def _grid(r: tuple[float, float, int | None], default_count: int) -> list[float]:
    import numpy as np

    start, stop, count = r
    return [float(v) for v in np.linspace(start, stop, count or default_count)]


def _cost_figures(ds: Any, out: Any) -> list[Any]:
    """The study's figures; without the paper's impact-only eta (described walkers) the cost
    figures only."""
    from heelstrike.plots.powered import cost_figure, write_cost_figures

    if "eta_paper" in ds:
        return write_cost_figures(ds, out)
    paths = []
    for var in ("cost_of_transport", "eta", "actuator_work"):
        if bool(ds[var].notnull().any()):
            path = out / f"{var}.png"
            cost_figure(ds, var).savefig(path, dpi=120)
            paths.append(path)
    return paths


def _run_study(args: argparse.Namespace) -> int:
    from pathlib import Path

    from heelstrike.analysis.cost_study import cost_study, save_study

    model = None
    if args.model is None:
        if args.param:
            raise CliError("--param sets a described walker's parameter: give --model too")
        if args.backend == "compiled":
            raise CliError("--backend compiled is not supported by the compass cost study "
                           "without --model (it runs on the scipy reference); for the compiled "
                           "backend use --model compass")
        walker = _walker_from_args(args)  # validates the other walker parameters
        leg_length = float(args.leg_length)
    else:
        acts_given = [a for a in args.actuation or () if a != "pushoff"]
        if acts_given:
            raise CliError(f"--actuation {acts_given[0]} is not supported with --model (only "
                           "pushoff, with the posture law the walker file declares)")
        given = [f"--{k.replace('_', '-')}" for k in ("gain", "kp", "kd", "max_torque")
                 if getattr(args, k) is not None]
        if given:
            raise CliError(f"{', '.join(given)} set(s) the compass hip laws, not used with "
                           "--model (the posture law's gains are declared in the walker file)")
        if any(item.partition("=")[0].strip() == "R" for item in args.param):
            raise CliError("--param R=... is swept by --radius START:STOP:COUNT: give it there")
        model = _model_from_args(args)
        if "R" not in model.params:
            raise CliError(f"model {model.description.name!r} has no foot radius parameter 'R' "
                           f"(its parameters: {', '.join(sorted(model.params))})")
        walker = None
        leg_length = float(model.scale.leg_length)
    radii = _grid(args.radii, 4)
    if min(radii) < 0 or max(radii) > leg_length:
        raise CliError(f"--radius must lie in [0, {leg_length:g}] m")
    if args.speeds is not None:
        target, values = "speed", _grid(args.speeds, 4)
    else:
        target, values = "step_length", _grid(args.lengths or (0.3, 0.6, 4), 4)
    if min(values) <= 0:
        raise CliError(f"--{target.replace('_', '-')} values must be > 0")
    acts = args.actuation or ["pushoff"]
    options = _actuation_options(args)
    _writable_dir(args.out)
    try:
        ds = _run_with_store(args.store, lambda: cost_study(
            radii, values, target=target, actuations=acts, walker=walker, model=model,
            backend=args.backend or "compiled", actuation_options=options, progress=True,
            store=args.store))
    except ValueError as exc:  # e.g. a radius the walker file's constraints reject
        raise CliError(str(exc)) from exc
    out = Path(args.out)
    try:
        nc = save_study(ds, out / "cost_study.nc")
        paths = [nc, *_cost_figures(ds, out)]
    except OSError as exc:
        raise CliError(f"cannot write to {args.out!r}: {exc.strerror or exc}") from exc
    for path in paths:
        print(path)
    fresh = int((ds["branch"] == 1).sum())
    print(f"gaits: the cheapest found at each point, by continuation from neighbours or by "
          f"fresh searches from several seeds ({fresh} point(s) came from a fresh search; "
          f"up to {int(ds['gaits_found'].max())} distinct gaits met at one point)")
    found = int(ds["cost_of_transport"].notnull().sum())
    print(f"{found} of {ds['cost_of_transport'].size} gaits found", file=sys.stderr)
    return 0 if found else 1


_command(cli_robot.add_robot_command)  # issue 10: heelstrike robot list|info


def _version() -> str:
    """The installed distribution's version (:mod:`importlib.metadata`)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("heelstrike")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    """The ``heelstrike`` argument parser with every registered command."""
    parser = _Parser(
        prog="heelstrike",
        description="Impulsive dynamics and energetics of walking machines.",
    )
    parser.add_argument("--version", action="version", version=f"heelstrike {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in _COMMANDS:
        add(sub)
    return parser


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def _fail(message: str) -> int:
    """Print the one-line error (after the traceback when ``HEELSTRIKE_DEBUG=1``); status 2."""
    if os.environ.get("HEELSTRIKE_DEBUG") == "1":
        import traceback

        traceback.print_exc()
    print(f"heelstrike: error: {message}", file=sys.stderr)
    return 2


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``heelstrike`` command; returns the exit status.

    Every failure ends in one line ``heelstrike: error: ...`` on stderr and exit status 2;
    set ``HEELSTRIKE_DEBUG=1`` to see the traceback of unexpected errors.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        status = int(args.func(args))
    except CliError as exc:
        return _fail(_one_line(exc))
    except (ValueError, ArithmeticError) as exc:
        return _fail(_one_line(exc))
    except MemoryError as exc:
        detail = _one_line(exc) if str(exc) else "the computation needs more memory than is free"
        return _fail(f"out of memory: {detail}")
    except KeyboardInterrupt:
        print("heelstrike: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of stdout went away (e.g. `| head`): nothing to say
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 2
    except OSError as exc:
        where = f" {exc.filename!r}" if exc.filename else ""
        return _fail(f"{exc.strerror or _one_line(exc)}{where}")
    except MissingExtraError as exc:  # e.g. a sweep store without heelstrike[scale]
        return _fail(_one_line(exc))
    except Exception as exc:  # the last resort: one line, never a traceback
        hint = "" if os.environ.get("HEELSTRIKE_DEBUG") == "1" else \
            " (set HEELSTRIKE_DEBUG=1 for the traceback)"
        return _fail(f"unexpected {type(exc).__name__}: {_one_line(exc)}{hint}")
    return status


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
