"""Impact decompositions per second: heelstrike's paths and Pinocchio's ``impulseDynamics``.

All paths resolve the same heel strike of the paper's compass gait (mH = 2 m = 10 kg,
a = b = 0.5 m, l = 1 m) at random impact angles q3 in [0.02, pi/4] rad and foot radii R in
[0, 1] m, with q3_dot = 1 rad/s, q4_dot = 0 and the stance foot rolling (the paper's model,
see heelstrike.models.compass).

Paths
-----
fast        ``heelstrike.models.compass_fast.heel_strike_impact`` (compiled closed form), batched.
reference   ``heelstrike.core.impact.impact`` on ``CompassGait`` matrices, batched numpy
            (matrix assembly included).
loop        the same, one configuration per Python call.
pinocchio   ``pinocchio.impulseDynamics(model, data, q, v, J)`` per call, on the compass gait
            built as a Pinocchio model (planar floating base: prismatic x, y; revolute stance
            leg and hip; point masses), ``J`` the striking foot's rolling-contact Jacobian
            computed by Pinocchio from its frame Jacobian. Timed with ``J`` precomputed.

Before timing, Pinocchio's mass matrix, contact Jacobian and ``q_dot+`` are compared with
heelstrike's on random configurations; the largest differences are reported.

Run ``python benchmarks/bench_impact.py`` (``--quick`` for a smoke run, ``--json PATH`` to save
the rows). Times are medians of repeated runs in one process; see ``benchmarks/README.md``.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from _common import machine, run_main

from heelstrike.core.impact import impact
from heelstrike.models.compass import CompassGait, heel_strike_state
from heelstrike.models.compass_fast import heel_strike_impact

WALKER = CompassGait()


def configurations(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random impact angles (rad) and foot radii (m)."""
    rng = np.random.default_rng(seed)
    return rng.uniform(0.02, np.pi / 4, n), rng.uniform(0.0, 1.0, n)


def median_time(fn: Callable[[], object], repeats: int) -> float:
    """Median wall time (s) of ``repeats`` calls after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def reference_batched(q3: np.ndarray, R: np.ndarray) -> object:
    walker = WALKER.replace(foot_radius=R)
    q, qd = heel_strike_state(walker, q3)
    return impact(walker.mass_matrix(q), walker.contact_jacobian(q, "left"), qd)


def reference_loop(q3: np.ndarray, R: np.ndarray) -> None:
    for a, r in zip(q3, R, strict=True):
        walker = WALKER.replace(foot_radius=float(r))
        q, qd = heel_strike_state(walker, float(a))
        impact(walker.mass_matrix(q), walker.contact_jacobian(q, "left"), qd)


# -- Pinocchio ----------------------------------------------------------------------------------
def pinocchio_compass(foot_radius: float, walker: CompassGait = WALKER) -> tuple[Any, Any, int]:
    """The compass gait as a Pinocchio model; returns ``(model, data, left_foot_frame_id)``.

    Joints: prismatic x, prismatic y (``q1, q2``: the stance foot's arc centre), revolute z at
    that centre (``q3``, stance leg angle), revolute z at the hip (``q4``, relative swing
    angle). A revolute z joint maps a point ``(0, d)`` of its frame to ``d e(theta)``, the
    paper's convention (heelstrike.models.compass). Legs and hip are point masses (zero
    rotational inertia).
    """
    import pinocchio as pin

    s = float(walker.leg_length) - foot_radius
    b = float(walker.leg_com_from_hip)
    m, mH, inertia = float(walker.leg_mass), float(walker.hip_mass), float(walker.leg_inertia)
    model = pin.Model()
    eye = pin.SE3.Identity()
    jx = model.addJoint(0, pin.JointModelPX(), eye, "q1")
    jy = model.addJoint(jx, pin.JointModelPY(), eye, "q2")
    j3 = model.addJoint(jy, pin.JointModelRZ(), eye, "q3")
    hip = pin.SE3(np.eye(3), np.array([0.0, s, 0.0]))
    j4 = model.addJoint(j3, pin.JointModelRZ(), hip, "q4")

    def point(mass: float, y: float, rot: float = 0.0) -> Any:
        return pin.Inertia(mass, np.array([0.0, y, 0.0]), rot * np.eye(3))

    model.appendBodyToJoint(j3, point(m, s - b, inertia), eye)  # stance leg
    model.appendBodyToJoint(j3, point(mH, s), eye)  # hip
    model.appendBodyToJoint(j4, point(m, -b, inertia), eye)  # swing leg
    foot = model.addFrame(
        pin.Frame("left_foot_centre", j4, pin.SE3(np.eye(3), np.array([0.0, -s, 0.0])),
                  pin.FrameType.OP_FRAME)
    )
    model.gravity.linear = np.array([0.0, -float(walker.gravity), 0.0])
    return model, model.createData(), foot


def pinocchio_contact_jacobian(model: Any, data: Any, foot: int, q: np.ndarray, R: float) -> Any:
    """Rolling contact of the left foot: velocity of ``P_L`` plus ``omega x (0, -R)``."""
    import pinocchio as pin

    J6 = pin.computeFrameJacobian(model, data, q, foot, pin.LOCAL_WORLD_ALIGNED)
    A = J6[:2].copy()
    A[0] += R * J6[5]  # omega_z z x (0, -R) = (R omega_z, 0)
    return A


def pinocchio_agreement(n: int) -> dict[str, float]:
    """Largest differences between Pinocchio and heelstrike on ``n`` random configurations."""
    import pinocchio as pin

    q3s, Rs = configurations(n, seed=1)
    rng = np.random.default_rng(2)
    worst = {"mass_matrix": 0.0, "contact_jacobian": 0.0, "q_dot_post": 0.0, "impulse": 0.0}
    for a, r in zip(q3s, Rs, strict=True):
        walker = WALKER.replace(foot_radius=float(r))
        w3, w4 = rng.normal(size=2)
        q, qd = heel_strike_state(walker, float(a), q3_dot=w3, q4_dot=w4)
        model, data, foot = pinocchio_compass(float(r))
        M_pin = pin.crba(model, data, q)
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        A_pin = pinocchio_contact_jacobian(model, data, foot, q, float(r))
        v_pin = pin.impulseDynamics(model, data, q, qd, A_pin, 0.0, 0.0)
        fast = heel_strike_impact(float(a), foot_radius=float(r), q3_dot=w3, q4_dot=w4)
        M = walker.mass_matrix(q)
        worst["mass_matrix"] = max(worst["mass_matrix"], float(np.max(np.abs(M_pin - M))))
        worst["contact_jacobian"] = max(
            worst["contact_jacobian"],
            float(np.max(np.abs(A_pin - walker.contact_jacobian(q, "left")))),
        )
        scale = float(np.max(np.abs(qd)))
        worst["q_dot_post"] = max(
            worst["q_dot_post"], float(np.max(np.abs(v_pin - fast.velocity_post))) / scale
        )
        worst["impulse"] = max(
            worst["impulse"],
            float(np.max(np.abs(np.asarray(data.impulse_c) - fast.constraint_impulse)))
            / (float(WALKER.total_mass) * scale),
        )
    return worst


def pinocchio_loop(items: list[tuple[Any, Any, np.ndarray, np.ndarray, np.ndarray]]) -> None:
    import pinocchio as pin

    for model, data, q, v, A in items:
        pin.impulseDynamics(model, data, q, v, A, 0.0, 0.0)


# -- main ---------------------------------------------------------------------------------------
def run(quick: bool = False) -> dict[str, Any]:
    machine_info = machine()
    n_fast = 100_000 if quick else 1_000_000
    n_ref = 20_000 if quick else 200_000
    n_loop = 200 if quick else 2_000
    reps = 3 if quick else 7
    rows: list[dict[str, Any]] = []
    notes: list[str] = []

    def add(path: str, n: int, seconds: float) -> None:
        rows.append({"path": path, "n": n, "seconds": seconds, "per_second": n / seconds})

    q3, R = configurations(n_fast)
    add("heelstrike fast (compass closed form, numba)", n_fast,
        median_time(lambda: heel_strike_impact(q3, foot_radius=R), reps))
    add("heelstrike reference core.impact, batched numpy", n_ref,
        median_time(lambda: reference_batched(q3[:n_ref], R[:n_ref]), max(3, reps // 2)))
    add("heelstrike reference core.impact, Python loop", n_loop,
        median_time(lambda: reference_loop(q3[:n_loop], R[:n_loop]), 3))

    agreement: dict[str, float] | None = None
    try:
        import pinocchio as pin
    except ImportError:
        notes.append("pinocchio: not installed (pip install '.[bench]'), skipped")
    else:
        agreement = pinocchio_agreement(200 if quick else 1000)
        items = []
        for a, r in zip(q3[:n_loop], R[:n_loop], strict=True):
            model, data, foot = pinocchio_compass(float(r))
            qq, vv = heel_strike_state(WALKER.replace(foot_radius=float(r)), float(a))
            items.append((model, data, qq, vv,
                          pinocchio_contact_jacobian(model, data, foot, qq, float(r))))
        add(f"pinocchio {pin.__version__} impulseDynamics, Python loop (J given)", n_loop,
            median_time(lambda: pinocchio_loop(items), 3))
        notes.append(
            "pinocchio agreement over random configurations (max abs difference): "
            + ", ".join(f"{k} {v:.1e}" for k, v in agreement.items())
            + " (q_dot_post relative to max|q_dot-|, impulse to total mass * max|q_dot-|)"
        )
    fastest = rows[0]["per_second"]
    for row in rows:
        row["ratio_to_fast"] = row["per_second"] / fastest
    return {
        "benchmark": "impact decompositions per second",
        "machine": machine_info,
        "rows": rows,
        "notes": notes,
        "pinocchio_agreement": agreement,
    }



def format_table(result: dict[str, Any]) -> str:
    lines = [
        f"**{result['benchmark']}** ({result['machine']})",
        "",
        "| path | batch / calls | median time (s) | decompositions/s | ratio to fast |",
        "|---|---:|---:|---:|---:|",
    ]
    for row in result["rows"]:
        lines.append(
            f"| {row['path']} | {row['n']:,} | {row['seconds']:.4g} | "
            f"{row['per_second']:,.0f} | {row['ratio_to_fast']:.2g} |"
        )
    lines += [""] + [f"- {note}" for note in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv, quick_help="small sizes (smoke test)")


if __name__ == "__main__":
    sys.exit(main())
