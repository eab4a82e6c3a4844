"""The period-one line of ``heelstrike bifurcation`` follows the branch (QA sweep).

The branch used to be continued over 12 slopes evenly spaced over the range and drawn as
straight segments between them: where it curves (the compass gait on gentle slopes, the kneed
walker near 2.2 deg, where its gaits start at a fold) the line visibly missed the simulated
steady states. It is now continued over every slope of the diagram and refined where straight
segments would miss it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.gait_map import compass_bifurcation, model_bifurcation
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.cli import main
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker
from heelstrike.models import CompassGait


def _brute_force_period_one(out: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The slopes (deg) of the written diagram whose recorded steps all agree (the walk has
    settled on a period-one gait), with their impact angles (rad) and periods (s)."""
    import pandas as pd

    rows = pd.read_csv(out / "bifurcation.csv")
    # the recorded steps (the ``status`` column says how each slope's walk ended)
    rows = rows[["slope_deg", "impact_angle_rad", "period_s"]].dropna()
    g = rows.groupby("slope_deg")
    spread, mean = g.max() - g.min(), g.mean()
    settled = (spread["impact_angle_rad"] < 1e-7) & (spread["period_s"] < 1e-7)
    p1 = mean[settled]
    return p1.index.to_numpy(), p1["impact_angle_rad"].to_numpy(), p1["period_s"].to_numpy()


@pytest.mark.parametrize("argv", [
    ["--model", "kneed", "--slope-range", "2.2deg:3deg:9"],  # the reported case
    ["--slope-range", "0.5deg:2deg:7"],  # the compass gait on gentle slopes
])
def test_drawn_branch_meets_the_simulated_steady_states(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The written branch (the line drawn), interpolated at the slopes where the brute-force
    walks settled on a period-one gait, gives their impact angle and period (old sampling:
    misses of 4e-5 s (kneed) and 9e-5 rad (compass))."""
    import pandas as pd

    assert main(["bifurcation", *argv, "--transient", "50", "--record", "3",
                 "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    slopes, angle, period = _brute_force_period_one(tmp_path)
    assert slopes.size >= 6  # the walks settle on the stable range
    branch = pd.read_csv(tmp_path / "period_one_branch.csv")
    assert branch["stable"].all() and np.all(np.diff(branch["slope_deg"]) > 0)
    x = branch["slope_deg"].to_numpy()
    np.testing.assert_allclose(np.interp(slopes, x, branch["impact_angle_rad"]), angle,
                               rtol=0, atol=2e-6)
    np.testing.assert_allclose(np.interp(slopes, x, branch["period_s"]), period,
                               rtol=0, atol=2e-6)


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


@pytest.mark.slow
def test_branch_segments_follow_the_branch_near_its_onset(kneed: PhasedWalker) -> None:
    """From the onset (a fold near 2.16 deg, where the branch rises as a square root of the
    slope) every straight segment of the refined branch passes within 0.2 % of the branch's
    span of the gait found halfway along it (Newton from the ends' mean)."""
    _, branch = model_bifurcation(kneed, np.radians(np.linspace(2.1, 2.6, 4)), transient=5,
                                  record=1, continuation_points=None)
    x = branch.values
    assert 2.1 < np.degrees(x[0]) < 2.2  # the onset was found
    y = np.array([[c.impact_angle, c.period] for c in branch.cycles])
    span = np.ptp(y, axis=0)
    misses = []
    for k in range(x.size - 1):
        a, b = branch.cycles[k], branch.cycles[k + 1]
        mid = find_model_gait(kneed, slope=0.5 * (x[k] + x[k + 1]),
                              guess=0.5 * (a.fixed_point + b.fixed_point))
        misses.append(np.max(np.abs([mid.impact_angle, mid.period] - 0.5 * (y[k] + y[k + 1]))
                             / span))
    assert max(misses) < 2.5e-3  # 2e-3 by construction; Newton's tolerances aside
    # evenly spaced slopes (the library's default) miss it by far more there
    _, coarse = model_bifurcation(kneed, np.radians(np.linspace(2.1, 2.6, 4)), transient=5,
                                  record=1, continuation_points=4)
    a, b = coarse.cycles[0], coarse.cycles[1]
    mid = find_model_gait(kneed, slope=0.5 * (coarse.values[0] + coarse.values[1]),
                          guess=0.5 * (a.fixed_point + b.fixed_point))
    assert abs(mid.period - 0.5 * (a.period + b.period)) / span[1] > 10 * max(misses)


def test_refined_branch_keeps_its_period_doubling() -> None:
    """Across the compass gait's period doubling (4.391 deg at R = 0) the refined branch has
    the diagram's slopes, stable below the doubling and unstable above it."""
    slopes = np.radians(np.linspace(4.0, 4.8, 5))
    _, branch = compass_bifurcation(CompassGait(), slopes, transient=10, record=2,
                                    continuation_points=None)
    assert np.all(np.isin(slopes, branch.values))
    assert branch.period_doubling.size == 1
    pd_deg = float(np.degrees(branch.period_doubling[0]))
    assert pd_deg == pytest.approx(4.391, abs=1e-3)
    stable = np.array([c.stable for c in branch.cycles])
    np.testing.assert_array_equal(stable, np.degrees(branch.values) < pd_deg)
