"""Ensembles of a described walker: walker-steps per second per core (``basin --model kneed``).

The task is walking the shipped kneed walker (slope 3 deg) from many post-heel-strike section
points, as ``heelstrike basin --model kneed`` does, with three paths:

ensemble   ``heelstrike.dynamics.compiled_phased.ensemble_walk_phased``: all walkers in one
           compiled call (numba; a loop over walkers around the walk kernel), one thread.
loop       a Python loop of ``simulate_phased_compiled`` (the same kernel, one call per walker,
           samples and impact records kept).
scipy      a Python loop of the scipy reference ``simulate_phased`` (DOP853), few walkers.

Correctness before speed: every walker's status, step count and final state are compared
between the ensemble and the loop (must be identical to 1e-8) and, on a few walkers, the scipy
reference (1e-8, at rtol = atol = 1e-11); the benchmark fails otherwise.

Timed (warm caches, one untimed call first, medians of repeats; **one thread**, so the rates
are per core):

- walking states (the gait's fixed point plus small random perturbations, all walk every step)
  at the basin's tolerances (rtol 1e-8, atol 1e-9) and at rtol = atol = 1e-10;
- the whole basin ``model_basin_of_attraction`` (fixed point given, so Newton is excluded) over
  a grid of the default window: falls are cheap, converged walks stop on arrival;
- compile time without a cache: a new process with empty ``HEELSTRIKE_CACHE_DIR`` and
  ``NUMBA_CACHE_DIR`` runs a one-walker ensemble twice (first minus second: derivation and
  numba compilation of the walk and ensemble kernels); skipped with ``--quick``.

Run ``python benchmarks/bench_model_basin.py`` (``--quick``: smaller sizes, ``--json PATH``).
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

from heelstrike.analysis.basin import model_basin_of_attraction
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.dynamics.compiled_phased import ensemble_walk_phased, simulate_phased_compiled
from heelstrike.dynamics.phased import load_phased_walker, simulate_phased

SLOPE = math.radians(3.0)
TOL = 1e-8

_CHILD = """
import json, math, time
t0 = time.perf_counter()
from heelstrike.dynamics.compiled_phased import ensemble_walk_phased
from heelstrike.dynamics.phased import load_phased_walker
w = load_phased_walker("kneed")
z = [-0.26837474, 1.2227157, -1.14217385]
t1 = time.perf_counter()
ensemble_walk_phased(w, z, slope=math.radians(3.0), steps=2, parallel=False)
t2 = time.perf_counter()
ensemble_walk_phased(w, z, slope=math.radians(3.0), steps=2, parallel=False)
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


def run(quick: bool = False) -> dict[str, Any]:
    machine_line = machine()
    rows: list[dict[str, Any]] = []
    notes: list[str] = []
    w = load_phased_walker("kneed")
    zstar = np.asarray(find_model_gait(w, slope=SLOPE).fixed_point)
    rng = np.random.default_rng(0)
    n_walk, steps = (100, 10) if quick else (400, 20)
    Z = zstar + rng.normal(scale=[0.005, 0.02, 0.02], size=(n_walk, zstar.size))
    reps = 3 if quick else 5
    # -- correctness --------------------------------------------------------------------------
    ens = ensemble_walk_phased(w, Z, slope=SLOPE, steps=steps, rtol=1e-8, atol=1e-9,
                               parallel=False)
    if not np.all(ens.steps == steps):
        raise SystemExit("the benchmark's walking states do not all walk")
    diff_loop = 0.0
    for i in range(0, n_walk, max(1, n_walk // 20)):
        q, qd = w.section_to_state(Z[i])
        one = simulate_phased_compiled(w, q, qd, slope=SLOPE, steps=steps, rtol=1e-8, atol=1e-9)
        if one.status.value != ens.status_names[i] or one.n_steps != ens.steps[i]:
            raise SystemExit(f"ensemble and loop differ at walker {i}")
        diff_loop = max(diff_loop, float(np.max(np.abs(one.final_q - ens.q[i]))),
                        float(np.max(np.abs(one.final_q_dot - ens.q_dot[i]))))
    ref_z = np.vstack((Z[:2], zstar + np.array([0.0, -0.6, 0.0])))
    ens_r = ensemble_walk_phased(w, ref_z, slope=SLOPE, steps=2, rtol=1e-11, atol=1e-11)
    diff_ref = 0.0
    for i, z in enumerate(ref_z):
        q, qd = w.section_to_state(z)
        ref = simulate_phased(w, q, qd, slope=SLOPE, steps=2, rtol=1e-11, atol=1e-11)
        if ref.status.value != ens_r.status_names[i] or ref.n_steps != ens_r.steps[i]:
            raise SystemExit(f"ensemble and scipy differ at walker {i}")
        diff_ref = max(diff_ref, float(np.max(np.abs(ref.final_q - ens_r.q[i]))),
                       float(np.max(np.abs(ref.final_q_dot - ens_r.q_dot[i]))))
    if not (diff_loop <= TOL and diff_ref <= TOL):
        raise SystemExit(f"differences {diff_loop:.1e} (loop), {diff_ref:.1e} (scipy) > {TOL}")
    # -- walking states -----------------------------------------------------------------------
    for rtol, atol in ((1e-8, 1e-9), (1e-10, 1e-10)):
        t_e, _ = _timed(lambda rt=rtol, at=atol: ensemble_walk_phased(
            w, Z, slope=SLOPE, steps=steps, rtol=rt, atol=at, parallel=False), reps)
        n_loop = 20 if quick else 50

        def loop(rt: float = rtol, at: float = atol, n: int = n_loop) -> None:
            for z in Z[:n]:
                q, qd = w.section_to_state(z)
                simulate_phased_compiled(w, q, qd, slope=SLOPE, steps=steps, rtol=rt, atol=at)

        t_l, _ = _timed(loop, reps)
        rows.append({"path": f"ensemble_walk_phased, walking states, rtol {rtol:g}",
                     "walker_steps": n_walk * steps, "seconds": t_e,
                     "rate": n_walk * steps / t_e})
        rows.append({"path": f"loop of simulate_phased_compiled, rtol {rtol:g}",
                     "walker_steps": n_loop * steps, "seconds": t_l,
                     "rate": n_loop * steps / t_l})
    n_ref = 2
    t_s, _ = _timed(lambda: [simulate_phased(w, *w.section_to_state(z), slope=SLOPE, steps=2,
                                             rtol=1e-10, atol=1e-10) for z in Z[:n_ref]], 1)
    rows.append({"path": "loop of scipy simulate_phased, rtol 1e-10",
                 "walker_steps": 2 * n_ref, "seconds": t_s, "rate": 2 * n_ref / t_s})
    # -- the basin ----------------------------------------------------------------------------
    n = 20 if quick else 40
    t_b, basin = _timed(lambda: model_basin_of_attraction(
        w, SLOPE, grid=(n, n), steps=60, fixed_point=zstar, parallel=False), reps)
    rows.append({"path": f"model_basin_of_attraction {n} x {n}, up to 60 steps (whole run)",
                 "walker_steps": basin.walker_steps, "seconds": t_b,
                 "rate": basin.walker_steps / t_b})
    fr = basin.fractions()
    notes.append(
        "basin outcomes: " + ", ".join(f"{k} {100 * v:.1f} %" for k, v in fr.items() if v > 0)
        + "; converged walks stop on arrival (tol 1e-3), so most walker-steps are transients"
    )
    notes.append(
        f"agreement: ensemble vs loop of simulate_phased_compiled max abs difference of the "
        f"final state {diff_loop:.1e} (same statuses and step counts); vs scipy "
        f"simulate_phased (rtol = atol = 1e-11, 3 walkers, 2 steps) {diff_ref:.1e}"
    )
    # -- compile time -------------------------------------------------------------------------
    if not quick:
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, HEELSTRIKE_CACHE_DIR=str(Path(tmp) / "hs"),
                       NUMBA_CACHE_DIR=str(Path(tmp) / "numba"))
            cold = json.loads(subprocess.run([sys.executable, "-c", _CHILD],
                                             capture_output=True, text=True, env=env,
                                             check=True).stdout)
        notes.append(
            f"compile time without a cache (new process, empty caches): first one-walker "
            f"ensemble {cold['first']:.1f} s, second {cold['second']:.3f} s; derivation and "
            f"numba compilation of the walk and ensemble kernels "
            f"{cold['first'] - cold['second']:.1f} s"
        )
    return {"benchmark": "model basin", "machine": machine_line, "rows": rows, "notes": notes}


def format_table(result: dict[str, Any]) -> str:
    lines = [
        f"**ensembles of the kneed walker (slope 3 deg): walker-steps per second per core** "
        f"({result['machine']})",
        "",
        "| path (one thread) | walker-steps | median time (s) | walker-steps/s |",
        "|---|---:|---:|---:|",
    ]
    for r in result["rows"]:
        lines.append(f"| {r['path']} | {r['walker_steps']:,} | {r['seconds']:.4g} | "
                     f"{r['rate']:,.0f} |")
    lines.append("")
    lines += [f"- {n}" for n in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv, quick_help="smaller sizes (smoke test)")


if __name__ == "__main__":
    sys.exit(main())
