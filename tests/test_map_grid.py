"""The gait maps follow one branch whatever the output grid (QA sweep P1-1, P1-2).

The slope continuation takes sub-steps with step control between the grid's slopes, so a coarse
grid and a fine grid over the same range give the same gaits at their common points, and a
period doubling between two coarse grid slopes is found. The kneed walker's map refuses radii
its constraint ``R <= a1 + b1`` rejects, its default radius range stops there, and its large
feet (R = 0.4, 0.5 m), whose stable gaits do not reach down to the 3 deg anchor slope, get
their gaits.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from heelstrike.analysis.gait_map import GaitMap, gait_map, model_gait_map, newton_gait
from heelstrike.cli import main
from heelstrike.dynamics.compiled_phased import simulate_phased_compiled
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker
from heelstrike.models import CompassGait

COARSE = np.radians(np.linspace(1.0, 6.0, 3))  # 1, 3.5, 6 deg
FINE = np.radians(np.linspace(1.0, 6.0, 11))  # every 0.5 deg: contains the coarse slopes
COMMON = [0, 5, 10]  # indices of the coarse slopes in FINE


def _assert_same_gaits(coarse: GaitMap, fine: GaitMap, common: list[int]) -> None:
    """Same gait found, same fixed point (1e-8) and same stability at every common point."""
    c, f = coarse.dataset, fine.dataset
    fc = f.isel(slope=common)
    np.testing.assert_allclose(fc["slope"].values, c["slope"].values, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(c["gait_found"].values, fc["gait_found"].values)
    np.testing.assert_allclose(c["fixed_point"].values, fc["fixed_point"].values, rtol=0,
                               atol=1e-8, equal_nan=True)
    np.testing.assert_array_equal(c["stable"].values, fc["stable"].values)
    np.testing.assert_allclose(c["spectral_radius"].values, fc["spectral_radius"].values,
                               rtol=0, atol=1e-5, equal_nan=True)


def test_compass_map_coarse_and_fine_grids_agree_and_find_period_doubling() -> None:
    """The compass path: R = 0 has a gait at 6 deg (unstable, past the period doubling at
    4.39 deg) and the period doubling is found between the coarse slopes 3.5 and 6 deg."""
    radii = [0.0, 0.3, 0.6]
    coarse = gait_map(CompassGait(), radii, COARSE)
    fine = gait_map(CompassGait(), radii, FINE)
    _assert_same_gaits(coarse, fine, COMMON)
    assert bool(coarse.dataset["gait_found"].all())
    assert coarse.dataset["stable"].values.tolist() == [[True, True, False], [True] * 3,
                                                        [True] * 3]
    pd_c, pd_f = coarse.period_doubling_slope, fine.period_doubling_slope
    assert np.degrees(pd_c[0]) == pytest.approx(4.39, abs=0.01)
    assert np.degrees(pd_c[0]) == pytest.approx(np.degrees(pd_f[0]), abs=1e-5)
    assert np.isnan(pd_c[1:]).all() and np.isnan(pd_f[1:]).all()
    # the refined slope brackets the sign change of the smallest real multiplier
    z = coarse.dataset["fixed_point"].values[0, 1]
    below = newton_gait(CompassGait(), float(pd_c[0]) - 1e-4, z)
    above = newton_gait(CompassGait(), float(pd_c[0]) + 1e-4, below.z)
    assert below.smallest_real > -1.0 > above.smallest_real


@pytest.mark.slow
def test_model_compass_map_coarse_and_fine_grids_agree() -> None:
    """``--model compass``: R = 0.6 stays on its stable branch on the coarse grid (it jumped to
    an unstable family, q3 0.27/0.68/0.88 rad), as on the fine grid and the compass path."""
    walker = load_phased_walker("compass")
    radii = [0.0, 0.6]
    coarse = model_gait_map(walker, "R", radii, COARSE)
    fine = model_gait_map(walker, "R", radii, FINE)
    _assert_same_gaits(coarse, fine, COMMON)
    ds = coarse.dataset
    assert bool(ds["gait_found"].all())
    assert bool(ds["stable"].values[1].all())  # R = 0.6: stable at 1, 3.5 and 6 deg
    pd = np.degrees(float(ds["period_doubling_slope"].values[0]))
    assert pd == pytest.approx(4.39, abs=0.01)
    # the same gaits as the compass path (its own compiled kernel)
    ref = gait_map(CompassGait(), radii, COARSE).dataset
    np.testing.assert_allclose(np.abs(ds["fixed_point"].values[..., 0]),
                               np.abs(ref["fixed_point"].values[..., 0]), rtol=0, atol=1e-6)
    np.testing.assert_array_equal(ds["stable"].values, ref["stable"].values)


@pytest.mark.slow
def test_kneed_map_grids_agree_and_large_feet_have_their_gaits() -> None:
    """Kneed walker, R = 0.3-0.5 m over 3-5 deg: a 1 deg grid and a 0.25 deg grid agree at
    their common slopes; R = 0.4 and 0.5 m have gaits at 4 and 5 deg (they had none: their
    branches do not reach the anchor slope, 3 deg), stable there, and every point is a fixed
    point of the walker's step map."""
    kneed = load_phased_walker("kneed")
    radii = [0.3, 0.4, 0.5]
    coarse = model_gait_map(kneed, "R", radii, np.radians([3.0, 4.0, 5.0]))
    fine = model_gait_map(kneed, "R", radii, np.radians(np.linspace(3.0, 5.0, 9)))
    _assert_same_gaits(coarse, fine, [0, 4, 8])
    ds = coarse.dataset
    assert ds["gait_found"].values[:, 1:].all()
    assert ds["stable"].values[:, 1:].all()
    for i, R in enumerate(radii):
        w = kneed.replace(R=R)
        for j, s in enumerate(ds["slope"].values):
            if not ds["gait_found"].values[i, j]:
                continue
            z = ds["fixed_point"].values[i, j]
            q, qd = w.section_to_state(z)
            one = simulate_phased_compiled(w, q, qd, slope=float(s), steps=1, rtol=1e-11,
                                           atol=1e-11)
            np.testing.assert_allclose(w.state_to_section(one.final_q, one.final_q_dot), z,
                                       rtol=0, atol=1e-8)


def test_model_map_refuses_parameter_values_the_walker_rejects() -> None:
    kneed = load_phased_walker("kneed")
    limit = kneed.parameters["a1"] + kneed.parameters["b1"]
    with pytest.raises(ValueError, match=r"R = 0\.6 is not admitted"):
        model_gait_map(kneed, "R", [0.3, limit + 0.1], np.radians([3.0]))


@pytest.mark.parametrize("argv, option", [
    (["--radius", "0:0.6:3"], "--radius"),
    (["--x", "R:0.2:0.7:2"], "--x"),
])
def test_map_command_refuses_kneed_radii_beyond_its_constraint(
    argv: list[str], option: str, tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["map", "--model", "kneed", *argv, "--out", str(tmp_path / "m")]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert captured.out == ""
    assert len(err) == 1 and err[0].startswith(f"heelstrike: error: {option}: R = ")
    assert "R <= a1 + b1" in err[0] and "largest admitted R is 0.5" in err[0]
    assert not (tmp_path / "m").exists()


class _Captured(Exception):
    pass


def test_map_command_default_kneed_radii_stop_at_the_constraint(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Any
) -> None:
    """The default radius range (0 to 0.6 m, 7 values) ends at the largest radius the kneed
    walker admits, a1 + b1, and every value is admitted."""
    import heelstrike.analysis.gait_map as gm

    seen: dict[str, Any] = {}

    def fake(walker: PhasedWalker, parameter: str, values: Any, slopes: Any,
             **kw: Any) -> GaitMap:
        seen.update(walker=walker, parameter=parameter, values=np.asarray(values))
        raise _Captured

    monkeypatch.setattr(gm, "model_gait_map", fake)
    main(["map", "--model", "kneed", "--out", str(tmp_path / "m")])
    values, walker = seen["values"], seen["walker"]
    assert seen["parameter"] == "R" and values.size == 7 and values[0] == 0.0
    assert values[-1] == pytest.approx(walker.parameters["a1"] + walker.parameters["b1"], abs=1e-9)
    for v in values:
        walker.replace(R=float(v))  # admitted: no ValueError


def test_compass_map_anchors_large_feet_on_shallow_slopes() -> None:
    """R = 0.8 m has no gait at the 3 deg anchor slope (the branch ends near R = 0.73 there) but
    has stable gaits on shallow slopes. The compass map drew its whole row as "no gait"; it now
    anchors such a radius at the fallback slopes (as the described-walker map does), and finds
    the gaits ``map --model compass`` finds, which are fixed points of the scipy step map."""
    from heelstrike.analysis.limit_cycle import PoincareMap
    from heelstrike.models import load_walker

    slopes = np.radians([0.5, 1.0, 1.5, 3.0])
    ds = gait_map(CompassGait(), [0.8], slopes).dataset
    found = ds["gait_found"].values[0]
    assert found[:2].all()
    assert not found[-1]  # none at 3 deg: the large-feet branch ends below it
    ref = model_gait_map(load_walker("compass"), "R", [0.8], slopes).dataset
    np.testing.assert_array_equal(ref["gait_found"].values[0], found)
    np.testing.assert_allclose(ds["period"].values[0], ref["period"].values[0], rtol=0,
                               atol=1e-9, equal_nan=True)
    for j in np.flatnonzero(found):
        z = ds["fixed_point"].values[0, j]
        pmap = PoincareMap(walker=CompassGait(foot_radius=0.8), slope=float(slopes[j]),
                           rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(pmap(z), z, atol=1e-8)
