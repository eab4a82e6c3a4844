"""Lock torque ranges and notes as data of the one gait type (issue 32, item 3).

``Gait.locks`` carries what ``heelstrike gait --model`` computed itself (the torques each lock
exerts over the step, :func:`~heelstrike.analysis.model_gaits.gait_locks`), computed on first
access; ``Gait.notes`` what its reports say besides the numbers, decided by
:func:`~heelstrike.analysis.gaits.find_gaits`, not by the CLI.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from heelstrike.analysis.gaits import GaitNote, find_gaits
from heelstrike.analysis.model_gaits import (
    LOCK_TORQUE_SAMPLES,
    GaitLocks,
    lock_torque_ranges,
    two_sided_locks,
)
from heelstrike.cli import main
from heelstrike.dynamics import simulate
from heelstrike.models import CompassGait, load_walker

SLOPE = float(np.deg2rad(3.0))


def test_kneed_gait_locks_are_the_old_cli_paths_lock_ranges() -> None:
    walker = load_walker("kneed")
    gaits = find_gaits(walker, SLOPE, backend="compiled", every_start=True)
    assert len(gaits) >= 2
    # lazy: no gait's dense walk is taken before its locks are asked for
    assert all(callable(g.__dict__["_locks_value"]) for g in gaits)
    for g in gaits:
        direct = lock_torque_ranges(walker, g, backend="compiled")  # what the CLI called
        locks = g.locks
        assert locks is not None
        assert set(locks.ranges) == set(direct) == {"stance_knee", "swing_knee"}
        for name, (lo, hi) in direct.items():
            np.testing.assert_allclose(locks.ranges[name], (lo, hi), rtol=1e-12, atol=0.0)
        assert locks.two_sided == two_sided_locks(walker, locks.ranges)
        assert g.locks is locks  # computed once, then kept
    # the stable 3 deg gait's stance knee must be pulled and pushed (QA sweep 13)
    first = gaits[0].locks
    assert gaits[0].stable and first is not None
    assert list(first.two_sided) == ["stance_knee"]


def test_walkers_without_locks_and_powered_gaits_have_no_locks() -> None:
    assert all(g.locks is None for g in find_gaits(load_walker("compass"), SLOPE))
    assert all(g.locks is None for g in find_gaits(CompassGait(), 0.02))


def test_lock_torque_range_brackets_the_torque_from_m_and_h() -> None:
    """The knee locks' torques recomputed from the equations of motion, ``M q_dd + h =
    A^T lam + E^T tau`` with the stance foot's rolling contact ``A q_dd + A_dot q_dot = 0`` and
    the locked joints ``E q_dd = 0`` (one KKT solve per sample, not the reduced solve of
    :func:`~heelstrike.dynamics.hybrid.lock_torques`), along the walk the range is measured
    on: every sample lies in the field's bracket, and the extremes are its ends."""
    walker = load_walker("kneed")
    gait = find_gaits(walker, SLOPE, backend="compiled")[0]
    locks = gait.locks
    assert locks is not None
    walk = simulate(walker, gait.q, gait.q_dot, slope=SLOPE, steps=1, backend="compiled",
                    max_step=gait.period / LOCK_TORQUE_SAMPLES)
    phases = {p.name: p.locked for p in walker.step_schedule().phases}
    names = walker.coordinate_names
    n = len(names)
    torques: dict[str, list[float]] = {"stance_knee": [], "swing_knee": []}
    q, qd = np.asarray(walk.q), np.asarray(walk.q_dot)
    M, h = walker.dynamics_terms(q, qd, SLOPE)
    A = walker.contact_jacobian(q, "right")
    a_rate = walker.contact_jacobian_rate(q, qd, "right")
    for i, phase in enumerate(walk.phase):
        locked = phases[str(phase)]
        E = np.eye(n)[list(locked)]
        C = np.vstack((A[i], E))
        k = C.shape[0]
        kkt = np.block([[M[i], -C.T], [C, np.zeros((k, k))]])
        rhs = np.concatenate((-h[i], -a_rate[i], np.zeros(len(locked))))
        sol = np.linalg.solve(kkt, rhs)
        for j, tau in zip(locked, sol[n + 2:], strict=True):
            torques[names[j]].append(float(tau))
    assert len(torques["stance_knee"]) > LOCK_TORQUE_SAMPLES // 2
    for name, values in torques.items():
        lo, hi = locks.ranges[name]
        v = np.asarray(values)
        tol = 1e-9 * max(abs(lo), abs(hi))
        assert np.all((v >= lo - tol) & (v <= hi + tol)), name
        assert v.min() == pytest.approx(lo, abs=tol) and v.max() == pytest.approx(hi, abs=tol)
    lo, hi = locks.ranges["stance_knee"]
    assert lo < -0.1 and hi > 0.2  # pulls and pushes: the two-sided lock


def test_notes_follow_each_gaits_fields() -> None:
    gaits = find_gaits(CompassGait(), 0.02)
    assert any(g.multi_swing for g in gaits) and not all(g.multi_swing for g in gaits)
    for g in gaits:
        assert (GaitNote.MULTI_SWING in g.notes) == (g.leg_crossings is not None
                                                     and g.leg_crossings > 1)
        assert GaitNote.NO_STABLE_GAIT not in g.notes  # the search met a stable gait
        assert GaitNote.HANGING_LINKS not in g.notes
    kneed = find_gaits(load_walker("kneed"), SLOPE)
    assert kneed[0].stable and kneed[0].notes == ()


def test_notes_of_a_search_that_meets_no_stable_gait() -> None:
    """The torso walker's upright gaits at 3 deg are unstable (QA sweeps 10 and 13); at its
    own parameters and reference slope there is no reference gait to follow."""
    gaits = find_gaits(load_walker("torso"), SLOPE)
    assert not any(g.stable for g in gaits)
    for g in gaits:
        assert GaitNote.NO_STABLE_GAIT in g.notes
        assert GaitNote.REFERENCE_FOLLOWED not in g.notes
        assert (GaitNote.HANGING_LINKS in g.notes) == bool(g.hanging_links)
    # given a guess, Newton converges to one gait: no search to speak of
    one = find_gaits(load_walker("torso"), SLOPE, guess=gaits[0].fixed_point)
    assert GaitNote.NO_STABLE_GAIT not in one[0].notes


def test_notes_of_hanging_torso_gaits() -> None:
    """The torso walker's passive gaits at 1.5 deg include one carrying the torso hanging
    (QA sweep 13), none stable; off the walker file's reference slope the search also follows
    the reference gait: the notes say all three, and only of the gaits they concern."""
    gaits = find_gaits(load_walker("torso"), float(np.deg2rad(1.5)))
    assert any(g.hanging_links for g in gaits) and not all(g.hanging_links for g in gaits)
    assert not any(g.stable for g in gaits)
    for g in gaits:
        assert (GaitNote.HANGING_LINKS in g.notes) == bool(g.hanging_links)
        assert {GaitNote.NO_STABLE_GAIT, GaitNote.REFERENCE_FOLLOWED} <= set(g.notes)


def test_cli_prints_the_gaits_notes_and_locks(monkeypatch: pytest.MonkeyPatch,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """``gait --model`` decides nothing: given a gait whose fields say so (a stable gait with
    a no-stable-gait note, locks on a walker without joints to lock), it prints them."""
    import heelstrike.analysis.gaits as gaits_module

    found = find_gaits(load_walker("compass"), SLOPE)
    assert found[0].stable and found[0].locks is None
    locks = GaitLocks(ranges={"knee": (-1.0, 2.0)}, two_sided={"knee": (-1.0, 2.0)})
    noted = tuple(replace(g, notes=(GaitNote.NO_STABLE_GAIT,), locks=locks) for g in found)
    monkeypatch.setattr(gaits_module, "find_gaits", lambda *a, **k: noted)
    assert main(["gait", "--model", "compass", "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["lock_torque_range"] == {"knee": [-1.0, 2.0]}
    assert "no stable period-one gait found (not by the automatic search)" in captured.err
    assert "the lock of 'knee' holds it with torques of both signs" in captured.err
    monkeypatch.setattr(gaits_module, "find_gaits", lambda *a, **k: found)
    assert main(["gait", "--model", "compass", "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["lock_torque_range"] == {}
    assert "note" not in captured.err


def test_notes_of_powered_gaits_of_mcgeers_wheel() -> None:
    """At ``R = l`` (McGeer's wheel) every powered gait's stability is undecided and its
    trailing foot grazes; at ``R = 0.3 l`` neither: the notes say so gait by gait, and that
    the search met no stable gait exactly where its first gait is unstable (not undecided)."""
    from heelstrike.analysis.powered import BOOKS_NOTE, books_gap

    for radius, wheel in ((1.0, True), (0.3, False)):
        gaits = find_gaits(CompassGait(foot_radius=radius), control="pushoff",
                           target={"speed": 0.5})
        assert all(g.stability_undecided == wheel for g in gaits)
        for g in gaits:
            assert (GaitNote.STABILITY_UNDECIDED in g.notes) == wheel
            assert (GaitNote.TRAILING_FOOT_GRAZES in g.notes) == g.trailing_foot_grazes == wheel
            # the wheel's gaits are undecided, not unstable: no "no stable gait" note
            assert (GaitNote.NO_STABLE_GAIT in g.notes) == (
                not gaits[0].stable and not gaits[0].stability_undecided)
            if wheel:
                assert GaitNote.NO_STABLE_GAIT not in g.notes
            assert (GaitNote.BOOKS_OPEN in g.notes) == (books_gap(g) > BOOKS_NOTE)
            assert g.locks is None and GaitNote.HANGING_LINKS not in g.notes
