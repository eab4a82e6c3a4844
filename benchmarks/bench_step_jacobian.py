"""One step-map Jacobian: exact (variational equations + saltation) against central differences.

At each walker's periodic gait, the time of one Jacobian of the step map on the scipy reference:

exact     ``PoincareMap.exact_jacobian`` (:func:`heelstrike.dynamics.variational.step_jacobian`):
          the nominal step, then every phase's variational equations (complex-step ``D_x F``)
          and one saltation matrix per event.
central   ``PoincareMap.jacobian(z)``: ``2 d`` step maps (``d`` section coordinates); the
          ``2 d + 1``-th map (at ``z`` itself) that Newton also needs is timed separately.

Then the parameter derivatives ``dP/dp`` for ``k = 6`` parameters:

exact p   ``step_jacobian(..., parameters=names)``: the same chain on the state augmented with
          the parameters (also ``D_z P`` and the exact partials of the period, step length,
          speed, ``T_c`` and ``eta`` in ``z`` and ``p``: all a gait sensitivity needs).
central p ``2 k`` step maps at ``p +- h`` (each with its changed walker built, as
          :func:`heelstrike.analysis.sensitivity.gait_sensitivity` with ``method="central"``
          does), without ``D_z P``.

Walkers: the compass gait (R = 0 and 0.3 m, 3 deg), the kneed walker (McGeer, 0.0504 rad) and
the torso walker (level, PD torque and push-off). Also printed: the largest difference of the
two Jacobians (central differences' own accuracy, about 1e-8), and of the two ``dP/dp``
(relative to its largest entry).

Run ``python benchmarks/bench_step_jacobian.py`` (``--quick`` for a smoke run, ``--json PATH``
to save the rows). Times are medians of repeated runs in one process; see
``benchmarks/README.md``.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from _common import machine, run_main

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.phased import TorsoPD, load_phased_walker
from heelstrike.dynamics.variational import step_jacobian
from heelstrike.models import CompassGait


def _median_time(fn: Callable[[], Any], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


#: The six parameters differentiated in for each walker (``"slope"``: the map's slope).
PARAMETERS = {
    "compass": ("foot_radius", "leg_com_from_hip", "leg_mass", "hip_mass", "leg_length", "slope"),
    "kneed": ("R", "a1", "b2", "mH", "mt", "slope"),
    "torso": ("b", "l", "m", "mH", "mT", "cT"),
}


def _cases(quick: bool) -> list[tuple[str, PoincareMap, np.ndarray, tuple[str, ...]]]:
    out = []
    for R in (0.0,) if quick else (0.0, 0.3):
        walker = CompassGait(foot_radius=R)
        slope = float(np.deg2rad(3.0))
        z = find_limit_cycle(walker, slope=slope).fixed_point
        names = PARAMETERS["compass"] if R > 0 else PARAMETERS["compass"][1:]  # R >= 0
        out.append((f"compass R={R:g} m", PoincareMap(walker=walker, slope=slope), z, names))
    if quick:
        return out
    kneed = load_phased_walker("kneed")
    gait = find_model_gait(kneed, slope=0.0504, guess=[-0.2647694, 1.2181144, -1.0955048])
    out.append(("kneed", PoincareMap(walker=kneed, slope=0.0504), gait.fixed_point,
                PARAMETERS["kneed"]))
    torso = load_phased_walker("torso")
    law, push = TorsoPD(walker=torso), PushOff(impulse=2.0)
    gait = find_model_gait(torso, slope=0.0, torque=law, push_off=push,
                           guess=[-0.1180757, 0.1118158, 0.5531974, -0.0140899, -0.6214368])
    out.append(("torso", PoincareMap(walker=torso, slope=0.0, torque=law, push_off=push),
                gait.fixed_point, PARAMETERS["torso"]))
    return out


def _exact_parameters(pmap: PoincareMap, z: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    return step_jacobian(pmap.walker, z, slope=pmap.slope, torque=pmap.torque,
                         push_off=pmap.push_off, parameters=names, rtol=pmap.rtol,
                         atol=pmap.atol).parameter_jacobian


def _central_parameters(pmap: PoincareMap, z: np.ndarray, names: tuple[str, ...],
                        rel_step: float = 1e-5) -> np.ndarray:
    cols = []
    for name in names:
        p = pmap.slope if name == "slope" else float(pmap.walker.parameters[name])
        h = rel_step * max(1.0, abs(p))
        maps = [replace(pmap, slope=v) if name == "slope"
                else replace(pmap, walker=pmap.walker.replace(**{name: v}))
                for v in (p + h, p - h)]
        cols.append((maps[0](z) - maps[1](z)) / (2.0 * h))
    return np.stack(cols, axis=-1)


def run(quick: bool = False) -> dict[str, Any]:
    repeats = 3 if quick else 7
    rows = []
    for name, pmap, z, names in _cases(quick):
        exact = pmap.exact_jacobian(z).jacobian
        central = pmap.jacobian(z)
        exact_p = _exact_parameters(pmap, z, names)
        central_p = _central_parameters(pmap, z, names)
        rows.append({
            "walker": name,
            "d": int(z.size),
            "exact_s": _median_time(lambda p=pmap, z=z: p.exact_jacobian(z), repeats),
            "central_s": _median_time(lambda p=pmap, z=z: p.jacobian(z), repeats),
            "one_map_s": _median_time(lambda p=pmap, z=z: p(z), repeats),
            "max_difference": float(np.max(np.abs(exact - central))),
            "k": len(names),
            "exact_p_s": _median_time(lambda p=pmap, z=z, n=names: _exact_parameters(p, z, n),
                                      repeats),
            "central_p_s": _median_time(
                lambda p=pmap, z=z, n=names: _central_parameters(p, z, n), repeats),
            "max_difference_p": float(np.max(np.abs(exact_p - central_p))
                                      / np.max(np.abs(central_p))),
        })
    return {"machine": machine(("numpy", "scipy")), "repeats": repeats, "rows": rows}


def format_table(result: dict[str, Any]) -> str:
    lines = [result["machine"], f"medians of {result['repeats']} runs",
             f"{'walker':<16}{'d':>3}{'exact (s)':>12}{'2d maps (s)':>13}{'1 map (s)':>11}"
             f"{'2d+1 maps (s)':>15}{'|exact - central|':>19}"]
    for r in result["rows"]:
        lines.append(f"{r['walker']:<16}{r['d']:>3}{r['exact_s']:>12.3f}{r['central_s']:>13.3f}"
                     f"{r['one_map_s']:>11.3f}{r['central_s'] + r['one_map_s']:>15.3f}"
                     f"{r['max_difference']:>19.2e}")
    lines += ["", "parameter Jacobian dP/dp (k parameters; exact also gives D_z P and the "
              "quantities' partials)",
              f"{'walker':<16}{'k':>3}{'exact p (s)':>13}{'2k maps (s)':>13}{'1 map (s)':>11}"
              f"{'exact / 1 map':>15}{'rel |exact - central|':>23}"]
    for r in result["rows"]:
        lines.append(f"{r['walker']:<16}{r['k']:>3}{r['exact_p_s']:>13.3f}"
                     f"{r['central_p_s']:>13.3f}{r['one_map_s']:>11.3f}"
                     f"{r['exact_p_s'] / r['one_map_s']:>15.1f}{r['max_difference_p']:>23.2e}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv)


if __name__ == "__main__":
    sys.exit(main())
