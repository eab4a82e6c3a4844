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


@pytest.mark.slow  # two gait searches and two short walks
@pytest.mark.parametrize(("slope_deg", "warned"), [(4.5, True), (3.0, False)])
def test_walk_says_when_it_starts_on_an_unstable_gait(slope_deg, warned, tmp_path, capsys):
    # Beyond the period doubling (about 4.4 deg at R = 0) the period-one gait is unstable: a
    # walk started exactly on it repeats it until round-off grows, which looks like periodic
    # walking. The command must say so, and say nothing at 3 deg, where the gait is stable.
    cycle = find_limit_cycle(CompassGait(foot_radius=0.0), slope=np.deg2rad(slope_deg))
    assert cycle.stable is not warned
    assert bool(np.max(np.abs(cycle.multipliers)) > 1.0) is warned
    assert main(["walk", "--radius", "0", "--slope", f"{slope_deg}deg", "--steps", "1",
                 "--fps", "8", "--out", str(tmp_path / "walk.gif")]) == 0
    err = capsys.readouterr().err
    assert ("unstable" in err) is warned
    if warned:
        assert f"{np.max(np.abs(cycle.multipliers)):.4g}" in err


@pytest.mark.parametrize("slope", ["90deg", "200deg", "1.6rad"])
def test_gait_refuses_a_slope_of_90_deg_or_more(slope, capsys, monkeypatch):
    # No incline of 90 deg or more can be walked down: refused before any search (which would
    # only end in "no period-one gait found from 864 seeds").
    import heelstrike.analysis.limit_cycle as lc

    def forbidden(*args, **kwargs):
        raise AssertionError("searched for a gait")

    monkeypatch.setattr(lc, "find_limit_cycles", forbidden)
    monkeypatch.setattr(lc, "find_limit_cycle", forbidden)
    assert main(["gait", "--slope", slope]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heelstrike: error: --slope must be below 90deg")


@pytest.mark.parametrize("argv", [
    ["gait", "--slope", "3"], ["walk", "--slope", "3"], ["basin", "--slope", "3"],
    ["map", "--slope", "1:6:3"], ["bifurcation", "--slope-range", "0.5:6"],
])
def test_every_slope_option_says_a_bare_number_is_radians(argv, capsys, monkeypatch):
    # QA sweep 4: only gait refused 3 (= 172 deg); basin and walk searched 864 seeds and said
    # "no gait found", map computed for 9 s and exited 0 with a grey figure over 57-344 deg
    import heelstrike.analysis.limit_cycle as lc

    def forbidden(*args, **kwargs):
        raise AssertionError("searched for a gait")

    monkeypatch.setattr(lc, "find_limit_cycles", forbidden)
    monkeypatch.setattr(lc, "find_limit_cycle", forbidden)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "must be below 90deg" in err[0], err
    assert "a bare number is radians; for degrees write" in err[0]


def test_bifurcation_csv_slopes_are_the_degrees_asked_for(tmp_path, capsys):
    # QA sweep 5: slope_deg read 2.0000000000000004 (rad2deg of deg2rad)
    import pandas as pd

    assert main(["bifurcation", "--slope-range", "2deg:3deg:3", "--transient", "3",
                 "--record", "2", "--out", str(tmp_path)]) == 0
    df = pd.read_csv(tmp_path / "bifurcation.csv", dtype={"slope_deg": str})
    assert sorted(set(df["slope_deg"])) == ["2", "2.5", "3"]
    # a value with no exact binary form too (it read 4.2000000000000002 once rounded)
    assert main(["bifurcation", "--slope-range", "4deg:4.4deg:3", "--transient", "3",
                 "--record", "2", "--out", str(tmp_path / "b")]) == 0
    for name in ("bifurcation.csv", "period_one_branch.csv"):
        df = pd.read_csv(tmp_path / "b" / name, dtype={"slope_deg": str})
        assert {"4", "4.2", "4.4"} <= set(df["slope_deg"]), name


def test_one_point_basin_draws_without_a_warning(tmp_path, capsys):
    # QA sweep 5 (P3): a 1x1 grid leaked matplotlib's "identical low and high xlims" warning
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["basin", "--grid", "1x1", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "basin.png").is_file()


@pytest.mark.parametrize("argv", [["basin", "--grid", "5x5"],
                                  ["basin", "--model", "kneed", "--grid", "5x5"],
                                  ["map", "--radius", "0:0.3:2", "--slope", "2deg:4deg:3"]])
def test_netcdf_attributes_state_their_units(argv, tmp_path, capsys):
    # QA sweep 5 (P3): foot_radius, hip_mass, fixed_point_*, param_* ... had no units
    import xarray as xr

    assert main([*argv, "--out", str(tmp_path)]) == 0
    name = "basin.nc" if argv[0] == "basin" else "gait_map.nc"
    with xr.open_dataset(tmp_path / name) as ds:
        numeric = [k for k, v in ds.attrs.items()
                   if not k.endswith("_units") and not isinstance(v, str)]
        assert numeric and all(f"{k}_units" in ds.attrs for k in numeric), [
            k for k in numeric if f"{k}_units" not in ds.attrs]
        if argv[1] == "--model":
            assert ds.attrs["param_R_units"] == "m" and ds.attrs["param_mH_units"] == "kg"
        elif argv[0] == "basin":
            assert ds.attrs["hip_mass_units"] == "kg" and ds.attrs["foot_radius_units"] == "m"


def test_model_map_json_lists_the_swept_values(tmp_path, capsys):
    # QA sweep 5 (P3): the compass map's JSON had foot_radius, the model map's no values
    import json

    assert main(["map", "--model", "kneed", "--x", "R:0:0.2:3", "--slope", "2deg:4deg:3",
                 "--out", str(tmp_path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["parameter_name"] == "R" and d["parameter_values"] == pytest.approx([0, 0.1, 0.2])
    assert d["parameter_unit"] == "m" and d["units"]["parameter_values"] == "m"
    assert len(d["gait_found"]) == 3  # one row per swept value


def test_bifurcation_json_says_what_the_diagram_shows(tmp_path, capsys):
    """QA sweep 5 (P3): ``bifurcation`` had no ``--json`` and its CSV had bare NaN rows where
    a walk fell. The JSON and the CSV's ``status`` column now say how each slope's walk ended
    and which period it settled into, consistent with the period-one branch's stability."""
    import pandas as pd

    assert main(["bifurcation", "--slope-range", "4deg:5.6deg:9", "--transient", "60",
                 "--record", "8", "--out", str(tmp_path), "--json"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    d = json.loads(out[0])
    assert d["units"]["walks"] == {"slope": "rad", "status": None, "period_steps": "1",
                                   "settling": None}
    assert d["units"]["branch"]["slope"] == "rad" and d["units"]["branch"]["period"] == "s"
    assert d["units"]["period_doubling_slopes"] == "rad"
    # the compass gait's period doubling (4.39 deg, Goswami et al. 1998's cascade)
    (pd_slope,) = d["period_doubling_slopes"]
    assert 4.3 < np.degrees(pd_slope) < 4.5
    for gait in d["branch"]:  # stable exactly below the period doubling
        assert gait["stable"] == (gait["slope"] < pd_slope), gait
        assert (gait["spectral_radius"] < 1) == gait["stable"]
    rows = pd.read_csv(tmp_path / "bifurcation.csv")
    branch = {round(g["slope"], 12): g for g in d["branch"]}
    periods = {}
    for walk in d["walks"]:
        at = rows[np.isclose(rows["slope_deg"], np.degrees(walk["slope"]), atol=1e-9)]
        assert len(at) == 8 and set(at["status"]) == {walk["status"]}
        angles = at["impact_angle_rad"].to_numpy()
        periods[walk["period_steps"]] = periods.get(walk["period_steps"], 0) + 1
        if walk["status"] != "completed":  # the walk fell: no step recorded
            assert np.isnan(angles).all() and walk["period_steps"] is None
            continue
        gait = branch[round(walk["slope"], 12)]
        if walk["period_steps"] == 1:  # the brute-force walk sits on the Newton gait
            assert walk["slope"] < pd_slope
            np.testing.assert_allclose(angles, gait["impact_angle"], rtol=0, atol=1e-6)
        elif walk["period_steps"] == 2:  # the 2-cycle straddles the unstable period-one gait
            assert walk["slope"] > pd_slope and not gait["stable"]
            assert angles.min() < gait["impact_angle"] < angles.max()
    # what the walks do over this range: period one, the doubled cycle, and falls
    assert periods[1] >= 2 and periods[2] >= 1 and periods[None] >= 2
    assert {"lost_contact"} <= {w["status"] for w in d["walks"]}


def test_period_steps_of_recorded_walks() -> None:
    from heelstrike.analysis.limit_cycle import BifurcationDiagram

    a, b, c = 0.3, 0.31, 0.32
    angles = np.array([[a] * 6, [a, b] * 3, [a, b, c] * 2, [a, b, c, a, b, a], [a] * 5 + [np.nan],
                       [a, a + 2e-6, a, a, a, a]])
    diagram = BifurcationDiagram(slopes=np.arange(6.0), impact_angles=angles,
                                 periods=np.ones_like(angles))
    assert diagram.period_steps().tolist() == [1, 2, 3, 0, 0, 0]
    assert diagram.period_steps(tol=1e-5)[-1] == 1
    assert diagram.statuses == ()  # built by hand: no statuses recorded
    # QA sweep 7 (P1): a walk converging to a stable gait through a multiplier of -0.9
    # alternates with a shrinking amplitude; angles two steps apart agree to 1e-6 before one
    # step apart do, and it was called "settled on period 2"
    k = np.arange(16)
    settling = a + 5e-6 * (-0.9) ** k
    assert np.max(np.abs(settling[2:] - settling[:-2])) < 1e-6 < np.max(np.abs(np.diff(settling)))
    two = a + 1e-3 * (-1.0) ** k  # a genuine 2-cycle
    d = BifurcationDiagram(slopes=np.arange(2.0), impact_angles=np.stack([settling, two]),
                           periods=np.ones((2, 16)))
    assert d.period_steps().tolist() == [0, 2]
    assert BifurcationDiagram(slopes=np.arange(1.0), impact_angles=np.full((1, 1), a),
                              periods=np.ones((1, 1))).period_steps().tolist() == [0]


@pytest.mark.parametrize("slope", ["3deg", "0.5deg"])
def test_mcgeer_wheel_has_no_passive_gait_and_says_why(slope, capsys, monkeypatch):
    # QA sweep 5 (P3): `gait --radius 1` searched 864 seeds and said "no period-one gait
    # found". R = l is McGeer's wheel: after a heel strike its trailing foot neither lifts nor
    # presses, so no passive step completes; said at once, without a search. (QA sweep 7: the
    # first wording, "a heel strike loses nothing", holds only for q4_dot = 0.)
    from heelstrike.analysis import limit_cycle as lc
    from heelstrike.analysis.heel_strike import heel_strike_study
    from heelstrike.dynamics import simulate
    from heelstrike.dynamics.hybrid import WalkStatus

    def forbidden(*args, **kwargs):
        raise AssertionError("searched")

    monkeypatch.setattr(lc, "_compiled_seeds", forbidden)
    monkeypatch.setattr(lc, "_automatic_guess", forbidden)
    assert main(["gait", "--radius", "1", "--slope", slope]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("heelstrike: error: no gait found at slope")
    assert "McGeer's wheel" in err and "exactly zero normal velocity" in err
    assert "loses nothing" not in err
    # the premise, simulated: a passive step of the wheel ends at its heel strike with the
    # trailing foot's normal velocity zero to round-off (and losing energy: the swing leg
    # moves relative to the stance leg); just below the wheel the same start lifts it
    z = np.array([-0.3, 1.0, -1.0])
    for radius, lifts in ((1.0, False), (0.99, True)):
        w = CompassGait(foot_radius=radius)
        q, qd = w.section_to_state(z)
        r = simulate(w, q, qd, steps=1, slope=np.deg2rad(3.0), backend="scipy", rtol=1e-11,
                     atol=1e-11)
        (imp,) = r.impacts
        if lifts:
            assert r.status is WalkStatus.COMPLETED and imp.trailing_normal_velocity > 1e-3
        else:
            assert r.status is WalkStatus.TRAILING_FOOT_STAYS
            assert abs(imp.trailing_normal_velocity) < 1e-12 and imp.energy_lost > 0.1
    # the paper's heel strike (imposed q4_dot = 0) loses nothing at R = l only
    angles = np.deg2rad([5.0, 15.0, 30.0])
    wheel = heel_strike_study(CompassGait(foot_radius=1.0), angles)
    below = heel_strike_study(CompassGait(foot_radius=0.99), angles)
    assert np.all(np.abs(wheel.kinetic_energy_constrained) < 1e-12 * wheel.kinetic_energy)
    assert np.all(below.kinetic_energy_constrained > 1e-6 * below.kinetic_energy)
    assert CompassGait(foot_radius=1.0).is_wheel and not CompassGait(foot_radius=0.99).is_wheel


@pytest.mark.parametrize(("slope_range", "at_least"),
                         [("0.5deg:6deg:12", 7), ("1deg:6deg:6", 4), ("0.1deg:1deg:4", 4)])
def test_coarse_bifurcation_grid_does_not_carry_a_fall_along_a_stable_branch(
    slope_range, at_least, tmp_path, capsys
):
    # QA sweep 7 (P2): on 0.5deg:6deg:12 the walk at 1 deg, released from the 0.5 deg gait,
    # lost contact, and every later slope started from that same stale state: 11 slopes of a
    # stable branch "lost contact". A walk that falls is now walked again from the period-one
    # gait at its slope. QA sweep 10: on 1deg:6deg:6 and 0.1deg:1deg:4 that second walk started
    # from the unstable gait Newton found from the stale state, and fell too (2-6 deg and 0.4-1
    # deg "lost contact", drawn as "the simulated walk fell" across the stable branch): it now
    # starts from the continued branch's gait
    assert main(["bifurcation", "--slope-range", slope_range, "--out", str(tmp_path),
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    stable = {round(g["slope"], 12) for g in d["branch"] if g["stable"]}
    walks = {round(w["slope"], 12): w for w in d["walks"]}
    on_stable = [walks[s] for s in stable if s in walks]
    assert len(on_stable) >= at_least
    for w in on_stable:  # released on a stable gait, the walker walks and stays on it
        assert w["status"] == "completed" and w["period_steps"] == 1, w


def test_bifurcation_files_are_the_same_bytes_run_to_run(tmp_path, capsys):
    # QA sweep 13: bifurcation.pdf carried its creation date, so no two runs wrote the same
    # file (the reproduce figures already did not)
    argv = ["bifurcation", "--slope-range", "2deg:5deg:4", "--transient", "10", "--record", "4"]
    for name in ("a", "b"):
        assert main([*argv, "--out", str(tmp_path / name)]) == 0
    capsys.readouterr()
    for f in sorted(p.name for p in (tmp_path / "a").iterdir()):
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f
    assert b"CreationDate" not in (tmp_path / "a" / "bifurcation.pdf").read_bytes()


def test_a_slowly_shrinking_alternation_is_not_period_two() -> None:
    # QA sweep 13: just below the period doubling (multiplier -0.998) the walk alternates on its
    # way to the period-one gait, its alternation shrinking 3 % over the 16 recorded steps; it
    # passed as "period 2". A cycle's width must hold over the record.
    from heelstrike.analysis.limit_cycle import BifurcationDiagram

    i = np.arange(16)
    converging = 0.3085 + 1.58e-4 * (-0.998) ** (i + 300)  # x* + A mu^i after 300 steps
    two_cycle = 0.3085 + 1.58e-4 * (-1.0) ** i
    fixed = np.full(16, 0.3085)
    rows = np.stack([converging, two_cycle, fixed])
    diagram = BifurcationDiagram(slopes=np.array([0.0766, 0.078, 0.07]), impact_angles=rows,
                                 periods=np.ones_like(rows))
    assert diagram.period_steps().tolist() == [0, 2, 1]


@pytest.mark.slow
def test_walks_still_settling_on_a_stable_branch_are_not_drawn_as_steady_states(tmp_path, capsys):
    # QA sweep 13: at R = 0.9 m (multipliers near 1) 50 transient steps left the walks far
    # from the stable gait, and the figure drew them as "steady state (simulated)": 8 deg off
    # the branch at 0.0967 deg
    from heelstrike.analysis.gait_map import compass_bifurcation
    from heelstrike.plots.gait import bifurcation_figure

    walker = CompassGait(foot_radius=0.9)
    slopes = np.linspace(0.0005, 0.01, 9)
    diagram, branch = compass_bifurcation(walker, slopes, continuation_points=None)
    settling = diagram.settling(branch)
    assert settling.tolist()[:3] == [False, True, True]
    # walked 3000 steps instead of 50, the same walks do settle on the stable gait
    longer, _ = compass_bifurcation(walker, slopes[:3], transient=3000, continuation_points=None)
    assert longer.period_steps().tolist() == [1, 1, 1]
    for k in np.flatnonzero(settling):
        at = np.isclose(branch.values, diagram.slopes[k], rtol=1e-9)
        gait = branch.cycles[int(np.flatnonzero(at)[0])]
        assert gait.stable
        np.testing.assert_allclose(longer.impact_angles[k], gait.impact_angle, atol=1e-7)
        recorded = diagram.impact_angles[k]
        assert np.min(np.abs(recorded - gait.impact_angle)) > 1e-3  # off it when recorded
    fig = bifurcation_figure(diagram, branch)
    lines = {ln.get_label(): ln for ln in fig.axes[0].lines}
    steady = np.asarray(lines["steady state (simulated)"].get_xdata())
    still = np.asarray(lines["still settling (the stable gait not yet reached)"].get_xdata())
    degrees = np.rad2deg(diagram.slopes)
    assert not np.isin(degrees[settling], steady).any()
    assert set(np.unique(still)) == set(degrees[settling])
    assert main(["bifurcation", "--radius", "0.9", "--slope-range", "0.0005:0.01:9",
                 "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "walks at 0.09669, 0.1647 deg: still settling towards the stable period-one gait" in out
    assert main(["bifurcation", "--radius", "0.9", "--slope-range", "0.0005:0.01:9",
                 "--out", str(tmp_path), "--json"]) == 0
    walks = json.loads(capsys.readouterr().out)["walks"]
    assert [w["settling"] for w in walks] == settling.tolist()


def test_a_multi_swing_passive_gait_is_marked_and_listed_last(capsys):
    # QA sweep 13: 'gait' listed a 1.74 s gait whose swing leg crosses the stance leg three
    # times (its foot under the ground away from mid-stance, outside the scuffing convention)
    # as an ordinary gait; the powered search already set such gaits apart
    from heelstrike.analysis.limit_cycle import find_limit_cycles
    from heelstrike.dynamics import simulate

    walker = CompassGait(foot_radius=0.2, hip_mass=5.0, leg_mass=2.0, leg_com_from_hip=0.3,
                         leg_inertia=0.05, leg_length=0.8)
    slope = np.deg2rad(2.0)
    for method in ("compiled", "scipy"):
        gaits = find_limit_cycles(walker, slope=slope, method=method)
        counts = [g.leg_crossings for g in gaits]
        assert counts == [1, 1, 3], (method, counts)
        assert [g.multi_swing for g in gaits] == [False, False, True]
        for g in gaits:  # each count against the reference walk, sampled every millisecond
            walk = simulate(walker, g.q, g.q_dot, slope=slope, steps=1, rtol=1e-10, atol=1e-10,
                            max_step=1e-3)
            hip = np.asarray(walk.q)[:, walker.hip_joint]
            assert np.count_nonzero(np.diff(np.sign(hip[hip != 0]))) == g.leg_crossings
    argv = ["gait", "--radius", "0.2", "--hip-mass", "5", "--leg-mass", "2", "--com-from-hip",
            "0.3", "--leg-inertia", "0.05", "--leg-length", "0.8", "--slope", "2deg"]
    assert main(argv) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[3].startswith("  [2] ") and "multi-swing: the legs cross 3 times" in lines[3]
    assert not any("multi-swing" in line for line in lines[1:3])
    assert main([*argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert [g["leg_crossings"] for g in d["gaits"]] == [1, 1, 3]


def test_tiny_energies_are_printed_so_that_the_books_can_be_read(capsys):
    # QA sweep 13: on a slope of 1e-6 rad the loss and the energy released both printed as
    # 0.00000 J; they are 2.8e-6 J, equal (a passive gait's books), m g L sin(slope)
    assert main(["gait", "--radius", "0", "--slope", "1e-6", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    released = 20.0 * 9.81 * d["step_length"] * np.sin(1e-6)  # m_H + 2 m = 20 kg
    assert d["collision_loss"] == pytest.approx(released, rel=1e-6)
    assert main(["gait", "--radius", "0", "--slope", "1e-6"]) == 0
    out = capsys.readouterr().out
    text = f"{d['collision_loss']:.4e}"
    assert f"collision loss  {text:>10} J/step (T_c)" in out
    assert f"energy released {text:>10} J/step (gravity)" in out


def test_bifurcation_records_from_the_first_step_with_transient_zero(tmp_path, capsys):
    # QA sweep 13: --transient 0 was refused ("expected a positive integer"); recording from
    # the first step is a legitimate choice: the walk at the first slope starts on its gait
    assert main(["bifurcation", "--slope-range", "2deg:4deg:3", "--transient", "0", "--record",
                 "4", "--out", str(tmp_path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["walks"][0]["period_steps"] == 1
    assert main(["bifurcation", "--transient", "-1", "--out", str(tmp_path)]) == 2
    assert "expected an integer >= 0, got '-1'" in capsys.readouterr().err
