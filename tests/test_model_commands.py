"""Described walkers in the ensemble commands: the compiled ensemble runner, ``basin --model``,
``walk --model``, ``map --model`` and ``bifurcation --model``.

Physics checks: the ensemble reproduces single-walker runs of both backends, a basin point at
the fixed point converges and one far off falls, and the fixed points of a map are fixed points
of the step map.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.basin import model_basin_of_attraction
from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.cli import main
from heelstrike.dynamics.compiled_phased import (
    STATUS_NAMES,
    ensemble_walk_phased,
    section_states,
    simulate_phased_compiled,
)
from heelstrike.dynamics.hybrid import WalkStatus
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker, simulate_phased

SLOPE = math.radians(3.0)
TOL = 1e-8


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


@pytest.fixture(scope="module")
def kneed_gait(kneed: PhasedWalker) -> Gait:
    return find_model_gait(kneed, slope=SLOPE)


def _states(gait: Gait) -> np.ndarray:
    """Section points: the gait, small and large perturbations, a backward fall, a stuck foot."""
    z = np.asarray(gait.fixed_point)
    return np.array([
        z,
        z + np.array([0.01, 0.05, -0.05]),
        z + np.array([0.0, -0.6, 0.0]),  # too slow: falls backward
        [-0.4, 1.871, -2.0],  # trailing foot stays on the ground
        z + np.array([0.05, 0.4, 0.0]),  # too fast
    ])


# -- the ensemble runner -------------------------------------------------------------------------
@pytest.mark.parametrize("parallel", [False, True])
def test_ensemble_equals_single_walker_runs(
    kneed: PhasedWalker, kneed_gait: Gait, parallel: bool
) -> None:
    Z = _states(kneed_gait)
    ens = ensemble_walk_phased(kneed, Z, slope=SLOPE, steps=4, parallel=parallel)
    assert len(set(ens.status_names)) >= 3  # the states exercise different endings
    for i, z in enumerate(Z):
        q, qd = kneed.section_to_state(z)
        one = simulate_phased_compiled(kneed, q, qd, slope=SLOPE, steps=4)
        assert ens.status_names[i] == one.status.value, i
        assert ens.steps[i] == one.n_steps, i
        np.testing.assert_allclose(ens.q[i], one.final_q, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(ens.q_dot[i], one.final_q_dot, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(ens.z[i], kneed.state_to_section(one.final_q,
                                                                    one.final_q_dot))


@pytest.mark.slow
def test_ensemble_matches_scipy_reference(kneed: PhasedWalker, kneed_gait: Gait) -> None:
    Z = _states(kneed_gait)[:4]
    ens = ensemble_walk_phased(kneed, Z, slope=SLOPE, steps=2, rtol=1e-11, atol=1e-11)
    for i, z in enumerate(Z):
        q, qd = kneed.section_to_state(z)
        ref = simulate_phased(kneed, q, qd, slope=SLOPE, steps=2, rtol=1e-11, atol=1e-11)
        assert ens.status_names[i] == ref.status.value, i
        assert ens.steps[i] == ref.n_steps, i
        np.testing.assert_allclose(ens.q[i], ref.final_q, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(ens.q_dot[i], ref.final_q_dot, rtol=TOL, atol=TOL)


def test_ensemble_states_input_and_stop_near(kneed: PhasedWalker, kneed_gait: Gait) -> None:
    Z = _states(kneed_gait)
    Q, QD = section_states(kneed, Z)
    for i, z in enumerate(Z):  # the batched conversion is the walker's own
        q, qd = kneed.section_to_state(z)
        np.testing.assert_allclose(Q[i], q, atol=1e-12)
        np.testing.assert_allclose(QD[i], qd, atol=1e-12)
    a = ensemble_walk_phased(kneed, Z, slope=SLOPE, steps=3, parallel=False)
    b = ensemble_walk_phased(kneed, states=(Q, QD), slope=SLOPE, steps=3, parallel=False)
    np.testing.assert_array_equal(a.status, b.status)
    np.testing.assert_allclose(a.q, b.q, atol=1e-12)
    # a walker on the fixed point stops after its first step; the others walk on
    zstar = np.asarray(kneed_gait.fixed_point)
    s = ensemble_walk_phased(kneed, Z[:2], slope=SLOPE, steps=5, stop_near=(zstar, 1e-6))
    assert list(s.steps) == [1, 5]
    assert np.linalg.norm(s.z[0] - zstar) < 1e-6
    with pytest.raises(ValueError, match="stance foot"):
        ensemble_walk_phased(kneed, states=(Q + np.array([0.0, 0.1, 0, 0, 0, 0]), QD), slope=SLOPE)
    with pytest.raises(ValueError, match="exactly one"):
        ensemble_walk_phased(kneed, Z, states=(Q, QD), slope=SLOPE)
    assert STATUS_NAMES[0] == "completed"


# -- basin -----------------------------------------------------------------------------------------
def test_model_basin_fixed_point_converges_far_point_falls(
    kneed: PhasedWalker, kneed_gait: Gait
) -> None:
    z = np.asarray(kneed_gait.fixed_point)
    basin = model_basin_of_attraction(
        kneed, SLOPE, grid=(3, 3), ranges=((z[0] - 0.2, z[0] + 0.2), (z[1] - 0.9, z[1] + 0.9)),
        steps=30, fixed_point=z,
    )
    ds = basin.dataset
    assert ds["outcome"].dims == ("stance_shank", "stance_shank_dot")
    assert ds["stance_shank"].attrs["units"] == "rad"
    assert ds["stance_shank_dot"].attrs["units"] == "rad s-1"
    out = ds["outcome"].values
    assert WalkStatus.from_code(out[1, 1]) == "converged"  # the fixed point itself
    assert ds["steps"].values[1, 1] == 1
    assert WalkStatus.from_code(out[2, 2]) in ("fell_forward", "fell_backward", "lost_contact",
                                   "trailing_foot_stays")  # far off: a fall
    # 0.9 rad/s slower, the trailing foot starts moving into the ground (QA11 #5)
    assert [WalkStatus.from_code(c) for c in out[:, 0]] == ["inadmissible_start"] * 3
    # every grid point's fate is the single walker's
    for i, a in enumerate(ds["stance_shank"].values):
        for j, b in enumerate(ds["stance_shank_dot"].values):
            q, qd = kneed.section_to_state([a, b, z[2]])
            walks = WalkStatus.from_code(out[i, j]) in ("converged", "keeps_walking")
            taken = int(ds["steps"].values[i, j])
            assert _sinks(kneed, q, qd) == (WalkStatus.from_code(out[i, j]) == "inadmissible_start")
            if WalkStatus.from_code(out[i, j]) == "inadmissible_start":
                assert taken == 0
                continue
            one = simulate_phased_compiled(kneed, q, qd, slope=SLOPE, rtol=1e-8, atol=1e-9,
                                           steps=taken if walks else taken + 1)
            assert one.status.value == ("completed" if walks else WalkStatus.from_code(out[i, j]))
            assert one.n_steps == taken


def _sinks(walker: PhasedWalker, q: np.ndarray, qd: np.ndarray, dt: float = 1e-6) -> bool:
    """Whether the trailing foot of a start is on the ground and moving into it, from its
    clearance along the state's velocity (a finite difference, no contact Jacobian)."""
    on_ground = abs(float(walker.foot_clearance(q, "left"))) < 1e-9
    return on_ground and float(walker.foot_clearance(q + dt * qd, "left")) < -1e-9 * dt


@pytest.mark.slow
def test_model_basin_flags_starts_whose_trailing_foot_sinks(
    kneed: PhasedWalker, kneed_gait: Gait
) -> None:
    """QA11 #5: on the default 20x16 slice, the two slowest stance-rate columns (40 cells) start
    with the trailing foot moving into the ground (QA11's own check counted 40): they are
    ``inadmissible_start``, not walked, on both backends; no other cell is."""
    z = np.asarray(kneed_gait.fixed_point)
    ranges = ((z[0] - 0.25, z[0] + 0.2), (z[1] - 0.9, z[1] + 1.1))  # the documented default
    compiled = model_basin_of_attraction(kneed, SLOPE, grid=(20, 16), steps=3, fixed_point=z)
    ds = compiled.dataset
    np.testing.assert_allclose(ds["stance_shank"].values[[0, -1]], ranges[0], rtol=1e-12)
    np.testing.assert_allclose(ds["stance_shank_dot"].values[[0, -1]], ranges[1], rtol=1e-12)
    out = ds["outcome"].values
    flagged = out == WalkStatus.INADMISSIBLE_START.code
    sinks = np.array([[_sinks(kneed, *kneed.section_to_state([a, b, z[2]]))
                       for b in ds["stance_shank_dot"].values]
                      for a in ds["stance_shank"].values])
    np.testing.assert_array_equal(flagged, sinks)
    assert int(flagged.sum()) == 40 and flagged[:, :2].all()
    assert np.all(ds["steps"].values[flagged] == 0)
    assert compiled.fractions()["inadmissible_start"] == pytest.approx(40 / 320)
    # the scipy reference flags the same starts (on a thin slice through them)
    ref = model_basin_of_attraction(kneed, SLOPE, grid=(20, 2), steps=1, fixed_point=z,
                                    ranges=(ranges[0], (ranges[1][0], ranges[1][0] + 2.0 / 15)),
                                    backend="scipy")
    np.testing.assert_array_equal(ref.dataset["outcome"].values, out[:, :2])


def test_basin_command_with_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["basin", "--model", "kneed", "--param", "R=0.1", "--grid", "4x3", "--steps",
                 "10", "--out", str(tmp_path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["fixed_point"]) == {"stance_shank", "stance_shank_dot", "hip_dot"}
    assert sum(d["fractions"].values()) == pytest.approx(1.0)
    assert (tmp_path / "basin.png").stat().st_size > 0
    import xarray as xr

    with xr.open_dataset(tmp_path / "basin.nc") as ds:
        assert ds.attrs["model"] == "kneed"
        assert ds["outcome"].shape == (4, 3)


@pytest.mark.parametrize("argv, message", [
    (["basin", "--param", "R=0.1"], "--param needs --model"),
    (["basin", "--backend", "scipy", "--q3-range=-0.1:-0.2"], "need MIN < MAX"),
    (["basin", "--model", "kneed", "--leg-length", "2"], "does not have"),
    (["basin", "--model", "kneed", "--q3-range=-0.3:-0.2"], "both --q3-range"),
])
def test_basin_model_option_errors(
    argv: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


# -- walk ------------------------------------------------------------------------------------------
def test_walk_command_with_model(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                 kneed_gait: Gait) -> None:
    import pandas as pd

    assert main(["walk", "--model", "kneed", "--steps", "2", "--fps", "10", "--out",
                 str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert "2 steps, status: completed" in out
    assert "not written" not in err  # every walk figure is drawn for a described walker
    for name in ("walk.gif", "strobe.png", "phase_portrait.png", "step.png", "energy.png"):
        assert (tmp_path / name).stat().st_size > 0
    # the first step's angles start on the gait; the stance foot is pressed and holds
    step = pd.read_csv(tmp_path / "step.csv")
    assert list(step.columns) == [
        "t_s", "stance_shank_rad", "stance_knee_rad", "hip_rad", "swing_knee_rad", "swing_rad",
        "stance_shank_dot_rad_s", "stance_knee_dot_rad_s", "hip_dot_rad_s",
        "swing_knee_dot_rad_s", "tangential_N", "normal_N", "required_friction"]
    assert step["t_s"].iloc[0] == 0.0
    assert step["stance_shank_rad"].iloc[0] == pytest.approx(
        kneed_gait.fixed_point[0], abs=1e-9)
    assert np.all(step["stance_knee_rad"] == 0.0)  # locked through the step
    assert np.all(step["normal_N"] > 0) and np.all(step["required_friction"] < 1.0)
    # starts on the gait, and every heel strike drops the energy by its T_c
    portrait = pd.read_csv(tmp_path / "phase_portrait.csv")
    z = kneed_gait.fixed_point
    assert portrait["q3_rad"].iloc[0] == pytest.approx(z[0], abs=1e-9)
    assert portrait["q3_dot_rad_s"].iloc[0] == pytest.approx(z[1], abs=1e-9)
    impacts = pd.read_csv(tmp_path / "impacts.csv")
    # every impact: a knee strike, then the heel strike, in each of the 2 steps
    assert list(impacts["kind"]) == ["knee_strike", "heel_strike"] * 2
    assert (impacts["kind"] == "heel_strike").sum() == 2
    np.testing.assert_allclose(impacts["drop_J"], impacts["T_c_J"], rtol=1e-6)
    assert np.all(impacts["T_c_J"] > 0)


@pytest.mark.parametrize("argv, message", [
    (["walk", "--guess", "1,2"], "--guess"),
    (["walk", "--param", "R=0.1"], "--param needs --model"),
    (["walk", "--model", "kneed", "--guess", "1,2"], "--guess"),
    (["bifurcation", "--model", "kneed", "--slope-range", "0.5deg:1deg:2"], "no gait found"),
    (["map", "--x", "R:0:0.1:2"], "--x needs --model"),
    (["map", "--backend", "scipy", "--radius", "0:2:3"], "--radius needs 0 <= START <= STOP"),
    (["map", "--model", "kneed", "--x", "nope:0:1:2"], "unknown parameter 'nope'"),
    (["map", "--model", "kneed", "--x", "R:0:0.1:2", "--radius", "0:0.1"], "not both"),
    (["impact-map", "--model", "compass", "--x", "R:0:0.3:2", "--y", "angle:10deg:20deg:2",
      "--backend", "compiled"], "impact-map's heel strikes run on the reference"),
])
def test_model_option_errors(
    argv: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


@pytest.mark.parametrize("command", [["impact", "--angle", "15deg"], ["gait"]])
def test_unknown_param_is_refused_before_the_derivation(
    command: list[str], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """QA sweep 9: ``--param Q=3`` was refused only after the walker's derivation (seconds on a
    cold cache). It is checked against the description's parameters first."""
    import heelstrike.models.builder as builder

    def no_derivation(*args: object, **kwargs: object) -> None:
        raise AssertionError("derived the walker before checking --param")

    monkeypatch.setattr(builder, "build", no_derivation)
    assert main([*command, "--model", "kneed", "--param", "Q=3"]) == 2
    err = capsys.readouterr().err
    assert err == ("heelstrike: error: --param Q: model 'kneed' has no parameter 'Q' (its "
                   "parameters: Is, It, R, a1, a2, b1, b2, g, mH, ms, mt)\n")


# -- map -------------------------------------------------------------------------------------------
def test_model_gait_map_points_are_fixed_points(kneed: PhasedWalker) -> None:
    from heelstrike.analysis.gait_map import model_gait_map

    slopes = np.radians([2.5, 3.0, 3.5])
    gmap = model_gait_map(kneed, "R", [0.05, 0.1], slopes)
    ds = gmap.dataset
    assert ds["spectral_radius"].dims == ("R", "slope")
    found = ds["gait_found"].values
    assert found.sum() >= 4
    for i, R in enumerate(ds["R"].values):
        w = kneed.replace(R=float(R))
        for j, s in enumerate(slopes):
            if not found[i, j]:
                continue
            z = ds["fixed_point"].values[i, j]
            q, qd = w.section_to_state(z)
            one = simulate_phased_compiled(w, q, qd, slope=float(s), steps=1, rtol=1e-11,
                                           atol=1e-11)
            assert one.ok
            np.testing.assert_allclose(w.state_to_section(one.final_q, one.final_q_dot), z,
                                       rtol=0, atol=1e-8)
            assert bool(ds["stable"].values[i, j]) == (ds["spectral_radius"].values[i, j] < 1)


def test_map_command_with_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["map", "--model", "kneed", "--x", "R:0.05:0.1:2", "--slope", "2.5deg:3deg:2",
                 "--out", str(tmp_path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == "kneed" and d["parameter_name"] == "R"
    assert np.asarray(d["gait_found"]).shape == (2, 2)
    assert d["gait_found_fraction"] > 0
    assert (tmp_path / "gait_map.png").stat().st_size > 0


# -- bifurcation -----------------------------------------------------------------------------------
def test_model_bifurcation_steady_states_lie_on_the_branch(kneed: PhasedWalker) -> None:
    from heelstrike.analysis.gait_map import model_bifurcation

    diagram, branch = model_bifurcation(kneed, np.radians([3.0, 3.5]), transient=40, record=4,
                                        continuation_points=2)
    assert branch.stopped is None and len(branch.cycles) == 2
    for i, cycle in enumerate(branch.cycles):
        assert cycle.stable  # so the simulated walk settles on it
        np.testing.assert_allclose(diagram.impact_angles[i], cycle.impact_angle, atol=1e-5)
        np.testing.assert_allclose(diagram.periods[i], cycle.period, atol=1e-5)
    assert branch.period_doubling.size == 0


def test_bifurcation_command_with_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                        ) -> None:
    import pandas as pd

    assert main(["bifurcation", "--model", "kneed", "--slope-range", "3deg:3.5deg:2",
                 "--transient", "5", "--record", "2", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "bifurcation.png").stat().st_size > 0
    rows = pd.read_csv(tmp_path / "bifurcation.csv")
    assert len(rows) == 4 and rows["impact_angle_rad"].notna().all()
    branch = pd.read_csv(tmp_path / "period_one_branch.csv")
    assert branch["stable"].all()


@pytest.mark.slow
def test_compass_bifurcation_runs_on_either_backend() -> None:
    """The compass bifurcation diagram takes --backend like every command (it was refused on
    scipy): the scipy reference and the compiled kernel give the same period-one branch and the
    same steady states, and the same period-doubling slope."""
    import numpy as np

    from heelstrike.analysis.gait_map import compass_bifurcation
    from heelstrike.models import CompassGait

    slopes = np.deg2rad([4.0, 4.3, 4.6])
    kw = {"transient": 20, "record": 4, "continuation_points": 3}
    d_c, b_c = compass_bifurcation(CompassGait(), slopes, backend="compiled", **kw)
    d_s, b_s = compass_bifurcation(CompassGait(), slopes, backend="scipy", **kw)
    np.testing.assert_allclose(d_c.impact_angles, d_s.impact_angles, atol=1e-7)
    np.testing.assert_allclose(d_c.periods, d_s.periods, atol=1e-7)
    np.testing.assert_allclose([c.fixed_point for c in b_c.cycles],
                               [c.fixed_point for c in b_s.cycles], atol=1e-8)
    assert b_c.period_doubling.size == b_s.period_doubling.size == 1
    assert np.degrees(b_c.period_doubling[0]) == pytest.approx(
        np.degrees(b_s.period_doubling[0]), abs=1e-4)
    assert np.degrees(b_c.period_doubling[0]) == pytest.approx(4.391, abs=1e-3)


def test_impact_map_backend_scipy_is_its_reference(tmp_path: Path) -> None:
    """``impact-map`` takes ``--backend`` like every command (issue 9); ``scipy`` is its one
    computation, the same table as without the option."""
    grid = ["impact-map", "--model", "compass", "--x", "R:0:0.3:3", "--y", "angle:10deg:25deg:4"]
    assert main([*grid, "--out", str(tmp_path / "a")]) == 0
    assert main([*grid, "--backend", "scipy", "--out", str(tmp_path / "b")]) == 0
    a = (tmp_path / "a" / "impact_map.csv").read_bytes()
    assert a == (tmp_path / "b" / "impact_map.csv").read_bytes() and len(a) > 100


def test_impact_model_says_when_the_ground_holds_the_trailing_foot(capsys, tmp_path) -> None:
    """QA sweep 10: at 40 deg ``impact --model compass`` printed T_c 8.131197 J where ``impact``
    prints the paper's 7.664558 J, with nothing saying why: the ground holds the trailing foot
    (a frictionless contact), whose loss the first includes. Both checked here against
    independent projections, and the impulse units follow the rows (locks N m s)."""
    from heelstrike.core.impact import impact
    from heelstrike.models import CompassGait, heel_strike_state

    assert main(["impact", "--model", "compass", "--angle", "40deg", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["trailing_foot_held"] is True and d["trailing_foot_lifts"] is False
    assert d["units"]["impulse"] == ["N s"] * 3
    w = CompassGait(foot_radius=0.0)
    q, qd = heel_strike_state(w, math.radians(40.0), q3_dot=1.0)
    A_L, A_R = w.contact_jacobian(q, "left"), w.contact_jacobian(q, "right")
    both = impact(w.mass_matrix(q), np.vstack((A_L, A_R[1:])), qd)  # + the trailing normal row
    striking = impact(w.mass_matrix(q), A_L, qd)  # the paper's eq. 10
    assert d["T_c"] == pytest.approx(float(both.kinetic_energy_constrained), rel=1e-12)
    assert d["T_c"] > float(striking.kinetic_energy_constrained) + 0.4
    np.testing.assert_allclose(d["impulse"][-1], float(both.constraint_impulse[-1]), rtol=1e-10)
    assert main(["impact", "--angle", "40deg", "--json"]) == 0
    paper = json.loads(capsys.readouterr().out)
    assert paper["T_c"] == pytest.approx(float(striking.kinetic_energy_constrained), rel=1e-12)
    # the text says so, and a map's CSV marks the cells
    assert main(["impact", "--model", "compass", "--angle", "40deg"]) == 0
    assert "the ground holds the trailing foot" in capsys.readouterr().out
    assert main(["impact", "--model", "compass", "--angle", "20deg"]) == 0
    assert "holds" not in capsys.readouterr().out
    assert main(["impact-map", "--model", "compass", "--x", "R:0:0.5:2", "--y",
                 "angle:20deg:40deg:2", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    import pandas as pd

    rows = pd.read_csv(tmp_path / "impact_map.csv")
    assert (rows["trailing_foot_held"] == 1 - rows["trailing_foot_lifts"]).all()
    assert rows["trailing_foot_held"].tolist() == [0, 0, 1, 0]  # R = 0 at 40 deg
    # the kneed walker: striking foot (N s), two knee locks (N m s), trailing foot (N s)
    assert main(["impact", "--model", "kneed", "--angle", "40deg", "--json"]) == 0
    k = json.loads(capsys.readouterr().out)
    assert k["trailing_foot_held"] is True
    assert k["units"]["impulse"] == ["N s", "N s", "N m s", "N m s", "N s"]


def test_a_copy_with_the_shipped_name_is_noted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """QA sweep 11: a copy of kneed.toml with changed values is still named 'kneed' and its
    outputs read as the shipped walker's; the command says so. An unchanged copy, a renamed
    copy and the shipped name itself get no note."""
    from importlib.resources import files

    text = (files("heelstrike") / "walkers" / "kneed.toml").read_text()
    assert '\nmH = ' in text
    head, _, tail = text.partition("\nmH = ")
    changed = head + "\nmH = 2.0" + tail[tail.index("\n"):]
    cases = {
        "changed.toml": (changed, True),
        "same.toml": (text, False),
        "renamed.toml": (changed.replace('name = "kneed"', 'name = "my_kneed"', 1), False),
    }
    for fname, (body, noted) in cases.items():
        path = tmp_path / fname
        path.write_text(body)
        assert main(["impact", "--model", str(path), "--angle", "15deg", "--json"]) == 0
        err = capsys.readouterr().err
        assert ("is named 'kneed' like the shipped walker but differs" in err) == noted, fname
    assert main(["impact", "--model", "kneed", "--angle", "15deg", "--json"]) == 0
    assert "like the shipped walker" not in capsys.readouterr().err
    # a command that fails still says one line: its error (the note is news of a result)
    argv = ["gait", "--model", str(tmp_path / "changed.toml"), "--slope", "0deg"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heelstrike: error:")
