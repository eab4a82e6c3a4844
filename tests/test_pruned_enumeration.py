"""Issue #34: the branch-and-bound enumeration of active sets finds exactly the full one's.

Oracle: the exhaustive enumeration of every active set (``_enumerate`` below its budget), each
decided by the same exact test (``_try_set``). The pruned tree must return the same consistent
sets, in the same order, with the same impulses: a node pruned wrongly (an LP declared
infeasible, a Carathéodory test on a subset) shows as a missing set.
"""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.core import complementarity as cc

MASS = 12.0
HEIGHT = 0.4


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _problem(corners: list[tuple[float, float]], mu: float) -> tuple[object, object, np.ndarray]:
    """A free rigid body (``M`` (6, 6) for the twist of its centre of mass) over a sole whose
    corners are ``(x, y)`` at ``z = -HEIGHT``; rows stacked ``(n, t_x, t_y)`` per corner."""
    M = np.zeros((6, 6))
    M[:3, :3] = MASS * np.eye(3)
    M[3:, 3:] = np.diag([0.9, 0.7, 0.5])
    rows = []
    for x, y in corners:
        J = np.hstack((np.eye(3), -_skew(np.array([x, y, -HEIGHT]))))
        rows += [J[2], J[0], J[1]]
    R = np.array(rows)
    m = len(corners)
    lay = cc._Layout(principal=tuple(3 * i for i in range(m)), extra=((),) * m,
                     tangential=tuple((3 * i + 1, 3 * i + 2) for i in range(m)))
    red = cc._reduce(M, np.zeros((0, 6)), R)
    return red, lay, R


TRIANGLE = [(0.1, 0.05), (-0.1, 0.05), (0.0, -0.05)]
TWIST = {
    "flat landing": [0.0, 0.0, -1.0, 0.0, 0.0, 0.0],
    "small slide": [0.05, 0.02, -1.0, 0.0, 0.0, 0.0],
    "large slide": [2.0, 0.3, -1.0, 0.0, 0.0, 0.0],
    "tilted": [0.0, 0.0, -1.0, 2.0, 0.0, 0.0],
    "spinning": [0.0, 0.0, -1.0, 0.0, 0.0, 3.0],
}


@pytest.mark.parametrize("name", list(TWIST))
@pytest.mark.parametrize("mu", [0.5])
def test_pruned_tree_finds_the_full_enumerations_sets(name: str, mu: float) -> None:
    red, lay, R = _problem(TRIANGLE, mu)
    v = np.array(TWIST[name])
    u0, tau, mus = R @ v, np.zeros(R.shape[0]), np.full(len(TRIANGLE), mu)
    full, exhaustive, count = cc._enumerate(red, u0, tau, mus, lay, 10_000, 2.0,
                                            np.zeros(len(TRIANGLE), dtype=bool))
    assert exhaustive and count == 10 ** 3 and full
    vtol = 1e-9 * max(float(np.max(np.abs(u0))), 2.0)
    pruned = cc._enumerate_pruned(red, u0, tau, mus, lay, 10_000, vtol,
                                  max(float(np.max(np.abs(u0))), 2.0))
    assert pruned is not None
    assert [s.key for s in pruned] == [s.key for s in full]
    for a, b in zip(pruned, full, strict=True):
        np.testing.assert_array_equal(a.f, b.f)
        assert a.impulse_free == b.impulse_free and len(a.ends) == len(b.ends)


def test_pruned_tree_declines_unbounded_cones_and_a_small_node_budget() -> None:
    """Infinite friction (free sticking impulses: the Carathéodory test is not monotone) is
    not its case; a node budget too small for the tree gives None, never a partial list."""
    red, lay, R = _problem(TRIANGLE, 0.5)
    v = np.array(TWIST["flat landing"])
    u0, tau = R @ v, np.zeros(R.shape[0])
    assert cc._enumerate_pruned(red, u0, tau, np.full(3, np.inf), lay, 10_000, 1e-9,
                                1.0) is None
    assert cc._enumerate_pruned(red, u0, tau, np.full(3, 0.5), lay, 3, 1e-9, 1.0) is None
