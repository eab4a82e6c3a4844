"""Gaits that carry a link described upright hanging are said to (QA sweep 13).

The torso walker's stable passive gaits on 1-2 deg carry the torso through the legs, 179 deg
from upright, while its upright gaits are unstable; ``gait`` showed the hanging one as "the
most attracting stable gait" and ``map`` followed the upright ones, with no word on which was
which.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.model_gaits import hanging_links
from heelstrike.cli import main
from heelstrike.models import load_walker

ARGS = ["--model", "torso", "--param", "R=0.3"]


def _torso_points_down(q: list[float]) -> bool:
    """The torso's absolute angle (stance leg + torso joint) more than 90 deg from upright."""
    return bool(np.cos(q[2] + q[4]) < 0.0)


def test_gait_says_which_gaits_hang_the_torso(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["gait", *ARGS, "--slope", "0.02", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert len(d["gaits"]) >= 2
    kinds = set()
    for g in d["gaits"]:
        down = _torso_points_down(g["q"])
        assert g["hanging_links"] == (["torso"] if down else [])
        kinds.add(down)
    assert kinds == {True, False}  # both kinds of gait are met here
    assert d["hanging_links"] == d["gaits"][0]["hanging_links"] == ["torso"]
    assert d["gaits"][0]["stable"] and not d["gaits"][1]["stable"]
    assert main(["gait", *ARGS, "--slope", "0.02"]) == 0
    out = capsys.readouterr().out
    assert "note: 'torso' hangs (its centre of mass below its joint) in this gait" in out


def test_the_compass_and_the_kneed_walker_hang_nothing() -> None:
    from heelstrike.analysis.model_gaits import upright_links

    for name in ("compass", "kneed"):
        w = load_walker(name)
        q = np.zeros(len(w.coordinate_names))
        assert hanging_links(w, q, 0.05) == ()
        # the kneed walker's stance thigh stands on a lockable knee: not a link to turn over
        assert upright_links(w) == ()
    assert upright_links(load_walker("torso")) == ("torso",)


def test_an_upright_torso_turned_over_hangs() -> None:
    w = load_walker("torso")
    q = np.zeros(5)
    assert hanging_links(w, q, 0.0) == ()
    for angle in (2.0, -2.0, np.pi):  # the torso joint turned past 90 deg either way
        q[4] = angle
        assert hanging_links(w, q, 0.0) == ("torso",)
    q[4] = 1.5  # 86 deg from upright on level ground: still above the hip
    assert hanging_links(w, q, 0.0) == ()


@pytest.mark.slow
def test_bifurcation_basin_and_map_say_which_gait_they_follow(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert main(["bifurcation", *ARGS, "--slope-range", "0.02:0.06:3", "--out",
                 str(tmp_path / "b"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert "on the branch followed, 'torso' hangs" in d["note"]
    assert main(["basin", *ARGS, "--slope", "0.02", "--grid", "4x4", "--steps", "5", "--out",
                 str(tmp_path / "basin")]) == 0
    assert "in the gait the basin is built around, 'torso' hangs" in capsys.readouterr().err
    import xarray as xr

    # the map's gaits, each checked from its fixed point (stance leg and torso angles)
    for x, slopes, hanging in (("R:0:0.3:2", "1deg:2deg:2", 4), ("R:0:0.3:3", "1deg:3deg:3", 0)):
        assert main(["map", "--model", "torso", "--x", x, "--slope", slopes,
                     "--out", str(tmp_path / x), "--json"]) == 0
        d = json.loads(capsys.readouterr().out)
        with xr.open_dataset(d["data"]) as ds:
            z = ds["fixed_point"].values.reshape(-1, 3 + 2)
        found = z[np.isfinite(z[:, 0])]
        down = int(np.sum(np.cos(found[:, 0] + found[:, 1]) < 0.0))  # stance_leg + torso
        assert down == hanging
        if hanging:
            assert d["note"].startswith(f"in {down} of the {len(found)} gaits found, 'torso' "
                                        "hangs")
        else:  # this grid's branch is of the upright gaits, and the note says so
            assert d["note"].startswith(f"in all {len(found)} gaits found, 'torso' stands "
                                        "above its joint: gaits of the upright link; gaits "
                                        "with it hanging may exist too")


@pytest.mark.parametrize(("torso", "hangs"), [(0.2, False), (np.pi + 0.2, True), (1.9, True)])
def test_a_basin_records_whether_its_gait_hangs_a_link(torso: float, hangs: bool) -> None:
    """Issue #32, item 5: the basin result says whether the fixed point it is built around
    carries the torso hanging (the CLI prints the field); checked against the torso's
    absolute angle (stance leg + torso joint) more than 90 deg from upright."""
    from heelstrike.analysis.basin import basin_of_attraction, model_basin_of_attraction
    from heelstrike.models import CompassGait

    z = np.array([-0.2, torso, 1.0, -0.5, 0.0])  # (stance_leg, torso, their rates, hip rate)
    assert (np.cos(z[0] + z[1]) < 0.0) == hangs
    basin = model_basin_of_attraction(
        load_walker("torso"), 0.02, grid=(1, 1), steps=1, fixed_point=z, backend="scipy",
        ranges=((z[0] - 1e-3, z[0] + 1e-3), (z[2] - 1e-3, z[2] + 1e-3)))
    assert basin.hanging_links == (("torso",) if hangs else ())
    compass = basin_of_attraction(CompassGait(), 0.05, grid=(1, 1), steps=1, backend="scipy",
                                  fixed_point=[-0.27, 1.09, -0.72],
                                  ranges=((-0.271, -0.269), (1.089, 1.091)))
    assert compass.hanging_links == ()


def test_a_model_map_counts_the_gaits_that_hang_a_link() -> None:
    """Issue #32, item 5: the map result counts its gaits that carry the torso hanging (the
    CLI prints the fields); checked cell by cell from the fixed points' torso angle (stance
    leg + torso joint more than 90 deg from upright). On 1-2 deg the torso walker's gaits at
    R = 0 and 0.3 m all hang it (the slow CLI test above: 4 of 4)."""
    from heelstrike.analysis.gait_map import model_gait_map

    gmap = model_gait_map(load_walker("torso"), "R", [0.0, 0.3], np.deg2rad([1.0, 2.0]))
    z = gmap.dataset["fixed_point"].values.reshape(-1, 5)
    found = z[np.isfinite(z[:, 0])]
    down = int(np.sum(np.cos(found[:, 0] + found[:, 1]) < 0.0))
    assert gmap.hanging_cells == down == len(found) == 4
    assert gmap.hanging_links == ("torso",)
    assert gmap.upright_links == ("torso",)
