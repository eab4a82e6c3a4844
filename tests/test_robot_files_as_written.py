"""Robot files checked as written (issue #36): one bounded parse of the file, then checks of
the values the file itself gives, for URDF and MJCF alike, before Pinocchio's loader runs; and
special files (FIFO, devices, directories) refused by type before anything reads them.

Every bad file is built here, small: a bound is met by counting, never by letting the loader
allocate or recurse.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

if not os.environ.get("CI"):  # CI installs heelstrike[robots]: there these tests must run
    pytest.importorskip("pinocchio", reason="needs heelstrike[robots]")

from heelstrike.cli import main
from heelstrike.robots import RobotError, load_mjcf, load_urdf

pytestmark = pytest.mark.robots
Capture = pytest.CaptureFixture[str]

_I = 'ixy="0" ixz="0" iyz="0"'


def _urdf(tmp_path: Path, *, robot: str = '<robot name="bip">', pelvis_mass: str = "10",
          extra: str = "", hip: str = "", axis: str = "0 1 0", lower: str = "-1",
          upper: str = "1", leg_inertia: str = 'ixx="0.1" iyy="0.1" izz="0.1"',
          name: str = "bip.urdf") -> Path:
    """A two-link biped: a pelvis and one leg on a revolute hip."""
    path = tmp_path / name
    path.write_text(f"""<?xml version="1.0"?>
{robot}
  <link name="pelvis"><inertial><origin xyz="0 0 0"/><mass value="{pelvis_mass}"/>
    <inertia ixx="0.1" iyy="0.1" izz="0.1" {_I}/></inertial></link>
  <link name="leg"><inertial><origin xyz="0 0 -0.5"/><mass value="5"/>
    <inertia {leg_inertia} {_I}/></inertial></link>
  <joint name="hip" type="revolute"><parent link="pelvis"/><child link="leg"/>
    <axis xyz="{axis}"/><limit lower="{lower}" upper="{upper}" effort="1" velocity="1"/>{hip}
  </joint>
  {extra}
</robot>
""")
    return path


_HEAVY = ('<link name="weight"><inertial><mass value="-2"/><inertia ixx="0" iyy="0" izz="0" '
          f'{_I}/></inertial></link><joint name="weld" type="fixed"><parent link="pelvis"/>'
          '<child link="weight"/></joint>')


def test_the_biped_file_loads(tmp_path: Path) -> None:
    robot = load_urdf(_urdf(tmp_path))
    assert robot.mass == pytest.approx(15.0) and robot.nv == 7


def test_an_entity_is_refused_not_a_reason_to_skip_the_checks(tmp_path: Path) -> None:
    # urdfdom reads '&nbsp;'; the old check's own parse failed on it and skipped the check,
    # so a -2 kg link welded to the pelvis loaded
    path = _urdf(tmp_path, robot='<robot name="bip" note="&nbsp;">', extra=_HEAVY)
    with pytest.raises(RobotError, match=r"bip\.urdf: not a URDF robot \(not well-formed XML: "
                       r"undefined entity at line 2, column \d+\): only &amp; .* are read"):
        load_urdf(path)
    doctype = ('<!DOCTYPE robot [<!ENTITY m "-2">]>\n<robot name="bip">')
    with pytest.raises(RobotError, match=r"not a URDF robot: it has a document type "
                       r"declaration"):
        load_urdf(_urdf(tmp_path, robot=doctype))
    # the five XML entities and character references are read as usual
    assert load_urdf(_urdf(tmp_path, robot='<robot name="b&amp;p&#33;">')).mass == 15.0


def _nested_mjcf(path: Path, n: int) -> Path:
    opening = "".join(f'<body name="b{i}">' + ('<freejoint/>' if i == 0 else
                      f'<joint name="j{i}" axis="0 1 0"/>') +
                      '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>' for i in range(n))
    path.write_text(f'<mujoco model="m"><worldbody>{opening}{"</body>" * n}'
                    "</worldbody></mujoco>")
    return path


def _chain_urdf(path: Path, n: int) -> Path:
    links = "".join(f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="1" iyy="1" '
                    f'izz="1" {_I}/></inertial></link>' for i in range(n))
    joints = "".join(f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child '
                     f'link="l{i}"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" '
                     'velocity="1"/></joint>' for i in range(1, n))
    path.write_text(f'<robot name="chain">{links}{joints}</robot>')
    return path


def test_bounds_are_counted_before_the_loader_runs(tmp_path: Path) -> None:
    # 10,000 nested MJCF bodies crashed Pinocchio's parser (SIGSEGV); 1,000 took 23.8 GB
    for n in (10_000, 1_000):
        with pytest.raises(RobotError, match=r"elements nested more than 128 deep .*at most 64 "
                           "bodies on one chain"):
            load_mjcf(_nested_mjcf(tmp_path / f"n{n}.xml", n))
    with pytest.raises(RobotError, match=r"body 'b64' is 65 bodies from the root: at most 64"):
        load_mjcf(_nested_mjcf(tmp_path / "n65.xml", 65))
    assert load_mjcf(_nested_mjcf(tmp_path / "n64.xml", 64)).nv == 6 + 63
    # a 10,000-link URDF chain crashed too
    with pytest.raises(RobotError, match=r"10000 links: at most 1000 are allowed"):
        load_urdf(_chain_urdf(tmp_path / "c10000.urdf", 10_000))
    with pytest.raises(RobotError, match=r"link 'l65' is 65 links from the root: at most 64"):
        load_urdf(_chain_urdf(tmp_path / "c65.urdf", 66))
    many = "".join("<a/>" for _ in range(100_001))
    with pytest.raises(RobotError, match=r"more than 100000 XML elements"):
        load_urdf(_urdf(tmp_path, extra=f"<gazebo>{many}</gazebo>"))
    big = tmp_path / "big.urdf"
    with big.open("wb") as f:  # sparse: refused by its size, never read
        f.truncate(40 << 20)
    with pytest.raises(RobotError, match=r"URDF file '.*big\.urdf' has 41943040 bytes, more "
                       r"than the 8 MiB allowed"):
        load_urdf(big)


def test_couplings_are_found_by_the_parse_not_a_regex(tmp_path: Path) -> None:
    # the mimic regex was cubic: 1,000 joint tags in a comment took 18.5 s
    comment = "<!--" + '<joint type="revolute">' * 2_000 + "-->"
    assert load_urdf(_urdf(tmp_path, extra=comment)).ignored_couplings == ()
    assert load_urdf(_urdf(tmp_path, hip='<mimic joint="hip"/>')).ignored_couplings == (
        "mimic",)
    # a long comment is read in one pass
    assert load_urdf(_urdf(tmp_path, extra="<!--" + "x" * (4 << 20) + "-->")).nv == 7


@pytest.mark.parametrize(("values", "message"), [
    ({"pelvis_mass": "nan"}, r"link 'pelvis': <mass value> is 'nan': finite numbers are needed"),
    ({"pelvis_mass": "-1"}, r"link 'pelvis': <mass value> is -1 kg: a mass is >= 0 kg"),
    ({"leg_inertia": 'ixx="0.01" iyy="0.01" izz="0.1"'},
     r"link 'leg' has an inertia tensor that no rigid body has \(principal moments 0\.01, "
     r"0\.01, 0\.1 kg m\^2\): the largest must be at most the sum of the other two"),
    ({"leg_inertia": 'ixx="-0.1" iyy="0.1" izz="0.1"'},
     r"link 'leg' has an inertia tensor .* principal moment of -0\.1 kg m\^2\): it must be "
     "positive semi-definite"),
    ({"axis": "0 0 0"}, r"joint 'hip': <axis xyz> is zero: a joint axis must be nonzero"),
    ({"axis": "0 1"}, r"joint 'hip': <axis xyz> has 2 values \('0 1'\): exactly 3"),
    ({"lower": "1", "upper": "-1"},
     r"joint 'hip': <limit lower=1 upper=-1> is inverted: lower must be at most upper"),
    ({"extra": '<link name="leg"/>'}, r"two links are named 'leg': names must be unique"),
    ({"extra": '<link name="l2"/><joint name="hip" type="fixed"><parent link="leg"/>'
               '<child link="l2"/></joint>'}, r"two joints are named 'hip'"),
    ({"extra": '<link name="l2"/><joint name="f" type="floating"><parent link="leg"/>'
               '<child link="l2"/></joint>'},
     r"joint 'f' is floating but not at the root"),
    ({"extra": '<link name="l2&#x9b;31m"/>'},
     r"the link named 'l2\\x9b31m' has control characters in its name: printable names only"),
    ({"extra": '<link name="l2\x1b[31m"/>'}, r"not a URDF robot \(not well-formed XML: not "
     r"well-formed \(invalid token\)"),
])
def test_urdf_values_are_checked_as_written(tmp_path: Path, values: dict[str, str],
                                            message: str) -> None:
    with pytest.raises(RobotError, match=r"bip\.urdf: " + message):
        load_urdf(_urdf(tmp_path, **values))


def _mjcf(tmp_path: Path, *, base: str = 'mass="2" diaginertia="0.02 0.03 0.04"',
          joint: str = 'type="hinge" axis="0 1 0" range="-1 1"', extra_body: str = "",
          world: str = "", top: str = "", leg: str = "leg") -> Path:
    path = tmp_path / "hop.xml"
    path.write_text(f"""<mujoco model="hopper">{top}
  <worldbody>
    <body name="base" pos="0 0 0.5">
      <freejoint name="root"/>
      <inertial pos="0 0 0" {base}/>
      <body name="{leg}" pos="0 0 0">
        <joint name="hip" {joint}/>
        <inertial pos="0 0 -0.25" mass="1" diaginertia="0.01 0.01 0.001"/>
        <site name="foot" pos="0 0 -0.5"/>
      </body>
      {extra_body}
    </body>
    {world}
  </worldbody>
</mujoco>
""")
    return path


_FREE = ('<body name="box" pos="1 0 0"><freejoint/><inertial pos="0 0 0" mass="1" '
         'diaginertia="1 1 1"/></body>')


@pytest.mark.parametrize(("values", "message"), [
    ({"base": 'mass="-2" diaginertia="1 1 1"'},
     r"body 'base': <inertial mass> is -2 kg: a mass is >= 0 kg"),
    ({"base": 'mass="2" diaginertia="nan 1 1"'},
     r"body 'base': <inertial diaginertia> is 'nan 1 1': finite numbers are needed"),
    ({"base": 'mass="2" diaginertia="-1 1 1"'}, r"body 'base' has an inertia tensor that no "
     r"rigid body has \(a principal moment of -1 kg m\^2\)"),
    ({"base": 'mass="2" diaginertia="1 1"'},
     r"body 'base': <inertial diaginertia> has 2 values \('1 1'\): exactly 3 are allowed"),
    ({"base": 'mass="2" diaginertia="1 1 5"'}, r"body 'base' .*\(principal moments 1, 1, 5 "
     r"kg m\^2\): .* \(triangle inequality\)"),
    ({"base": 'mass="2" fullinertia="1 1 1 0 0"'},
     r"body 'base': <inertial fullinertia> has 5 values \('1 1 1 0 0'\): exactly 6"),
    ({"leg": "base"}, r"two bodys are named 'base'"),
    ({"extra_body": '<body name="arm"><joint name="hip"/></body>'},
     r"two joints are named 'hip'"),
    ({"world": _FREE}, r"2 free bodies \('base', 'box'\): one robot has one free body"),
    ({"extra_body": _FREE}, r"body 'box' has a free joint but is not at the root"),
    ({"extra_body": '<geom type="sphere" size="0.1" density="nan"/>'},
     r"body 'base': <geom density> is 'nan': finite numbers are needed"),
    ({"top": '<default><geom density="-1"/></default>'},
     r"<default>: <geom density> is -1: it must be >= 0"),
    ({"joint": 'type="hinge" axis="0 0 0"'}, r"body 'leg': joint 'hip' axis is zero: a joint axis "
     "must be nonzero"),
    ({"joint": 'type="hinge" axis="0 1 0" range="1 -1"'}, r"body 'leg': joint 'hip' range \"1 -1\" "
     "is inverted: the lower limit must be at most the upper one"),
    ({"extra_body": '<body name="arm" childclass="nope"/>'},
     r"<body childclass='nope'> names no <default class>"),
    ({"top": '<include file="other.xml"/>'}, r"<include> is not allowed"),
    ({"extra_body": '<frame><body name="arm"/></frame>'},
     r"1 bodies sit inside elements other than <body> \(e\.g\. <frame>\)"),
])
def test_mjcf_values_are_checked_as_written(tmp_path: Path, values: dict[str, str],
                                            message: str) -> None:
    assert load_mjcf(_mjcf(tmp_path)).nv == 7
    with pytest.raises(RobotError, match=r"hop\.xml: " + message):
        load_mjcf(_mjcf(tmp_path, **values))


# -- special files ----------------------------------------------------------------------------
def _special(tmp_path: Path, kind: str) -> tuple[str, str]:
    """A special file of ``kind`` and what the message calls it."""
    if kind == "fifo":
        fifo = tmp_path / "pipe"
        os.mkfifo(fifo)
        return str(fifo), "a FIFO (named pipe)"
    if kind == "device":
        return "/dev/zero", "a character device"
    return str(tmp_path), "a directory"


@pytest.mark.skipif(not hasattr(os, "mkfifo") or not Path("/dev/zero").exists(),
                    reason="needs FIFOs and /dev/zero")
@pytest.mark.parametrize("kind", ["fifo", "device", "directory"])
def test_special_files_are_refused_by_type(tmp_path: Path, capsys: Capture, kind: str) -> None:
    path, what = _special(tmp_path, kind)
    for loader, name in ((load_urdf, "URDF"), (load_mjcf, "MJCF")):
        with pytest.raises(RobotError, match=re.escape(f"{name} file '{path}' is {what}, not "
                                                       "a regular file: give a file")):
            loader(path)
    robot = _urdf(tmp_path)
    assert main(["impact", "--urdf", str(robot), "--state", path, "--keep",
                 "leg:point"]) == 2
    err = capsys.readouterr().err
    assert f"state file '{path}' is {what}, not a regular file" in err, err
    assert main(["robot", "info", "--urdf", path]) == 2
    assert f"URDF file '{path}' is {what}" in capsys.readouterr().err


def test_a_huge_state_file_is_refused_by_its_size(tmp_path: Path, capsys: Capture) -> None:
    state = tmp_path / "s.json"
    with state.open("wb") as f:
        f.truncate(64 << 20)
    assert main(["impact", "--urdf", str(_urdf(tmp_path)), "--state", str(state), "--keep",
                 "leg:point"]) == 2
    assert "state file" in (err := capsys.readouterr().err) and "more than the 1 MiB" in err
    state.write_text(json.dumps({"q": [0.0] * 6 + [1.0, 0.0], "v": [0.0] * 7}))
    assert main(["impact", "--urdf", str(_urdf(tmp_path)), "--state", str(state), "--keep",
                 "leg:point"]) == 0


# -- gait states ------------------------------------------------------------------------------
def test_a_state_the_feet_constraints_cannot_have_is_refused(tmp_path: Path,
                                                             capsys: Capture) -> None:
    from heelstrike.robots import gait_state, gait_velocity, load_robot
    from heelstrike.robots.loading import robot_data_dir

    # bolt: 12 degrees of freedom, flat feet need 17 rows (it wrote 1e16 rad/s)
    path = robot_data_dir() / "bolt_description/robots/bolt.urdf"
    flat = load_urdf(path, feet=("FL_FOOT", "FR_FOOT"), foot_contact="flat")
    message = (r"robot 'bolt' cannot meet the feet constraints of a gait state: flat feet need "
               r"17 independent velocity rows \(6 per sole, 5 for the base\), the robot has "
               r"nv = 12 degrees of freedom: point feet")
    with pytest.raises(RobotError, match=message):
        gait_state(flat, 0.3, 0.3)
    point = load_urdf(path, feet=("FL_FOOT", "FR_FOOT"), foot_contact="point")
    q, _ = gait_state(point, 0.3, 0.3)
    with pytest.raises(RobotError, match=message):
        gait_velocity(flat, q, strike_speed=0.3)
    out = tmp_path / "s.json"
    assert main(["robot", "state", "--urdf", str(path), "--feet", "FL_FOOT,FR_FOOT",
                 "--out", str(out)]) == 2
    assert "cannot meet the feet constraints" in capsys.readouterr().err
    assert not out.exists()
    # a shipped robot: the option is honoured (it was silently ignored)
    assert main(["robot", "state", "bolt", "--foot-contact", "flat", "--out", str(out)]) == 2
    assert "flat feet need 17 independent velocity rows" in capsys.readouterr().err
    assert not out.exists()
    assert main(["robot", "state", "talos", "--foot-contact", "point", "--out", str(out)]) == 0
    assert json.loads(out.read_text())["foot_contact"] == "point"
    assert main(["robot", "state", "bolt", "--out", str(out)]) == 0
    assert json.loads(out.read_text())["foot_contact"] == "point"
    # a singular pose is refused by the rank of its rows (not solved into huge rates)
    talos = load_robot("talos")
    q = talos.reference_q.copy()
    q[7:] = 0.0  # every joint at zero: straight legs, the soles' rows lose rank
    with pytest.raises(RobotError, match=r"its 17 rows \(6 per sole, 5 for the base\) are "
                       r"not independent \(straight or folded legs"):
        gait_velocity(talos, q, strike_speed=0.3)


# -- messages ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def talos():
    from heelstrike.robots import load_robot

    return load_robot("talos")


def test_api_arguments_are_named_not_numpy_or_attribute_errors(talos) -> None:
    import numpy as np

    from heelstrike.robots import (
        contact_heights,
        gait_state,
        inert_energy_split_batch,
        mass_matrices_and_jacobians,
        parse_contact,
        robot_impact,
    )

    q, v = gait_state(talos, 0.3, 0.3)
    sole = [parse_contact("left_sole_link:flat")]
    with pytest.raises(RobotError, match=r"strike\[0\] must be a ContactSpec, got str: "
                       r"parse_contact\('left_sole_link:flat'\) makes one"):
        robot_impact(talos, q, v, strike=["left_sole_link:flat"])
    with pytest.raises(RobotError, match=r"keep must be a sequence of ContactSpec, got str"):
        robot_impact(talos, q, v, keep="right_sole_link:flat")
    with pytest.raises(RobotError, match=r"contacts\[0\] must be a ContactSpec, got int"):
        contact_heights(talos, q, [1])
    with pytest.raises(RobotError, match=r"q must be real numbers, got complex numbers"):
        robot_impact(talos, q.astype(complex), v, strike=sole)
    with pytest.raises(RobotError, match=r"v must be real numbers, got text"):
        robot_impact(talos, q, [*v[:-1], "a"], strike=sole)
    with pytest.raises(RobotError, match=r"configurations are an empty batch: give at least "
                       r"one \(B >= 1\)"):
        inert_energy_split_batch(talos, np.empty((0, talos.nq)), np.empty((0, talos.nv)), sole)
    with pytest.raises(RobotError, match=r"configurations must be real numbers, got complex"):
        mass_matrices_and_jacobians(talos, q[None, :] + 1j, sole)
    # a base far away spoiled the rows, and the error blamed "redundant contacts"
    far = q.copy()
    far[0] = 1e20
    with pytest.raises(RobotError, match=r"q\[0:3\], the base position, is 1e\+20 m from the "
                       r"origin: at most 1e\+06 m is allowed"):
        robot_impact(talos, far, v, strike=sole)
    far[0] = 1e5  # far, but exact enough: the same impact
    near = robot_impact(talos, q, v, strike=sole).to_dict()
    assert robot_impact(talos, far, v, strike=sole).to_dict()["T_c"] == pytest.approx(
        near["T_c"], rel=1e-6)


def test_a_frame_name_with_colons_can_strike(tmp_path: Path, capsys: Capture) -> None:
    from heelstrike.robots import parse_contact

    assert parse_contact("base:foot:point").frame == "base:foot"
    arc = parse_contact("a:b:arc:0.05")
    assert (arc.frame, arc.kind, arc.radius) == ("a:b", "arc", 0.05)
    sole = parse_contact("a:b:flat:0.1,0.05")  # a support polygon's size after the type
    assert (sole.frame, sole.kind, sole.sole) == ("a:b", "flat", (-0.1, 0.1, -0.05, 0.05))
    assert parse_contact("a:b:flat-bilateral").frame == "a:b"
    with pytest.raises(RobotError, match=r"the type is read from the end"):
        parse_contact("foot:round")
    path = _urdf(tmp_path, extra='<link name="leg:sole"/><joint name="sole" type="fixed">'
                 '<parent link="leg"/><child link="leg:sole"/><origin xyz="0 0 -1"/></joint>')
    state = tmp_path / "s.json"
    state.write_text(json.dumps({"q": [0.0] * 6 + [1.0, 0.0],
                                 "v": [0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0]}))
    assert main(["impact", "--urdf", str(path), "--state", str(state), "--strike",
                 "leg:sole:point", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["contacts"][0]["frame"] == "leg:sole"


def test_control_characters_reach_the_terminal_escaped(tmp_path: Path, capsys: Capture) -> None:
    path = _urdf(tmp_path, name="bip\x1b[31m.urdf")
    assert main(["robot", "info", "--urdf", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "bip\\x1b[31m: nq=8 nv=7" in out
    with pytest.raises(SystemExit):
        main(["impact", "--help"])
    assert "base:foot:point" in " ".join(capsys.readouterr().out.split())


def test_loader_and_state_arguments_are_named(talos) -> None:
    from heelstrike.robots import (
        gait_configuration,
        gait_state,
        joint_limit_violations,
        load_robot,
        robot_heel_strike_study,
    )

    with pytest.raises(RobotError, match=r"a URDF file is given by its path \(str or Path\), "
                       "got int"):
        load_urdf(123)  # type: ignore[arg-type]
    with pytest.raises(RobotError, match=r"the MJCF file's path is empty"):
        load_mjcf("")
    with pytest.raises(RobotError, match=r"unknown robot \['talos'\]"):
        load_robot(["talos"])  # type: ignore[arg-type]
    with pytest.raises(RobotError, match=r"step_length must be a real number, got str '0\.3'"):
        gait_state(talos, "0.3", 0.3)  # type: ignore[arg-type]
    with pytest.raises(RobotError, match=r"strike_speed must be a real number, got str"):
        gait_state(talos, 0.3, "0.3")  # type: ignore[arg-type]
    with pytest.raises(RobotError, match=r"forward_speed must be a real number, got NoneType"):
        gait_state(talos, 0.3, 0.3, forward_speed=None)  # type: ignore[arg-type]
    with pytest.raises(RobotError, match=r"max_iterations must be an int >= 1, got 'a'"):
        gait_configuration(talos, 0.3, max_iterations="a")  # type: ignore[arg-type]
    with pytest.raises(RobotError, match=r"tol must be a real number, got str"):
        joint_limit_violations(talos, talos.reference_q, tol="a")  # type: ignore[arg-type]
    with pytest.raises(RobotError, match=r"step lengths must be real numbers, got complex"):
        robot_heel_strike_study(talos, [0.3 + 1j], [0.3])
    with pytest.raises(RobotError, match=r"strike speeds must be real numbers, got text"):
        robot_heel_strike_study(talos, [0.3], "a")


def test_gait_rates_beyond_the_stated_bound_are_refused(talos, monkeypatch) -> None:
    from heelstrike.robots import gait_state, states

    _, v = gait_state(talos, 0.3, 0.3)  # forward at 0.5 m/s, the largest speed
    assert 0.0 < abs(v).max() < states.MAX_RATE_PER_SPEED * 0.5
    monkeypatch.setattr(states, "MAX_RATE_PER_SPEED", 1.0)  # a bound the state exceeds
    with pytest.raises(RobotError, match=r"robot 'talos': the gait state needs v\[\d+\] = "
                       r".*beyond the 0\.5 allowed \(1 times the largest speed asked"):
        gait_state(talos, 0.3, 0.3)
