"""The one Newton engine (``heelstrike.analysis.newton``): roots, per-start outcomes, and the
passive gait it finds on the compiled compass map."""

from __future__ import annotations

import json

import numpy as np
import pytest

from heelstrike.analysis.newton import floquet_multipliers, newton_solve
from heelstrike.status import SolveStatus


def _circle_line(X: np.ndarray) -> np.ndarray:
    """x^2 + y^2 = 4, y = x: roots (+-sqrt 2, +-sqrt 2); NaN for x < -5 (the walker 'falls')."""
    x, y = X[:, 0], X[:, 1]
    F = np.stack((x * x + y * y - 4.0, y - x), axis=1)
    F[x < -5.0] = np.nan
    return F


def test_batched_starts_end_each_in_its_own_way() -> None:
    calls: list[int] = []

    def residual(X: np.ndarray) -> np.ndarray:
        calls.append(X.shape[0])
        return _circle_line(X)

    starts = np.array([[1.0, 0.5], [-1.0, -3.0], [-6.0, 0.0], [0.0, 0.0]])
    sol = newton_solve(residual, starts, tol=1e-12)
    r2 = np.sqrt(2.0)
    assert sol.status[0] is SolveStatus.CONVERGED
    np.testing.assert_allclose(sol.x[0], [r2, r2], atol=1e-12)
    assert sol.status[1] is SolveStatus.CONVERGED
    np.testing.assert_allclose(sol.x[1], [-r2, -r2], atol=1e-12)
    assert sol.status[2] is SolveStatus.STEP_FAILED  # F is NaN at the start
    assert sol.status[3] is SolveStatus.SINGULAR  # J = [[0, 0], [-1, 1]] at the origin
    assert list(sol.converged) == [True, True, False, False]
    assert np.all(sol.residual_norm[:2] < 1e-12)
    # the converged Jacobian is F's (central differences): [[2x, 2y], [-1, 1]]
    np.testing.assert_allclose(sol.jacobian[0], [[2 * r2, 2 * r2], [-1.0, 1.0]], atol=1e-6)
    # batched: the first call holds every start and its 4 neighbours
    assert calls[0] == 4 * (1 + 4)
    assert sol.message(2).startswith("the walker fails to take a step from the Newton iterate")
    # with labels the iterate is told by name and unit (a QA finding: a bare array)
    assert sol.message(2, (("q3", "rad"), ("energy", "J"))).endswith(
        "Newton iterate (q3 = -6 rad, energy = 0 J)")
    json.dumps(sol.to_dict())


def test_max_iterations_and_time_limit() -> None:
    sol = newton_solve(_circle_line, [3.0, 1.0], tol=1e-14, max_iter=1)
    assert sol.status == (SolveStatus.MAX_ITERATIONS,)
    assert sol.iterations[0] == 2  # the start and one Newton step were evaluated
    sol = newton_solve(_circle_line, [3.0, 1.0], tol=1e-14, deadline=0.0)
    assert sol.status == (SolveStatus.TIME_LIMIT,)


def test_finite_line_search_halves_until_the_walker_steps() -> None:
    # F = x - 10 with failures beyond x > 2: the full step fails, lam halves to 1/8 (x = 1.125)
    def residual(X: np.ndarray) -> np.ndarray:
        F = X - 10.0
        F[X[:, 0] > 2.0] = np.nan
        return F

    sol = newton_solve(residual, [0.0], tol=1e-12, max_iter=1)
    assert sol.x[0, 0] == pytest.approx(10.0 / 8.0)


def test_broyden_with_decrease_and_projection() -> None:
    # powered-gait style: the last unknown is clamped to >= 0.5; the root (2, 1) satisfies it
    def residual(X: np.ndarray) -> np.ndarray:
        x, p = X[:, 0], X[:, 1]
        return np.stack((x * x * p - 4.0, x - 2.0 * p), axis=1)

    def project(X: np.ndarray) -> np.ndarray:
        Y = X.copy()
        Y[:, -1] = np.maximum(Y[:, -1], 0.5)
        return Y

    sol = newton_solve(residual, [1.5, 0.6], tol=1e-12, jacobian="broyden",
                       line_search="decrease", min_rate=1.0, project=project, max_iter=50)
    assert sol.status == (SolveStatus.CONVERGED,)
    np.testing.assert_allclose(sol.x[0], [2.0, 1.0], atol=1e-10)
    # a stalled search below the noise floor counts as converged (accept), above it does not
    flat = newton_solve(lambda X: np.abs(X) + 1e-9, [1.0], tol=1e-12, line_search="decrease",
                        accept=1e-6, max_iter=50)
    assert flat.status == (SolveStatus.CONVERGED,)
    assert flat.residual_norm[0] < 1e-6
    stall = newton_solve(lambda X: np.abs(X) + 1e-3, [1.0], tol=1e-12, line_search="decrease",
                         accept=1e-6, max_iter=50)
    assert stall.status[0] in (SolveStatus.STALLED, SolveStatus.SLOW)


def test_lazy_jacobian_skips_the_neighbours_at_the_root() -> None:
    counts: list[int] = []

    def residual(X: np.ndarray) -> np.ndarray:
        counts.append(X.shape[0])
        return _circle_line(X)

    eager = newton_solve(residual, [np.sqrt(2.0), np.sqrt(2.0)], tol=1e-9)
    n_eager = sum(counts)
    counts.clear()
    lazy = newton_solve(residual, [np.sqrt(2.0), np.sqrt(2.0)], tol=1e-9, jacobian_at_root=False)
    assert eager.converged[0] and lazy.converged[0]
    assert n_eager == 5 and sum(counts) == 1


@pytest.mark.slow
def test_chord_reuses_a_good_jacobian_and_replaces_a_bad_one_once() -> None:
    """``jacobian="chord"``: one evaluation per iteration with the given Jacobian; a Jacobian that
    does not contract 5x is replaced once by forward differences (2 more evaluations); one that
    still fails ends the start STALLED instead of looping."""
    r2 = np.sqrt(2.0)
    root = np.array([r2, r2])
    J_root = np.array([[2 * r2, 2 * r2], [-1.0, 1.0]])  # the exact Jacobian at the root
    calls: list[int] = []

    def residual(X: np.ndarray) -> np.ndarray:
        calls.append(X.shape[0])
        return _circle_line(X)

    x0 = root + np.array([1e-3, -2e-3])
    sol = newton_solve(residual, x0, tol=1e-13, jacobian="chord", jacobian0=J_root[None],
                       jacobian_at_root=False)
    assert sol.status[0] is SolveStatus.CONVERGED
    np.testing.assert_allclose(sol.x[0], root, atol=1e-13)
    assert sum(calls) == sol.iterations[0]  # one evaluation per iteration, no differences
    # a poor Jacobian (wrong sign of a column): replaced once by forward differences
    calls.clear()
    bad = J_root * np.array([[1.0, -1.0], [1.0, -1.0]])
    sol = newton_solve(residual, x0, tol=1e-12, jacobian="chord", jacobian0=bad[None],
                       fd_step=1e-7, jacobian_at_root=False)
    assert sol.status[0] is SolveStatus.CONVERGED
    assert calls.count(2) == 1  # the one forward-difference Jacobian (n = 2 points)
    # a residual no chord step can reduce (|F| grows away from a saddle): STALLED, not a loop
    calls.clear()
    sol = newton_solve(lambda X: np.stack((X[:, 0] ** 2 + 1.0, X[:, 1]), axis=1),
                       np.array([0.3, 0.0]), tol=1e-12, jacobian="chord",
                       jacobian0=np.eye(2)[None], jacobian_at_root=False)
    assert sol.status[0] is SolveStatus.STALLED
    assert sol.iterations[0] < 20


def test_compass_fixed_point_matches_the_step_map() -> None:
    """On the compiled compass map, the engine's fixed point is a gait: P(z) = z to 1e-10, and
    its multipliers are those of an independent finite-difference Jacobian of P."""
    pytest.importorskip("numba")
    from heelstrike.dynamics.compiled import COMPLETED, ensemble_walk
    from heelstrike.models.compass import CompassGait

    walker = CompassGait(foot_radius=0.3)
    slope = np.radians(3.0)

    def P(Z: np.ndarray) -> np.ndarray:
        res = ensemble_walk(walker, Z, slope, steps=1, rtol=1e-11, atol=1e-11, parallel=False)
        return np.where((res.status == COMPLETED)[:, None], res.z, np.nan)

    sol = newton_solve(lambda Z: P(Z) - Z, [-0.37, 1.4, -0.95], tol=1e-10)
    assert sol.status == (SolveStatus.CONVERGED,), sol.status[0].message
    z = sol.x[0]
    assert np.linalg.norm(P(z[None, :])[0] - z) < 1e-10
    h = 1e-6
    J = np.column_stack([(P((z + h * e)[None, :])[0] - P((z - h * e)[None, :])[0]) / (2 * h)
                         for e in np.eye(3)])
    mult = np.sort(np.abs(np.linalg.eigvals(sol.jacobian[0] + np.eye(3))))
    np.testing.assert_allclose(mult, np.sort(np.abs(np.linalg.eigvals(J))), atol=1e-5)


@pytest.mark.parametrize("at_root", [True, False])
def test_no_point_is_evaluated_twice(at_root: bool) -> None:
    # a residual is a whole simulated step: the accepted trial point of the line search is the
    # next iterate, and its F is reused, not computed again
    seen: list[tuple[float, ...]] = []

    def residual(X: np.ndarray) -> np.ndarray:
        seen.extend(tuple(row) for row in X)
        return _circle_line(X)

    starts = np.array([[1.0, 0.5], [-1.0, -3.0], [3.0, 2.9]])
    sol = newton_solve(residual, starts, tol=1e-12, jacobian_at_root=at_root)
    assert list(sol.converged) == [True, True, True]
    assert len(seen) == len(set(seen))
    # and the roots are still the roots
    np.testing.assert_allclose(np.abs(sol.x), np.sqrt(2.0), atol=1e-12)


def test_floquet_multipliers_are_the_eigenvalues_largest_first() -> None:
    # a rotation by 60 deg scaled by 0.5 (multipliers 0.5 e^{+-i pi/3}) beside a real -0.9
    c, s = 0.5 * np.cos(np.pi / 3), 0.5 * np.sin(np.pi / 3)
    basis = np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 3.0], [1.0, 0.0, 1.0]])
    DP = basis @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, -0.9]]) @ np.linalg.inv(basis)
    mult = floquet_multipliers(DP)
    assert mult.dtype == complex and mult.shape == (3,)
    assert mult[0] == pytest.approx(-0.9, abs=1e-12)
    np.testing.assert_allclose(sorted(mult[1:].imag), [-s, s], atol=1e-12)
    np.testing.assert_allclose(mult[1:].real, [c, c], atol=1e-12)
    # a Jacobian that failed (NaN) has no multipliers, and says so with NaN
    DP[1, 2] = np.nan
    assert np.all(np.isnan(floquet_multipliers(DP)))


def test_backend_names_are_checked_in_one_place() -> None:
    from heelstrike.analysis.gait_map import gait_map
    from heelstrike.models.base import BACKEND_NAMES, check_backend_name
    from heelstrike.models.compass import CompassGait

    assert set(BACKEND_NAMES) == {"scipy", "compiled"}
    for name in BACKEND_NAMES:
        check_backend_name(name)
    with pytest.raises(ValueError, match="backend must be 'scipy' or 'compiled', got 'numba'"):
        gait_map(CompassGait(foot_radius=0.0), [0.0], np.deg2rad([3.0, 4.0]), backend="numba")
