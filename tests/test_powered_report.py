"""What ``powered`` reports: every gait it meets at the target, and the gains it used.

- Near McGeer's wheel several push-off gaits meet one target. ``powered --radius 0.97 --speed
  0.5`` reported a gait needing 1.01 J per step (unstable), while a stable one needing 0.00025 J
  exists and ``study cost`` kept it there; at ``R = 0.96`` the command had reported 0.00043 J,
  against the paper's trend (the loss falls as ``R`` nears ``l``). ``powered`` now meets the
  gaits the study meets at a design point (:func:`powered_gaits`: the seed search and the fresh
  starts), keeps the one needing the least work, as the study does (issue 11, item 8), and lists
  the others.
- The hip laws' default gains scale with the walker: ``powered`` and ``study cost`` record the
  gains a gait was found with.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.powered import find_powered_gait, powered_gaits
from heelstrike.cli import main
from heelstrike.models.compass import CompassGait

Capture = pytest.CaptureFixture[str]


def _powered(argv: list[str], capsys: Capture) -> dict:
    assert main(["powered", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.slow
def test_powered_near_the_wheel_keeps_the_cheap_gait(capsys: Capture, tmp_path: Path) -> None:
    import xarray as xr

    d = _powered(["--radius", "0.97", "--speed", "0.5"], capsys)
    assert d["speed"] == pytest.approx(0.5, abs=1e-8)
    assert d["actuator_work"] == pytest.approx(d["collision_loss"], abs=1e-8)  # eqs. 14-15
    assert d["collision_loss"] < 1e-3 and d["stable"]
    assert d["gaits_found"] == 1 + len(d["other_gaits"]) >= 2
    costly = d["other_gaits"][0]
    assert costly["actuator_work"] > 1.0 and costly["speed"] == pytest.approx(0.5, abs=1e-8)
    assert costly["actuator_work"] == pytest.approx(costly["collision_loss"], abs=1e-8)
    assert set(d["units"]["other_gaits"]) == set(costly)
    # the seed search alone finds the costly gait: the one the command used to report
    seeded = find_powered_gait(CompassGait(foot_radius=0.97), speed=0.5)
    assert seeded.actuator_work == pytest.approx(costly["actuator_work"], rel=1e-6)
    # the paper's trend: closer to the wheel, less loss at the same speed
    nearer = _powered(["--radius", "0.99", "--speed", "0.5"], capsys)
    farther = _powered(["--radius", "0.9", "--speed", "0.5"], capsys)
    assert nearer["collision_loss"] < d["collision_loss"] < farther["collision_loss"]
    # the study keeps the same gait at this design point
    assert main(["study", "cost", "--radius", "0.97:0.97:1", "--speed", "0.5:0.5:1",
                 "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    with xr.open_dataset(tmp_path / "cost_study.nc") as ds:
        work = float(ds["actuator_work"].values.ravel()[0])
    assert work == pytest.approx(d["actuator_work"], rel=1e-6)


def test_powered_lists_the_other_gaits_at_the_target(capsys: Capture) -> None:
    # point feet at 0.3 m/s: a stable gait needing 0.0302 J and an unstable one needing 0.0415 J
    gaits = powered_gaits(0.0, speed=0.3)
    assert len(gaits) == 2
    works = [g.actuator_work for g in gaits]
    assert works == sorted(works) and works[1] > 1.3 * works[0]
    assert gaits[0].stable and not gaits[1].stable
    for g in gaits:
        assert g.speed == pytest.approx(0.3, abs=1e-8) and g.residual <= 1e-9
        assert g.actuator_work == pytest.approx(g.collision_loss, abs=1e-8)
    assert main(["powered", "--radius", "0", "--speed", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "2 distinct gaits meet this target" in out and "stable no" in out
    assert "q3_dot = " in out and "rad/s" in out  # the fixed point's units
    d = _powered(["--radius", "0", "--speed", "0.3"], capsys)
    assert d["parameter"] == pytest.approx(gaits[0].actuation.parameter, abs=1e-9)
    assert d["other_gaits"][0]["parameter"] == pytest.approx(gaits[1].actuation.parameter, abs=1e-9)
    # one gait: an empty list, with its (empty) units
    one = _powered(["--radius", "0.3", "--speed", "0.5"], capsys)
    assert one["gaits_found"] == 1 and one["other_gaits"] == []
    assert set(one["units"]) == set(one) - {"units"}


def test_powered_records_the_gains_it_used(capsys: Capture) -> None:
    heavy = _powered(["--actuation", "hip-pd", "--radius", "0.3", "--hip-mass", "20",
                      "--leg-mass", "10"], capsys)
    # twice the paper walker's m g l: twice its default torques (dimensionless gains)
    assert heavy["gains"] == pytest.approx({"kp": 100.0, "kd": 10.0, "max_torque": 100.0})
    assert heavy["units"]["gains"] == {"kp": "N m/rad", "kd": "N m s/rad", "max_torque": "N m"}
    given = _powered(["--actuation", "hip-energy", "--radius", "0.3", "--gain", "4",
                      "--max-torque", "30"], capsys)
    assert given["gains"] == {"gain": 4.0, "max_torque": 30.0}
    assert _powered(["--radius", "0.3"], capsys)["gains"] == {}  # the push-off has none
    torso = _powered(["--model", "torso"], capsys)
    assert torso["gains"] == {"kp": 300.0, "kd": 30.0, "angle": 0.0}  # torso.toml's law
    assert main(["powered", "--actuation", "hip-pd", "--radius", "0.3"]) == 0
    assert "gains           kp 50 N m/rad, kd 5 N m s/rad, max_torque 50 N m" in \
        capsys.readouterr().out


@pytest.mark.slow
def test_study_records_the_gains_and_parameter_units(tmp_path: Path, capsys: Capture) -> None:
    import xarray as xr

    assert main(["study", "cost", "--radius", "0:0.3:2", "--step-length", "0.4:0.4:1",
                 "--actuation", "pushoff", "--actuation", "hip-pd", "--kp", "60",
                 "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    with xr.open_dataset(tmp_path / "cost_study.nc") as ds:
        assert ds["parameter_unit"].values.tolist() == ["N s", "rad"]
        kp = ds["kp"].sel(actuation="hip-pd").values
        found = ds["found"].sel(actuation="hip-pd").values == 1
        assert found.any() and np.all(kp[found] == 60.0)
        assert np.all(ds["kd"].sel(actuation="hip-pd").values[found] == 5.0)
        assert np.all(np.isnan(ds["kp"].sel(actuation="pushoff").values))
        assert ds["kp"].attrs["units"] == "N m/rad"


def test_report_says_what_the_parameter_and_a_failed_iterate_are(capsys: Capture,
                                                                tmp_path: Path) -> None:
    # QA findings: "energy 158.33 J" did not say it is the law's target E = T + V, and a
    # failed search printed an unlabelled Newton iterate "[-0.284291 0.96226 ...]"
    assert main(["powered", "--actuation", "hip-energy", "--out", str(tmp_path)]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines()
                if ln.strip().startswith("energy"))
    assert "J (the hip law's target energy E_ref = T + V" in line
    assert main(["powered", "--actuation", "hip-energy", "--speed", "0.8",
                 "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no gait with speed 0.8 m/s" in err[0]
    # Newton fails past the family's end: the iterate, each unknown by name and unit
    tail = err[0].split("fails to take a step from the Newton iterate", 1)[1]
    assert re.match(r" \(q3 = \S+ rad, q3_dot = \S+ rad/s, q4_dot = \S+ rad/s, "
                    r"energy = \S+ J\)", tail), err[0]


@pytest.mark.slow
def test_kneed_report_splits_the_collision_loss(capsys: Capture, tmp_path: Path) -> None:
    # QA finding: the kneed walker's T_c is its knee strike's and heel strike's together; the
    # report now gives each, and they add up to the step's loss
    assert main(["powered", "--model", "kneed", "--out", str(tmp_path)]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "collision loss" in ln)
    m = re.search(r"collision loss\s+([0-9.]+) J \(T_c = knee_strike ([0-9.]+) J \+ "
                  r"heel_strike ([0-9.]+) J\)", line)
    assert m is not None, line
    total, knee, heel = map(float, m.groups())
    assert knee > 0 and heel > knee and total == pytest.approx(knee + heel, abs=2e-6)


@pytest.mark.slow
def test_model_near_the_wheel_meets_the_compass_gaits(capsys: Capture) -> None:
    # QA sweep 4, P1: compass.toml at R = 0.99 reported only the costly unstable gait (5.39 N s,
    # 1.05 J per step) where the built-in compass gait finds a stable one needing 2.8e-5 J: the
    # radius continuation from 0.9 l ran for the compass gait only
    lib = _powered(["--radius", "0.99", "--speed", "0.5"], capsys)
    model = _powered(["--model", "compass", "--param", "R=0.99", "--speed", "0.5"], capsys)
    assert model["stable"] and model["gaits_found"] == lib["gaits_found"] == 2
    assert model["parameter"] == pytest.approx(lib["parameter"], abs=1e-8)
    assert list(model["fixed_point"].values()) == pytest.approx(
        list(lib["fixed_point"].values()), abs=1e-8)
    assert model["actuator_work"] == pytest.approx(model["collision_loss"], abs=1e-9)
    assert model["actuator_work"] < 1e-4  # the cheap branch (the costly one needs ~1 J)


def test_time_limit_is_an_option_and_its_end_says_so(capsys: Capture, tmp_path: Path) -> None:
    # QA sweep 4: the scipy search stopped at a 45 s limit that the CLI could not raise
    assert main(["powered", "--model", "kneed", "--backend", "scipy", "--time-limit", "0.5",
                 "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "gave up after 0.5 s (time limit" in err
    assert err.endswith("give it more with --time-limit SECONDS or use --backend compiled, "
                        "much faster")
    assert main(["powered", "--time-limit", "nan"]) == 2
    assert "--time-limit must be finite and > 0" in capsys.readouterr().err


def test_slow_gait_multipliers_match_an_independent_jacobian() -> None:
    # QA sweep 5, P1: DP by forward differences at a step of 1e-5 erred by 5e-3 on this slow
    # gait (its section coordinates are ~0.01) and called it unstable (|m| 1.0018); the
    # reference: central differences (h = 1e-6) of the scipy walk at rtol = atol = 1e-12
    from heelstrike.dynamics import simulate
    from heelstrike.dynamics.actuation import PushOff

    w = CompassGait()
    g = find_powered_gait(w, speed=0.05)
    push = PushOff(impulse=g.actuation.parameter)

    def step(z: np.ndarray) -> np.ndarray:
        q, qd = w.section_to_state(z)
        r = simulate(w, q, qd, steps=1, push_off=push, backend="scipy", rtol=1e-12, atol=1e-12)
        assert r.ok
        return w.state_to_section(r.final_q, r.final_q_dot)

    z = np.asarray(g.fixed_point)
    assert np.max(np.abs(step(z) - z)) < 1e-9  # the gait is periodic on the reference
    h = 1e-6
    DP = np.column_stack([(step(z + h * e) - step(z - h * e)) / (2 * h) for e in np.eye(3)])
    ref = np.sort(np.abs(np.linalg.eigvals(DP)))[::-1]
    np.testing.assert_allclose(np.abs(g.multipliers), ref, atol=1e-5)
    assert ref[0] < 1.0 and g.stable


@pytest.mark.slow
def test_slow_end_of_the_search_is_not_called_a_fold(capsys: Capture) -> None:
    # QA sweep 5, P1: "at a fold ... none of its gaits has a speed below about 0.0207 m/s",
    # yet gaits exist below (a push-off gait's multiplier nears 1 as it slows: no fold). The
    # seed search still stops there, on either backend, and says so:
    from heelstrike.analysis.powered import (
        PoweredGaitNotFoundError,
        actuation_family,
        family_simulator,
    )

    fam = actuation_family("pushoff")
    for backend in ("compiled", "scipy"):
        sim = family_simulator(CompassGait(), fam, backend)
        with pytest.raises(PoweredGaitNotFoundError) as info:
            find_powered_gait(CompassGait(), speed=0.02, simulator=sim)
        err = str(info.value)
        assert "at a fold" not in err and "no fold" in err and "may exist" in err
    # ... and the command reaches such a gait now (QA sweep 6: from the gait at 0.75 times the
    # target, continued to it): stable, at the speed asked, its push-off work the heel
    # strike's loss
    assert main(["powered", "--radius", "0", "--speed", "0.02", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["speed"] == pytest.approx(0.02, rel=1e-9) and d["stable"]
    assert d["actuator_work"] == pytest.approx(d["collision_loss"], rel=1e-6)
    # the gaits it says may exist: continued by hand from 0.05 m/s, each periodic with the
    # push-off's work equal to the heel strike's loss (eqs. 14-15)
    w = CompassGait()
    g = find_powered_gait(w, speed=0.05)
    for v in (0.04, 0.03, 0.025, 0.02, 0.015):
        g = find_powered_gait(w, speed=v, guess=np.append(g.fixed_point, g.actuation.parameter),
                              fallback=False)
        assert g.speed == pytest.approx(v, abs=1e-8) and g.residual < 1e-8
        assert g.actuator_work == pytest.approx(g.collision_loss, abs=1e-9)


@pytest.mark.slow
def test_slow_gaits_books_close_relative_to_their_size(capsys: Capture) -> None:
    # QA sweep 5, P2: at R = 0.9 m and 0.02 m/s (W = 4.7e-9 J against T = 4e-3 J) the absolute
    # tolerances left the change of T + V over a step at 0.6 % of the work, and the backends
    # 1.8e-3 apart in W; the gait is now converged again at tolerances scaled to its size
    from heelstrike.analysis.powered import (
        BOOKS_NOTE,
        BOOKS_RTOL,
        actuation_family,
        books_gap,
        family_simulator,
    )

    w = CompassGait(foot_radius=0.9)
    fam = actuation_family("pushoff")
    gaits = [find_powered_gait(w, speed=0.02, simulator=family_simulator(w, fam, b))
             for b in ("compiled", "scipy")]
    for g in gaits:
        # a period-one gait on level ground: push-off work = collision loss, no change of E
        assert books_gap(g) < 1e-4
        assert not books_gap(g) > BOOKS_NOTE  # what the report reads: no note
        assert g.actuator_work == pytest.approx(g.collision_loss, rel=1e-4)
        assert abs(g.energy_change) < 1e-4 * g.actuator_work
        assert g.speed == pytest.approx(0.02, rel=1e-9)
    assert gaits[0].actuator_work == pytest.approx(gaits[1].actuator_work, rel=2e-5)
    assert gaits[0].actuation.parameter == pytest.approx(gaits[1].actuation.parameter, rel=2e-5)
    # an ordinary gait's books close to the bar too
    assert books_gap(find_powered_gait(w, speed=0.5)) < BOOKS_RTOL
    # the report shows them: six significant digits (the work read "0.000000 J"), and the
    # largest multiplier with the digits that tell it from 1 (it read "1.0000")
    assert main(["powered", "--radius", "0.9", "--speed", "0.02"]) == 0
    out = capsys.readouterr().out
    work = re.search(r"actuator work\s+(\S+) J", out)
    assert work is not None and float(work.group(1)) == pytest.approx(
        gaits[0].actuator_work, rel=1e-5)
    mods = re.search(r"\|multipliers\|\s+(\S+),", out)
    assert mods is not None and mods.group(1).startswith("0.99999") and len(mods.group(1)) > 6
    assert "note: the books close" not in out  # 1e-5 after the refinement: below BOOKS_NOTE


@pytest.mark.slow
def test_report_qualifies_what_it_cannot_decide(capsys: Capture) -> None:
    # QA sweep 6 (F7): McGeer's wheel with push-off printed "|m| 1.0000 ... stable yes" for
    # |m| = 1 - 3.5e-9, below the multipliers' accuracy; (F1) an unstable gait was reported
    # with no word that a stable one may exist (one does at --step-length 0.05, 61x cheaper)
    from heelstrike.analysis.limit_cycle import MULTIPLIER_ACCURACY

    assert main(["powered", "--radius", "1", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert abs(max(d["multipliers"]) - 1.0) < MULTIPLIER_ACCURACY  # the premise: neutral
    assert main(["powered", "--radius", "1"]) == 0
    out = capsys.readouterr().out
    # McGeer's wheel: its stability is undecided (a neutral family), said with the accuracy
    assert re.search(r"stable +undecided: the largest \|multiplier\| is within 1e-6 of 1",
                     out)
    assert "1.0000," not in out and "|m| 1.0000)" not in out
    assert main(["powered", "--step-length", "0.05", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert main(["powered", "--step-length", "0.05"]) == 0
    out = capsys.readouterr().out
    note = "note: the search met no stable gait at this target, which does not show that none"
    assert (note in out) == (not d["stable"])
    # an ordinary stable gait is reported plainly
    assert main(["powered"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"stable +yes\n", out) and note not in out


@pytest.mark.slow
def test_kneed_energy_books_mark_the_knee_strike(tmp_path: Path, capsys: Capture) -> None:
    # QA sweep 6 (F6): powered --out drew and wrote the kneed walker's step with its knee strike
    # unmarked, and titled the heel strike with the step's whole T_c (knee strike included)
    import pandas as pd

    from heelstrike.analysis.powered import energy_book_tables, find_model_powered_gait
    from heelstrike.dynamics.phased import load_phased_walker

    walker = load_phased_walker("kneed")
    gait = find_model_powered_gait(walker, speed=1.3)
    energy, impacts = energy_book_tables(walker, gait)
    assert list(impacts["kind"]) == ["knee_strike", "heel_strike"]
    # each inert impact drops the total energy by its own T_c (eq. 13), and they add up to the
    # step's collision loss
    np.testing.assert_allclose(impacts["drop_J"], impacts["T_c_J"], rtol=1e-6)
    assert impacts["T_c_J"].sum() == pytest.approx(gait.collision_loss, rel=1e-12)
    knee = energy[energy["event"] == "knee_strike"]
    assert len(knee) == 1
    i = knee.index[0]
    assert energy.loc[i - 1, "t_s"] == energy.loc[i, "t_s"]  # the sample just before it
    assert energy.loc[i - 1, "total_J"] - energy.loc[i, "total_J"] == pytest.approx(
        impacts["T_c_J"].iloc[0], rel=1e-6)
    assert main(["powered", "--model", "kneed", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    written = pd.read_csv(tmp_path / "powered_energy.csv")
    assert list(written["event"].dropna()) == ["knee_strike", "push_off", "heel_strike"]


@pytest.mark.slow
def test_the_seed_continuation_passes_the_push_off_gaits_branch_point() -> None:
    # the seed gait's continuation (0.51 m/s) stalled near 0.89-0.92 m/s, where two families of
    # push-off gaits meet (a multiplier pair on the unit circle; Newton converges slowly), and
    # the search said "no gait ... end near 0.8878 m/s" (or 0.9202 on the compiled backend):
    # no end, since gaits exist on both sides. One full solve at the stalled step carries it on.
    from heelstrike.analysis import powered as P
    from heelstrike.dynamics.actuation import PushOff

    w = CompassGait()
    sim = P.family_simulator(w, P.actuation_family("pushoff"), "compiled")
    for speed in (0.9, 1.0, 1.5):
        gait = find_powered_gait(w, speed=speed, simulator=sim)  # the search alone, no anchors
        assert gait.speed == pytest.approx(speed, rel=1e-9)
        # a gait of the walker on the scipy reference: periodic, and its books close
        z = np.asarray(gait.fixed_point)
        st = P.powered_step(w, z, None, PushOff(impulse=gait.actuation.parameter), rtol=1e-12,
                            atol=1e-12)
        assert st.ok and np.max(np.abs(st.z_next - z)) < 1e-7
        assert st.record is not None
        assert st.record.step_length / st.record.step_duration == pytest.approx(speed, rel=1e-7)
        assert gait.actuator_work == pytest.approx(gait.collision_loss, rel=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize(("argv", "own"), [
    (["--radius", "0", "--speed", "0.9"], False),  # "no gait ... end near 0.8878 m/s"
    (["--model", "compass", "--param", "mH=40", "--param", "m=8", "--param", "l=0.9",
      "--param", "b=0.35", "--param", "R=0.25", "--param", "I=0.3", "--speed", "0.5"], True),
])
def test_gaits_beyond_a_fold_are_reached_from_another_target(
    argv: list[str], own: bool, capsys: Capture, monkeypatch: pytest.MonkeyPatch
) -> None:
    # QA sweep 6 (F2): the seed gait's continuation stopped at a fold of its family and the
    # command said "no gait", where stable gaits exist (continued from 1.2 m/s, or from the
    # walker's 1 m/s gait); the command now also continues gaits from 1.35 and 0.75 times the
    # target
    from heelstrike.analysis import powered as P
    from heelstrike.dynamics.actuation import PushOff

    with monkeypatch.context() as m:
        m.setattr(P, "ANCHOR_FACTORS", ())
        # without the full solve at a stalled continuation step (``_rescue``, which now passes
        # the push-off gaits' branch point near 0.91 m/s: the test below)
        m.setattr(P, "_rescue", lambda *args, **kwargs: None)
        assert main(["powered", *argv]) == 2  # the premise: the search alone finds none
    capsys.readouterr()
    assert main(["powered", *argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    target = float(argv[-1])
    assert d["speed"] == pytest.approx(target, rel=1e-9) and d["stable"]
    assert d["actuator_work"] == pytest.approx(d["collision_loss"], rel=1e-6)
    if own:
        return
    # periodic and stable on the scipy reference: its own step map, central differences
    w = CompassGait()
    z = np.array([d["fixed_point"][k] for k in ("q3", "q3_dot", "q4_dot")])
    push = PushOff(impulse=d["parameter"])

    def step(x: np.ndarray) -> np.ndarray:
        st = P.powered_step(w, x, None, push, rtol=1e-12, atol=1e-12)
        assert st.ok
        return st.z_next

    assert np.max(np.abs(step(z) - z)) < 1e-8
    h = 1e-6
    DP = np.column_stack([(step(z + h * e) - step(z - h * e)) / (2 * h) for e in np.eye(3)])
    moduli = np.sort(np.abs(np.linalg.eigvals(DP)))[::-1]
    assert moduli[0] < 1.0
    np.testing.assert_allclose(moduli, sorted(map(abs, d["multipliers"]), reverse=True),
                               atol=1e-5)


@pytest.mark.slow
def test_multi_swing_gaits_are_counted_and_kept_last(capsys: Capture, tmp_path: Path) -> None:
    # QA sweep 6 (F3): study cost kept, as the cheapest at R = 0.6 m and L = 0.5 m, a gait whose
    # legs cross three times a step, the swing foot 4.4 mm under the ground for 0.4 s with the
    # legs up to 19 deg apart: outside the scuffing convention (one crossing, near mid-stance)
    import xarray as xr

    from heelstrike.analysis.powered import powered_gaits, preferred_gait

    gaits = powered_gaits(0.6, step_length=0.5)
    multi = [g for g in gaits if g.multi_swing]
    single = [g for g in gaits if g.leg_crossings == 1]
    assert multi and single
    w = CompassGait(foot_radius=0.6)
    for g in gaits:  # what the count stands for, from the walker's own geometry
        q = np.asarray(g.walk.q)
        clearance = np.asarray(w.foot_clearance(q, "left"))
        deep = clearance < -1e-3
        if g.multi_swing:
            assert deep.any() and np.abs(q[deep, 3]).max() > 0.1
        else:
            assert not deep.any()
    assert not preferred_gait(gaits).multi_swing
    # the study keeps an ordinary step wherever one was found
    assert main(["study", "cost", "--radius", "0.6:0.6:1", "--step-length", "0.4:0.6:3",
                 "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    ds = xr.open_dataset(tmp_path / "cost_study.nc")
    assert ds["leg_crossings"].attrs["units"] == "1"
    assert np.all(ds["leg_crossings"].values == 1)
    work = ds["actuator_work"].values.ravel()
    assert np.all(np.diff(work) > 0)  # no dip where the multi-swing gait was kept


@pytest.mark.slow
def test_other_gaits_say_how_often_their_legs_cross(capsys: Capture) -> None:
    # QA sweep 7 (P2): the text said "legs cross 3 times a step" of another gait, the JSON did
    # not; and the list put the 3-crossing gait first although the study keeps the other
    from heelstrike.analysis.powered import powered_gaits

    gaits = powered_gaits(0.6, step_length=0.5)
    assert [g.multi_swing for g in gaits] == sorted(g.multi_swing for g in gaits)
    assert main(["powered", "--radius", "0.6", "--step-length", "0.5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["leg_crossings"] == 1 and d["units"]["other_gaits"]["leg_crossings"] == "1"
    assert any(o["leg_crossings"] == 3 for o in d["other_gaits"])
