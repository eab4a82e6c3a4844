"""Robot files as users write them (QA sweep 4): MJCF without a free joint, continuous and
composite joints, a URDF's own floating root, couplings the parsers drop, and the reasons
behind a refused impact, each checked against the physics (momentum, energy, an equivalent
model).

A one-legged "hopper" (a 2 kg base and a 1 kg leg on a pitch hip, its foot 0.5 m below) is
written here in URDF and MJCF.
"""

from __future__ import annotations

import json
import math
import os
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

from heelstrike.cli import main
from heelstrike.core.impact import ImpactInputError
from heelstrike.robots import (
    RobotError,
    load_mjcf,
    load_robot,
    load_urdf,
    parse_contact,
    robot_impact,
)

pytestmark = pytest.mark.robots
Capture = pytest.CaptureFixture[str]

_INERTIA = 'ixy="0" ixz="0" iyz="0"'


def _hopper_urdf(path: Path, *, hip: str = "revolute", root: str = "", extra: str = "",
                 foot_mass: float = 0.0, ankle: str = "fixed") -> Path:
    limit = '<limit lower="-1.5" upper="1.5" effort="100" velocity="10"/>' \
        if hip == "revolute" else ""
    ankle_axis = '<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/>' \
        if ankle == "revolute" else ""
    foot_i = 1e-3 * foot_mass
    path.write_text(f"""<?xml version="1.0"?>
<robot name="hopper">
  {root}
  <link name="base"><inertial><origin xyz="0 0 0"/><mass value="2.0"/>
    <inertia ixx="0.02" iyy="0.03" izz="0.04" {_INERTIA}/></inertial></link>
  <link name="leg"><inertial><origin xyz="0 0 -0.25"/><mass value="1.0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.001" {_INERTIA}/></inertial></link>
  <link name="foot"><inertial><origin xyz="0 0 0"/><mass value="{foot_mass}"/>
    <inertia ixx="{foot_i}" iyy="{foot_i}" izz="{foot_i}" {_INERTIA}/></inertial></link>
  <joint name="hip" type="{hip}"><parent link="base"/><child link="leg"/>
    <origin xyz="0 0 0"/><axis xyz="0 1 0"/>{limit}</joint>
  <joint name="ankle" type="{ankle}"><parent link="leg"/><child link="foot"/>
    <origin xyz="0 0 -0.5"/>{ankle_axis}</joint>
  {extra}
</robot>
""")
    return path


def _hopper_mjcf(path: Path, *, freejoint: bool, leg_joints: str = "", extra: str = "") -> Path:
    free = '<freejoint name="root"/>' if freejoint else ""
    joints = leg_joints or '<joint name="hip" type="hinge" axis="0 1 0"/>'
    path.write_text(f"""<mujoco model="hopper">
  <worldbody>
    <body name="base" pos="0 0 0.5">
      {free}
      <inertial pos="0 0 0" mass="2" diaginertia="0.02 0.03 0.04"/>
      <body name="leg" pos="0 0 0">
        {joints}
        <inertial pos="0 0 -0.25" mass="1" diaginertia="0.01 0.01 0.001"/>
        <site name="foot" pos="0 0 -0.5"/>
      </body>
    </body>
  </worldbody>
  {extra}
</mujoco>
""")
    return path


def _state(path: Path, q: list[float], v: list[float]) -> str:
    path.write_text(json.dumps({"q": q, "v": v}))
    return str(path)


DROP_Q = [0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 1.0]  # base 0.5 m up, upright
DROP_V = [0.0, 0.0, -1.0, 0.0, 0.0, 0.0]  # falling at 1 m/s


def _check_drop(res: Any, mass: float) -> None:
    """A rigid drop onto one sticking point below the centre of mass: the walker stops, the
    vertical impulse is its momentum and all of T is lost."""
    d = res.to_dict()
    assert d["T"] == pytest.approx(0.5 * mass, rel=1e-12)
    assert d["T_c"] == pytest.approx(d["T"], rel=1e-12) and abs(d["T_a"]) < 1e-12
    assert np.max(np.abs(d["qdot_plus"])) < 1e-12
    assert d["impulse"][2] == pytest.approx(mass * 1.0, rel=1e-12)


# -- P1: an MJCF without a free joint crashed (Pinocchio's overload needs the root's name) ----
def test_mjcf_without_a_free_joint_gets_a_floating_base(tmp_path: Path,
                                                        capsys: Capture) -> None:
    fixed = load_mjcf(_hopper_mjcf(tmp_path / "fixed.xml", freejoint=False))
    free = load_mjcf(_hopper_mjcf(tmp_path / "free.xml", freejoint=True))
    assert (fixed.nq, fixed.nv) == (free.nq, free.nv) == (8, 7)
    assert fixed.model.joints[1].shortname() == "JointModelFreeFlyer"
    foot = [parse_contact("foot:point")]
    for robot in (fixed, free):
        _check_drop(robot_impact(robot, [*DROP_Q, 0.0], [*DROP_V, 0.0], strike=foot), 3.0)
    state = _state(tmp_path / "s.json", [*DROP_Q, 0.0], [*DROP_V, 0.0])
    assert main(["impact", "--mjcf", str(tmp_path / "fixed.xml"), "--state", state,
                 "--strike", "foot:point", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["T_c"] == pytest.approx(1.5, rel=1e-12)


# -- P1: a continuous joint's (cos, sin) pair was used as given: a silently wrong answer ------
def test_continuous_joint_pair_is_normalised_like_the_base_quaternion(
        tmp_path: Path, capsys: Capture) -> None:
    rev = load_urdf(_hopper_urdf(tmp_path / "rev.urdf"))
    cont = load_urdf(_hopper_urdf(tmp_path / "cont.urdf", hip="continuous"))
    assert (cont.nq, cont.nv) == (9, 7)
    assert [(b.joint, b.start, b.stop, b.kind) for b in cont.unit_blocks] == [
        ("root_joint", 3, 7, "quaternion"), ("hip", 7, 9, "cos_sin")]
    a = math.pi / 4
    v = [0.3, 0.0, -1.0, 0.0, 0.5, 0.0, 0.8]
    foot = [parse_contact("foot:point")]
    ref = robot_impact(rev, [*DROP_Q, a], v, strike=foot).to_dict()
    for scale in (1.0, 0.8485, 1.2):  # (cos, sin) of 45 deg, scaled: the same angle
        got = robot_impact(cont, [*DROP_Q, scale * math.cos(a), scale * math.sin(a)], v,
                           strike=foot).to_dict()
        for key in ("T", "T_c", "T_a", "T_plus"):
            assert got[key] == pytest.approx(ref[key], rel=1e-12, abs=1e-14), (scale, key)
        np.testing.assert_allclose(got["qdot_plus"], ref["qdot_plus"], atol=1e-12)
    # the CLI says which block it normalised; a pair far from the unit circle is refused
    state = _state(tmp_path / "s.json", [*DROP_Q, 0.6, 0.6], v)
    assert main(["impact", "--urdf", str(tmp_path / "cont.urdf"), "--state", state,
                 "--strike", "foot:point"]) == 0
    err = capsys.readouterr().err
    assert "q[7:9], the (cos, sin) pair of joint 'hip', has norm 0.848528137" in err
    for bad in ([0.0, 0.0], [0.3, 0.3]):
        with pytest.raises(RobotError, match=r"q\[7:9\], the \(cos, sin\) pair of joint 'hip'"):
            robot_impact(cont, [*DROP_Q, *bad], v, strike=foot)
        with pytest.raises(RobotError, match=r"joint 'hip'.*configuration 1"):
            cont.check_states([[*DROP_Q, 1.0, 0.0], [*DROP_Q, *bad]])


# -- P2: a body with two joints (hinge + slide) had its slide's rate labelled rad/s -----------
def test_composite_joint_units_are_those_of_its_parts(tmp_path: Path,
                                                      capsys: Capture) -> None:
    path = _hopper_mjcf(tmp_path / "comp.xml", freejoint=True, leg_joints=(
        '<joint name="hip" type="hinge" axis="0 1 0"/>'
        '<joint name="slide" type="slide" axis="0 0 1"/>'))
    robot = load_mjcf(path)
    assert robot.model.joints[2].shortname() == "JointModelComposite"
    state = _state(tmp_path / "s.json", [*DROP_Q, 0.0, 0.0], [*DROP_V, 0.0, 0.0])
    assert main(["impact", "--mjcf", str(path), "--state", state, "--strike", "foot:point",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["units"]["qdot_plus"] == ["m/s"] * 3 + ["rad/s"] * 4 + ["m/s"]
    # the drop: the slide lets the 2 kg base go on falling, only the 1 kg leg is stopped
    assert d["T"] == pytest.approx(1.5, rel=1e-12)
    assert d["T_c"] == pytest.approx(0.5, rel=1e-12)
    assert d["qdot_plus"][2] == pytest.approx(-1.0, abs=1e-12)  # the base
    assert d["qdot_plus"][7] == pytest.approx(1.0, abs=1e-12)  # the base slides down the leg


# -- P2: a URDF with its own root floating joint got a second free flyer ----------------------
def test_urdf_root_floating_joint_is_the_floating_base(tmp_path: Path) -> None:
    root = ('<link name="world"/><joint name="float" type="floating"><parent link="world"/>'
            '<child link="base"/></joint>')
    robot = load_urdf(_hopper_urdf(tmp_path / "float.urdf", root=root))
    assert (robot.nq, robot.nv) == (8, 7)
    assert [robot.model.joints[j].shortname() for j in range(1, robot.model.njoints)] == [
        "JointModelFreeFlyer", "JointModelRY"]
    _check_drop(robot_impact(robot, [*DROP_Q, 0.0], [*DROP_V, 0.0],
                             strike=[parse_contact("foot:point")]), 3.0)


# -- P2: couplings the parsers drop were dropped silently --------------------------------------
def test_dropped_couplings_are_named(tmp_path: Path, capsys: Capture) -> None:
    mimic = ('<link name="leg2"><inertial><origin xyz="0 0 -0.25"/><mass value="1.0"/>'
             f'<inertia ixx="0.01" iyy="0.01" izz="0.001" {_INERTIA}/></inertial></link>'
             '<joint name="hip2" type="revolute"><parent link="base"/><child link="leg2"/>'
             '<axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" velocity="1"/>'
             '<mimic joint="hip" multiplier="-1"/></joint>')
    fixed_mimic = ('<link name="tag"/><joint name="tagj" type="fixed"><parent link="base"/>'
                   '<child link="tag"/><mimic joint="hip"/></joint>')
    assert load_urdf(_hopper_urdf(tmp_path / "m.urdf", extra=mimic)).ignored_couplings == (
        "mimic",)
    # a mimic inside a fixed joint couples nothing (talos' grippers have 24 of them)
    assert load_urdf(_hopper_urdf(tmp_path / "f.urdf", extra=fixed_mimic)
                     ).ignored_couplings == ()
    assert load_robot("talos").ignored_couplings == ()
    path = _hopper_mjcf(tmp_path / "eq.xml", freejoint=True, extra=(
        '<equality><joint joint1="hip" joint2="hip"/></equality>'))
    assert load_mjcf(path).ignored_couplings == ("equality",)
    state = _state(tmp_path / "s.json", [*DROP_Q, 0.0], [*DROP_V, 0.0])
    assert main(["impact", "--mjcf", str(path), "--state", state, "--strike",
                 "foot:point"]) == 0
    assert "has <equality> elements, which the model does not hold" in capsys.readouterr().err


# -- P2: refusals named no joint or contact -----------------------------------------------------
def test_refused_impacts_say_which_joint_or_contact(tmp_path: Path) -> None:
    # a revolute ankle carrying a massless foot: M is singular, and the ankle is why
    robot = load_urdf(_hopper_urdf(tmp_path / "a.urdf", ankle="revolute"))
    foot = [parse_contact("foot:point")]
    with pytest.raises(ImpactInputError,
                       match=r"not positive definite: joint\(s\) ankle move no mass"):
        robot_impact(robot, [*DROP_Q, 0.0, 0.0], [*DROP_V, 0.0, 0.0], strike=foot)
    # with a foot mass the same robot is fine (the check is not a blanket refusal)
    heavy = load_urdf(_hopper_urdf(tmp_path / "b.urdf", ankle="revolute", foot_mass=0.1))
    assert robot_impact(heavy, [*DROP_Q, 0.0, 0.0], [*DROP_V, 0.0, 0.0],
                        strike=foot).to_dict()["T"] > 0
    # a frame fixed to the world repeats earlier rows (it has none)
    hop = load_urdf(_hopper_urdf(tmp_path / "c.urdf"))
    for extra in ("universe:point",):
        with pytest.raises(ImpactInputError,
                           match=rf"the rows of {extra.split(':')[0]} repeat"):
            robot_impact(hop, [*DROP_Q, 0.0], [*DROP_V, 0.0], strike=foot,
                         keep=[parse_contact(extra)])
    # the same point struck and kept (redundant rows) is solved, not refused (issue #34): the
    # kept point holds, the struck one ends at rest with it and carries no impulse
    both = robot_impact(hop, [*DROP_Q, 0.0], [*DROP_V, 0.0], strike=foot,
                        keep=[parse_contact("foot:point")])
    kept = robot_impact(hop, [*DROP_Q, 0.0], [*DROP_V, 0.0], keep=[parse_contact("foot:point")])
    np.testing.assert_allclose(both.result.velocity_post, kept.result.velocity_post,
                               atol=1e-12)
    assert both.result.modes[0] == "separate" and both.result.unique


def test_parser_errors_give_their_reason(tmp_path: Path) -> None:
    urdf = _hopper_urdf(tmp_path / "h.urdf")
    with pytest.raises(RobotError, match=r"not an MJCF robot \((?!From file)"):
        load_mjcf(urdf)


# -- P2: energy created or slip under unbounded friction went without a word -------------------
def test_kane_and_painleve_cases_are_said(tmp_path: Path, capsys: Capture) -> None:
    # a toe 0.1 m ahead of the ankle descends while the foot's origin rises: sticking would
    # need a pull, so even unbounded friction lets it slide (lam_n -> 0)
    toe = ('<link name="toe"/><joint name="toej" type="fixed"><parent link="foot"/>'
           '<child link="toe"/><origin xyz="0.1 0.05 0"/></joint>')
    path = _hopper_urdf(tmp_path / "toe.urdf", extra=toe)
    q, v = [*DROP_Q, 0.0], [0.0, 0.0, 0.01, 0.0, 2.0, 0.0, 0.0]
    res = robot_impact(load_urdf(path), q, v, strike=[parse_contact("toe:point")]).to_dict()
    assert res["contacts"][0]["mode"] == "slip"
    assert abs(res["impulse"][2]) < 1e-9 and res["T_plus"] <= res["T"] + 1e-12
    assert main(["impact", "--urdf", str(path), "--state", _state(tmp_path / "s.json", q, v),
                 "--strike", "toe:point"]) == 0
    assert "toe slips although friction is unbounded" in capsys.readouterr().err
    # Newton's restitution with sticking friction can create energy (Kane's paradox): said
    kane_q = [0.0, 0.0, 0.0, 0.07105618375443806, -0.543057372893551, 0.7493374683563215,
              0.3722003049616551, 0.7101996064158816, 0.9856571949202331,
              0.00010016552710619245, -0.17317849031685392, -0.056611503326838154,
              -0.8366226013397807, -0.68343351274552, -1.3330831754728916, -0.8357782256076511,
              0.039219578501801376, 1.277289547095914, 0.7046076708428979]
    kane_v = [-0.1925321987397248, 0.9190912755327113, -1.1218039704426375,
              0.19414788614525075, 0.7662680314577092, -1.641201986748805, -0.2808350600677953,
              -0.2284223904550061, -1.6193123463593089, 0.05580551765079563,
              -0.25295136835869947, -0.7741305964812595, -0.7741137959104165,
              1.2503190963983666, -1.040735339180056, 1.1781928126474857,
              -0.19062666391538752, 0.558864872995444]
    from heelstrike.robots import robot_data_dir

    solo = str(robot_data_dir() / "solo_description/robots/solo12.urdf")
    state = _state(tmp_path / "k.json", kane_q, kane_v)
    assert main(["impact", "--urdf", solo, "--state", state, "--strike", "FL_FOOT:point",
                 "--restitution", "1", "--friction", "0.8", "--json"]) == 0
    out = capsys.readouterr()
    d = json.loads(out.out)
    assert d["contacts"][0]["mode"] == "stick" and d["T_plus"] > d["T"] + 0.1
    assert "Kane's paradox" in out.err
    # with a frictionless or inert contact no energy is created, and nothing is said
    assert main(["impact", "--urdf", solo, "--state", state, "--strike", "FL_FOOT:point",
                 "--restitution", "1", "--friction", "0", "--json"]) == 0
    out = capsys.readouterr()
    d = json.loads(out.out)
    assert d["T_plus"] == pytest.approx(d["T"], rel=1e-12) and "Kane" not in out.err


def test_flat_sole_reports_its_centre_of_pressure(tmp_path: Path, capsys: Capture) -> None:
    # QA sweep 4: a flat sole is unbounded, so a centre of pressure 0.7 m behind a real sole
    # went unnoticed; it is now reported. A rigid brick (a wheel on an axle through its centre
    # of mass, at rest) dropped flat at 1 m/s: the sole stops all of it, and its impulse acts
    # below the centre of mass, (0.1, 0.05) m from the sole frame
    path = tmp_path / "brick.urdf"
    path.write_text(f"""<?xml version="1.0"?>
<robot name="brick">
  <link name="base"><inertial><origin xyz="0.1 0.05 0.2"/><mass value="2.0"/>
    <inertia ixx="0.02" iyy="0.03" izz="0.04" {_INERTIA}/></inertial></link>
  <link name="wheel"><inertial><origin xyz="0 0 0"/><mass value="0.5"/>
    <inertia ixx="0.001" iyy="0.002" izz="0.001" {_INERTIA}/></inertial></link>
  <joint name="axle" type="revolute"><parent link="base"/><child link="wheel"/>
    <origin xyz="0.1 0.05 0.2"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
""")
    robot = load_urdf(path)
    q, v = [*DROP_Q[:2], 0.0, *DROP_Q[3:], 0.0], [*DROP_V, 0.0]
    d = robot_impact(robot, q, v, strike=[parse_contact("base:flat")]).to_dict()
    c = d["contacts"][0]
    assert c["mode"] == "stick"
    np.testing.assert_allclose(c["force_impulse"], [0.0, 0.0, 2.5], atol=1e-12)  # m v
    np.testing.assert_allclose(c["centre_of_pressure"], [0.1, 0.05], atol=1e-12)
    assert d["T_c"] == pytest.approx(1.25, rel=1e-12) and np.max(np.abs(d["qdot_plus"])) < 1e-12
    state = _state(tmp_path / "s.json", q, v)
    assert main(["impact", "--urdf", str(path), "--state", state, "--strike", "base:flat",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["units"]["contacts"]["centre_of_pressure"] == "m"
    assert out["contacts"][0]["centre_of_pressure"] == pytest.approx([0.1, 0.05], abs=1e-12)
    assert main(["impact", "--urdf", str(path), "--state", state, "--strike", "base:flat"]) == 0
    assert "centre of pressure (+0.1000, +0.0500) m" in capsys.readouterr().out
