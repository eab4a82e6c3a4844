"""Robot impact decompositions per second: heelstrike[robots] against ``pin.impulseDynamics``.

Problem: Talos (``talos_reduced.urdf`` from example-robot-data, free-flyer base, nv = 38) at
random admissible states (the ``half_sitting`` pose perturbed by N(0, 0.2) in every coordinate,
base orientation included, joints clipped to their limits; v ~ N(0, 1)), both soles kept flat
on the ground (two 6-row contacts, 12 constraint rows, bilateral and inert). One Pinocchio
``Model`` and one ``Data`` are reused for every configuration, by every path.

Work done
---------
Pinocchio's ``impulseDynamics`` returns ``v+`` and the impulses only. heelstrike's tree path
(``inert_energy_split``, ``robot_impact``, ``inert_energy_split_batch``) returns those **and**
the energy split ``T``, ``T_c``, ``T_a``, ``T+`` and the per-contact normal/tangential shares
of ``T_c``, from ``q``, ``v`` and the contact frames, as the Pinocchio row "J computed" does
(mass matrix and frame Jacobians included). "J given" is Pinocchio's best case: the Jacobians
precomputed, untimed. The dense like-for-like rows (``robot_matrices`` + ``inert_velocity``,
or the batched ``inert_velocity_batch``) compute ``v+`` and the impulses only.

Paths
-----
single calls        one configuration per Python call (300 configurations per timing):
                    ``inert_energy_split`` checked (state validated, rank certificate) and with
                    ``check=False`` (states checked beforehand, untimed), ``robot_impact`` (the
                    same kernel plus its ``RobotImpact`` report).
batched             10,000 configurations: Pinocchio fills ``M`` and ``J`` configuration by
                    configuration (one loop of Pinocchio calls), one compiled kernel call per
                    chunk of 256 (``inert_energy_split_batch``).
before              a frozen copy of the dense path the API took before the tree kernel
                    (``_robot_inert_dense.py``: LAPACK on the dense ``M`` per call, numpy's
                    stacked solvers per chunk).
reference           heelstrike's general machinery: the complementarity solver
                    ``resolve_contact_impact`` with the split by ``core.impact`` (single), and
                    ``inert_impact_batch`` (projectors by ``core.impact``, batched numpy).

Accuracy: before timing, ``v+`` of every heelstrike path is compared with ``impulseDynamics``
on all 10,000 configurations, and the energies of the tree path with the frozen dense path and
of the direct paths with the reference path;
the achieved agreement is reported. Threads: the measurements run twice, each in a new process:
once with ``OMP_NUM_THREADS = OPENBLAS_NUM_THREADS = MKL_NUM_THREADS = 1`` (single thread), once
with the libraries' default (all cores). In each process the first call of each path is timed
separately (cold: first use after loading the robot) from the warm medians of repeated runs.
The paths are timed in interleaved rounds (every path once per round, 7 rounds after a warm-up
round), so that the paths of a round share the machine's load; a row's rate is the median over
the rounds, its ratios to Pinocchio the medians of the per-round ratios. Where the time goes:
each stage of the single call and of the batch timed separately (medians of repeats); the tree
kernel's stages by stopping it after each (its ``upto`` argument), as differences of medians.

Run ``python benchmarks/bench_robot.py`` (``--quick`` for a smoke run, ``--json PATH``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from _common import machine

THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
               "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")
CHUNK = 256
#: Throughputs of this benchmark before the direct path (same machine, load average 6.0):
#: ``robot_impact`` went through the complementarity machinery, the batch through core.impact.
BEFORE = {"heelstrike robot_impact, single calls": 272.2,
          "heelstrike batched over 10,000": 1758.2,
          "pinocchio impulseDynamics, single calls (J given)": 31951.4}


def median_time(fn: Callable[[], object], repeats: int) -> float:
    """Median wall time (s) of ``repeats`` calls after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def first_time(fn: Callable[[], object]) -> float:
    """Wall time (s) of one call (cold when it is the first use in the process)."""
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def states(pin: Any, robot: Any, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random admissible states (q (n, nq), v (n, nv))."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.model.lowerPositionLimit[7:], robot.model.upperPositionLimit[7:]
    qs = np.empty((n, robot.nq))
    for i in range(n):
        q = np.array(pin.integrate(robot.model, robot.reference_q,
                                   0.2 * rng.standard_normal(robot.nv)))
        q[7:] = np.clip(q[7:], lo, hi)
        qs[i] = q
    return qs, rng.standard_normal((n, robot.nv))


def worker(quick: bool, threads: str) -> dict[str, Any]:
    """All measurements in this process (its thread settings were fixed by the parent)."""
    t0 = time.perf_counter()
    try:
        import pinocchio as pin
        from _robot_inert_dense import inert_energy_split_batch_dense, robot_impact_dense

        from heelstrike.core.contact_laws import (
            ContactRows,
            InertLayout,
            check_inert_batch,
            inert_contact_impact,
            inert_contact_impact_batch,
            inert_velocity,
            inert_velocity_batch,
            resolve_contact_impact,
        )
        from heelstrike.robots import (
            ContactSpec,
            inert_energy_split,
            inert_energy_split_batch,
            inert_impact_batch,
            load_robot,
            mass_matrices_and_jacobians,
            robot_impact,
            robot_matrices,
        )
        from heelstrike.robots.contacts import _inert_path
    except ImportError:
        return {"skipped": True}
    t_import = time.perf_counter() - t0
    t0 = time.perf_counter()
    robot = load_robot("talos")
    t_load = time.perf_counter() - t0
    model, data = robot.model, robot.data
    feet = tuple(ContactSpec(frame=f, kind="flat") for f in robot.feet)
    fids = [robot.frame_id(f) for f in robot.feet]
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    layout = InertLayout(normal=tuple(c.normal for c in feet),
                         tangential=tuple(c.tangential for c in feet))
    n_batch = 500 if quick else 10_000
    n_single = 50 if quick else 300
    n_ref = 20 if quick else 100
    n_ref_batch = 256 if quick else 1_024
    repeats = 3 if quick else 7
    qs, vs = states(pin, robot, n_batch)

    def jac(q: np.ndarray) -> np.ndarray:
        pin.computeJointJacobians(model, data, q)
        return np.vstack([pin.getFrameJacobian(model, data, f, lwa) for f in fids])

    # -- cold: the first call of each path in this process ------------------------------------
    q0, v0 = qs[0], vs[0]
    J_first = jac(q0)
    cold = {
        "import pinocchio + heelstrike.robots (s)": t_import,
        "load_robot('talos') (s)": t_load,
        "first pin.impulseDynamics (J given) (s)": first_time(
            lambda: pin.impulseDynamics(model, data, q0, v0, J_first, 0.0, 0.0)),
        "first heelstrike inert_energy_split (loads the kernel module) (s)": first_time(
            lambda: inert_energy_split(robot, q0, v0, feet)),
        "first heelstrike robot_impact (s)": first_time(
            lambda: robot_impact(robot, q0, v0, strike=[], keep=feet)),
        f"first heelstrike inert_energy_split_batch, {n_batch:,} configurations (s)":
            first_time(lambda: inert_energy_split_batch(robot, qs, vs, feet, chunk=CHUNK)),
    }
    Js = np.stack([jac(q) for q in qs])

    # -- agreement ------------------------------------------------------------------------------
    v_pin = np.stack([np.array(pin.impulseDynamics(model, data, q, v, J, 0.0, 0.0))
                      for q, v, J in zip(qs, vs, Js, strict=True)])
    scale = np.maximum(1.0, np.abs(v_pin).max(axis=1))

    def worst_v(v_plus: np.ndarray) -> float:
        return float((np.abs(v_plus - v_pin[: len(v_plus)]).max(axis=1) / scale[: len(v_plus)])
                     .max())

    batch = inert_energy_split_batch(robot, qs, vs, feet, chunk=CHUNK)
    singles = [robot_impact(robot, q, v, strike=[], keep=feet).result for q, v in zip(qs, vs,
                                                                                     strict=True)]
    def velocity_only(q: np.ndarray, v: np.ndarray) -> np.ndarray:
        M, A = robot_matrices(robot, q, feet)
        return inert_velocity(M, v, A)[0]

    v_only = np.stack([velocity_only(q, v) for q, v in zip(qs, vs, strict=True)])
    lean = [inert_energy_split(robot, q, v, feet) for q, v in zip(qs, vs, strict=True)]
    dense = inert_energy_split_batch_dense(robot, qs, vs, feet, chunk=CHUNK)
    keys = ("T", "T_c", "T_a", "T_post", "energy_lost", "T_c_normal", "T_c_tangential")
    tree_vs_dense = max(
        float(np.max(np.abs(np.asarray(getattr(x, key)) - np.asarray(getattr(dense, key)[i]))))
        / float(dense.T[i])
        for i, x in enumerate(lean) for key in keys)
    tree_vs_dense = max(tree_vs_dense, *(
        float(np.max(np.abs(getattr(batch, key) - getattr(dense, key)) / (
            dense.T if getattr(dense, key).ndim == 1 else dense.T[:, None])))
        for key in keys))
    def velocity_only_batch(i: int) -> np.ndarray:
        M, A = mass_matrices_and_jacobians(robot, qs[i:i + CHUNK], feet)
        return inert_velocity_batch(M, vs[i:i + CHUNK], A)[0]

    v_only_batch = np.concatenate([velocity_only_batch(i) for i in range(0, n_batch, CHUNK)])
    energy_worst = 0.0
    for i in range(n_ref):
        M, A = robot_matrices(robot, qs[i], feet)
        crows = [ContactRows(jacobian=A[6 * j:6 * j + 6], normal=c.normal,
                             tangential=c.tangential, tangential_weights=c.tangential_weights,
                             bilateral=True) for j, c in enumerate(feet)]
        ref = resolve_contact_impact(M, vs[i], crows)
        one = singles[i]
        diffs = [abs(one.T_c - ref.T_c), abs(one.T_a - ref.T_a), abs(one.T - ref.T),
                 *np.abs(one.T_c_normal - ref.T_c_normal),
                 *np.abs(one.T_c_tangential - ref.T_c_tangential),
                 abs(batch.T_c[i] - ref.T_c), abs(batch.T_a[i] - ref.T_a),
                 *np.abs(batch.T_c_normal[i] - ref.T_c_normal),
                 *np.abs(batch.T_c_tangential[i] - ref.T_c_tangential)]
        energy_worst = max(energy_worst, float(max(diffs)) / ref.T)
    balance = max(abs(r.T_c + r.T_a - r.T) / r.T for r in singles)
    agreement = {
        "v+ robot_impact vs impulseDynamics": worst_v(np.stack([r.velocity_post
                                                               for r in singles])),
        "v+ inert_energy_split (tree) vs impulseDynamics": worst_v(np.stack(
            [x.velocity_post for x in lean])),
        "v+ inert_energy_split_batch (tree) vs impulseDynamics": worst_v(batch.velocity_post),
        "v+ frozen dense batch vs impulseDynamics": worst_v(dense.velocity_post),
        "energies (T, T_c, T_a, T+, shares) tree vs frozen dense path, / T": tree_vs_dense,
        "v+ robot_matrices + inert_velocity vs impulseDynamics": worst_v(v_only),
        "v+ inert_velocity_batch vs impulseDynamics": worst_v(v_only_batch),
        "energies (T, T_c, T_a, shares) direct vs reference path, / T": energy_worst,
        "|T_c + T_a - T| / T": float(balance),
    }
    # -- warm medians ---------------------------------------------------------------------------
    paths: list[tuple[str, str, str, int, Callable[[], object]]] = []

    def add(section: str, path: str, work: str, n: int, fn: Callable[[], object]) -> None:
        paths.append((section, path, work, n, fn))

    sl = slice(0, n_single)
    qs_checked = robot.check_states(qs)
    vplus = "v+, impulses"
    full = "v+, impulses, T, T_c, T_a, T+, normal/tangential T_c per contact"

    def pin_given() -> None:
        for q, v, J in zip(qs[sl], vs[sl], Js[sl], strict=True):
            pin.impulseDynamics(model, data, q, v, J, 0.0, 0.0)

    def pin_full() -> None:
        for q, v in zip(qs[sl], vs[sl], strict=True):
            pin.impulseDynamics(model, data, q, v, jac(q), 0.0, 0.0)

    def hs_vplus() -> None:
        for q, v in zip(qs[sl], vs[sl], strict=True):
            M, A = robot_matrices(robot, q, feet)
            inert_velocity(M, v, A)

    def hs_single() -> None:
        for q, v in zip(qs[sl], vs[sl], strict=True):
            robot_impact(robot, q, v, strike=[], keep=feet)

    def hs_lean() -> None:
        for q, v in zip(qs[sl], vs[sl], strict=True):
            inert_energy_split(robot, q, v, feet)

    def hs_lean_unchecked() -> None:
        for q, v in zip(qs_checked[sl], vs[sl], strict=True):
            inert_energy_split(robot, q, v, feet, check=False)

    def hs_single_dense() -> None:
        for q, v in zip(qs[sl], vs[sl], strict=True):
            robot_impact_dense(robot, q, v, feet)

    def hs_reference() -> None:
        for q, v in zip(qs[:n_ref], vs[:n_ref], strict=True):
            M, A = robot_matrices(robot, q, feet)
            rows_ = [ContactRows(jacobian=A[6 * j:6 * j + 6], normal=c.normal,
                                 tangential=c.tangential,
                                 tangential_weights=c.tangential_weights, bilateral=True)
                     for j, c in enumerate(feet)]
            resolve_contact_impact(M, v, rows_)

    def pin_batch() -> None:
        for q, v, J in zip(qs, vs, Js, strict=True):
            pin.impulseDynamics(model, data, q, v, J, 0.0, 0.0)

    def pin_batch_full() -> None:
        for q, v in zip(qs, vs, strict=True):
            pin.impulseDynamics(model, data, q, v, jac(q), 0.0, 0.0)

    def hs_batch_vplus() -> None:
        for i in range(0, n_batch, CHUNK):
            M, A = mass_matrices_and_jacobians(robot, qs[i:i + CHUNK], feet)
            inert_velocity_batch(M, vs[i:i + CHUNK], A)

    def hs_batch() -> None:
        inert_energy_split_batch(robot, qs, vs, feet, chunk=CHUNK)

    def hs_batch_unchecked() -> None:
        inert_energy_split_batch(robot, qs, vs, feet, chunk=CHUNK, check=False)

    def hs_batch_dense() -> None:
        inert_energy_split_batch_dense(robot, qs, vs, feet, chunk=CHUNK)

    def hs_batch_reference() -> None:
        for i in range(0, n_ref_batch, CHUNK):
            inert_impact_batch(robot, qs[i:min(i + CHUNK, n_ref_batch)],
                               vs[i:min(i + CHUNK, n_ref_batch)], feet)

    s1, s2 = "single calls", f"batched over {n_batch:,}"
    add(s1, "pinocchio impulseDynamics (J given)", vplus, n_single, pin_given)
    add(s1, "pinocchio impulseDynamics (J computed: joint + 2 frame Jacobians)", vplus,
        n_single, pin_full)
    add(s1, "heelstrike inert_energy_split (tree kernel, checked)", full, n_single, hs_lean)
    add(s1, "heelstrike inert_energy_split (tree kernel, check=False)", full, n_single,
        hs_lean_unchecked)
    add(s1, "heelstrike robot_impact (tree kernel + RobotImpact report)", full, n_single,
        hs_single)
    add(s1, "before: robot_impact on the dense LAPACK path (frozen copy)", full, n_single,
        hs_single_dense)
    add(s1, "heelstrike robot_matrices + inert_velocity (dense, like-for-like)", vplus,
        n_single, hs_vplus)
    add(s1, "heelstrike reference path (resolve_contact_impact)", full, n_ref, hs_reference)
    add(s2, "pinocchio impulseDynamics loop (J given)", vplus, n_batch, pin_batch)
    add(s2, "pinocchio impulseDynamics loop (J computed)", vplus, n_batch, pin_batch_full)
    add(s2, "heelstrike inert_energy_split_batch (tree kernel, checked)", full, n_batch, hs_batch)
    add(s2, "heelstrike inert_energy_split_batch (tree kernel, check=False)", full, n_batch,
        hs_batch_unchecked)
    add(s2, "before: inert_energy_split_batch on numpy's stacked solvers (frozen copy)", full,
        n_batch, hs_batch_dense)
    add(s2, "heelstrike mass_matrices_and_jacobians + inert_velocity_batch (dense, "
        "like-for-like)", vplus, n_batch, hs_batch_vplus)
    add(s2, "heelstrike reference inert_impact_batch (core.impact, projectors)",
        full + ", P_c, P_a", n_ref_batch, hs_batch_reference)
    # Interleaved rounds: every path once per round (the first round is a warm-up), so that
    # the paths of a round share the machine's load; ratios are medians of per-round ratios.
    times: list[list[float]] = [[] for _ in paths]
    for rnd in range(repeats + 1):
        for i, (*_, fn) in enumerate(paths):
            t0 = time.perf_counter()
            fn()
            if rnd:
                times[i].append(time.perf_counter() - t0)
    rows: list[dict[str, Any]] = []
    for i, (section, path, work, n, _) in enumerate(paths):
        same = [j for j, p in enumerate(paths) if p[0] == section]
        g, c = same[0], same[1]  # the section's Pinocchio rows: J given, J computed

        def ratio(ref: int, i: int = i) -> float:
            n_i, n_ref_ = paths[i][3], paths[ref][3]
            return statistics.median((n_i / t) / (n_ref_ / t_ref)
                                     for t, t_ref in zip(times[i], times[ref], strict=True))

        med = statistics.median(times[i])
        rows.append({"section": section, "path": path, "work": work, "threads": threads,
                     "n": n, "seconds": med, "per_second": n / med,
                     "vs_pin_J_given": ratio(g), "vs_pin_J_computed": ratio(c),
                     "rounds": repeats})

    # -- where the time goes ----------------------------------------------------------------
    reps = 20 if quick else 200

    def per_call(fn: Callable[[], object]) -> float:
        def many() -> None:
            for _ in range(reps):
                fn()
        return median_time(many, repeats) / reps

    q_c, _ = robot.check_state(q0, v0)
    M0, A0 = robot_matrices(robot, q0, feet)
    rows0 = [ContactRows(jacobian=A0[6 * j:6 * j + 6], normal=c.normal, tangential=c.tangential,
                         tangential_weights=c.tangential_weights, bilateral=True)
             for j, c in enumerate(feet)]

    def floor() -> None:
        for q in qs:
            pin.crba(model, data, q)
            pin.computeJointJacobians(model, data, q)
            for f in fids:
                pin.getFrameJacobian(model, data, f, lwa)

    Ms, As = mass_matrices_and_jacobians(robot, qs, feet)

    def chunked(fn: Callable[[slice], object]) -> Callable[[], None]:
        def run_all() -> None:
            for i in range(0, n_batch, CHUNK):
                fn(slice(i, i + CHUNK))
        return run_all

    # the tree path's stages: Pinocchio's calls, then the kernel stopped after each stage
    path = _inert_path(robot, feet)
    M_t = path.assemble(q_c, path.A)
    A_t, v_t = path.A, np.ascontiguousarray(v0)
    world = pin.Convention.WORLD

    # The kernel stopped after each stage, the stops interleaved round by round and the least
    # time of the rounds kept: differences of a few microseconds survive a loaded machine.
    stops = [(i, False) for i in range(6)] + [(0, True)]
    least = [float("inf")] * len(stops)
    for _ in range(3 * repeats):
        for j, (stage, check) in enumerate(stops):
            t0 = time.perf_counter()
            for _ in range(reps):
                path.item(M_t, A_t, v_t, path.tree, path.work, path.out, check, stage)
            least[j] = min(least[j], (time.perf_counter() - t0) / reps)
    upto = least[:6]

    def kernel_upto(stage: int, check: bool = False) -> float:
        return least[stops.index((stage, check))]

    tree_stages = [
        ("tree single: crba, world convention (M and the joint Jacobians)",
         per_call(lambda: pin.crba(model, data, q_c, world))),
        ("tree single: 2 frame Jacobians into the rows", per_call(
            lambda: path.plan.fill(data, A_t))),
        ("tree single: kernel call, returning at once (dispatch, no work)", upto[0]),
        ("tree single: + rank certificate of A (check=True)",
         kernel_upto(0, True) - upto[0]),
        ("tree single: + M = U D U^T, tree-sparse (Pinocchio's cholesky::decompose)",
         upto[1] - upto[0]),
        ("tree single: + Y = U^-1 A^T on the contacts' chains", upto[2] - upto[1]),
        ("tree single: + Delassus W = Y D^-1 Y^T and W = L L^T", upto[3] - upto[2]),
        ("tree single: + lambda, q_dot+ (two triangular solves, U^-T)", upto[4] - upto[3]),
        ("tree single: + energy split (T, T+, nested shares) and contact outputs",
         upto[5] - upto[4]),
        ("tree single: whole kernel, check=False", upto[5]),
        ("tree single: result object (InertImpactBatch, copies)",
         per_call(lambda: path.single(v_t))),
        ("tree single: inert_energy_split, checked (all of it)",
         per_call(lambda: inert_energy_split(robot, q0, v0, feet))),
        ("tree single: inert_energy_split, check=False (all of it)",
         per_call(lambda: inert_energy_split(robot, q_c, v_t, feet, check=False))),
    ]
    stages = [
        *tree_stages,
        ("single: check_state (q, v)", per_call(lambda: robot.check_state(q0, v0))),
        ("single: crba + symmetrise", per_call(lambda: robot._mass_matrix(q_c, data))),
        ("single: robot_matrices (check, crba, joint + 2 frame Jacobians)",
         per_call(lambda: robot_matrices(robot, q0, feet))),
        ("single: inert_contact_impact, checked (M, A given: v+, energies)",
         per_call(lambda: inert_contact_impact(M0, v0, A0, layout))),
        ("single: inert_contact_impact, check=False",
         per_call(lambda: inert_contact_impact(M0, v0, A0, layout, check=False))),
        ("single: inert_velocity (M, A given: v+ only)",
         per_call(lambda: inert_velocity(M0, v0, A0))),
        ("single: reference resolve_contact_impact (M, rows given)",
         per_call(lambda: resolve_contact_impact(M0, v0, rows0))),
        ("single: pinocchio impulseDynamics (J given)",
         per_call(lambda: pin.impulseDynamics(model, data, q0, v0, A0, 0.0, 0.0))),
        (f"batch of {n_batch:,}: Pinocchio calls alone (crba, joint + frame Jacobians; floor)",
         median_time(floor, repeats)),
        (f"batch of {n_batch:,}: mass_matrices_and_jacobians (stacks, symmetrised)",
         median_time(lambda: mass_matrices_and_jacobians(robot, qs, feet), repeats)),
        (f"batch of {n_batch:,}: check_inert_batch (chunks of {CHUNK})",
         median_time(chunked(lambda s: check_inert_batch(Ms[s], vs[s], As[s],
                                                         symmetric=True)), repeats)),
        (f"batch of {n_batch:,}: inert_contact_impact_batch, check=False (chunks of {CHUNK})",
         median_time(chunked(lambda s: inert_contact_impact_batch(Ms[s], vs[s], As[s], layout,
                                                                  check=False)), repeats)),
        (f"batch of {n_batch:,}: inert_velocity_batch (chunks of {CHUNK})",
         median_time(chunked(lambda s: inert_velocity_batch(Ms[s], vs[s], As[s])), repeats)),
    ]
    return {
        "threads": threads,
        "rows": rows,
        "stages": [{"stage": s, "seconds": t, "threads": threads} for s, t in stages],
        "cold": cold,
        "agreement": agreement,
        "pinocchio": pin.__version__,
    }


def run(quick: bool = False) -> dict[str, Any]:
    """Run the worker twice in new processes: single thread, then all threads."""
    runs = []
    for threads in ("1", "all"):
        env = {k: v for k, v in os.environ.items() if k not in THREAD_VARS}
        if threads == "1":
            env.update({k: "1" for k in THREAD_VARS})
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "worker.json"
            cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", threads,
                   "--json", str(out)] + (["--quick"] if quick else [])
            subprocess.run(cmd, check=True, env=env)
            runs.append(json.loads(out.read_text()))
    title = "robot impact decompositions per second (Talos, nv = 38, two flat soles, 12 rows)"
    if any(r.get("skipped") for r in runs):
        return {"benchmark": title, "machine": machine(("numpy", "scipy", "pin")), "rows": [],
                "stages": [], "notes": ["skipped: pip install '.[robots]'"]}
    one, every = runs
    rows = one["rows"] + every["rows"]
    ref = BEFORE["pinocchio impulseDynamics, single calls (J given)"]
    before = [
        f"before the direct path (previous run of this benchmark, load average 6.0): {k} "
        f"{v:,.0f}/s" + ("" if k.startswith("pinocchio") else f" ({v / ref:.2g} of Pinocchio's "
                                                              "single calls, J given)")
        for k, v in BEFORE.items()
    ]
    return {
        "benchmark": title,
        "machine": machine(("numpy", "scipy", "pin")),
        "rows": rows,
        "stages": one["stages"],
        "cold": {"1": one["cold"], "all": every["cold"]},
        "agreement": one["agreement"],
        "notes": [
            f"pinocchio {one['pinocchio']}; one Model and Data reused by every path",
            "work: Pinocchio returns v+ and the impulses; heelstrike's full rows add T, T_c, "
            "T_a, T+ and each contact's normal/tangential share of T_c; the like-for-like rows "
            "compute v+ and the impulses only, from q, v and the frames",
            "agreement (max over the configurations, v+ as max|dv+| / max(1, max|v+|)): "
            + "; ".join(f"{k} {v:.1e}" for k, v in one["agreement"].items()),
            "threads '1': OMP/OPENBLAS/MKL_NUM_THREADS=1 in a new process; 'all': library "
            f"defaults ({os.cpu_count()} logical cores) in another new process. Pinocchio is "
            "single-threaded and numpy's stacked solvers loop over the stack on one thread, so "
            "differences between the two runs' absolute rates are mostly the shared machine's "
            "load at the time; compare the ratios (interleaved rounds) within a run",
            "cold, single thread: " + "; ".join(f"{k} {v:.3g}" for k, v in one["cold"].items()),
            "cold, all threads: " + "; ".join(f"{k} {v:.3g}" for k, v in every["cold"].items()),
            *before,
        ],
    }


def format_table(result: dict[str, Any]) -> str:
    lines = [
        f"**{result['benchmark']}** ({result['machine']})",
        "",
        "| path | work | threads | configurations | median time (s) | decompositions/s "
        "| vs pin (J given) | vs pin (J computed) |",
        "|---|---|---|---:|---:|---:|---:|---:|",
    ]
    section = None
    for row in result["rows"]:
        if row.get("section") != section:
            section = row.get("section")
            lines.append(f"| *{section}* | | | | | | | |")
        lines.append(
            f"| {row['path']} | {row['work']} | {row['threads']} | {row['n']:,} | "
            f"{row['seconds']:.4g} | {row['per_second']:,.0f} | {row['vs_pin_J_given']:.2g} | "
            f"{row['vs_pin_J_computed']:.2g} |"
        )
    if result.get("stages"):
        lines += ["", "**where the time goes** (single thread; median per single call, or per "
                  "whole batch; the tree kernel's stages: least of interleaved rounds, as "
                  "differences)", "", "| stage | time (s) |", "|---|---:|"]
        for st in result["stages"]:
            lines.append(f"| {st['stage']} | {st['seconds']:.3g} |")
    lines += [""] + [f"- {note}" for note in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes (smoke test)")
    parser.add_argument("--json", type=Path, help="write the result to this file")
    parser.add_argument("--worker", choices=("1", "all"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        out = worker(args.quick, args.worker)
        if args.json:
            args.json.write_text(json.dumps(out))
        return 0
    result = run(quick=args.quick)
    print(format_table(result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
