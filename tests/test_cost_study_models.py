"""``study cost --model``: the cost study of described walkers (issue 9, item 4).

Physics checked:

- the compass walker described by ``compass.toml`` (compiled phased simulator) gives the compass
  study's gaits (scipy reference, :class:`~heelstrike.models.compass.CompassGait`) at every grid
  point: the same cost of transport and collision loss ``T_c``;
- on the torso walker (push-off plus the posture law of its file) every stored gait is periodic
  on level ground, so its energy book per step closes, ``W_push + W_posture = T_c``, and it meets
  its target (speed ``L_S / T`` or step length ``L_S``);
- a grid point no gait reaches is marked (NaN, ``found = 0``, a failure message), and the
  study carries on.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from heelstrike.analysis.cost_study import cost_study
from heelstrike.cli import main
from heelstrike.models.builder import load_walker

RADII = (0.0, 0.3)
LENGTHS = (0.4,)


def _cli(argv: list[str], out: Path) -> xr.Dataset:
    assert main([*argv, "--out", str(out)]) == 0
    with xr.open_dataset(out / "cost_study.nc") as ds:
        return ds.load()


def test_model_compass_equals_compass_study(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    grid = ["--radius", "0:0.3:2", "--step-length", "0.4:0.4:1"]
    ref = _cli(["study", "cost", *grid], tmp_path / "compass")
    got = _cli(["study", "cost", "--model", "compass", *grid], tmp_path / "model")
    assert "cost_of_transport.png" in capsys.readouterr().out
    assert np.array_equal(ref["radius"].values, got["radius"].values)
    assert int(ref["found"].sum()) == ref["found"].size == int(got["found"].sum())
    for var in ("cost_of_transport", "collision_loss"):
        a, b = ref[var].values, got[var].values
        assert np.all(np.isfinite(a)) and np.all(np.isfinite(b))
        assert np.max(np.abs(a - b)) < 1e-6, var
    # the foot radius matters: the study did not compute one gait twice
    assert abs(float(got["collision_loss"][0, 0, 0] - got["collision_loss"][0, 1, 0])) > 1e-3
    # cost of transport with the walker's own scale (m_total g L)
    m, g = got.attrs["total_mass"], got.attrs["gravity"]
    cot = got["actuator_work"] / (m * g * got["step_length"])
    assert np.allclose(cot.values, got["cost_of_transport"].values, rtol=1e-12)
    assert got.attrs["model"] == "compass"


@pytest.fixture(scope="module")
def torso_study() -> xr.Dataset:
    # 5 m/s is far beyond the torso walker's push-off gaits (they end at a fold, 0.4902 m/s)
    return cost_study((0.0, 0.1), (0.35, 0.4, 5.0), target="speed", model=load_walker("torso"))


def test_torso_energy_book_closes_and_targets_met(torso_study: xr.Dataset) -> None:
    ds = torso_study.isel(speed=slice(0, 2))
    assert int(ds["found"].sum()) == ds["found"].size == 4
    W_push, W_post = ds["push_off_work"].values, ds["torque_work"].values
    T_c = ds["collision_loss"].values
    assert np.all(np.abs(W_push + W_post - T_c) < 1e-8)
    assert np.all(np.abs(W_post) > 1e-3)  # the posture law works: not the push-off's book alone
    assert np.allclose(ds["actuator_work"].values, W_push + W_post, atol=1e-12)
    speed = ds["step_length"].values / ds["period"].values
    assert np.max(np.abs(speed - ds["speed"].values[None, None, :])) < 1e-6
    # the cost of transport uses the torso walker's total mass (legs, hip and torso)
    m, g = ds.attrs["total_mass"], ds.attrs["gravity"]
    assert m == pytest.approx(25.0)
    assert np.allclose(ds["cost_of_transport"].values,
                       ds["actuator_work"].values / (m * g * ds["step_length"].values))


def test_unreachable_point_is_marked_not_fatal(torso_study: xr.Dataset) -> None:
    far = torso_study.sel(speed=5.0)
    assert np.all(far["found"].values == 0)
    assert np.all(np.isnan(far["cost_of_transport"].values))
    assert all("no gait" in str(msg) for msg in far["failure"].values.ravel())
    near = torso_study.sel(speed=0.4)
    assert np.all(near["found"].values == 1)
    assert all(str(msg) == "" for msg in near["failure"].values.ravel())


def test_torso_step_length_grid_meets_targets(tmp_path: Path) -> None:
    # step lengths of the torso walker's push-off gaits near 0.35-0.4 m/s
    ds = _cli(["study", "cost", "--model", "torso", "--radius", "0:0.1:2",
               "--step-length", "0.25:0.28:2"], tmp_path)
    assert int(ds["found"].sum()) == ds["found"].size
    L = ds["step_length"].values
    assert np.max(np.abs(ds["speed"].values * ds["period"].values
                         - L[None, None, :])) < 1e-6
    T_c = ds["collision_loss"].values
    assert np.all(np.abs(ds["push_off_work"].values + ds["torque_work"].values - T_c) < 1e-8)
    assert "eta_paper" not in ds  # the paper's impact-only measure is the compass gait's


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--model", "torso", "--actuation", "hip-energy"],
         "model 'torso' actuates hip, torso"),
        (["--model", "torso", "--param", "R=0.1"], "--param R=... is swept by --radius"),
        (["--model", "torso", "--radius", "0:2:2"], "--radius must lie in [0, 1] m"),
        (["--param", "m=2"], "give --model too"),
    ],
)
def test_refusals_are_one_line(argv: list[str], needle: str, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["study", "cost", *argv, "--out", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = [ln for ln in captured.err.splitlines() if ln.startswith("heelstrike: error:")]
    assert len(lines) == 1 and needle in lines[0]


def test_model_study_refuses_in_library() -> None:
    with pytest.raises(ValueError, match="the hip law hip-pd needs a walker whose one actuated"):
        cost_study(RADII, LENGTHS, model=load_walker("torso"), actuations=("hip-pd",))
    with pytest.raises(ValueError, match=r"R = 2 m outside \[0, 1\] m"):
        cost_study((0.0, 2.0), LENGTHS, model=load_walker("torso"))


def test_largest_admissible_radius_follows_the_walker_files_constraints() -> None:
    kneed = load_walker("kneed")
    a1, b1 = kneed.parameters["a1"], kneed.parameters["b1"]
    r = kneed.largest_admissible("R", 1.0)  # the constraint R <= a1 + b1 (0.5 m) binds
    assert abs(r - (a1 + b1)) < 1e-9 and r <= a1 + b1
    kneed.replace(R=r)  # admitted
    with pytest.raises(ValueError):
        kneed.replace(R=r + 1e-6)
    assert load_walker("torso").largest_admissible("R", 0.7) == 0.7  # not binding (R <= l)
    with pytest.raises(ValueError, match="not a parameter"):
        kneed.largest_admissible("nope", 1.0)


def test_model_without_declared_speed_asks_for_a_target(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import heelstrike

    src = (Path(heelstrike.__file__).parent / "walkers" / "torso.toml").read_text()
    head, sep, _ = src.partition("[powered]")
    assert sep  # the shipped file declares one; this copy does not
    own = tmp_path / "own.toml"
    own.write_text(head)
    assert main(["study", "cost", "--model", str(own), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "declares no target speed" in err and "--speed or --step-length" in err


@pytest.mark.slow
def test_kneed_defaults_study_the_walkers_own_range(tmp_path: Path) -> None:
    """With defaults the kneed study used R up to 0.9 m (its file admits R <= 0.5 m) and step
    lengths 0.3-0.6 m (its level push-off gaits have 0.70-0.96 m): it failed. Now: radii up to
    0.9 x 0.5 m and speeds 0.95-1.05 x its declared 1.3 m/s; the gaits found are periodic
    level gaits at their target speed whose energy books close."""
    ds = _cli(["study", "cost", "--model", "kneed"], tmp_path)
    assert np.allclose(ds["radius"].values, np.linspace(0.0, 0.45, 4), atol=1e-9)
    assert np.allclose(ds["speed"].values, np.linspace(0.95 * 1.3, 1.05 * 1.3, 4))
    found = ds["found"].values.astype(bool)
    assert found.sum() >= 8  # most of the grid (10 of 16 on the reference machine)
    T_c = ds["collision_loss"].values[found]
    W = ds["push_off_work"].values[found] + ds["torque_work"].values[found]
    assert np.all(np.abs(W - T_c) < 1e-8)
    speed = (ds["step_length"] / ds["period"]).transpose(*ds["found"].dims).values
    target = np.broadcast_to(ds["speed"].values, found.shape)
    assert np.all(np.abs(speed[found] - target[found]) < 1e-6)
