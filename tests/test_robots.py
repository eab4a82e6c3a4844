"""Robots through Pinocchio (heelstrike[robots]): loading, contacts, laws, studies, command line.

Marked ``robots``; CI installs the extra, so these run there (a missing Pinocchio fails under
``CI``). Elsewhere, without Pinocchio, they skip.
"""

from __future__ import annotations

import json
import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

try:
    import pinocchio as pin
except ImportError:
    if os.environ.get("CI"):  # CI installs heelstrike[robots]: these tests must run there
        raise
    pytest.skip("needs heelstrike[robots] (pin, example-robot-data)", allow_module_level=True)

from heelstrike.cli import main
from heelstrike.core.contact_laws import ContactRows, resolve_contact_impact
from heelstrike.core.impact import ImpactInputError, impact
from heelstrike.models.compass import CompassGait, heel_strike_state
from heelstrike.plots.robots import plot_robot_study
from heelstrike.robots import (
    ContactSpec,
    RobotError,
    contact_jacobian,
    inert_energy_split_batch,
    inert_impact_batch,
    list_robots,
    load_mjcf,
    load_robot,
    load_urdf,
    mass_matrices_and_jacobians,
    parse_contact,
    robot_data_dir,
    robot_impact,
    robot_matrices,
)
from heelstrike.robots.states import gait_state
from heelstrike.robots.study import robot_heel_strike_study

pytestmark = pytest.mark.robots

ROBOTS = ("talos", "g1", "bolt")


@pytest.fixture(scope="module")
def robots() -> dict[str, object]:
    return {name: load_robot(name) for name in ROBOTS}


def _random_state(robot, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Random admissible state: reference pose perturbed (base orientation too), random v."""
    rng = np.random.default_rng(seed)
    dq = 0.2 * rng.standard_normal(robot.nv)
    q = np.array(pin.integrate(robot.model, robot.reference_q, dq))
    lo, hi = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    q[7:] = np.clip(q[7:], lo[7:], hi[7:])
    return q, rng.standard_normal(robot.nv)


def _feet(robot) -> list[ContactSpec]:
    return [ContactSpec(frame=f, kind=robot.foot_contact) for f in robot.feet]  # type: ignore[arg-type]


# -- loading ---------------------------------------------------------------------------------
def test_shipped_robots_load_offline_with_a_free_flyer(robots) -> None:
    listed = {r["name"]: r for r in list_robots()}
    assert set(ROBOTS) <= set(listed)
    for name, r in robots.items():
        assert listed[name]["nq"] == r.nq == r.nv + 1
        assert r.model.joints[1].shortname() == "JointModelFreeFlyer"
        assert Path(listed[name]["source"]).is_file()
        assert str(robot_data_dir()) in listed[name]["source"]
        assert listed[name]["mass"] == pytest.approx(
            sum(i.mass for i in r.model.inertias), rel=1e-12)
        assert r.mass > 0


def test_talos_reference_is_half_sitting_from_its_srdf(robots) -> None:
    talos = robots["talos"]
    assert Path(talos.source).name == "talos_reduced.urdf"
    srdf = robot_data_dir() / "talos_data/srdf/talos.srdf"
    state = next(s for s in ET.parse(srdf).getroot().iter("group_state")
                 if s.get("name") == "half_sitting")
    checked = 0
    for j in state.iter("joint"):
        vals = [float(x) for x in j.get("value", "").split()]
        name = j.get("name")
        if not talos.model.existJointName(name):
            continue
        jid = talos.model.getJointId(name)
        iq = talos.model.joints[jid].idx_q
        np.testing.assert_allclose(talos.reference_q[iq:iq + len(vals)], vals)
        checked += 1
    assert checked >= 20


def test_mass_matrix_is_crba_symmetrised(robots) -> None:
    talos = robots["talos"]
    q, _ = _random_state(talos, 0)
    M = talos.mass_matrix(q)
    np.testing.assert_array_equal(M, M.T)
    data = talos.model.createData()
    v = np.random.default_rng(1).standard_normal(talos.nv)
    # kinetic energy from the mass matrix equals Pinocchio's own
    assert 0.5 * v @ M @ v == pytest.approx(
        pin.computeKineticEnergy(talos.model, data, q, v), rel=1e-12)


# -- the inert law against Pinocchio ---------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("seed", range(3))
def test_bilateral_inert_impact_equals_pinocchio_impulse_dynamics(robots, name, seed) -> None:
    robot = robots[name]
    q, v = _random_state(robot, seed)
    res = robot_impact(robot, q, v, strike=[], keep=_feet(robot))
    data = robot.model.createData()
    J = np.vstack(res.jacobians)
    v_pin = np.array(pin.impulseDynamics(robot.model, data, q, v, J, 0.0, 0.0))
    r = res.result
    tol = 1e-12 * max(1.0, np.abs(v_pin).max())
    np.testing.assert_allclose(r.velocity_post, v_pin, rtol=0, atol=tol)
    np.testing.assert_allclose(r.impulse, np.array(data.impulse_c), rtol=1e-9,
                               atol=1e-9 * np.abs(r.impulse).max())
    M = res.M
    T = 0.5 * v @ M @ v
    assert r.T == pytest.approx(T, rel=1e-12)
    assert r.T_c + r.T_a == pytest.approx(T, rel=1e-12)
    assert r.T_a == pytest.approx(0.5 * v_pin @ M @ v_pin, rel=1e-10)  # inert: T_a is kept
    assert r.T_c_normal.sum() + r.T_c_tangential.sum() == pytest.approx(r.T_c, rel=1e-10)
    # the batched path gives the same numbers
    b = inert_impact_batch(robot, q[None], v[None], _feet(robot))
    np.testing.assert_allclose(b.velocity_post[0], v_pin, rtol=0, atol=tol)


# -- the direct (fast) inert path against the reference path -----------------------------------
def _reference_inert(robot, q, v, specs: list[ContactSpec]):
    """The reference path: M from ``mass_matrix``, rows from ``contact_jacobian`` after
    ``updateFramePlacements``, all contacts bilateral through ``resolve_contact_impact``."""
    q_, v_ = robot.check_state(q, v)
    data = robot.model.createData()
    M = robot.mass_matrix(q_, data)
    pin.computeJointJacobians(robot.model, data, q_)
    pin.updateFramePlacements(robot.model, data)
    rows = [ContactRows(jacobian=contact_jacobian(robot, data, c), normal=c.normal,
                        tangential=c.tangential, tangential_weights=c.tangential_weights,
                        bilateral=True, name=c.frame) for c in specs]
    return resolve_contact_impact(M, v_, rows), M, [r.jacobian for r in rows]


def _assert_same(fast, ref, tol: float = 1e-12) -> None:
    scale_v = max(1.0, float(np.abs(ref.velocity_post).max()))
    np.testing.assert_allclose(fast.velocity_post, ref.velocity_post, rtol=0, atol=tol * scale_v)
    np.testing.assert_allclose(fast.impulse, ref.impulse, rtol=0,
                               atol=tol * float(np.abs(ref.impulse).max()))
    for key in ("T", "T_c", "T_a", "T_post", "energy_lost"):
        assert abs(float(getattr(fast, key)) - getattr(ref, key)) <= tol * ref.T, key
    for key in ("T_c_normal", "T_c_tangential"):
        np.testing.assert_allclose(getattr(fast, key), getattr(ref, key), rtol=0, atol=tol * ref.T)


def _mixed_contacts(robot) -> list[ContactSpec]:
    """The feet as the robot's natural contact, plus an arc heel and a point on the base."""
    left, right = robot.feet
    other = next(str(f.name) for f in robot.model.frames if f.parentJoint == 1)
    return [ContactSpec(frame=left, kind=robot.foot_contact),  # type: ignore[arg-type]
            ContactSpec(frame=right, kind="arc", radius=0.05),
            ContactSpec(frame=other, kind="point")]


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("seed", range(3))
def test_direct_inert_robot_impact_equals_the_reference_path(robots, name, seed) -> None:
    robot = robots[name]
    q, v = _random_state(robot, 100 + seed)
    for specs in (_feet(robot), _mixed_contacts(robot)):
        res = robot_impact(robot, q, v, strike=[], keep=specs)
        ref, M, jacs = _reference_inert(robot, q, v, specs)
        _assert_same(res.result, ref)
        assert res.result.modes == ref.modes
        np.testing.assert_array_equal(res.M, M)  # the same crba, symmetrised the same way
        for J_fast, J_ref in zip(res.jacobians, jacs, strict=True):
            np.testing.assert_array_equal(J_fast, J_ref)
        for u_fast, u_ref in zip(res.result.contact_velocity_post, ref.contact_velocity_post,
                                 strict=True):
            np.testing.assert_allclose(u_fast, u_ref, rtol=0,
                                       atol=1e-12 * max(1.0, float(np.abs(v).max())))


@pytest.mark.parametrize("name", ["talos", "bolt"])
def test_batched_energy_split_equals_the_reference_path(robots, name) -> None:
    robot = robots[name]
    states = [_random_state(robot, 200 + i) for i in range(7)]
    qs = np.stack([s[0] for s in states])
    vs = np.stack([s[1] for s in states])
    specs = _mixed_contacts(robot)
    batch = inert_energy_split_batch(robot, qs, vs, specs, chunk=3)  # chunks of 3, 3, 1
    assert batch.velocity_post.shape == (7, robot.nv)
    assert batch.T_c_normal.shape == batch.T_c_tangential.shape == (7, 3)
    for i, (q, v) in enumerate(states):
        ref, _, _ = _reference_inert(robot, q, v, specs)
        row = type("Row", (), {})()
        for key in ("velocity_post", "impulse", "T", "T_c", "T_a", "T_post", "energy_lost",
                    "T_c_normal", "T_c_tangential"):
            setattr(row, key, getattr(batch, key)[i])
        _assert_same(row, ref)


def test_batched_assembly_equals_mass_matrix_and_contact_jacobian(robots) -> None:
    talos = robots["talos"]
    states = [_random_state(talos, 300 + i) for i in range(4)]
    qs = np.stack([s[0] for s in states])
    qs[1, 3:7] *= 1.2  # a quaternion that is normalised on the way in
    specs = _mixed_contacts(talos)
    Ms, As = mass_matrices_and_jacobians(talos, qs, specs)
    data = talos.model.createData()
    for q, M, A in zip(qs, Ms, As, strict=True):
        q_, _ = talos.check_state(q)
        np.testing.assert_allclose(M, talos.mass_matrix(q_, data), rtol=0, atol=1e-13)
        pin.computeJointJacobians(talos.model, data, q_)
        pin.updateFramePlacements(talos.model, data)
        ref = np.vstack([contact_jacobian(talos, data, c) for c in specs])
        np.testing.assert_allclose(A, ref, rtol=0, atol=1e-13)
        np.testing.assert_array_equal(M, M.T)
        M1, A1 = robot_matrices(talos, q, specs)
        np.testing.assert_array_equal(M1, talos.mass_matrix(q_, data))
        np.testing.assert_array_equal(A1, ref)
    np.testing.assert_allclose(talos.check_states(qs),
                               np.stack([talos.check_state(q)[0] for q in qs]), atol=1e-15)
    bad = qs.copy()
    bad[2, 3:7] = 0.0
    with pytest.raises(RobotError, match=r"unit quaternion.*configuration 2"):
        talos.check_states(bad)
    with pytest.raises(RobotError, match="nq=39"):
        talos.check_states(qs[:, :-1])


def test_direct_path_rejects_redundant_contacts_like_the_reference(robots) -> None:
    talos = robots["talos"]
    q, v = _random_state(talos, 5)
    twice = [ContactSpec(frame=talos.feet[0], kind="flat"),
             ContactSpec(frame=talos.feet[0], kind="point")]
    with pytest.raises(ImpactInputError, match="rank deficient"):
        _reference_inert(talos, q, v, twice)
    with pytest.raises(ImpactInputError, match="rank deficient"):
        robot_impact(talos, q, v, strike=[], keep=twice)
    with pytest.raises(ImpactInputError, match="rank deficient"):
        inert_energy_split_batch(talos, q[None], v[None], twice)
    with pytest.raises(RobotError, match="velocities"):
        inert_energy_split_batch(talos, q[None], v[None, :-1], _feet(talos))


def _momentum_about(robot, q, v, point) -> tuple[np.ndarray, np.ndarray]:
    data = robot.model.createData()
    h = pin.computeCentroidalMomentum(robot.model, data, q, v)
    c = np.array(data.com[0])
    lin, ang = np.array(h.linear), np.array(h.angular)
    return lin, ang + np.cross(c - point, lin)


@pytest.mark.parametrize("seed", range(3))
def test_momentum_changes_only_by_the_contact_impulse(robots, seed) -> None:
    talos = robots["talos"]
    q, v = _random_state(talos, 10 + seed)
    data = talos.model.createData()
    pin.framesForwardKinematics(talos.model, data, q)
    # one point contact with finite friction: angular momentum about it is conserved
    foot = "left_sole_link"
    p = np.array(data.oMf[talos.model.getFrameId(foot)].translation)
    res = robot_impact(talos, q, -v, strike=[ContactSpec(frame=foot)], friction=0.4)
    r = res.result
    if r.modes[0] == "separate":
        res = robot_impact(talos, q, v, strike=[ContactSpec(frame=foot)], friction=0.4)
        r = res.result
    assert r.modes[0] in ("stick", "slip")
    lin0, ang0 = _momentum_about(talos, q, r.velocity_pre, p)
    lin1, ang1 = _momentum_about(talos, q, r.velocity_post, p)
    np.testing.assert_allclose(lin1 - lin0, r.impulse, atol=1e-9 * np.abs(lin0).max())
    np.testing.assert_allclose(ang1, ang0, atol=1e-9 * np.abs(ang0).max())
    # two flat soles: linear by the sum of forces, angular about a point by their moments
    res2 = robot_impact(talos, q, v, strike=[], keep=_feet(talos))
    lam = res2.result.impulse.reshape(2, 6)
    o = np.zeros(3)
    lin0, ang0 = _momentum_about(talos, q, v, o)
    lin1, ang1 = _momentum_about(talos, q, res2.result.velocity_post, o)
    np.testing.assert_allclose(lin1 - lin0, lam[:, :3].sum(axis=0), atol=1e-9 * np.abs(lam).max())
    moment = np.zeros(3)
    for i, f in enumerate(talos.feet):
        pf = np.array(data.oMf[talos.model.getFrameId(f)].translation)
        moment += np.cross(pf - o, lam[i, :3]) + lam[i, 3:]
    np.testing.assert_allclose(ang1 - ang0, moment, atol=1e-9 * np.abs(lam).max())


# -- friction and restitution on a robot ------------------------------------------------------
def test_friction_limits_on_talos(robots) -> None:
    talos = robots["talos"]
    q, v = gait_state(talos, 0.4, 0.4, swing_forward_speed=0.3)  # the heel slides forward
    strike = [ContactSpec(frame="left_sole_link", kind="point")]
    keep = [ContactSpec(frame="right_sole_link", kind="flat")]
    stick = robot_impact(talos, q, v, strike=strike, keep=keep, friction=1e9).result
    inert = robot_impact(talos, q, v, strike=[], keep=strike + keep).result
    assert stick.modes[0] == "stick"
    np.testing.assert_allclose(stick.velocity_post, inert.velocity_post, atol=1e-10)
    free = robot_impact(talos, q, v, strike=strike, keep=keep, friction=0.0).result
    data = talos.model.createData()
    pin.computeJointJacobians(talos.model, data, q)
    pin.updateFramePlacements(talos.model, data)
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    Jl = np.array(pin.getFrameJacobian(talos.model, data, talos.model.getFrameId(
        "left_sole_link"), lwa))
    Jr = np.array(pin.getFrameJacobian(talos.model, data, talos.model.getFrameId(
        "right_sole_link"), lwa))
    ref = impact(free_M := talos.mass_matrix(q), np.vstack((Jl[2:3], Jr)), v)
    np.testing.assert_allclose(free.velocity_post, ref.velocity_post, atol=1e-10)
    assert free.T_c == pytest.approx(float(ref.kinetic_energy_constrained), rel=1e-10)
    modes = set()
    for mu in (0.02, 0.05, 0.1, 0.3, 1.0):
        r = robot_impact(talos, q, v, strike=strike, keep=keep, friction=mu).result
        lam = r.impulse[:3]
        modes.add(r.modes[0])
        assert np.all(np.abs(lam[:2]) <= mu * lam[2] * (1 + 1e-9))  # the pyramid cone
        assert r.T_post <= r.T * (1 + 1e-12)
        assert r.kkt_residual < 1e-9
        if r.modes[0] == "slip":
            slip = r.contact_velocity_post[0][:2]
            assert lam[:2] @ slip < 0
            for a in (0, 1):  # a sliding row: on the cone's edge, against its slip
                if abs(slip[a]) > 1e-9:
                    assert lam[a] == pytest.approx(-mu * lam[2] * np.sign(slip[a]), rel=1e-9)
        # linear momentum changes by the striking and the kept contacts' forces
        lin0, _ = _momentum_about(talos, q, v, np.zeros(3))
        lin1, _ = _momentum_about(talos, q, r.velocity_post, np.zeros(3))
        np.testing.assert_allclose(lin1 - lin0, lam + r.impulse[3:6], atol=1e-9)
    assert free_M.shape == (talos.nv, talos.nv)
    assert "slip" in modes


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_restitution_per_contact_on_g1(robots, e) -> None:
    g1 = robots["g1"]
    q, v = gait_state(g1, 0.3, 0.5)
    strike = [ContactSpec(frame=g1.feet[0], kind="point")]
    keep = [ContactSpec(frame=g1.feet[1], kind="flat")]
    r = robot_impact(g1, q, v, strike=strike, keep=keep, friction=0.0, restitution=e).result
    assert r.modes[0] == "slip"
    u_minus = r.contact_velocity_pre[0][2]
    assert u_minus < 0
    assert r.contact_velocity_post[0][2] == pytest.approx(-e * u_minus, rel=1e-9)
    assert r.energy_lost == pytest.approx((1 - e * e) * r.T_c, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("L", [0.1, 0.3])
def test_trailing_foot_lift_is_decided(robots, name, L) -> None:
    robot = robots[name]
    q, v = gait_state(robot, L, 0.4)
    lead, trail = (ContactSpec(frame=f, kind="point") for f in robot.feet)
    r = robot_impact(robot, q, v, strike=[lead, trail], friction=0.8).result
    assert r.modes[0] != "separate"  # the descending sole strikes
    lam = r.impulse.reshape(2, 3)
    u_trail = r.contact_velocity_post[1]
    if r.modes[1] == "separate":  # lifts: no impulse, moving up (or grazing)
        np.testing.assert_array_equal(lam[1], 0.0)
        assert u_trail[2] >= -1e-12
    else:  # stays: pushes, does not penetrate, inside the cone
        assert lam[1, 2] > 0 and u_trail[2] == pytest.approx(0.0, abs=1e-10)
        assert np.all(np.abs(lam[1, :2]) <= 0.8 * lam[1, 2] * (1 + 1e-9))  # pyramid
    # the paper's way (trailing foot left free): where it lifts, the decided law agrees
    free = robot_impact(robot, q, v, strike=[lead], friction=0.8).result
    if contact_velocity(robot, q, free.velocity_post, trail)[2] > 0:
        assert r.modes[1] == "separate"
        np.testing.assert_allclose(r.velocity_post, free.velocity_post, atol=1e-10)


def contact_velocity(robot, q, v, spec: ContactSpec) -> np.ndarray:
    data = robot.model.createData()
    pin.computeJointJacobians(robot.model, data, q)
    pin.updateFramePlacements(robot.model, data)
    return contact_jacobian(robot, data, spec) @ v


# -- the compass gait written as a URDF ------------------------------------------------------
def compass_urdf(w: CompassGait) -> str:
    """The paper's compass in the world x-z plane (z up), right leg as the floating base.

    The base frame sits at the right foot's arc centre ``P_R`` with its z axis up the leg, so
    the base rotation is ``R_y(-q3)``; the hip is a revolute joint at ``(0, 0, l - R)`` about
    ``-y`` (counter-clockwise in the x-z plane seen with z up, x right), its angle is ``q4``.
    Out-of-plane inertias are nonzero (and decoupled from the plane) so that M is definite.
    """
    l, b, R = w.leg_length, w.leg_com_from_hip, w.foot_radius
    m, mH, I = w.leg_mass, w.hip_mass, w.leg_inertia
    s = l - R
    small = 1e-2

    def inertial(mass: float, z: float, iyy: float) -> str:
        return (f'<inertial><origin xyz="0 0 {z!r}"/><mass value="{mass!r}"/>'
                f'<inertia ixx="{iyy + small!r}" ixy="0" ixz="0" iyy="{iyy!r}" iyz="0" '
                f'izz="{small!r}"/></inertial>')

    return f"""<?xml version="1.0"?>
<robot name="compass">
  <link name="right_leg">{inertial(m, s - b, I)}</link>
  <link name="hip">{inertial(mH, 0.0, 0.0)}</link>
  <joint name="hip_mass" type="fixed"><parent link="right_leg"/><child link="hip"/>
    <origin xyz="0 0 {s!r}"/></joint>
  <link name="left_leg">{inertial(m, -b, I)}</link>
  <joint name="hip_joint" type="revolute"><parent link="right_leg"/><child link="left_leg"/>
    <origin xyz="0 0 {s!r}"/><axis xyz="0 -1 0"/>
    <limit lower="-3.14" upper="3.14" effort="0" velocity="100"/></joint>
  <link name="left_foot_centre"/>
  <joint name="left_foot" type="fixed"><parent link="left_leg"/><child link="left_foot_centre"/>
    <origin xyz="0 0 {-s!r}"/></joint>
</robot>
"""


def compass_to_pin(q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q1, q2, q3, q4 = q
    Ry = pin.utils.rotate("y", -q3)
    quat = pin.Quaternion(Ry).coeffs()  # x, y, z, w
    q_pin = np.concatenate(([q1, 0.0, q2], quat, [q4]))
    v_lin = Ry.T @ np.array([qd[0], 0.0, qd[1]])
    v_pin = np.concatenate((v_lin, [0.0, -qd[2], 0.0], [qd[3]]))
    return q_pin, v_pin


def pin_to_compass(q_pin: np.ndarray, v_pin: np.ndarray) -> np.ndarray:
    Rb = pin.Quaternion(q_pin[6], *q_pin[3:6]).toRotationMatrix()
    lin = Rb @ v_pin[:3]
    assert abs(lin[1]) < 1e-12 and abs(v_pin[3]) < 1e-12 and abs(v_pin[5]) < 1e-12
    return np.array([lin[0], lin[2], -v_pin[4], v_pin[6]])


@pytest.mark.parametrize("R", [0.0, 0.3, 0.7, 1.0])
@pytest.mark.parametrize("inertia", [0.0, 0.1])
def test_compass_urdf_equals_compass_gait(tmp_path, R, inertia) -> None:
    w = CompassGait(foot_radius=R, leg_inertia=inertia)
    path = tmp_path / "compass.urdf"
    path.write_text(compass_urdf(w))
    robot = load_urdf(path)
    assert robot.nv == 7 and robot.mass == pytest.approx(float(w.total_mass))
    for q3_deg in (1.0, 12.0, 27.0, 45.0):
        q, qd = heel_strike_state(w, math.radians(q3_deg))
        ref = impact(w.mass_matrix(q), w.contact_jacobian(q, "left"), qd)
        q_pin, v_pin = compass_to_pin(q, qd)
        # the configurations agree: pinocchio's left foot centre is the compass's P_L
        data = robot.model.createData()
        pin.framesForwardKinematics(robot.model, data, q_pin)
        P_L = data.oMf[robot.model.getFrameId("left_foot_centre")].translation
        np.testing.assert_allclose(P_L[[0, 2]], w.positions(q).left_foot_centre, atol=1e-12)
        res = robot_impact(robot, q_pin, v_pin,
                           strike=[ContactSpec(frame="left_foot_centre", kind="arc", radius=R)])
        r = res.result
        if R < w.leg_length:
            assert r.modes == ("stick",)
        else:  # McGeer's wheel does not approach the ground (up to round-off): nothing lost
            assert abs(r.contact_velocity_pre[0][2]) < 1e-12 and r.T_c < 1e-20
        kept = robot_impact(robot, q_pin, v_pin, strike=[], keep=res.contacts).result
        assert kept.T_c == pytest.approx(float(ref.kinetic_energy_constrained), abs=1e-12)
        assert r.T == pytest.approx(float(ref.kinetic_energy), rel=1e-12)
        assert r.T_c == pytest.approx(float(ref.kinetic_energy_constrained), rel=1e-9, abs=1e-13)
        assert r.T_a == pytest.approx(float(ref.kinetic_energy_admissible), rel=1e-10)
        np.testing.assert_allclose(pin_to_compass(q_pin, r.velocity_post), ref.velocity_post,
                                   atol=1e-11)


def test_mjcf_robot_loads_and_matches_its_urdf(tmp_path) -> None:
    w = CompassGait(foot_radius=0.3, leg_inertia=0.1)
    s, b = w.leg_length - w.foot_radius, w.leg_com_from_hip
    mjcf = f"""<mujoco model="compass">
  <worldbody>
    <body name="right_leg" pos="0 0 0">
      <freejoint name="root"/>
      <inertial pos="0 0 {s - b}" mass="{w.leg_mass}" diaginertia="0.11 0.1 0.01"/>
      <body name="hip" pos="0 0 {s}">
        <inertial pos="0 0 0" mass="{w.hip_mass}" diaginertia="0.01 1e-12 0.01"/>
      </body>
      <body name="left_leg" pos="0 0 {s}">
        <joint name="hip_joint" type="hinge" axis="0 -1 0"/>
        <inertial pos="0 0 {-b}" mass="{w.leg_mass}" diaginertia="0.11 0.1 0.01"/>
        <body name="left_foot_centre" pos="0 0 {-s}">
          <inertial pos="0 0 0" mass="1e-9" diaginertia="1e-12 1e-12 1e-12"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
    path = tmp_path / "compass.xml"
    path.write_text(mjcf)
    robot = load_mjcf(path)
    assert robot.model.joints[1].shortname() == "JointModelFreeFlyer"
    assert robot.nv == 7
    q, qd = heel_strike_state(w, math.radians(20.0))
    ref = impact(w.mass_matrix(q), w.contact_jacobian(q, "left"), qd)
    q_pin, v_pin = compass_to_pin(q, qd)
    r = robot_impact(robot, q_pin, v_pin, strike=[
        ContactSpec(frame="left_foot_centre", kind="arc", radius=0.3)]).result
    assert r.T_c == pytest.approx(float(ref.kinetic_energy_constrained), rel=1e-6)


# -- gait states and the study ---------------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
def test_gait_state_has_stance_at_rest_and_swing_descending(robots, name) -> None:
    robot = robots[name]
    L, speed = 0.2 if name != "bolt" else 0.1, 0.3
    q, v = gait_state(robot, L, speed, forward_speed=0.4)
    data = robot.model.createData()
    pin.computeJointJacobians(robot.model, data, q)
    pin.updateFramePlacements(robot.model, data)
    lead, trail = (robot.model.getFrameId(f) for f in robot.feet)
    k = 3 if robot.foot_contact == "point" else 6
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    u_trail = np.array(pin.getFrameJacobian(robot.model, data, trail, lwa))[:k] @ v
    u_lead = np.array(pin.getFrameJacobian(robot.model, data, lead, lwa))[:k] @ v
    np.testing.assert_allclose(u_trail, 0.0, atol=1e-10)
    np.testing.assert_allclose(u_lead[:3], [0.0, 0.0, -speed], atol=1e-10)
    d = data.oMf[lead].translation - data.oMf[trail].translation
    assert d[0] == pytest.approx(L, abs=1e-9) and d[2] == pytest.approx(0.0, abs=1e-9)
    if k == 6:
        np.testing.assert_allclose(data.oMf[lead].rotation, np.eye(3), atol=1e-9)


@pytest.mark.parametrize("name", ROBOTS)
def test_gait_state_feet_are_on_the_ground_plane(robots, name) -> None:
    """QA P3: the feet of the gait states were at the reference pose's height (g1's soles at
    z = -0.728 m, talos's at -2e-6 m); now on z = 0 for every robot. The impact does not
    depend on that height: lifting the whole robot leaves T_c and q_dot+ unchanged."""
    robot = robots[name]
    q, v = gait_state(robot, 0.1, 0.3)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    for frame in robot.feet:
        assert data.oMf[robot.model.getFrameId(frame)].translation[2] == pytest.approx(
            0.0, abs=1e-9)
    kind = "point" if robot.foot_contact == "point" else "flat"
    strike = [ContactSpec(frame=robot.feet[0], kind=kind)]
    keep = [ContactSpec(frame=robot.feet[1], kind=kind)]
    lifted = np.array(q)
    lifted[2] += 0.7
    a = robot_impact(robot, q, v, strike=strike, keep=keep).result
    b = robot_impact(robot, lifted, v, strike=strike, keep=keep).result
    assert a.T_c > 0
    assert b.T_c == pytest.approx(a.T_c, rel=1e-10)
    np.testing.assert_allclose(b.velocity_post, a.velocity_post, atol=1e-10)


def test_study_is_batched_and_scales_with_strike_speed(robots) -> None:
    talos = robots["talos"]
    L = np.array([0.1, 0.3, 0.5])
    S = np.array([0.2, 0.4])
    st = robot_heel_strike_study(talos, L, S, forward_speed=0.0)
    assert st.T_c.shape == (3, 2)
    np.testing.assert_allclose(st.T_c + st.T_a, st.T, rtol=1e-12)
    np.testing.assert_allclose(st.T_c_normal + st.T_c_tangential, st.T_c, rtol=1e-12)
    # with the base not moving forward v is proportional to the strike speed: T_c ~ speed^2
    np.testing.assert_allclose(st.T_c[:, 1], 4.0 * st.T_c[:, 0], rtol=1e-8)
    np.testing.assert_allclose(st.loss_per_metre, st.T_c / L[:, None], rtol=1e-12)
    # one grid point by the single-impact path
    q, v = gait_state(talos, 0.3, 0.4, forward_speed=0.0)
    one = robot_impact(talos, q, v, strike=[], keep=[ContactSpec(
        frame="left_sole_link", kind="flat")]).result
    assert st.T_c[1, 1] == pytest.approx(one.T_c, rel=1e-9)
    fig = plot_robot_study(st)
    assert len(fig.axes) >= 2


# -- command line ----------------------------------------------------------------------------
def _state_file(tmp_path: Path, q, v) -> str:
    path = tmp_path / "state.json"
    path.write_text(json.dumps({"q": list(map(float, q)), "v": list(map(float, v))}))
    return str(path)


def test_cli_robot_list_and_info(capsys) -> None:
    assert main(["robot", "list", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    names = {r["name"] for r in out["robots"]}
    assert set(ROBOTS) <= names
    for r in out["robots"]:
        assert {"name", "nq", "nv", "mass", "source"} <= set(r)
    assert set(out["units"]) == {"robots"} and out["units"]["robots"]["mass"] == "kg"
    assert set(out["units"]["robots"]) == set(out["robots"][0])
    assert main(["robot", "info", "talos"]) == 0
    assert "nv=38" in capsys.readouterr().out
    assert main(["robot", "info", "bolt", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert set(info["units"]) == set(info) - {"units"}
    assert info["units"]["reference_q"] == ["m"] * 3 + ["1"] * 4 + ["rad"] * 6


def test_cli_impact_json(robots, tmp_path, capsys) -> None:
    talos = robots["talos"]
    q, v = gait_state(talos, 0.4, 0.3)
    state = _state_file(tmp_path, q, v)
    argv = ["impact", "--robot", "talos", "--state", state, "--strike",
            "left_sole_link:flat-bilateral", "--keep", "right_sole_link:flat", "--friction",
            "0.7", "--restitution", "0.1", "--json"]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert {"T", "T_c", "T_a", "qdot_plus", "impulse", "contacts"} <= set(d)
    assert len(d["qdot_plus"]) == talos.nv and len(d["impulse"]) == 12
    assert [c["frame"] for c in d["contacts"]] == ["left_sole_link", "right_sole_link"]
    for c in d["contacts"]:
        assert c["mode"] in ("stick", "slip", "separate")
        assert {"T_c_normal", "T_c_tangential"} <= set(c)
    u = d["units"]
    assert set(u) == set(d) - {"units"}
    assert u["qdot_plus"] == ["m/s"] * 3 + ["rad/s"] * (talos.nv - 3)
    assert u["impulse"] == (["N s"] * 3 + ["N m s"] * 3) * 2
    assert u["T_c"] == "J" and set(u["contacts"]) >= set(d["contacts"][0])
    # the contact's own impulse and the global list agree
    np.testing.assert_allclose(d["contacts"][1]["force_impulse"], d["impulse"][6:9])
    ref = robot_impact(talos, q, v, strike=[parse_contact("left_sole_link:flat-bilateral")],
                       keep=[parse_contact("right_sole_link:flat")], friction=0.7,
                       restitution=0.1).result
    assert d["T_c"] == pytest.approx(ref.T_c, rel=1e-12)
    assert d["T"] == pytest.approx(d["T_c"] + d["T_a"], rel=1e-12)


def test_cli_robot_state_writes_the_gait_state_impact_reads(robots, tmp_path, capsys) -> None:
    talos = robots["talos"]
    out = tmp_path / "state.json"
    assert main(["robot", "state", "talos", "--step-length", "0.25", "--strike-speed", "0.4",
                 "--out", str(out)]) == 0
    assert "state.json" in capsys.readouterr().out
    state = json.loads(out.read_text())
    q, v = gait_state(talos, 0.25, 0.4)
    np.testing.assert_allclose(state["q"], q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(state["v"], v, rtol=0, atol=1e-12)
    assert state["leading_foot"] == "left_sole_link"
    assert set(state["units"]) == set(state) - {"units"}
    assert state["units"]["v"] == ["m/s"] * 3 + ["rad/s"] * (talos.nv - 3)
    argv = ["impact", "--robot", "talos", "--state", str(out), "--strike", "left_sole_link:flat",
            "--keep", "right_sole_link:flat", "--friction", "0.8", "--json"]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["contacts"][0]["normal_velocity_pre"] == pytest.approx(-0.4, rel=1e-9)
    assert d["T"] == pytest.approx(0.5 * v @ talos.mass_matrix(q) @ v, rel=1e-12)
    # without --out the state is printed (one JSON object); --json describes the written file
    assert main(["robot", "state", "bolt", "--leading", "right", "--step-length", "0.1"]) == 0
    bolt = json.loads(capsys.readouterr().out)
    assert len(bolt["q"]) == robots["bolt"].nq and len(bolt["v"]) == robots["bolt"].nv
    assert bolt["leading_foot"] == robots["bolt"].feet[1]
    assert main(["robot", "state", "talos", "--out", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["out"] == str(out)


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--strike-speed", "0"], "--strike-speed"),
        (["--step-length", "-0.1"], "--step-length"),
        (["--step-length", "nan"], "--step-length"),
        (["--json"], "--json needs --out"),
        (["--out", "no/such/dir/state.json"], "no/such/dir"),
    ],
)
def test_cli_robot_state_bad_input_is_one_line_exit_2(capsys, args, needle) -> None:
    assert main(["robot", "state", "talos", *args]) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("heelstrike: error:") and needle in lines[0]


@pytest.mark.slow
def test_readme_robot_example_runs(tmp_path) -> None:
    """The README's "Real robots" commands, run as written in a fresh directory."""
    import re
    import shlex
    import subprocess
    import sys

    text = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    section = text.split("## Real robots (URDF/MJCF)", 1)[1]
    block = re.search(r"^```console\n(.*?)^```", section, flags=re.S | re.M)
    assert block is not None
    commands = [line.split("  #")[0].strip() for line in block.group(1).strip().splitlines()]
    assert commands[0] == "pip install '.[robots]'"  # installed here; not rerun
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    outputs = []
    for cmd in commands[1:]:
        proc = subprocess.run(shlex.split(cmd), cwd=tmp_path, env=env, capture_output=True,
                              text=True, timeout=120, check=False)
        assert proc.returncode == 0, (cmd, proc.stderr)
        outputs.append(proc.stdout)
    assert "talos" in outputs[0] and (tmp_path / "state.json").is_file()
    d = json.loads(outputs[-1])
    keys = {"robot", "nq", "nv", "T", "T_c", "T_a", "T_plus", "energy_lost", "qdot_plus",
            "impulse", "contacts", "units", "loss_beyond_T_c", "admissible", "pulling_contacts",
            "outcomes", "unique", "active_sets", "solutions", "restitution_law",
            "tilting_contacts", "impulse_unique", "velocity_range", "kkt_residual"}
    assert set(d) == keys  # the keys the README lists, no more
    assert d["T"] == pytest.approx(d["T_c"] + d["T_a"], rel=1e-12)
    shares = sum(c["T_c_normal"] + c["T_c_tangential"] for c in d["contacts"])
    assert shares == pytest.approx(d["T_c"], rel=1e-10)
    per_contact = {
        "frame", "type", "role", "mode", "T_c_normal", "T_c_tangential", "force_impulse",
        "moment_impulse", "centre_of_pressure", "normal_velocity_pre", "normal_velocity_post",
        "slip_speed_post"}
    assert set(d["contacts"][0]) == per_contact | {"corners"}  # the striking support polygon
    assert set(d["contacts"][1]) == per_contact  # the kept sole, held flat
    assert d["unique"] is True and d["outcomes"] == len(d["solutions"]) == 1
    corners = d["contacts"][0]["corners"]
    assert len(corners) == 4 and all(k["normal_velocity_post"] > -1e-9 for k in corners)


def test_cli_impact_from_urdf(tmp_path, capsys) -> None:
    w = CompassGait(foot_radius=0.3)
    urdf = tmp_path / "compass.urdf"
    urdf.write_text(compass_urdf(w))
    q, qd = heel_strike_state(w, math.radians(20.0))
    q_pin, v_pin = compass_to_pin(q, qd)
    state = _state_file(tmp_path, q_pin, v_pin)
    assert main(["impact", "--urdf", str(urdf), "--state", state,
                 "--strike", "left_foot_centre:arc:0.3", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    ref = impact(w.mass_matrix(q), w.contact_jacobian(q, "left"), qd)
    assert d["T_c"] == pytest.approx(float(ref.kinetic_energy_constrained), rel=1e-9)


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--robot", "talos", "--strike", "no_such_frame:flat"], "no_such_frame"),
        (["--robot", "atlas", "--strike", "x:flat"], "atlas"),
        (["--robot", "talos", "--strike", "left_sole_link:round"], "left_sole_link:round"),
        (["--robot", "g1", "--strike", "left_ankle_roll_link:flat"], "'q' has 39 entries"),
        (["--urdf", "README.md", "--strike", "x:point"], "not a URDF robot"),
        (["--mjcf", "README.md", "--strike", "x:point"], "not an MJCF robot"),
        (["--robot", "talos", "--strike", "left_sole_link:flat", "--restitution", "2"],
         "restitution"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(robots, tmp_path, capsys, args, needle) -> None:
    talos = robots["talos"]
    q, v = gait_state(talos, 0.2, 0.2)
    state = _state_file(tmp_path, q, v)
    assert main(["impact", *args, "--state", state, "--json"]) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("heelstrike: error:")
    assert needle in lines[0]


def test_cli_wrong_v_length(robots, tmp_path, capsys) -> None:
    talos = robots["talos"]
    state = _state_file(tmp_path, talos.reference_q, np.zeros(talos.nv - 1))
    assert main(["impact", "--robot", "talos", "--state", state,
                 "--strike", "left_sole_link:flat"]) == 2
    assert "'v' has 37 entries" in capsys.readouterr().err


def test_parse_contact_and_errors() -> None:
    assert parse_contact("foot:arc:0.05") == ContactSpec(frame="foot", kind="arc", radius=0.05)
    with pytest.raises(RobotError, match="invalid contact"):
        parse_contact("foot")
    with pytest.raises(RobotError, match="unknown robot"):
        load_robot("nao")
