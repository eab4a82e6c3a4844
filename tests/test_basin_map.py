"""Basin of attraction and stable-gait map (compiled ensemble), and their commands."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from heelstrike.analysis.basin import OUTCOMES, basin_of_attraction
from heelstrike.analysis.gait_map import gait_map, newton_gait
from heelstrike.cli import main
from heelstrike.dynamics.hybrid import WalkStatus, simulate
from heelstrike.models.compass import CompassGait
from heelstrike.outputs import write_basin

SLOPE3 = np.deg2rad(3.0)
Z3 = np.array([-0.27102868, 1.09238359, -0.71500964])
CONVERGED = WalkStatus.CONVERGED.code
#: The outcomes only a basin gives (a walk completed or was not started).
BASIN_ONLY = {WalkStatus.CONVERGED, WalkStatus.KEEPS_WALKING, WalkStatus.INADMISSIBLE_START}


def _sinks(walker, z, dt=1e-6):
    """Whether the trailing foot of section point ``z`` is on the ground and moving into it,
    from its clearance along the state's velocity (a finite difference, no Jacobian)."""
    q, qd = walker.section_to_state(z)
    on_ground = abs(float(walker.foot_clearance(q, "left"))) < 1e-9
    return on_ground and float(walker.foot_clearance(q + dt * qd, "left")) < -1e-9 * dt


@pytest.fixture(scope="module")
def basin():
    return basin_of_attraction(
        CompassGait(), SLOPE3, grid=(31, 29), ranges=((-0.5, -0.05), (0.3, 2.3)),
        steps=40, fixed_point=Z3,
    )


@pytest.mark.slow
def test_basin_dataset_and_classification(basin, tmp_path):
    ds = basin.dataset
    assert ds["outcome"].shape == (31, 29)
    assert ds["q3"].attrs["units"] == "rad" and ds["q3_dot"].attrs["units"] == "rad s-1"
    assert 0.0 < basin.converging_fraction < 0.5
    assert basin.converging_fraction == pytest.approx(float(np.mean(ds["outcome"] == CONVERGED)))
    assert sum(basin.fractions().values()) == pytest.approx(1.0)
    # the grid point nearest the fixed point converges; slow launches fall backward
    assert int(ds["outcome"].sel(q3=Z3[0], q3_dot=Z3[1], method="nearest")) == CONVERGED
    slow = int(ds["outcome"].sel(q3=-0.5, q3_dot=0.4, method="nearest"))
    assert WalkStatus.from_code(slow) == "fell_backward"
    # slower still, the trailing foot starts moving into the ground: not a post-impact state
    slowest = int(ds["outcome"].sel(q3=-0.5, q3_dot=0.3, method="nearest"))
    assert WalkStatus.from_code(slowest) == "inadmissible_start"
    assert _sinks(CompassGait(), np.array([-0.5, 0.3, Z3[2]]))
    png, nc = write_basin(basin, tmp_path)
    assert png.stat().st_size > 10_000
    back = xr.open_dataset(nc)
    np.testing.assert_array_equal(back["outcome"].values, ds["outcome"].values)


@pytest.mark.slow
def test_basin_outcomes_agree_with_reference_simulation(basin):
    """A sample of grid points: the scipy reference reaches the same fate."""
    ds = basin.dataset
    walker = CompassGait()
    rng = np.random.default_rng(0)
    codes = ds["outcome"].values
    picks = []
    for code in np.unique(codes):
        idx = np.argwhere(codes == code)
        picks += [tuple(idx[k]) for k in rng.choice(len(idx), min(2, len(idx)), replace=False)]
    for i, j in picks:
        z = np.array([ds["q3"].values[i], ds["q3_dot"].values[j], Z3[2]])
        q, qd = walker.section_to_state(z)
        name = WalkStatus.from_code(codes[i, j])
        steps = int(ds["steps"].values[i, j])
        assert _sinks(walker, z) == (name == "inadmissible_start")
        if name == "inadmissible_start":
            assert steps == 0
        elif name == "converged":
            res = simulate(walker, q, qd, slope=SLOPE3, steps=steps, rtol=1e-9, atol=1e-9)
            assert res.ok
            zf = walker.state_to_section(res.final_q, res.final_q_dot)
            assert np.linalg.norm(zf - Z3) < 1e-3
        else:
            res = simulate(walker, q, qd, slope=SLOPE3, steps=steps + 1, rtol=1e-9, atol=1e-9)
            assert res.status.value == name
            assert res.n_steps == steps


@pytest.mark.slow
def test_gait_map_period_doubling_of_point_feet_near_4_4_deg():
    slopes = np.deg2rad([3.0, 4.0, 5.0])
    gm = gait_map(CompassGait(), [0.0, 0.3], slopes)
    ds = gm.dataset
    np.testing.assert_allclose(ds["fixed_point"].sel(foot_radius=0.0).values[0], Z3, atol=1e-7)
    assert ds["stable"].sel(foot_radius=0.0).values.tolist() == [True, True, False]
    pd = gm.period_doubling_slope
    assert np.degrees(pd[0]) == pytest.approx(4.40, abs=0.03)
    assert np.isnan(pd[1])  # R = 0.3 m stays stable up to 5 deg
    assert bool(ds["stable"].sel(foot_radius=0.3).all())
    # the multipliers' sign change brackets the refined slope
    g = newton_gait(CompassGait(), float(pd[0]) + 0.002, Z3)
    assert g.smallest_real < -1.0
    assert ds["period"].sel(foot_radius=0.0).values[0] == pytest.approx(0.7343, abs=1e-4)


def test_basin_and_map_commands(tmp_path, capsys):
    assert main(["basin", "--grid", "12x10", "--steps", "20", "--out", str(tmp_path / "b"),
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert 0 < d["converging_fraction"] < 1
    assert (tmp_path / "b" / "basin.png").exists() and (tmp_path / "b" / "basin.nc").exists()
    assert main(["map", "--radius", "0:0.1:2", "--slope", "3deg:3.5deg:2",
                 "--out", str(tmp_path / "m"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["stable_fraction"] == 1.0 and d["period_doubling_slope"] == [None, None]
    assert (tmp_path / "m" / "gait_map.png").exists()
    assert main(["basin", "--grid", "0x3"]) == 2
    assert "invalid grid" in capsys.readouterr().err
    assert main(["map", "--slope", "3deg:1deg"]) == 2


def test_gait_map_figure_axes_stay_on_the_computed_grid():
    # The cells are centred on the grid points; their outer halves must not put a negative
    # foot radius (or uncomputed slopes) on the axes: R >= 0 and the map spans 0-0.3 m, 2-4 deg.
    from heelstrike.analysis.gait_map import GaitMap
    from heelstrike.plots.gait import gait_map_figure

    radii, slopes = np.array([0.0, 0.15, 0.3]), np.deg2rad([2.0, 3.0, 4.0])
    rho = np.array([[0.6, 0.7, 1.2], [0.55, 0.6, 0.9], [0.5, 0.55, 0.6]])
    ds = xr.Dataset(
        {"spectral_radius": (("foot_radius", "slope"), rho),
         "period_doubling_slope": ("foot_radius", np.array([np.deg2rad(3.6), np.nan, np.nan]))},
        coords={"foot_radius": radii, "slope": slopes},
    )
    ax = gait_map_figure(GaitMap(dataset=ds)).axes[0]
    r0, r1 = ax.get_ylim()
    s0, s1 = ax.get_xlim()
    assert r0 >= 0.0 and r1 <= 0.3 + 1e-12
    assert s0 >= 2.0 - 1e-9 and s1 <= 4.0 + 1e-9


def test_gait_map_figure_draws_no_stability_line_along_the_no_gait_region():
    # QA sweep 13: NaN cells (no gait) stood in as 10 for the contour, so a black "spectral
    # radius 1" line ran along the grey region's edge where every gait is stable
    from heelstrike.analysis.gait_map import GaitMap
    from heelstrike.plots.gait import gait_map_figure

    radii, slopes = np.array([0.0, 0.3, 0.6, 0.9]), np.deg2rad([1.0, 2.0, 3.0, 4.0])
    rho = np.array([[0.6, 0.7, 0.8, 1.2], [0.55, 0.6, 0.7, 0.9],
                    [0.5, 0.55, 0.6, 0.65], [np.nan] * 4])
    ds = xr.Dataset(
        {"spectral_radius": (("foot_radius", "slope"), rho),
         "period_doubling_slope": ("foot_radius", np.full(4, np.nan))},
        coords={"foot_radius": radii, "slope": slopes},
    )
    fig = gait_map_figure(GaitMap(dataset=ds))
    ax = fig.axes[0]
    lines = [seg for c in ax.collections if hasattr(c, "allsegs") for seg in c.allsegs[0]]
    points = np.concatenate(lines)
    # the one boundary is between 0.8 and 1.2 (R = 0, 3-4 deg) and between 0.7 and 0.9 (R =
    # 0.3): it never reaches R = 0.6, the last row with gaits, all stable
    assert points[:, 1].max() < 0.6 - 1e-9
    assert "black line: spectral radius 1" in ax.get_title()
    rho_stable = np.where(np.isfinite(rho), np.minimum(rho, 0.95), np.nan)
    rho_stable[0, 0] = 1.5  # nothing crosses 1 but one corner cell
    ds2 = ds.assign(spectral_radius=(("foot_radius", "slope"), rho_stable))
    assert "black line" in gait_map_figure(GaitMap(dataset=ds2)).axes[0].get_title()
    ds3 = ds.assign(spectral_radius=(("foot_radius", "slope"), np.where(
        np.isfinite(rho), np.minimum(rho, 0.95), np.nan)))
    title = gait_map_figure(GaitMap(dataset=ds3)).axes[0].get_title()
    assert "black line" not in title and "grey: no gait found" in title


def test_every_walk_status_has_its_own_basin_outcome() -> None:
    # QA sweep 6 (layout audit): slipped, no_consistent_assignment and no_leg_swap were
    # counted as integration_failed, and the colours matched the outcomes by position.
    # Issue #32: the basin's outcomes are WalkStatus members and the dataset stores their
    # codes, so a code means the same in a basin as in every walk result.
    from heelstrike.analysis import basin as basin_module
    from heelstrike.plots import gait as gait_plots

    assert all(isinstance(s, WalkStatus) for s in OUTCOMES)
    assert set(OUTCOMES) == set(WalkStatus) - {WalkStatus.COMPLETED}
    assert len(set(OUTCOMES)) == len(OUTCOMES)
    # the report order (JSON "fractions", the text lines) is the one it always was
    assert [s.value for s in OUTCOMES] == [
        "converged", "keeps_walking", "fell_forward", "fell_backward", "trailing_foot_stays",
        "lost_contact", "no_heel_strike", "integration_failed", "slipped",
        "no_consistent_assignment", "no_leg_swap", "inadmissible_start", "off_profile"]
    ended = [s for s in OUTCOMES if s not in BASIN_ONLY]  # what a walk itself can end with
    codes = np.array([s.code for s in ended] + [WalkStatus.COMPLETED.code] * 2
                     + [WalkStatus.INADMISSIBLE_START.code])
    dist = np.array([0.0] * len(ended) + [1e-5, 1.0, 0.0])
    out = basin_module._classify(codes, dist, 1e-3)
    assert [WalkStatus.from_code(k) for k in out] == [
        *ended, WalkStatus.CONVERGED, WalkStatus.KEEPS_WALKING, WalkStatus.INADMISSIBLE_START]
    assert WalkStatus.COMPLETED.code not in out  # a basin never reports a bare completion
    assert set(gait_plots._COLOURS) == set(OUTCOMES)
    assert all(len(s.message) > 10 for s in OUTCOMES)


def test_basin_dataset_flags_are_walk_status_codes() -> None:
    """The dataset's CF flags name the members whose codes it stores (3x2 grid, scipy, no
    fixed-point search), and fractions() counts each member's code."""
    b = basin_of_attraction(CompassGait(), SLOPE3, grid=(3, 2), steps=3, fixed_point=Z3,
                            ranges=((-0.5, Z3[0]), (0.3, Z3[1])), backend="scipy")
    attrs = b.dataset["outcome"].attrs
    names = attrs["flag_meanings"].split()
    assert [WalkStatus.from_code(c) for c in attrs["flag_values"]] == names
    assert names == [s.value for s in OUTCOMES]
    codes = b.dataset["outcome"].values
    assert set(codes.ravel().tolist()) <= {s.code for s in OUTCOMES}
    assert WalkStatus.from_code(codes[-1, -1]) is WalkStatus.CONVERGED  # z* itself
    assert WalkStatus.from_code(codes[0, 0]) is WalkStatus.INADMISSIBLE_START  # q3_dot = 0.3
    fr = b.fractions()
    assert list(fr) == names
    for s in OUTCOMES:
        assert fr[s] == pytest.approx(float(np.mean(codes == s.code)))
    assert b.converging_fraction == fr["converged"] > 0


@pytest.mark.parametrize("model", ["compass", "kneed", "torso"])
def test_trailing_foot_presses_is_the_sign_of_the_clearance_rate(model):
    """``trailing_foot_presses`` (batched) agrees point by point with a finite difference of the
    trailing foot's clearance on random post-impact section points, and never holds at a
    gait's own post-heel-strike state (the heel strike lifted that foot)."""
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.compiled_phased import section_states
    from heelstrike.dynamics.phased import PhasedWalker
    from heelstrike.models.builder import load_walker

    walker = PhasedWalker.from_built(load_walker(model))
    z = np.asarray(find_model_gait(walker, slope=SLOPE3).fixed_point)
    q, qd = walker.section_to_state(z)
    assert not walker.trailing_foot_presses(q, qd)
    assert float(walker.foot_clearance(q + 1e-6 * qd, "left")) > 0.0
    rng = np.random.default_rng(1)
    Z = z + rng.uniform(-1.0, 1.0, (40, z.size)) * np.where(np.arange(z.size) < 1, 0.2, 1.5)
    Q, QD = section_states(walker, Z)
    flags = walker.trailing_foot_presses(Q, QD)
    assert flags.shape == (40,) and 0 < flags.sum() < 40  # both kinds are sampled
    for k in range(40):
        assert flags[k] == _sinks(walker, Z[k])


def test_default_window_holds_the_fixed_point_of_large_feet(tmp_path, capsys):
    """R = 0.5 m at 3 deg walks with q3 = -0.547 rad, outside the old fixed default window
    (-0.5..-0.05 rad): its basin figure drew the fixed point off the image. The default window
    is widened to keep the fixed point 0.1 rad and 0.3 rad/s inside; R = 0's is unchanged, and
    an axis the user gives is used as given."""
    from heelstrike.analysis.basin import DEFAULT_RANGES, default_ranges

    assert default_ranges(Z3) == DEFAULT_RANGES
    b = basin_of_attraction(CompassGait(foot_radius=0.5), SLOPE3, grid=(6, 4), steps=3)
    z = b.fixed_point
    q3, rate = b.dataset["q3"].values, b.dataset["q3_dot"].values
    assert z[0] < DEFAULT_RANGES[0][0]  # the hard case: outside the old window
    assert q3[0] == pytest.approx(z[0] - 0.1) and q3[-1] == DEFAULT_RANGES[0][1]
    assert (rate[0], rate[-1]) == DEFAULT_RANGES[1]
    assert q3[0] < z[0] < q3[-1] and rate[0] < z[1] < rate[-1]
    mine = basin_of_attraction(CompassGait(foot_radius=0.5), SLOPE3, grid=(3, 3), steps=3,
                               ranges=(None, (1.0, 2.0)), fixed_point=z)
    assert mine.dataset["q3"].values[0] == pytest.approx(z[0] - 0.1)
    assert tuple(mine.dataset["q3_dot"].values[[0, -1]]) == (1.0, 2.0)
    with pytest.raises(ValueError, match="increasing"):
        basin_of_attraction(CompassGait(), SLOPE3, grid=(2, 2), ranges=((0.1, -0.1), None),
                            fixed_point=Z3)
    out = tmp_path / "b"
    assert main(["basin", "--radius", "0.5", "--grid", "6x4", "--steps", "3", "--out",
                 str(out), "--json"]) == 0
    capsys.readouterr()
    back = xr.open_dataset(out / "basin.nc")
    assert float(back["q3"][0]) == pytest.approx(z[0] - 0.1, abs=1e-6)


def test_the_map_follows_the_fast_changing_gaits_near_the_wheel(capsys, tmp_path) -> None:
    # QA sweep 13: at R = 0.9 m the gait's impact angle goes from 15 to 41 deg between 0.01 and
    # 0.107 deg of slope; the continuation's first sub-step jumped farther than it accepts, and
    # the smallest sub-step (1/32 of 0.25 deg) ended the branch: "no gait" where a stable one
    # exists. Each cell is checked against the automatic gait search at that slope alone.
    from heelstrike.analysis.limit_cycle import GaitNotFoundError, find_limit_cycle

    assert main(["map", "--radius", "0.9:0.95:2", "--slope", "0.01deg:0.3deg:4", "--json",
                 "--out", str(tmp_path)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["gait_found"][0][:2] == [True, True]
    with xr.open_dataset(d["data"]) as ds:
        rho = ds["spectral_radius"].values
    slopes = np.deg2rad(np.linspace(0.01, 0.3, 4))
    for i, radius in enumerate((0.9, 0.95)):
        for j, slope in enumerate(slopes):
            try:
                alone = find_limit_cycle(CompassGait(foot_radius=radius), slope=float(slope),
                                         method="compiled")
            except GaitNotFoundError:
                assert not d["gait_found"][i][j], (radius, slope)
                continue
            assert d["gait_found"][i][j], (radius, slope)
            assert rho[i, j] == pytest.approx(alone.spectral_radius, abs=1e-6)


def test_a_single_value_is_a_range_of_one_point(capsys, tmp_path) -> None:
    # QA sweep 13: map --radius 0.3 was refused; 0.3:0.3:1 had to be spelled out
    from heelstrike.cli import parse_range

    assert parse_range("0.3") == (0.3, 0.3, 1)
    assert main(["map", "--radius", "0.3", "--slope", "2deg:4deg:3", "--out", str(tmp_path),
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["foot_radius"] == [0.3] and d["gait_found"] == [[True, True, True]]
    # one row of the grid is drawn as points coloured by their spectral radius (a 2-D colour
    # array left them uncoloured, with a warning)
    from heelstrike.analysis.gait_map import GaitMap
    from heelstrike.plots.gait import gait_map_figure

    with xr.open_dataset(d["data"]) as ds:
        ds = ds.load()
    ax = gait_map_figure(GaitMap(dataset=ds)).axes[0]
    coloured = [c for c in ax.collections if c.get_array() is not None]
    assert len(coloured) == 1
    np.testing.assert_allclose(coloured[0].get_array(), ds["spectral_radius"].values.ravel())
    assert main(["map", "--radius", "abc", "--out", str(tmp_path)]) == 2
    assert "invalid range 'abc'" in capsys.readouterr().err
    # one slope too: the gait there, as 'gait' finds it alone
    assert main(["map", "--radius", "0:0.3:2", "--slope", "2deg", "--out", str(tmp_path),
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["slope"] == [pytest.approx(np.deg2rad(2.0))] and d["gait_found"] == [[True], [True]]
    assert main(["map", "--slope", "0", "--out", str(tmp_path)]) == 2
    assert "--slope needs 0 < START < STOP, or one slope > 0" in capsys.readouterr().err
