"""Every backend decides the same physics the same way (issue 9).

Four simulators walk the same compass gait: :func:`~heelstrike.dynamics.hybrid.simulate` (scipy)
and the compiled kernel (:mod:`heelstrike.dynamics.compiled`) on the paper's
:class:`~heelstrike.models.CompassGait`, :func:`~heelstrike.dynamics.phased.simulate_phased`
(scipy) and its compiled backend on the described ``compass.toml`` walker. They must give the
same :class:`~heelstrike.dynamics.hybrid.WalkStatus` where the decision is sharp:

- *the trailing foot lifts*: one relative rule (:mod:`heelstrike.models._contact`) for all four,
  checked on impacts whose lift velocity lies just below and just above ``LIFT_TOLERANCE`` (and
  far above any absolute round-off threshold such as ``1e-12 m/s``, so a backend with its own
  rule disagrees);
- *a launch too fast for the ground*: the stance normal force is negative (or crosses zero)
  before the hip passes the vertical, so contact is lost; the walker cannot "fall forward".
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.heel_strike import LIFT_TOLERANCE, trailing_foot_lifts
from heelstrike.dynamics.compiled import ensemble_walk, step_map_compiled
from heelstrike.dynamics.compiled_phased import ensemble_walk_phased, simulate_phased_compiled
from heelstrike.dynamics.hybrid import WalkStatus, simulate
from heelstrike.dynamics.phased import simulate_phased
from heelstrike.dynamics.single_support import SingleSupport
from heelstrike.models import CompassGait
from heelstrike.models._contact import lift_velocity_scale, lifts
from heelstrike.models.builder import load_walker

SLOPE = 0.05  # rad


@pytest.fixture(scope="module", autouse=True)
def _cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    d = tmp_path_factory.mktemp("hs_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("HEELSTRIKE_CACHE_DIR", str(d))
        yield d


def _start(R: float, q3: float, q3_dot: float, q4_dot: float) -> tuple[np.ndarray, np.ndarray]:
    """Post-impact state: stance foot rolling, legs symmetric (``q4 = -2 q3``)."""
    return np.array([0.0, R, q3, -2.0 * q3]), np.array([-R * q3_dot, 0.0, q3_dot, q4_dot])


def _statuses(R: float, q3: float, q3_dot: float, q4_dot: float) -> dict[str, WalkStatus]:
    """One step of every backend (both scipy, both compiled, and both ensembles)."""
    walker = CompassGait(foot_radius=R)
    built = load_walker("compass", R=R)
    q, qd = _start(R, q3, q3_dot, q4_dot)
    z = np.array([q3, q3_dot, q4_dot])
    return {
        "simulate": simulate(walker, q, qd, slope=SLOPE).status,
        "step_map_compiled": step_map_compiled(walker, z, SLOPE).status,
        "ensemble_walk": WalkStatus.from_code(
            int(ensemble_walk(walker, z, SLOPE, parallel=False).status[0])
        ),
        "simulate_phased": simulate_phased(built, q, qd, slope=SLOPE).status,
        "simulate_phased_compiled": simulate_phased_compiled(built, q, qd, slope=SLOPE).status,
        "ensemble_walk_phased": WalkStatus.from_code(int(ensemble_walk_phased(
            built, states=(q[None], qd[None]), slope=SLOPE, parallel=False).status[0])),
    }


def test_lift_rule_is_relative_and_compilable() -> None:
    """The scalar rule (what the kernels compile) and the array rule are the same rule."""
    numba = pytest.importorskip("numba")
    jit_lifts = numba.njit(lifts)
    jit_scale = numba.njit(lift_velocity_scale)
    rates = np.array([0.7, -1.3])
    scale = lift_velocity_scale(0.8, rates)
    assert scale == pytest.approx(0.8 * 2.0)
    assert jit_scale(0.8, rates) == scale
    for factor in (0.5, 0.999, 1.001, 2.0):
        v = factor * LIFT_TOLERANCE * scale
        assert jit_lifts(v, scale) == lifts(v, scale) == bool(trailing_foot_lifts(v, scale))
        assert lifts(v, scale) == (factor > 1.0)


# Near McGeer's wheel (R -> l) the trailing foot's lift velocity after heel strike is about
# 0.24 (l - R) l |q_dot-|: these two radii put it at ~0.3 and ~3 LIFT_TOLERANCE.
@pytest.mark.slow  # the compiled phased kernel: a minute or two on a cold numba cache
@pytest.mark.parametrize("gap", [1.2e-9, 1.2e-8])
def test_every_backend_applies_the_one_lift_rule(gap: float) -> None:
    R = 1.0 - gap
    q, qd = _start(R, -0.2, 0.6, 0.0)
    ref = simulate(CompassGait(foot_radius=R), q, qd, slope=SLOPE)
    assert len(ref.impacts) == 1
    hit = ref.impacts[0]
    v = hit.trailing_normal_velocity
    scale = lift_velocity_scale(1.0, hit.q_dot_minus[2:])
    # the impact is a close call for the relative rule, and no call at all for 1e-12 m/s
    assert 0.1 * LIFT_TOLERANCE < v / scale < 10.0 * LIFT_TOLERANCE
    assert v > 100.0 * 1e-12
    expected = (
        WalkStatus.COMPLETED if trailing_foot_lifts(v, scale) else WalkStatus.TRAILING_FOOT_STAYS
    )
    assert (expected is WalkStatus.COMPLETED) == (gap > 5e-9)  # both sides are exercised
    statuses = _statuses(R, -0.2, 0.6, 0.0)
    assert statuses == dict.fromkeys(statuses, expected)


@pytest.mark.slow  # the compiled phased kernel: a minute or two on a cold numba cache
@pytest.mark.parametrize("q3_dot", [3.5, 4.0, 6.0])
def test_too_fast_launch_loses_contact_on_every_backend(q3_dot: float) -> None:
    """Hip behind the stance foot (``q3 < 0``) and fast: the ground would have to pull.

    At 4 and 6 rad/s the normal force is negative from the start (the scipy described walker used
    to integrate on and report ``fell_forward`` at ``q3 = pi/2``); at 3.5 rad/s it is positive at
    the start and crosses zero during the step (after mid-stance): contact is lost either way.
    """
    q3 = -0.2
    walker = CompassGait()
    q, qd = _start(0.0, q3, q3_dot, 0.0)
    normal = float(SingleSupport(walker=walker, slope=SLOPE).ground_reaction(0.0, q, qd)[1])
    assert (normal < 0.0) == (q3_dot > 3.75)
    ref = simulate(walker, q, qd, slope=SLOPE)
    assert ref.status is WalkStatus.LOST_CONTACT
    if normal < 0.0:
        assert float(ref.final_q[2]) == q3  # lost at once, before the hip passed the vertical
    statuses = _statuses(0.0, q3, q3_dot, 0.0)
    assert statuses == dict.fromkeys(statuses, WalkStatus.LOST_CONTACT)
