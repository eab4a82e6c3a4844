"""Newton's gait solve on the exact step-map Jacobian against central differences.

``find_limit_cycle(walker, guess=..., jacobian=...)`` on the scipy reference, one thread:

exact     ``jacobian="exact"`` (the default): every iterate is one step with its variational
          equations (:meth:`~heelstrike.analysis.limit_cycle.PoincareMap.exact_jacobian`:
          ``P(z)`` and ``DP(z)`` together); the gait's multipliers are the Jacobian at the root.
central   ``jacobian="central"``: every iterate is ``P(z)`` and ``2 d`` step maps of central
          differences; the multipliers afterwards (the exact Jacobian for the passive compass on
          the plain reference, ``2 d`` more maps for the kneed walker's phased simulator).

Walkers: the compass gait (R = 0, 3 deg, from the start of ``bench_walk.py``) and the kneed
walker (McGeer, 0.0504 rad, from 0.02 off its gait). Each solve is timed whole (Newton and the
gait's characterisation) in rounds alternating the two Jacobians, medians of 5 after one
untimed run; the step maps and exact Jacobians each solve evaluates are counted, and the two
fixed points compared.

Run ``python benchmarks/bench_newton.py`` (``--quick``: 2 rounds, the compass only; ``--json
PATH`` to save the rows). See ``benchmarks/README.md``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one thread, before numpy loads

import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from _common import machine, run_main  # noqa: E402

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle  # noqa: E402
from heelstrike.dynamics.backends import simulator as backend_simulator  # noqa: E402
from heelstrike.dynamics.phased import load_phased_walker  # noqa: E402
from heelstrike.models import CompassGait  # noqa: E402

JACOBIANS = ("exact", "central")


def _cases(quick: bool) -> list[tuple[str, dict[str, Any]]]:
    out = [("compass R=0 m", dict(walker=CompassGait(), slope=float(np.deg2rad(3.0)),
                                  guess=[-0.26, 1.1, -0.7]))]
    if not quick:
        kneed = load_phased_walker("kneed")
        out.append(("kneed", dict(walker=kneed, slope=0.0504,
                                  guess=[-0.2447694, 1.2381144, -1.0755048],
                                  simulator=backend_simulator(kneed, "scipy"))))
    return out


def _counted(kwargs: dict[str, Any], jacobian: str) -> tuple[Any, Counter[str]]:
    """One solve, counting the step maps and exact Jacobians it evaluates."""
    counts: Counter[str] = Counter()
    call, exact = PoincareMap.__call__, PoincareMap.exact_jacobian

    def counted_call(self: PoincareMap, z: Any) -> Any:
        counts["maps"] += 1
        return call(self, z)

    def counted_exact(self: PoincareMap, z: Any) -> Any:
        counts["exact"] += 1
        return exact(self, z)

    PoincareMap.__call__ = counted_call  # type: ignore[method-assign]
    PoincareMap.exact_jacobian = counted_exact  # type: ignore[method-assign]
    try:
        cycle = find_limit_cycle(jacobian=jacobian, **kwargs)
    finally:
        PoincareMap.__call__ = call  # type: ignore[method-assign]
        PoincareMap.exact_jacobian = exact  # type: ignore[method-assign]
    return cycle, counts


def run(quick: bool = False) -> dict[str, Any]:
    rounds = 2 if quick else 5
    rows = []
    for name, kwargs in _cases(quick):
        cycles, counts = {}, {}
        for jac in JACOBIANS:  # the untimed run: counts, fixed points, warm caches
            cycles[jac], counts[jac] = _counted(kwargs, jac)
        times: dict[str, list[float]] = {jac: [] for jac in JACOBIANS}
        for _ in range(rounds):
            for jac in JACOBIANS:
                t0 = time.perf_counter()
                find_limit_cycle(jacobian=jac, **kwargs)
                times[jac].append(time.perf_counter() - t0)
        rows.append({
            "walker": name,
            "d": int(cycles["exact"].fixed_point.size),
            **{f"{jac}_s": statistics.median(times[jac]) for jac in JACOBIANS},
            **{f"{jac}_iterations": int(cycles[jac].iterations) for jac in JACOBIANS},
            **{f"{jac}_maps": int(counts[jac]["maps"]) for jac in JACOBIANS},
            **{f"{jac}_exact_jacobians": int(counts[jac]["exact"]) for jac in JACOBIANS},
            "recorded": [cycles[jac].newton_jacobian for jac in JACOBIANS],
            "max_difference": float(np.max(np.abs(cycles["exact"].fixed_point
                                                  - cycles["central"].fixed_point))),
        })
    return {"machine": machine(("numpy", "scipy")), "rounds": rounds, "rows": rows}


def format_table(result: dict[str, Any]) -> str:
    lines = [result["machine"],
             f"find_limit_cycle from a guess, scipy reference, one thread; medians of "
             f"{result['rounds']} alternating rounds",
             f"{'walker':<15}{'Jacobian':>9}{'time (s)':>10}{'iterations':>12}"
             f"{'step maps':>11}{'exact DP':>10}{'|z* exact - z* central|':>25}"]
    for r in result["rows"]:
        for jac in JACOBIANS:
            diff = f"{r['max_difference']:.1e}" if jac == "exact" else ""
            lines.append(f"{r['walker']:<15}{jac:>9}{r[f'{jac}_s']:>10.3f}"
                         f"{r[f'{jac}_iterations']:>12}{r[f'{jac}_maps']:>11}"
                         f"{r[f'{jac}_exact_jacobians']:>10}{diff:>25}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv)


if __name__ == "__main__":
    sys.exit(main())
