"""The compiled walking path against the scipy reference :func:`simulate`."""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.dynamics import compiled
from heelstrike.dynamics.compiled import (
    STATUS_NAMES,
    ensemble_walk,
    single_support_compiled,
    step_map_compiled,
)
from heelstrike.dynamics.hybrid import WalkStatus, simulate
from heelstrike.dynamics.single_support import SingleSupport
from heelstrike.models.compass import CompassGait

SLOPE3 = np.deg2rad(3.0)
Z3 = np.array([-0.27102868, 1.09238359, -0.71500964])  # passive gait, R = 0, 3 deg
TOL = dict(rtol=1e-12, atol=1e-12)


def _reference(walker, z, slope, steps):
    q, qd = walker.section_to_state(z)
    return simulate(walker, q, qd, slope=slope, steps=steps, **TOL)


def test_status_names_are_walk_status_values():
    assert STATUS_NAMES == tuple(s.value for s in WalkStatus)


def reduced_dynamics_compiled(walker, state, slope):
    """The compiled kernel's single-support accelerations (N, 2) and ground reactions (N, 2)
    (tangential, normal; N) at reduced states ``(q3, q4, q3_dot, q4_dot)``, one call per row."""
    p = compiled.walker_parameters(walker, slope)
    Y = np.atleast_2d(np.asarray(state, dtype=float))
    out = np.array([compiled._serial().dynamics(p, np.ascontiguousarray(y)) for y in Y])
    return out[:, :2], out[:, 2:]


@pytest.mark.parametrize("radius", [0.0, 0.3, 0.9])
def test_reduced_dynamics_equal_single_support(radius):
    rng = np.random.default_rng(7)
    walker = CompassGait(foot_radius=radius, leg_inertia=0.03, hip_mass=8.0, leg_mass=3.0)
    sup = SingleSupport(walker=walker, slope=0.07)
    Y = np.column_stack(
        (rng.uniform(-0.7, 0.7, 30), rng.uniform(-1.2, 1.2, 30), rng.uniform(-3, 3, (30, 2)))
    )
    acc, lam = reduced_dynamics_compiled(walker, Y, 0.07)
    for y, a, f in zip(Y, acc, lam, strict=True):
        q = np.array([0.3, radius, y[0], y[1]])
        qd = np.array([-radius * y[2], 0.0, y[2], y[3]])
        ref = sup.accelerations(0.0, q, qd)
        np.testing.assert_allclose(a, ref[2:], rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(f, sup.ground_reaction(0.0, q, qd), rtol=1e-10, atol=1e-9)


CASES = [
    # radius, slope (rad), z0, steps
    (0.0, SLOPE3, Z3, 3),
    (0.0, SLOPE3, [-0.26, 1.13, -0.53], 3),
    (0.2, np.deg2rad(2.0), [-0.35, 1.59, -1.9], 3),
    (0.5, np.deg2rad(4.0), [-0.39, 1.4, 0.21], 3),
    (0.8, 0.01, [-0.32, 1.27, -0.5], 3),
]


@pytest.mark.parametrize(("radius", "slope", "z0", "steps"), CASES)
def test_compiled_walk_matches_reference(radius, slope, z0, steps):
    walker = CompassGait(foot_radius=radius)
    ref = _reference(walker, z0, slope, steps)
    ens = ensemble_walk(walker, z0, slope, steps=steps, **TOL)
    assert STATUS_NAMES[ens.status[0]] == ref.status.value
    assert ens.steps[0] == ref.n_steps
    assert ref.ok, ref.message  # these cases walk
    n = ref.n_steps
    np.testing.assert_allclose(ens.impact_angle[0, :n], ref.impact_array("impact_angle"),
                               atol=1e-8)
    np.testing.assert_allclose(np.cumsum(ens.step_time[0, :n]), ref.impact_array("time"),
                               atol=1e-8)
    np.testing.assert_allclose(ens.collision_loss[0, :n],
                               ref.impact_array("kinetic_energy_constrained"), atol=1e-8)
    np.testing.assert_allclose(ens.step_length[0, :n], ref.impact_array("step_length"),
                               atol=1e-8)
    z_ref = walker.state_to_section(ref.final_q, ref.final_q_dot)
    np.testing.assert_allclose(ens.z[0], z_ref, atol=1e-8)
    one = step_map_compiled(walker, z0, slope, **TOL)
    assert one.status is WalkStatus.COMPLETED
    rec = ref.impacts[0]
    assert abs(one.step_time - rec.step_duration) < 1e-8
    assert abs(one.collision_loss - rec.kinetic_energy_constrained) < 1e-8
    assert abs(one.impact_angle - rec.impact_angle) < 1e-8
    z1_ref = walker.state_to_section(*walker.swap_legs(rec.q, rec.q_dot_plus))
    np.testing.assert_allclose(one.z, z1_ref, atol=1e-8)


FAILURES = [
    # a walker launched too slowly stops before mid-stance and falls backward
    (0.0, SLOPE3, [-0.3, 0.3, 0.0], "fell_backward", 0),
    (0.2, 0.05, [-0.493, 0.017, 0.096], "fell_backward", 0),
    (0.5, 0.05, [-0.1, 1.004, -0.461], "fell_forward", 0),
    (0.0, 0.05, [-0.134, 1.13, 0.415], "lost_contact", 0),
    (0.0, 0.0587, [-0.48725615, 1.84898854, -0.41007071], "trailing_foot_stays", 1),
]


@pytest.mark.parametrize(("radius", "slope", "z0", "status", "n"), FAILURES)
def test_failures_match_reference(radius, slope, z0, status, n):
    walker = CompassGait(foot_radius=radius)
    ref = _reference(walker, z0, slope, 3)
    ens = ensemble_walk(walker, z0, slope, steps=3, **TOL)
    assert ref.status.value == status
    assert STATUS_NAMES[ens.status[0]] == status
    assert ens.steps[0] == ref.n_steps == n
    one = step_map_compiled(walker, z0, slope, **TOL)
    assert one.status.value == status
    assert np.all(np.isnan(one.z))
    # the state where the walk ended agrees with the reference
    y_ref = np.array([ref.final_q[2], ref.final_q[3], ref.final_q_dot[2], ref.final_q_dot[3]])
    np.testing.assert_allclose(ens.state[0], y_ref, atol=1e-7)


def test_ensemble_equals_loop_of_single_walkers():
    rng = np.random.default_rng(3)
    n = 24
    z = np.column_stack(
        (rng.uniform(-0.35, -0.2, n), rng.uniform(0.9, 1.4, n), rng.uniform(-1.0, -0.4, n))
    )
    radius = rng.choice([0.0, 0.1, 0.4], n)
    slope = rng.uniform(0.02, 0.07, n)
    ens = ensemble_walk(CompassGait(foot_radius=radius), z, slope, steps=4, parallel=True)
    assert len(set(ens.status.tolist())) > 1  # both walks and failures in the ensemble
    for i in range(n):
        one = ensemble_walk(CompassGait(foot_radius=radius[i]), z[i], slope[i], steps=4,
                            parallel=False)
        assert one.status[0] == ens.status[i]
        assert one.steps[0] == ens.steps[i]
        np.testing.assert_array_equal(one.state[0], ens.state[i])
        np.testing.assert_array_equal(one.step_time[0], ens.step_time[i])
        np.testing.assert_array_equal(one.collision_loss[0], ens.collision_loss[i])


def test_stop_near_target_stops_converged_walkers_early():
    walker = CompassGait()
    z = np.array([Z3, Z3 + np.array([0.01, 0.02, 0.0])])
    ens = ensemble_walk(walker, z, SLOPE3, steps=200, stop_near=(Z3, 1e-5), record=False)
    assert np.all(ens.status == 0)
    assert ens.steps[0] == 1 and 1 < ens.steps[1] < 200
    assert np.linalg.norm(ens.z[1] - Z3) < 1e-5


@pytest.mark.parametrize("radius", [0.0, 0.4])
def test_compiled_single_support_conserves_energy(radius):
    walker = CompassGait(foot_radius=radius, leg_inertia=0.05)
    y0 = np.array([-0.25, 0.5, 1.2, -0.6])
    ys = single_support_compiled(walker, y0, SLOPE3, 0.6, rtol=1e-12, atol=1e-12)
    assert len(ys) > 20
    ys = np.vstack((y0, ys))
    q = np.column_stack((-radius * ys[:, 0], np.full(len(ys), radius), ys[:, 0], ys[:, 1]))
    qd = np.column_stack((-radius * ys[:, 2], np.zeros(len(ys)), ys[:, 2], ys[:, 3]))
    E = walker.mechanical_energy(q, qd, SLOPE3)
    assert np.ptp(ys[:, 0]) > 0.2  # a substantial motion
    assert np.ptp(E) < 1e-9 * abs(E[0]) + 1e-9


def test_compiled_walk_rejects_other_walkers_and_bad_input():
    with pytest.raises(ValueError, match="steps"):
        ensemble_walk(CompassGait(), Z3, SLOPE3, steps=0)
    with pytest.raises(ValueError, match="shape"):
        ensemble_walk(CompassGait(), [1.0, 2.0], SLOPE3)
    with pytest.raises(TypeError):
        ensemble_walk(object(), Z3, SLOPE3)  # type: ignore[arg-type]


def test_poincare_map_compiled_method_matches_scipy():
    from heelstrike.analysis.limit_cycle import PoincareMap

    walker = CompassGait(foot_radius=0.2)
    z = np.array([-0.3, 1.1, -0.6])
    fast = PoincareMap(walker=walker, slope=SLOPE3, method="compiled")
    ref = PoincareMap(walker=walker, slope=SLOPE3)
    np.testing.assert_allclose(fast(z), ref(z), atol=1e-8)
    assert np.all(np.isnan(fast([-0.3, 0.3, 0.0])))  # a fall gives NaN, as the scipy map
    with pytest.raises(ValueError, match="method"):
        PoincareMap(walker=walker, method="euler")
