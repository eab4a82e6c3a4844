"""Impacts along recorded motions (heelstrike.robots.replay): MuJoCo's state mapped to
Pinocchio's, touchdowns found, the rigid prediction checked against a closed form and against
MuJoCo's own stiff, inelastic contact."""

from __future__ import annotations

import dataclasses
import json
import sys

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from heelstrike._optional import MissingExtraError
from heelstrike._results import ResultDictMixin
from heelstrike.cli import main
from heelstrike.robots import ContactSpec, load_mjcf
from heelstrike.robots.replay import (
    ReplayResult,
    Touchdown,
    Trajectory,
    detect_touchdowns,
    kinetic_energy,
    mujoco_rollout,
    mujoco_to_pinocchio,
    read_trajectory,
    replay,
    write_trajectory,
)

# A rod (mass 1 kg, its axis the body's z) with a sphere foot 0.25 m below its centre of mass,
# and a spherical rotor (0.5 kg, isotropic) on a hinge about the body's x through that centre:
# the smallest MJCF robot (nv = 7). MuJoCo's contact is stiff (time constant 0.5 ms, critically
# damped: no rebound), its friction cone elliptic with a high impratio (stiff tangentially).
ROD_MASS, ROTOR_MASS = 1.0, 0.5
ROD_INERTIA = np.diag([0.02, 0.021, 0.001])
ROTOR_INERTIA = 0.004
FOOT, RADIUS = np.array([0.0, 0.0, -0.25]), 0.005
TILT = np.pi / 6  # the rod's axis 30 degrees from the vertical, about world y
QUAT = (np.cos(TILT / 2), 0.0, np.sin(TILT / 2), 0.0)  # MuJoCo's (w, x, y, z)


def _on_floor(model: str, bodies: str, dt: float = 1e-4, tc: float = 5e-4) -> str:
    """An MJCF of ``bodies`` above a floor, with the stiff contact (``tc``: time constant, s)."""
    return f"""<mujoco model="{model}">
  <option timestep="{dt}" cone="elliptic" impratio="100"/>
  <default><geom solref="{tc} 1" solimp="0.99 0.999 0.001" friction="5 0.005 0.0001"
    condim="3"/></default>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
{bodies}
  </worldbody>
</mujoco>
"""


def _body(name: str, joint: str, inertial: str, *, foot: tuple[str, float] | None = None,
          inner: str = "", place: str = 'pos="0 0 0"') -> str:
    """An MJCF body: its joint element, ``<inertial>`` attributes, a sphere foot of radius
    RADIUS (``(name, z)``: a geom and a site of that name at ``z`` m), and child bodies."""
    parts = [f"<body name=\"{name}\" {place}>", joint, f"<inertial {inertial}/>"]
    if foot is not None:
        parts += [f'<geom name="{foot[0]}" type="sphere" size="{RADIUS}" pos="0 0 {foot[1]}"/>',
                  f'<site name="{foot[0]}" pos="0 0 {foot[1]}"/>']
    return "\n".join([*parts, inner, "</body>"])


ROD_BODY = _body(
    "rod", '<freejoint name="root"/>', 'pos="0 0 0" mass="1.0" diaginertia="0.02 0.021 0.001"',
    foot=("foot", -0.25), place='pos="0 0 0.3" quat="{quat}"',
    inner=_body("rotor", '<joint name="spin" type="hinge" axis="1 0 0"/>',
                'pos="0 0 0" mass="0.5" diaginertia="0.004 0.004 0.004"'))

# Every joint kind MJCF has (free, ball, hinge about a tilted axis, slide), a root body placed
# and turned in the file (Pinocchio's parser then gives the free flyer a joint placement).
CHAIN_XML = """<mujoco model="chain">
  <worldbody>
    <body name="base" pos="0.1 -0.2 0.7" quat="0.8 0.2 -0.4 0.4">
      <freejoint name="root"/>
      <inertial pos="0.02 0.01 -0.03" mass="2.0" fullinertia="0.03 0.04 0.05 0.001 -0.002 0.003"/>
      <site name="tip0" pos="0.1 0 -0.2"/>
      <body name="arm" pos="0.1 0.05 0">
        <joint name="shoulder" type="ball"/>
        <inertial pos="0 0 -0.15" mass="0.7" diaginertia="0.006 0.005 0.002"/>
        <body name="fore" pos="0 0 -0.3">
          <joint name="elbow" type="hinge" axis="0.3 1 0.2"/>
          <inertial pos="0.01 0 -0.1" mass="0.4" diaginertia="0.003 0.002 0.001"/>
          <body name="slider" pos="0 0 -0.2">
            <joint name="slide" type="slide" axis="0 0.6 0.8"/>
            <inertial pos="0 0 0" mass="0.2" diaginertia="0.001 0.001 0.001"/>
            <site name="tip" pos="0 0 -0.05"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


# A compass: two legs (1 kg, 0.5 m, centre of mass at mid-leg) joined at the hip by a hinge about
# y, a sphere foot at the end of each; the same stiff contact.
LEG = 'pos="0 0 -0.25" mass="1.0" diaginertia="0.02 0.021 0.001"'
COMPASS_BODIES = _body(
    "leg_a", '<freejoint name="root"/>', LEG, foot=("a", -0.5), place='pos="0 0 1"',
    inner=_body("leg_b", '<joint name="hip" type="hinge" axis="0 1 0"/>', LEG, foot=("b", -0.5)))


@pytest.fixture()
def mujoco():
    return pytest.importorskip("mujoco")


def _rod_file(tmp_path, dt=1e-4, tc=5e-4):
    path = tmp_path / "rod.xml"
    quat = " ".join(f"{x:.17g}" for x in QUAT)
    path.write_text(_on_floor("rod", ROD_BODY.format(quat=quat), dt=dt, tc=tc))
    return path


def _rod_start(speed=1.0, drift=0.3, gap=0.001):
    """MuJoCo state: the foot ``gap`` above the ground, the rod translating (no rotation)."""
    z = -FOOT[2] * np.cos(TILT) + RADIUS + gap
    return np.array([0.0, 0.0, z, *QUAT, 0.0]), np.array([drift, 0.0, -speed, 0, 0, 0, 0])


def _quat_matrix(wxyz):
    w, x, y, z = np.asarray(wxyz) / np.linalg.norm(wxyz)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _rod_T_c(R, v_world, omega_world):
    """The classical rigid-body formula for the energy a sticking, inelastic point impact
    takes: ``T_c = 1/2 u^T K^-1 u`` with ``K = 1/m - [r]x I^-1 [r]x`` at the contact point.

    The rotor (isotropic, on a hinge through the centre of mass) adds its inertia across the
    hinge axis ``a`` only: ``I = I_rod + I_s (1 - a a^T)`` (its spin about ``a`` takes no
    impulse), written here from the numbers of the MJCF, without Pinocchio."""
    a = np.array([1.0, 0.0, 0.0])
    inertia = R @ (ROD_INERTIA + ROTOR_INERTIA * (np.eye(3) - np.outer(a, a))) @ R.T
    r = R @ FOOT - np.array([0.0, 0.0, RADIUS])  # centre of mass -> the sphere's lowest point
    K = np.eye(3) / (ROD_MASS + ROTOR_MASS) - _skew(r) @ np.linalg.solve(inertia, _skew(r))
    u = v_world + np.cross(omega_world, r)
    return 0.5 * u @ np.linalg.solve(K, u)


def test_mujoco_state_maps_to_pinocchio(mujoco, tmp_path) -> None:
    """Kinetic energy, potential energy and site positions of the mapped states equal
    MuJoCo's own (mj_energyVel, mj_energyPos, site_xpos) for random states of a chain with a
    free, a ball, a hinge and a slide joint; the naive copy of qvel does not."""
    pin = pytest.importorskip("pinocchio")
    path = tmp_path / "chain.xml"
    path.write_text(CHAIN_XML)
    robot = load_mjcf(path)
    mm = mujoco.MjModel.from_xml_path(str(path))
    mm.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    data = mujoco.MjData(mm)
    pd = robot.model.createData()
    rng = np.random.default_rng(34)
    naive_errors = []
    for _ in range(20):
        data.qpos[:3] = rng.normal(size=3)
        data.qpos[3:7] = rng.normal(size=4)
        data.qpos[7:11] = rng.normal(size=4)
        data.qpos[3:7] /= np.linalg.norm(data.qpos[3:7])
        data.qpos[7:11] /= np.linalg.norm(data.qpos[7:11])
        data.qpos[11:] = rng.normal(size=2)
        data.qvel[:] = rng.normal(size=mm.nv) * 2.0
        mujoco.mj_forward(mm, data)
        q, v = mujoco_to_pinocchio(robot, data.qpos, data.qvel)
        T = pin.computeKineticEnergy(robot.model, pd, q, v)
        assert abs(T - data.energy[1]) <= 1e-9 * max(1.0, data.energy[1])
        V = pin.computePotentialEnergy(robot.model, pd, q)
        assert abs(V - data.energy[0]) <= 1e-9 * max(1.0, abs(data.energy[0]))
        pin.framesForwardKinematics(robot.model, pd, q)
        for name in ("tip0", "tip"):
            sid = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_SITE, name)
            assert np.allclose(pd.oMf[robot.frame_id(name)].translation, data.site_xpos[sid],
                               atol=1e-12)
        naive_errors.append(abs(pin.computeKineticEnergy(robot.model, pd, q, data.qvel)
                                - data.energy[1]))
    assert max(naive_errors) > 1e-2  # the base's linear velocity must be rotated


def test_rod_landing_matches_closed_form_and_stiff_contact(mujoco, tmp_path) -> None:
    """A rod landing on its sphere foot: one touchdown; the prediction equals the rigid-body
    formula to 1e-9 and closes its books to 1e-10; the recorded losses are the stated
    differences; MuJoCo's stiff inelastic contact loses T_c to within 2%."""
    path = _rod_file(tmp_path)
    robot = load_mjcf(path)
    qpos, qvel = _rod_start()
    traj = mujoco_rollout(path, duration=0.012, robot=robot, qpos=qpos, qvel=qvel)
    assert np.allclose(kinetic_energy(robot, traj), traj.reference_kinetic, rtol=1e-9)
    foot = ContactSpec(frame="foot", kind="arc", radius=RADIUS)
    result = replay(robot, traj, [foot], window=0.002)
    assert len(result.touchdowns) == 1
    d = result.touchdowns[0]
    assert d.strike == ("foot",) and d.keep == ()
    k = d.index_pre
    # the pre-impact state is the last sample above the ground, the next one below it
    assert result.heights[k, 0] > 0.0 >= result.heights[k + 1, 0]
    # independent prediction from the MJCF's numbers and MuJoCo's own recorded state
    mm = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(mm)
    mujoco.mj_resetData(mm, data)
    data.qpos[:], data.qvel[:] = qpos, qvel
    mujoco.mj_step(mm, data, nstep=k)
    R = _quat_matrix(data.qpos[3:7])
    T_c = _rod_T_c(R, data.qvel[:3].copy(), R @ data.qvel[3:6])
    assert d.T_c == pytest.approx(T_c, rel=1e-9)
    # books of the prediction, and the recorded losses exactly as stated
    assert abs(d.T - d.T_c - d.T_a) <= 1e-10 * d.T
    assert abs(sum(d.T_c_contact) - d.T_c) <= 1e-10 * d.T
    assert d.recorded_loss == result.kinetic[k] - result.kinetic[d.index_post]
    assert d.mechanical_loss == pytest.approx(
        d.recorded_loss + result.potential[k] - result.potential[d.index_post], abs=1e-12)
    assert d.time_post - d.time_pre >= 0.002 - 1e-12
    # a sticking, inelastic rigid impact stops the contact point: all of T_c is lost
    assert d.predicted_loss == pytest.approx(d.T_c, rel=1e-9)
    assert abs(d.predicted_normal_velocity[0]) < 1e-9
    # MuJoCo's stiff contact (0.5 ms, critically damped): the penetration (~0.5 mm) and the
    # rotation over the transient are small, so the energy lost without gravity's work is the
    # rigid T_c to within 2% (measured 0.7%; the rest is the friction cone's softness); the
    # foot does not bounce back (effective restitution 0.09 two milliseconds after touchdown)
    assert d.mechanical_loss == pytest.approx(d.T_c, rel=0.02)
    assert 0.0 <= d.effective_restitution[0] < 0.15
    # a rod falling vertically loses everything, one lying flat a quarter: T_c is not T
    assert 0.3 * d.T < d.T_c < 0.8 * d.T


def _compass_rollout(tmp_path):
    """The compass dropped with foot a 1 mm above the ground (leg a 0.25 rad from the
    vertical, legs 0.6 rad apart), moving at (0.5, 0, -0.5) m/s, for 0.1 s: robot, record."""
    path = tmp_path / "compass.xml"
    path.write_text(_on_floor("compass", COMPASS_BODIES))
    robot = load_mjcf(path)
    tilt, spread = -0.25, 0.6
    qpos = np.array([0.0, 0.0, 0.5 * np.cos(tilt) + 0.006, np.cos(tilt / 2), 0.0,
                     np.sin(tilt / 2), 0.0, spread])
    qvel = np.array([0.5, 0.0, -0.5, 0.0, 0.0, 0.0, 0.0])
    return robot, mujoco_rollout(path, duration=0.1, robot=robot, qpos=qpos, qvel=qvel,
                                 every=2)


COMPASS_FEET = [ContactSpec(frame=f, kind="arc", radius=RADIUS) for f in ("a", "b")]


def _compass_replay(tmp_path):
    """The compass's replay (height signal, 2 ms window)."""
    robot, traj = _compass_rollout(tmp_path)
    return replay(robot, traj, COMPASS_FEET, window=0.002)


def test_compass_second_foot_lands_with_the_first_kept(mujoco, tmp_path) -> None:
    """A compass landing on foot a, then pivoting onto foot b: two touchdowns, the second
    keeps a. Its motion is planar (x-z) and, with both feet pinned, only a rotation about
    the line through the feet (in the x-z plane) remains, which planar momentum does not
    reach: the rigid law takes everything, T_a = 0. MuJoCo's stiff contact agrees within 3%
    (measured: 0.07% and 1.5%)."""
    result = _compass_replay(tmp_path)
    assert [(d.strike, d.keep) for d in result.touchdowns] == [(("a",), ()), (("b",), ("a",))]
    first, second = result.touchdowns
    for d in result.touchdowns:
        assert abs(d.T - d.T_c - d.T_a) <= 1e-10 * d.T
        assert d.admissible and d.note == ""
        assert d.mechanical_loss == pytest.approx(d.T_c, rel=0.03)
    assert 0.1 * first.T < first.T_c < 0.9 * first.T
    assert second.T_a <= 1e-9 * second.T


def test_mujoco_contact_list_finds_the_same_touchdowns(mujoco, tmp_path) -> None:
    """The contact-list signal (the geom named like the frame entering MuJoCo's contact
    list) finds the compass's touchdowns at the same samples as the height signal (sphere
    geoms of the arcs' radius: MuJoCo lists a contact when the sphere's lowest point is below
    the floor); a log has no contact list."""
    robot, rollout = _compass_rollout(tmp_path)
    by_height = replay(robot, rollout, COMPASS_FEET, window=0.002)
    log = dataclasses.replace(rollout, contact_geoms=(), touching=None)
    with pytest.raises(ValueError, match="needs a MuJoCo rollout"):
        replay(robot, log, COMPASS_FEET, signal="mujoco")
    assert rollout.contact_geoms == ("a", "b")
    by_list = replay(robot, rollout, COMPASS_FEET, window=0.002, signal="mujoco")
    assert [(d.index_pre, d.strike, d.keep) for d in by_list.touchdowns] == [
        (d.index_pre, d.strike, d.keep) for d in by_height.touchdowns]
    for a, b in zip(by_list.touchdowns, by_height.touchdowns, strict=True):
        assert a.T_c == b.T_c and a.time == rollout.time[a.index_pre + 1]
    with pytest.raises(ValueError, match="no geom named 'leg_b'"):
        replay(robot, rollout, [ContactSpec(frame="leg_b")], signal="mujoco")


def test_a_refused_prediction_is_reported_not_raised(mujoco, tmp_path, monkeypatch) -> None:
    """Where the impact law refuses a touchdown's contacts, that touchdown has NaN
    predictions and a note (None in JSON); the recorded numbers are still there."""
    import heelstrike.robots.replay as module
    from heelstrike.core.impact import ImpactInputError

    def refuse(*args, **kwargs):
        raise ImpactInputError("contact rows are rank deficient")

    path = _rod_file(tmp_path)
    robot = load_mjcf(path)
    qpos, qvel = _rod_start()
    traj = mujoco_rollout(path, duration=0.004, robot=robot, qpos=qpos, qvel=qvel)
    monkeypatch.setattr(module, "robot_impact", refuse)
    foot = ContactSpec(frame="foot", kind="arc", radius=RADIUS)
    (d,) = replay(robot, traj, [foot], window=0.002).touchdowns
    assert np.isnan(d.T_c) and "rank deficient" in d.note and not d.admissible
    assert d.recorded_loss > 0.0
    item = json.loads(json.dumps(replay(robot, traj, [foot], window=0.002).to_dict(),
                                 allow_nan=False))["touchdowns"][0]
    assert item["T_c"] is None and item["recorded_loss"] > 0.0


def test_soft_contact_needs_a_longer_window(mujoco, tmp_path) -> None:
    """With MuJoCo's default soft contact (time constant 20 ms) the transient is not over
    after 2 ms: the recorded loss is far from T_c; it is there after a window of 10 ms (and
    the window is measured from the pre-impact sample)."""
    path = _rod_file(tmp_path, dt=2e-3, tc=0.02)
    robot = load_mjcf(path)
    qpos, qvel = _rod_start()
    traj = mujoco_rollout(path, duration=0.05, robot=robot, qpos=qpos, qvel=qvel)
    foot = ContactSpec(frame="foot", kind="arc", radius=RADIUS)
    short = replay(robot, traj, [foot], window=0.002).touchdowns[0]
    long = replay(robot, traj, [foot], window=0.01).touchdowns[0]
    assert short.mechanical_loss < 0.2 * short.T_c
    assert long.mechanical_loss == pytest.approx(long.T_c, rel=0.05)


def test_logs_round_trip_in_both_conventions(mujoco, tmp_path) -> None:
    """NPZ and CSV logs read back to the trajectory written; a log of MuJoCo's qpos/qvel read
    with convention='mujoco' gives Pinocchio's q/v."""
    path = _rod_file(tmp_path)
    robot = load_mjcf(path)
    qpos, qvel = _rod_start()
    traj = mujoco_rollout(path, duration=0.004, robot=robot, qpos=qpos, qvel=qvel, every=5)
    assert traj.time.size == 9
    for name in ("log.npz", "log.csv"):
        back = read_trajectory(write_trajectory(traj, tmp_path / name), robot)
        assert np.array_equal(back.time, traj.time)
        assert np.array_equal(back.q, traj.q) and np.array_equal(back.v, traj.v)
    mm = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(mm)
    data.qpos[:], data.qvel[:] = qpos, qvel
    qp, qv = [], []
    for _ in range(9):
        qp.append(data.qpos.copy())
        qv.append(data.qvel.copy())
        mujoco.mj_step(mm, data, nstep=5)
    np.savez(tmp_path / "mj.npz", t=traj.time, q=np.array(qp), v=np.array(qv))
    mapped = read_trajectory(tmp_path / "mj.npz", robot, convention="mujoco")
    assert np.allclose(mapped.q, traj.q, atol=1e-12) and np.allclose(mapped.v, traj.v,
                                                                      atol=1e-12)


def test_hdf5_logs_round_trip_and_replay_as_the_npz(mujoco, tmp_path, capsys) -> None:
    """An HDF5 log (root datasets or a named group) reads back to the trajectory written, and
    ``robot replay LOG.h5`` gives the same touchdown numbers as the NPZ of the same record."""
    h5py = pytest.importorskip("h5py")
    path = _rod_file(tmp_path)
    robot = load_mjcf(path)
    qpos, qvel = _rod_start()
    traj = mujoco_rollout(path, duration=0.01, robot=robot, qpos=qpos, qvel=qvel)
    back = read_trajectory(write_trajectory(traj, tmp_path / "log.h5"), robot)
    assert np.array_equal(back.time, traj.time)
    assert np.array_equal(back.q, traj.q) and np.array_equal(back.v, traj.v)
    with h5py.File(tmp_path / "runs.hdf5", "w") as f:
        g = f.create_group("trials/run3")
        for key, arr in (("t", traj.time), ("q", traj.q), ("v", traj.v)):
            g.create_dataset(key, data=arr)
    grouped = read_trajectory(f"{tmp_path / 'runs.hdf5'}#/trials/run3", robot)
    assert np.array_equal(grouped.q, traj.q) and np.array_equal(grouped.v, traj.v)
    assert grouped.source.endswith("runs.hdf5#/trials/run3")
    write_trajectory(traj, tmp_path / "log.npz")
    results = []
    for name in ("log.npz", "log.h5"):
        assert main(["robot", "replay", str(tmp_path / name), "--model", str(path),
                     "--contact", "foot:arc:0.005", "--window", "0.002", "--json"]) == 0
        results.append(json.loads(capsys.readouterr().out)["touchdowns"])
    assert len(results[0]) == 1 and results[0] == results[1]


def test_hdf5_log_refusals_name_what_is_missing(tmp_path, monkeypatch) -> None:
    """A missing group or dataset is named with what the file holds; a group in a non-HDF5
    path is refused; without h5py the message names the 'hdf5' extra."""
    h5py = pytest.importorskip("h5py")
    robot = load_mjcf(_rod_file(tmp_path))
    with h5py.File(tmp_path / "log.h5", "w") as f:
        f.create_dataset("t", data=np.arange(3.0))
        f.create_dataset("q", data=np.zeros((3, robot.nq)))
        f.create_group("other")
    with pytest.raises(ValueError, match=r"no dataset v \(needs t, q, v; found q, t\)"):
        read_trajectory(tmp_path / "log.h5", robot)
    with pytest.raises(ValueError, match=r"no group '/run9' \(groups: /, /other\)"):
        read_trajectory(f"{tmp_path / 'log.h5'}#/run9", robot)
    np.savez(tmp_path / "log.npz", t=np.arange(3.0), q=np.zeros((3, robot.nq)),
             v=np.zeros((3, robot.nv)))
    with pytest.raises(ValueError, match="does not exist"):
        read_trajectory(f"{tmp_path / 'log.npz'}#/run", robot)
    (tmp_path / "bad.h5").write_text("not hdf5")
    with pytest.raises(ValueError, match="not an HDF5 file"):
        read_trajectory(tmp_path / "bad.h5", robot)
    with h5py.File(tmp_path / "odd.h5", "w") as f:
        g = f.create_group("runs/run#1")  # a '#' in a group's name
        g.create_dataset("t", data=np.arange(3.0))
        g.create_dataset("q", data=np.zeros((3, robot.nq)))
        g.create_dataset("v", data=np.zeros((3, robot.nv)) + 1j)
        h = f.create_group("wide")
        h.create_dataset("t", data=np.zeros((2, 3)))
        h.create_dataset("q", data=np.zeros((3, robot.nq)))
        h.create_dataset("v", data=np.zeros((3, robot.nv)))
    with pytest.raises(ValueError, match=r"must be real numbers; v \(complex128\) is not"):
        read_trajectory(f"{tmp_path / 'odd.h5'}#/runs/run#1", robot)
    with pytest.raises(ValueError, match=r"t must be one row of sample times"):
        read_trajectory(f"{tmp_path / 'odd.h5'}#wide", robot)
    monkeypatch.setitem(sys.modules, "h5py", None)
    with pytest.raises(MissingExtraError, match=r"the 'hdf5' extra: pip install '\.\[hdf5\]'"):
        read_trajectory(tmp_path / "log.h5", robot)


def test_touchdowns_ignore_chatter_and_keep_the_stance() -> None:
    """A contact hovering around the ground within the clearance touches down once; a second
    contact landing later finds the first on the ground (kept)."""
    h = np.array([[0.01, 0.05], [0.001, 0.04], [-1e-4, 0.03], [2e-4, 0.02], [-1e-4, 0.01],
                  [-2e-4, 0.001], [-1e-4, -1e-4], [0.02, -2e-4], [0.01, -1e-4],
                  [-1e-3, -1e-4]])
    events = detect_touchdowns(h, clearance=1e-3)
    assert events == [(1, (0,), ()), (5, (1,), (0,)), (8, (0,), (1,))]
    # without a clearance the chatter counts as touchdowns
    assert len(detect_touchdowns(h, clearance=0.0)) == 4


@pytest.mark.parametrize("cls", [Trajectory, Touchdown, ReplayResult])
def test_results_are_frozen_keyword_only_with_to_dict(cls) -> None:
    assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen
    assert issubclass(cls, ResultDictMixin)
    with pytest.raises(TypeError):
        cls(*range(len(dataclasses.fields(cls))))


def test_trajectory_refuses_bad_input(tmp_path) -> None:
    with pytest.raises(ValueError, match="increase"):
        Trajectory(time=np.array([0.0, 0.0]), q=np.zeros((2, 8)), v=np.zeros((2, 7)))
    with pytest.raises(ValueError, match="one row per sample"):
        Trajectory(time=np.array([0.0, 1.0]), q=np.zeros((3, 8)), v=np.zeros((2, 7)))


def test_missing_mujoco_names_the_extra(tmp_path, monkeypatch) -> None:
    """Without the mujoco package a rollout fails with one line naming the install."""
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(MissingExtraError,
                       match=r"the 'mujoco' extra: pip install '\.\[mujoco\]'"):
        mujoco_rollout(_rod_file(tmp_path), duration=0.01)


def test_cli_defaults_are_the_api_defaults() -> None:
    from heelstrike.cli import replay as cli_replay
    from heelstrike.robots import replay as api_replay

    assert cli_replay.DEFAULT_WINDOW == api_replay.DEFAULT_WINDOW
    assert cli_replay.DEFAULT_CLEARANCE == api_replay.DEFAULT_CLEARANCE


def test_cli_robot_replay(mujoco, tmp_path, capsys) -> None:
    """``robot replay MJCF`` simulates and tabulates; ``--out`` writes the figure, the table
    and the trajectory, which ``robot replay LOG --model`` reads back to the same numbers."""
    path = tmp_path / "rod.xml"
    qpos, qvel = _rod_start()
    text = _rod_file(tmp_path).read_text().replace(
        "</mujoco>", f"<keyframe><key qpos=\"{' '.join(f'{x:.17g}' for x in qpos)}\" "
        f"qvel=\"{' '.join(f'{x:.17g}' for x in qvel)}\"/></keyframe></mujoco>")
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["robot", "replay", str(path), "--contact", "foot:arc:0.005", "--duration",
                 "0.01", "--window", "0.002", "--out", str(out), "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert len(first["touchdowns"]) == 1 and first["friction"] is None
    assert first["units"]["touchdowns"]["T_c"] == "J"
    assert {p.name for p in out.iterdir()} == {"replay.png", "touchdowns.csv",
                                               "trajectory.npz"}
    assert "recorded_loss_J" in (out / "touchdowns.csv").read_text().splitlines()[0]
    assert main(["robot", "replay", str(path), "--contact", "foot:arc:0.005", "--duration",
                 "0.01", "--window", "0.002", "--signal", "mujoco", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["touchdowns"][0]["index_pre"] == \
        first["touchdowns"][0]["index_pre"]
    assert main(["robot", "replay", str(out / "trajectory.npz"), "--model", str(path),
                 "--contact", "foot:arc:0.005", "--window", "0.002"]) == 0
    table = capsys.readouterr().out
    d = first["touchdowns"][0]
    assert f"{d['T_c']:.5g}" in table and f"{d['recorded_loss']:.5g}" in table
    assert main(["robot", "replay", str(out / "trajectory.npz"), "--contact",
                 "foot:arc:0.005"]) == 2
    assert "needs --model" in capsys.readouterr().err
    assert main(["robot", "replay", str(path), "--contact", "foot:arc:0.005", "--out",
                 str(out / "replay.png")]) == 2
    assert "is not a directory" in capsys.readouterr().err


def test_replay_figure_draws_both_losses_and_is_readable(mujoco, tmp_path) -> None:
    """The figure's bars hang from the pre-impact energy by T_c (predicted) and by the
    recorded loss; axes labelled with units; data clear of the legend."""
    from heelstrike.plots.replay import plot_replay
    from test_figure_bounds import assert_figure_is_readable

    result = _compass_replay(tmp_path)
    fig = plot_replay(result)
    assert_figure_is_readable(fig)
    (ax,) = fig.axes
    assert ax.get_xlabel() == "time (s)" and ax.get_ylabel() == "kinetic energy (J)"
    spans = sorted(float(np.ptp(seg[:, 1])) for c in ax.collections for seg in c.get_segments())
    expected = sorted(x for d in result.touchdowns for x in (d.T_c, d.recorded_loss))
    assert np.allclose(spans, expected, rtol=1e-12)
