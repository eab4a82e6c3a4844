"""Walker files declare their heel-strike guard and reset (``[events]``, issue 32 item 1).

McGeer's wheel (``walkers/wheel.toml``: feet of radius ``l`` centred on the hip, one circle)
cannot be walked with the swing foot's clearance as its guard (zero throughout a step); its
file declares the symmetric configuration ``2 stance_leg + hip`` and a trailing foot that may
graze. Its passive walk on the generated path (scipy backend) is checked step by step against
the hand-written :class:`~heelstrike.models.CompassGait` at ``R = l`` (its own equations, its
own guard ``2 q3 + q4``), whose one-step walks end with the grazing trailing foot and are
chained by relabelling the legs: the states at the strikes agree to 1e-8. Refusals of bad
tables, and the default (no table) unchanged, are checked too.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import heelstrike
from heelstrike.dynamics import simulate as simulate_entry
from heelstrike.dynamics.hybrid import WalkStatus, heel_strike, simulate
from heelstrike.dynamics.phased import load_phased_walker
from heelstrike.models import CompassGait, load_walker
from heelstrike.models.builder import BuiltWalker, walker_description
from heelstrike.models.description import ModelDescriptionError, parse_description

WALKERS = Path(heelstrike.__file__).parent / "walkers"
SLOPE = np.deg2rad(1.0)
#: a post-strike start (q3, q3_dot, q4_dot) from which the passive wheel walks on 1 deg
Z_WHEEL = np.array([-0.25, 0.8, 0.0])
#: compass.toml (R = 0) near its gait (test_backend_conformance's COMPASS_GAIT, slope 0.05)
COMPASS_SLOPE = 0.05
COMPASS_GAIT = np.array([-0.26682122, 1.08394013, -0.68587173])


def _compass_chain(walker: CompassGait, q: Any, qd: Any, steps: int) -> list[Any]:
    """CompassGait's wheel walk: one-step walks (each ends at its strike, the trailing foot
    grazing: ``trailing_foot_stays``), chained by relabelling the legs; the strike records
    with times from the start of the walk."""
    records, t0 = [], 0.0
    for _ in range(steps):
        walk = simulate(walker, q, qd, slope=SLOPE, steps=1, rtol=1e-11, atol=1e-11)
        assert walk.status is WalkStatus.TRAILING_FOOT_STAYS  # its lift rule: no lift
        (rec,) = walk.impacts
        records.append((t0 + rec.time, rec))
        t0 += rec.time
        q, qd = walker.swap_legs(rec.q, rec.q_dot_plus)
    return records


def test_wheel_walks_compass_gaits_wheel_steps_on_the_generated_path() -> None:
    wheel = load_phased_walker("wheel")
    compass = CompassGait(foot_radius=1.0)  # R = l, every other parameter as wheel.toml's
    assert dict(wheel.parameters) == {"I": 0.0, "b": 0.5, "g": 9.81, "l": 1.0, "m": 5.0,
                                      "mH": 10.0}
    q, qd = compass.section_to_state(Z_WHEEL)
    q_w, qd_w = wheel.section_to_state(wheel.section_point(*Z_WHEEL))
    np.testing.assert_array_equal(q_w, q)  # the declared guard places the hip on the section
    np.testing.assert_array_equal(qd_w, qd)
    steps = 6
    walk = simulate_entry(wheel, q, qd, slope=SLOPE, steps=steps, rtol=1e-11, atol=1e-11)
    assert walk.status is WalkStatus.COMPLETED and walk.n_steps == steps
    ref = _compass_chain(compass, q, qd, steps)
    heel = [e for e in walk.events if e.kind == "heel_strike"]
    for k, ((t_ref, r), a, e) in enumerate(zip(ref, walk.impacts, heel, strict=True)):
        what = f"strike {k}"
        assert a.time == pytest.approx(t_ref, abs=1e-8), what
        for name in ("q", "q_dot_minus", "q_dot_plus"):
            np.testing.assert_allclose(getattr(a, name), getattr(r, name), rtol=0, atol=1e-8,
                                       err_msg=f"{what}: {name}")
        for name in ("kinetic_energy", "kinetic_energy_constrained", "energy_lost"):
            assert getattr(a, name) == pytest.approx(getattr(r, name), abs=1e-8), what
        # the strike is at the symmetric configuration, and the trailing foot grazes
        assert abs(2.0 * a.q[2] + a.q[3]) < 1e-12, what
        assert abs(a.trailing_normal_velocity) < 1e-12 and e.trailing_mode == "graze", what
        # the energy books: T = T_c + T_a, the loss is T_c (eq. 10)
        assert a.kinetic_energy == pytest.approx(
            a.kinetic_energy_constrained + a.kinetic_energy_admissible, rel=1e-12)
    # between strikes the passive walk conserves mechanical energy; it does lose T_c at each
    # strike, the swing leg moving relative to the stance leg
    assert min(a.kinetic_energy_constrained for a in walk.impacts) > 1e-3


def test_wheel_strike_loses_nothing_iff_the_legs_move_together() -> None:
    """At R = l both feet roll on one circle about the hip: the striking foot's contact point
    moves at ``l q4_dot`` along the ground, so a strike with ``q4_dot = 0`` loses nothing
    (T_c = 0 to round-off, the paper's Figs. 2-3 at R = l) and leaves the trailing foot with
    zero normal velocity; any relative swing rate loses energy."""
    wheel = load_walker("wheel")
    for a in np.deg2rad([5.0, 15.0, 30.0]):
        q = np.array([0.0, 1.0, a, -2.0 * a])
        for w4, lossless in ((0.0, True), (0.5, False), (-1.0, False)):
            qd = np.array([-1.0, 0.0, 1.0, w4])  # stance foot rolling, q3_dot = 1 rad/s
            res, v_trailing = heel_strike(wheel, q, qd)
            T, T_c = float(res.kinetic_energy), float(res.kinetic_energy_constrained)
            assert abs(float(v_trailing)) < 1e-12
            if lossless:
                assert T_c < 1e-14 * T
                np.testing.assert_allclose(res.velocity_post, qd, atol=1e-14)
            else:
                assert T_c > 1e-3 * T


def test_wheel_runs_on_both_backends() -> None:
    """The declared guard runs on the compiled kernel too (its walks against the scipy
    reference: tests/test_wheel_compiled.py); the compass at R = l, whose guard is the
    clearance, is still refused on both."""
    wheel = load_phased_walker("wheel")
    assert wheel.compiled_kernel == "generated" and wheel.backends == ("scipy", "compiled")
    wheel.check_heel_strike_detectable()  # its declared guard detects the strike
    one_circle = load_phased_walker("compass", R=1.0)
    q, qd = one_circle.section_to_state(one_circle.section_point(*Z_WHEEL))
    for backend in ("scipy", "compiled"):
        with pytest.raises(ValueError, match="one circle in every posture"):
            simulate_entry(one_circle, q, qd, slope=SLOPE, backend=backend)


def test_generated_guard_is_the_declared_expression() -> None:
    wheel = load_walker("wheel")
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.0, 1.0, (5, 4))
    np.testing.assert_allclose(wheel.heel_strike_function(q), 2.0 * q[:, 2] + q[:, 3],
                               rtol=0, atol=1e-15)
    assert "heel_strike_guard" in wheel.model.namespace
    assert "heel_strike_guard" not in load_walker("compass").model.namespace


def _compass_with_events(events: str) -> Any:
    """compass.toml's description with an ``[events]`` table of the given body."""
    import tomllib

    text = (WALKERS / "compass.toml").read_text()
    text = text.replace('name = "compass"', 'name = "compass_events"') + "\n[events]\n" + events
    return parse_description(tomllib.loads(text), source="<test>")


def test_declared_symmetric_guard_walks_the_clearance_guards_steps() -> None:
    """For R < l the swing foot's clearance (rolling stance foot) is
    ``2 (l - R) sin((2 q3 + q4)/2) sin(q4/2)``: declaring ``2 stance_leg + hip`` as the guard
    (the default reset and trailing-foot rule) strikes where the default guard does."""
    from heelstrike.dynamics.phased import PhasedWalker

    default = load_phased_walker("compass")
    declared = PhasedWalker(_compass_with_events('heel_strike = "2 * stance_leg + hip"\n'))
    assert declared.step_schedule().trailing_foot == "complementarity"
    q, qd = default.section_to_state(COMPASS_GAIT)
    np.testing.assert_allclose(declared.section_to_state(COMPASS_GAIT)[0], q, atol=1e-14)
    kw = {"slope": COMPASS_SLOPE, "steps": 3, "rtol": 1e-11, "atol": 1e-11}
    a, b = simulate(default, q, qd, **kw), simulate(declared, q, qd, **kw)
    assert a.status is b.status is WalkStatus.COMPLETED
    for name in ("time", "kinetic_energy_constrained", "step_length"):
        np.testing.assert_allclose(b.impact_array(name), a.impact_array(name), rtol=0,
                                   atol=1e-8, err_msg=name)
    np.testing.assert_allclose(b.final_q_dot, a.final_q_dot, atol=1e-8)


def test_without_events_the_walker_is_as_before() -> None:
    desc = walker_description("compass")
    assert desc.events is None
    assert "events" not in json.loads(desc.structure_key())
    w = load_walker("compass")
    assert w.compiled_kernel == "generated"
    assert w.step_schedule().trailing_foot == "complementarity"
    q = np.array([0.0, 0.0, 0.2, -0.4])
    assert float(w.heel_strike_function(q)) == -float(w.foot_clearance(q, "left"))
    # the compass at R = l still cannot walk: its guard is the clearance
    with pytest.raises(ValueError, match="one circle in every posture"):
        load_walker("compass", R=1.0).check_heel_strike_detectable()


@pytest.mark.parametrize(
    ("events", "message"),
    [
        ('heel_strike = "2 * stance_leg + knee"\n',
         "events.heel_strike: unknown name 'knee' (coordinates: ['x', 'y', 'stance_leg', 'hip']"),
        ("heel_strike = 0.0\n", "events.heel_strike: must be an expression string"),
        ('heel_strike = "l - b"\n', "events.heel_strike: 'l - b' does not depend on the state"),
        ('heel_strike = "hip **"\n', "events.heel_strike: invalid expression"),
        ('heel_strike = "hip ** l"\n', "events.heel_strike: exponents must be numbers"),
        ('heel_strike = "hip"\nreset = "swap"\n',
         "events.reset: must be one of ['swap_legs'], got 'swap'"),
        ('heel_strike = "hip"\ntrailing_foot = "stays"\n',
         "events.trailing_foot: must be one of ['lifts', 'lifts_or_grazes'], got 'stays'"),
        ('reset = "swap_legs"\n', "events.heel_strike: missing required field"),
        ('heel_strike = "hip"\nwitness = "hip"\n', "events.witness: unknown key"),
    ],
)
def test_bad_events_tables_are_refused(events: str, message: str) -> None:
    with pytest.raises(ModelDescriptionError) as info:
        _compass_with_events(events)
    assert str(info.value).startswith(message), str(info.value)


def test_more_refusals() -> None:
    import tomllib

    text = (WALKERS / "compass.toml").read_text()
    # a parameter named like a coordinate, used in the guard, is ambiguous
    clash = text.replace("g = 9.81", "g = 9.81\nx = 1.0") + '\n[events]\nheel_strike = "x + hip"\n'
    with pytest.raises(ModelDescriptionError, match=r"^events\.heel_strike: 'x' names both"):
        parse_description(tomllib.loads(clash))
    # without mirrors there is no leg swap to reset by
    plain = text.replace('mirror = "swing_leg"\n', "").replace('mirror = "stance_leg"\n', "")
    with pytest.raises(ModelDescriptionError, match=r"^events\.reset: 'swap_legs' relabels"):
        parse_description(tomllib.loads(plain + '\n[events]\nheel_strike = "hip"\n'))
    # a guard with coordinate names that still takes one value everywhere: refused when built
    desc = _compass_with_events('heel_strike = "hip - hip + l"\n')
    with pytest.raises(ModelDescriptionError, match="does not depend on the state"):
        BuiltWalker(desc)
    # the guard's parameters count as used: setting them is not refused as idle
    desc = _compass_with_events('heel_strike = "2 * stance_leg + hip + 0 * I"\n')
    assert "I" not in desc.unused_params


def test_passive_search_refuses_the_wheel_only_where_its_step_cannot_end() -> None:
    """CompassGait at R = l keeps the lift rule: its passive step ends with the trailing foot
    grazing, so there is no passive step map (refused at once). wheel.toml's declared reset
    accepts the grazing foot: its passive step map exists (the walk above) and is searched."""
    from heelstrike.analysis.limit_cycle import GaitNotFoundError, _check_passive_slope

    with pytest.raises(GaitNotFoundError, match="McGeer's wheel"):
        _check_passive_slope(SLOPE, walker=CompassGait(foot_radius=1.0))
    wheel = load_phased_walker("wheel")
    assert wheel.is_wheel and wheel.step_schedule().trailing_foot == "lift_or_graze"
    _check_passive_slope(SLOPE, walker=wheel)  # not refused
    with pytest.raises(GaitNotFoundError, match="slope must be > 0"):
        _check_passive_slope(0.0, walker=wheel)  # the slope rule still holds


def test_walk_command_walks_the_wheel_file_on_its_backend(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``walk --model wheel`` (the compiled backend by default) writes an impacts table holding
    the strikes of the scipy reference's walk from the same start."""
    import pandas as pd

    from heelstrike.cli import main

    assert main(["walk", "--model", "wheel", "--slope", "1deg", "--steps", "3",
                 "--guess=" + ",".join(map(str, Z_WHEEL)), "--fps", "5",
                 "--out", str(tmp_path)]) == 0
    out, _ = capsys.readouterr()
    assert "3 steps, status: completed" in out
    impacts = pd.read_csv(tmp_path / "impacts.csv")
    wheel = load_phased_walker("wheel")
    q, qd = wheel.section_to_state(Z_WHEEL)
    walk = simulate(wheel, q, qd, slope=SLOPE, steps=3, rtol=1e-9, atol=1e-9, max_step=0.1)
    assert len(impacts) == 3
    np.testing.assert_allclose(impacts["time_s"], walk.impact_array("time"), atol=1e-6)
    np.testing.assert_allclose(impacts["T_c_J"], walk.impact_array("kinetic_energy_constrained"),
                               atol=1e-6)
    assert list(impacts["kind"]) == ["heel_strike"] * 3


def test_wheel_walks_passively_on_level_ground_losing_nothing() -> None:
    """McGeer's wheel has passive gaits on level ground that lose nothing: a step from the
    symmetric configuration with the swing leg at rest relative to the stance leg
    (``q4_dot = 0``) that strikes with it at rest again loses ``T_c = 0`` (the striking foot's
    contact point moves at ``l q4_dot``), and by the reversibility of the passive dynamics (the
    reflection ``(q3, q4) -> (-q3, -q4)`` with time reversed) every later step repeats it. The
    start is found on CompassGait's own step (a root of ``q4_dot`` at its first strike in the
    step angle, at ``q3_dot = 1 rad/s``); wheel.toml's walk from it, on the generated path,
    must then lose nothing at every one of its strikes and repeat its strike state."""
    from scipy.optimize import brentq

    compass = CompassGait(foot_radius=1.0)

    def swing_rate_at_strike(a: float) -> float:
        q, qd = compass.section_to_state([-a, 1.0, 0.0])
        walk = simulate(compass, q, qd, slope=0.0, steps=1, rtol=1e-12, atol=1e-12)
        return float(walk.impacts[0].q_dot_minus[3])

    a = brentq(swing_rate_at_strike, 0.3, 0.4, xtol=1e-15, rtol=1e-15)  # 0.34641899640...
    wheel = load_phased_walker("wheel")
    q, qd = wheel.section_to_state(wheel.section_point(-a, 1.0, 0.0))
    steps = 8
    walk = simulate_entry(wheel, q, qd, slope=0.0, steps=steps, rtol=1e-12, atol=1e-12)
    assert walk.status is WalkStatus.COMPLETED and walk.n_steps == steps
    E0 = float(wheel.mechanical_energy(q, qd))
    for k, imp in enumerate(walk.impacts):
        what = f"strike {k}"
        assert imp.kinetic_energy_constrained < 1e-12 * imp.kinetic_energy, what  # T_c = 0
        assert abs(imp.energy_lost) < 1e-12 * imp.kinetic_energy, what
        np.testing.assert_allclose(imp.q[2:], [a, -2.0 * a], atol=1e-8, err_msg=what)
        np.testing.assert_allclose(imp.q_dot_minus[2:], [1.0, 0.0], atol=1e-8, err_msg=what)
    # nothing lost anywhere: the mechanical energy of the whole walk is the start's
    np.testing.assert_allclose(walk.mechanical_energy, E0, rtol=1e-9)


def test_gait_of_the_wheel_answers_with_the_physics_on_both_backends(capsys) -> None:
    """``gait --model wheel`` (compiled by default) and ``--backend scipy`` answer with the
    physics (no passive wheel gait on a slope), not a backend refusal."""
    from heelstrike.cli import main

    for backend in ("compiled", "scipy"):
        assert main(["gait", "--model", "wheel", "--slope", "1deg", "--guess", "0.2,-1.0,0.0",
                     "--backend", backend]) != 0
        err = capsys.readouterr().err
        assert "backend" not in err and "gait" in err, backend


@pytest.mark.parametrize(("guard", "status", "said"), [
    # above zero at every state: it cannot rise through zero, so nothing ends the step until
    # the walker fails (the physical outcome, as the compiled kernel reports it), named so
    ("hip*hip + 1", "lost_contact", "no heel strike before that: the declared heel-strike "
     "guard 'hip*hip + 1' (events.heel_strike) did not rise through zero in step 0: it took "
     "values in [1.1002, 1.29077], never below zero, so it cannot rise through zero"),
])
def test_a_declared_guard_that_never_fires_is_named(guard: str, status: str, said: str) -> None:
    """Review finding: a declared guard that never crosses zero ended the walk as
    ``lost_contact`` without naming it. The walk's message names the expression and the range
    of its values over the stage that was to end in the strike (checked against the guard
    evaluated on the walk's own samples), and says when it was never below zero (so could not
    rise through zero). The status stays the physical outcome that stopped the walk (as on the
    compiled kernel, whose walks and ensembles must classify alike: review finding)."""
    from heelstrike.dynamics.phased import PhasedWalker

    default = load_phased_walker("compass")
    w = PhasedWalker(_compass_with_events(f'heel_strike = "{guard}"\n'))
    q, qd = default.section_to_state(COMPASS_GAIT)
    walk = simulate(w, q, qd, slope=COMPASS_SLOPE, steps=2)
    assert walk.status == status and walk.n_steps == 0
    assert walk.status is not WalkStatus.COMPLETED
    assert f"the declared heel-strike guard {guard!r} (events.heel_strike) did not rise " \
        "through zero in step 0" in walk.message
    assert said in walk.message
    # the values quoted are the guard's over the samples after mid-stance (stance_leg >= 0)
    after = walk.q[walk.q[:, 2] >= -1e-12]
    g = np.asarray(w.heel_strike_function(after))
    assert f"[{g.min():.6g}, {g.max():.6g}]" in walk.message
    # the default guard walks the same start: the test's walker fails only by its guard
    assert simulate(default, q, qd, slope=COMPASS_SLOPE, steps=2).status is WalkStatus.COMPLETED


def test_an_armed_guard_is_not_named_when_the_walker_fails_first() -> None:
    """A declared guard below zero (armed) when the walker fails is not why the step ended:
    the walk's status and message are the physical outcome's, as the compiled kernels report
    them (the backends' messages must agree: tests/test_backend_conformance.py)."""
    from heelstrike.dynamics.phased import PhasedWalker

    default = load_phased_walker("compass")
    w = PhasedWalker(_compass_with_events('heel_strike = "-1 - stance_leg**2"\n'))
    q, qd = default.section_to_state(COMPASS_GAIT)
    walk = simulate(w, q, qd, slope=COMPASS_SLOPE, steps=2)
    assert walk.status is WalkStatus.LOST_CONTACT and walk.n_steps == 0
    assert walk.message == WalkStatus.LOST_CONTACT.message
