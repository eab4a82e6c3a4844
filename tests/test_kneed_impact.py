"""Knee strike and heel strike of the kneed walker vs an independent momentum derivation.

The reference here does not use the builder's equations: the kinematics of the kneed walker are
written out by hand (points as sums of ``c e(theta)``, ``e = (-sin, cos)``), and the post-impact
velocity follows from angular-momentum conservation laws:

- knee strike (stance foot rolling, stance knee locked, swing knee locks): the angular momentum
  of the whole walker about the stance contact point (the ground impulse acts there) and of the
  swing leg (thigh + shank) about the hip (the only external impulse on it acts at the hip) are
  unchanged;
- heel strike with both knees locked, trailing foot lifting: the angular momentum of the whole
  walker about the leading contact point and of the trailing leg about the hip are unchanged.

Together with the kinematic constraints these fix the post-impact velocity (2 unknown rates).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import null_space

from heelstrike.core import impact
from heelstrike.core.complementarity import CandidateContact, resolve_impact
from heelstrike.models.builder import BuiltWalker, load_walker


@pytest.fixture(scope="module", autouse=True)
def _cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    d = tmp_path_factory.mktemp("hs_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("HEELSTRIKE_CACHE_DIR", str(d))
        yield d


PARAMS = {"R": 0.12, "It": 0.004, "Is": 0.001}


@pytest.fixture(scope="module")
def walker() -> BuiltWalker:
    return load_walker("kneed", **PARAMS)


# -- hand-written kinematics ---------------------------------------------------------------------


def _e(th: float) -> np.ndarray:
    return np.array([-np.sin(th), np.cos(th)])


def _de(th: float) -> np.ndarray:
    return np.array([-np.cos(th), -np.sin(th)])


class Hand:
    """Independent kinematics of the kneed walker: bodies, positions and velocities."""

    def __init__(self, p: dict[str, float]) -> None:
        self.p = p
        self.ls = p["a1"] + p["b1"]
        self.lt = p["a2"] + p["b2"]

    def angles(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Absolute angles of shank1, thigh1, thigh2, shank2 and their rows d theta / d q."""
        W = np.array(
            [[0, 0, 1, 0, 0, 0], [0, 0, 1, 1, 0, 0], [0, 0, 1, 1, 1, 0], [0, 0, 1, 1, 1, 1]],
            dtype=float,
        )
        return W @ q, W

    def points(self, q: np.ndarray, qd: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """(position, velocity) of the named points."""
        p, R = self.p, self.p["R"]
        th, W = self.angles(q)
        w = W @ qd
        C = q[:2]
        vC = qd[:2]

        # chain of terms (coefficient, link index)
        def pt(terms: list[tuple[float, int]]) -> tuple[np.ndarray, np.ndarray]:
            r = C.copy()
            v = vC.copy()
            for c, k in terms:
                r = r + c * _e(th[k])
                v = v + c * w[k] * _de(th[k])
            return r, v

        knee1 = [(-R, 0), (self.ls, 0)]
        hip = [*knee1, (self.lt, 1)]
        knee2 = [*hip, (-self.lt, 2)]
        return {
            "shank1": pt([(-R, 0), (p["a1"], 0)]),
            "thigh1": pt([*knee1, (p["a2"], 1)]),
            "hip": pt(hip),
            "thigh2": pt([*hip, (-p["b2"], 2)]),
            "shank2": pt([*knee2, (-p["b1"], 3)]),
            "foot2": pt([*knee2, (-(self.ls - R), 3)]),
        }

    def bodies(self) -> dict[str, tuple[float, float, int]]:
        """name -> (mass, inertia, link index or -1 for the point mass)."""
        p = self.p
        return {
            "shank1": (p["ms"], p["Is"], 0),
            "thigh1": (p["mt"], p["It"], 1),
            "hip": (p["mH"], 0.0, -1),
            "thigh2": (p["mt"], p["It"], 2),
            "shank2": (p["ms"], p["Is"], 3),
        }

    def angular_momentum(
        self, q: np.ndarray, qd: np.ndarray, about: np.ndarray, which: tuple[str, ...]
    ) -> float:
        pts = self.points(q, qd)
        _, W = self.angles(q)
        w = W @ qd
        L = 0.0
        for name in which:
            m, inertia, k = self.bodies()[name]
            r, v = pts[name]
            d = r - about
            L += m * (d[0] * v[1] - d[1] * v[0]) + (inertia * w[k] if k >= 0 else 0.0)
        return L

    def rolling_rows(self, q: np.ndarray, foot: str) -> np.ndarray:
        """Rows (2, 6) of the rolling constraint of a foot.

        The material contact point sits ``R`` below the arc centre ``c``: its velocity is
        ``v_c + omega k x (0, -R) = v_c + (R omega, 0)``.
        """
        R = self.p["R"]
        rows = np.zeros((2, 6))
        for j in range(6):
            e_j = np.eye(6)[j]
            _, W = self.angles(q)
            if foot == "stance":
                vc, omega = e_j[:2], (W @ e_j)[0]
            else:
                vc, omega = self.points(q, e_j)["foot2"][1], (W @ e_j)[3]
            rows[:, j] = vc + np.array([R * omega, 0.0])
        return rows


def _solve_by_momentum(
    hand: Hand,
    q: np.ndarray,
    qd: np.ndarray,
    constraint_rows: np.ndarray,
    laws: list[tuple[np.ndarray, tuple[str, ...]]],
) -> np.ndarray:
    """Post-impact velocity in the null space of ``constraint_rows`` conserving the ``laws``."""
    N = null_space(constraint_rows)
    assert N.shape[1] == len(laws)
    G = np.zeros((len(laws), N.shape[1]))
    rhs = np.zeros(len(laws))
    for i, (about, which) in enumerate(laws):
        rhs[i] = hand.angular_momentum(q, qd, about, which)
        for j in range(N.shape[1]):
            G[i, j] = hand.angular_momentum(q, N[:, j], about, which)
    return N @ np.linalg.solve(G, rhs)


ALL = ("shank1", "thigh1", "hip", "thigh2", "shank2")


def test_hand_kinematics_agree_with_builder(walker: BuiltWalker) -> None:
    """Sanity of the reference itself: same points and same kinetic energy."""
    hand = Hand(walker.parameters)
    rng = np.random.default_rng(2)
    for _ in range(5):
        q, qd = rng.normal(size=6) * 0.5, rng.normal(size=6)
        pts = hand.points(q, qd)
        pos = walker.positions(q)
        np.testing.assert_allclose(pts["hip"][0], pos["hip"], atol=1e-14)
        np.testing.assert_allclose(pts["foot2"][0], pos["swing_foot.centre"], atol=1e-14)
        T = 0.0
        _, W = hand.angles(q)
        for name, (m, inertia, k) in hand.bodies().items():
            v = pts[name][1]
            T += 0.5 * m * v @ v + (0.5 * inertia * (W @ qd)[k] ** 2 if k >= 0 else 0.0)
        assert walker.kinetic_energy(q, qd) == pytest.approx(T, rel=1e-13)


@pytest.mark.parametrize("seed", range(5))
def test_knee_strike_conserves_the_right_angular_momenta(walker: BuiltWalker, seed: int) -> None:
    hand = Hand(walker.parameters)
    rng = np.random.default_rng(seed)
    R = walker.parameters["R"]
    # single support, stance knee locked (q3 = 0), swing knee reaching its lock (q5 = 0)
    q = np.array([0.0, R, rng.uniform(-0.3, 0.1), 0.0, rng.uniform(0.2, 0.6), 0.0])
    w3, w4 = rng.uniform(0.3, 1.5), rng.uniform(0.5, 3.0)
    qd = np.array([-R * w3, 0.0, w3, 0.0, w4, -rng.uniform(1.0, 4.0)])  # knee extending
    A_R = walker.contact_jacobian(q, "right")
    np.testing.assert_allclose(A_R @ qd, 0.0, atol=1e-15)
    A = np.vstack((A_R, walker.lock_jacobian()))  # rolling foot + both knee locks
    res = impact(walker.mass_matrix(q), A, qd)
    # independent reference
    Ac = hand.rolling_rows(q, "stance")
    cons = np.vstack((Ac, np.eye(6)[[3, 5]]))
    contact = q[:2] - np.array([0.0, R])
    hip = hand.points(q, qd)["hip"][0]
    v_ref = _solve_by_momentum(hand, q, qd, cons, [(contact, ALL), (hip, ("thigh2", "shank2"))])
    np.testing.assert_allclose(res.velocity_post, v_ref, rtol=1e-10, atol=1e-12)
    # the knee impulse is the one on the swing knee row; a lock pushes against the extension
    assert res.constraint_impulse[3] > 0.0
    assert float(res.energy_lost) > 0.0
    # the result also conserves the laws it was not built from (sanity of the reference)
    L0 = hand.angular_momentum(q, qd, contact, ALL)
    assert hand.angular_momentum(q, res.velocity_post, contact, ALL) == pytest.approx(L0, rel=1e-11)


@pytest.mark.parametrize("q2", [0.15, 0.25, 0.35])
def test_heel_strike_with_knee_locks(walker: BuiltWalker, q2: float) -> None:
    """Both knees locked at heel strike; the trailing foot lifts (checked by complementarity)."""
    hand = Hand(walker.parameters)
    R = walker.parameters["R"]
    # straight legs, symmetric: the swing foot touches the ground ahead (q4 = -2 q2)
    q = np.array([0.0, R, q2, 0.0, -2.0 * q2, 0.0])
    assert walker.foot_clearance(q, "left") == pytest.approx(0.0, abs=1e-14)
    qd = np.array([-R * 1.0, 0.0, 1.0, 0.0, 0.3, 0.0])
    M = walker.mass_matrix(q)
    A_L = walker.contact_jacobian(q, "left")
    locks = walker.lock_jacobian()
    bil = np.vstack((A_L, locks))
    res = impact(M, bil, qd)
    # trailing (stance) foot as a unilateral candidate
    mc = resolve_impact(
        M, qd, bil, [CandidateContact.from_jacobian(walker.contact_jacobian(q, "right"))]
    )
    assert mc.modes == ("separate",)
    np.testing.assert_allclose(mc.velocity_post, res.velocity_post, atol=1e-13)
    assert (walker.contact_jacobian(q, "right") @ res.velocity_post)[1] > 0.0
    # independent reference
    cons = np.vstack((hand.rolling_rows(q, "swing"), np.eye(6)[[3, 5]]))
    np.testing.assert_allclose(cons[:2], A_L, atol=1e-14)  # same constraint geometry
    pts = hand.points(q, qd)
    lead_contact = pts["foot2"][0] - np.array([0.0, R])
    v_ref = _solve_by_momentum(
        hand,
        q,
        qd,
        cons,
        [(lead_contact, ALL), (pts["hip"][0], ("shank1", "thigh1"))],
    )
    np.testing.assert_allclose(res.velocity_post, v_ref, rtol=1e-10, atol=1e-12)
    # after the swap the knees are still locked and the new stance foot rolls
    qs, qds = walker.swap_legs(q, res.velocity_post)
    np.testing.assert_allclose(walker.contact_jacobian(qs, "right") @ qds, 0.0, atol=1e-12)
    np.testing.assert_allclose(qds[[3, 5]], 0.0, atol=1e-12)
