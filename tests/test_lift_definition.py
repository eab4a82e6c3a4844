"""One definition of "the trailing foot lifts" for every heel-strike path (issue 9)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.heel_strike import heel_strike_study, trailing_foot_lifts
from heelstrike.analysis.model_gaits import (
    ANGLE,
    impact_map,
    model_heel_strike,
    symmetric_heel_strike_state,
)
from heelstrike.models import CompassGait
from heelstrike.models.builder import load_walker


@pytest.fixture(scope="module", autouse=True)
def _cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    d = tmp_path_factory.mktemp("hs_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("HEELSTRIKE_CACHE_DIR", str(d))
        yield d


def test_rule_is_relative_to_the_velocity_scale() -> None:
    assert trailing_foot_lifts(1e-6, 1.0)
    assert not trailing_foot_lifts(1e-12, 1.0)  # round-off of a zero lift velocity
    assert not trailing_foot_lifts(0.0, 1.0)
    assert not trailing_foot_lifts(-1e-3, 1.0)
    # scale-free: the same impact in other units decides the same way
    assert trailing_foot_lifts(1e-6 * 1e3, 1.0 * 1e3) == trailing_foot_lifts(1e-6, 1.0)
    np.testing.assert_array_equal(
        trailing_foot_lifts([1.0, -1.0, 0.0], [1.0, 1.0, 1.0]), [True, False, False]
    )


@pytest.mark.parametrize("R", [0.0, 0.3, 0.6, 1.0])
def test_described_and_paper_paths_decide_lift_alike(R: float) -> None:
    """The TOML compass and CompassGait agree on every impact, the wheel R = l included."""
    angles = np.deg2rad(np.linspace(2.0, 44.0, 15))
    study = heel_strike_study(CompassGait(foot_radius=R), angles)
    walker = load_walker("compass", R=R)
    for k, ang in enumerate(angles):
        q, qd = symmetric_heel_strike_state(walker, float(ang), stance_rate=1.0)
        hs = model_heel_strike(walker, q, qd)
        assert hs.trailing_foot_lifts == bool(study.trailing_foot_lifts[k]), (R, np.rad2deg(ang))
        if hs.trailing_foot_lifts:
            # admissible: the same impact (striking foot only); otherwise the described path
            # keeps the trailing contact active (complementarity), the paper's study does not
            assert hs.T_c == pytest.approx(
                float(study.kinetic_energy_constrained[k]), rel=1e-10, abs=1e-12
            )
    if R == 1.0:  # McGeer's wheel: q2_dot+ = 0 exactly, never admissible
        assert not np.any(study.trailing_foot_lifts)


def test_impact_map_has_no_lifting_cells_at_the_wheel() -> None:
    walker = load_walker("compass")
    m = impact_map(
        walker, ("R", np.array([0.9, 1.0])), (ANGLE, np.deg2rad(np.linspace(5.0, 40.0, 8)))
    )
    assert not np.any(m.lifts[:, 1])  # R = l: no cell may claim the foot lifts
