"""Passive walking steps per second: heelstrike compiled vs scipy paths vs Drake's CompassGait.

All paths walk the paper's point-foot compass gait (mH = 10 kg, m = 5 kg, a = b = 0.5 m,
l = 1 m, g = 9.81 m/s^2, R = 0) down a 3 deg slope from its period-one gait, with the same
integrator tolerances (rtol = atol = 1e-10 unless stated).

Paths
-----
compiled       ``heelstrike.dynamics.compiled.ensemble_walk`` (numba DP5 + event location +
               impact), one walker, serial.
reference      ``heelstrike.dynamics.hybrid.simulate`` (scipy DOP853, the reference).
plain scipy    a classical compass gait written here: Lagrange's equations in absolute leg
               angles, impact by conservation of angular momentum (about the striking foot, and
               of the trailing leg about the hip), ``solve_ivp(DOP853)`` with events in a loop.
drake          ``pydrake.examples.CompassGait`` (parameters set to the values above) in a
               ``Simulator`` with the ``runge_kutta5`` integrator at target accuracy 1e-10;
               steps counted by the simulator's unrestricted (impact) updates.

Before timing, each path's own fixed point of the step map (post-impact section
``z = (q3, q3_dot, q4_dot)``, slope-relative angles) is found by Newton's method on that path's
map and compared with heelstrike's reference fixed point.

Also timed: an ensemble of 10,000 walkers near the gait (compiled ``ensemble_walk`` on all cores
vs the per-walker rate of the ``simulate`` loop measured on a subsample), Newton's limit-cycle
solve (``find_limit_cycle`` with the scipy map vs the compiled map), the 400 x 400 basin of
attraction, and ``heelstrike reproduce`` from a cold start (a fresh process).

Run ``python benchmarks/bench_walk.py`` (``--quick`` for a smoke run, ``--json PATH`` to save).
"""

from __future__ import annotations

import math
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from _common import machine, run_main
from scipy.integrate import solve_ivp

from heelstrike.analysis.basin import basin_of_attraction
from heelstrike.analysis.limit_cycle import find_limit_cycle
from heelstrike.dynamics.compiled import ensemble_walk
from heelstrike.dynamics.hybrid import simulate
from heelstrike.models.compass import CompassGait

MH, M, A, B, L, G = 10.0, 5.0, 0.5, 0.5, 1.0, 9.81
SLOPE = math.radians(3.0)
TOL = 1e-10
WALKER = CompassGait()


def median_time(fn: Callable[[], Any], repeats: int) -> float:
    fn()  # warm-up (numba cache load, imports)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def newton(pmap: Callable[[np.ndarray], np.ndarray], z0: np.ndarray, tol: float = 1e-10,
           fd: float = 1e-6) -> np.ndarray:
    """Newton's method on ``P(z) = z`` with a central-difference Jacobian."""
    z = np.asarray(z0, dtype=float)
    for _ in range(20):
        F = pmap(z) - z
        if np.linalg.norm(F) < tol:
            return z
        J = np.empty((3, 3))
        for i in range(3):
            dz = np.zeros(3)
            dz[i] = fd
            J[:, i] = (pmap(z + dz) - pmap(z - dz)) / (2 * fd)
        z = z - np.linalg.solve(J - np.eye(3), F)
    return z


# ---------------------------------------------------------------------------------------------
# A classical point-foot compass gait with scipy (written for this benchmark)
# ---------------------------------------------------------------------------------------------
def _e(t: float) -> np.ndarray:
    return np.array([-math.sin(t), math.cos(t)])


def _de(t: float) -> np.ndarray:
    return np.array([-math.cos(t), -math.sin(t)])


def classical_rhs(t: float, x: np.ndarray, slope: float) -> np.ndarray:
    """``x = (th1, th2, w1, w2)``: absolute stance and swing angles from the slope normal."""
    th1, th2, w1, w2 = x
    c, s = math.cos(th1 - th2), math.sin(th1 - th2)
    m11 = MH * L * L + M * (A * A + L * L)
    m12 = -M * L * B * c
    m22 = M * B * B
    r1 = M * L * B * s * w2 * w2 + G * (MH * L + M * A + M * L) * math.sin(th1 + slope)
    r2 = -M * L * B * s * w1 * w1 - M * G * B * math.sin(th2 + slope)
    det = m11 * m22 - m12 * m12
    return np.array([w1, w2, (m22 * r1 - m12 * r2) / det, (m11 * r2 - m12 * r1) / det])


def classical_impact(x: np.ndarray) -> np.ndarray:
    """Plastic heel strike by angular momentum: returns the relabelled post-impact state."""
    th1, th2, w1, w2 = x

    def cross(r: np.ndarray, v: np.ndarray) -> float:
        return float(r[0] * v[1] - r[1] * v[0])

    H = L * _e(th1)
    C = H - L * _e(th2)
    rR, rL = A * _e(th1), H - B * _e(th2)

    def pre(o1: float, o2: float) -> np.ndarray:
        vH = L * _de(th1) * o1
        vR = A * _de(th1) * o1
        vL = vH - B * _de(th2) * o2
        total = MH * cross(H - C, vH) + M * cross(rR - C, vR) + M * cross(rL - C, vL)
        return np.array([total, M * cross(rR - H, vR)])

    def post(o1: float, o2: float) -> np.ndarray:  # o1: new stance (old swing) leg
        vH = L * _de(th2) * o1
        vN = A * _de(th2) * o1  # new stance leg's centre of mass (at rL)
        vO = vH - B * _de(th1) * o2  # old stance leg, now swinging
        total = MH * cross(H - C, vH) + M * cross(rL - C, vN) + M * cross(rR - C, vO)
        return np.array([total, M * cross(rR - H, vO)])

    Qm = np.column_stack((pre(1, 0), pre(0, 1)))
    Qp = np.column_stack((post(1, 0), post(0, 1)))
    om = np.linalg.solve(Qp, Qm @ np.array([w1, w2]))
    return np.array([th2, th1, om[0], om[1]])


def classical_walk(x0: np.ndarray, steps: int, slope: float, tol: float) -> tuple[np.ndarray, int]:
    def mid(t: float, x: np.ndarray, slope: float) -> float:
        return float(x[0])

    def strike(t: float, x: np.ndarray, slope: float) -> float:
        return float(x[0] + x[1])

    for ev, d in ((mid, 1), (strike, 1)):
        ev.terminal, ev.direction = True, d  # type: ignore[attr-defined]
    x = np.asarray(x0, dtype=float)
    for k in range(steps):
        for ev in ((mid,) if x[0] < 0 else ()) + (strike,):
            sol = solve_ivp(classical_rhs, (0.0, 5.0), x, method="DOP853", rtol=tol, atol=tol,
                            events=ev, args=(slope,))
            if sol.status != 1:
                return x, k
            x = sol.y_events[0][0]
        x = classical_impact(x)
    return x, steps


def classical_map(z: np.ndarray, tol: float = 1e-12) -> np.ndarray:
    x0 = np.array([z[0], -z[0], z[1], z[1] + z[2]])
    x, n = classical_walk(x0, 1, SLOPE, tol)
    return np.array([x[0], x[2], x[3] - x[2]]) if n == 1 else np.full(3, np.nan)


# ---------------------------------------------------------------------------------------------
# Drake
# ---------------------------------------------------------------------------------------------
def drake_setup(tol: float) -> Any:
    from pydrake.examples import CompassGait as DrakeCompassGait
    from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator

    plant = DrakeCompassGait()
    sim = Simulator(plant)
    ctx = sim.get_mutable_context()
    p = ctx.get_mutable_numeric_parameter(0)
    p.set_mass_hip(MH)
    p.set_mass_leg(M)
    p.set_length_leg(L)
    p.set_center_of_mass_leg(B)
    p.set_gravity(G)
    p.set_slope(SLOPE)
    integ = ResetIntegratorFromFlags(sim, "runge_kutta5", 0.1)
    integ.set_target_accuracy(tol)
    ctx.SetAccuracy(tol)
    return sim


def drake_set(sim: Any, z: np.ndarray) -> None:
    ctx = sim.get_mutable_context()
    ctx.SetTime(0.0)
    ctx.get_mutable_discrete_state_vector().SetAtIndex(0, 0.0)
    q3, w3, w4 = z
    ctx.get_mutable_continuous_state_vector().SetFromVector(
        [q3 + SLOPE, -q3 + SLOPE, w3, w3 + w4]
    )
    sim.Initialize()


def drake_pre_impact(sim: Any, z: np.ndarray, steps: int) -> np.ndarray:
    """Drake's state just before each heel strike, walking ``steps`` steps from ``z``.

    Returned in heelstrike's slope-relative terms ``(q3, q4, q3_dot, q4_dot)``, shape
    (steps, 4). (Drake's monitor sees the state at the impact time before the reset; the first
    post-reset state it sees is one integrator step later, so the pre-impact section is used.)
    """
    from pydrake.systems.framework import EventStatus

    last: list[np.ndarray] = []
    pre: list[np.ndarray] = []

    def monitor(ctx: Any) -> Any:
        toe = ctx.get_discrete_state_vector().GetAtIndex(0)
        x = ctx.get_continuous_state_vector().CopyToVector()
        if last and toe != last[0][0]:
            pre.append(last[0][1:])
            if len(pre) == steps:
                return EventStatus.ReachedTermination(None, "done")
        last[:] = [np.concatenate(([toe], x))]
        return EventStatus.Succeeded()

    sim.set_monitor(monitor)
    drake_set(sim, z)
    sim.AdvanceTo(5.0 * steps)
    sim.clear_monitor()
    x = np.array(pre)
    return np.column_stack((x[:, 0] - SLOPE, x[:, 1] - x[:, 0], x[:, 2], x[:, 3] - x[:, 2]))


# ---------------------------------------------------------------------------------------------

def run(quick: bool = False) -> dict[str, Any]:
    rows: list[dict[str, Any]] = []
    notes: list[str] = []
    rep = 3 if quick else 7
    # -- fixed points ------------------------------------------------------------------------
    z_ref = find_limit_cycle(WALKER, slope=SLOPE, guess=[-0.27, 1.09, -0.72], rtol=1e-12,
                             atol=1e-12).fixed_point
    fps: dict[str, np.ndarray] = {}
    start = np.array([-0.26, 1.1, -0.7])  # every path's Newton starts here
    fps["compiled"] = find_limit_cycle(WALKER, slope=SLOPE, guess=start, method="compiled",
                                       rtol=1e-12, atol=1e-12, tol=1e-12).fixed_point
    fps["plain scipy"] = newton(classical_map, start, tol=1e-11)
    agree = ", ".join(f"{k} {np.max(np.abs(v - z_ref)):.1e}" for k, v in fps.items())
    notes.append(
        "fixed point z* = (q3, q3_dot, q4_dot) = ("
        + ", ".join(f"{v:.8f}" for v in z_ref)
        + ") from heelstrike's reference (simulate, rtol = atol = 1e-12); each path's own "
        f"fixed point (Newton from {start.tolist()}) differs from it by (max abs): {agree}"
    )
    drake_version = None
    try:
        import importlib.metadata

        import pydrake  # noqa: F401

        try:
            drake_version = importlib.metadata.version("drake")
        except importlib.metadata.PackageNotFoundError:
            drake_version = "(version unknown)"
    except ImportError:
        notes.append("drake not installed (`pip install drake`): its rows are skipped")
    if drake_version is not None:
        q, qd = WALKER.section_to_state(z_ref)
        rec = simulate(WALKER, q, qd, slope=SLOPE, steps=1, rtol=1e-12, atol=1e-12).impacts[0]
        ours = np.array([rec.q[2], rec.q[3], rec.q_dot_minus[2], rec.q_dot_minus[3]])
        pre = drake_pre_impact(drake_setup(1e-12), start, 60)
        fps["drake (pre-impact)"] = pre[-1]
        notes.append(
            "drake agreement: after 60 steps from the same start, Drake's attractor's pre-impact "
            "state (q3, q4, q3_dot, q4_dot) differs from heelstrike's pre-impact state on z* by "
            f"{np.max(np.abs(pre[-1] - ours)):.1e} (max abs; Drake accuracy 1e-12; its last two "
            f"steps differ by {np.max(np.abs(pre[-1] - pre[-2])):.1e})"
        )
    # -- single walker -----------------------------------------------------------------------
    n_fast = 200 if quick else 1000
    n_slow = 5 if quick else 20

    def single(path: str, steps: int, fn: Callable[[], Any]) -> None:
        t = median_time(fn, rep)
        rows.append({"table": "single", "path": path, "n": steps, "seconds": t,
                     "per_second": steps / t})

    single("heelstrike compiled (numba DP5, serial)", n_fast,
           lambda: ensemble_walk(WALKER, z_ref, SLOPE, steps=n_fast, rtol=TOL, atol=TOL,
                                 parallel=False))
    q0, qd0 = WALKER.section_to_state(z_ref)
    single("heelstrike reference simulate (scipy DOP853)", n_slow,
           lambda: simulate(WALKER, q0, qd0, slope=SLOPE, steps=n_slow, rtol=TOL, atol=TOL))
    x0 = np.array([z_ref[0], -z_ref[0], z_ref[1], z_ref[1] + z_ref[2]])
    single("plain solve_ivp loop (classical compass gait, DOP853)", n_slow,
           lambda: classical_walk(x0, n_slow, SLOPE, TOL))
    if drake_version is not None:
        sim = drake_setup(TOL)
        period = float(
            simulate(WALKER, q0, qd0, slope=SLOPE, steps=1, rtol=1e-12, atol=1e-12)
            .impacts[0].step_duration
        )
        n_drake = 20 if quick else 100

        def drake_walk() -> int:
            drake_set(sim, z_ref)
            u0 = sim.get_num_unrestricted_updates()
            sim.AdvanceTo((n_drake - 0.5) * period)
            return int(sim.get_num_unrestricted_updates() - u0)

        taken = drake_walk()
        if taken != n_drake - 1:
            notes.append(f"drake took {taken} steps in {n_drake - 0.5} periods")
        t = median_time(drake_walk, rep)
        rows.append({"table": "single", "path": f"drake {drake_version} CompassGait "
                     "(runge_kutta5, accuracy 1e-10)", "n": taken, "seconds": t,
                     "per_second": taken / t})
    base = rows[0]["per_second"]
    for r in rows:
        r["ratio"] = r["per_second"] / base
    # -- ensemble ----------------------------------------------------------------------------
    n_ens = 1000 if quick else 10_000
    steps_ens = 10
    rng = np.random.default_rng(0)
    Z = z_ref + rng.normal(0.0, 1e-3, (n_ens, 3))
    res = ensemble_walk(WALKER, Z, SLOPE, steps=steps_ens, rtol=TOL, atol=TOL, record=False)
    ok = int(np.sum(res.ok))
    t_ens = median_time(lambda: ensemble_walk(WALKER, Z, SLOPE, steps=steps_ens, rtol=TOL,
                                              atol=TOL, record=False), 3)
    sub = 4 if quick else 12

    def scipy_loop() -> None:
        for z in Z[:sub]:
            q, qd = WALKER.section_to_state(z)
            simulate(WALKER, q, qd, slope=SLOPE, steps=steps_ens, rtol=TOL, atol=TOL)

    t_sub = median_time(scipy_loop, 1 if quick else 3)
    ens_rate = n_ens * steps_ens / t_ens
    loop_rate = sub * steps_ens / t_sub
    rows.append({"table": "ensemble", "path": f"compiled ensemble_walk, {n_ens:,} walkers x "
                 f"{steps_ens} steps (prange, all cores)", "n": n_ens * steps_ens,
                 "seconds": t_ens, "per_second": ens_rate, "ratio": 1.0})
    rows.append({"table": "ensemble", "path": f"simulate loop per walker ({sub} walkers timed, "
                 f"extrapolated to {n_ens:,}: {n_ens / sub * t_sub:.0f} s)",
                 "n": sub * steps_ens, "seconds": t_sub, "per_second": loop_rate,
                 "ratio": loop_rate / ens_rate})
    notes.append(f"ensemble: {ok:,} of {n_ens:,} walkers completed all steps; compiled ensemble "
                 f"is {ens_rate / loop_rate:,.0f}x the per-walker rate of the scipy loop")
    # -- Newton ------------------------------------------------------------------------------
    guess = [-0.26, 1.1, -0.7]
    for method in ("scipy", "compiled"):
        t = median_time(lambda m=method: find_limit_cycle(WALKER, slope=SLOPE, guess=guess,
                                                          method=m), 1 if quick else 3)
        rows.append({"table": "tasks", "path": f"find_limit_cycle(method={method!r}), "
                     "rtol = atol = 1e-11", "n": 1, "seconds": t, "per_second": 1 / t})
    # -- basin -------------------------------------------------------------------------------
    grid = (100, 100) if quick else (400, 400)
    t0 = time.perf_counter()
    basin = basin_of_attraction(WALKER, SLOPE, grid=grid, fixed_point=z_ref)
    t_basin = time.perf_counter() - t0
    rows.append({"table": "tasks", "path": f"basin_of_attraction {grid[0]}x{grid[1]}, up to 60 "
                 "steps, rtol 1e-8 (all cores)", "n": grid[0] * grid[1], "seconds": t_basin,
                 "per_second": grid[0] * grid[1] / t_basin})
    notes.append(f"basin (R = 0, 3 deg, q3 in [-0.5, -0.05] rad, q3_dot in [0.3, 2.3] rad/s, "
                 f"q4_dot = q4_dot*): converging fraction {basin.converging_fraction:.4f}")
    # -- reproduce from a cold start ---------------------------------------------------------
    exe = Path(sys.executable).with_name("heelstrike")
    with tempfile.TemporaryDirectory() as tmp:
        times = []
        for _ in range(1 if quick else 3):
            t0 = time.perf_counter()
            subprocess.run([str(exe), "reproduce", "--out", tmp], check=True,
                           capture_output=True)
            times.append(time.perf_counter() - t0)
    rows.append({"table": "tasks", "path": "`heelstrike reproduce` (new process, cold start)",
                 "n": 1, "seconds": statistics.median(times),
                 "per_second": 1 / statistics.median(times)})
    return {"benchmark": "passive walking", "machine": machine(), "rows": rows, "notes": notes,
            "fixed_points": {k: v.tolist() for k, v in fps.items()}, "reference": z_ref.tolist()}


def format_table(result: dict[str, Any]) -> str:
    rows = result["rows"]
    lines = [
        f"**{result['benchmark']}: one walker, steps per second at rtol = atol = 1e-10** "
        f"({result['machine']})",
        "",
        "| path | steps | median time (s) | steps/s | ratio to compiled |",
        "|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        if r["table"] == "single":
            lines.append(f"| {r['path']} | {r['n']:,} | {r['seconds']:.4g} | "
                         f"{r['per_second']:,.0f} | {r['ratio']:.3g} |")
    lines += ["", "**walking ensemble: walker-steps per second**", "",
              "| path | walker-steps | median time (s) | walker-steps/s | ratio to compiled |",
              "|---|---:|---:|---:|---:|"]
    for r in rows:
        if r["table"] == "ensemble":
            lines.append(f"| {r['path']} | {r['n']:,} | {r['seconds']:.4g} | "
                         f"{r['per_second']:,.0f} | {r['ratio']:.3g} |")
    lines += ["", "**tasks: wall time**", "", "| task | median time (s) |", "|---|---:|"]
    for r in rows:
        if r["table"] == "tasks":
            lines.append(f"| {r['path']} | {r['seconds']:.4g} |")
    lines += [""] + [f"- {note}" for note in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv, quick_help="small sizes (smoke test)")


if __name__ == "__main__":
    sys.exit(main())
