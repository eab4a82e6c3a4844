"""Phased hybrid simulation of described walkers: energy, impacts, gaits, energy books."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from heelstrike.analysis.limit_cycle import find_limit_cycle
from heelstrike.analysis.model_gaits import (
    Gait,
    find_model_gait,
    model_heel_strike,
    symmetric_heel_strike_state,
)
from heelstrike.core.impact import impact
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.phased import (
    PhasedWalker,
    TorsoPD,
    load_phased_walker,
    simulate_phased,
)
from heelstrike.models import CompassGait

KNEED_SLOPE = 0.0504
KNEED_GUESS = [-0.2647694, 1.2181144, -1.0955048]
COMPASS_SLOPE = 0.05
TORSO_GUESS = [-0.1180757, 0.1118158, 0.5531974, -0.0140899, -0.6214368]
TORSO_PUSH = 2.0


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


@pytest.fixture(scope="module")
def torso() -> PhasedWalker:
    return load_phased_walker("torso")


@pytest.fixture(scope="module")
def kneed_gait(kneed: PhasedWalker) -> Gait:
    return find_model_gait(kneed, slope=KNEED_SLOPE, guess=KNEED_GUESS)


@pytest.fixture(scope="module")
def torso_gait(torso: PhasedWalker) -> Gait:
    return find_model_gait(
        torso, slope=0.0, guess=TORSO_GUESS, torque=TorsoPD(walker=torso),
        push_off=PushOff(impulse=TORSO_PUSH),
    )


def _segments(t: np.ndarray) -> list[tuple[int, int]]:
    cuts = [0, *list(np.flatnonzero(np.diff(t) == 0) + 1), len(t)]
    return [(a, b - 1) for a, b in itertools.pairwise(cuts) if b - a > 1]


def test_lock_split(kneed: PhasedWalker) -> None:
    assert kneed.stance_and_swing_locks() == ((3,), (5,))


def test_energy_conserved_in_every_phase_kneed(kneed: PhasedWalker) -> None:
    q, qd = kneed.section_to_state(KNEED_GUESS)
    walk = simulate_phased(kneed, q, qd, slope=KNEED_SLOPE, steps=2)
    assert walk.ok
    assert {"knee_swing", "locked_swing"} <= set(walk.phase)
    segs = _segments(walk.t)
    assert len(segs) >= 4  # two phases per step (the armed sub-phase may add more)
    E = walk.mechanical_energy
    for a, b in segs:
        assert np.ptp(E[a : b + 1]) < 1e-8 * max(1.0, abs(E[a]))
    # ...while every impact loses exactly its T_c
    for ev in walk.events:
        assert ev.kinetic_energy_constrained > 0
        assert ev.energy_lost == pytest.approx(ev.kinetic_energy_constrained, rel=1e-12)


def test_energy_conserved_in_every_phase_compass_and_torso(torso: PhasedWalker) -> None:
    compass = load_phased_walker("compass")
    q, qd = compass.section_to_state([-0.26682122, 1.08394013, -0.68587173])
    walk = simulate_phased(compass, q, qd, slope=COMPASS_SLOPE, steps=1)
    assert walk.ok
    for a, b in _segments(walk.t):
        assert np.ptp(walk.mechanical_energy[a : b + 1]) < 1e-8
    # powered torso walker: E - W_act is conserved; W_act is not trivially zero
    q, qd = torso.section_to_state(TORSO_GUESS)
    walk = simulate_phased(torso, q, qd, steps=1, torque=TorsoPD(walker=torso, angle=0.05))
    assert walk.ok
    assert np.ptp(walk.actuator_work) > 1e-3
    conserved = walk.mechanical_energy - walk.actuator_work
    for a, b in _segments(walk.t):
        assert np.ptp(conserved[a : b + 1]) < 1e-7
        assert np.ptp(walk.mechanical_energy[a : b + 1]) > 1e-4


@pytest.mark.slow  # kneed gait: sympy + numba build on a cold cache (~90 s)
def test_knee_strike_is_an_inert_lock(kneed: PhasedWalker, kneed_gait: Gait) -> None:
    knee = [e for e in kneed_gait.impacts if e.kind == "knee_strike"]
    assert len(knee) == 1
    ev = knee[0]
    assert ev.kinetic_energy_constrained > 1e-3
    assert ev.kinetic_energy == pytest.approx(
        ev.kinetic_energy_constrained + ev.kinetic_energy_admissible, rel=1e-12
    )
    np.testing.assert_allclose(ev.lock_velocity_post, 0.0, atol=1e-12)
    assert abs(ev.q_dot_minus[5]) > 1e-2  # the knee really was moving into its stop
    # the stance foot keeps rolling through the knee strike
    np.testing.assert_allclose(kneed.contact_jacobian(ev.q, "right") @ ev.q_dot_plus, 0, atol=1e-12)
    # and the result is the projector of [A_R; locks]
    A = np.vstack((kneed.contact_jacobian(ev.q, "right"), kneed.lock_jacobian()))
    ref = impact(kneed.mass_matrix(ev.q), A, ev.q_dot_minus)
    np.testing.assert_allclose(ev.q_dot_plus, ref.velocity_post, atol=1e-12)


@pytest.mark.slow  # kneed gait: sympy + numba build on a cold cache (~90 s)
def test_complementarity_agrees_with_single_contact(kneed_gait: Gait,
                                                    kneed: PhasedWalker) -> None:
    hs = next(e for e in kneed_gait.impacts if e.kind == "heel_strike")
    assert hs.trailing_mode == "separate" and hs.trailing_normal_velocity > 0
    A = np.vstack((kneed.contact_jacobian(hs.q, "left"), kneed.lock_jacobian()))
    single = impact(kneed.mass_matrix(hs.q), A, hs.q_dot_minus)
    np.testing.assert_allclose(hs.q_dot_plus, single.velocity_post, atol=1e-12)
    assert hs.kinetic_energy_constrained == pytest.approx(
        float(single.kinetic_energy_constrained), rel=1e-12
    )
    # a steep heel strike of the point-foot kneed walker: the trailing foot does not lift,
    # and the single-contact answer would pull it into the ground
    w = kneed.replace(R=0.0)
    q, qd = symmetric_heel_strike_state(w, 0.45)
    res = model_heel_strike(w, q, qd)
    single = impact(w.mass_matrix(q), np.vstack((w.contact_jacobian(q, "left"),
                                                 w.lock_jacobian())), qd)
    assert not res.trailing_foot_lifts
    assert (w.contact_jacobian(q, "right") @ single.velocity_post)[1] < 0


@pytest.mark.slow
def test_builder_compass_gait_equals_compass_gait() -> None:
    ref = find_limit_cycle(CompassGait(), slope=COMPASS_SLOPE,
                           guess=[-0.27, 1.09, -0.70])
    w = load_phased_walker("compass")
    g = find_model_gait(w, slope=COMPASS_SLOPE, guess=[-0.25, 1.0, -0.6])
    np.testing.assert_allclose(g.fixed_point, ref.fixed_point, atol=1e-8)
    assert g.period == pytest.approx(ref.period, abs=1e-8)
    assert g.collision_loss == pytest.approx(ref.collision_loss, rel=1e-7)
    np.testing.assert_allclose(np.abs(g.multipliers), np.abs(ref.multipliers), atol=1e-5)
    assert abs(g.energy_residual) < 1e-8


@pytest.mark.slow
def test_automatic_model_gait_is_the_stable_one_the_compass_path_finds() -> None:
    """Without a guess, ``find_model_gait`` prefers a stable gait, as ``find_limit_cycles`` does:
    the builder compass at 3 deg gave the unstable short-step gait (|m| 4.3) although the
    stable one (|m| 0.58) exists, so ``basin``/``map --model compass`` reported no stable gait."""
    from heelstrike.analysis.limit_cycle import find_limit_cycles

    ref = find_limit_cycles(CompassGait(), slope=COMPASS_SLOPE)[0]
    assert ref.stable
    g = find_model_gait(load_phased_walker("compass"), slope=COMPASS_SLOPE)
    assert g.stable
    np.testing.assert_allclose(g.fixed_point, ref.fixed_point, atol=1e-8)
    assert g.spectral_radius == pytest.approx(ref.spectral_radius, abs=1e-5)


@pytest.mark.slow  # kneed gait: sympy + numba build on a cold cache (~90 s)
def test_kneed_passive_gait_energy_book(kneed_gait: Gait) -> None:
    g = kneed_gait
    assert g.residual < 1e-10
    assert g.stable
    kinds = [e.kind for e in g.impacts]
    assert kinds == ["knee_strike", "heel_strike"]
    assert g.actuator_work == 0.0
    assert g.collision_loss == pytest.approx(sum(e.kinetic_energy_constrained
                                                 for e in g.impacts), rel=1e-14)
    assert g.potential_energy_released == pytest.approx(g.collision_loss, rel=1e-8)
    assert abs(g.energy_residual) < 1e-8
    assert g.step_length > 0.3


@pytest.mark.slow
def test_torso_powered_level_gait_energy_book(torso_gait: Gait) -> None:
    g = torso_gait
    assert g.slope == 0.0
    assert g.residual < 1e-10
    assert g.stable
    assert abs(g.potential_energy_released) < 1e-8  # level ground, periodic
    assert g.actuator_work > 0
    assert g.actuator_work == pytest.approx(g.collision_loss, rel=1e-7)
    assert abs(g.energy_residual) < 1e-8
    # the torso is held up: its absolute angle stays near vertical all step
    walk = g.walk
    assert np.max(np.abs(walk.q[:, 2] + walk.q[:, 4])) < 0.1
