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
    p.add_argument("--slope", type=parse_angle, default=parse_angle("3deg"),
                   help="slope angle, e.g. 3deg (default 3deg)")
    p.add_argument("--guess", default=None,
                   help="post-impact Q3,Q3DOT,Q4DOT to start Newton from (rad, rad/s); "
                   "write --guess=-0.27,1.09,-0.72 when Q3 is negative")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_gait)


def _run_gait(args: argparse.Namespace) -> int:
    from heelstrike.analysis.limit_cycle import GaitNotFoundError, find_limit_cycle

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
