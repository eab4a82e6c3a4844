"""The stance foot's ground force of a walker with locked joints (the kneed walker's knees).

The force is Newton's law for the whole walker: the base coordinates ``(x, y)`` carry every
link, so ``P = (M q_dot)[:2]`` is the walker's linear momentum and ``lambda = dP/dt - m g``.
The locked knees are held by torques that belong in that balance. The contact-only formula
``(A M^-1 A^T)^-1 A M^-1 h`` lets the knees accelerate and misses it. The lost-contact and
slip events of both backends used that formula until 2026-11-23.
"""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.analysis.walk_tables import step_table
from heelstrike.dynamics.compiled_phased import simulate_phased_compiled
from heelstrike.dynamics.hybrid import ground_reaction
from heelstrike.dynamics.phased import (
    PhasedWalker,
    PhasedWalkResult,
    load_phased_walker,
    simulate_phased,
)
from heelstrike.dynamics.single_support import SingleSupport
from heelstrike.models.base import gravity_vector

KNEED_SLOPE = 0.0504
KNEED_GAIT = [-0.2647694, 1.2181144, -1.0955048]


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


def _unlocked_reaction(w: PhasedWalker, q: np.ndarray, qd: np.ndarray, slope: float) -> np.ndarray:
    M, h = w.dynamics_terms(q, qd, slope)
    A = w.contact_jacobian(q, "right")
    X = np.linalg.solve(M, np.concatenate((A.T, h[:, None]), axis=1))
    return np.linalg.solve(A @ X[:, :2], A @ X[:, 2])


def _newtons_law(w: PhasedWalker, walk: PhasedWalkResult, phase: str
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The samples of ``phase`` in the walk's first step and ``dP/dt - m g`` at each (N), by
    central differences of the momentum ``P = (M q_dot)[:2]``."""
    idx = np.flatnonzero((walk.phase == phase) & (walk.step == 0))
    assert idx.size > 40 and np.all(np.diff(idx) == 1)  # one run of samples per phase
    assert np.all(np.diff(walk.t[idx]) > 0)
    momentum = np.einsum("...ij,...j->...i", w.mass_matrix(walk.q[idx]), walk.q_dot[idx])[:, :2]
    scale = w.scale
    weight = float(scale.total_mass) * gravity_vector(float(scale.gravity), KNEED_SLOPE)
    return idx, np.gradient(momentum, walk.t[idx], axis=0) - weight


def test_ground_reaction_is_newtons_law_with_the_knees_held(kneed: PhasedWalker) -> None:
    """``lambda = dP/dt - m g`` by central differences along a walk sampled every 1 ms, in both
    phases of the step (stance knee held; both knees held), to 2e-3 N of a 15.7 N weight; the
    unlocked formula misses it by more than 0.1 N."""
    w = kneed
    q, qd = w.section_to_state(np.asarray(KNEED_GAIT))
    walk = simulate_phased(w, q, qd, slope=KNEED_SLOPE, steps=1, rtol=1e-12, atol=1e-12,
                           max_step=1e-3)
    assert walk.status.value == "completed"
    locks = {phase.name: phase.locked for phase in w.step_schedule().phases}
    assert set(np.unique(walk.phase)) == set(locks)
    worst_unlocked = 0.0
    for name, locked in locks.items():
        idx, newton = _newtons_law(w, walk, name)
        inner = slice(3, -3)  # away from the impacts that bound the phase
        support = SingleSupport(walker=w, slope=KNEED_SLOPE, locked=locked)
        got = support.ground_reaction(0.0, walk.q[idx], walk.q_dot[idx])
        np.testing.assert_allclose(got[inner], newton[inner], atol=2e-3, err_msg=name)
        for i in idx[inner][::10]:  # one state at a time (the events' path) agrees
            np.testing.assert_allclose(support.ground_reaction(0.0, walk.q[i], walk.q_dot[i]),
                                       got[np.searchsorted(idx, i)], rtol=1e-12, atol=1e-12)
            miss = _unlocked_reaction(w, walk.q[i], walk.q_dot[i], KNEED_SLOPE) - got[
                np.searchsorted(idx, i)]
            worst_unlocked = max(worst_unlocked, float(np.max(np.abs(miss))))
    assert worst_unlocked > 0.1


def test_ground_reaction_is_the_constrained_form_with_lock_rows(kneed: PhasedWalker) -> None:
    """The same force from the KKT system ``[[M, -C^T], [C, 0]]`` with ``C = [A_R; E]`` (the
    contact rows and the locked joints' rows) at random states of both phases."""
    w = kneed
    rng = np.random.default_rng(7)
    q0, _ = w.section_to_state(np.asarray(KNEED_GAIT))
    n = q0.size
    for locked in ((3,), (3, 5)):
        support = SingleSupport(walker=w, slope=KNEED_SLOPE, locked=locked)
        for _ in range(10):
            x = support.pack(q0, np.zeros(n))
            m = len(support.free_coordinates)
            x[:m] += rng.normal(scale=0.2, size=m)
            x[m:] = rng.normal(scale=1.5, size=m)
            q, qd = support.unpack(x, q0)
            M, h = w.dynamics_terms(q, qd, KNEED_SLOPE)
            C = np.vstack((w.contact_jacobian(q, "right"), np.eye(n)[list(locked)]))
            k = C.shape[0]
            # A_dot q_dot of the contact rows; the lock rows are constant
            rate = np.concatenate((w.contact_jacobian_rate(q, qd, "right"), np.zeros(k - 2)))
            K = np.block([[M, -C.T], [C, np.zeros((k, k))]])
            sol = np.linalg.solve(K, np.concatenate((-h, -rate)))
            np.testing.assert_allclose(support.accelerations(0.0, q, qd), sol[:n], atol=1e-9)
            np.testing.assert_allclose(support.ground_reaction(0.0, q, qd), sol[n:n + 2],
                                       atol=1e-9)


def test_both_backends_slip_where_the_held_knee_force_leaves_the_cone(
    kneed: PhasedWalker,
) -> None:
    """A step from near the gait (hip rate 0.5 rad/s slower) whose ratio ``|lambda_t| /
    lambda_n`` is largest late in the step, both knees held; a friction coefficient between
    that ratio and the ratio at the start: both backends walk on and report ``slipped`` at the
    same time, where ``mu lambda_n = |lambda_t|`` holds for the force with the knees held."""
    w = kneed
    q, qd = w.section_to_state(np.add(KNEED_GAIT, [0.0, 0.0, -0.5]))
    walk = simulate_phased(w, q, qd, slope=KNEED_SLOPE, steps=1, rtol=1e-12, atol=1e-12,
                           max_step=1e-3)
    locks = {phase.name: phase.locked for phase in w.step_schedule().phases}
    ratio = np.empty(walk.t.size)
    for name, locked in locks.items():
        sel = walk.phase == name
        lam = SingleSupport(walker=w, slope=KNEED_SLOPE, locked=locked).ground_reaction(
            0.0, walk.q[sel], walk.q_dot[sel])
        ratio[sel] = np.abs(lam[:, 0]) / lam[:, 1]
    mu = 0.5 * (ratio[0] + ratio.max())
    assert walk.status.value == "completed"
    assert ratio.max() > ratio[0] + 1e-3  # the cone is left during the step, not at its start
    ends = []
    for sim in (simulate_phased, simulate_phased_compiled):
        res = sim(w, q, qd, slope=KNEED_SLOPE, steps=1, friction=mu, rtol=1e-11, atol=1e-11)
        assert res.status.value == "slipped"
        assert res.t[-1] > 0.0
        locked = locks[str(res.phase[-1])]
        lam = SingleSupport(walker=w, slope=KNEED_SLOPE, locked=locked).ground_reaction(
            0.0, res.q[-1], res.q_dot[-1])
        assert mu * lam[1] - abs(lam[0]) == pytest.approx(0.0, abs=1e-7)
        ends.append(res.t[-1])
    assert ends[0] == pytest.approx(ends[1], abs=1e-8)


def test_walk_ground_reaction_and_step_table_hold_each_phase_locks(kneed: PhasedWalker) -> None:
    """:func:`~heelstrike.dynamics.hybrid.ground_reaction` over a walk, and the step table (the
    ``walk --model`` step figure's data) built on it, take each sample's locks from its phase:
    Newton's law over the whole first step, both phases."""
    w = kneed
    q, qd = w.section_to_state(np.asarray(KNEED_GAIT))
    walk = simulate_phased(w, q, qd, slope=KNEED_SLOPE, steps=2, rtol=1e-12, atol=1e-12,
                           max_step=1e-3)
    gr = ground_reaction(w, walk)
    step = step_table(w, walk, 0)
    first = np.flatnonzero(walk.step == 0)
    np.testing.assert_array_equal(step["normal_N"], gr.normal[first])
    np.testing.assert_allclose(step["swing_rad"], walk.q[first, 2] + walk.q[first, 4]
                               + walk.q[first, 3], atol=1e-15)  # shank + knee + hip: thigh
    for name in ("knee_swing", "locked_swing"):
        idx, newton = _newtons_law(w, walk, name)
        got = np.stack((gr.tangential[idx], gr.normal[idx]), axis=1)
        np.testing.assert_allclose(got[3:-3], newton[3:-3], atol=2e-3, err_msg=name)


def test_walk_ground_reaction_refuses_a_walk_of_unknown_phases(kneed: PhasedWalker) -> None:
    """A walk whose phase labels are not the walker's phases (here: the labels dropped) has
    unknown locked joints: the ground force is refused, not computed with the knees free."""
    import dataclasses

    q, qd = kneed.section_to_state(np.asarray(KNEED_GAIT))
    walk = simulate_phased(kneed, q, qd, slope=KNEED_SLOPE, steps=1)
    unlabelled = dataclasses.replace(walk, phase=np.full(walk.t.size, ""))
    with pytest.raises(ValueError, match="which joints it holds is unknown"):
        ground_reaction(kneed, unlabelled)
    renamed = dataclasses.replace(walk, phase=np.full(walk.t.size, "swing"))
    with pytest.raises(ValueError, match="'swing' is none of the walker's phases"):
        ground_reaction(kneed, renamed)
