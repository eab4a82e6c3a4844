"""``heelstrike gait``, ``walk``, ``bifurcation``, ``basin`` and ``map`` (issues 3 and 6)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from typing import Any

from heelstrike.analysis._defaults import (
    BASIN_STEPS,
    BASIN_TOLERANCE,
    BIFURCATION_RECORD,
    BIFURCATION_TRANSIENT,
)
from heelstrike.analysis._memory import (
    GAIT_SEARCH_BYTES,
    GAIT_SEARCH_STEPS,
    WALKER_STEP_BYTES,
    WALKER_STEP_SECONDS,
    require_budget,
)
from heelstrike.cli._common import (
    CliError,
    DeprecatedAlias,
    add_backend_option,
    add_model_options,
    add_store_option,
    add_walker_options,
    model_from_args,
    nonnegative_int,
    parse_angle,
    parse_floats,
    parse_grid,
    parse_guess,
    parse_range,
    parse_slope,
    parse_sweep,
    positive_int,
    run_with_store,
    walker_from_args,
    writable_dir,
)
from heelstrike.cli._render import (
    energy_text,
    fixed_point_text,
    multipliers_text,
    print_impact_angle_line,
    print_json,
    print_paths,
    print_stability_lines,
    print_step_lines,
)

__all__ = ['add_basin', 'add_bifurcation', 'add_gait', 'add_map', 'add_walk']


def _no_gait(slope: float, exc: Exception) -> CliError:
    """The error of a command that found no gait at ``slope`` (rad)."""
    return CliError(f"no gait found at slope {math.degrees(slope):g} deg: {exc}")


def add_gait(sub: Any) -> None:
    p = sub.add_parser(
        "gait",
        help="find a passive limit cycle on a slope",
        description="Find the passive period-one gait of the circular-feet compass gait on a "
        "slope, its stability (Floquet multipliers) and energetics.",
    )
    add_walker_options(p)
    add_model_options(p)
    p.add_argument("--slope", type=parse_slope, default=parse_angle("3deg"),
                   help="slope angle, e.g. 3deg (default 3deg)")
    p.add_argument("--guess", default=None,
                   help="post-impact Q3,Q3DOT,Q4DOT to start Newton from (rad, rad/s); "
                   "write --guess=-0.27,1.09,-0.72 when Q3 is negative (with --model: the "
                   "walker's section coordinates)")
    add_backend_option(p, "step simulator: compiled numba kernels (default; generated from the "
                       "walker file with --model, a walker whose legs differ alternating its "
                       "two parameter sets) or the scipy reference")
    p.add_argument("--sensitivity", default=None, metavar="NAMES",
                   help="comma-separated walker parameters (the walker file's names: R, b, "
                   "mH, m, l, I, g): print the derivatives of the fixed point, period, step "
                   "length, speed, T_c, eta and |multipliers| in each (implicit function "
                   "theorem with the exact step Jacobian, scipy reference)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_gait)


def _sensitivity_names(text: str, walker: Any) -> list[tuple[str, str, str]]:
    """``(name as given, walker parameter, unit)`` of each name of ``--sensitivity``."""
    from heelstrike.models.compass import DESCRIBED_PARAMETERS
    from heelstrike.models.description import parameter_units

    described = walker.as_described()
    units = parameter_units(described.description) if described is not None else {}
    field = {v: k for k, v in DESCRIBED_PARAMETERS.items()}
    out = []
    for raw in text.split(","):
        name = raw.strip()
        if name not in field:
            raise CliError(f"--sensitivity: {name!r} is not a walker parameter (one of "
                           f"{', '.join(field)})")
        out.append((name, field[name], units.get(name, "1")))
    return out


def _sensitivity(args: argparse.Namespace, walker: Any, cycle: Any) -> dict[str, Any]:
    """The ``sensitivity`` object of ``gait --sensitivity``: derivatives per parameter, with
    their units."""
    from heelstrike.analysis.sensitivity import GAIT_QUANTITY_UNITS, gait_sensitivity
    from heelstrike.dynamics.variational import ExactJacobianUnavailable
    from heelstrike.models.base import section_unit

    names = _sensitivity_names(args.sensitivity, walker)
    try:
        sens = gait_sensitivity(walker, cycle.fixed_point, [f for _, f, _ in names],
                                slope=args.slope)
    except (ExactJacobianUnavailable, ValueError) as exc:
        raise CliError(f"--sensitivity: {exc}") from exc
    out: dict[str, Any] = {"parameters": {n: u for n, _, u in names}, "derivatives": {}}
    units: dict[str, Any] = {}
    for k, (n, _, u) in enumerate(names):
        row: dict[str, Any] = {z: float(sens.fixed_point[i, k])
                               for i, z in enumerate(sens.section_names)}
        row.update({q: float(v[k]) for q, v in sens.quantities.items()})
        row["multipliers"] = [float(v) for v in sens.modulus_derivatives[:, k]]  # d|m_i|/dp
        out["derivatives"][n] = row
        units[n] = {**{z: _per(section_unit(z), u) for z in sens.section_names},
                    **{q: _per(qu, u) for q, qu in GAIT_QUANTITY_UNITS.items()},
                    "multipliers": _per("1", u)}
    out["units"] = {"parameters": "unit of each parameter", "derivatives": units}
    return out


def _per(unit: str, per: str) -> str:
    """``unit`` per ``per``: ``"rad/m"``, ``"(rad/s)/m"``."""
    top = f"({unit})" if "/" in unit or " " in unit else unit
    return f"{top}/({per})" if " " in per or "/" in per else f"{top}/{per}"


def _print_sensitivity(sens: dict[str, Any]) -> None:
    units = sens["units"]["derivatives"]
    print("  sensitivities (implicit function theorem, exact step Jacobian):")
    for n, row in sens["derivatives"].items():
        print(f"    d/d{n} ({sens['parameters'][n]}):")
        for key, value in row.items():
            if key == "multipliers":
                text = ", ".join(f"{v:.6g}" for v in value)
                print(f"      {'|multipliers|':<15} {text} {units[n][key]}")
            else:
                print(f"      {key:<15} {value: .6g} {units[n][key]}")


def _run_gait_model(args: argparse.Namespace) -> int:
    from heelstrike.analysis.gaits import GaitNote, find_gaits
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.analysis.model_gaits import REFERENCE_SLOPE

    walker = model_from_args(args)
    backend = args.backend or ("compiled" if walker.supports("compiled") else "scipy")
    guess = None
    if args.guess is not None:
        guess = parse_floats(args.guess, "--guess", len(walker.section_names))
    try:
        # every start on the compiled backend, as the compass search (QA sweep 9: --model
        # compass listed 1 of its 2 gaits); the scipy reference's steps cost ~1000x more
        gaits = find_gaits(walker, args.slope, guess=guess, backend=backend,
                           every_start=backend == "compiled")
    except GaitNotFoundError as exc:
        raise _no_gait(args.slope, exc) from exc
    gait = gaits[0]
    d = gait.to_dict()
    d["model"] = walker.description.name
    d["hanging_links"] = list(gait.hanging_links)
    locks = gait.locks
    d["lock_torque_range"] = {} if locks is None else {
        k: list(v) for k, v in locks.ranges.items()}
    # each gait's collision loss is its step's total (knee strikes included), as in d
    d["gaits"] = [_gait_summary(g) | {"hanging_links": list(g.hanging_links)} for g in gaits]
    if GaitNote.NO_STABLE_GAIT in gait.notes:
        # QA sweep 10: this said "where it has a stable one" of the torso walker, which has none
        followed = ("" if GaitNote.REFERENCE_FOLLOWED not in gait.notes else
                    f", nor by following the walker file's own parameters' stable gait at "
                    f"{math.degrees(REFERENCE_SLOPE):g} deg, if it has one, to these "
                    "parameters and slope")
        print(f"heelstrike: note: no stable period-one gait found (not by the automatic "
              f"search{followed}); the least unstable gait found is shown", file=sys.stderr)
    for name, (lo, hi) in ({} if locks is None else locks.two_sided).items():
        # a one-sided knee stop could not hold it
        print(f"heelstrike: note: the lock of '{name}' holds it with torques of both signs over "
              f"the step ({lo:+.4g} to {hi:+.4g} N m): the walker file's locks are two-sided "
              "latches; a knee stop that can only push could not hold it, and the knee would "
              "buckle where the lock pulls", file=sys.stderr)
    if args.json:
        print_json(d)
        return 0
    c = gait
    _print_gait_list(list(gaits))
    print(f"passive gait of '{d['model']}', slope = {math.degrees(args.slope):g} deg")
    print(f"  fixed point (just after heel strike): {fixed_point_text(d['fixed_point'])}")
    if GaitNote.HANGING_LINKS in gait.notes:
        print(f"  note: {hanging_text(gait.hanging_links)} in this gait: a gait of the hanging "
              "link, not of the upright one")
    per = "step" if len(gait.steps) <= 1 else "stride"
    if per == "stride":
        print(f"  the period is a stride of {len(gait.steps)} steps (the legs differ): period, "
              "step length and speed are the stride's, the impact angle its first step's")
    print_step_lines(c)
    print_impact_angle_line(c)
    print_stability_lines(c)
    for imp in d["impacts"]:
        at = f" (step {imp['step']})" if per == "stride" else ""
        print(f"  {imp['kind']:<15} T_c = {imp['T_c']:.6f} J{at}")
    if per == "stride":
        for b in gait.steps:
            print(f"  step {b.step}: collision loss {energy_text(b.collision_loss)} J, energy "
                  f"released {energy_text(b.potential_energy_released)} J, kinetic energy "
                  f"gained {energy_text(b.kinetic_energy_gained)} J")
    print(f"  collision loss  {energy_text(gait.collision_loss)} J/{per} (sum of T_c)")
    print(f"  energy released {energy_text(gait.potential_energy_released)} J/{per} (gravity)")
    print(f"  eta             {energy_text(gait.eta)} J/m")
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
        "leg_crossings": c.leg_crossings,
    }


#: What a report of gaits with an upright link says of the others (QA sweep 13: the torso
#: walker's map followed its unstable upright gaits where stable ones with the torso hanging
#: exist, and said nothing).
OTHER_POSTURE = ("gaits with it hanging may exist too, and be stable where these are not "
                 "('heelstrike gait --model ...' lists the gaits at one slope)")


def upright_text(links: Sequence[str]) -> str:
    """``'torso' stands above its joint`` for links described upright that do."""
    names = ", ".join(f"'{n}'" for n in links)
    one = len(links) == 1
    return f"{names} {'stands' if one else 'stand'} above {'its' if one else 'their'} joint"


def hanging_text(links: Sequence[str]) -> str:
    """``'torso' hangs (its centre of mass below its joint)`` for links described upright
    that hang (:func:`~heelstrike.analysis.model_gaits.hanging_links`)."""
    names = ", ".join(f"'{n}'" for n in links)
    one = len(links) == 1
    return (f"{names} {'hangs' if one else 'hang'} ({'its centre' if one else 'their centres'} "
            f"of mass below {'its' if one else 'their'} joint)")


def _first_gait_text(gaits: Sequence[Any]) -> str:
    """What the first of ``gaits`` is in the one order of gaits (cheapest stable first,
    :func:`~heelstrike.analysis._gait_order.gait_order`)."""
    first = gaits[0]
    if any(g.actuator_work != 0.0 for g in gaits):  # a torque law: the gaits cost work
        return ("the stable one needing the least actuator work" if first.stable else
                "none is stable: the one needing the least actuator work")
    return "the most attracting stable one" if first.stable else "the least unstable"


def _print_gait_list(gaits: Sequence[Any]) -> None:
    """With several gaits found, one line each (the first is shown in detail), with the
    notes of each (:attr:`~heelstrike.analysis.gaits.Gait.notes`: multi-swing, hanging
    links)."""
    from heelstrike.analysis.gaits import GaitNote

    if len(gaits) < 2:
        return
    print(f"{len(gaits)} period-one gaits found (the first, "
          f"{_first_gait_text(gaits)}, "
          "is shown in detail):")
    for i, c in enumerate(gaits):
        swings = (f", multi-swing: the legs cross {c.leg_crossings} times, the swing foot "
                  "through the ground away from mid-stance"
                  if GaitNote.MULTI_SWING in c.notes else "")
        if GaitNote.HANGING_LINKS in c.notes:
            swings += f", {hanging_text(c.hanging_links)}"
        print(f"  [{i}] step length {c.step_length:.5f} m, period {c.period:.5f} s, "
              f"|multipliers| {multipliers_text(c.multipliers)}, "
              f"{'stable' if c.stable else 'unstable'}{swings}")


def _run_gait(args: argparse.Namespace) -> int:
    from heelstrike.analysis.gaits import find_gaits
    from heelstrike.analysis.limit_cycle import GaitNotFoundError

    if not args.slope > 0:
        raise CliError(
            f"no gait found at slope {math.degrees(args.slope):g} deg: a passive walker has an "
            "isolated gait only on a downhill slope > 0 (on level ground nothing replaces the "
            "energy its heel strikes lose; a walker whose strikes can lose nothing, such as "
            "wheel.toml, walks there a continuum of gaits, one per energy, none isolated: "
            "'heelstrike walk --model wheel --slope 0 --guess=-0.2,0.6,0' simulates one); "
            "e.g. --slope 3deg, or see 'heelstrike powered' "
            "for level ground"
        )
    if not args.slope < math.pi / 2:
        raise CliError(f"--slope must be below 90deg (a walkable incline), got "
                       f"{math.degrees(args.slope):g} deg")
    if args.model is not None:
        if args.sensitivity is not None:
            raise CliError("--sensitivity is available for the compass gait's options, not "
                           "with --model")
        return _run_gait_model(args)
    walker = walker_from_args(args)
    if args.sensitivity is not None:
        _sensitivity_names(args.sensitivity, walker)  # refuse a bad name before the search
    guess = parse_guess(args.guess)
    try:
        gaits = find_gaits(walker, args.slope, guess=guess, backend=args.backend or "compiled",
                           progress=guess is None)
    except GaitNotFoundError as exc:
        raise _no_gait(args.slope, exc) from exc
    cycle = gaits[0]
    d = cycle.to_dict()
    d["gaits"] = [_gait_summary(c) for c in gaits]
    sens = None if args.sensitivity is None else _sensitivity(args, walker, cycle)
    if sens is not None:
        d["sensitivity"] = sens
    if args.json:
        print_json(d)
        return 0
    _print_gait_list(gaits)
    print(f"passive gait, R = {args.radius:g} m, slope = {math.degrees(args.slope):g} deg")
    print(f"  fixed point (just after impact): {fixed_point_text(d['fixed_point'])}")
    print_step_lines(cycle)
    print_impact_angle_line(cycle)
    print_stability_lines(cycle)
    print(f"  collision loss  {energy_text(cycle.collision_loss)} J/step (T_c)")
    print(f"  energy released {energy_text(cycle.potential_energy_released)} J/step (gravity)")
    print(f"  eta             {energy_text(cycle.eta)} J/m")
    if sens is not None:
        _print_sensitivity(sens)
    return 0


def add_walk(sub: Any) -> None:
    p = sub.add_parser(
        "walk",
        help="simulate steps and animate the walker",
        description="Simulate the passive walker from its limit cycle (or --guess) and write "
        "an animation (.gif, or .mp4 where ffmpeg exists). With --out DIR, also write figures "
        "and their CSV data into DIR: a stick-figure strobe of one step, the phase portrait, "
        "joint angles and ground reaction over a step, the energy over the walk and the "
        "impacts (with --model: the walker's own links and joints, its locked joints held).",
    )
    add_walker_options(p)
    add_model_options(p)
    add_backend_option(p, "step simulator: compiled (default; the walker file's generated "
                       "kernel, for the compass gait that of compass.toml) or the scipy reference "
                       "(the default for McGeer's wheel, --radius equal to --leg-length, and for "
                       "a walker file declaring its heel strike, --model wheel)")
    p.add_argument("--slope", type=parse_slope, default=parse_angle("3deg"),
                   help="slope angle (default 3deg)")
    p.add_argument("--steps", type=positive_int, default=6, help="number of steps (default 6)")
    p.add_argument("--guess", default=None,
                   help="start from this post-impact Q3,Q3DOT,Q4DOT instead of the limit cycle "
                   "(with --model: the walker's section coordinates)")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--out", default="walk.gif",
                   help="output file (.gif or .mp4), or a directory for walk.gif plus the "
                   "figures (PNG) and their data (CSV) (default ./walk.gif)")
    p.set_defaults(func=_run_walk)


def _note_unstable_start(stable: bool, multipliers: Any) -> None:
    """Say on stderr that the walk starts on an unstable period-one gait.

    Started exactly on it, the walk follows it until round-off has grown (by the largest
    ``|multiplier|`` per step): the steps look periodic, yet this is not how the walker walks.
    """
    if not stable:
        rho = float(max(abs(complex(m)) for m in multipliers))
        print(f"heelstrike: note: the walk starts on the period-one gait found, which is "
              f"unstable (largest |multiplier| {rho:.4g}): it stays on it only until round-off "
              "grows; a walk from any nearby state leaves it (see 'heelstrike bifurcation' "
              "and 'heelstrike basin')", file=sys.stderr)


def _walk_model(args: argparse.Namespace, walker: Any, out: Any, to_dir: bool) -> int:
    """``walk --model``: the walk from the gait (or --guess), animation and figures."""
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.analysis.walk_tables import model_walk_frames
    from heelstrike.dynamics import simulate
    from heelstrike.outputs import write_model_walk_figures
    from heelstrike.plots.gait import animate_model_walk

    # the default: compiled where the walker runs on it (every walker file, a stride walker
    # included; a walker declaring its own step schedule runs on the scipy reference only)
    backend = args.backend or ("compiled" if walker.supports("compiled") else "scipy")
    if args.guess is not None:
        z = parse_floats(args.guess, "--guess", len(walker.section_names))
    else:
        try:
            cycle = find_model_gait(walker, slope=args.slope, backend=backend)
        except GaitNotFoundError as exc:
            raise CliError(f"no gait found to start from: {exc}") from exc
        z = list(cycle.fixed_point)
        _note_unstable_start(cycle.stable, cycle.multipliers)
    q, qd = walker.section_to_state(z)
    walk = simulate(walker, q, qd, backend=backend, slope=args.slope, steps=args.steps,
                    rtol=1e-9, atol=1e-9, max_step=0.5 / args.fps)
    path = animate_model_walk(
        model_walk_frames(walker, walk, args.fps), out / "walk.gif" if to_dir else out,
        slope=walk.slope, fps=args.fps, progress=True,
        title=f"{walker.description.name}, slope = {math.degrees(walk.slope):.2f} deg")
    print(f"{walk.n_steps} steps, status: {walk.status.value} ({walk.message})")
    print(path)
    if to_dir:
        print_paths(write_model_walk_figures(walker, walk, out))
    return 0 if walk.ok else 1


def _run_walk(args: argparse.Namespace) -> int:
    from pathlib import Path

    from heelstrike.analysis.limit_cycle import GaitNotFoundError, PoincareMap, find_limit_cycle
    from heelstrike.analysis.walk_tables import walk_frames
    from heelstrike.dynamics.backends import simulator
    from heelstrike.outputs import write_walk_figures
    from heelstrike.plots.gait import animate_walk

    walker = None if args.model is not None else walker_from_args(args)
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
    require_budget(f"a walk of {args.steps:,} steps", args.steps,
                   bytes_per_point=WALKER_STEP_BYTES,
                   seconds_per_point=WALKER_STEP_SECONDS[args.backend or "scipy"],
                   hint="give fewer --steps")
    model = None if args.model is None else model_from_args(args)  # before making --out
    writable_dir(out if to_dir else out.parent)
    if model is not None:
        return _walk_model(args, model, out, to_dir)
    assert walker is not None  # no --model: the compass shorthand
    # compiled by default; McGeer's wheel (no description to run dense samples on): scipy
    backend = args.backend or ("compiled" if walker.as_described() is not None else "scipy")
    z = parse_guess(args.guess)
    if z is None:
        try:
            cycle = find_limit_cycle(walker, slope=args.slope, progress=True, method=backend)
        except GaitNotFoundError as exc:
            raise CliError(f"no gait found to start from: {exc}") from exc
        z = list(cycle.fixed_point)
        _note_unstable_start(cycle.stable, cycle.multipliers)
    walk = PoincareMap(walker=walker, slope=args.slope, rtol=1e-9, atol=1e-9,
                       max_step=0.5 / args.fps,
                       simulator=simulator(walker, backend)).walk(z, args.steps)
    R = float(walker.foot_radius)
    title = f"compass gait, R = {R:g} m, slope = {math.degrees(walk.slope):.2f} deg"
    path = animate_walk(walk_frames(walker, walk, args.fps), out / "walk.gif" if to_dir else out,
                        foot_radius=R, slope=walk.slope, title=title, fps=args.fps,
                        progress=True)
    print(f"{walk.n_steps} steps, status: {walk.status.value} ({walk.message})")
    print(path)
    if to_dir:
        print_paths(write_walk_figures(walker, walk, out))
    return 0 if walk.ok else 1


def add_bifurcation(sub: Any) -> None:
    p = sub.add_parser(
        "bifurcation",
        help="period-doubling diagram over the slope",
        description="Steady-state impact angles and step periods against the slope (brute "
        "force, as Goswami et al. 1998) with the period-one branch and its period doublings.",
    )
    add_walker_options(p)
    add_model_options(p)
    add_backend_option(p, "step simulator of the walks and the period-one branch: compiled "
                       "(default) or the scipy reference (slower: minutes for the compass "
                       "gait's 45 slopes)", "compiled")
    slopes = p.add_mutually_exclusive_group()
    slopes.add_argument("--slope", default="0.5deg:6deg",
                        type=lambda t: parse_range(t, parse_slope),
                        help="START:STOP[:COUNT] slopes, e.g. 0.5deg:6deg:56 (default "
                        "0.5deg:6deg, count 45), or one slope, e.g. 3deg (as map --slope)")
    slopes.add_argument("--slope-range", dest="slope", action=DeprecatedAlias, new="--slope",
                        type=lambda t: parse_range(t, parse_slope), metavar="SLOPE_RANGE",
                        help="deprecated: the old name of --slope (still accepted, with a "
                        "note)")
    p.add_argument("--transient", type=nonnegative_int, default=BIFURCATION_TRANSIENT,
                   help="steps discarded at each slope before recording, 0 or more (default "
                   f"{BIFURCATION_TRANSIENT})")
    p.add_argument("--record", type=positive_int, default=BIFURCATION_RECORD,
                   help=f"steps recorded at each slope (default {BIFURCATION_RECORD})")
    p.add_argument("--out", default="bifurcation",
                   help="output directory (default ./bifurcation)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_bifurcation)


def _run_bifurcation(args: argparse.Namespace) -> int:
    from pathlib import Path

    import numpy as np

    from heelstrike.analysis.gait_map import compass_bifurcation, model_bifurcation
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.outputs import bifurcation_gap_note, bifurcation_title, write_bifurcation_files

    walker = walker_from_args(args) if args.model is None else model_from_args(args)
    start, stop, count = args.slope
    if not (0 < start < stop or (0 < start == stop and count == 1)):
        raise CliError("--slope needs 0 < START < STOP, or one slope > 0")
    n = count or 45
    require_budget(
        f"a bifurcation diagram of {n:,} slopes, {args.transient + args.record:,} steps each",
        n, bytes_per_point=32 * args.record + GAIT_SEARCH_BYTES,
        seconds_per_point=(args.transient + args.record + GAIT_SEARCH_STEPS)
        * WALKER_STEP_SECONDS[args.backend],
        hint="give fewer slopes (--slope START:STOP:COUNT), a shorter --transient or "
        "fewer --record steps")
    writable_dir(args.out)
    slopes = np.linspace(start, stop, n)
    # the branch over the diagram's slopes, refined where it curves (what the figure draws)
    kw: dict[str, Any] = {"transient": args.transient, "record": args.record,
                          "continuation_points": None, "backend": args.backend}
    try:
        if args.model is not None:
            diagram, branch = model_bifurcation(walker, slopes, **kw)
        else:
            diagram, branch = compass_bifurcation(walker, slopes, progress=True, **kw)
    except GaitNotFoundError as exc:  # no gait anywhere in the range (the message says so)
        raise CliError(str(exc)) from exc
    paths = write_bifurcation_files(diagram, branch, Path(args.out), bifurcation_title(walker))
    onset = float(branch.values[0]) if branch.values.size else None
    note = None
    if onset is not None and onset > start:
        gap = bifurcation_gap_note(math.degrees(start), math.degrees(onset),
                                   branch.cycles[0].stable)
        note = (f"{gap}: the branch followed starts there (automatic gait search, then "
                "bisection to 1e-5 rad); the diagram and the branch are empty below it (other, "
                "unstable gaits may exist there: 'heelstrike gait --slope ...' lists them)")
    period_steps = diagram.period_steps()
    if args.model is not None:
        from heelstrike.analysis.model_gaits import hanging_links, upright_links

        hanging = [hanging_links(walker, c.q, float(v))
                   for v, c in zip(branch.values, branch.cycles, strict=True)]
        if any(hanging):
            at = [float(v) for v, h in zip(branch.values, hanging, strict=True) if h]
            names = sorted({n for h in hanging for n in h})
            where = ("at every slope of the branch" if len(at) == len(hanging) else
                     f"from {math.degrees(min(at)):.4g} to {math.degrees(max(at)):.4g} deg")
            hang_note = (f"on the branch followed, {hanging_text(names)} {where}: gaits of the "
                         "hanging link, not of the upright one")
            note = hang_note if note is None else f"{note}; {hang_note}"
        elif hanging and (upright := upright_links(walker)):
            hang_note = (f"on the branch followed, {upright_text(upright)}: gaits of the upright "
                         f"link; {OTHER_POSTURE}")
            note = hang_note if note is None else f"{note}; {hang_note}"
    if args.json:
        print_json({
            "model": None if args.model is None else walker.description.name,
            "backend": args.backend,
            "walks": [{"slope": float(s), "status": st or None,
                       "period_steps": int(n) if n else None, "settling": bool(slow)}
                      for s, st, n, slow in zip(diagram.slopes, diagram.statuses, period_steps,
                                                diagram.settling(branch), strict=True)],
            "branch": [{"slope": float(v), "impact_angle": c.impact_angle, "period": c.period,
                        "spectral_radius": c.spectral_radius, "stable": c.stable}
                       for v, c in zip(branch.values, branch.cycles, strict=True)],
            "period_doubling_slopes": [float(v) for v in branch.period_doubling],
            "branch_stopped": branch.stopped,
            "note": note,
            "figure": str(paths[0]),
            "data": str(paths[2]),
            "branch_data": str(paths[3]),
        })
        return 0
    print_paths(paths)
    for line in _bifurcation_summary(diagram, branch, period_steps):
        print(line)
    if note:
        print(f"note: {note}")
    return 0


def _bifurcation_summary(diagram: Any, branch: Any, period_steps: Any) -> list[str]:
    """Lines saying what the diagram shows: the branch's span, stability and period
    doublings, and the periods the walks settled into (or where they fell)."""
    import numpy as np

    from heelstrike.dynamics.hybrid import WalkStatus

    deg = np.rad2deg
    lines = []
    if branch.values.size:
        stable = [float(v) for v, c in zip(branch.values, branch.cycles, strict=True) if c.stable]
        span = f"{deg(branch.values[0]):.4g} to {deg(branch.values[-1]):.4g} deg"
        if stable:
            span += f", stable from {deg(min(stable)):.4g} to {deg(max(stable)):.4g} deg"
        else:
            span += ", unstable throughout"
        lines.append(f"period-one branch: {span}")
        if branch.period_doubling.size:
            slopes = ", ".join(f"{deg(v):.4g}" for v in branch.period_doubling)
            lines.append(f"period doubling at {slopes} deg")
        if branch.stopped:
            lines.append(f"branch stopped: {branch.stopped}")
    counts: dict[str, list[float]] = {}
    settling = diagram.settling(branch)
    for s, st, n, slow in zip(diagram.slopes, diagram.statuses, period_steps, settling,
                              strict=True):
        if not st:
            continue
        longest = diagram.impact_angles.shape[1] // 2
        if st != "completed":
            key = f"{st} ({WalkStatus(st).message})"
        elif n:
            key = f"settled on period {n}"
        elif slow:
            key = ("still settling towards the stable period-one gait (drawn as circles, not "
                   "as a steady state; --transient longer)")
        elif longest < 2:  # 1 step tells nothing, 2-3 only period 1
            key = (f"walked, period not told from {diagram.impact_angles.shape[1]} recorded "
                   f"step{'s' if longest else ''} (--record 2P tells periods up to P)")
        else:
            key = (f"no period of at most {longest} steps (chaotic, or still settling: "
                   "--transient longer)")
        counts.setdefault(key, []).append(float(deg(s)))
    for what, at in counts.items():
        where = ", ".join(f"{a:.4g}" for a in at) if len(at) <= 6 else (
            f"{len(at)} slopes from {at[0]:.4g} to {at[-1]:.4g}")
        lines.append(f"walks at {where} deg: {what}")
    return lines


def add_basin(sub: Any) -> None:
    p = sub.add_parser(
        "basin",
        help="basin of attraction of the passive gait",
        description="Basin of attraction (Schwab & Wisse 2001) of the passive period-one gait on "
        "the post-impact (q3, q3_dot) slice through the fixed point (q4_dot at its fixed-point "
        "value), computed with the compiled ensemble. With --model: the slice of the walker's "
        "post-heel-strike section spanned by the stance angle and its rate, the other section "
        "coordinates held at the fixed point. Writes basin.png and basin.nc.",
    )
    add_walker_options(p)
    add_model_options(p)
    add_backend_option(p, "step simulator: the compiled ensemble (default) or the scipy "
                       "reference, walker by walker (slow: about 10,000 walker-steps a minute, "
                       "hours for the compass gait's default 400x400 grid)", "compiled")
    p.add_argument("--slope", type=parse_slope, default=parse_angle("3deg"),
                   help="slope angle (default 3deg)")
    p.add_argument("--grid", type=parse_grid, default=None,
                   help="N_Q3xN_Q3DOT grid points (default 400x400; 100x100 with --model)")
    p.add_argument("--q3-range", type=lambda t: parse_range(t, parse_angle),
                   default=None, help="Q3MIN:Q3MAX post-impact stance angles (default "
                   "-0.5:-0.05 rad, widened to keep the fixed point 0.1 rad inside; with "
                   "--model the stance angle, by default the fixed point's "
                   "-0.25 to +0.2 rad, a range given is absolute); write --q3-range=-0.5:-0.05")
    p.add_argument("--q3dot-range", type=parse_range, default=None,
                   help="MIN:MAX post-impact stance velocities in rad/s (default 0.3:2.3, widened "
                   "to keep the fixed point 0.3 rad/s inside; with "
                   "--model by default the fixed point's -0.9 to +1.1 rad/s, a range given is "
                   "absolute)")
    p.add_argument("--steps", type=positive_int, default=BASIN_STEPS,
                   help=f"largest number of steps per initial state (default {BASIN_STEPS})")
    p.add_argument("--tol", type=float, default=BASIN_TOLERANCE,
                   help="convergence radius around the fixed point, the norm of the section "
                   f"coordinates' difference (rad and rad/s together; default {BASIN_TOLERANCE:g})")
    p.add_argument("--out", default="basin", help="output directory (default ./basin)")
    add_store_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_basin)


def _basin(args: argparse.Namespace, grid: tuple[int, int], compute: Any) -> Any:
    """Check ``--tol``, the run's size and ``--out``, then compute the basin (with
    ``--store``)."""
    from heelstrike.analysis.basin import BYTES_PER_POINT
    from heelstrike.analysis.limit_cycle import GaitNotFoundError

    if not (math.isfinite(args.tol) and args.tol > 0):
        raise CliError(f"--tol must be finite and > 0 (a convergence radius in rad and rad/s), "
                       f"got {args.tol:g}")
    points = grid[0] * grid[1]
    require_budget(f"a {grid[0]}x{grid[1]} basin of up to {args.steps:,} steps a start",
                   points, bytes_per_point=BYTES_PER_POINT,
                   seconds_per_point=args.steps * WALKER_STEP_SECONDS[args.backend],
                   hint="use a smaller --grid or fewer --steps")
    writable_dir(args.out)
    try:
        return run_with_store(args.store, compute, out=args.out)
    except GaitNotFoundError as exc:
        raise _no_gait(args.slope, exc) from exc


def _render_basin(basin: Any, args: argparse.Namespace, grid: tuple[int, int],
                  head: dict[str, Any], names: Any, title: str, fp: str, work: str) -> int:
    """Write the basin's figure and data and report it (JSON ``head`` keys first); say on
    stderr when the gait is unstable (then nothing converges to it)."""
    from heelstrike.outputs import write_basin

    png, nc = write_basin(basin, args.out)
    if basin.gait_stable is False:
        print(f"heelstrike: note: the period-one gait the basin is built around is unstable "
              f"(largest |multiplier| {basin.spectral_radius:.4g} > 1): no start converges to "
              "it, its basin is empty ('heelstrike bifurcation' shows over which slopes, if "
              "any, it is stable)", file=sys.stderr)
    if args.json:
        print_json({
            **head,
            "converging_fraction": basin.converging_fraction,
            "fractions": basin.fractions(),
            "fixed_point": dict(zip(names, map(float, basin.fixed_point), strict=True)),
            "gait_stable": basin.gait_stable,
            "spectral_radius": basin.spectral_radius,
            "grid": list(grid),
            "steps": args.steps,
            "slope": args.slope,
            "elapsed": basin.elapsed,
            "figure": str(png),
            "data": str(nc),
        })
        return 0
    print(title)
    print(f"  {'fixed point':20s} {fp}")
    if basin.gait_stable is not None:
        print(f"  {'gait':20s} {'stable' if basin.gait_stable else 'unstable'} (largest "
              f"|multiplier| {basin.spectral_radius:.4g})")
    print(f"  {'converging':20s} {100 * basin.converging_fraction:.3f} % of the grid")
    for name, frac in basin.fractions().items():
        if frac > 0 and name != "converged":
            print(f"  {name.replace('_', ' '):20s} {100 * frac:.3f} %")
    print(f"  {'ensemble time':20s} {basin.elapsed:.1f} s{work}")
    print_paths((png, nc))
    return 0


def _run_basin_model(args: argparse.Namespace) -> int:
    from heelstrike.analysis import basin as basin_module

    walker = model_from_args(args)
    grid = args.grid or (100, 100)
    ranges = None
    if args.q3_range is not None or args.q3dot_range is not None:
        if args.q3_range is None or args.q3dot_range is None:
            raise CliError("with --model give both --q3-range and --q3dot-range, or neither "
                           "(default: a window about the fixed point)")
        ranges = (args.q3_range[:2], args.q3dot_range[:2])
        if not (ranges[0][0] < ranges[0][1] and ranges[1][0] < ranges[1][1]):
            raise CliError("--q3-range and --q3dot-range need MIN < MAX")
    basin = _basin(args, grid, lambda: basin_module.model_basin_of_attraction(
        walker, args.slope, grid=grid, ranges=ranges, steps=args.steps, tol=args.tol,
        backend=args.backend, progress=True,
        store=args.store,
    ))
    names = walker.section_names
    ia, ib = basin.axes
    hang = basin.hanging_links
    if hang:
        print(f"heelstrike: note: in the gait the basin is built around, {hanging_text(hang)}: "
              "a gait of the hanging link, not of the upright one", file=sys.stderr)
    return _render_basin(
        basin, args, grid, {"model": walker.description.name}, names,
        f"basin of attraction of '{walker.description.name}', slope = "
        f"{math.degrees(args.slope):g} deg, grid {grid[0]}x{grid[1]} over ({names[ia]}, "
        f"{names[ib]}), up to {args.steps} steps",
        fixed_point_text(dict(zip(names, basin.fixed_point, strict=True))),
        f" ({basin.walker_steps} walker-steps)")


def _run_basin(args: argparse.Namespace) -> int:
    from heelstrike.analysis.basin import basin_of_attraction

    if args.model is not None:
        return _run_basin_model(args)
    walker = walker_from_args(args)
    # an axis not given: the default window, widened to hold the fixed point
    q3_range, rate_range = (None if r is None else (float(r[0]), float(r[1]))
                            for r in (args.q3_range, args.q3dot_range))
    ranges = (q3_range, rate_range)
    if any(r is not None and not r[0] < r[1] for r in ranges):
        raise CliError("--q3-range and --q3dot-range need MIN < MAX")
    grid = args.grid or (400, 400)
    basin = _basin(args, grid, lambda: basin_of_attraction(
        walker, args.slope, grid=grid, ranges=ranges, steps=args.steps,
        tol=args.tol, progress=True, store=args.store,
        backend=args.backend,
    ))
    z = basin.fixed_point
    return _render_basin(
        basin, args, grid, {}, ("q3", "q3_dot", "q4_dot"),
        f"basin of attraction, R = {args.radius:g} m, slope = {math.degrees(args.slope):g} deg, "
        f"grid {grid[0]}x{grid[1]}, up to {args.steps} steps",
        f"q3 = {z[0]:.6f} rad, q3_dot = {z[1]:.6f} rad/s, q4_dot = {z[2]:.6f} rad/s", "")


def add_map(sub: Any) -> None:
    p = sub.add_parser(
        "map",
        help="stable passive gaits over foot radius and slope",
        description="Period-one passive gaits over (foot radius, slope): spectral radius, "
        "stability and the period-doubling slope per radius (continuation along the slope with "
        "the compiled step map). Writes gait_map.png and gait_map.nc.",
        conflict_handler="resolve",  # --radius below replaces the walker option by a range
    )
    add_walker_options(p)
    add_model_options(p)
    add_backend_option(p, "step simulator: compiled (default) or the scipy reference (the same "
                       "continuation, minutes)", "compiled")
    p.add_argument("--radius", type=parse_range, default=None,
                   help="START:STOP[:COUNT] foot radii in m (default 0:0.6:7; with --model "
                   "the walker's parameter R, the default 7 radii from 0 to 0.6 m or to the "
                   "largest R the walker admits if that is smaller)")
    p.add_argument("--x", type=parse_sweep, default=None, metavar="NAME:START:STOP:COUNT",
                   help="with --model: the swept walker parameter instead of --radius, e.g. "
                   "R:0:0.2:5 (SI units)")
    p.add_argument("--slope", type=lambda t: parse_range(t, parse_slope),
                   default=(math.radians(1.0), math.radians(6.0), 21),
                   help="START:STOP[:COUNT] slopes, e.g. 1deg:6deg:21 (default)")
    p.add_argument("--out", default="gait_map", help="output directory (default ./gait_map)")
    add_store_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_map)


def _map_slopes(args: argparse.Namespace) -> Any:
    """The map's slopes (rad) from ``--slope START:STOP[:COUNT]`` (21 by default)."""
    import numpy as np

    s0, s1, ns = args.slope
    if not (0 < s0 < s1 or (0 < s0 == s1 and ns == 1)):
        raise CliError("--slope needs 0 < START < STOP, or one slope > 0")
    return np.linspace(s0, s1, ns or 21)


def _check_map_budget(args: argparse.Namespace, n_values: int, option: str) -> None:
    """Refuse a map too large for the machine (:func:`require_budget`), before any grid is
    made: ``n_values`` walkers (``option``) times the ``--slope`` count, a gait search each."""
    n_slopes = args.slope[2] or 21
    require_budget(f"a map of {n_values:,} x {n_slopes:,} cells", n_values * n_slopes,
                   bytes_per_point=GAIT_SEARCH_BYTES,
                   seconds_per_point=GAIT_SEARCH_STEPS
                   * WALKER_STEP_SECONDS[args.backend or "compiled"],
                   hint=f"give fewer {option} or --slope values (COUNT)")


def _run_map_model(args: argparse.Namespace) -> int:
    import numpy as np

    from heelstrike.analysis.gait_map import model_gait_map

    walker = model_from_args(args)
    if args.store is not None:
        raise CliError("--store is not supported with --model yet (the map is not chunked)")
    if args.x is not None and args.radius is not None:
        raise CliError("give --x NAME:START:STOP:COUNT or --radius, not both")
    option = "--x" if args.x is not None else "--radius"
    if args.x is not None:
        name, x0, x1, nx = args.x
    elif "R" in walker.parameters:
        # the default range stops where the walker's constraints end (kneed: R <= a1 + b1)
        name, (x0, x1, nx) = "R", args.radius or (
            0.0, walker.largest_admissible("R", 0.6), 7)
    else:
        raise CliError(f"model {walker.description.name!r} has no parameter 'R': give the swept "
                       f"parameter with --x NAME:START:STOP:COUNT (its parameters: "
                       f"{', '.join(sorted(walker.parameters))})")
    if name not in walker.parameters:
        raise CliError(f"unknown parameter {name!r} of model {walker.description.name!r} (its "
                       f"parameters: {', '.join(sorted(walker.parameters))})")
    _check_map_budget(args, nx or 7, option)
    slopes = _map_slopes(args)
    values = np.linspace(x0, x1, nx or 7)
    for v in values:  # refuse values the walker's constraints reject (never "no gait")
        try:
            walker.replace(**{name: float(v)})
        except ValueError as exc:
            hint = ""
            if v > walker.parameters[name]:
                hint = f"; the largest admitted {name} is {walker.largest_admissible(name, v):.6g}"
            raise CliError(f"{option}: {name} = {v:g} is not admitted by model "
                           f"{walker.description.name!r}: {exc}{hint}") from None
    writable_dir(args.out)
    gmap = model_gait_map(walker, name, values, slopes, backend=args.backend,
                          progress=True)
    from heelstrike.models.description import parameter_units

    unit = parameter_units(walker.description).get(name)
    head = {"model": walker.description.name, "parameter_name": name,
            "parameter_unit": unit, "parameter_values": values.tolist()}
    return _render_gait_map(
        gmap, args, head,
        f"stable passive gaits of '{walker.description.name}'", f"({name}, slope)",
        [f"{name} = {v:8.4g}{'' if unit is None else ' ' + unit}" for v in values],
        note=_hanging_cells_note(gmap))


def _hanging_cells_note(gmap: Any) -> str | None:
    """Where the map's gaits carry a link described upright hanging (QA sweep 13: the torso
    walker's map followed its upright gaits, its bifurcation diagram a hanging-torso gait):
    a note, or None."""
    import numpy as np

    found = int(np.isfinite(gmap.dataset["fixed_point"].values[..., 0]).sum())
    if not gmap.hanging_cells:
        if not (gmap.upright_links and found):
            return None
        return (f"in all {found} gaits found, {upright_text(gmap.upright_links)}: gaits of "
                f"the upright link; {OTHER_POSTURE}")
    return (f"in {gmap.hanging_cells} of the {found} gaits found, "
            f"{hanging_text(gmap.hanging_links)}: gaits of the hanging link, not of the upright "
            "one")


def _run_map(args: argparse.Namespace) -> int:
    import numpy as np

    from heelstrike.analysis.gait_map import gait_map
    from heelstrike.analysis.limit_cycle import GaitNotFoundError

    if args.model is not None:
        return _run_map_model(args)
    if args.x is not None:
        raise CliError("--x needs --model (the compass gait's map sweeps --radius)")
    r0, r1, nr = args.radius or (0.0, 0.6, 7)
    if not 0 <= r0 <= r1 <= args.leg_length:
        raise CliError("--radius needs 0 <= START <= STOP <= leg length")
    _check_map_budget(args, nr or 7, "--radius")
    slopes = _map_slopes(args)
    radii = np.linspace(r0, r1, nr or 7)
    base = walker_from_args(argparse.Namespace(**{**vars(args), "radius": float(radii[0])}))
    writable_dir(args.out)
    try:
        gmap = run_with_store(args.store, lambda: gait_map(
            base, radii, slopes, progress=True,
            store=args.store, backend=args.backend), out=args.out)
    except GaitNotFoundError as exc:
        raise CliError(f"no starting gait found: {exc}") from exc
    return _render_gait_map(gmap, args, {"foot_radius": radii.tolist()}, "stable passive gaits",
                            "(R, slope)", [f"R = {R:6.3f} m" for R in radii])


def _render_gait_map(gmap: Any, args: argparse.Namespace, head: dict[str, Any], title: str,
                     points: str, rows: list[str], note: str | None = None) -> int:
    """Write the map's figure and data and report it (JSON ``head`` keys first; ``note``
    said last, and as the JSON's ``note``)."""
    import warnings

    import numpy as np

    from heelstrike.outputs import write_gait_map

    with warnings.catch_warnings():  # all-NaN rows (values without a gait) are expected
        warnings.simplefilter("ignore", RuntimeWarning)
        png, nc = write_gait_map(gmap, args.out)
    ds = gmap.dataset
    pd = [None if not np.isfinite(v) else float(v) for v in gmap.period_doubling_slope]
    stable = ds["stable"].values
    found = ds["gait_found"].values
    if args.json:
        print_json({
            **head,
            "slope": ds["slope"].values.tolist(),
            "stable_fraction": float(np.mean(stable)),
            "period_doubling_slope": pd,
            "gait_found_fraction": float(np.mean(found)),
            "gait_found": found.tolist(),
            "figure": str(png),
            "data": str(nc),
            "note": note,
        })
        return 0
    # counts of grid points, written "K of N grid points" / "K/N slopes" so that no count
    # reads as a parameter value ("no gait at 0" read as "at R = 0")
    # the map follows the period-one branch from its anchor gaits: where it finds none, another
    # gait (e.g. an unstable one off the branch) may still exist (QA sweep 9)
    missing = int((~found).sum())
    print(f"{title}: stable at {int(stable.sum())} of {stable.size} {points} grid points; no "
          f"gait found on the followed branch at {missing} of {found.size} grid points"
          + (" (NaN in the data, blank in the figure; a gait off the branch may still exist "
             "there: 'heelstrike gait' searches one point)" if missing else ""))
    for label, v, row, frow in zip(rows, pd, stable, found, strict=True):
        pd_text = "none in range" if v is None else f"{math.degrees(v):.3f} deg"
        print(f"  {label}: stable at {int(row.sum()):3d}/{row.size} slopes, "
              f"no gait on the branch at {int((~frow).sum()):3d}/{frow.size} slopes, "
              f"period doubling {pd_text}")
    print_paths((png, nc))
    if note:
        print(f"note: {note}")
    return 0
