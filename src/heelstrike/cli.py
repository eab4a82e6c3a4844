"""Command-line interface: ``heelstrike <command> ...``. It parses and calls, nothing more.

Conventions shared by every command:

- angles accept a ``deg`` or ``rad`` suffix (``20deg``, ``0.3rad``); bare numbers are radians;
- lengths are metres, masses kilograms, times seconds;
- ``--json`` prints exactly one JSON object on stdout;
- bad input exits with status 2 and a one-line ``heelstrike: error: ...`` message on stderr.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

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


def _add_walker_options(p: argparse.ArgumentParser) -> None:
    """Options for every parameter of the paper's compass gait (SI units)."""
    g = p.add_argument_group("walker parameters (paper defaults)")
    g.add_argument("--radius", type=float, default=0.0, help="foot radius R (m), 0 <= R <= l")
    g.add_argument("--hip-mass", type=float, default=10.0, help="hip mass mH (kg)")
    g.add_argument("--leg-mass", type=float, default=5.0, help="mass of each leg m (kg)")
    g.add_argument("--leg-length", type=float, default=1.0, help="leg length l (m)")
    g.add_argument(
        "--com-from-hip", type=float, default=0.5, help="hip to leg centre of mass b (m)"
    )
    g.add_argument(
        "--leg-inertia", type=float, default=0.0, help="leg inertia about its COM (kg m^2)"
    )
    g.add_argument("--gravity", type=float, default=9.81, help="gravity g (m/s^2)")


def _walker_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.models.compass import CompassGait

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
    try:
        return load_phased_walker(args.model, **params)
    except OSError as exc:
        raise CliError(f"cannot read model {args.model!r}: {exc.strerror or exc}") from exc


def _parse_floats(text: str, option: str, n: int | None = None) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise CliError(f"invalid {option} {text!r}: use comma-separated numbers") from None
    if n is not None and len(vals) != n:
        raise CliError(f"invalid {option} {text!r}: expected {n} comma-separated numbers")
    return vals


def _print_json(obj: Any) -> None:
    json.dump(obj, sys.stdout, allow_nan=False)
    sys.stdout.write("\n")


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
    from heelstrike.plots import reproduce_paper

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
                   help="with --model: full pre-impact configuration (m, rad) instead of --angle")
    p.add_argument("--velocity", default=None, metavar="QD1,...,QDN",
                   help="with --model and --state: pre-impact velocities (m/s, rad/s); default: "
                   "stance rate --q3dot, foot rolling, joints at rest")
    p.add_argument("--q3dot", type=float, default=1.0,
                   help="pre-impact stance-leg rate q3_dot (rad/s, default 1)")
    p.add_argument("--q4dot", type=float, default=0.0,
                   help="pre-impact inter-leg rate q4_dot (rad/s, default 0)")
    p.add_argument("--restitution", type=float, default=0.0,
                   help="restitution e of the constrained velocity, 0 <= e <= 1 (default 0)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_impact)


def _run_impact_model(args: argparse.Namespace) -> int:
    from heelstrike.analysis.model_gaits import model_heel_strike, symmetric_heel_strike_state

    walker = _model_from_args(args)
    n = walker.n_coordinates
    if args.state is not None:
        q = _parse_floats(args.state, "--state", n)
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
    s = model_heel_strike(walker, q, qd)
    d = s.to_dict()
    d["model"] = walker.description.name
    d["coordinates"] = list(walker.coordinate_names)
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

    if args.model is not None:
        return _run_impact_model(args)
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
        gait = find_model_gait(walker, slope=args.slope, guess=guess)
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


def _run_gait(args: argparse.Namespace) -> int:
    from heelstrike.analysis.limit_cycle import GaitNotFoundError, find_limit_cycle

    if args.model is not None:
        return _run_gait_model(args)
    walker = _walker_from_args(args)
    try:
        cycle = find_limit_cycle(
            walker, slope=args.slope, guess=_parse_guess(args.guess),
            progress=not args.json and sys.stderr.isatty(),
        )
    except GaitNotFoundError as exc:
        raise CliError(f"no gait found at slope {math.degrees(args.slope):g} deg: {exc}") from exc
    d = cycle.to_dict()
    if args.json:
        _print_json(d)
        return 0
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
        "an animation (.gif, or .mp4 where ffmpeg exists).",
    )
    _add_walker_options(p)
    p.add_argument("--slope", type=parse_angle, default=parse_angle("3deg"),
                   help="slope angle (default 3deg)")
    p.add_argument("--steps", type=_positive_int, default=6, help="number of steps (default 6)")
    p.add_argument("--guess", default=None,
                   help="start from this post-impact Q3,Q3DOT,Q4DOT instead of the limit cycle")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--out", default="walk.gif", help="output file, .gif or .mp4")
    p.set_defaults(func=_run_walk)


def _run_walk(args: argparse.Namespace) -> int:
    from heelstrike.analysis.limit_cycle import GaitNotFoundError, PoincareMap, find_limit_cycle
    from heelstrike.gait_plots import animate_walk


    walker = _walker_from_args(args)
    if not str(args.out).lower().endswith((".gif", ".mp4")):
        raise CliError(f"--out must end in .gif or .mp4, got {args.out!r}")
    z = _parse_guess(args.guess)
    if z is None:
        try:
            z = list(find_limit_cycle(walker, slope=args.slope).fixed_point)
        except GaitNotFoundError as exc:
            raise CliError(f"no gait found to start from: {exc}") from exc
    walk = PoincareMap(walker=walker, slope=args.slope, rtol=1e-9, atol=1e-9,
                       max_step=0.5 / args.fps).walk(z, args.steps)
    path = animate_walk(walker, walk, args.out, fps=args.fps)
    print(f"{walk.n_steps} steps, status: {walk.status.value} ({walk.message})")
    print(path)
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
    p.add_argument("--slope-range", default="0.5deg:6deg",
                   type=lambda t: parse_range(t, parse_angle),
                   help="START:STOP[:COUNT] slopes, e.g. 0.5deg:6deg:56 (default count 45)")
    p.add_argument("--transient", type=_positive_int, default=50, help="steps discarded")
    p.add_argument("--record", type=_positive_int, default=16, help="steps recorded")
    p.add_argument("--out", default="bifurcation", help="output directory")
    p.set_defaults(func=_run_bifurcation)


def _run_bifurcation(args: argparse.Namespace) -> int:
    from pathlib import Path

    from heelstrike.gait_plots import write_bifurcation

    walker = _walker_from_args(args)
    start, stop, count = args.slope_range
    if not 0 < start < stop:
        raise CliError("--slope-range needs 0 < START < STOP")
    paths = write_bifurcation(
        walker, start, stop, count or 45, Path(args.out), transient=args.transient,
        record=args.record, progress=True,
    )
    for path in paths:
        print(path)
    return 0


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
        "value), computed with the compiled ensemble. Writes basin.png and basin.nc.",
    )
    _add_walker_options(p)
    p.add_argument("--slope", type=parse_angle, default=parse_angle("3deg"),
                   help="slope angle (default 3deg)")
    p.add_argument("--grid", type=_parse_grid, default=(400, 400),
                   help="N_Q3xN_Q3DOT grid points (default 400x400)")
    p.add_argument("--q3-range", type=lambda t: parse_range(t, parse_angle),
                   default=(-0.5, -0.05, None), help="Q3MIN:Q3MAX post-impact stance angles "
                   "(default -0.5:-0.05 rad); write --q3-range=-0.5:-0.05")
    p.add_argument("--q3dot-range", type=parse_range, default=(0.3, 2.3, None),
                   help="MIN:MAX post-impact stance velocities in rad/s (default 0.3:2.3)")
    p.add_argument("--steps", type=_positive_int, default=60,
                   help="largest number of steps per initial state (default 60)")
    p.add_argument("--tol", type=float, default=1e-3,
                   help="convergence radius around the fixed point (default 1e-3)")
    p.add_argument("--out", default="basin", help="output directory (default ./basin)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_basin)


def _run_basin(args: argparse.Namespace) -> int:
    from heelstrike.analysis.basin import basin_of_attraction
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.gait_plots import write_basin

    walker = _walker_from_args(args)
    a0, a1, _ = args.q3_range
    b0, b1, _ = args.q3dot_range
    if not (a0 < a1 and b0 < b1):
        raise CliError("--q3-range and --q3dot-range need MIN < MAX")
    if not args.tol > 0:
        raise CliError("--tol must be > 0")
    try:
        basin = basin_of_attraction(
            walker, args.slope, grid=args.grid, ranges=((a0, a1), (b0, b1)), steps=args.steps,
            tol=args.tol, progress=not args.json and sys.stderr.isatty(),
        )
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
    p.add_argument("--radius", type=parse_range, default=(0.0, 0.6, 7),
                   help="START:STOP[:COUNT] foot radii in m (default 0:0.6:7)")
    p.add_argument("--slope", type=lambda t: parse_range(t, parse_angle),
                   default=(math.radians(1.0), math.radians(6.0), 21),
                   help="START:STOP[:COUNT] slopes, e.g. 1deg:6deg:21 (default)")
    p.add_argument("--out", default="gait_map", help="output directory (default ./gait_map)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_map)


def _run_map(args: argparse.Namespace) -> int:
    import numpy as np

    from heelstrike.analysis.gait_map import gait_map
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.gait_plots import write_gait_map

    r0, r1, nr = args.radius
    s0, s1, ns = args.slope
    if not 0 <= r0 <= r1 <= args.leg_length:
        raise CliError("--radius needs 0 <= START <= STOP <= leg length")
    if not 0 < s0 < s1:
        raise CliError("--slope needs 0 < START < STOP")
    radii = np.linspace(r0, r1, nr or 7)
    slopes = np.linspace(s0, s1, ns or 21)
    base = _walker_from_args(argparse.Namespace(**{**vars(args), "radius": float(radii[0])}))
    try:
        gmap = gait_map(base, radii, slopes, progress=not args.json and sys.stderr.isatty())
    except GaitNotFoundError as exc:
        raise CliError(f"no starting gait found: {exc}") from exc
    png, nc = write_gait_map(gmap, args.out)
    ds = gmap.dataset
    pd = [None if not np.isfinite(v) else float(v) for v in gmap.period_doubling_slope]
    stable = ds["stable"].values
    if args.json:
        _print_json({
            "foot_radius": radii.tolist(),
            "slope": slopes.tolist(),
            "stable_fraction": float(np.mean(stable)),
            "period_doubling_slope": pd,
            "gait_found_fraction": float(np.mean(np.isfinite(ds["spectral_radius"].values))),
            "figure": str(png),
            "data": str(nc),
        })
        return 0
    print(f"stable passive gaits: {int(stable.sum())} of {stable.size} (R, slope) points")
    for R, v, row in zip(radii, pd, stable, strict=True):
        pd_text = "none in range" if v is None else f"{math.degrees(v):.3f} deg"
        print(f"  R = {R:6.3f} m: stable at {int(row.sum()):3d}/{row.size} slopes, "
              f"period doubling {pd_text}")
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

    from heelstrike.analysis.model_gaits import impact_map
    from heelstrike.plots_models import write_impact_map

    if args.model is None:
        raise CliError("--model is required (a .toml file or compass, kneed, torso)")
    walker = _model_from_args(args)
    axes = [(n, np.linspace(a, b, c)) for n, a, b, c in (args.x, args.y)]
    m = impact_map(walker, axes[0], axes[1], angle=args.angle, stance_rate=args.q3dot)
    try:
        paths = write_impact_map(m, args.out)
    except OSError as exc:
        raise CliError(f"cannot write to {args.out!r}: {exc.strerror or exc}") from exc
    for path in paths:
        print(path)
    return 0


# -- powered walking on level ground (issue 4) -------------------------------------------------
_ACTUATIONS = ("pushoff", "hip-energy", "hip-pd")


def _add_actuation_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("actuation")
    g.add_argument("--gain", type=float, default=10.0,
                   help="energy-tracking gain k of hip-energy (default 10)")
    g.add_argument("--kp", type=float, default=5.0, help="hip-pd stiffness (N m/rad)")
    g.add_argument("--kd", type=float, default=1.0, help="hip-pd damping (N m s/rad)")
    g.add_argument("--max-torque", type=float, default=20.0,
                   help="hip torque limit (N m, default 20)")


def _family_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.analysis.powered import actuation_family

    if not args.max_torque > 0:
        raise CliError("--max-torque must be > 0 (N m)")
    return actuation_family(args.actuation, gain=args.gain, kp=args.kp, kd=args.kd,
                            max_torque=args.max_torque)


@_command
def _add_powered(sub: Any) -> None:
    p = sub.add_parser(
        "powered",
        help="periodic powered gait on level ground and its energy books",
        description="Find the level-ground periodic gait of a powered compass gait with a "
        "target speed or step length: push-off impulse (pushoff), energy-tracking hip torque "
        "(hip-energy) or swing-leg PD (hip-pd). Prints the energy books per step: on a "
        "periodic gait the actuator work equals the collision loss T_c (paper eqs. 14-15).",
    )
    _add_walker_options(p)
    tgt = p.add_mutually_exclusive_group()
    tgt.add_argument("--speed", type=float, default=None, help="target mean speed (m/s)")
    tgt.add_argument("--step-length", type=float, default=None, help="target step length (m)")
    p.add_argument("--actuation", choices=_ACTUATIONS, default="pushoff",
                   help="actuation model (default pushoff)")
    _add_actuation_options(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_powered)


def _run_powered(args: argparse.Namespace) -> int:
    from heelstrike.analysis.powered import PoweredGaitNotFoundError, find_powered_gait

    walker = _walker_from_args(args)
    if args.speed is None and args.step_length is None:
        args.speed = 0.5
    target, value = (
        ("speed", args.speed) if args.speed is not None else ("step_length", args.step_length)
    )
    if not (math.isfinite(value) and value > 0):
        raise CliError(f"--{target.replace('_', '-')} must be > 0, got {value:g}")
    family = _family_from_args(args)
    try:
        gait = find_powered_gait(walker, actuation=family, **{target: value})
    except PoweredGaitNotFoundError as exc:
        raise CliError(
            f"no {args.actuation} gait found with {target.replace('_', ' ')} {value:g} "
            f"at R = {args.radius:g} m: {exc}"
        ) from exc
    d = gait.to_dict()
    if args.json:
        _print_json(d)
        return 0
    fp = ", ".join(f"{k} = {v:.6f}" for k, v in d["fixed_point"].items())
    mult = ", ".join(f"{abs(m):.4f}" for m in gait.multipliers)
    print(f"powered gait ({args.actuation}), R = {args.radius:g} m, level ground")
    print(f"  {gait.parameter_name:15s} {gait.parameter:10.5f} {gait.parameter_unit}")
    print(f"  fixed point (just after impact): {fp}")
    print(f"  period          {gait.period:10.5f} s")
    print(f"  step length     {gait.step_length:10.5f} m")
    print(f"  speed           {gait.speed:10.5f} m/s")
    print(f"  |multipliers|   {mult}")
    print(f"  stable          {'yes' if gait.stable else 'no'}")
    print("  energy books per step")
    print(f"    actuator work   {gait.actuator_work:12.6f} J "
          f"(push-off {gait.push_off_work:.6f} J, hip {gait.hip_work:.6f} J)")
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
        "impact-only eta against the actuator work per metre of the real gaits.",
        conflict_handler="resolve",
    )
    _add_walker_options(c)  # its --radius is replaced by the range below
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
    c.set_defaults(func=_run_study, radius=0.0)


def _grid(r: tuple[float, float, int | None], default_count: int) -> list[float]:
    import numpy as np

    start, stop, count = r
    return [float(v) for v in np.linspace(start, stop, count or default_count)]


def _run_study(args: argparse.Namespace) -> int:
    from pathlib import Path

    from heelstrike.analysis.cost_study import cost_study, save_study
    from heelstrike.plots_powered import write_cost_figures

    walker = _walker_from_args(args)  # validates the other walker parameters (radius unused)
    radii = _grid(args.radii, 4)
    if min(radii) < 0 or max(radii) > args.leg_length:
        raise CliError(f"--radius must lie in [0, {args.leg_length:g}] m")
    if args.speeds is not None:
        target, values = "speed", _grid(args.speeds, 4)
    else:
        target, values = "step_length", _grid(args.lengths or (0.3, 0.6, 4), 4)
    if min(values) <= 0:
        raise CliError(f"--{target.replace('_', '-')} values must be > 0")
    acts = args.actuation or ["pushoff"]
    if not args.max_torque > 0:
        raise CliError("--max-torque must be > 0 (N m)")
    options = {"gain": args.gain, "kp": args.kp, "kd": args.kd, "max_torque": args.max_torque}
    ds = cost_study(radii, values, target=target, actuations=acts, walker=walker,
                    actuation_options=options, progress=True)
    out = Path(args.out)
    try:
        nc = save_study(ds, out / "cost_study.nc")
        paths = [nc, *write_cost_figures(ds, out)]
    except OSError as exc:
        raise CliError(f"cannot write to {args.out!r}: {exc.strerror or exc}") from exc
    for path in paths:
        print(path)
    found = int(ds["cost_of_transport"].notnull().sum())
    print(f"{found} of {ds['cost_of_transport'].size} gaits found", file=sys.stderr)
    return 0 if found else 1


def build_parser() -> argparse.ArgumentParser:
    """The ``heelstrike`` argument parser with every registered command."""
    parser = _Parser(
        prog="heelstrike",
        description="Impulsive dynamics and energetics of walking machines.",
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in _COMMANDS:
        add(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``heelstrike`` command; returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        status = int(args.func(args))
    except CliError as exc:
        print(f"heelstrike: error: {exc}", file=sys.stderr)
        return 2
    except (ValueError, ArithmeticError) as exc:
        print(f"heelstrike: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("heelstrike: interrupted", file=sys.stderr)
        return 130
    return status


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
