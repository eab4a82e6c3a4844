"""Level-ground push-off gaits of the kneed walker (``walkers/kneed.toml``), found by a homotopy.

The kneed walker's passive gaits exist only on slopes steeper than about 2 deg (the branch
folds there), and the push-off seeds on level ground converge to nothing. The model search
(:func:`~heelstrike.analysis.powered.find_model_powered_gait`) then starts from the passive
gait on a slope and lowers the slope to 0 while the push-off impulse takes over the energy
input (:func:`~heelstrike.analysis.powered._slope_homotopy`). The level-ground gaits so reached
start at a fold near 1.22 m/s; slower targets (0.5 m/s, the CLI's default before the walker
file declared 1.3 m/s) get an error that says what was tried.

Physics checked on the gait at 1.3 m/s, independently of the search, on the scipy reference map
at ``rtol = 1e-12``: the state is periodic, the mean speed is the target, and the energy book
of one period closes: the push-off work ``T(q_dot-) - T(q_dot- - dq)`` equals the knee strike's
``T_c`` plus the heel strike's (the hip is passive and the kneed file declares no posture law),
while ``T + V`` is conserved in single support apart from the knee strike's loss.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.limit_cycle import GaitNotFoundError, PoincareMap
from heelstrike.analysis.powered import (
    HOMOTOPY_SLOPES,
    PoweredGaitNotFoundError,
    declared_posture_law,
    find_model_powered_gait,
)
from heelstrike.cli import main
from heelstrike.core.impact import kinetic_energy
from heelstrike.dynamics.actuation import PushOff, mechanical_energy, push_off_velocity_change
from heelstrike.dynamics.phased import PhasedWalker, PhasedWalkResult, simulate_phased
from heelstrike.models.builder import load_walker

SPEED = 1.3  # m/s: inside the level-ground push-off gaits the homotopy reaches (~1.22-1.41)
SLOW = 0.5  # m/s: the CLI's former default target, below the slowest of those gaits


@pytest.fixture(scope="module")
def walker() -> PhasedWalker:
    return PhasedWalker.from_built(load_walker("kneed"))


@pytest.fixture(scope="module")
def gait() -> Gait:
    return find_model_powered_gait(load_walker("kneed"), speed=SPEED)


@pytest.fixture(scope="module")
def slow_error() -> str:
    with pytest.raises(PoweredGaitNotFoundError) as info:
        find_model_powered_gait(load_walker("kneed"), speed=SLOW)
    return str(info.value)


def _reference_step(walker: PhasedWalker, g: Gait) -> PhasedWalkResult:
    walk = simulate_phased(walker, *walker.section_to_state(g.fixed_point), slope=0.0, steps=1,
                           push_off=PushOff(impulse=g.actuation.parameter), rtol=1e-12, atol=1e-12)
    assert isinstance(walk, PhasedWalkResult) and walk.ok
    return walk


def test_kneed_declares_no_posture_law(walker: PhasedWalker) -> None:
    # the energy book below has no posture term because the file declares none
    assert declared_posture_law(walker) is None


def test_level_gait_is_periodic_at_the_target_speed(walker: PhasedWalker,
                                                    gait: Gait) -> None:
    g = gait
    walk = _reference_step(walker, g)
    z_next = walker.state_to_section(walk.final_q, walk.final_q_dot)
    assert np.max(np.abs(z_next - g.fixed_point)) < 1e-8
    rec = walk.impacts[0]
    assert abs(rec.step_length / rec.step_duration - SPEED) < 1e-8
    assert abs(g.speed - SPEED) < 1e-9
    assert g.residual < 1e-8
    assert g.actuation.parameter > 0.0  # the push-off does the work
    # a knee strike, then the heel strike, in the period
    assert [e.kind for e in walk.events] == ["knee_strike", "heel_strike"]


def test_level_gait_energy_book_closes(walker: PhasedWalker, gait: Gait) -> None:
    g = gait
    walk = _reference_step(walker, g)
    rec = walk.impacts[0]
    q0, qd0 = walker.section_to_state(g.fixed_point)
    E_start = float(mechanical_energy(walker, q0, qd0))
    dq, _ = push_off_velocity_change(walker, rec.q, g.actuation.parameter,
                                     walk.events[-1].lock_rows)
    qd_before_push = rec.q_dot_minus - dq
    M = walker.mass_matrix(rec.q)
    W_push = float(kinetic_energy(M, rec.q_dot_minus) - kinetic_energy(M, qd_before_push))
    knee = sum(e.kinetic_energy_constrained for e in walk.events if e.kind == "knee_strike")
    heel = sum(e.kinetic_energy_constrained for e in walk.events if e.kind == "heel_strike")
    assert knee > 0.0 and heel > 0.0
    # inert heel strike: the kinetic energy it takes is its T_c
    assert float(kinetic_energy(M, rec.q_dot_minus) - kinetic_energy(M, rec.q_dot_plus)) == \
        pytest.approx(heel, abs=1e-10)
    # single support (passive hip, no posture law): T + V changes only by the knee strike's loss
    assert abs(float(mechanical_energy(walker, rec.q, qd_before_push)) - (E_start - knee)) < 1e-8
    # periodic level gait: push-off work = knee-strike loss + heel-strike loss
    assert abs(W_push - (knee + heel)) < 1e-8
    # ... and the reported (compiled) books say the same
    assert abs(g.actuation.push_off_work - W_push) < 1e-8
    assert abs(g.collision_loss - (knee + heel)) < 1e-8
    assert abs(g.actuator_work - g.actuation.push_off_work) < 1e-12
    assert g.actuation.torque_work == pytest.approx(0.0)
    assert abs(g.energy_balance_error) < 1e-8


def test_level_gait_multipliers_match_reference_map(walker: PhasedWalker,
                                                    gait: Gait) -> None:
    P = PoincareMap(walker=walker, simulator=simulate_phased,
                    push_off=PushOff(impulse=gait.actuation.parameter), rtol=1e-12, atol=1e-12)
    mult = np.sort(np.abs(np.linalg.eigvals(P.jacobian(gait.fixed_point, 1e-5))))[::-1]
    assert np.allclose(mult, np.abs(gait.multipliers), atol=1e-3)
    assert gait.stable == bool(np.all(mult < 1.0))


def test_push_off_holds_the_locked_knees(walker: PhasedWalker, gait: Gait) -> None:
    """Both knees are locked when the trailing foot pushes off, and hold through the impulse
    (QA sweep 11: it was applied with the knees free, so the stance knee jumped to 85 rad/s,
    the heel strike took that motion back, and the books counted 2.54993 J of push-off work
    per step for this gait: the same gait, 4.4 times its cost). Checked against the impulse
    problem solved here as one linear system (Lagrange multipliers for the locks)."""
    walk = _reference_step(walker, gait)
    heel = walk.events[-1]
    assert heel.kind == "heel_strike"
    q, L = heel.q, heel.lock_rows
    assert L.shape[0] == 2  # both knees locked at heel strike
    n, k = walker.n_coordinates, L.shape[0]
    M = walker.mass_matrix(q)
    f = walker.contact_jacobian(q, "right").T @ (
        gait.actuation.parameter * np.array([-np.sin(q[2]), np.cos(q[2])]))
    # M dq = f + L^T lam, L dq = 0
    kkt = np.block([[M, -L.T], [L, np.zeros((k, k))]])
    sol = np.linalg.solve(kkt, np.concatenate([f, np.zeros(k)]))
    dq_ref, lam = sol[:n], sol[n:]
    dq, f_got = push_off_velocity_change(walker, q, gait.actuation.parameter, L)
    np.testing.assert_allclose(f_got, f, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(dq, dq_ref, rtol=1e-10, atol=1e-10)
    # the simulated walk applied exactly this jump: the knees are at rest before the heel
    # strike, after the push-off as before it
    qd_before = heel.q_dot_minus - dq
    np.testing.assert_allclose(L @ heel.q_dot_minus, 0.0, atol=1e-9)
    np.testing.assert_allclose(L @ qd_before, 0.0, atol=1e-9)
    w_push = float(kinetic_energy(M, heel.q_dot_minus) - kinetic_energy(M, qd_before))
    # with the knees free the same impulse does more work, by exactly the kinetic energy of
    # the locks' impulse, 1/2 |M^-1 L^T lam|_M^2 (the pre-impact knees are at rest)
    free, _ = push_off_velocity_change(walker, q, gait.actuation.parameter)
    w_free = float(kinetic_energy(M, qd_before + free) - kinetic_energy(M, qd_before))
    x = np.linalg.solve(M, L.T @ lam)
    assert w_free - w_push == pytest.approx(0.5 * float(x @ M @ x), rel=1e-8)
    assert abs(gait.actuation.push_off_work - w_push) < 1e-8
    # QA sweep 11's own model (sympy/scipy, no heelstrike code) of this gait: 0.58312 J
    assert gait.actuation.push_off_work == pytest.approx(0.58312, abs=2e-5)


@pytest.mark.slow
def test_scipy_backend_homotopy_finds_the_same_gait(gait: Gait) -> None:
    # the whole search (seeds, homotopy, continuation, polish) on the scipy reference
    ref = find_model_powered_gait(load_walker("kneed"), speed=SPEED, backend="scipy")
    assert np.max(np.abs(ref.fixed_point - gait.fixed_point)) < 1e-8
    assert abs(ref.actuation.parameter - gait.actuation.parameter) < 1e-8
    assert abs(ref.collision_loss - gait.collision_loss) < 1e-8


# -- no gait at 0.5 m/s: a specific message -----------------------------------------------------
def test_slow_target_error_says_what_was_tried(slow_error: str) -> None:
    msg = slow_error
    deg0 = f"{np.rad2deg(HOMOTOPY_SLOPES[0]):.3g} deg"
    assert f"no gait with speed {SLOW:g} m/s" in msg
    assert f"homotopy from the passive gait on a {deg0} slope" in msg
    assert "the slope lowered to 0" in msg and "push-off impulse took over" in msg
    m = re.search(r"gaits found span ([0-9.]+) to ([0-9.]+) m/s and end near ([0-9.]+) m/s", msg)
    assert m is not None, msg
    lo, hi, end = map(float, m.groups())
    assert SLOW < lo < hi and end == lo  # the family ends above the target, at a fold


def test_reported_end_of_the_family_is_real(slow_error: str, gait: Gait) -> None:
    # a gait exists just above the speed the message says the level gaits end at
    m = re.search(r"end near ([0-9.]+) m/s", slow_error)
    assert m is not None
    lo = float(m.group(1))
    near = find_model_powered_gait(load_walker("kneed"), speed=lo + 0.01,
                                   guess=np.append(gait.fixed_point, gait.actuation.parameter))
    assert abs(near.speed - (lo + 0.01)) < 1e-9 and near.residual < 1e-8


def test_without_passive_gaits_the_error_says_so() -> None:
    def none(slope: float) -> np.ndarray:
        raise GaitNotFoundError(f"none at {slope}")

    with pytest.raises(PoweredGaitNotFoundError) as info:
        find_model_powered_gait(load_walker("kneed"), speed=SPEED, passive_gait=none)
    msg = str(info.value)
    assert msg.startswith("no periodic pushoff gait found on level ground")
    for s in HOMOTOPY_SLOPES:
        assert f"no passive gait on a {np.rad2deg(s):.3g} deg slope" in msg


# -- CLI ----------------------------------------------------------------------------------------
def test_cli_kneed_default_speed_fails_with_one_specific_line(
        capsys: pytest.CaptureFixture[str]) -> None:
    # 0.5 m/s, the former default target (the file now declares 1.3 m/s, inside the family)
    assert main(["powered", "--model", "kneed", "--speed", "0.5"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = [ln for ln in captured.err.splitlines() if ln.startswith("heelstrike: error:")]
    assert len(lines) == 1
    assert "speed 0.5" in lines[0] and "homotopy" in lines[0] and "deg slope" in lines[0]


def test_cli_kneed_json(capsys: pytest.CaptureFixture[str], gait: Gait) -> None:
    assert main(["powered", "--model", "kneed", "--speed", str(SPEED), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == "kneed" and d["torque_work"] == pytest.approx(0.0)
    assert abs(d["speed"] - SPEED) < 1e-9
    assert abs(d["parameter"] - gait.actuation.parameter) < 1e-8
    assert abs(d["push_off_work"] - d["collision_loss"]) < 1e-8
