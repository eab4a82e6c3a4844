"""Newton's method on the exact Jacobian of the step map (issue 33, leftovers).

``find_limit_cycle(..., jacobian="exact")`` (the default) evaluates every Newton iterate with
:meth:`PoincareMap.exact_jacobian` (variational equations and saltation matrices: ``P(z)`` and
``DP(z)`` from one step) where it applies, and central differences of the map elsewhere. Checked:

- the same fixed points as Newton on central differences (the route before), to 1e-10, on the
  compass gait and on the kneed walker (a knee strike inside the step), with the Jacobian
  used recorded on the gait;
- quadratic convergence: the residuals of successive iterates obey ``r_{k+1} <= C r_k^2``
  on the compass gait from a start 0.44 away; the same criterion fails for Newton on the naive
  product of reset and flow Jacobians (no saltation terms: linear convergence at best), so the
  test can tell a wrong Jacobian;
- the fall-back to differences where the exact Jacobian does not apply (compiled map, actuated
  walk, a walker whose period is two steps), and the refusal of an unknown ``jacobian``.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.limit_cycle import (
    PoincareMap,
    _exact_newton_ok,
    _exact_pairs,
    find_limit_cycle,
    find_limit_cycles,
)
from heelstrike.analysis.newton import floquet_multipliers, newton_solve
from heelstrike.dynamics.backends import simulator as backend_simulator
from heelstrike.dynamics.phased import load_phased_walker
from heelstrike.models import CompassGait
from heelstrike.status import SolveStatus

SLOPE = float(np.deg2rad(3.0))
GUESS = [-0.26, 1.1, -0.7]
KNEED_SLOPE = 0.0504
# 0.02 rad and rad/s off the kneed gait (-0.2647694, 1.2181144, -1.0955048): several iterates
KNEED_GUESS = [-0.2447694, 1.2381144, -1.0755048]
AMPUTEE = Path(__file__).resolve().parents[1] / "examples" / "walkers" / "amputee.toml"


def test_compass_fixed_point_and_multipliers_as_with_central_differences() -> None:
    exact = find_limit_cycle(CompassGait(), slope=SLOPE, guess=GUESS)
    central = find_limit_cycle(CompassGait(), slope=SLOPE, guess=GUESS, jacobian="central")
    assert exact.newton_jacobian == "exact" and central.newton_jacobian == "central"
    assert np.max(np.abs(exact.fixed_point - central.fixed_point)) < 1e-10
    assert exact.residual < 1e-10 and central.residual < 1e-10
    # the multipliers: the exact Jacobian at the root (Newton's own) is the one the central
    # route computes afterwards for a passive walk on the scipy reference
    np.testing.assert_allclose(exact.multipliers, central.multipliers, rtol=0, atol=1e-12)


def test_kneed_fixed_point_as_with_central_differences() -> None:
    kneed = load_phased_walker("kneed")
    sim = backend_simulator(kneed, "scipy")  # as find_model_gait(backend="scipy") runs it
    exact = find_limit_cycle(kneed, slope=KNEED_SLOPE, guess=KNEED_GUESS, simulator=sim)
    central = find_limit_cycle(kneed, slope=KNEED_SLOPE, guess=KNEED_GUESS, simulator=sim,
                               jacobian="central")
    assert exact.newton_jacobian == "exact" and central.newton_jacobian == "central"
    assert exact.iterations >= 3  # started away from the gait
    assert np.max(np.abs(exact.fixed_point - central.fixed_point)) < 1e-10
    # central differences of the map (1e-6 steps) agree with the exact Jacobian to ~1e-8
    np.testing.assert_allclose(np.abs(exact.multipliers), np.abs(central.multipliers),
                               rtol=0, atol=1e-6)


def _residual_history(pmap: PoincareMap, z0: list[float], naive: bool
                      ) -> tuple[SolveStatus, np.ndarray]:
    """Newton's residual norms at every point it evaluated (with the default line search
    every finite trial is taken: these are the iterates)."""
    pairs = _exact_pairs(pmap, 1e-6, set())
    norms: list[float] = []

    def derivative(Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        F, J = pairs(Z)
        if naive:  # reset times flow Jacobians, no saltation: the event-time shift ignored
            for i, z in enumerate(np.atleast_2d(Z)):
                if np.all(np.isfinite(F[i])):
                    J[i] = pmap.exact_jacobian(z).naive - np.eye(z.size)
        norms.extend(np.linalg.norm(F, axis=1))
        return F, J

    sol = newton_solve(lambda Z: pmap.many(Z) - Z, z0, tol=1e-13, max_iter=12,
                       jacobian="exact", derivative=derivative)
    return sol.status[0], np.asarray(norms)


def _quadratic(r: np.ndarray, C: float, floor: float) -> tuple[int, bool]:
    """Pairs ``(r_k, r_{k+1})`` with ``r_k < 0.02`` and ``r_{k+1}`` above the integrator's
    noise ``floor``, and whether each obeys ``r_{k+1} <= C r_k^2``."""
    pairs = [(a, b) for a, b in itertools.pairwise(r)
             if a < 0.02 and np.isfinite(b) and b > floor]
    return len(pairs), all(b <= C * a * a for a, b in pairs)


def test_exact_newton_converges_quadratically_on_the_compass() -> None:
    pmap = PoincareMap(walker=CompassGait(), slope=SLOPE)
    start = [-0.2, 1.0, -0.5]  # |P(z) - z| = 0.44
    status, r = _residual_history(pmap, start, naive=False)
    assert status is SolveStatus.CONVERGED
    # r: 0.44, 0.14, 0.11, 1.5e-2, 8.7e-4, 1.8e-6, 9.6e-12, 7e-15 (ratios r_{k+1}/r_k^2 2-4)
    checked, quadratic = _quadratic(r, C=10.0, floor=1e-12)
    assert checked >= 3, r
    assert quadratic, r
    assert r[-1] < 1e-13
    # the naive Jacobian, even from 1e-3 off the gait: no such contraction (the criterion
    # can fail)
    z_star = find_limit_cycle(CompassGait(), slope=SLOPE, guess=GUESS).fixed_point
    _, r_n = _residual_history(pmap, list(z_star + 1e-3), naive=True)
    checked_n, quadratic_n = _quadratic(r_n, C=10.0, floor=1e-12)
    assert checked_n >= 1 and not quadratic_n, r_n


def test_differences_where_the_exact_jacobian_does_not_apply() -> None:
    compass = CompassGait()
    assert _exact_newton_ok(PoincareMap(walker=compass, slope=SLOPE))
    assert not _exact_newton_ok(PoincareMap(walker=compass, slope=SLOPE, method="compiled"))
    assert not _exact_newton_ok(
        PoincareMap(walker=compass, slope=SLOPE, torque=lambda t, q, qd: np.zeros(4)))
    amputee = load_phased_walker(AMPUTEE)
    assert amputee.steps_per_period == 2  # the stride map: two steps, not step_jacobian's one
    assert not _exact_newton_ok(PoincareMap(walker=amputee, slope=SLOPE))
    compiled = find_limit_cycle(compass, slope=SLOPE, guess=GUESS, method="compiled")
    assert compiled.newton_jacobian == "central"


def test_unknown_jacobian_is_refused() -> None:
    with pytest.raises(ValueError, match="jacobian must be one of 'exact', 'central', got "
                                         "'forward'"):
        find_limit_cycle(CompassGait(), slope=SLOPE, guess=GUESS, jacobian="forward")
    with pytest.raises(ValueError, match="jacobian must be one of"):  # before any search
        find_limit_cycles(CompassGait(), slope=SLOPE, jacobian="forward", time_limit=1e-9)
    with pytest.raises(ValueError, match="jacobian='exact' needs derivative"):
        newton_solve(lambda X: X, [1.0], tol=1e-12, jacobian="exact")


def test_exact_newton_on_a_closed_form_root() -> None:
    """``jacobian="exact"`` on x^2 + y^2 = 4, y = x with its analytic Jacobian: the root
    (sqrt 2, sqrt 2) to round-off, one ``derivative`` call per iterate (no differences), the
    Jacobian at the root returned."""
    calls: list[int] = []

    def derivative(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        calls.append(X.shape[0])
        x, y = X[:, 0], X[:, 1]
        F = np.stack((x * x + y * y - 4.0, y - x), axis=1)
        J = np.stack((np.stack((2 * x, 2 * y), axis=1),
                      np.stack((-np.ones_like(x), np.ones_like(y)), axis=1)), axis=1)
        return F, J

    sol = newton_solve(lambda X: derivative(X)[0], [[1.0, 0.5]], tol=1e-14, jacobian="exact",
                       derivative=derivative)
    r2 = np.sqrt(2.0)
    assert sol.status[0] is SolveStatus.CONVERGED and sol.method == "exact"
    np.testing.assert_allclose(sol.x[0], [r2, r2], rtol=0, atol=1e-15)
    np.testing.assert_allclose(sol.jacobian[0], [[2 * r2, 2 * r2], [-1.0, 1.0]], atol=1e-14)
    assert all(c == 1 for c in calls) and len(calls) == sol.iterations[0]


def test_a_stride_map_has_no_one_step_exact_jacobian() -> None:
    """A walker whose legs differ maps a stride (two steps): the one-step exact Jacobian is not
    its map's (its multipliers 0.55, 0.55, 0.22 against the stride map's 0.44, 0.22, 0.02), so
    it is refused, and the gait's multipliers are central differences of the stride map."""
    from heelstrike.dynamics.variational import ExactJacobianUnavailable

    amputee = load_phased_walker(AMPUTEE)
    pmap = PoincareMap(walker=amputee, slope=SLOPE)
    with pytest.raises(ExactJacobianUnavailable, match="stride map"):
        pmap.exact_jacobian([-0.3, 1.2, -0.8])
    gait = find_limit_cycle(amputee, slope=SLOPE, guess=[-0.3, 1.2, -0.8])
    assert gait.newton_jacobian == "central"
    stride = floquet_multipliers(pmap.jacobian(gait.fixed_point))
    np.testing.assert_allclose(gait.multipliers, stride, rtol=0, atol=1e-6)
