"""The automatic gait search of described walkers finds the stable gait that exists.

A QA sweep found ``gait --model kneed --param R=0.5 --slope 4deg`` reporting an unstable gait
(|m| 2.17) where ``map`` follows a stable one (spectral radius 0.747): Newton from the five most
nearly periodic grid states reached only the unstable gait. The search now follows the walker
file's own stable gait (3 deg) to the requested parameters and slope when the grid finds no
stable gait, and lists every gait it found (``gaits`` in ``--json``), stable first.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from heelstrike.analysis.limit_cycle import GaitNotFoundError, PoincareMap
from heelstrike.analysis.model_gaits import find_model_gait, find_model_gaits
from heelstrike.dynamics.phased import PhasedWalker
from heelstrike.models import load_walker

SLOPE = float(np.deg2rad(4.0))


@pytest.fixture(scope="module")
def kneed_r05() -> PhasedWalker:
    return PhasedWalker.from_built(load_walker("kneed", R=0.5))


@pytest.fixture(scope="module")
def gaits(kneed_r05: PhasedWalker) -> tuple:
    return find_model_gaits(kneed_r05, slope=SLOPE)


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "heelstrike", *args], capture_output=True,
                          text=True, timeout=600)


def test_stable_gait_found_first(gaits: tuple) -> None:
    first = gaits[0]
    assert first.stable
    assert first.spectral_radius < 1.0
    # the unstable gait the grid search reaches is found too, and listed after it
    assert len(gaits) >= 2
    assert not gaits[1].stable
    assert gaits[1].spectral_radius > 1.0
    # distinct gaits: different fixed points and periods
    assert np.linalg.norm(np.asarray(first.fixed_point) - gaits[1].fixed_point) > 1e-3
    assert abs(first.period - gaits[1].period) > 1e-2
    assert find_model_gait(load_walker("kneed", R=0.5), slope=SLOPE).stable


def test_found_gaits_are_periodic_on_the_scipy_reference(kneed_r05: PhasedWalker,
                                                         gaits: tuple) -> None:
    """Each gait is a fixed point of the independent scipy step map, and its energy book
    closes: the potential energy released equals the sum of T_c over its impacts."""
    pmap = PoincareMap(walker=kneed_r05, slope=SLOPE, rtol=1e-11, atol=1e-11)
    for g in gaits:
        z = np.asarray(g.fixed_point)
        np.testing.assert_allclose(pmap(z), z, atol=1e-8)
        assert abs(g.energy_residual) < 1e-8
        assert g.collision_loss == pytest.approx(
            sum(e.kinetic_energy_constrained for e in g.impacts), abs=1e-12)
        assert [e.kind for e in g.impacts] == ["knee_strike", "heel_strike"]


def test_the_stable_gait_is_the_one_map_follows(gaits: tuple) -> None:
    from heelstrike.analysis.gait_map import model_gait_map

    gmap = model_gait_map(load_walker("kneed"), "R", [0.5], [SLOPE])
    ds = gmap.dataset
    np.testing.assert_allclose(ds["fixed_point"].values[0, 0], gaits[0].fixed_point,
                               atol=1e-8)
    assert float(ds["spectral_radius"].values[0, 0]) == pytest.approx(
        gaits[0].spectral_radius, abs=1e-6)


def test_passive_walker_on_level_ground_is_refused_with_the_reason() -> None:
    for name in ("kneed", "compass"):
        with pytest.raises(GaitNotFoundError, match=r"slope must be > 0"):
            find_model_gait(load_walker(name), slope=0.0)
        with pytest.raises(GaitNotFoundError, match=r"slope must be > 0"):
            find_model_gaits(load_walker(name), slope=-0.01)


def test_cli_lists_the_gaits_stable_first() -> None:
    r = _cli("gait", "--model", "kneed", "--param", "R=0.5", "--slope", "4deg", "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["stable"] is True
    assert d["gaits"][0]["stable"] is True
    assert any(not g["stable"] for g in d["gaits"][1:])
    # the listed first gait is the one shown; its collision loss is the step's total
    assert d["gaits"][0]["period"] == d["period"]
    assert d["gaits"][0]["collision_loss"] == pytest.approx(
        sum(i["T_c"] for i in d["impacts"]), abs=1e-12)
    text = _cli("gait", "--model", "kneed", "--param", "R=0.5", "--slope", "4deg")
    assert text.returncode == 0, text.stderr
    assert "period-one gaits found (the first, the most attracting stable one" in text.stdout


def test_model_compass_lists_the_gaits_of_the_compass_shorthand() -> None:
    """QA sweep 9: ``gait --model compass --param R=0.2`` listed 1 gait (the search stopped at
    the first stable one) where ``gait --radius 0.2`` lists 2; the same walker, one list."""

    outs = []
    for argv in (["--model", "compass", "--param", "R=0.2"], ["--radius", "0.2"]):
        r = _cli("gait", *argv, "--slope", "3deg", "--json")
        assert r.returncode == 0, r.stderr
        outs.append([list(g["fixed_point"].values()) for g in json.loads(r.stdout)["gaits"]])
    model, shorthand = outs
    assert len(shorthand) == 2 and len(model) == len(shorthand)
    np.testing.assert_allclose(model, shorthand, atol=1e-9)


def test_cli_says_when_no_stable_gait_was_found() -> None:
    """At 2 deg the kneed walker's stable family has ended (near 2.16 deg); the one gait found
    is unstable, and the command says that no stable gait was found."""
    r = _cli("gait", "--model", "kneed", "--slope", "2deg", "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["stable"] is False
    assert all(not g["stable"] for g in d["gaits"])
    assert "no stable period-one gait found" in r.stderr
    # 2 deg is not the walker file's reference slope: the reference gait was followed too
    assert "nor by following the walker file's own parameters' stable gait at 3 deg" in r.stderr


def test_cli_note_claims_no_stable_reference_gait_that_does_not_exist() -> None:
    """QA sweep 10: ``gait --model torso`` (the file's own parameters at 3 deg, where the passive
    torso walker has no stable gait) said it had followed the file's gait at 3 deg, "where it
    has a stable one"."""
    r = _cli("gait", "--model", "torso", "--slope", "3deg", "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert all(not g["stable"] for g in d["gaits"])
    assert "no stable period-one gait found (not by the automatic search)" in r.stderr
    assert "stable one" not in r.stderr and "following" not in r.stderr


def test_cli_level_ground_message_for_walk_and_basin(tmp_path) -> None:
    for args in (("walk", "--out", str(tmp_path / "w.gif")),
                 ("basin", "--out", str(tmp_path / "b"))):
        r = _cli(*args, "--model", "kneed", "--slope", "0deg")
        assert r.returncode == 2
        assert "slope must be > 0" in r.stderr
        assert "Jacobian" not in r.stderr


def test_failure_message_says_what_was_searched() -> None:
    with pytest.raises(GaitNotFoundError, match=r"none of the 5 most nearly periodic of 120 "
                                                 r"automatic starts .*3 deg continue"):
        find_model_gait(load_walker("compass", R=0.9), slope=float(np.deg2rad(3.0)))


@pytest.mark.slow
def test_scipy_backend_finds_the_same_stable_gait(gaits: tuple,
                                                  kneed_r05: PhasedWalker) -> None:
    ref = find_model_gaits(kneed_r05, slope=SLOPE, backend="scipy")
    assert ref[0].stable
    np.testing.assert_allclose(ref[0].fixed_point, gaits[0].fixed_point, atol=1e-8)
    assert ref[0].period == pytest.approx(gaits[0].period, abs=1e-8)
