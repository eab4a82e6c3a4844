"""Exact step-map Jacobians (variational equations + saltation matrices) against independent
derivatives of the step map: central differences of the nominal map, and their Richardson
extrapolation at tight tolerances."""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.phased import PhasedWalker, TorsoPD, load_phased_walker
from heelstrike.dynamics.variational import (
    ExactJacobianUnavailable,
    StepFailedError,
    step_jacobian,
)
from heelstrike.models import CompassGait

KNEED_SLOPE = 0.0504
KNEED_GUESS = [-0.2647694, 1.2181144, -1.0955048]
TORSO_GUESS = [-0.1180757, 0.1118158, 0.5531974, -0.0140899, -0.6214368]


def _gait(R: float, slope_deg: float) -> tuple[PoincareMap, np.ndarray]:
    walker = CompassGait(foot_radius=R)
    slope = float(np.deg2rad(slope_deg))
    cycle = find_limit_cycle(walker, slope=slope)
    return PoincareMap(walker=walker, slope=slope), cycle.fixed_point


@pytest.mark.parametrize(("R", "slope_deg"), [(0.0, 1.0), (0.0, 3.0), (0.0, 4.3), (0.0, 5.0),
                                              (0.3, 1.0), (0.3, 3.0), (0.3, 4.3)])
def test_compass_exact_jacobian_matches_central_differences(R: float, slope_deg: float) -> None:
    pmap, z = _gait(R, slope_deg)
    exact = pmap.exact_jacobian(z)
    central = pmap.jacobian(z, 1e-6)
    assert np.allclose(exact.z_next, z, atol=1e-9)  # at the fixed point
    assert np.max(np.abs(exact.jacobian - central)) < 1e-7
    # the multipliers of the exact Jacobian are those of the search (central differences)
    m_exact = np.sort(np.abs(np.linalg.eigvals(exact.jacobian)))
    m_central = np.sort(np.abs(np.linalg.eigvals(central)))
    assert np.allclose(m_exact, m_central, atol=1e-6)


def test_compass_exact_jacobian_matches_richardson_extrapolation() -> None:
    """At rtol = atol = 1e-13 the Richardson extrapolation of central differences
    ``(4 D(h/2) - D(h)) / 3`` (truncation O(h^4)) agrees with the exact Jacobian far below
    central differences' own accuracy: the variational part is exact, not just consistent."""
    walker = CompassGait()
    slope = float(np.deg2rad(3.0))
    z = find_limit_cycle(walker, slope=slope).fixed_point
    tight = PoincareMap(walker=walker, slope=slope, rtol=1e-13, atol=1e-13)
    exact = tight.exact_jacobian(z).jacobian
    h = 2.5e-4
    richardson = (4.0 * tight.jacobian(z, h / 2) - tight.jacobian(z, h)) / 3.0
    plain = tight.jacobian(z, h)
    assert np.max(np.abs(plain - exact)) > 1e-5  # the comparison resolves an O(h^2) error
    assert np.max(np.abs(richardson - exact)) < 1e-9  # measured 2.2e-10 (h^4 = 4e-15)


def test_naive_product_gives_wrong_multipliers() -> None:
    """Without the event-time corrections (saltation and section projection) the product of
    reset and flow Jacobians is a different matrix with different multipliers: on the stable
    3 deg gait it even predicts instability."""
    pmap, z = _gait(0.0, 3.0)
    res = pmap.exact_jacobian(z)
    central = pmap.jacobian(z)
    rho_exact = np.max(np.abs(np.linalg.eigvals(res.jacobian)))
    rho_naive = np.max(np.abs(np.linalg.eigvals(res.naive)))
    rho_central = np.max(np.abs(np.linalg.eigvals(central)))
    assert abs(rho_exact - rho_central) < 1e-6
    assert rho_exact < 1.0 < rho_naive
    assert np.max(np.abs(res.naive - central)) > 1.0


def test_jacobian_method_argument() -> None:
    pmap, z = _gait(0.0, 3.0)
    assert np.array_equal(pmap.jacobian(z, method="exact"), pmap.exact_jacobian(z).jacobian)
    with pytest.raises(ValueError, match="'central' or 'exact'"):
        pmap.jacobian(z, method="forward")


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


def test_kneed_exact_jacobian_through_the_knee_strike(kneed: PhasedWalker) -> None:
    gait = find_model_gait(kneed, slope=KNEED_SLOPE, guess=KNEED_GUESS)
    z = gait.cycle.fixed_point
    pmap = PoincareMap(walker=kneed, slope=KNEED_SLOPE)
    res = pmap.exact_jacobian(z)
    assert res.events == ("knee_strike", "heel_strike")
    central = pmap.jacobian(z, 1e-6)
    assert np.max(np.abs(res.jacobian - central)) < 1e-7
    assert np.max(np.abs(res.naive - central)) > 1.0


def test_torso_exact_jacobian_with_torque_and_push_off() -> None:
    """The torso walker's PD torque (stiff: central differences' truncation error is
    ``~1e4 h^2``) and push-off: the difference to central differences falls as ``h^2``, and
    the Richardson extrapolation agrees with the exact Jacobian."""
    torso = load_phased_walker("torso")
    law, push = TorsoPD(walker=torso), PushOff(impulse=2.0)
    gait = find_model_gait(torso, slope=0.0, guess=TORSO_GUESS, torque=law, push_off=push)
    z = gait.cycle.fixed_point
    pmap = PoincareMap(walker=torso, slope=0.0, torque=law, push_off=push)
    exact = pmap.exact_jacobian(z).jacobian
    errors = [np.max(np.abs(pmap.jacobian(z, h) - exact)) for h in (1e-3, 1e-4)]
    assert 50.0 < errors[0] / errors[1] < 200.0  # O(h^2): the exact Jacobian is their limit
    h = 1e-4
    richardson = (4.0 * pmap.jacobian(z, h / 2) - pmap.jacobian(z, h)) / 3.0
    assert np.max(np.abs(richardson - exact)) < 1e-6 * max(1.0, np.max(np.abs(exact)))


def test_errors() -> None:
    walker = CompassGait()
    with pytest.raises(StepFailedError, match="no step"):
        step_jacobian(walker, [-0.3, -2.0, 0.0], slope=0.05)

    class OwnStep(CompassGait):  # a hand-written walker without a description
        @property
        def compiled_kernel(self) -> None:  # type: ignore[override]
            return None

    with pytest.raises(ExactJacobianUnavailable, match="no generated equations"):
        step_jacobian(OwnStep(), [-0.27, 1.09, -0.72], slope=0.05)
    with pytest.raises(ValueError, match="scipy reference"):
        PoincareMap(walker=walker, slope=0.05, method="compiled").exact_jacobian([-0.27, 1, 0])
