"""Reliability of the gait searches (issue 11, items 7, 8 and 12).

- Item 7: the automatic search finds every period-one gait it can, lists them, and prefers the
  most attracting stable one; ``gait`` finds what ``map`` finds; ``map`` marks radii without a
  gait instead of aborting; the compiled map agrees with scipy.
- Item 8: ``study cost`` follows the cheapest periodic gait at every design.
- Item 12: searches that cannot succeed fail at once with the reason; searches are bounded and
  report progress on stderr only.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.gait_map import _anchors
from heelstrike.analysis.limit_cycle import (
    GaitNotFoundError,
    find_limit_cycle,
    find_limit_cycles,
)
from heelstrike.cli import main
from heelstrike.models.compass import CompassGait

Capture = pytest.CaptureFixture[str]

# -- item 7: all gaits, the stable one preferred ------------------------------------------------


@pytest.mark.parametrize("slope_deg", [3.7, 4.0, 4.3])
def test_point_foot_search_prefers_stable_long_step_gait(slope_deg: float) -> None:
    """Goswami et al. (1998): on 3.7-4.3 deg the point-foot compass gait has a stable long-step
    gait (|mu| 0.56-0.90) and an unstable short-step one. The automatic search used to return
    the short one (and failed at 4.0 deg)."""
    slope = np.deg2rad(slope_deg)
    walker = CompassGait(foot_radius=0.0)
    gaits = find_limit_cycles(walker, slope=slope, method="compiled")
    chosen = find_limit_cycle(walker, slope=slope, method="compiled")
    np.testing.assert_allclose(chosen.fixed_point, gaits[0].fixed_point, atol=1e-8)
    assert chosen.stable
    assert 0.5 < chosen.spectral_radius < 0.95
    short = [g for g in gaits if not g.stable and g.step_length < chosen.step_length]
    assert short, "the unstable short-step gait is listed too"
    assert all(g.spectral_radius > 1.0 for g in short)
    # the gaits are distinct fixed points of the map
    for i, g in enumerate(gaits):
        assert g.residual < 1e-9
        for h in gaits[:i]:
            assert np.linalg.norm(g.fixed_point - h.fixed_point) > 1e-6
        # passive gait: gravity pays exactly for the heel-strike loss
        assert g.collision_loss == pytest.approx(g.potential_energy_released, rel=1e-6)
    # stable gaits first, the most attracting first
    radii = [g.spectral_radius for g in gaits if g.stable]
    assert radii == sorted(radii)


def test_compiled_and_scipy_gaits_agree_to_1e8() -> None:
    slope = np.deg2rad(4.0)
    walker = CompassGait(foot_radius=0.2)
    fast = find_limit_cycle(walker, slope=slope, method="compiled")
    ref = find_limit_cycle(walker, slope=slope, guess=fast.fixed_point, method="scipy")
    np.testing.assert_allclose(fast.fixed_point, ref.fixed_point, atol=1e-8, rtol=0)
    assert fast.period == pytest.approx(ref.period, abs=1e-8)
    np.testing.assert_allclose(
        np.abs(fast.multipliers), np.abs(ref.multipliers), atol=1e-5
    )


def test_gait_json_lists_all_gaits_and_picks_the_stable_one(capsys: Capture) -> None:
    assert main(["gait", "--slope", "4deg", "--json"]) == 0
    captured = capsys.readouterr()
    lines = captured.out.strip().splitlines()
    assert len(lines) == 1
    d = json.loads(lines[0])
    assert len(d["gaits"]) >= 2
    for g in d["gaits"]:
        assert {"q", "q_dot", "period", "step_length", "multipliers", "stable"} <= g.keys()
        assert len(g["q"]) == 4 and len(g["q_dot"]) == 4
        assert all(m >= 0 for m in g["multipliers"])
        assert g["stable"] == (max(g["multipliers"]) < 1.0)
    assert d["stable"] is True
    assert d["period"] == pytest.approx(d["gaits"][0]["period"])
    assert any(not g["stable"] for g in d["gaits"])


def test_gait_finds_the_round_foot_gait_that_map_finds(capsys: Capture) -> None:
    """``gait --radius 0.7 --slope 3deg`` said "no gait" where ``map`` (continuation in the
    radius from the point foot) finds one."""
    slope = np.deg2rad(3.0)
    ((s_map, z_map),) = _anchors(CompassGait(), np.array([0.7]), np.array([slope]), None,
                                 1e-11, 1e-11)
    assert s_map == slope
    assert np.all(np.isfinite(z_map))
    assert main(["gait", "--radius", "0.7", "--slope", "3deg", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    zs = [np.array(list(g["fixed_point"].values())) for g in d["gaits"]]
    assert min(np.linalg.norm(z - z_map) for z in zs) < 1e-6


def test_level_ground_passive_gait_fails_at_once(capsys: Capture) -> None:
    """``gait --slope 0`` searched for 45 s; a passive walker cannot walk on level ground."""
    with pytest.raises(GaitNotFoundError, match="slope must be > 0"):
        find_limit_cycles(CompassGait(), slope=0.0)
    for slope in ("0", "-2deg"):
        assert main(["gait", f"--slope={slope}", "--json"]) == 2
        captured = capsys.readouterr()
        assert captured.out == ""
        err = captured.err.strip().splitlines()
        assert len(err) == 1 and "slope > 0" in err[0]


@pytest.mark.slow
def test_map_marks_radii_without_a_gait_instead_of_aborting(
    tmp_path: Path, capsys: Capture
) -> None:
    argv = ["map", "--radius", "0.8:1:3", "--slope", "2deg:4deg:3",
            "--out", str(tmp_path / "m"), "--json"]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    found = np.array(d["gait_found"])
    assert found.shape == (3, 3)
    import xarray as xr

    ds = xr.open_dataset(d["data"])
    sr = ds["spectral_radius"].values
    np.testing.assert_array_equal(np.isfinite(sr), found)
    assert d["gait_found_fraction"] == pytest.approx(found.mean())


# -- item 12: reject what cannot succeed, bound every search ------------------------------------


def test_max_walking_speed_is_the_froude_limit() -> None:
    from heelstrike.analysis.powered import max_walking_speed

    g, l = 9.81, 1.0
    assert max_walking_speed(CompassGait()) == pytest.approx(np.sqrt(g * l))
    assert max_walking_speed(CompassGait(foot_radius=0.5)) == pytest.approx(
        l * np.sqrt(g / (l - 0.5))
    )
    assert max_walking_speed(CompassGait(foot_radius=1.0)) == np.inf  # a wheel rolls at any speed
    assert max_walking_speed(CompassGait(gravity=1.62)) < max_walking_speed(CompassGait())


def test_unreachable_speed_fails_at_once_with_the_range(capsys: Capture) -> None:
    """``powered --speed 100`` searched for 68 s before failing."""
    from heelstrike.analysis.powered import PoweredGaitNotFoundError, find_powered_gait

    with pytest.raises(PoweredGaitNotFoundError, match=r"reachable range 0 < speed < 3.13"):
        # time_limit=0 would fail on the first simulated step: the check comes first
        find_powered_gait(CompassGait(), speed=100.0, time_limit=0.0)
    assert main(["powered", "--speed", "100", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and "reachable range" in err[0]
    # the target is said with its unit (QA sweep 11: "with speed 1.3 (the walker's ...)")
    assert "with speed 100 m/s at R = 0 m" in err[0]


def test_powered_search_is_bounded_in_time() -> None:
    from heelstrike.analysis.powered import SearchLimitError, find_powered_gait

    with pytest.raises(SearchLimitError, match="time limit"):
        find_powered_gait(CompassGait(), actuation="hip-pd", speed=0.5, time_limit=0.0)
    with pytest.raises(SearchLimitError, match="budget"):
        find_powered_gait(CompassGait(), actuation="hip-pd", speed=0.5, max_evaluations=3)


def test_gait_search_is_bounded_in_time() -> None:
    """With no time left the search fails cleanly, saying why; it never runs on."""
    with pytest.raises(GaitNotFoundError, match="time limit"):
        find_limit_cycles(CompassGait(), slope=np.deg2rad(3.0), method="compiled",
                          time_limit=0.0)


def _clock_jumps_after(monkeypatch: pytest.MonkeyPatch, module: object, name: str) -> None:
    """After the first call of ``module.name``, ``time.monotonic`` runs 10^6 s ahead: every
    deadline of the search has passed from then on."""
    import time

    real, shift = time.monotonic, [0.0]
    monkeypatch.setattr(time, "monotonic", lambda: real() + shift[0])
    inner = getattr(module, name)

    def wrapped(*args: object, **kwargs: object) -> object:
        out = inner(*args, **kwargs)
        shift[0] = 1e6
        return out

    monkeypatch.setattr(module, name, wrapped)


def test_a_search_cut_by_its_time_limit_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    """The gaits found before the time limit are returned with a warning: the search did not
    look everywhere (it returned a subset without a word). 3 deg, point foot: Garcia's long
    and short gaits; scipy Newton from each compiled start, cut after the first."""
    import heelstrike.analysis.limit_cycle as lc
    from heelstrike.analysis.newton import SearchTimeLimitWarning

    walker, slope = CompassGait(foot_radius=0.0), np.deg2rad(3.0)
    assert len(find_limit_cycles(walker, slope=slope, method="compiled")) == 2
    _clock_jumps_after(monkeypatch, lc, "_newton")
    with pytest.warns(SearchTimeLimitWarning, match="time limit of 300 s: the 1 gait found"):
        gaits = find_limit_cycles(walker, slope=slope, method="scipy")
    assert len(gaits) == 1 and gaits[0].residual < 1e-9


def test_gait_notes_a_search_cut_by_its_time_limit(
    monkeypatch: pytest.MonkeyPatch, capsys: Capture
) -> None:
    """On the command line the warning is a note on stderr (no Python warning line), and the
    gaits found are printed as usual."""
    import heelstrike.analysis.limit_cycle as lc

    _clock_jumps_after(monkeypatch, lc, "_compiled_seeds")
    assert main(["gait", "--radius", "0", "--slope", "3deg", "--json"]) == 0
    captured = capsys.readouterr()
    assert ("heelstrike: note: the gait search reached its time limit of 300 s: the 2 gaits "
            "found by then are returned, and others may exist") in captured.err
    assert "Warning" not in captured.err
    assert len(json.loads(captured.out)["gaits"]) == 2


# -- item 8: the cost study keeps the cheapest gait ---------------------------------------------


@pytest.mark.slow
def test_cost_study_keeps_the_cheapest_gait_near_the_wheel(tmp_path: Path, capsys: Capture) -> None:
    """``study cost`` showed McGeer's wheel (R = l) as the most expensive design: continuation
    (and the seed search) followed a push-off branch needing 1.45 J per step at L = 0.4 m where
    a 0.15 J gait exists (Newton from an independent guess, below)."""
    import xarray as xr

    from heelstrike.analysis.powered import find_powered_gait

    wheel = CompassGait(foot_radius=1.0)
    cheap = find_powered_gait(wheel, actuation="pushoff", step_length=0.4,
                              guess=[-0.2, 0.6, -0.3, 0.3], fallback=False)
    assert cheap.actuator_work == pytest.approx(cheap.collision_loss, rel=1e-5)
    out = tmp_path / "study"
    assert main(["study", "cost", "--radius", "0.75:1:2", "--step-length", "0.4:0.4:1",
                 "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert "cheapest" in stdout
    ds = xr.open_dataset(out / "cost_study.nc")
    work = ds["actuator_work"].sel(actuation="pushoff").values[:, 0]
    assert np.all(np.isfinite(work))
    assert work[1] <= cheap.actuator_work * (1 + 1e-6)
    assert "cheapest" in ds.attrs["branch_note"]
    assert set(np.unique(ds["branch"].values[np.isfinite(ds["branch"].values)])) <= {0.0, 1.0}
    assert int(ds["gaits_found"].sel(actuation="pushoff").values[1, 0]) >= 1


def test_api_slope_in_degrees_by_mistake_fails_at_once() -> None:
    # QA sweep 4: find_limit_cycle(slope=3) (3 rad = 172 deg) searched 864 seeds and said only
    # "no period-one gait found"; slopes are radians and the error now says so
    for slope in (3.0, -2.0, np.pi / 2):
        with pytest.raises(GaitNotFoundError, match=r"no walkable incline \(slopes are in "
                                                    r"radians"):
            find_limit_cycles(CompassGait(), slope=slope)
