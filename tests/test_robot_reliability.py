"""Robot path reliability (QA sweep of the robot commands, P2 findings 1-4).

1. a result that overflows is refused as one error line (exit 2, nothing on stdout, no numpy
   warnings), and ``robot state`` refuses a state whose kinetic energy overflows;
2. a kept contact that the ground would have to pull on is reported (``admissible``,
   ``pulling_contacts``, a note on stderr), with the study's rule (``ground_admissible``);
3. the energy books when a contact slips: ``T = T_plus + energy_lost`` and
   ``loss_beyond_T_c = energy_lost - T_c`` (friction), 0 for sticking inert contacts;
4. joint limits: ``robot state`` and ``impact --robot`` note joints outside the model's
   position limits and the state file lists them.

Marked ``robots``; they skip without Pinocchio (as tests/test_robots.py).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

try:
    import pinocchio  # noqa: F401
except ImportError:
    if os.environ.get("CI"):  # CI installs heelstrike[robots]: these tests must run there
        raise
    pytest.skip("needs heelstrike[robots] (pin, example-robot-data)", allow_module_level=True)

from heelstrike._units import json_units
from heelstrike.cli import main
from heelstrike.robots import (
    ContactSpec,
    ground_admissible,
    joint_limit_violations,
    load_robot,
    robot_heel_strike_study,
    robot_impact,
)
from heelstrike.robots.states import gait_state

pytestmark = pytest.mark.robots

README_KEEP = ["--strike", "left_sole_link:flat", "--keep", "right_sole_link:flat"]


@pytest.fixture(scope="module")
def talos() -> Any:
    return load_robot("talos")


@pytest.fixture(scope="module")
def g1() -> Any:
    return load_robot("g1")


def _state_file(path: Path, q: Any, v: Any) -> str:
    path.write_text(json.dumps({"q": [float(x) for x in q], "v": [float(x) for x in v]}))
    return str(path)


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("heelstrike: error:"), err
    return lines[0]


def _notes(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("heelstrike: note:")]


# -- 1. overflow -----------------------------------------------------------------------------
@pytest.mark.parametrize("as_json", [True, False])
def test_overflowing_impact_is_one_error_line_without_warnings(talos, tmp_path, capsys,
                                                               as_json) -> None:
    q, v = gait_state(talos, 0.3, 0.3)
    big = 1e200 * v  # finite, but its kinetic energy overflows
    with np.errstate(all="ignore"):
        T = 0.5 * big @ talos.mass_matrix(q) @ big
    assert np.all(np.isfinite(big)) and not np.isfinite(T)
    state = _state_file(tmp_path / "big.json", q, big)
    argv = ["impact", "--robot", "talos", "--state", state, *README_KEEP]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc = main(argv + (["--json"] if as_json else []))
    cap = capsys.readouterr()
    assert rc == 2
    assert cap.out == ""
    assert "not finite" in _one_error_line(cap.err)
    assert [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)] == []


def test_overflow_in_a_real_process_prints_only_the_error_line(talos, tmp_path) -> None:
    """As the QA ran it: warnings would reach the real stderr of a new process."""
    q, v = gait_state(talos, 0.3, 0.3)
    state = _state_file(tmp_path / "big.json", q, 1e200 * v)
    code = "import sys; from heelstrike.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.run(
        [sys.executable, "-c", code, "impact", "--robot", "talos", "--state", state,
         *README_KEEP, "--json"],
        capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 2
    assert proc.stdout == ""
    _one_error_line(proc.stderr)


def test_robot_state_refuses_a_state_whose_energy_overflows(tmp_path, capsys) -> None:
    out = tmp_path / "big.json"
    assert main(["robot", "state", "talos", "--forward-speed", "1e200", "--out", str(out)]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and not out.exists()
    assert "not finite" in _one_error_line(cap.err)
    # an ordinary large speed is still written
    assert main(["robot", "state", "talos", "--forward-speed", "5", "--out", str(out)]) == 0
    assert out.is_file()


# -- 2. a kept contact that pulls on the ground ----------------------------------------------
def test_readme_example_reports_the_pulling_kept_sole(talos, tmp_path, capsys) -> None:
    q, v = gait_state(talos, 0.3, 0.3)
    state = _state_file(tmp_path / "state.json", q, v)
    argv = ["impact", "--robot", "talos", "--state", state, *README_KEEP, "--friction", "0.8"]
    assert main([*argv, "--json"]) == 0
    cap = capsys.readouterr()
    d = json.loads(cap.out)
    kept = d["contacts"][1]
    assert kept["role"] == "keep" and kept["frame"] == "right_sole_link"
    lam_n = kept["force_impulse"][2]
    assert lam_n < -0.01  # the ground pulls (-0.033 N s)
    assert d["admissible"] is False
    assert d["pulling_contacts"] == [{"frame": "right_sole_link", "normal_impulse": lam_n}]
    # the README's numbers are unchanged by the check
    assert d["T"] == pytest.approx(d["T_c"] + d["T_a"], rel=1e-12)
    assert d["T_c"] == pytest.approx(0.459130, abs=5e-7)
    notes = _notes(cap.err)
    assert len(notes) == 1 and cap.err.strip() == notes[0]
    assert "right_sole_link" in notes[0] and f"{lam_n:.4g} N s" in notes[0]
    assert "--strike right_sole_link:flat" in notes[0] and "drop it" in notes[0]
    # units: said by the command, the same as the registry's
    u = d["units"]
    assert set(u) == set(d) - {"units"}
    new = ("loss_beyond_T_c", "admissible", "pulling_contacts")
    assert {k: u[k] for k in new} == json_units({k: d[k] for k in new})
    assert u["pulling_contacts"] == {"frame": None, "normal_impulse": "N s"}
    # what the note says: released (struck), the sole lifts and the ground never pulls
    assert main([*argv[:5], "--strike", "left_sole_link:flat", "--strike",
                 "right_sole_link:flat", "--friction", "0.8", "--json"]) == 0
    cap = capsys.readouterr()
    both = json.loads(cap.out)
    assert both["contacts"][1]["mode"] == "separate"
    assert both["contacts"][1]["normal_velocity_post"] > 0.0
    assert both["admissible"] is True and both["pulling_contacts"] == [] and _notes(cap.err) == []
    # the text output says it too
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert "admissible      no" in cap.out and len(_notes(cap.err)) == 1


def test_a_strike_moving_away_is_noted_and_round_off_does_not_pull(talos, tmp_path,
                                                                    capsys) -> None:
    """QA P3: a --strike contact moving away before the impact gave mode 'separate' and T_c 0
    with no note; the kept sole's round-off impulse (-1e-15 N s) was reported as pulling."""
    q, v = gait_state(talos, 0.3, -0.1)  # the leading sole rises at 0.1 m/s
    state = _state_file(tmp_path / "away.json", q, v)
    assert main(["impact", "--robot", "talos", "--state", state, *README_KEEP, "--friction",
                 "0.8", "--json"]) == 0
    cap = capsys.readouterr()
    d = json.loads(cap.out)
    strike = d["contacts"][0]
    assert strike["mode"] == "separate"
    assert strike["normal_velocity_pre"] == pytest.approx(0.1, abs=1e-12)
    assert d["T_c"] == pytest.approx(0.0, abs=1e-12)
    assert d["T"] == pytest.approx(d["T_plus"], rel=1e-12)  # nothing happened
    assert abs(d["contacts"][1]["force_impulse"][2]) < 1e-12
    assert d["admissible"] is True and d["pulling_contacts"] == []
    notes = _notes(cap.err)
    assert len(notes) == 1 and cap.err.strip() == notes[0]
    assert "left_sole_link moves away from the ground" in notes[0] and "+0.1 m/s" in notes[0]
    # approaching: no such note (the README example)
    q, v = gait_state(talos, 0.3, 0.3)
    state = _state_file(tmp_path / "toward.json", q, v)
    assert main(["impact", "--robot", "talos", "--state", state, "--strike",
                 "left_sole_link:flat", "--friction", "0.8"]) == 0
    assert _notes(capsys.readouterr().err) == []


def test_a_flat_strike_never_passes_through_the_ground(tmp_path, capsys) -> None:
    """QA sweep 9: Bolt's point foot given as a flat strike, descending at 0.3 m/s, came out
    'separate' with normal velocity -0.3 m/s after the impact, zero impulse, T_c 0 and
    admissible, exit 0. Holding it flat needs a pull, releasing it passes through the ground:
    refused now, and as a point contact it sticks and stops."""
    bolt = load_robot("bolt")
    q, v = gait_state(bolt, 0.2, 0.3)
    state = _state_file(tmp_path / "bolt.json", q, v)
    assert main(["impact", "--robot", "bolt", "--state", state, "--strike",
                 "FL_FOOT:flat-bilateral", "--json"]) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    assert cap.err.startswith("heelstrike: error: contact 'FL_FOOT': no consistent impact")
    assert "moving into the ground at -0.3 m/s" in cap.err
    assert main(["impact", "--robot", "bolt", "--state", state, "--strike", "FL_FOOT:point",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["contacts"][0]["mode"] == "stick" and d["admissible"] is True
    assert d["contacts"][0]["normal_velocity_post"] == pytest.approx(0.0, abs=1e-12)
    assert d["T_c"] > 0.0 and d["T"] == pytest.approx(d["T_c"] + d["T_a"], rel=1e-12)
    # issue #34: as a support polygon (FRAME:flat) it lands on its corners, none of which
    # ends moving into the ground
    assert main(["impact", "--robot", "bolt", "--state", state, "--strike", "FL_FOOT:flat",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    corners = d["contacts"][0]["corners"]
    assert len(corners) == 4 and any(c["mode"] != "separate" for c in corners)
    assert min(c["normal_velocity_post"] for c in corners) >= -1e-12
    assert d["T_c"] > 0.0 and d["T"] == pytest.approx(d["T_c"] + d["T_a"], rel=1e-12)


def test_a_contact_off_the_ground_is_noted(talos, tmp_path, capsys) -> None:
    """QA sweep 9: a strike frame away from the ground plane was treated as touching, silently.
    An arc heel centred on the sole frame (on the ground) reaches ``radius`` below it."""
    from heelstrike.robots import contact_heights

    q, v = gait_state(talos, 0.3, 0.3)
    state = _state_file(tmp_path / "s.json", q, v)
    flat, arc = ContactSpec(frame="left_sole_link", kind="flat"), ContactSpec(
        frame="left_sole_link", kind="arc", radius=0.05)
    z_flat, z_arc = contact_heights(talos, q, [flat, arc])
    assert abs(z_flat) < 1e-9 and z_arc == pytest.approx(z_flat - 0.05, abs=1e-12)
    assert main(["impact", "--robot", "talos", "--state", state, "--strike",
                 "left_sole_link:arc:0.05", "--json"]) == 0
    notes = _notes(capsys.readouterr().err)
    assert len(notes) == 1 and "contact left_sole_link is 50 mm below the ground" in notes[0]


def test_a_non_unit_base_quaternion_is_noted_and_normalised(talos, tmp_path, capsys) -> None:
    """QA P3: a base quaternion of norm 0.5-1.5 was normalised silently. The impact is that
    of the normalised pose (the same as the unit state's), and stderr says so once; a unit
    quaternion (to round-off) is silent, and one outside (0.5, 1.5) is refused."""
    q, v = gait_state(talos, 0.3, 0.3)
    runs = {}
    for name, scale in (("unit", 1.0), ("scaled", 1.2)):
        qs = np.array(q, dtype=float)
        qs[3:7] *= scale
        state = _state_file(tmp_path / f"{name}.json", qs, v)
        assert main(["impact", "--robot", "talos", "--state", state, *README_KEEP, "--friction",
                     "0.8", "--json"]) == 0
        cap = capsys.readouterr()
        runs[name] = (json.loads(cap.out), _notes(cap.err))
    quat_notes = [n for n in runs["scaled"][1] if "quaternion" in n]
    assert len(quat_notes) == 1 and "norm 1.2;" in quat_notes[0]
    assert not [n for n in runs["unit"][1] if "quaternion" in n]
    assert runs["scaled"][0]["T_c"] == pytest.approx(runs["unit"][0]["T_c"], rel=1e-12)
    np.testing.assert_allclose(runs["scaled"][0]["qdot_plus"], runs["unit"][0]["qdot_plus"],
                               atol=1e-12)
    qs = np.array(q, dtype=float)
    qs[3:7] *= 2.0
    state = _state_file(tmp_path / "bad.json", qs, v)
    assert main(["impact", "--robot", "talos", "--state", state, *README_KEEP]) == 2
    assert "unit quaternion" in _one_error_line(capsys.readouterr().err)


def test_keep_only_impact_is_the_papers_inert_law(talos, tmp_path, capsys) -> None:
    """QA P3: the CLI refused impacts with --keep contacts only (the paper's inert law)."""
    q, v = gait_state(talos, 0.3, 0.3)
    state = _state_file(tmp_path / "state.json", q, v)
    keep = ["--keep", "left_sole_link:flat", "--keep", "right_sole_link:flat"]
    assert main(["impact", "--robot", "talos", "--state", state, *keep, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    feet = [ContactSpec(frame=f, kind="flat") for f in ("left_sole_link", "right_sole_link")]
    ref = robot_impact(talos, q, v, keep=feet)  # strike defaults to none
    assert d["T_c"] == pytest.approx(ref.result.T_c, rel=1e-12)
    np.testing.assert_allclose(d["qdot_plus"], ref.result.velocity_post, atol=1e-12)
    # inert: A v+ = 0 at every kept contact, T = T_c + T_a, and the loss is exactly T_c
    for J in ref.jacobians:
        np.testing.assert_allclose(J @ np.asarray(d["qdot_plus"]), 0.0, atol=1e-12)
    assert d["T"] == pytest.approx(d["T_c"] + d["T_a"], rel=1e-12)
    assert d["energy_lost"] == pytest.approx(d["T_c"], rel=1e-12)
    assert [c["role"] for c in d["contacts"]] == ["keep", "keep"]
    # the striking contacts' laws mean nothing here; nothing at all is an error
    for extra in (["--friction", "0.5"], ["--restitution", "0.3"]):
        assert main(["impact", "--robot", "talos", "--state", state, *keep, *extra]) == 2
        assert "--keep contacts only is inert" in _one_error_line(capsys.readouterr().err)
    assert main(["impact", "--robot", "talos", "--state", state]) == 2
    assert "at least one --strike or --keep" in _one_error_line(capsys.readouterr().err)


def test_pulling_contacts_follow_the_sign_of_the_kept_normal_impulse(talos) -> None:
    """Random states: a kept contact is listed exactly when its vertical impulse is < 0."""
    rng = np.random.default_rng(7)
    feet = [ContactSpec(frame=f, kind="flat") for f in talos.feet]
    seen = set()
    for _ in range(12):
        q, v = gait_state(talos, float(rng.uniform(0.0, 0.5)), float(rng.uniform(0.1, 0.6)),
                          forward_speed=float(rng.uniform(-0.5, 1.0)))
        v = v + 0.3 * rng.standard_normal(talos.nv)
        r = robot_impact(talos, q, v, strike=[], keep=feet)
        lam_z = [r.result.impulse[2], r.result.impulse[6 + 2]]
        expected = [(c.frame, float(x)) for c, x in zip(feet, lam_z, strict=True) if x < 0.0]
        assert r.pulling_contacts() == expected
        d = r.to_dict()
        assert d["admissible"] is (not expected)
        seen.add(bool(expected))
    assert seen == {True, False}  # both cases were exercised


def test_study_and_impact_share_one_admissibility_rule(talos) -> None:
    s = robot_heel_strike_study(talos, [0.1, 0.3], [0.2, 0.4])
    np.testing.assert_array_equal(s.admissible, ground_admissible(s.trailing_lift_speed,
                                                                  kept=False))
    assert np.array_equal(s.admissible, s.trailing_lift_speed > 0.0)
    # kept: the ground may push (>= 0) but not pull, up to round-off of the impulse scale
    assert ground_admissible([0.0, 1.0, -1e-3, -1e-12], kept=True, scale=10.0).tolist() == [
        True, True, False, True]
    assert ground_admissible([0.0, 1e-3, -1e-3], kept=False).tolist() == [False, True, False]


# -- 3. energy books when a contact slips ----------------------------------------------------
@pytest.mark.parametrize("mu", [0.05, 0.1, 0.3])
def test_slip_energy_books(talos, tmp_path, capsys, mu) -> None:
    q, v = gait_state(talos, 0.3, 0.3)
    state = _state_file(tmp_path / "state.json", q, v)
    argv = ["impact", "--robot", "talos", "--state", state, "--strike",
            "left_sole_link:flat-bilateral", "--friction", str(mu)]
    assert main([*argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["contacts"][0]["mode"] == "slip"
    M = talos.mass_matrix(q)
    vp = np.array(d["qdot_plus"])
    T_plus = 0.5 * vp @ M @ vp
    assert d["T"] == pytest.approx(0.5 * v @ M @ v, rel=1e-12)
    assert d["T_plus"] == pytest.approx(T_plus, rel=1e-10)
    assert d["T"] == pytest.approx(d["T_plus"] + d["energy_lost"], rel=1e-12)
    assert d["loss_beyond_T_c"] == pytest.approx(d["energy_lost"] - d["T_c"], abs=1e-12)
    assert d["loss_beyond_T_c"] == pytest.approx(d["T_a"] - d["T_plus"], abs=1e-12)
    # friction dissipates: more is lost than T_c, well beyond round-off
    assert d["loss_beyond_T_c"] > 1e-3 * d["T_c"]
    assert d["units"]["loss_beyond_T_c"] == "J" == json_units({"loss_beyond_T_c": 0.0})[
        "loss_beyond_T_c"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "energy_lost - T_c" in text and "friction at the slipping left_sole_link" in text


@pytest.mark.parametrize("keep", [[], ["--keep", "right_sole_link:flat"]])
def test_sticking_inert_contacts_lose_exactly_t_c(talos, tmp_path, capsys, keep) -> None:
    q, v = gait_state(talos, 0.3, 0.3)
    state = _state_file(tmp_path / "state.json", q, v)
    argv = ["impact", "--robot", "talos", "--state", state, "--strike", "left_sole_link:flat",
            *keep]  # default friction: inf, no rebound
    assert main([*argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert all(c["mode"] == "stick" for c in d["contacts"])
    assert d["T"] == pytest.approx(d["T_plus"] + d["energy_lost"], rel=1e-12)
    assert d["energy_lost"] == pytest.approx(d["T_c"], rel=1e-10)
    assert abs(d["loss_beyond_T_c"]) <= 1e-10 * d["T"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "energy_lost - T_c" not in text
    assert re.search(r"loss_beyond_T_c +0\.000000 J", text)  # round-off shown as 0, not -0


def test_energy_lost_means_what_the_compass_impact_means(capsys) -> None:
    """``energy_lost`` is ``T - T_plus`` for the compass ``impact --json`` as for robots."""
    assert main(["impact", "--angle", "20deg", "--restitution", "0.3", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["energy_lost"] == pytest.approx(d["T"] - d["T_plus"], rel=1e-12)
    assert d["energy_lost"] > 0.0


# -- 4. joint limits -------------------------------------------------------------------------
def _outside(robot: Any, q: Any) -> dict[str, tuple[float, float, float]]:
    """Independent check: 1-dof joints with finite limits, q outside them by more than 1e-9."""
    m = robot.model
    out = {}
    for jid in range(1, m.njoints):
        j = m.joints[jid]
        if j.nq != 1:
            continue
        lo, hi = float(m.lowerPositionLimit[j.idx_q]), float(m.upperPositionLimit[j.idx_q])
        x = float(q[j.idx_q])
        if np.isfinite(lo) and np.isfinite(hi) and lo < hi and not lo - 1e-9 <= x <= hi + 1e-9:
            out[str(m.names[jid])] = (x, lo, hi)
    return out


def test_robot_state_notes_and_records_joints_outside_their_limits(g1, tmp_path,
                                                                   capsys) -> None:
    out = tmp_path / "g1long.json"
    assert main(["robot", "state", "g1", "--step-length", "1.2", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    state = json.loads(out.read_text())
    expected = _outside(g1, state["q"])
    assert "right_ankle_pitch_joint" in expected  # the QA's -1.548 rad vs [-0.873, 0.524]
    x, lo, hi = expected["right_ankle_pitch_joint"]
    assert x < lo - 0.5
    recorded = {e["joint"]: (e["position"], e["lower"], e["upper"])
                for e in state["joint_limit_violations"]}
    assert recorded == expected
    assert all(e["unit"] == "rad" for e in state["joint_limit_violations"])
    assert state["units"]["joint_limit_violations"] == {
        "joint": None, "position": "rad", "lower": "rad", "upper": "rad", "unit": None}
    assert state["units"]["joint_limit_violations"] == json_units(
        {"joint_limit_violations": state["joint_limit_violations"]})["joint_limit_violations"]
    assert set(state["units"]) == set(state) - {"units"}
    notes = _notes(cap.err)
    assert len(notes) == len(expected) and cap.err.strip().splitlines() == notes
    for name, (x, lo, hi) in expected.items():
        line = next(n for n in notes if repr(name) in n)
        assert f"{x:.3f} rad" in line and f"[{lo:.3f}, {hi:.3f}] rad" in line
    # impact --robot with that state notes them too (and still answers)
    assert main(["impact", "--robot", "g1", "--state", str(out), "--strike",
                 "left_sole:flat", "--json"]) == 0  # g1's foot frame (its ankle-roll link
    # before QA sweep 12, 35 mm above the sole)
    cap = capsys.readouterr()
    json.loads(cap.out)
    assert len(_notes(cap.err)) == len(expected)
    assert all(any(repr(name) in n for n in _notes(cap.err)) for name in expected)


def test_states_within_limits_are_silent(g1, tmp_path, capsys) -> None:
    out = tmp_path / "g1.json"
    assert main(["robot", "state", "g1", "--out", str(out), "--json"]) == 0
    cap = capsys.readouterr()
    assert cap.err == ""
    assert json.loads(cap.out)["joint_limit_violations"] == []
    state = json.loads(out.read_text())
    assert state["joint_limit_violations"] == [] == joint_limit_violations(g1, state["q"])
    assert _outside(g1, state["q"]) == {}


def test_joint_limit_violations_library(g1) -> None:
    q = np.array(g1.reference_q)
    assert joint_limit_violations(g1, q) == []
    m = g1.model
    jid = m.getJointId("left_knee_joint")
    i = m.joints[jid].idx_q
    q[i] = float(m.upperPositionLimit[i]) + 0.2
    (bad,) = joint_limit_violations(g1, q)
    assert bad.joint == "left_knee_joint" and bad.unit == "rad"
    assert bad.position == pytest.approx(bad.upper + 0.2)
    assert bad.lower == float(m.lowerPositionLimit[i])
    q[i] = float(m.upperPositionLimit[i]) + 1e-12  # round-off at a limit is not a violation
    assert joint_limit_violations(g1, q) == []


def test_a_directory_given_as_urdf_is_named_as_such(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    state = tmp_path / "s.json"
    assert main(["robot", "state", "talos", "--out", str(state)]) == 0
    capsys.readouterr()
    assert main(["impact", "--urdf", str(tmp_path), "--state", str(state),
                 "--strike", "base_link:point"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is a directory" in err[0]
