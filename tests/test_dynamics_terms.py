"""The right-hand side's building blocks: ``dynamics_terms`` and the reduced solve.

``PlanarWalker.dynamics_terms(q, q_dot, slope)`` returns ``(M, h)`` from one kinematics pass; it
must equal the separate ``mass_matrix`` / ``bias_forces`` to round-off for the compass (scalar
and array parameters, single and batched states) and for every built walker. The compass's
column-wise assembly is also checked against the plain point-Jacobian products
``sum_i m_i J_i^T J_i`` and ``sum_i m_i J_i^T (a_i - g)``, and the single-support right-hand
side against the generic (batched) reduced equations.
"""

from __future__ import annotations

import numpy as np
import pytest

from _compass_points import point_jacobians
from heelstrike.dynamics.single_support import SingleSupport, solve_small
from heelstrike.models import CompassGait
from heelstrike.models.base import gravity_vector
from heelstrike.models.builder import load_walker, shipped_walkers

RNG_SEED = 20261122


def _states(n: int, shape: tuple[int, ...], seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.0, 1.0, (*shape, n)), rng.uniform(-3.0, 3.0, (*shape, n))


COMPASSES = {
    "paper-R0.3": CompassGait(foot_radius=0.3),
    "inertia": CompassGait(foot_radius=0.1, leg_inertia=0.07, hip_mass=3.0, leg_com_from_hip=0.4),
    "radius-grid": CompassGait(foot_radius=np.array([0.0, 0.25, 0.5]), leg_inertia=0.02),
}


@pytest.mark.parametrize("name", sorted(COMPASSES))
@pytest.mark.parametrize("shape", [(), (3,), (2, 3)])
def test_compass_terms_equal_separate_calls(name: str, shape: tuple[int, ...]) -> None:
    w = COMPASSES[name]
    if np.ndim(w.foot_radius) and shape[-1:] != (3,):
        pytest.skip("array parameters broadcast against a trailing axis of 3 states")
    q, qd = _states(4, shape, RNG_SEED)
    for slope in (0.0, 0.07):
        M, h = w.dynamics_terms(q, qd, slope)
        M_sep, h_sep = w.mass_matrix(q), w.bias_forces(q, qd, slope)
        assert M.shape == M_sep.shape == (*shape, 4, 4)
        assert h.shape == h_sep.shape == (*shape, 4)
        np.testing.assert_allclose(M, M_sep, rtol=1e-14, atol=1e-13)
        np.testing.assert_allclose(h, h_sep, rtol=1e-14, atol=1e-12)


@pytest.mark.parametrize("name", sorted(COMPASSES))
def test_compass_terms_equal_point_jacobian_products(name: str) -> None:
    """The column-wise assembly is ``M = sum m_i J_i^T J_i + I W`` and ``h = sum m_i J_i^T
    (a_i - g)`` with the full point Jacobians, one state at a time (the scalar fast path) and
    batched."""
    w = COMPASSES[name]
    q, qd = _states(4, (3,), RNG_SEED + 1)
    slope = 0.05
    J_H, J_R, J_L = point_jacobians(w, q)
    mH, m, inertia = (np.asarray(v, dtype=float)[..., None, None]
                      for v in (w.hip_mass, w.leg_mass, w.leg_inertia))
    W = np.zeros((4, 4))
    W[2:, 2:] = [[2.0, 1.0], [1.0, 1.0]]
    M_ref = (mH * np.swapaxes(J_H, -1, -2) @ J_H
             + m * (np.swapaxes(J_R, -1, -2) @ J_R + np.swapaxes(J_L, -1, -2) @ J_L)
             + inertia * W)
    # accelerations of the points at q_ddot = 0 by finite differences of J(q) q_dot along q_dot
    eps = 1e-6
    Jp = point_jacobians(w, q + eps * qd)
    Jm = point_jacobians(w, q - eps * qd)
    g = gravity_vector(w.gravity, slope)[..., None, :]
    acc = [np.einsum("...ij,...j->...i", (a - b) / (2 * eps), qd)
           for a, b in zip(Jp, Jm, strict=True)]
    h_ref = sum(
        mass[..., 0] * np.einsum("...ji,...j->...i", J, a - g[..., 0, :])
        for mass, J, a in zip((mH, m, m), (J_H, J_R, J_L), acc, strict=True)
    )
    M, h = w.dynamics_terms(q, qd, slope)
    np.testing.assert_allclose(M, M_ref, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(h, h_ref, rtol=1e-7, atol=1e-7)
    if not np.ndim(w.foot_radius):
        for i in range(3):  # one state: the Python-float path
            M1, h1 = w.dynamics_terms(q[i], qd[i], slope)
            np.testing.assert_allclose(M1, M[i], rtol=1e-14, atol=1e-13)
            np.testing.assert_allclose(h1, h[i], rtol=1e-14, atol=1e-12)


@pytest.mark.parametrize("name", shipped_walkers())
def test_built_walker_terms_equal_separate_calls(name: str) -> None:
    w = load_walker(name)
    n = w.n_coordinates
    for shape in [(), (4,)]:
        q, qd = _states(n, shape, RNG_SEED + 2)
        M, h = w.dynamics_terms(q, qd, 0.04)
        np.testing.assert_allclose(M, w.mass_matrix(q), rtol=1e-14, atol=1e-13)
        np.testing.assert_allclose(h, w.bias_forces(q, qd, 0.04), rtol=1e-14, atol=1e-12)


@pytest.mark.parametrize("m", [1, 2, 3, 5])
def test_solve_small_solves_spd_systems(m: int) -> None:
    rng = np.random.default_rng(m)
    X = rng.normal(size=(m, m))
    A = X @ X.T + m * np.eye(m)
    b = rng.normal(size=m)
    y = solve_small(A, b)
    assert y.shape == (m,)
    np.testing.assert_allclose(A @ y, b, rtol=1e-12, atol=1e-12)


def _walkers() -> list[tuple[str, object, tuple[int, ...]]]:
    kneed = load_walker("kneed")
    return [
        ("compass", CompassGait(foot_radius=0.3), ()),
        ("compass-inertia", COMPASSES["inertia"], ()),
        ("kneed-free", kneed, ()),
        ("kneed-locked", kneed, kneed.lockable_joints[:1]),
        ("torso", load_walker("torso"), ()),
    ]


@pytest.mark.parametrize(("name", "walker", "locked"), _walkers(), ids=[w[0] for w in _walkers()])
def test_rhs_matches_generic_reduced_equations(name: str, walker, locked) -> None:
    """The specialised ``rhs`` (one state, unchecked, closed-form small solve) equals the
    batched ``accelerations`` path built from ``mass_matrix`` and ``bias_forces`` separately."""
    n_u = walker.actuation_matrix().shape[1]
    gains = np.linspace(0.5, 1.5, n_u)

    def law(t: float, q: np.ndarray, q_dot: np.ndarray) -> np.ndarray:
        return gains * (np.sin(3.0 * t) - 0.2 * q_dot[..., -1:])

    for torque in (None, law):
        sup = SingleSupport(walker=walker, slope=0.03, torque=torque, locked=locked)
        m = len(sup.free_coordinates)
        rng = np.random.default_rng(RNG_SEED + m)
        n = walker.n_coordinates
        q_ref = rng.uniform(-0.5, 0.5, n)
        x = np.concatenate((rng.uniform(-0.5, 0.5, m), rng.uniform(-2.0, 2.0, m), [0.3]))
        dx = sup.rhs(0.4, x, q_ref)
        q, qd = sup.unpack(x[: 2 * m][None, :], q_ref[None, :])
        qdd = sup.accelerations(0.4, q, qd)[0]
        np.testing.assert_allclose(dx[:m], x[m : 2 * m], rtol=0, atol=0)
        np.testing.assert_allclose(dx[m : 2 * m], qdd[list(sup.free_coordinates)],
                                   rtol=1e-11, atol=1e-11)
        power = sup.actuator_power(0.4, q, qd)[0] if torque is not None else 0.0
        np.testing.assert_allclose(dx[2 * m], power, rtol=1e-12, atol=1e-12)
        # the one-state unpack equals the batched one
        q1, qd1 = sup.unpack(x[: 2 * m], q_ref)
        np.testing.assert_array_equal(q1, q[0])
        np.testing.assert_array_equal(qd1, qd[0])
