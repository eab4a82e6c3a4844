"""One step-map Jacobian: exact (variational equations + saltation) against central differences.

At each walker's periodic gait, the time of one Jacobian of the step map on the scipy reference:

exact     ``PoincareMap.exact_jacobian`` (:func:`heelstrike.dynamics.variational.step_jacobian`):
          the nominal step, then every phase's variational equations (complex-step ``D_x F``)
          and one saltation matrix per event.
central   ``PoincareMap.jacobian(z)``: ``2 d`` step maps (``d`` section coordinates); the
          ``2 d + 1``-th map (at ``z`` itself) that Newton also needs is timed separately.

Walkers: the compass gait (R = 0 and 0.3 m, 3 deg), the kneed walker (McGeer, 0.0504 rad) and
the torso walker (level, PD torque and push-off). Also printed: the largest difference of the
two Jacobians (central differences' own accuracy, about 1e-8).

Run ``python benchmarks/bench_step_jacobian.py`` (``--quick`` for a smoke run, ``--json PATH``
to save the rows). Times are medians of repeated runs in one process; see
``benchmarks/README.md``.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from _common import machine, run_main

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.phased import TorsoPD, load_phased_walker
from heelstrike.models import CompassGait


def _median_time(fn: Callable[[], Any], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _cases(quick: bool) -> list[tuple[str, PoincareMap, np.ndarray]]:
    out = []
    for R in (0.0,) if quick else (0.0, 0.3):
        walker = CompassGait(foot_radius=R)
        slope = float(np.deg2rad(3.0))
        z = find_limit_cycle(walker, slope=slope).fixed_point
        out.append((f"compass R={R:g} m", PoincareMap(walker=walker, slope=slope), z))
    if quick:
        return out
    kneed = load_phased_walker("kneed")
    gait = find_model_gait(kneed, slope=0.0504, guess=[-0.2647694, 1.2181144, -1.0955048])
    out.append(("kneed", PoincareMap(walker=kneed, slope=0.0504), gait.cycle.fixed_point))
    torso = load_phased_walker("torso")
    law, push = TorsoPD(walker=torso), PushOff(impulse=2.0)
    gait = find_model_gait(torso, slope=0.0, torque=law, push_off=push,
                           guess=[-0.1180757, 0.1118158, 0.5531974, -0.0140899, -0.6214368])
    out.append(("torso", PoincareMap(walker=torso, slope=0.0, torque=law, push_off=push),
                gait.cycle.fixed_point))
    return out


def run(quick: bool = False) -> dict[str, Any]:
    repeats = 3 if quick else 7
    rows = []
    for name, pmap, z in _cases(quick):
        exact = pmap.exact_jacobian(z).jacobian
        central = pmap.jacobian(z)
        rows.append({
            "walker": name,
            "d": int(z.size),
            "exact_s": _median_time(lambda p=pmap, z=z: p.exact_jacobian(z), repeats),
            "central_s": _median_time(lambda p=pmap, z=z: p.jacobian(z), repeats),
            "one_map_s": _median_time(lambda p=pmap, z=z: p(z), repeats),
            "max_difference": float(np.max(np.abs(exact - central))),
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
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv)


if __name__ == "__main__":
    sys.exit(main())
