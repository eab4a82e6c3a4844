"""Properties of the impact algebra (paper eqs. 2-13) on random systems, and its input checks.

Random systems: ``M`` symmetric positive definite (n in 2..7), ``A`` full row rank (k in 1..n),
with bounded condition numbers so that tolerances are meaningful.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from heelstrike.core.impact import (
    ImpactInputError,
    admissible_projector,
    constrained_projector,
    decompose_impulse,
    decompose_velocity,
    impact,
)

RTOL = 1e-9


@dataclass
class System:
    M: np.ndarray
    A: np.ndarray
    q_dot: np.ndarray
    e: float


def _random_system(rng: np.random.Generator, n: int, k: int, batch: tuple[int, ...] = ()):
    B = rng.normal(size=(*batch, n, n))
    scale = np.exp(rng.uniform(-2.0, 2.0))
    M = scale * (B @ np.swapaxes(B, -1, -2) + 0.2 * np.eye(n))
    # A = U diag(s) V^T with singular values in [0.3, 3]: full row rank, well conditioned
    U = np.linalg.qr(rng.normal(size=(*batch, k, k)))[0]
    V = np.linalg.qr(rng.normal(size=(*batch, n, n)))[0][..., :k]
    s = rng.uniform(0.3, 3.0, size=(*batch, k))
    A = (U * s[..., None, :]) @ np.swapaxes(V, -1, -2)
    q_dot = rng.normal(scale=3.0, size=(*batch, n))
    return M, A, q_dot


@st.composite
def systems(draw: st.DrawFn) -> System:
    n = draw(st.integers(2, 7))
    k = draw(st.integers(1, n))
    seed = draw(st.integers(0, 2**32 - 1))
    e = draw(st.sampled_from([0.0, 1.0]) | st.floats(0.0, 1.0))
    M, A, q_dot = _random_system(np.random.default_rng(seed), n, k)
    return System(M=M, A=A, q_dot=q_dot, e=e)


def _T(M: np.ndarray, v: np.ndarray) -> float:
    return float(0.5 * v @ M @ v)


@given(systems())
def test_projectors_are_idempotent_complementary_and_mass_orthogonal(s: System):
    P_c = constrained_projector(s.M, s.A)
    P_a = admissible_projector(s.M, s.A)
    n = s.M.shape[0]
    np.testing.assert_allclose(P_c @ P_c, P_c, atol=1e-9)
    np.testing.assert_allclose(P_a @ P_a, P_a, atol=1e-9)
    np.testing.assert_allclose(P_c + P_a, np.eye(n), atol=1e-12)
    scale = np.linalg.norm(s.M)
    np.testing.assert_allclose(P_c.T @ s.M @ P_a, 0.0, atol=1e-9 * scale)
    np.testing.assert_allclose(P_a.T @ s.M @ P_c, 0.0, atol=1e-9 * scale)
    # P_a maps onto the constraint null space, P_c has the rank of A
    np.testing.assert_allclose(s.A @ P_a, 0.0, atol=1e-9 * np.linalg.norm(s.A))
    assert np.linalg.matrix_rank(P_c, tol=1e-8) == s.A.shape[0]


@given(systems())
def test_energy_decomposition_eq10(s: System):
    r = impact(s.M, s.A, s.q_dot, restitution=s.e)
    T = _T(s.M, s.q_dot)
    assert float(r.kinetic_energy) == pytest.approx(T, rel=RTOL)
    # T_a is computed in ImpactResult from v_a, not as T - T_c
    assert float(r.kinetic_energy_constrained + r.kinetic_energy_admissible) == pytest.approx(
        T, rel=RTOL, abs=1e-12
    )
    assert float(r.kinetic_energy_constrained) == pytest.approx(
        _T(s.M, r.velocity_constrained), rel=RTOL, abs=1e-12
    )
    assert float(r.kinetic_energy_admissible) == pytest.approx(
        _T(s.M, r.velocity_admissible), rel=RTOL, abs=1e-12
    )
    v_c, v_a = decompose_velocity(r.constrained_projector, s.q_dot)
    np.testing.assert_allclose(v_c + v_a, s.q_dot, atol=1e-12)
    np.testing.assert_allclose(v_c, r.velocity_constrained, atol=1e-9 * (1 + np.abs(v_c).max()))


@given(systems())
def test_impact_law_and_energy_loss(s: System):
    r = impact(s.M, s.A, s.q_dot, restitution=s.e)
    q_plus = r.velocity_post
    Aq_minus = s.A @ s.q_dot
    tol = 1e-9 * (1.0 + np.abs(Aq_minus).max())
    # eq. (3), generalised by restitution: A q+ = -e A q-
    np.testing.assert_allclose(s.A @ q_plus, -s.e * Aq_minus, atol=tol)
    if s.e == 0.0:
        np.testing.assert_allclose(s.A @ q_plus, 0.0, atol=tol)
        np.testing.assert_allclose(q_plus, r.admissible_projector @ s.q_dot, atol=tol)
    T_minus, T_plus = _T(s.M, s.q_dot), _T(s.M, q_plus)
    assert T_plus <= T_minus * (1 + 1e-12) + 1e-12
    assert float(r.kinetic_energy_post) == pytest.approx(T_plus, rel=RTOL, abs=1e-12)
    # energy lost (1 - e^2) T_c, from the kinetic energies computed here
    assert T_minus - T_plus == pytest.approx(
        (1 - s.e**2) * float(r.kinetic_energy_constrained), rel=1e-7, abs=1e-9 * T_minus
    )
    assert float(r.energy_lost) == pytest.approx(T_minus - T_plus, rel=1e-7, abs=1e-9 * T_minus)


@given(systems())
def test_impulse_equals_momentum_jump_eq2(s: System):
    r = impact(s.M, s.A, s.q_dot, restitution=s.e)
    f = s.A.T @ r.constraint_impulse
    jump = s.M @ (r.velocity_post - s.q_dot)
    tol = 1e-9 * (1 + np.abs(s.M @ s.q_dot).max())
    np.testing.assert_allclose(f, jump, atol=tol)
    np.testing.assert_allclose(r.generalized_impulse, jump, atol=tol)
    # eq. (9): the impulse lies entirely in the constrained space
    f_c, f_a = decompose_impulse(r.constrained_projector, f)
    np.testing.assert_allclose(f_c, f, atol=tol)
    np.testing.assert_allclose(f_a, 0.0, atol=tol)


@given(systems())
def test_matches_independent_kkt_solve(s: System):
    """[[M, -A^T], [A, 0]] [q+, lambda] = [M q-, -e A q-] solved directly."""
    n, k = s.M.shape[0], s.A.shape[0]
    K = np.block([[s.M, -s.A.T], [s.A, np.zeros((k, k))]])
    rhs = np.concatenate([s.M @ s.q_dot, -s.e * s.A @ s.q_dot])
    sol = np.linalg.solve(K, rhs)
    r = impact(s.M, s.A, s.q_dot, restitution=s.e)
    np.testing.assert_allclose(r.velocity_post, sol[:n], atol=1e-8 * (1 + np.abs(sol).max()))
    np.testing.assert_allclose(
        r.constraint_impulse, sol[n:], atol=1e-8 * (1 + np.abs(sol).max())
    )


@settings(max_examples=30)
@given(n=st.integers(2, 7), data=st.data(), seed=st.integers(0, 2**32 - 1))
def test_batched_equals_looped(n: int, data: st.DataObject, seed: int):
    k = data.draw(st.integers(1, n))
    e = data.draw(st.floats(0.0, 1.0))
    M, A, q_dot = _random_system(np.random.default_rng(seed), n, k, batch=(3, 2))
    r = impact(M, A, q_dot, restitution=e)
    for idx in np.ndindex(3, 2):
        ri = impact(M[idx], A[idx], q_dot[idx], restitution=e)
        np.testing.assert_allclose(r.velocity_post[idx], ri.velocity_post, rtol=1e-10,
                                   atol=1e-12)
        np.testing.assert_allclose(r.constraint_impulse[idx], ri.constraint_impulse,
                                   rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(r.constrained_projector[idx], ri.constrained_projector,
                                   rtol=1e-10, atol=1e-12)
        assert r.kinetic_energy_constrained[idx] == pytest.approx(
            float(ri.kinetic_energy_constrained), rel=1e-10, abs=1e-14)
    # broadcasting a single M, A against a batch of velocities
    rb = impact(M[0, 0], A[0, 0], q_dot)
    for idx in np.ndindex(3, 2):
        ri = impact(M[0, 0], A[0, 0], q_dot[idx])
        np.testing.assert_allclose(rb.velocity_post[idx], ri.velocity_post, rtol=1e-10,
                                   atol=1e-12)


def test_full_rank_square_constraint_stops_everything():
    """k = n: every velocity is constrained, an inert impact stops the system."""
    rng = np.random.default_rng(1)
    M, A, q_dot = _random_system(rng, 4, 4)
    r = impact(M, A, q_dot)
    np.testing.assert_allclose(r.velocity_post, 0.0, atol=1e-10)
    assert float(r.energy_lost) == pytest.approx(_T(M, q_dot), rel=1e-10)


def _good():
    rng = np.random.default_rng(0)
    return _random_system(rng, 4, 2)


@pytest.mark.parametrize(
    ("case", "match"),
    [
        ("M_not_square", "square"),
        ("A_columns", "columns"),
        ("q_dot_length", "q_dot"),
        ("M_nan", "non-finite"),
        ("q_dot_inf", "non-finite"),
        ("M_nonsymmetric", "symmetric"),
        ("M_indefinite", "positive definite"),
        ("A_rank_deficient", "rank"),
        ("A_too_many_rows", "rows"),
        ("batch_mismatch", "broadcast"),
        ("e_negative", "restitution"),
        ("e_above_one", "restitution"),
        ("e_nan", "restitution"),
    ],
)
def test_clear_errors(case: str, match: str):
    M, A, q_dot = _good()
    e = 0.0
    if case == "M_not_square":
        M = M[:, :3]
    elif case == "A_columns":
        A = A[:, :3]
    elif case == "q_dot_length":
        q_dot = q_dot[:3]
    elif case == "M_nan":
        M = M.copy()
        M[1, 1] = np.nan
    elif case == "q_dot_inf":
        q_dot = q_dot.copy()
        q_dot[0] = np.inf
    elif case == "M_nonsymmetric":
        M = M.copy()
        M[0, 1] += 0.5
    elif case == "M_indefinite":
        M = np.diag([1.0, 2.0, -0.5, 1.0])
    elif case == "A_rank_deficient":
        A = np.vstack([A[0], 2.0 * A[0]])
    elif case == "A_too_many_rows":
        A = np.vstack([A, A, A[:1]])
    elif case == "batch_mismatch":
        M = np.broadcast_to(M, (3, 4, 4))
        A = np.broadcast_to(A, (2, 2, 4))
    elif case == "e_negative":
        e = -0.1
    elif case == "e_above_one":
        e = 1.5
    elif case == "e_nan":
        e = float("nan")
    with pytest.raises(ImpactInputError, match=match):
        impact(M, A, q_dot, restitution=e)


def test_projector_functions_validate_too():
    with pytest.raises(ImpactInputError, match="positive definite"):
        constrained_projector(-np.eye(3), np.eye(3)[:1])
    assert issubclass(ImpactInputError, ValueError)
