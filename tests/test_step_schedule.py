"""The hybrid schedule as data: every walker declares its step, one loop runs them all.

Physics checked on the one loop (:func:`heelstrike.dynamics.hybrid.simulate`) for the paper's
compass gait and the kneed walker: mechanical energy conserved within every phase of a passive
walk, the energy lost at every impact equal to ``T_c`` (eq. 10) and ``T = T_c + T_a``, the
post-impact velocity satisfying ``A q_dot+ = 0`` for the rows the schedule declares; and the
loop obeys a schedule changed by the walker (a guard added, a reset rule switched).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from heelstrike.dynamics import BACKENDS
from heelstrike.dynamics import simulate as simulate_entry
from heelstrike.dynamics.hybrid import simulate
from heelstrike.dynamics.phased import simulate_phased
from heelstrike.models import CompassGait, load_walker
from heelstrike.models.schedule import Guard, Phase, StepSchedule

SLOPE = np.deg2rad(3.0)
#: a post-impact state of the R = 0.3 compass near its stable gait on 3 deg (the fixed point
#: find_limit_cycle gives, rounded to 8 digits: a start, not an expected result)
Z_COMPASS = np.array([-0.38628396, 1.41932714, -0.96794436])


def _compass_start() -> tuple[CompassGait, Any, Any]:
    w = CompassGait(foot_radius=0.3)
    q, qd = w.section_to_state(Z_COMPASS)
    return w, q, qd


def test_one_loop_for_every_walker_on_the_scipy_backend() -> None:
    assert simulate_phased is simulate
    for (kind, backend), entry in BACKENDS.items():
        if backend == "scipy":
            where = (entry.module, entry.function)
            assert where == ("heelstrike.dynamics.hybrid", "simulate"), kind


def test_declared_schedules() -> None:
    compass = CompassGait().step_schedule()
    assert [p.name for p in compass.phases] == ["locked_swing"]
    assert [s.until.name for s in compass.phases[0].stages] == ["midstance", "heel_strike"]
    assert compass.trailing_foot == "lift_rule" and compass.locks == ()
    kneed = load_walker("kneed")
    sched = kneed.step_schedule()
    assert [(p.name, p.reset) for p in sched.phases] == [
        ("knee_swing", "knee_strike"), ("locked_swing", "heel_strike")]
    stance, swing = kneed.stance_and_swing_locks()
    assert sched.phases[0].locked == stance and sched.phases[0].strike_joints == swing
    assert set(sched.phases[1].locked) == set(stance + swing) == set(sched.locks)
    assert sched.trailing_foot == "complementarity"
    assert kneed.compiled_kernel == "generated"

    class _OwnStep(type(kneed)):  # type: ignore[misc]
        def step_schedule(self, *, knee_flex_threshold: float = 1e-6) -> StepSchedule:
            return sched

    own = _OwnStep(kneed.description)
    assert own.compiled_kernel is None and own.backends == ("scipy",)
    assert [p.name for p in load_walker("torso").step_schedule().phases] == ["locked_swing"]
    with pytest.raises(ValueError, match="heel-strike"):
        StepSchedule(phases=(dataclasses.replace(sched.phases[0]),))


def test_compass_walk_energy_and_impacts_through_the_one_loop() -> None:
    w, q, qd = _compass_start()
    walk = simulate(w, q, qd, slope=SLOPE, steps=4)
    assert walk.ok
    assert set(walk.phase) == {"locked_swing"}
    # energy conserved between impacts (passive), dropping by T_c at every heel strike
    for k in range(4):
        e = walk.mechanical_energy[walk.step == k]
        assert np.ptp(e) < 1e-7 * abs(e).max()
    heel = [e for e in walk.events if e.kind == "heel_strike"]
    assert len(heel) == len(walk.impacts) == 4
    for ev, rec in zip(heel, walk.impacts, strict=True):
        assert ev.kinetic_energy_constrained == rec.kinetic_energy_constrained
        assert ev.energy_lost == pytest.approx(ev.kinetic_energy_constrained, rel=1e-12)
        assert ev.kinetic_energy == pytest.approx(
            ev.kinetic_energy_constrained + ev.kinetic_energy_admissible, rel=1e-12)
        assert np.max(np.abs(ev.rows @ ev.q_dot_plus)) < 1e-12  # A q_dot+ = 0
        assert ev.trailing_mode == "separate" and ev.trailing_normal_velocity > 0
        # the striking foot's impulse balances the momentum change: M (q+ - q-) = A^T lambda
        M = w.mass_matrix(ev.q)
        np.testing.assert_allclose(M @ (ev.q_dot_plus - ev.q_dot_minus), ev.rows.T @ ev.impulse,
                                   atol=1e-12)


@pytest.mark.slow
def test_kneed_walk_energy_and_impacts_through_the_one_loop() -> None:
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.phased import PhasedWalker

    kneed = PhasedWalker.from_built(load_walker("kneed"))
    gait = find_model_gait(kneed, slope=0.0504)
    walk = simulate(kneed, *kneed.section_to_state(gait.fixed_point), slope=0.0504, steps=2)
    assert walk.ok
    kinds = [e.kind for e in walk.events]
    assert kinds == ["knee_strike", "heel_strike"] * 2
    for ev in walk.events:
        assert np.max(np.abs(ev.rows @ ev.q_dot_plus)) < 1e-10
        assert ev.energy_lost == pytest.approx(ev.kinetic_energy_constrained, rel=1e-9, abs=1e-12)
    for label in ("knee_swing", "locked_swing"):
        for k in range(2):
            sel = (walk.phase == label) & (walk.step == k)
            e = walk.mechanical_energy[sel]
            assert np.ptp(e) < 1e-7 * abs(e).max()


class _StopAtAngle(CompassGait):
    """The compass gait with one more failure guard declared: a fall forward at q3 = 0.05."""

    def step_schedule(self, *, knee_flex_threshold: float = 1e-6) -> StepSchedule:
        base = super().step_schedule()
        phase = base.phases[0]
        early = Guard(name="fell_forward", function=lambda q, qd: float(q[2]) - 0.05,
                      direction=1)
        stages = tuple(dataclasses.replace(s, failures=(*s.failures, early))
                       for s in phase.stages)
        return dataclasses.replace(base, phases=(dataclasses.replace(phase, stages=stages),))


class _ComplementarityCompass(CompassGait):
    """The compass gait whose heel strike decides the trailing foot by complementarity."""

    def step_schedule(self, *, knee_flex_threshold: float = 1e-6) -> StepSchedule:
        return dataclasses.replace(super().step_schedule(), trailing_foot="complementarity")


def test_the_loop_runs_what_the_walker_declares() -> None:
    w, q, qd = _compass_start()
    stop = _StopAtAngle(foot_radius=0.3)
    walk = simulate(stop, q, qd, slope=SLOPE, steps=3)
    assert walk.status == "fell_forward"
    assert walk.final_q[2] == pytest.approx(0.05, abs=1e-9)
    assert walk.n_steps == 0
    # the compiled compass kernel runs the compass gait's own schedule only: a walker that
    # declares another one runs on the scipy reference only (never silently the wrong step)
    assert w.backends == ("scipy", "compiled") and stop.backends == ("scipy",)
    with pytest.raises(ValueError, match="unsupported backend 'compiled'"):
        simulate_entry(stop, q, qd, slope=SLOPE, backend="compiled")
    # the same physics by complementarity: the trailing foot separates, so the impact is the
    # projector's (same states to round-off)
    ref = simulate(w, q, qd, slope=SLOPE, steps=3)
    comp = simulate(_ComplementarityCompass(foot_radius=0.3), q, qd, slope=SLOPE, steps=3)
    assert comp.ok and ref.ok
    np.testing.assert_allclose(comp.final_q_dot, ref.final_q_dot, rtol=1e-10, atol=1e-12)
    with pytest.raises(ValueError, match="restitution"):
        simulate(_ComplementarityCompass(foot_radius=0.3), q, qd, slope=SLOPE, restitution=0.2)


def test_a_stage_already_past_is_skipped() -> None:
    """From a state past the vertical the compass schedule skips its mid-stance stage: the walk
    equals that of a schedule declaring the heel-strike stage only."""
    w, q, qd = _compass_start()
    base = w.step_schedule()
    only_strike = dataclasses.replace(
        base, phases=(Phase(name="locked_swing", locked=(), reset="heel_strike",
                            stages=(base.phases[0].stages[1],)),))

    class _OneStage(CompassGait):
        def step_schedule(self, *, knee_flex_threshold: float = 1e-6) -> StepSchedule:
            return only_strike

    # from a state already past mid-stance the two schedules are the same walk
    q1, qd1 = w.section_to_state([0.05, 1.0, 0.2])
    a = simulate(w, q1, qd1, slope=SLOPE, steps=1)
    b = simulate(_OneStage(foot_radius=0.3), q1, qd1, slope=SLOPE, steps=1)
    assert a.status == b.status
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.q, b.q)
    # from before the vertical they differ: without the mid-stance stage the heel-strike
    # stage's fall-backward guard (q3 falling through 0) is not the one that applies
    assert base.phases[0].stages[0].skip is not None
    assert not base.phases[0].stages[0].skip(q, qd) and base.phases[0].stages[0].skip(q1, qd1)
