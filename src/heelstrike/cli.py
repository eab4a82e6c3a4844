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
