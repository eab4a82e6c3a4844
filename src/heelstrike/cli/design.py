"""Command line for ``heelstrike design``: gradient-based design of a walker's parameters
(:func:`heelstrike.analysis.design.design`). Parses, calls and renders, nothing more."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from heelstrike.cli._common import (
    CliError,
    add_model_options,
    model_from_args,
    parse_slope,
    positive_int,
    writable_dir,
)
from heelstrike.cli._render import print_json, print_paths

__all__ = ["add_design"]

#: :data:`heelstrike.analysis.design.DESIGN_TOL`, repeated here so that building the parser
#: imports no analysis code (a test checks they agree).
DESIGN_TOL = 1e-7


def _vary(text: str) -> tuple[str, float, float]:
    """Parse ``NAME=LO:HI`` (SI units; ``slope`` in rad or with a ``deg`` suffix)."""
    from heelstrike.cli._common import parse_angle

    name, sep, rng = str(text).partition("=")
    lo, sep2, hi = rng.partition(":")
    if not sep or not sep2 or not name.strip():
        raise argparse.ArgumentTypeError(f"invalid --vary {text!r}: use NAME=LO:HI, e.g. R=0.1:0.5")
    convert = parse_angle if name.strip() == "slope" else float
    try:
        return name.strip(), convert(lo), convert(hi)
    except (ValueError, argparse.ArgumentTypeError) as exc:
        raise argparse.ArgumentTypeError(f"invalid --vary {text!r}: {exc}") from None


def _pair(text: str) -> tuple[float, float]:
    lo, sep, hi = str(text).partition(":")
    try:
        if not sep:
            raise ValueError("use LO:HI")
        return float(lo), float(hi)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"invalid range {text!r}: {exc}") from None


def add_design(sub: Any) -> None:
    """Register ``heelstrike design``."""
    p = sub.add_parser(
        "design", help="optimise walker parameters (a foot profile, the slope...) for a cost "
        "of the passive gait, with implicit-function-theorem gradients",
        description="Minimise a cost of a described walker's passive gait (a gait field or an "
        "expression of them) over named parameters with bounds, subject to a spectral radius "
        "bound, speed / step-length ranges and the trailing foot lifting (SLSQP with the "
        "implicit-function-theorem gradients of the gait; the gait is followed by "
        "continuation). Progress on stderr, a result table on stdout (or --json), figures and "
        "a resumable record in --out.")
    add_model_options(p, required=True)
    p.add_argument("--slope", type=parse_slope, required=True,
                   help="ground slope, e.g. 3deg (the start value if --vary slope=...)")
    p.add_argument("--vary", type=_vary, action="append", required=True, metavar="NAME=LO:HI",
                   help="a parameter to vary and its bounds (SI units), repeatable")
    p.add_argument("--cost", default="collision_loss",
                   help="a gait field (step_length, period, speed, collision_loss, eta, "
                   "cost_of_transport, spectral_radius, lift_velocity) or an expression of them "
                   "(default collision_loss)")
    p.add_argument("--max-spectral-radius", type=float, default=None,
                   help="constraint: largest Floquet multiplier modulus at most this")
    p.add_argument("--speed", type=_pair, default=None, metavar="LO:HI",
                   help="constraint: speed range (m/s)")
    p.add_argument("--step-length", type=_pair, default=None, metavar="LO:HI",
                   help="constraint: step-length range (m)")
    p.add_argument("--trailing-foot-lifts", action="store_true",
                   help="constraint: the trailing foot's normal velocity just after the heel "
                   "strike is not negative (lift_velocity >= 0)")
    p.add_argument("--max-iter", type=positive_int, default=50, help="SLSQP iterations")
    p.add_argument("--tol", type=float, default=DESIGN_TOL,
                   help=f"SLSQP's ftol on the cost divided by its start value "
                   f"(default {DESIGN_TOL:g})")
    p.add_argument("--json", action="store_true", help="print the result as one JSON object")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="write design_record.jsonl (resumable: a rerun replays it), "
                   "design_cost.png and design_foot.png here")
    p.set_defaults(func=_run_design)


def _run_design(args: argparse.Namespace) -> int:
    from heelstrike._progress import progress_bar
    from heelstrike.analysis.design import DesignError, design

    out = None if args.out is None else writable_dir(args.out)
    walker = model_from_args(args)
    vary: dict[str, tuple[float, float]] = {}
    for name, lo, hi in args.vary:
        if name in vary:
            raise CliError(f"--vary {name} is given twice: give it once")
        vary[name] = (lo, hi)
    record = None if out is None else out / "design_record.jsonl"
    bar = progress_bar(desc="heelstrike: design", total=args.max_iter + 1, unit="iterate")

    def progress(it: Any) -> None:
        bar.set_postfix_str(f"cost {it.cost:.6g}")
        bar.update(1)

    try:
        with bar:
            res = design(walker, vary=vary, cost=args.cost, slope=args.slope,
                         max_spectral_radius=args.max_spectral_radius, speed=args.speed,
                         step_length=args.step_length, max_iter=args.max_iter, tol=args.tol,
                         trailing_foot_lifts=args.trailing_foot_lifts,
                         record=record,
                         progress=progress)
    except DesignError as exc:
        raise CliError(str(exc)) from None
    paths: list[Path] = []
    if out is not None:
        from heelstrike.io import save_figure
        from heelstrike.plots.design import cost_history_figure, foot_figure

        paths.append(save_figure(cost_history_figure(res), out / "design_cost.png"))
        if res.foot_start is not None:
            paths.append(save_figure(foot_figure(res), out / "design_foot.png"))
        paths.append(record)  # type: ignore[arg-type]
    if args.json:
        d = res.to_dict()
        d["files"] = [str(x) for x in paths]
        print_json(d, units=_units(res))
        return 0
    print(f"design of {walker.description.name!r}: minimise {res.cost_name}")
    print(f"status: {res.status.value} ({res.status.message}); {res.message}")
    print(f"{'parameter':<12}{'start':>14}{'final':>14}{'lower':>12}{'upper':>12}")
    for j, n in enumerate(res.parameters):
        print(f"{n:<12}{res.start.values[j]:>14.8g}{res.final.values[j]:>14.8g}"
              f"{res.lower[j]:>12.6g}{res.upper[j]:>12.6g}")
    print(f"{'field':<20}{'start':>14}{'final':>14}")
    for f, v in res.final.fields.items():
        print(f"{f:<20}{res.start.fields[f]:>14.8g}{v:>14.8g}")
    print(f"cost: {res.start.cost:.10g} -> {res.final.cost:.10g} in {len(res.history) - 1} "
          f"iterations, {res.evaluations} gaits ({res.replayed} replayed from the record)")
    if res.active_bounds:
        print("on a bound: " + ", ".join(res.active_bounds))
    print_paths(paths)
    sys.stdout.flush()
    return 0


def _units(res: Any) -> dict[str, Any]:
    from heelstrike.analysis.design_gradients import GRADIENT_UNITS

    params = {n: ("rad" if n == "slope" else "SI") for n in res.parameters}
    return {"fields": GRADIENT_UNITS, "parameters": params, "cost": "units of the cost field"}
