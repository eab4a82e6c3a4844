"""Declared heel-strike guards on the compiled backend (issue 32: "the wheel walks compiled").

A walker file's ``[events] heel_strike`` guard is generated into the walker's numba functions
(``heel_strike_guard``, from the same sympy expression as the numpy one) and the compiled
kernel runs it with the declared trailing-foot rule, as the scipy reference does
(:meth:`heelstrike.models.builder.BuiltWalker.step_schedule`). Checked here against the scipy
reference: McGeer's wheel (``wheel.toml``, ``trailing_foot = "lifts_or_grazes"``) one step and
a few steps from a given state (end state, period, every impact), the ensemble kernel of
``basin`` and the maps, and the wheel's lossless level gait (a fixed point of the step map,
found on each backend as the root of the swing rate at the strike); the compass declared
through a guard equal to its default witness (minus the swing foot's clearance) steps as the
compass without the table (1e-10), and with the ``"lifts_or_grazes"`` rule where its trailing
foot lifts as the scipy reference and the table-less compass; the ``gait`` command runs the
wheel on ``--backend compiled``.

For these parameters the wheel has no passive gait on a slope (both backends): from any start
it gains speed step after step until it falls forward (0.2 deg: 96 steps from the level gait's
state, 1 deg: 20), its strike loss saturating below the work of gravity; its level gait is the
one periodic walk to compare.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import heelstrike
from heelstrike.dynamics.compiled_phased import ensemble_walk_phased, simulate_phased_compiled
from heelstrike.dynamics.hybrid import WalkStatus
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker, simulate_phased
from heelstrike.models._codegen_numba import build_numba
from heelstrike.models.description import parse_description

WALKERS = Path(heelstrike.__file__).parent / "walkers"
SLOPE = float(np.deg2rad(1.0))
#: a post-strike start (q3, q3_dot, q4_dot) from which the passive wheel walks on 1 deg
Z_WHEEL = (-0.25, 0.8, 0.0)
#: compass.toml (R = 0) near its gait (test_backend_conformance's COMPASS_GAIT, slope 0.05)
COMPASS_SLOPE = 0.05
COMPASS_GAIT = (-0.26682122, 1.08394013, -0.68587173)
#: minus the swing foot's clearance of compass.toml: its arc's lowest point is at
#: y + (l - R) (cos q3 - cos(q3 + q4)) - R above the ground ((x, y) the stance arc's centre,
#: the hip l - R from it along the stance leg, the swing arc's centre l - R below the hip)
MINUS_CLEARANCE = "(l - R) * (cos(stance_leg + hip) - cos(stance_leg)) + R - y"
TOL = 1e-8


@pytest.fixture(scope="module")
def wheel() -> PhasedWalker:
    return load_phased_walker("wheel")


def _start(w: PhasedWalker, z: Any) -> tuple[Any, Any]:
    return w.section_to_state(w.section_point(*z))


def test_generated_numba_guard_is_the_declared_guard(wheel: PhasedWalker) -> None:
    """The numba ``heel_strike_guard`` is the declared expression ``2 q3 + q4`` (and the numpy
    builder's); a walker declaring none has the stub (its kernel's guard is the clearance)."""
    model = build_numba(wheel.description)
    assert model.has_guard
    p = np.array([float(wheel.parameters[k]) for k in wheel.description.param_names])
    rng = np.random.default_rng(7)
    for q in rng.uniform(-1.0, 1.0, (5, 4)):
        g = model.heel_strike_guard(q, p)
        assert g == pytest.approx(2.0 * q[2] + q[3], abs=1e-15)
        assert g == pytest.approx(float(wheel.heel_strike_function(q)), abs=1e-15)
    compass = load_phased_walker("compass")
    assert not build_numba(compass.description).has_guard


def test_wheel_is_walked_on_both_backends(wheel: PhasedWalker) -> None:
    assert wheel.compiled_kernel == "generated"
    assert wheel.backends == ("scipy", "compiled")


@pytest.mark.slow
def test_wheel_one_step_compiled_equals_scipy(wheel: PhasedWalker) -> None:
    """One step from a given state: the strike's time (the period), state before and after,
    energies and the grazing trailing foot, and the end state after the leg swap."""
    q, qd = _start(wheel, Z_WHEEL)
    kw = {"slope": SLOPE, "steps": 1, "rtol": 1e-11, "atol": 1e-11}
    ref = simulate_phased(wheel, q, qd, **kw)
    got = simulate_phased_compiled(wheel, q, qd, **kw)
    assert ref.status is got.status is WalkStatus.COMPLETED
    (a,), (b,) = got.events, ref.events
    assert a.kind == b.kind == "heel_strike"
    assert a.trailing_mode == b.trailing_mode == "graze"
    assert a.time == pytest.approx(b.time, abs=TOL)  # the period of the step
    assert got.impacts[0].step_duration == pytest.approx(ref.impacts[0].step_duration, abs=TOL)
    for name in ("q", "q_dot_minus", "q_dot_plus", "impulse", "rows"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=TOL,
                                   err_msg=name)
    for name in ("kinetic_energy", "kinetic_energy_constrained", "kinetic_energy_admissible",
                 "trailing_normal_velocity"):
        assert getattr(a, name) == pytest.approx(getattr(b, name), abs=TOL), name
    assert abs(2.0 * a.q[2] + a.q[3]) < 1e-12  # struck at the declared guard's zero
    np.testing.assert_allclose(got.final_q, ref.final_q, rtol=0, atol=TOL)
    np.testing.assert_allclose(got.final_q_dot, ref.final_q_dot, rtol=0, atol=TOL)
    # a loss: the swing leg moves relative to the stance leg at the strike
    assert a.kinetic_energy_constrained > 1e-3


@pytest.mark.slow
def test_wheel_ensemble_equals_scipy_walks(wheel: PhasedWalker) -> None:
    """The ensemble kernel (``basin``, the maps) walks the wheel as the scipy reference: a
    completed walks, one that falls forward and one that falls backward."""
    starts = [Z_WHEEL, (-1.0, 2.2, -0.5), (-0.3, 2.5, 0.0), (-0.25, 0.2, 0.0)]
    states = [_start(wheel, z) for z in starts]
    Q = np.array([s[0] for s in states])
    QD = np.array([s[1] for s in states])
    steps = 4
    ens = ensemble_walk_phased(wheel, states=(Q, QD), slope=SLOPE, steps=steps, rtol=1e-11,
                               atol=1e-11, parallel=False)
    statuses = set()
    for i, (q, qd) in enumerate(states):
        ref = simulate_phased(wheel, q, qd, slope=SLOPE, steps=steps, rtol=1e-11, atol=1e-11)
        statuses.add(ref.status)
        assert WalkStatus.from_code(int(ens.status[i])) is ref.status, i
        assert int(ens.steps[i]) == ref.n_steps, i
        np.testing.assert_allclose(ens.q[i], ref.final_q, rtol=0, atol=TOL, err_msg=str(i))
        np.testing.assert_allclose(ens.q_dot[i], ref.final_q_dot, rtol=0, atol=TOL,
                                   err_msg=str(i))
    assert statuses == {WalkStatus.COMPLETED, WalkStatus.FELL_FORWARD, WalkStatus.FELL_BACKWARD}


def _level_gait_angle(w: PhasedWalker, simulate: Any) -> tuple[float, Any]:
    """The wheel's lossless level gait at ``q3_dot = 1 rad/s``: the step angle ``a`` whose
    step from ``(-a, 1, 0)`` strikes with the swing leg at rest relative to the stance leg
    (``q4_dot- = 0``, a root in ``a``); by the reversibility of the passive dynamics that
    strike is at ``(a, 1, 0)`` and loses nothing, so ``(-a, 1, 0)`` is a fixed point of the
    step map."""
    from scipy.optimize import brentq

    def rate(a: float) -> float:
        q, qd = _start(w, (-a, 1.0, 0.0))
        walk = simulate(w, q, qd, slope=0.0, steps=1, rtol=1e-12, atol=1e-12)
        return float(walk.events[0].q_dot_minus[3])

    a = brentq(rate, 0.3, 0.4, xtol=1e-14, rtol=1e-14)
    q, qd = _start(w, (-a, 1.0, 0.0))
    return a, simulate(w, q, qd, slope=0.0, steps=1, rtol=1e-12, atol=1e-12)


@pytest.mark.slow
def test_wheel_level_gait_fixed_point_compiled_equals_scipy(wheel: PhasedWalker) -> None:
    a_ref, ref = _level_gait_angle(wheel, simulate_phased)
    a, got = _level_gait_angle(wheel, simulate_phased_compiled)
    assert a == pytest.approx(a_ref, abs=TOL)
    assert a == pytest.approx(0.34641899640, abs=1e-9)  # CompassGait(R = l)'s (test_walker_events)
    for walk in (got, ref):
        assert walk.status is WalkStatus.COMPLETED
        (e,) = walk.events
        assert e.trailing_mode == "graze"
        assert e.kinetic_energy_constrained < 1e-12 * e.kinetic_energy  # lossless strike
        # the step returns to its start: a fixed point of the step map
        z_end = walk.final_q[2], walk.final_q_dot[2], walk.final_q_dot[3]
        np.testing.assert_allclose(z_end, (-a, 1.0, 0.0) if walk is got else (-a_ref, 1.0, 0.0),
                                   rtol=0, atol=1e-8)
    assert got.events[0].time == pytest.approx(ref.events[0].time, abs=TOL)  # the period


def _compass_with_guard(guard: str, trailing_foot: str = "lifts") -> PhasedWalker:
    text = (WALKERS / "compass.toml").read_text()
    text = text.replace('name = "compass"', 'name = "compass_declared"')
    text += f'\n[events]\nheel_strike = "{guard}"\ntrailing_foot = "{trailing_foot}"\n'
    return PhasedWalker(parse_description(tomllib.loads(text), source="<test>"))


@pytest.mark.slow
def test_compass_declaring_its_default_witness_steps_as_without_it() -> None:
    """compass.toml with ``[events] heel_strike`` = minus the swing foot's clearance (its
    default witness; default reset and ``trailing_foot = "lifts"``, the complementarity of the
    default) gives, on the compiled backend, the step of compass.toml without the table."""
    default = load_phased_walker("compass")
    declared = _compass_with_guard(MINUS_CLEARANCE)
    rng = np.random.default_rng(5)
    q_test = rng.uniform(-0.8, 0.8, (6, 4))
    for R in (0.0, 0.3):  # the guard is the default witness, whatever the feet
        np.testing.assert_allclose(declared.replace(R=R).heel_strike_function(q_test),
                                   default.replace(R=R).heel_strike_function(q_test), rtol=0,
                                   atol=1e-15)
    assert declared.compiled_kernel == "generated"
    q, qd = default.section_to_state(COMPASS_GAIT)
    kw = {"slope": COMPASS_SLOPE, "steps": 1, "rtol": 1e-12, "atol": 1e-12}
    a = simulate_phased_compiled(default, q, qd, **kw)
    b = simulate_phased_compiled(declared, q, qd, **kw)
    assert a.status is b.status is WalkStatus.COMPLETED
    (ea,), (eb,) = a.events, b.events
    assert ea.trailing_mode == eb.trailing_mode == "separate"
    assert eb.time == pytest.approx(ea.time, abs=1e-10)
    for name in ("q", "q_dot_minus", "q_dot_plus", "impulse"):
        np.testing.assert_allclose(getattr(eb, name), getattr(ea, name), rtol=0, atol=1e-10,
                                   err_msg=name)
    np.testing.assert_allclose(b.final_q, a.final_q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.final_q_dot, a.final_q_dot, rtol=0, atol=1e-10)


@pytest.mark.slow
def test_lift_or_graze_rule_with_a_lifting_trailing_foot_compiled_equals_scipy() -> None:
    """The declared ``"lifts_or_grazes"`` rule where the trailing foot lifts (the point-foot
    compass, mode ``"separate"``): the compiled kernel's projector branch walks three steps of
    the scipy reference's; and since a separating trailing foot is the complementarity
    solution too, the steps are those of compass.toml without the table."""
    declared = _compass_with_guard("2 * stance_leg + hip", "lifts_or_grazes")
    assert declared.step_schedule().trailing_foot == "lift_or_graze"
    default = load_phased_walker("compass")
    q, qd = default.section_to_state(COMPASS_GAIT)
    kw = {"slope": COMPASS_SLOPE, "steps": 3, "rtol": 1e-11, "atol": 1e-11}
    ref = simulate_phased(declared, q, qd, **kw)
    got = simulate_phased_compiled(declared, q, qd, **kw)
    plain = simulate_phased_compiled(default, q, qd, **kw)
    assert ref.status is got.status is plain.status is WalkStatus.COMPLETED
    for a, b, c in zip(got.events, ref.events, plain.events, strict=True):
        assert a.trailing_mode == b.trailing_mode == c.trailing_mode == "separate"
        assert a.time == pytest.approx(b.time, abs=TOL)
        for name in ("q", "q_dot_minus", "q_dot_plus", "impulse", "rows"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=TOL,
                                       err_msg=name)
            np.testing.assert_allclose(getattr(a, name), getattr(c, name), rtol=0, atol=TOL,
                                       err_msg=name)
        assert a.trailing_normal_velocity == pytest.approx(b.trailing_normal_velocity, abs=TOL)
        assert a.trailing_normal_velocity > 0.0  # it lifts
    np.testing.assert_allclose(got.final_q_dot, ref.final_q_dot, rtol=0, atol=TOL)


@pytest.mark.slow
def test_gait_command_runs_the_wheel_on_the_compiled_backend(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``gait --model wheel --backend compiled --json`` searches the wheel's gaits on the
    compiled backend and answers with the physics: no passive gait on the slope (see the
    module docstring), not a backend refusal."""
    from heelstrike.cli import main

    code = main(["gait", "--model", "wheel", "--backend", "compiled", "--json"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""  # a CliError
    assert "no gait found at slope 3 deg" in err
    assert "backend" not in err and "scipy" not in err
