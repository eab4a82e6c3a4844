"""CLI contracts of the gait commands (issue 3)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from heelstrike.analysis.limit_cycle import find_limit_cycle
from heelstrike.cli import main
from heelstrike.models.compass import CompassGait

GAIT_KEYS = {
    "period", "step_length", "speed", "impact_angle", "multipliers", "stable",
    "collision_loss", "eta", "fixed_point",
}


@pytest.mark.slow
def test_gait_json_contract_matches_library(capsys):
    assert main(["gait", "--radius", "0.3", "--slope", "3deg", "--json"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    d = json.loads(out[0])
    assert GAIT_KEYS <= d.keys()
    assert set(d["fixed_point"]) == {"q3", "q3_dot", "q4_dot"}
    assert d["multipliers"] == sorted(d["multipliers"], reverse=True)
    cycle = find_limit_cycle(CompassGait(foot_radius=0.3), slope=np.deg2rad(3.0))
    assert d["period"] == pytest.approx(cycle.period, rel=1e-8)
    assert d["impact_angle"] == pytest.approx(cycle.impact_angle, rel=1e-8)
    assert d["stable"] is True
    # passive gait: collision loss balances the potential energy released
    assert d["collision_loss"] == pytest.approx(d["potential_energy_released"], rel=1e-7)
    assert d["speed"] == pytest.approx(d["step_length"] / d["period"])


@pytest.mark.slow
def test_gait_without_solution_fails_cleanly(capsys):
    assert main(["gait", "--slope", "30deg", "--json"]) != 0
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("heelstrike: error: no gait found")


@pytest.mark.parametrize(
    "argv",
    [
        ["gait", "--slope", "abc"],
        ["gait", "--radius", "1.5"],
        ["gait", "--guess", "1,2"],
        ["walk", "--out", "walk.txt"],
        ["bifurcation", "--slope-range", "5deg:1deg"],
    ],
)
def test_gait_commands_reject_bad_input(argv, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heelstrike: error:")


def test_walk_writes_animation(tmp_path, capsys):
    out = tmp_path / "walk.gif"
    status = main(["walk", "--radius", "0.3", "--steps", "1", "--fps", "8",
                   "--guess=-0.386284,1.419327,-0.967944", "--out", str(out)])
    assert status == 0
    from PIL import Image

    with Image.open(out) as im:
        assert im.n_frames >= 5
    assert str(out) in capsys.readouterr().out
