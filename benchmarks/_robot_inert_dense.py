"""Frozen copy of heelstrike's inert robot impact before the tree path (the baseline).

As it stood on 2026-11-28 (commit d8e3bdd): :func:`robot_impact` with kept contacts only built
the symmetrised ``M`` (``crba``) and the rows (``computeJointJacobians`` + frame Jacobians),
then solved with the dense LAPACK path :func:`heelstrike.core.contact_laws.
inert_contact_impact` (checked) and wrapped the result in ``RobotImpact``;
:func:`inert_energy_split_batch` filled stacks of ``M`` and rows chunk by chunk and solved them
with numpy's stacked solvers (``inert_contact_impact_batch``, after ``check_inert_batch``).
Kept here, unchanged in substance, so that ``bench_robot.py`` times the old path next to the
new one in the same run; the library itself no longer uses it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from heelstrike.core.contact_laws import (
    InertImpactBatch,
    check_inert_batch,
    inert_contact_impact,
    inert_contact_impact_batch,
)
from heelstrike.robots.contacts import (
    _FLAT,
    ContactSpec,
    RobotImpact,
    _assemble,
    _matrices,
    _row_plan,
    _tilting,
)
from heelstrike.robots.loading import Robot, _pin


def robot_impact_dense(robot: Robot, q: Any, v: Any, keep: Sequence[ContactSpec]) -> RobotImpact:
    """The old ``robot_impact(robot, q, v, keep=keep)`` (no strike): dense LAPACK path."""
    specs = tuple(keep)
    q_, v_ = robot.check_state(q, v)
    bil = tuple([True] * len(specs))
    plan = _row_plan(robot, specs)
    M, A = _matrices(robot, plan, q_)
    jacs = tuple(A[sl] for sl in plan.layout.slices)
    flats = [i for i, sp in enumerate(specs) if sp.kind in _FLAT]
    rot = {}
    if flats:
        _pin().updateFramePlacements(robot.model, robot.data)
        rot = {i: np.array(robot.data.oMf[robot.frame_id(specs[i].frame)].rotation)
               for i in flats}
    if any(not np.any(J) for J in jacs):
        raise ValueError("contact rows are rank deficient (redundant contacts?)")
    res = inert_contact_impact(M, v_, A, plan.layout)
    return RobotImpact(contacts=specs, bilateral=bil, result=res, M=M, jacobians=jacs,
                       tilting=_tilting(specs, bil, res, rot,
                                        ((i,) for i in range(len(specs))), M))


def inert_energy_split_batch_dense(robot: Robot, qs: np.ndarray, vs: np.ndarray,
                                   contacts: Sequence[ContactSpec], *, chunk: int = 256,
                                   check: bool = True) -> InertImpactBatch:
    """The old ``inert_energy_split_batch``: stacks of ``M`` and rows, numpy's solvers."""
    q_all = robot.check_states(qs)
    v_all = np.asarray(vs, dtype=float)
    plan = _row_plan(robot, tuple(contacts))
    size = max(1, min(int(chunk), q_all.shape[0]))
    Ms = np.empty((size, robot.nv, robot.nv))
    As = np.empty((size, plan.k, robot.nv))
    parts = []
    for i in range(0, q_all.shape[0], size):
        q_c = q_all[i:i + size]
        B = q_c.shape[0]
        _assemble(robot, plan, q_c, Ms, As)
        v_c = v_all[i:i + size]
        if check:  # M is symmetric by construction
            check_inert_batch(Ms[:B], v_c, As[:B], symmetric=True)
        parts.append(inert_contact_impact_batch(Ms[:B], v_c, As[:B], plan.layout, check=False))
    return InertImpactBatch(**{
        f.name: np.concatenate([getattr(p, f.name) for p in parts])
        for f in dataclasses.fields(InertImpactBatch)
    })
