"""``heelstrike reproduce``, ``impact`` and ``impact-map``: the heel strike and the paper's figures
(issues 2 and 5)."""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

from heelstrike.cli import robot as cli_robot
from heelstrike.cli._common import (
    CliError,
    Explicit,
    add_backend_option,
    add_model_options,
    add_walker_options,
    compass_params,
    explicit_options,
    model_from_args,
    parse_angle,
    parse_floats,
    parse_sweep,
    walker_from_args,
    writable_dir,
)
from heelstrike.cli._render import one_line, print_json, print_paths, require_finite

__all__ = ['add_impact', 'add_impact_map', 'add_reproduce']


def add_reproduce(sub: Any) -> None:
    p = sub.add_parser(
        "reproduce",
        help="reproduce the paper's Figs. 2, 3a and 3b",
        description="Write Figs. 2, 3a and 3b of Font & Kövecses (2008) as PNG and PDF, with "
        "one CSV of data per figure, and print the paths written (one per line).",
    )
    p.add_argument("--out", default="figures", help="output directory (default: figures)")
    p.set_defaults(func=_run_reproduce)


def _run_reproduce(args: argparse.Namespace) -> int:
    from heelstrike.outputs import reproduce_paper

    writable_dir(args.out)
    try:
        paths = reproduce_paper(args.out)
    except OSError as exc:
        raise CliError(f"cannot write to {args.out!r}: {exc.strerror or exc}") from exc
    print_paths(paths)
    return 0


def add_impact(sub: Any) -> None:
    p = sub.add_parser(
        "impact",
        help="energy decomposition of one heel strike",
        description="Decompose the pre-impact kinetic energy of a heel strike of the "
        "circular-feet compass gait into the constrained part T_c (lost) and the admissible "
        "part T_a (kept), with the post-impact velocities, the ground impulse and the loss per "
        "metre eta = (energy lost) / L_S, which is T_c / L_S for the inert impact (e = 0; "
        "with --restitution e it is (1 - e^2) T_c / L_S) (Font & Kövecses 2008, eqs. 5-16).",
    )
    add_walker_options(p)
    add_model_options(p)
    p.add_argument("--angle", type=parse_angle, default=None,
                   help="impact angle q3, 0 < q3 < 90deg, e.g. 20deg (required unless --state)")
    p.add_argument("--state", default=None, metavar="Q1,...,QN",
                   help="with --model: full pre-impact configuration (m, rad) instead of --angle; "
                   "with --robot/--urdf/--mjcf: a STATE.json file {\"q\": [...], \"v\": [...]}")
    p.add_argument("--velocity", default=None, metavar="QD1,...,QDN",
                   help="with --model and --state: pre-impact velocities (m/s, rad/s); default: "
                   "stance rate --q3dot, foot rolling, joints at rest")
    p.add_argument("--q3dot", type=float, default=1.0, action=Explicit,
                   help="pre-impact stance-leg rate q3_dot (rad/s, default 1)")
    p.add_argument("--q4dot", type=float, default=0.0, action=Explicit,
                   help="pre-impact inter-leg rate q4_dot (rad/s, default 0; with --model the "
                   "rate of its 'hip' joint)")
    p.add_argument("--restitution", type=float, default=0.0, action=Explicit,
                   help="restitution e of the constrained velocity, 0 <= e <= 1 (default 0; "
                   "compass gait, and robots' striking contacts (normal rows))")
    add_backend_option(p, "heel-strike kernel of the compass gait: scipy (default: the "
                       "reference projectors of eqs. 5-13, numpy/scipy; the command then starts "
                       "without loading numba) or compiled (the numba compass kernel, "
                       "heelstrike.models.compass_fast; same numbers to round-off). A described "
                       "walker's (--model) or robot's heel strike runs on the reference", "scipy")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    cli_robot.add_robot_impact_options(p)  # issue 10: --robot/--urdf/--mjcf, --strike, --keep
    p.set_defaults(func=_run_impact)


def _check_rates(args: argparse.Namespace) -> None:
    for option, value in (("--q3dot", args.q3dot), ("--q4dot", args.q4dot)):
        if not math.isfinite(value):
            raise CliError(f"{option} must be finite, got {value:g}")


def _run_impact_model(args: argparse.Namespace) -> int:
    from heelstrike.analysis.heel_strike import (
        check_heel_strike_state,
        check_stance_foot_rolls,
        check_striking_foot_approaches,
    )
    from heelstrike.analysis.model_gaits import model_heel_strike, symmetric_heel_strike_state

    given = explicit_options(args)
    if args.state is not None and args.angle is not None:
        raise CliError("give --angle (symmetric heel strike) or --state, not both")
    if args.velocity is not None and given & {"q3dot", "q4dot"}:
        raise CliError("--velocity sets every pre-impact rate: drop --q3dot/--q4dot")
    if "restitution" in given and args.restitution != 0.0:
        raise CliError("--restitution applies to the compass gait only (without --model); "
                       "a described walker's heel strike is inert (e = 0)")
    _check_rates(args)
    walker = model_from_args(args)
    n = walker.n_coordinates
    if "q4dot" in given and "hip" not in walker.coordinate_names:
        raise CliError(f"--q4dot is the rate of the 'hip' joint, which model "
                       f"{walker.description.name!r} does not have; use --velocity")
    if args.state is not None:
        q = parse_floats(args.state, "--state", n)
        try:
            check_heel_strike_state(walker, q)
        except ValueError as exc:
            raise CliError(f"--state: {exc}") from None
        if args.velocity is not None:
            qd = parse_floats(args.velocity, "--velocity", n)
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
            qd = parse_floats(args.velocity, "--velocity", n)
    if args.velocity is None and "q4dot" in given:
        qd[walker.coordinate_names.index("hip")] = args.q4dot
    check_striking_foot_approaches(walker, q, qd)
    check_stance_foot_rolls(walker, q, qd)
    locked = walker.joints_at_lock(q)
    for j, angle in zip(walker.lockable_joints, walker.lock_angles, strict=True):
        if j not in locked:
            print(f"heelstrike: note: joint {walker.coordinate_names[j]!r} is at "
                  f"{q[j]:.6g} rad, not at its lock angle {float(angle):.6g} rad: it is free "
                  "in this impact (only joints at their lock angle are held locked)",
                  file=sys.stderr)
    s = model_heel_strike(walker, q, qd)
    d = s.to_dict()
    d["model"] = walker.description.name
    d["coordinates"] = list(walker.coordinate_names)
    require_finite(d)
    if args.json:
        print_json(d)
        return 0
    print(f"heel strike of '{d['model']}' ({', '.join(d['coordinates'])})")
    for key, unit in (("T", "J"), ("T_c", "J"), ("T_a", "J"), ("T_plus", "J"),
                      ("step_length", "m"), ("eta", "J/m")):
        print(f"  {key:<12} {d[key]:12.6f} {unit}")
    print(f"  trailing foot lifts  {'yes' if d['trailing_foot_lifts'] else 'no'}")
    if d["trailing_foot_held"]:
        # QA sweep 10: T_c differed from `impact`'s (the paper's, eq. 10) with nothing saying why
        print(f"  (the ground holds the trailing foot, a frictionless contact with normal impulse "
              f"{d['impulse'][-1]:.6f} N s:\n   T_c and T_a are those of both feet's "
              "constraints; the paper's T_c, eq. 10, is the striking foot's alone,\n   for an "
              "impact after which the trailing foot lifts)")
    return 0


def _shown(x: float) -> float:
    """``x`` as printed with 6 decimals, without a round-off ``-0.000000``."""
    return round(float(x), 6) + 0.0


def _run_impact(args: argparse.Namespace) -> int:
    from heelstrike.analysis.heel_strike import check_striking_foot_approaches, heel_strike_study
    from heelstrike.models import heel_strike_state

    given = explicit_options(args)
    if args.backend == "compiled" and (args.model is not None or cli_robot.robot_requested(args)):
        raise CliError("--backend compiled is the compass gait's heel-strike kernel; a described "
                       "walker's (--model) or a robot's heel strike (complementarity) runs on the "
                       "reference: drop --backend compiled")
    if cli_robot.robot_requested(args):
        ignored = [f"--{d.replace('_', '-')}" for d in sorted(given & {*compass_params(),
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
    walker = walker_from_args(args)
    q_pre, qd_pre = heel_strike_state(walker, args.angle, q3_dot=args.q3dot, q4_dot=args.q4dot)
    check_striking_foot_approaches(walker, q_pre, qd_pre)
    s = heel_strike_study(walker, args.angle, q3_dot=args.q3dot, q4_dot=args.q4dot,
                          restitution=args.restitution, backend=args.backend)
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
    require_finite(d)
    if args.json:
        print_json(d)
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
        print(f"    {name:<28}{_shown(d['qdot_minus'][i]):12.6f} "
              f"{_shown(d['qdot_plus'][i]):12.6f}")
    lx, ly = d["impulse"]
    print(f"  ground impulse on the striking foot (x, y)  {_shown(lx):.6f}, {_shown(ly):.6f} N s")
    if d["degenerate_wheel"]:
        verdict = "no: R = l, McGeer's wheel (degenerate, q2_dot+ = 0)"
    else:
        verdict = "yes" if d["trailing_foot_lifts"] else "no (impact not admissible)"
    print(f"  trailing foot lifts     {verdict}")
    return 0


def add_impact_map(sub: Any) -> None:
    p = sub.add_parser(
        "impact-map",
        help="map T_c, T_a and eta at heel strike over two swept quantities",
        description="For a described walker, sweep two description parameters (or one and "
        "the impact angle, NAME 'angle') and map the constrained and admissible kinetic "
        "energies and the loss per metre at a symmetric heel strike (stance rate --q3dot, "
        "joints at rest). Writes impact_map.png and impact_map.csv and prints their paths.",
    )
    add_model_options(p, required=True)
    p.add_argument("--x", type=parse_sweep, required=True, metavar="NAME:START:STOP:COUNT",
                   help="first swept quantity: a parameter of the walker file (SI units) or "
                   "'angle' (the impact angle, e.g. angle:5deg:30deg:11), COUNT values from "
                   "START to STOP")
    p.add_argument("--y", type=parse_sweep, required=True, metavar="NAME:START:STOP:COUNT",
                   help="second swept quantity, as --x")
    p.add_argument("--angle", type=parse_angle, default=None,
                   help="impact angle when not swept (default 20deg)")
    p.add_argument("--q3dot", type=float, default=1.0,
                   help="stance rate (rad/s, > 0, default 1)")
    p.add_argument("--out", default="impact_map", help="output directory (default ./impact_map)")
    add_backend_option(p, "heel-strike computation: scipy (default and only: the reference "
                       "complementarity heel strike of the walker's generated numpy "
                       "functions; a map of algebraic impacts, no simulation); compiled is "
                       "refused (the generated numba kernels resolve heel strikes inside their "
                       "walks only)", "scipy")
    p.set_defaults(func=_run_impact_map)


def _run_impact_map(args: argparse.Namespace) -> int:
    import numpy as np

    from heelstrike.analysis.model_gaits import (
        ANGLE,
        IMPACT_MAP_SECONDS_PER_POINT,
        check_impact_map_memory,
        impact_map,
    )
    from heelstrike.models.description import parameter_units
    from heelstrike.outputs import write_impact_map

    if args.backend == "compiled":
        raise CliError("--backend compiled: impact-map's heel strikes run on the reference "
                       "(the compiled kernels resolve heel strikes inside their walks only); "
                       "drop --backend compiled")
    if not math.isfinite(args.q3dot):
        raise CliError(f"--q3dot must be finite, got {args.q3dot:g}")
    if args.q3dot <= 0:  # joints at rest: the leading foot's normal velocity is -q3dot * L_S
        raise CliError(f"--q3dot must be > 0, got {args.q3dot:g}: with the stance leg at rest "
                       "or rotating backwards the striking foot does not move towards the "
                       "ground and no heel strike happens")
    check_impact_map_memory(args.x[3], args.y[3])  # before building any walker
    walker = model_from_args(args)
    axes = [(n, np.linspace(a, b, c)) for n, a, b, c in (args.x, args.y)]
    if axes[0][0] == axes[1][0]:
        raise CliError(f"--x and --y must sweep different quantities, both are {axes[0][0]!r}")
    swept_angle = any(name == ANGLE for name, _ in axes)
    if swept_angle and args.angle is not None:
        raise CliError("--angle sets the impact angle when it is not swept; it is swept by "
                       "--x or --y here: drop --angle")
    args.angle = parse_angle("20deg") if args.angle is None else args.angle
    given = {item.partition("=")[0].strip() for item in args.param}
    for name, _ in axes:
        if name in given:
            raise CliError(f"--param {name}=... is swept by --x/--y: give it there only")
    for option, (name, values) in zip(("--x", "--y"), axes, strict=True):
        if name == ANGLE:
            if not np.all((values > 0) & (values < math.pi / 2)):
                raise CliError(f"{option}: the impact angle must satisfy 0 < angle < 90deg")
            continue
        if name not in walker.parameters:
            raise CliError(f"{option}: {name!r} is not a parameter of model "
                           f"{walker.description.name!r} (its parameters: "
                           f"{', '.join(sorted(walker.parameters))}; or {ANGLE!r})")
        for v in values:
            try:
                walker.replace(**{name: float(v)})
            except ValueError as exc:
                raise CliError(f"{option}: {name} = {v:g} is not a valid "
                               f"{walker.description.name!r} walker: {exc}") from None
    if not swept_angle and not 0.0 < args.angle < math.pi / 2:
        raise CliError(f"--angle must satisfy 0 < angle < 90deg, got "
                       f"{math.degrees(args.angle):g} deg")
    out = writable_dir(args.out)
    n_points = args.x[3] * args.y[3]
    seconds = n_points * IMPACT_MAP_SECONDS_PER_POINT
    if seconds > 60:  # say what a long map costs before it starts
        print(f"impact-map: {n_points} points, about {seconds / 60:.3g} min (about "
              f"{IMPACT_MAP_SECONDS_PER_POINT * 1e3:g} ms a point)", file=sys.stderr)
    m = impact_map(walker, axes[0], axes[1], angle=args.angle, stance_rate=args.q3dot,
                   progress=True)
    bad = ~np.isfinite(m.T_c) | ~np.isfinite(m.T_a) | ~np.isfinite(m.eta)
    if np.any(bad):
        i, j = (int(k[0]) for k in np.nonzero(bad))
        point = {m.x_name: float(m.x[j]), m.y_name: float(m.y[i])}
        reason = "overflow or no symmetric heel strike"
        try:
            walker.replace(**{k: v for k, v in point.items() if k != ANGLE})
        except ValueError as exc:
            reason = one_line(exc)
        raise CliError(
            f"{int(bad.sum())} of {bad.size} grid points have no valid heel strike, e.g. "
            f"{', '.join(f'{k} = {v:g}' for k, v in point.items())}: {reason}; "
            "narrow --x/--y"
        )
    print_paths(write_impact_map(m, out, units=parameter_units(walker.description)))
    return 0
