"""The one continuation engine (``heelstrike.analysis._continuation.follow``).

Every continuation runs it: the gait maps, the described walkers' search from the walker file's
gait, ``continue_limit_cycle`` (the bifurcation branch) and the powered searches. Checked here
on a problem with a known branch and fold, and on ``continue_limit_cycle``, which took one
Newton step per value before and so jumped between gait families on coarse grids.
"""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike._typing import FloatArray
from heelstrike.analysis._continuation import Point, follow, follow_both_ways
from heelstrike.analysis.limit_cycle import GaitNotFoundError, continue_limit_cycle
from heelstrike.models import CompassGait


def _fold_problem(fold: float = 2.5) -> tuple[list[float], object]:
    """Roots of ``z^2 = fold - v`` on the branch ``z = sqrt(fold - v) > 0``: a fold at
    ``v = fold``, where Newton fails; every accepted value is recorded."""
    calls: list[float] = []

    def solve(v: float, z: FloatArray, max_iter: int) -> tuple[object, FloatArray, int, float]:
        calls.append(v)
        if v >= fold:
            raise GaitNotFoundError(f"no root at {v}")
        x = float(z[0]) if z[0] > 0 else 1.0
        for it in range(1, max_iter + 1):
            dx = (x * x - (fold - v)) / (2 * x)
            x -= dx
            if abs(dx) < 1e-14:
                return None, np.array([x]), it, float("nan")
        raise GaitNotFoundError("slow")

    return calls, solve


def test_follow_reaches_targets_on_the_branch_and_stops_at_the_fold() -> None:
    _calls, solve = _fold_problem()
    start = Point(value=0.0, z=np.array([np.sqrt(2.5)]), mnr=float("nan"), gait=None)
    got, path = follow(solve, start, [1.0, 2.0, 2.45, 3.0], 0.5)
    for t, p in zip([1.0, 2.0, 2.45], got[:3], strict=True):
        assert p is not None and p.value == t
        assert p.z[0] == pytest.approx(np.sqrt(2.5 - t), rel=1e-12)
    assert got[3] is None  # past the fold
    # the branch ends within the smallest sub-step (0.5 / 32) of the fold
    assert 2.5 - 0.5 / 32 <= path[-1].value < 2.5
    assert all(np.diff([p.value for p in path]) > 0)


def test_follow_rejects_a_jump_and_halves_the_step() -> None:
    """A corrector that lands far from the prediction (another branch) is refused: the engine
    halves the sub-step until the prediction is close, so the branch is kept."""

    def solve(v: float, z: FloatArray, max_iter: int) -> tuple[object, FloatArray, int, float]:
        # two branches z = v and z = v + 1; Newton goes to the nearer one of the guess
        lo, hi = v, v + 1.0
        z_new = lo if abs(z[0] - lo) <= abs(z[0] - hi) else hi
        return None, np.array([z_new]), 1, float("nan")

    start = Point(value=0.0, z=np.array([0.0]), mnr=float("nan"), gait=None)
    # the first sub-step (to v = 1) predicts z = 0 (no secant yet): Newton lands on the lower
    # branch at z = 1, 1.0 from the prediction, more than max_jump: refused, and the sub-step
    # halved until the corrector stays within 0.3 of its prediction
    got, path = follow(solve, start, [1.0], 1.0, max_jump=0.3)
    assert got[0] is not None and got[0].z[0] == pytest.approx(1.0)
    assert len(path) > 2  # sub-steps were taken
    assert all(abs(p.z[0] - p.value) < 1e-15 for p in path)  # never on the upper branch


def test_exact_reach() -> None:
    """With ``reach_tol=0`` a target is solved at exactly its value."""
    calls, solve = _fold_problem(fold=10.0)
    start = Point(value=0.1, z=np.array([np.sqrt(9.9)]), mnr=float("nan"), gait=None)
    target = 0.1 + 0.3  # not representable as the sum of the sub-steps
    got, _ = follow(solve, start, [target], 0.1, reach_tol=0.0)
    assert got[0] is not None and got[0].value == target
    assert calls[-1] == target


def test_follow_both_ways_sorts_its_points() -> None:
    _, solve = _fold_problem(fold=5.0)
    start = Point(value=1.0, z=np.array([2.0]), mnr=float("nan"), gait=None)
    got, points = follow_both_ways(solve, start, np.array([3.0, 0.0, 2.0, -1.0]), 0.5)
    assert [p.value for p in got if p is not None] == [3.0, 0.0, 2.0, -1.0]
    values = [p.value for p in points]
    assert values == sorted(values) and values[0] == -1.0 and values[-1] == 3.0


@pytest.mark.slow
def test_continue_limit_cycle_does_not_depend_on_the_grid() -> None:
    """R = 0.6 m from 1 to 6 deg: three values (2.5 deg apart) give the gaits of the same branch
    as eleven values, to Newton's tolerance; each is a gait at its slope."""
    walker = CompassGait(foot_radius=0.6)
    coarse = continue_limit_cycle(walker, "slope", np.deg2rad([1.0, 3.5, 6.0]),
                                  method="compiled")
    fine = continue_limit_cycle(walker, "slope", np.deg2rad(np.linspace(1.0, 6.0, 11)),
                                method="compiled")
    assert coarse.stopped is None and fine.stopped is None
    for c, f in zip(coarse.cycles, (fine.cycles[0], fine.cycles[5], fine.cycles[10]),
                    strict=True):
        np.testing.assert_allclose(c.fixed_point, f.fixed_point, atol=1e-8)
        assert c.stable == f.stable
