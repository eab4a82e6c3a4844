"""The torques walker files' locks exert (QA sweep 13).

The kneed walker's stance-knee lock holds the knee with torques of both signs over its 3 deg
gait: a two-sided latch, not the one-sided knee stop of McGeer's and Hsu Chen's models, which
would let the knee buckle where the lock pulls. Nothing said so.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from heelstrike.analysis.model_gaits import (
    find_model_gaits,
    gait_locks,
    lock_torque_ranges,
    two_sided_locks,
)
from heelstrike.cli import main
from heelstrike.dynamics import simulate
from heelstrike.dynamics.hybrid import lock_torques
from heelstrike.models import load_walker

SLOPE = float(np.deg2rad(3.0))


def test_the_lock_torque_balances_the_measured_accelerations() -> None:
    # independent of the reduced solve: accelerations from the walk's own velocities (central
    # differences of dense samples), then the knee row of M q_ddot + h
    walker = load_walker("kneed")
    gait = find_model_gaits(walker, slope=SLOPE)[0]
    walk = simulate(walker, gait.q, gait.q_dot, slope=SLOPE, steps=1, rtol=1e-12, atol=1e-12,
                    max_step=gait.period / 4000)
    held = lock_torques(walker, walk)["stance_knee"]
    knee = walker.coordinate_names.index("stance_knee")
    t, qd = np.asarray(walk.t), np.asarray(walk.q_dot)
    inner = np.flatnonzero((walk.phase == "knee_swing")[1:-1]) + 1
    inner = inner[(walk.phase[inner - 1] == "knee_swing") & (walk.phase[inner + 1] == "knee_swing")
                  & (t[inner + 1] > t[inner]) & (t[inner] > t[inner - 1])]
    inner = inner[5:-5]  # away from the phase's ends
    assert inner.size > 100
    q_dd = ((qd[inner + 1] - qd[inner]) / (t[inner + 1] - t[inner])[:, None]
            + (qd[inner] - qd[inner - 1]) / (t[inner] - t[inner - 1])[:, None]) / 2
    assert np.max(np.abs(q_dd[:, knee])) < 1e-6  # the knee held
    M, h = walker.dynamics_terms(walk.q[inner], qd[inner], SLOPE)
    measured = np.einsum("...ij,...j->...i", M, q_dd)[:, knee] + h[:, knee]
    np.testing.assert_allclose(held[inner], measured, atol=2e-4 * np.max(np.abs(measured)))
    assert held[inner].min() < -0.1 and held[inner].max() > 0.2  # both signs (N m)


def test_gait_notes_a_lock_that_must_pull(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["gait", "--model", "kneed", "--json"]) == 0
    captured = capsys.readouterr()
    d = json.loads(captured.out)
    lo, hi = d["lock_torque_range"]["stance_knee"]
    assert lo == pytest.approx(-0.1755, abs=2e-3) and hi == pytest.approx(0.2201, abs=2e-3)
    s_lo, s_hi = d["lock_torque_range"]["swing_knee"]  # locked after the knee strike
    assert 0 < s_lo <= s_hi  # one sign: a stop could hold it
    assert d["units"]["lock_torque_range"] == {"stance_knee": "N m", "swing_knee": "N m"}
    notes = [line for line in captured.err.splitlines() if "lock of" in line]
    assert len(notes) == 1 and "'stance_knee' holds it with torques of both signs" in notes[0]
    # the same ranges from the scipy reference's walk
    walker = load_walker("kneed")
    gait = find_model_gaits(walker, slope=SLOPE)[0]
    ref = lock_torque_ranges(walker, gait, backend="scipy")
    np.testing.assert_allclose(ref["stance_knee"], (lo, hi), rtol=1e-3)
    assert list(two_sided_locks(walker, ref)) == ["stance_knee"]  # the swing knee only pushes


def test_walkers_without_locks_have_no_lock_torques() -> None:
    walker = load_walker("compass")
    gait = find_model_gaits(walker, slope=SLOPE)[0]
    assert lock_torque_ranges(walker, gait) == {}


def test_gait_locks_names_the_stance_knee_two_sided() -> None:
    """Issue #32, item 5: the result the gait command prints. On the kneed walker's 3 deg gait
    the stance knee's lock holds it with -0.18 to +0.22 N m (the values of the test above and
    of QA sweep 13), the swing knee's with one sign only; the compass walker has no locks."""
    walker = load_walker("kneed")
    gait = find_model_gaits(walker, slope=SLOPE)[0]
    locks = gait_locks(walker, gait, backend="scipy")
    assert set(locks.ranges) == {"stance_knee", "swing_knee"}
    lo, hi = locks.ranges["stance_knee"]
    assert lo == pytest.approx(-0.1755, abs=2e-3) and hi == pytest.approx(0.2201, abs=2e-3)
    s_lo, s_hi = locks.ranges["swing_knee"]
    assert 0 < s_lo <= s_hi
    assert locks.two_sided == {"stance_knee": (lo, hi)}
    compass = load_walker("compass")
    none = gait_locks(compass, find_model_gaits(compass, slope=SLOPE)[0])
    assert none.ranges == {} and none.two_sided == {}
