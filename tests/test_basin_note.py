"""``basin`` says when its gait is unstable; ``map`` says what its counts count (QA sweep).

A basin built around an unstable period-one gait is empty (0 % converging): the torso walker's
gait at 3 deg (largest |multiplier| about 25) and the compass gait's past its period doubling
(about 4.4 deg at R = 0). The command used to report 0 % with no reason; now the stability found
with the fixed point is in the result, the dataset, the figure's title, the text and stderr.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from heelstrike.analysis.basin import basin_of_attraction
from heelstrike.analysis.limit_cycle import find_limit_cycle
from heelstrike.cli import main
from heelstrike.models import CompassGait
from heelstrike.plots.gait import basin_figure

NOTE = "heelstrike: note: the period-one gait the basin is built around is unstable"


@pytest.mark.parametrize("slope_deg, stable", [(3.0, True), (5.0, False)])
def test_basin_records_the_stability_of_its_gait(slope_deg: float, stable: bool) -> None:
    slope = np.radians(slope_deg)
    gait = find_limit_cycle(CompassGait(), slope=slope, method="compiled")
    assert gait.stable is stable  # the premise: past the period doubling it is unstable
    b = basin_of_attraction(CompassGait(), slope, grid=(6, 5), steps=8)
    assert b.gait_stable is stable
    assert b.spectral_radius == pytest.approx(gait.spectral_radius, rel=1e-6)
    assert int(b.dataset.attrs["gait_stable"]) == int(stable)
    assert b.dataset.attrs["gait_spectral_radius"] == pytest.approx(gait.spectral_radius,
                                                                    rel=1e-6)
    title = basin_figure(b).axes[0].get_title()
    assert ("unstable" in title) is not stable
    if not stable:
        assert f"{gait.spectral_radius:.4g}" in title and "no start converges" in title
        assert b.converging_fraction == 0.0
    # a given fixed point: the stability is unknown, and nothing is claimed
    given = basin_of_attraction(CompassGait(), slope, grid=(3, 3), steps=2,
                                fixed_point=gait.fixed_point)
    assert given.gait_stable is None and "gait_stable" not in given.dataset.attrs
    assert "unstable" not in basin_figure(given).axes[0].get_title()


@pytest.mark.parametrize("slope, warned", [("3deg", False), ("5deg", True)])
def test_compass_basin_command_notes_an_unstable_gait(
    slope: str, warned: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["basin", "--slope", slope, "--grid", "6x5", "--steps", "8",
                 "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if line.startswith(NOTE)]
    assert len(notes) == int(warned)
    ds = xr.open_dataset(tmp_path / "basin.nc")
    try:
        assert int(ds.attrs["gait_stable"]) == int(not warned)
        rho = float(ds.attrs["gait_spectral_radius"])
    finally:
        ds.close()
    assert (rho > 1.0) is warned
    if warned:
        assert f"largest |multiplier| {rho:.4g}" in notes[0]
        assert "no start converges to it" in notes[0]
    assert re.search(r"gait +" + ("unstable" if warned else "stable"), captured.out)
    # --json: one object on stdout, the stability in it, the note on stderr still
    assert main(["basin", "--slope", slope, "--grid", "3x3", "--steps", "2",
                 "--out", str(tmp_path / "j"), "--json"]) == 0
    captured = capsys.readouterr()
    d = json.loads(captured.out)
    assert d["gait_stable"] is (not warned) and (d["spectral_radius"] > 1.0) is warned
    assert (NOTE in captured.err) is warned


def test_model_basin_command_notes_the_unstable_torso_gait(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.phased import load_phased_walker

    gait = find_model_gait(load_phased_walker("torso"), slope=np.radians(3.0))
    assert not gait.stable  # the premise (largest |multiplier| about 25)
    assert main(["basin", "--model", "torso", "--grid", "4x4", "--steps", "3",
                 "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    notes = [line for line in captured.err.splitlines() if line.startswith(NOTE)]
    assert len(notes) == 1 and f"largest |multiplier| {gait.spectral_radius:.4g}" in notes[0]
    assert re.search(r"gait +unstable", captured.out)
    ds = xr.open_dataset(tmp_path / "basin.nc")
    try:
        assert int(ds.attrs["gait_stable"]) == 0
        assert float(ds.attrs["gait_spectral_radius"]) == pytest.approx(gait.spectral_radius,
                                                                        rel=1e-6)
    finally:
        ds.close()


# -- map: counts of grid points, not values of R ---------------------------------------------------
def _check_map_lines(out: str, nc: Path) -> None:
    ds = xr.open_dataset(nc)
    try:
        found = ds["gait_found"].values.astype(bool)
        stable = ds["stable"].values.astype(bool)
    finally:
        ds.close()
    head = out.splitlines()[0]
    m = re.search(r"stable at (\d+) of (\d+) .* grid points; no gait found on the followed "
                  r"branch at (\d+) of (\d+) grid points", head)
    assert m, head
    assert [int(g) for g in m.groups()] == [int(stable.sum()), stable.size,
                                            int((~found).sum()), found.size]
    rows = [line for line in out.splitlines() if "period doubling" in line]
    assert len(rows) == found.shape[0]
    for line, frow in zip(rows, found, strict=True):
        m = re.search(r"no gait on the branch at +(\d+)/(\d+) slopes", line)
        assert m, line
        assert (int(m[1]), int(m[2])) == (int((~frow).sum()), frow.size)


def test_map_lines_count_grid_points(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The compass path (a gait everywhere: 'no gait found at 0' read as 'at R = 0')."""
    assert main(["map", "--radius", "0:0.2:2", "--slope", "3deg:5deg:2",
                 "--out", str(tmp_path)]) == 0
    _check_map_lines(capsys.readouterr().out, tmp_path / "gait_map.nc")


def test_model_map_lines_count_grid_points(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    """The --model path, with grid points without a gait (the kneed walker below ~2 deg)."""
    assert main(["map", "--model", "kneed", "--radius", "0:0.15:2", "--slope", "1deg:3deg:2",
                 "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    _check_map_lines(out, tmp_path / "gait_map.nc")
    assert not re.search(r"no gait found on the followed branch at 0 of", out)  # some have none
    # QA sweep 9: where the branch has no gait, another may exist; the row labels carry units
    assert "a gait off the branch may still exist there" in out.splitlines()[0]
    assert "R =        0 m: stable at" in out
