"""Exact parameter derivatives of the step map (the state augmented with the parameters:
variational equations, saltation matrices, section projection, reset Jacobian) against central
differences of the step map, and the exact gait sensitivities built on them against
``method="central"`` and against central differences of converged gaits."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.sensitivity import (
    GAIT_QUANTITY_UNITS,
    _quantities,
    gait_sensitivity,
)
from heelstrike.dynamics.variational import ExactJacobianUnavailable, step_jacobian
from heelstrike.models import CompassGait

SLOPE = float(np.deg2rad(3.0))
TIGHT = {"rtol": 1e-12, "atol": 1e-12}
COMPASS = ("foot_radius", "leg_com_from_hip", "leg_mass", "hip_mass", "leg_length", "slope")


def _changed(pmap: PoincareMap, name: str, value: float) -> PoincareMap:
    if name == "slope":
        return PoincareMap(walker=pmap.walker, slope=value, **TIGHT)
    return PoincareMap(walker=pmap.walker.replace(**{name: value}), slope=pmap.slope, **TIGHT)


def _difference(pmap: PoincareMap, name: str, f: Any, h: float = 1e-5) -> np.ndarray:
    """``d f(map) / dp`` by central differences (second-order one-sided at ``R = 0``, where
    ``R < 0`` is no walker)."""
    p = pmap.slope if name == "slope" else float(pmap.walker.parameters[name])
    if name in ("foot_radius", "R") and p == 0.0:
        return np.asarray((-3.0 * f(pmap) + 4.0 * f(_changed(pmap, name, h))
                           - f(_changed(pmap, name, 2 * h))) / (2 * h))
    return np.asarray((f(_changed(pmap, name, p + h)) - f(_changed(pmap, name, p - h))) / (2 * h))


@pytest.fixture(scope="module", params=[0.0, 0.3], ids=["R=0", "R=0.3"])
def compass(request: pytest.FixtureRequest) -> tuple[PoincareMap, np.ndarray]:
    walker = CompassGait(foot_radius=request.param)
    z = find_limit_cycle(walker, slope=SLOPE, tol=1e-12, **TIGHT).fixed_point
    return PoincareMap(walker=walker, slope=SLOPE, **TIGHT), z


def test_compass_parameter_jacobian_matches_central_differences(
    compass: tuple[PoincareMap, np.ndarray]
) -> None:
    pmap, z = compass
    sj = step_jacobian(pmap.walker, z, slope=SLOPE, parameters=COMPASS, **TIGHT)
    assert sj.parameters == COMPASS
    assert sj.parameter_jacobian.shape == (3, len(COMPASS))
    # the augmented chain leaves D_z P as it was
    plain = step_jacobian(pmap.walker, z, slope=SLOPE, **TIGHT)
    assert np.allclose(sj.jacobian, plain.jacobian, rtol=0, atol=1e-10)
    for k, name in enumerate(COMPASS):
        ref = _difference(pmap, name, lambda m: m(z))
        col = sj.parameter_jacobian[:, k]
        assert np.max(np.abs(col - ref)) <= 1e-7 * np.max(np.abs(ref)), name


def test_compass_quantity_partials_match_central_differences(
    compass: tuple[PoincareMap, np.ndarray]
) -> None:
    """Period (event-time sensitivity), step length, speed, ``T_c`` and ``eta``: partial
    derivatives in ``z`` and in ``p`` against central differences of one step's record."""
    pmap, z = compass
    names = ("leg_com_from_hip", "hip_mass", "slope", "foot_radius")
    sj = step_jacobian(pmap.walker, z, slope=SLOPE, parameters=names, **TIGHT)
    keys = tuple(GAIT_QUANTITY_UNITS)
    values = _quantities(pmap, z)
    for i, key in enumerate(keys):
        assert sj.quantities[key] == pytest.approx(values[i], rel=1e-10), key
    h = 1e-5
    DQz = np.stack([(_quantities(pmap, z + h * e) - _quantities(pmap, z - h * e)) / (2 * h)
                    for e in np.eye(z.size)], axis=-1)
    for i, key in enumerate(keys):
        exact = sj.quantity_state_gradients[key]
        assert np.max(np.abs(exact - DQz[i])) <= 1e-7 * np.max(np.abs(DQz[i])), key
    for k, name in enumerate(names):
        ref = _difference(pmap, name, lambda m: _quantities(m, z))
        for i, key in enumerate(keys):
            scale = max(np.max(np.abs(DQz[i])), abs(ref[i]))
            assert abs(sj.quantity_parameter_gradients[key][k] - ref[i]) <= 1e-7 * scale, \
                (name, key)


@pytest.fixture(scope="module")
def kneed() -> tuple[PoincareMap, np.ndarray]:
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.phased import load_phased_walker

    walker = load_phased_walker("kneed")
    gait = find_model_gait(walker, slope=0.0504, guess=[-0.2647694, 1.2181144, -1.0955048])
    return PoincareMap(walker=walker, slope=0.0504, **TIGHT), gait.fixed_point


def test_kneed_parameter_jacobian_matches_central_differences(
    kneed: tuple[PoincareMap, np.ndarray]
) -> None:
    """Knee strike (saltation in the augmented state), touchdown section (the eliminated hip
    angle moves with the foot radius), heel strike."""
    pmap, z = kneed
    names = ("R", "a1", "mH", "slope")
    sj = step_jacobian(pmap.walker, z, slope=pmap.slope, parameters=names, **TIGHT)
    assert sj.events == ("knee_strike", "heel_strike")
    for k, name in enumerate(names):
        ref = _difference(pmap, name, lambda m: m(z))
        col = sj.parameter_jacobian[:, k]
        assert np.max(np.abs(col - ref)) <= 1e-7 * np.max(np.abs(ref)), name


def test_unknown_parameter_is_named() -> None:
    walker = CompassGait()
    with pytest.raises(ValueError, match="'R' is not a parameter of CompassGait"):
        step_jacobian(walker, [-0.2, 1.0, -0.5], slope=SLOPE, parameters=("R",))


def test_exact_gait_sensitivity_matches_central_method_and_converged_gaits() -> None:
    walker = CompassGait(foot_radius=0.3)
    cycle = find_limit_cycle(walker, slope=SLOPE, tol=1e-12, **TIGHT)
    names = ("foot_radius", "leg_mass", "slope")
    exact = gait_sensitivity(walker, cycle.fixed_point, names, slope=SLOPE)
    central = gait_sensitivity(walker, cycle.fixed_point, names, slope=SLOPE, method="central")
    assert exact.exact == (True, True, True)
    assert central.exact == (False, False, False)
    assert np.allclose(exact.fixed_point, central.fixed_point, rtol=1e-6,
                       atol=1e-6 * np.max(np.abs(central.fixed_point)))
    for q in GAIT_QUANTITY_UNITS:
        assert np.allclose(exact.quantities[q], central.quantities[q], rtol=1e-6,
                           atol=1e-6 * np.max(np.abs(central.quantities[q]))), q
    # the slope's column against central differences of converged gaits (Newton at s +- h)
    h = 1e-4
    plus = find_limit_cycle(walker, slope=SLOPE + h, guess=cycle.fixed_point, tol=1e-12,
                            **TIGHT)
    minus = find_limit_cycle(walker, slope=SLOPE - h, guess=cycle.fixed_point, tol=1e-12,
                             **TIGHT)
    dz = (plus.fixed_point - minus.fixed_point) / (2 * h)
    assert np.max(np.abs(exact.fixed_point[:, 2] - dz)) <= 1e-6 * np.max(np.abs(dz))
    for q in GAIT_QUANTITY_UNITS:
        ref = (getattr(plus, q) - getattr(minus, q)) / (2 * h)
        assert abs(exact.quantities[q][2] - ref) <= 1e-6 * abs(ref), q


def test_fallback_column_is_central(monkeypatch: pytest.MonkeyPatch) -> None:
    """A parameter without an exact derivative falls back to central differences for its
    column only (the other columns stay exact and equal)."""
    import heelstrike.dynamics.variational as variational

    walker = CompassGait(foot_radius=0.3)
    z = find_limit_cycle(walker, slope=SLOPE, tol=1e-12, **TIGHT).fixed_point
    names = ("leg_mass", "hip_mass")
    exact = gait_sensitivity(walker, z, names, slope=SLOPE)
    entry = variational._parameter_entry

    def refuse(w: Any, name: str) -> Any:
        if name == "hip_mass":
            raise ExactJacobianUnavailable(f"parameter {name!r}: refused (test)")
        return entry(w, name)

    monkeypatch.setattr(variational, "_parameter_entry", refuse)
    mixed = gait_sensitivity(walker, z, names, slope=SLOPE)
    assert mixed.exact == (True, False)
    # (the same exact column; the integrator's steps differ with the augmented size)
    assert np.allclose(mixed.fixed_point[:, 0], exact.fixed_point[:, 0], rtol=1e-9, atol=0)
    assert not np.array_equal(mixed.fixed_point[:, 1], exact.fixed_point[:, 1])
    assert np.allclose(mixed.fixed_point[:, 1], exact.fixed_point[:, 1], rtol=1e-6,
                       atol=1e-6 * np.max(np.abs(exact.fixed_point[:, 1])))


def test_kneed_quantity_partials_match_central_differences(
    kneed: tuple[PoincareMap, np.ndarray]
) -> None:
    """Two events (the period is the heel strike's time after a knee strike): the exact
    partials of the step quantities in ``z`` and ``p``."""
    pmap, z = kneed
    names = ("R", "b2")
    sj = step_jacobian(pmap.walker, z, slope=pmap.slope, parameters=names, **TIGHT)
    keys = tuple(GAIT_QUANTITY_UNITS)
    h = 1e-5
    DQz = np.stack([(_quantities(pmap, z + h * e) - _quantities(pmap, z - h * e)) / (2 * h)
                    for e in np.eye(z.size)], axis=-1)
    for i, key in enumerate(keys):
        exact = sj.quantity_state_gradients[key]
        assert np.max(np.abs(exact - DQz[i])) <= 1e-7 * np.max(np.abs(DQz[i])), key
    for k, name in enumerate(names):
        ref = _difference(pmap, name, lambda m: _quantities(m, z))
        for i, key in enumerate(keys):
            scale = max(np.max(np.abs(DQz[i])), abs(ref[i]))
            assert abs(sj.quantity_parameter_gradients[key][k] - ref[i]) <= 1e-7 * scale, \
                (name, key)


def test_kneed_gait_sensitivity_matches_converged_gaits(
    kneed: tuple[PoincareMap, np.ndarray]
) -> None:
    """The kneed walker's gait sensitivities (exact partials) against central differences of
    gaits re-solved by Newton at ``p +- h``."""
    from heelstrike.analysis.model_gaits import find_model_gait

    pmap, z = kneed
    walker = pmap.walker
    names = ("R", "mH")
    sens = gait_sensitivity(walker, z, names, slope=pmap.slope)
    assert sens.exact == (True, True)
    for k, name in enumerate(names):
        p = float(walker.parameters[name])
        h = 1e-4 * max(1.0, abs(p))
        plus, minus = (find_model_gait(walker.replace(**{name: v}), slope=pmap.slope, guess=z,
                                       tol=1e-12, **TIGHT) for v in (p + h, p - h))
        dz = (plus.fixed_point - minus.fixed_point) / (2 * h)
        assert np.max(np.abs(sens.fixed_point[:, k] - dz)) <= 1e-6 * np.max(np.abs(dz)), name
        for q in GAIT_QUANTITY_UNITS:
            ref = (_heel_strike_quantity(plus, q) - _heel_strike_quantity(minus, q)) / (2 * h)
            scale = max(abs(ref), 1e-2 * abs(_heel_strike_quantity(plus, q)) / max(1.0, abs(p)))
            assert abs(sens.quantities[q][k] - ref) <= 1e-6 * scale, (name, q)


def _heel_strike_quantity(gait: Any, q: str) -> float:
    """The gait's quantity ``q`` as :func:`gait_sensitivity` defines it: ``collision_loss``
    and ``eta`` of the heel strike alone (a gait's ``collision_loss`` sums every impact of
    the step, the kneed walker's knee strike too)."""
    if q in ("collision_loss", "eta"):
        loss = float(gait.walk.impacts[0].energy_lost)
        return loss if q == "collision_loss" else loss / float(gait.step_length)
    return float(getattr(gait, q))


def test_profile_foot_parameter_jacobian_matches_central_differences() -> None:
    """A foot given by its support function: the profile's coefficients move the rolling
    radius ``h(0) + h''(0)`` and the generated equations; their exact ``dP/dp`` and step
    quantities agree with central differences (a profile's radius was evaluated as an arc's,
    which has none: the design command failed on every profile foot)."""
    from pathlib import Path

    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.phased import load_phased_walker

    path = Path(__file__).resolve().parents[1] / "examples" / "walkers" / "compass_foot6.toml"
    walker = load_phased_walker(path)
    slope = 0.05
    z = find_model_gait(walker, slope=slope, backend="scipy", tol=1e-12).fixed_point
    pmap = PoincareMap(walker=walker, slope=slope, **TIGHT)
    names = ("R", "d", "k2", "s3")
    sj = step_jacobian(walker, z, slope=slope, parameters=names, **TIGHT)
    keys = tuple(GAIT_QUANTITY_UNITS)
    def richardson(f: Any, name: str) -> np.ndarray:
        # the profile's coefficients have a small natural scale (0.01 m): the plain central
        # difference's h^2 error is 1.5e-7 relative at h = 1e-5; extrapolated it is not
        return (4.0 * _difference(pmap, name, f, 5e-6) - _difference(pmap, name, f, 1e-5)) / 3.0

    for k, name in enumerate(names):
        ref = richardson(lambda m: m(z), name)
        col = sj.parameter_jacobian[:, k]
        assert np.max(np.abs(col - ref)) <= 1e-7 * np.max(np.abs(ref)), name
        qref = richardson(lambda m: _quantities(m, z), name)
        for i, key in enumerate(keys):
            got = sj.quantity_parameter_gradients[key][k]
            assert abs(got - qref[i]) <= 1e-6 * max(abs(qref[i]), 1e-3), (name, key)
