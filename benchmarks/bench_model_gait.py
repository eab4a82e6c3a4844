"""Gait of a described walker: the compiled backend vs the scipy reference (``gait --model``).

The task is ``heelstrike gait --model kneed`` (the shipped kneed walker, slope 3 deg, automatic
guess: a coarse grid of 120 post-impact states mapped once, then Newton with finite-difference
Jacobians) with its two step simulators:

compiled   ``heelstrike.dynamics.compiled_phased.simulate_phased_compiled``: numba kernel
           (DP5, events on the exact RK step, knee strike, complementarity heel strike) calling
           functions generated from the walker's sympy expressions
           (``heelstrike.models._codegen_numba``); serial calls run the walker's module
           compiled ahead of time from that kernel (``heelstrike.dynamics._aot``).
scipy      ``heelstrike.dynamics.phased.simulate_phased`` (DOP853, the reference).

Correctness before speed: both gaits are compared (fixed point, period, step length, ``T_c`` of
every impact) and the largest difference is reported; the benchmark fails if it exceeds 1e-8.

Timed:

- in one process, warm (caches loaded, one untimed call first): ``find_model_gait`` with each
  backend (median of repeats for compiled, one run for scipy);
- ``heelstrike gait --model kneed --json`` as a new process with each ``--backend`` (warm disk
  caches; includes interpreter start and imports; ``PYTHONDONTWRITEBYTECODE`` removed from the
  child's environment, as in a default Python, so imports use bytecode caches);
- compile time without any cache: a new process with empty ``HEELSTRIKE_CACHE_DIR`` and
  ``NUMBA_CACHE_DIR`` runs the compiled gait twice; the first call minus the second is the
  sympy derivation plus the numba compilation (the walker's ahead-of-time module). Then a new
  process with those (now warm) caches.

Run ``python benchmarks/bench_model_gait.py`` (``--quick``: fewer repeats, ``--json PATH``).
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from _common import machine, run_main

from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.dynamics.phased import load_phased_walker

SLOPE = math.radians(3.0)
TOL = 1e-8

_CHILD = """
import json, math, sys, time
t0 = time.perf_counter()
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.dynamics.phased import load_phased_walker
w = load_phased_walker("kneed")
t1 = time.perf_counter()
find_model_gait(w, slope=math.radians(3.0), backend="compiled")
t2 = time.perf_counter()
find_model_gait(w, slope=math.radians(3.0), backend="compiled")
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "first": t2 - t1, "second": t3 - t2}))
"""



def _timed(fn: Any, reps: int) -> tuple[float, Any]:
    times = []
    out = None
    for _ in range(reps):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def _difference(a: Gait, b: Gait) -> float:
    pairs: list[tuple[Any, Any]] = [
        (a.fixed_point, b.fixed_point),
        (a.period, b.period),
        (a.step_length, b.step_length),
        ([e.kinetic_energy_constrained for e in a.impacts],
         [e.kinetic_energy_constrained for e in b.impacts]),
    ]
    return max(float(np.max(np.abs(np.asarray(x, float) - np.asarray(y, float)))) for x, y in pairs)


def _cli(backend: str, env: dict[str, str]) -> tuple[float, dict[str, Any]]:
    cmd = [sys.executable, "-m", "heelstrike", "gait", "--model", "kneed", "--json",
           "--backend", backend]
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
    return time.perf_counter() - t, json.loads(proc.stdout)


def _cli_difference(a: dict[str, Any], b: dict[str, Any]) -> float:
    fa, fb = a["fixed_point"], b["fixed_point"]
    d = [abs(fa[k] - fb[k]) for k in fa]
    d += [abs(a[k] - b[k]) for k in ("period", "step_length", "collision_loss")]
    d += [abs(x["T_c"] - y["T_c"]) for x, y in zip(a["impacts"], b["impacts"], strict=True)]
    return max(d)


def run(quick: bool = False) -> dict[str, Any]:
    machine_line = machine()
    rows: list[dict[str, Any]] = []
    notes: list[str] = []
    # -- cold: no cache at all -------------------------------------------------------------
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, HEELSTRIKE_CACHE_DIR=str(Path(tmp) / "hs"),
                   NUMBA_CACHE_DIR=str(Path(tmp) / "numba"))
        cold = json.loads(subprocess.run([sys.executable, "-c", _CHILD], capture_output=True,
                                         text=True, env=env, check=True).stdout)
        warm = json.loads(subprocess.run([sys.executable, "-c", _CHILD], capture_output=True,
                                         text=True, env=env, check=True).stdout)
    rows.append({"table": "compile", "what": "new process, no cache: first compiled gait",
                 "seconds": cold["first"]})
    rows.append({"table": "compile", "what": "same process: second compiled gait",
                 "seconds": cold["second"]})
    rows.append({"table": "compile",
                 "what": "derivation + numba compilation, ahead of time (first minus second)",
                 "seconds": cold["first"] - cold["second"]})
    rows.append({"table": "compile", "what": "new process, warm caches: first compiled gait",
                 "seconds": warm["first"]})
    # -- warm, in one process --------------------------------------------------------------
    w = load_phased_walker("kneed")
    find_model_gait(w, slope=SLOPE, backend="compiled")  # warm-up (loads the caches)
    t_c, g_c = _timed(lambda: find_model_gait(w, slope=SLOPE, backend="compiled"),
                      3 if quick else 7)
    t_s, g_s = _timed(lambda: find_model_gait(w, slope=SLOPE, backend="scipy"), 1)
    diff = _difference(g_c, g_s)
    if not diff <= TOL:
        raise SystemExit(f"compiled and scipy gaits differ by {diff:.2e} > {TOL}")
    rows.append({"table": "gait", "path": "find_model_gait, backend='compiled' (warm)",
                 "seconds": t_c, "ratio": t_s / t_c})
    rows.append({"table": "gait", "path": "find_model_gait, backend='scipy'",
                 "seconds": t_s, "ratio": 1.0})
    # -- the command, new processes, warm disk caches --------------------------------------
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    _cli("compiled", env)  # make sure the disk caches are warm
    tc_cli, out_c = _cli("compiled", env)
    ts_cli, out_s = _cli("scipy", env)
    diff_cli = _cli_difference(out_c, out_s)
    if not diff_cli <= TOL:
        raise SystemExit(f"gait --model kneed: backends differ by {diff_cli:.2e} > {TOL}")
    rows.append({"table": "gait", "path": "`heelstrike gait --model kneed` (new process)",
                 "seconds": tc_cli, "ratio": ts_cli / tc_cli})
    rows.append({"table": "gait",
                 "path": "`heelstrike gait --model kneed --backend scipy` (new process)",
                 "seconds": ts_cli, "ratio": 1.0})
    fp = ", ".join(f"{v:.8f}" for v in g_c.fixed_point)
    notes.append(
        f"gait: fixed point ({', '.join(w.section_names)}) = ({fp}), period "
        f"{g_c.period:.6f} s, {len(g_c.impacts)} impacts per step; compiled vs scipy "
        f"max abs difference (fixed point, period, step length, T_c of each impact): "
        f"{diff:.1e} in process, {diff_cli:.1e} between the two commands' JSON"
    )
    notes.append(
        f"imports of the cold process: {cold['import']:.2f} s; numba and sympy caches live "
        "in HEELSTRIKE_CACHE_DIR/numba and numba's cache directory"
    )
    return {"benchmark": "model gait", "machine": machine_line, "rows": rows, "notes": notes}


def format_table(result: dict[str, Any]) -> str:
    rows = result["rows"]
    lines = [
        f"**gait of the kneed walker (slope 3 deg, automatic guess): compiled vs scipy "
        f"backend** ({result['machine']})",
        "",
        "| path | median time (s) | speed-up vs scipy |",
        "|---|---:|---:|",
    ]
    for r in rows:
        if r["table"] == "gait":
            lines.append(f"| {r['path']} | {r['seconds']:.4g} | {r['ratio']:.3g} |")
    lines += ["", "**compiled backend: compile time without a cache**", "",
              "| what | time (s) |", "|---|---:|"]
    for r in rows:
        if r["table"] == "compile":
            lines.append(f"| {r['what']} | {r['seconds']:.4g} |")
    lines.append("")
    lines += [f"- {n}" for n in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv, quick_help="fewer repeats (smoke test)")


if __name__ == "__main__":
    sys.exit(main())
