"""``bifurcation`` on a slope range that starts below the walker's first gait (qa_sweep P1-4).

The kneed walker has no passive gait on gentle slopes; its stable gaits start near 2.15 deg.
The bifurcation functions find where they start (automatic gait search, then bisection), draw
nothing below, and say so; a range without any gait is a one-line error.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.gait_map import model_bifurcation
from heelstrike.analysis.limit_cycle import GaitNotFoundError, PoincareMap
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.cli import main
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker, simulate_phased


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


@pytest.fixture(scope="module")
def kneed_default_range(kneed: PhasedWalker):  # type: ignore[no-untyped-def]
    """The command's default range, 0.5-6 deg (45 slopes)."""
    return model_bifurcation(kneed, np.deg2rad(np.linspace(0.5, 6.0, 45)), transient=20,
                             record=4)


@pytest.mark.slow
def test_kneed_default_range_starts_where_its_gaits_start(kneed_default_range) -> None:  # type: ignore[no-untyped-def]
    diagram, branch = kneed_default_range
    onset = float(np.degrees(branch.values[0]))
    assert 2.0 < onset < 2.3
    # nothing walked below the onset, the slopes above it walk (the gait there is stable)
    below = diagram.slopes < branch.values[0]
    assert below.any() and np.isnan(diagram.impact_angles[below]).all()
    assert np.isfinite(diagram.impact_angles[~below]).all()
    # the branch covers the rest of the range and is the stable family
    assert len(branch.cycles) == 12 and branch.values[-1] == pytest.approx(np.deg2rad(6.0))
    assert all(c.stable for c in branch.cycles)


@pytest.mark.slow
def test_the_kneed_onset_is_real(kneed: PhasedWalker, kneed_default_range) -> None:  # type: ignore[no-untyped-def]
    """A gait just above the onset (automatic search), none just below it; the branch's gaits
    are fixed points of the scipy reference map."""
    _, branch = kneed_default_range
    onset = float(branch.values[0])
    above = find_model_gait(kneed, slope=onset + np.deg2rad(0.01))
    assert above.stable
    with pytest.raises(GaitNotFoundError):
        find_model_gait(kneed, slope=onset - np.deg2rad(0.01))
    for cycle in (branch.cycles[0], branch.cycles[1], branch.cycles[6]):
        ref = PoincareMap(walker=kneed, simulator=simulate_phased, slope=cycle.slope,
                          rtol=1e-12, atol=1e-12)
        z = cycle.fixed_point
        assert np.linalg.norm(ref(z) - z) < 1e-7


def test_a_range_without_gaits_is_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["bifurcation", "--model", "kneed", "--slope-range", "0.5deg:1deg:3",
                 "--out", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert captured.out == ""
    assert len(err) == 1 and err[0].startswith("heelstrike: error: no gait found from 0.5 to 1 deg")
    assert not (tmp_path / "bifurcation.png").exists()


@pytest.mark.slow
def test_kneed_command_notes_the_empty_part(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import pandas as pd

    assert main(["bifurcation", "--model", "kneed", "--slope-range", "1.5deg:3deg:7",
                 "--transient", "10", "--record", "2", "--out", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    note = [line for line in lines if line.startswith("note:")]
    assert len(note) == 1 and "from 1.5 to 2.1" in note[0]
    branch = pd.read_csv(tmp_path / "period_one_branch.csv")
    assert 2.0 < branch["slope_deg"].iloc[0] < 2.3
    rows = pd.read_csv(tmp_path / "bifurcation.csv")
    low = rows["slope_deg"] < branch["slope_deg"].iloc[0]
    assert low.any() and rows.loc[low, "impact_angle_rad"].isna().all()
    assert rows.loc[~low, "impact_angle_rad"].notna().all()


@pytest.mark.slow
def test_an_unstable_gait_that_ends_does_not_start_the_diagram(kneed: PhasedWalker) -> None:
    """At 2 deg the kneed walker's automatic search finds only a long-period unstable gait
    (|m| 18.5) whose family ends before the next slope; the diagram used to start from it and
    its branch had one point. It now starts where the stable family starts (2.158 deg)."""
    at_two = find_model_gait(kneed, slope=np.deg2rad(2.0))
    assert not at_two.stable  # the premise: what the search finds at 2 deg
    _, branch = model_bifurcation(kneed, np.deg2rad(np.linspace(2.0, 3.0, 9)), transient=10,
                                  record=2, continuation_points=6)
    assert 2.1 < float(np.degrees(branch.values[0])) < 2.2
    assert len(branch.cycles) == 6 and all(c.stable for c in branch.cycles)


def test_past_period_doubling_the_unstable_branch_still_starts_the_diagram() -> None:
    """Above the compass gait's period doubling (4.39 deg) the period-one gait at the range's
    first slope is unstable and its family goes on: the diagram starts there, as before."""
    from heelstrike.analysis.gait_map import compass_bifurcation
    from heelstrike.models import CompassGait

    slopes = np.deg2rad(np.linspace(5.0, 5.5, 3))
    _, branch = compass_bifurcation(CompassGait(), slopes, transient=10, record=2,
                                    continuation_points=3)
    assert branch.values[0] == pytest.approx(slopes[0])
    assert not branch.cycles[0].stable and len(branch.cycles) == 3
