"""``heelstrike powered`` and ``study cost``: powered walking on level ground (issue 4)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from typing import Any

from heelstrike.cli._common import (
    ACTUATIONS,
    CliError,
    Parser,
    actuation_options,
    add_actuation_options,
    add_backend_option,
    add_model_options,
    add_store_option,
    add_walker_options,
    family_from_args,
    linspace_grid,
    model_from_args,
    parse_range,
    refuse_unused_gains,
    run_with_store,
    walker_from_args,
    writable_dir,
)
from heelstrike.cli._render import (
    fixed_point_text,
    multipliers_text,
    print_json,
    print_paths,
    print_stability_lines,
    print_step_lines,
)

__all__ = ['add_powered', 'add_study']


def refuse_model_actuation(walker: Any, actuations: Sequence[str]) -> None:
    """A one-line error unless the described walker takes every actuation
    (:func:`~heelstrike.analysis.powered.check_model_actuation`: the hip laws need a walker
    whose one actuated joint is its hip)."""
    from heelstrike.analysis.powered import check_model_actuation

    for actuation in actuations:
        try:
            check_model_actuation(walker, actuation)
        except ValueError as exc:
            raise CliError(str(exc)) from None


def declared_speed(walker: Any, model: str | None) -> float:
    """The walker's declared target speed (m/s, :attr:`PlanarWalker.powered_speed`), the
    default target of ``powered`` and ``study cost``; a one-line error if it declares none."""
    declared = walker.powered_speed
    if declared is None:
        raise CliError(f"--model {model} declares no target speed (a [powered] table with "
                       "speed = ... m/s in its walker file): give --speed or --step-length")
    return float(declared)


#: ``--backend`` of ``powered`` and ``study cost``.
BACKEND_HELP = ("step simulator: compiled (the default; it evaluates the push-off, the "
                "hip laws hip-energy and hip-pd, and with --model the walker file's posture "
                "law; for the compass gait the kernel generated from compass.toml) or the scipy "
                "reference (the default for McGeer's wheel, --radius equal to --leg-length, "
                "which has no generated kernel)")


def compass_simulator(walker: Any, family: Any, backend: str | None) -> Any:
    """The compass search's step simulator on ``--backend`` (None: the reference), see
    :func:`heelstrike.analysis.powered.family_simulator`; a one-line error for
    ``--backend compiled`` where its kernels cannot walk (McGeer's wheel)."""
    from heelstrike.analysis.powered import family_simulator

    try:
        return family_simulator(walker, family, backend)
    except ValueError as exc:
        reason = str(exc).replace("backend='scipy'", "--backend scipy (the default there)")
        raise CliError(f"--backend compiled: {reason}") from None


def add_powered(sub: Any) -> None:
    p = sub.add_parser(
        "powered",
        help="periodic powered gait on level ground and its energy books",
        description="Find the level-ground periodic gait of a powered compass gait with a "
        "target speed or step length: push-off impulse (pushoff), energy-tracking hip torque "
        "(hip-energy) or swing-leg PD (hip-pd). Prints the energy books per step: on a "
        "periodic gait the actuator work equals the collision loss T_c (paper eqs. 14-15). "
        "With --model: push-off (the impulse is found) plus the posture law the walker file "
        "declares ([control.torso], e.g. --model torso), or a hip law on a walker whose one "
        "actuated joint is its hip (compass, kneed); the hip laws' default gains are scaled "
        "to the walker's m_total g l and sqrt(l/g).",
    )
    add_walker_options(p)
    add_model_options(p)
    add_backend_option(p, BACKEND_HELP)
    tgt = p.add_mutually_exclusive_group()
    tgt.add_argument("--speed", type=float, default=None,
                     help="target mean speed (m/s); default: the walker's declared target "
                     "speed, 0.5 m/s for the compass gait (with --model: the walker file's "
                     "[powered] speed)")
    tgt.add_argument("--step-length", type=float, default=None, help="target step length (m)")
    p.add_argument("--actuation", choices=ACTUATIONS, default="pushoff",
                   help="actuation model (default pushoff)")
    add_actuation_options(p)
    p.add_argument("--out", default=None, metavar="DIR",
                   help="also write the period's energy books: DIR/powered_energy.png and "
                   "its data DIR/powered_energy.csv")
    p.add_argument("--time-limit", type=float, default=None, metavar="SECONDS",
                   help="stop the search after this many seconds of computing (default 45; "
                   "first-run kernel builds not counted)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_run_powered)


def _run_powered(args: argparse.Namespace) -> int:
    from heelstrike.analysis.gaits import GaitNote, find_gaits
    from heelstrike.analysis.powered import (
        DEFAULT_TIME_LIMIT,
        PoweredGaitNotFoundError,
        books_gap,
        design_radius,
    )

    refuse_unused_gains(args, [args.actuation])
    limit = DEFAULT_TIME_LIMIT if args.time_limit is None else args.time_limit
    if not (math.isfinite(limit) and limit > 0):
        raise CliError(f"--time-limit must be finite and > 0 (s), got {limit:g}")
    walker = walker_from_args(args) if args.model is None else model_from_args(args)
    if args.model is not None:
        refuse_model_actuation(walker, [args.actuation])
    if args.speed is None and args.step_length is None:
        target, value, source = "speed", declared_speed(walker, args.model), "walker"
        declared_note = " (the walker's declared target)"
    elif args.speed is not None:
        target, value, source, declared_note = "speed", args.speed, "--speed", ""
    else:
        target, value, source, declared_note = "step_length", args.step_length, "--step-length", ""
    if not (math.isfinite(value) and value > 0):
        raise CliError(f"--{target.replace('_', '-')} must be finite and > 0, got {value:g}")
    speed, step_length = (value, None) if target == "speed" else (None, value)
    radius = design_radius(walker) if args.model is not None else args.radius
    out = None if args.out is None else writable_dir(args.out)
    backend = args.backend or "compiled"
    if args.model is None:
        family = family_from_args(args)
        step_simulator = compass_simulator(walker, family, args.backend)
        backend = "scipy" if step_simulator is None else "compiled"
    try:
        # the gaits study cost meets at this design point, in the one order of gaits (the
        # cheapest stable first, issue 32)
        gaits = find_gaits(
            walker, 0.0, control=args.actuation, target={target: value},
            backend=args.backend if args.model is None else backend,
            actuation_options=actuation_options(args) or None,
            progress=True, time_limit=limit)
    except PoweredGaitNotFoundError as exc:
        hint = ("; give it more with --time-limit SECONDS"
                + ("" if backend == "compiled" else " or use --backend compiled, much faster")
                if "(time limit" in str(exc) else "")
        raise CliError(
            f"no {args.actuation} gait found with {target.replace('_', ' ')} {value:g} "
            f"{'m/s' if target == 'speed' else 'm'}"
            f"{declared_note} at R = {radius:g} m: {exc}{hint}"
        ) from exc
    # the first in the one order of gaits (McGeer's wheel: every gait's stability is
    # undecided, WHEEL_FAMILY: the cheapest)
    gait = gaits[0]
    _note_wheel(gaits)
    act = gait.actuation
    assert act is not None  # a powered gait
    others = [g for g in gaits if g is not gait]
    d = {**gait.to_dict(), "target_speed": speed, "target_step_length": step_length,
         "target_source": source, "backend": backend, "gaits_found": len(gaits),
         "other_gaits": [_gait_summary(g) for g in others]}
    if out is not None:
        from heelstrike.analysis.powered import energy_book_tables
        from heelstrike.outputs import write_powered_energy

        energy, impacts = energy_book_tables(walker, gait)
        png, csv = write_powered_energy(gait, energy, impacts, out)
        print(f"{png}\n{csv}", file=sys.stderr if args.json else sys.stdout)
    if args.json:
        print_json(d)
        return 0
    label = f"{args.actuation}, {backend} backend" if act.model is None else \
        f"{args.actuation}, model {act.model}, {backend} backend"
    print(f"powered gait ({label}), R = {radius:g} m, level ground")
    unit = "m/s" if target == "speed" else "m"
    given = "the walker's declared target" if source == "walker" else source
    print(f"  target          {target.replace('_', ' ')} {value:g} {unit} ({given})")
    from heelstrike.analysis.powered import actuation_family

    print(f"  {act.parameter_name:15s} {act.parameter:10.6g} {act.parameter_unit} "
          f"({actuation_family(act.name).parameter_meaning})")
    if act.gains:
        from heelstrike.analysis.powered import GAIN_UNITS

        print("  gains           " + ", ".join(
            f"{k} {v:g} {GAIN_UNITS[k]}" for k, v in act.gains.items()))
    print(f"  fixed point (just after impact): {fixed_point_text(d['fixed_point'])}")
    print_step_lines(gait)
    print_stability_lines(gait)
    print("  energy books per step")
    # six significant digits: a slow gait's work is ~1e-9 J (it read 0.000000 J)
    print(f"    actuator work   {gait.actuator_work:12.6g} J (push-off "
          f"{act.push_off_work:.6g} J, {act.torque_joint} {act.torque_work:.6g} J)")
    losses = gait.walk.impact_losses()
    split = (" = " + " + ".join(f"{kind} {loss:.6g} J" for kind, loss in losses)
             if len(losses) > 1 else "")
    print(f"    collision loss  {gait.collision_loss:12.6g} J (T_c{split})")
    print(f"    change of T + V {gait.energy_change:12.3e} J")
    print(f"    imbalance       {gait.energy_balance_error:12.3e} J")
    if GaitNote.BOOKS_OPEN in gait.notes:
        print(f"  note: the books close to {books_gap(gait):.1e} of the work only (change of "
              "T + V and imbalance): the gait is resolved no better than that; tighter tolerances "
              "(find_powered_gait's tol, rtol, atol) would resolve it further")
    print(f"  cost of transport {gait.cost_of_transport:10.6g} (net actuator work / (m g L))")
    print(f"  eta             {gait.eta:10.6g} J/m")
    if others:
        which = ("this is the one needing the least actuator work (McGeer's wheel: their "
                 "stability is undecided)" if gait.stability_undecided else
                 "this is the stable one needing the least actuator work" if gait.stable else
                 "none is stable: this is the one needing the least actuator work")
        print(f"  note: {len(gaits)} distinct gaits meet this target; {which} (study cost "
              "keeps the same one); the others:")
        for g in others:
            o = _gait_summary(g)
            print(f"    {act.parameter_name} {o['parameter']:.6g} {o['parameter_unit']}: "
                  f"actuator work "
                  f"{g.actuator_work:.6g} J, speed {g.speed:.5f} m/s, step length "
                  f"{g.step_length:.5f} m, stable {_verdict(g)} (|m| "
                  f"{multipliers_text([o['spectral_radius']])})"
                  + (f", legs cross {g.leg_crossings} times a step"
                     if GaitNote.MULTI_SWING in g.notes else ""))
    if GaitNote.MULTI_SWING in gait.notes:
        print(f"  note: the swing leg crosses the stance leg {gait.leg_crossings} times a step: "
              "its foot passes through the ground away from mid-stance, outside the scuffing "
              "convention (one crossing, near mid-stance); no ordinary step was found")
    if GaitNote.NO_STABLE_GAIT in gait.notes:
        # the search is local (seeds, continuation, a few fresh starts): QA sweep 6 found a
        # stable gait needing 1/61 of this work at --step-length 0.05, reached by continuing
        # from the 0.1 m/s gait
        print("  note: the search met no stable gait at this target, which does not show that "
              "none exists: it is local (seed gaits continued to the target, a few fresh "
              "starts); a stable one, or a cheaper one, may be reached by continuing from "
              "another target (find_powered_gait(..., guess=(*fixed_point, parameter)) in small "
              "steps)")
    if GaitNote.TRAILING_FOOT_GRAZES in gait.notes:
        print("  note: R = l (McGeer's wheel): the trailing foot's lift velocity is exactly 0; "
              "both contacts are the same point, so the step was accepted")
    return 0


def _note_wheel(gaits: Sequence[Any]) -> None:
    """Say on stderr what a powered gait of McGeer's wheel is (``WHEEL_FAMILY``): gaits whose
    stability is undecided (their notes' ``GaitNote.STABILITY_UNDECIDED``)."""
    from heelstrike.analysis.gaits import GaitNote
    from heelstrike.analysis.powered import WHEEL_FAMILY

    if any(GaitNote.STABILITY_UNDECIDED in g.notes for g in gaits):
        print(f"heelstrike: note: {WHEEL_FAMILY}", file=sys.stderr)


def _verdict(gait: Any) -> str:
    """``yes``, ``no`` or ``undecided`` (the gait's ``stability_undecided``)."""
    return "undecided" if gait.stability_undecided else "yes" if gait.stable else "no"


def _gait_summary(gait: Any) -> dict[str, Any]:
    """What tells another gait at the same target apart (``other_gaits`` of the JSON)."""
    import numpy as np

    a = gait.actuation
    return {"parameter": a.parameter, "parameter_unit": a.parameter_unit,
            "actuator_work": gait.actuator_work, "collision_loss": gait.collision_loss,
            "period": gait.period, "step_length": gait.step_length, "speed": gait.speed,
            "stable": bool(gait.stable), "stability_undecided": bool(gait.stability_undecided),
            "spectral_radius": float(np.max(np.abs(gait.multipliers))),
            "leg_crossings": gait.leg_crossings,
            "fixed_point": dict(zip(gait.section_names, map(float, gait.fixed_point),
                                    strict=True))}


def add_study(sub: Any) -> None:
    p = sub.add_parser(
        "study",
        help="design studies (cost: cost of transport over foot radius x step length)",
        description="Design studies of powered walkers on level ground.",
    )
    ssub = p.add_subparsers(dest="study", required=True, parser_class=Parser)
    c = ssub.add_parser(
        "cost",
        help="cost of transport over foot radius x step length (or speed)",
        description="Periodic level-ground gaits over foot radius x step length (or speed) "
        "for each actuation model; writes cost_study.nc and figures, including the paper's "
        "impact-only eta against the actuator work per metre of the real gaits. With --model "
        "(a walker file with a foot radius parameter R, e.g. compass, kneed, torso): push-off "
        "plus the posture law the file declares, or a hip law on a walker whose one actuated "
        "joint is its hip.",
        conflict_handler="resolve",
    )
    add_walker_options(c)  # its --radius is replaced by the range below
    add_model_options(c)
    add_backend_option(c, BACKEND_HELP)
    c.add_argument("--radius", dest="radii", type=parse_range, default=None,
                   help="foot radii START:STOP:COUNT (m); default 0 to 0.9 x the largest foot "
                   "radius the walker admits, 4 values (0:0.9:4 for the paper's compass gait, "
                   "R <= l = 1 m; with --model: its file's constraints, e.g. 0:0.45:4 for kneed)")
    tgt = c.add_mutually_exclusive_group()
    tgt.add_argument("--step-length", dest="lengths", type=parse_range, default=None,
                     help="step lengths START:STOP:COUNT (m), default 0.3:0.6:4 for the "
                     "paper's compass gait (without --model)")
    tgt.add_argument("--speed", dest="speeds", type=parse_range, default=None,
                     help="speeds START:STOP:COUNT (m/s); the default with --model: 4 speeds "
                     "from 0.95 to 1.05 x the walker's declared target speed (its file's "
                     "[powered] speed, where its push-off gaits exist)")
    c.add_argument("--actuation", action="append", choices=ACTUATIONS, default=None,
                   help="actuation model, repeatable (default pushoff)")
    add_actuation_options(c)
    c.add_argument("--out", default="cost_study", help="output directory (default ./cost_study)")
    add_store_option(c)
    c.set_defaults(func=_run_study, radius=0.0)


def _run_study(args: argparse.Namespace) -> int:
    from pathlib import Path

    from heelstrike.analysis.cost_study import check_study_memory, cost_study
    from heelstrike.analysis.powered import actuation_family
    from heelstrike.outputs import write_cost_figures, write_cost_study

    model = None
    if args.model is None:
        if args.param:
            raise CliError("--param sets a described walker's parameter: give --model too")
        walker = walker_from_args(args)  # validates the other walker parameters
        leg_length = float(args.leg_length)
    else:
        if any(item.partition("=")[0].strip() == "R" for item in args.param):
            raise CliError("--param R=... is swept by --radius START:STOP:COUNT: give it there")
        model = model_from_args(args)
        refuse_model_actuation(model, args.actuation or ["pushoff"])
        if "R" not in model.parameters:
            raise CliError(f"model {model.description.name!r} has no foot radius parameter 'R' "
                           f"(its parameters: {', '.join(sorted(model.parameters))})")
        walker = None
        leg_length = float(model.scale.leg_length)
    if args.radii is None:  # the walker's own range (R = l is McGeer's wheel: stop short)
        largest = leg_length if model is None else model.largest_admissible("R", leg_length)
        args.radii = (0.0, 0.9 * largest, 4)
    check_study_memory(len(args.actuation or ["pushoff"]), args.radii[2] or 4,
                       (args.speeds or args.lengths or (0, 0, 4))[2] or 4)
    radii = linspace_grid(args.radii, 4)
    if min(radii) < 0 or max(radii) > leg_length:
        raise CliError(f"--radius must lie in [0, {leg_length:g}] m")
    if args.speeds is None and args.lengths is None and model is not None:
        declared = declared_speed(model, args.model)
        args.speeds = (0.95 * declared, 1.05 * declared, 4)
    if args.speeds is not None:
        target, values = "speed", linspace_grid(args.speeds, 4)
    else:
        target, values = "step_length", linspace_grid(args.lengths or (0.3, 0.6, 4), 4)
    if min(values) <= 0:
        raise CliError(f"--{target.replace('_', '-')} values must be > 0")
    acts = args.actuation or ["pushoff"]
    refuse_unused_gains(args, acts)
    options = actuation_options(args)
    if walker is not None:  # --backend compiled for McGeer's wheel: one line
        for act in acts:
            for r in radii:
                compass_simulator(walker.replace(foot_radius=r),
                                  actuation_family(act, **options), args.backend)
    writable_dir(args.out)
    try:
        ds = run_with_store(args.store, lambda: cost_study(
            radii, values, target=target, actuations=acts, walker=walker, model=model,
            backend=args.backend, actuation_options=options, progress=True,
            store=args.store), out=args.out)
    except ValueError as exc:  # e.g. a radius the walker file's constraints reject
        raise CliError(str(exc)) from exc
    out = Path(args.out)
    try:
        nc = write_cost_study(ds, out / "cost_study.nc")
        paths = [nc, *write_cost_figures(ds, out)]
    except OSError as exc:
        raise CliError(f"cannot write to {args.out!r}: {exc.strerror or exc}") from exc
    found = int(ds["cost_of_transport"].notnull().sum())
    if not found:
        raise CliError(f"no gait found at any of the {ds['cost_of_transport'].size} points of "
                       f"the grid ({', '.join(acts)} actuation; no figure drawn; the all-NaN "
                       f"data is in {str(nc)!r}); try other step lengths or speeds")
    from heelstrike.analysis.cost_study import cheapest_gaits

    print(_study_table(cheapest_gaits(ds), wheel_from=leg_length))
    print("files written:")
    print_paths(f"  {p}" for p in paths)
    fresh = int((ds["branch"] == 1).sum())
    print(f"gaits: the cheapest stable one found at each point (else the cheapest unstable "
          f"one, marked), by continuation from neighbours or by fresh searches from several "
          f"seeds ({fresh} point(s) came from a fresh search; "
          f"up to {int(ds['gaits_found'].max())} distinct gaits met at one point; every gait "
          f"found is listed in {nc.name}: gait_actuator_work, gait_stable over 'gait')")
    print(f"{found} of {ds['cost_of_transport'].size} gaits found", file=sys.stderr)
    from heelstrike.analysis.powered import WHEEL_FAMILY

    if float(ds["radius"].max()) >= leg_length:  # a wheel's gaits: stability undecided
        print(f"heelstrike: note: {WHEEL_FAMILY}", file=sys.stderr)
    return 0


def _study_table(rows: list[dict[str, Any]], *, wheel_from: float) -> str:
    """The cost study's summary: one line per row of
    :func:`~heelstrike.analysis.cost_study.cheapest_gaits` (a foot radius ``>= wheel_from``, m,
    is McGeer's wheel, whose stability is undecided)."""
    target = rows[0]["target"] if rows else "step_length"
    tlabel = "step length (m)" if target == "step_length" else "speed (m/s)"
    head = ["actuation", "gait", "R (m)", tlabel, "parameter", "CoT (1)", "eta (J/m)",
            "max |mult|", "stable", "found"]
    table = [head]
    for r in rows:
        if r["radius"] >= wheel_from:
            stable = "undecided (wheel)"
        else:
            stable = {True: "yes", False: "no", None: "undecided"}[r["stable"]]
        table.append([
            r["actuation"], r["which"], f"{r['radius']:.4g}", f"{r['target_value']:.4g}",
            f"{r['parameter']:.4g} {r['parameter_unit']}".strip(),
            f"{r['cost_of_transport']:.4g}", f"{r['eta']:.4g}", f"{r['spectral_radius']:.3g}",
            stable, f"{r['found']}/{r['points']}",
        ])
    widths = [max(len(row[k]) for row in table) for k in range(len(head))]
    lines = ["cheapest gait per actuation (CoT = W_act / (m_total g L_S); stable: every "
             "Floquet multiplier inside the unit circle)"]
    lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
              for row in table]
    return "\n".join(lines)

