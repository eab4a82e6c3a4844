"""Accuracy and input checks of the impact algebra on ill-conditioned mass matrices (issue 11.11).

The reference :func:`heelstrike.core.impact.impact` is compared with an exact reference: the
impact equations solved in 60-digit arithmetic (mpmath) on the very same floating-point inputs.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from _compass_points import point_jacobians
from heelstrike.core.impact import ImpactInputError, constrained_projector, impact
from heelstrike.models.compass import CompassGait, heel_strike_state


def _exact(M: np.ndarray, A: np.ndarray, qd: np.ndarray) -> dict[str, object]:
    """T, T_c, T_a, q_dot+ and lambda (e = 0) in 60 digits from the float inputs."""
    with mpmath.workdps(60):
        Mm = mpmath.matrix(M.tolist())
        Am = mpmath.matrix(A.tolist())
        v = mpmath.matrix(qd.tolist())
        k = A.shape[0]
        X = mpmath.matrix(M.shape[0], k)
        for j in range(k):
            X[:, j] = mpmath.lu_solve(Mm, Am.T[:, j])
        W = Am * X
        mu = mpmath.lu_solve(W, Am * v)
        v_c = X * mu
        v_a = v - v_c

        def energy(x: mpmath.matrix) -> float:
            return float((x.T * Mm * x)[0] / 2)

        return {
            "T": energy(v),
            "T_c": energy(v_c),
            "T_a": energy(v_a),
            "q_plus": np.array([float(x) for x in v_a]),
            "lam": np.array([-float(x) for x in mu]),
        }


def _m_norm(M: np.ndarray, x: np.ndarray) -> float:
    """Energy norm sqrt(x^T M x), the natural norm of velocity errors."""
    return float(np.sqrt(abs(x @ M @ x)))


def _system(seed: int, cond: float, grading: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n = 4, k = 2: ``M = D Q diag(...) Q^T D`` with intrinsic condition ``cond`` and unit
    scales ``D`` spanning ``grading`` (e.g. metres vs micrometres)."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    M0 = Q @ np.diag(np.geomspace(1.0, 1.0 / cond, 4)) @ Q.T
    D = np.diag(np.geomspace(1.0, 1.0 / grading, 4))
    M = D @ M0 @ D
    M = 0.5 * (M + M.T)
    A = rng.normal(size=(2, 4)) @ np.linalg.inv(D)
    qd = np.linalg.solve(D, rng.normal(size=4))
    return M, A, qd


CASES = [
    # (intrinsic condition, unit grading): raw cond(M) from 1e12 up to beyond 1e30. Before
    # issue 11 the reference path was off by up to 100 % here (and the compiled one raised).
    (1e4, 1e6),  # raw cond ~1e16
    (1e2, 1e8),  # raw cond ~1e18
    (1e8, 1e8),  # raw cond ~1e24
    (1e6, 1e12),  # raw cond ~1e30
    (1e12, 1.0),  # intrinsic 1e12
    (1e14, 1.0),  # intrinsic 1e14, close to the singularity limit (~1e15)
]
#: Relative accuracy required of energies (and of q_dot+, lambda in the energy norm). The
#: sensitivity of T_c to rounding of the scaled M is far below its condition number, which is
#: what the exact reference confirms; the old code missed this by up to 1e0 on graded M.
RTOL = 1e-6


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize(("cond", "grading"), CASES)
def test_reference_matches_exact_reference_on_ill_conditioned_M(
    seed: int, cond: float, grading: float
) -> None:
    M, A, qd = _system(seed, cond, grading)
    ref = _exact(M, A, qd)
    T = float(ref["T"])  # type: ignore[arg-type]
    res = impact(M, A, qd)
    for name, got in (("reference", res),):
        for key, attr in (("T", "kinetic_energy"), ("T_c", "kinetic_energy_constrained"),
                          ("T_a", "kinetic_energy_admissible")):
            assert float(getattr(got, attr)) == pytest.approx(
                float(ref[key]), rel=RTOL, abs=1e-12 * T  # type: ignore[arg-type]
            ), (name, key)
        err = _m_norm(M, np.asarray(got.velocity_post) - ref["q_plus"])  # type: ignore[operator]
        assert err <= RTOL * np.sqrt(T), (name, err)
    # the impulse satisfies M (q+ - q-) = A^T lambda in the energy-dual norm
    lam_err = np.linalg.solve(M, A.T @ (res.constraint_impulse - ref["lam"]))  # type: ignore[operator]
    assert _m_norm(M, lam_err) <= RTOL * np.sqrt(T)


@pytest.mark.parametrize("factor", [1e250, 1e-250, 1e-3])
def test_checks_and_results_are_scale_free(factor: float) -> None:
    M, A, qd = _system(3, 1e3, 1.0)
    base = impact(M, A, qd)
    scaled = impact(factor * M, A * 1e-20, qd)
    assert float(scaled.kinetic_energy_constrained) == pytest.approx(
        factor * float(base.kinetic_energy_constrained), rel=1e-12
    )
    np.testing.assert_allclose(scaled.velocity_post, base.velocity_post, rtol=1e-11, atol=1e-13)


def _singular_psd() -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    B = rng.normal(size=(4, 3))
    Q, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    return [
        np.diag([1.0, 2.0, 3.0, 0.0]),
        B @ B.T,  # rank 3
        Q @ np.diag([1.0, 1.0, 1.0, 1e-17]) @ Q.T,
        1e250 * (B @ B.T),
    ]


@pytest.mark.parametrize("which", range(4))
def test_singular_psd_mass_matrix_is_rejected_with_condition_number(which: int) -> None:
    M = _singular_psd()[which]
    M = 0.5 * (M + M.T)
    rng = np.random.default_rng(which)
    A = rng.normal(size=(2, 4))
    qd = rng.normal(size=4)
    with pytest.raises(ImpactInputError, match="positive definite") as info:
        impact(M, A, qd)
    if which:  # a zero diagonal entry is reported as such
        assert "condition number" in str(info.value)
    with pytest.raises(ImpactInputError, match="positive definite"):
        constrained_projector(M, A)


def test_indefinite_mass_matrix_is_rejected() -> None:
    M = np.array([[1.0, 2.0, 0, 0], [2.0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])
    A = np.eye(4)[:2] + 0.1
    with pytest.raises(ImpactInputError, match="indefinite"):
        impact(M, A, np.ones(4))


def test_rank_test_of_A_is_scale_free() -> None:
    M, A, qd = _system(4, 10.0, 1.0)
    A2 = A.copy()
    A2[1] *= 1e-14  # a badly scaled but independent row
    a = impact(M, A, qd)
    b = impact(M, A2, qd)
    np.testing.assert_allclose(b.velocity_post, a.velocity_post, rtol=1e-10, atol=1e-12)
    with pytest.raises(ImpactInputError, match="rank"):
        impact(M, np.vstack([A[0], 3e-20 * A[0]]), qd)


def _compass_exact_tc(b: float, q3: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Float ``M, A, q_dot`` of the compass heel strike, and T_c of the exact physics: ``M``
    assembled in 60 digits from the point Jacobians (``M = sum m J^T J``), not rounded."""
    w = CompassGait(leg_com_from_hip=b)
    q, qd = heel_strike_state(w, q3)
    J_H, J_R, J_L = point_jacobians(w, q)
    A = w.contact_jacobian(q, "left")
    with mpmath.workdps(60):
        Mm = mpmath.zeros(4, 4)
        for mass, J in ((w.hip_mass, J_H), (w.leg_mass, J_R), (w.leg_mass, J_L)):
            Jm = mpmath.matrix(np.asarray(J).tolist())
            Mm += mpmath.mpf(mass) * (Jm.T * Jm)
        Am = mpmath.matrix(A.tolist())
        v = mpmath.matrix(qd.tolist())
        X = mpmath.matrix(4, 2)
        for j in range(2):
            X[:, j] = mpmath.lu_solve(Mm, Am.T[:, j])
        mu = mpmath.lu_solve(Am * X, Am * v)
        tc = float(((Am * v).T * mu)[0] / 2)
    return w.mass_matrix(q), A, qd, tc


@pytest.mark.parametrize("b", [1e-3, 1e-5, 1e-9, 1e-12])
def test_tiny_leg_com_offset_is_exact_or_rejected_never_wrong(b: float) -> None:
    """Issue 11.11: ``leg_com_from_hip = 1e-9`` gave T_c 52 J (reference) and 1e-4 J (compiled)
    where the exact value is ~3.6 J. Each path must give the exact T_c of its input ``M`` or
    refuse with the condition number; with ``b = 1e-9`` the rounded ``M`` is singular to
    working precision (scaled condition ~1e17) and must be refused."""
    M, A, qd, tc_physics = _compass_exact_tc(b, np.deg2rad(20.0))
    tc_input = float(_exact(M, A, qd)["T_c"])  # type: ignore[arg-type]
    s = np.sqrt(np.diag(M))
    ev = np.linalg.eigvalsh(M / np.outer(s, s))
    # forward-error bound of a backward-stable solve: eps times the scaled condition number
    rtol = max(RTOL, np.finfo(float).eps * ev[-1] / max(ev[0], 1e-300))
    for path in (impact,):
        try:
            got = float(path(M, A, qd).kinetic_energy_constrained)
        except ImpactInputError as exc:
            assert "condition number" in str(exc)
            assert b < 1e-5, "well-posed enough to be solved"
        else:
            assert b > 1e-9, f"{path.__name__} accepted a numerically singular M"
            assert got == pytest.approx(tc_input, rel=rtol), path.__name__
            if b >= 1e-3:
                assert got == pytest.approx(tc_physics, rel=RTOL), path.__name__


def _compass_factor(b: float, q3: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass factor ``F = [sqrt(mH) J_H; sqrt(m) J_R; sqrt(m) J_L]`` (``M = F^T F``), A, q_dot."""
    w = CompassGait(leg_com_from_hip=b)
    q, qd = heel_strike_state(w, q3)
    J_H, J_R, J_L = point_jacobians(w, q)
    F = np.vstack([np.sqrt(w.hip_mass) * J_H, np.sqrt(w.leg_mass) * J_R,
                   np.sqrt(w.leg_mass) * J_L])
    return F, w.contact_jacobian(q, "left"), qd


@pytest.mark.parametrize("b", [0.5, 1e-3, 1e-6, 1e-9])
def test_mass_factor_resolves_tiny_leg_com_offset_exactly(b: float) -> None:
    """With ``M = F^T F`` given as its factor, ``leg_com_from_hip = 1e-9`` is no longer
    singular to working precision: T_c equals the exact physics (~3.63 J at 20 deg)."""
    q3 = np.deg2rad(20.0)
    F, A, qd = _compass_factor(b, q3)
    _, _, _, tc = _compass_exact_tc(b, q3)
    res = impact(None, A, qd, mass_factor=F)
    assert float(res.kinetic_energy_constrained) == pytest.approx(tc, rel=RTOL)
    if b >= 1e-3:  # and the same as the matrix path where that one is accurate
        M = F.T @ F
        ref = impact(M, A, qd)
        assert float(ref.kinetic_energy_constrained) == pytest.approx(tc, rel=RTOL)
        np.testing.assert_allclose(res.velocity_post, ref.velocity_post, rtol=1e-6, atol=1e-9)
    # the post-impact state satisfies the constraint (relative to its size: with b = 1e-9 the
    # nearly massless swing leg is kicked to ~1e8 rad/s, as in the exact solution) and the
    # energy books
    qp = np.asarray(res.velocity_post)
    assert np.max(np.abs(A @ qp)) <= 1e-12 * max(1.0, float(np.max(np.abs(qp))))
    assert float(res.kinetic_energy) == pytest.approx(
        float(res.kinetic_energy_constrained + res.kinetic_energy_admissible), rel=RTOL
    )


def test_mass_factor_input_checks() -> None:
    F, A, qd = _compass_factor(0.5, 0.3)
    with pytest.raises(ImpactInputError, match="not both"):
        impact(F.T @ F, A, qd, mass_factor=F)
    with pytest.raises(ImpactInputError, match="required"):
        impact(None, A, qd)
    with pytest.raises(ImpactInputError, match="singular"):
        impact(None, A, qd, mass_factor=F[:, :3] @ np.ones((3, 4)))  # rank 1
    with pytest.raises(ImpactInputError, match="at least"):
        impact(None, A, qd, mass_factor=F[:3])
