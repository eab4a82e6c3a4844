"""Issue #34 leftovers: one exact impact solver, and whether its outcome is unique.

Every striking contact (point, arc, a sole's corners, a sole held flat) is solved by the exact
active-set law (pyramid friction cones). Uniqueness of ``q_dot+`` and of the impulses is decided
by the enumeration of the active sets and the null directions of each set's Delassus system;
the oracles here are closed forms derived in the docstrings (no optimiser, no iteration).
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from heelstrike.core.complementarity import solve_point_contacts
from heelstrike.core.contact_laws import ContactLaw, ContactRows, resolve_contact_impact

MASS = 12.0
HEIGHT = 0.4  # centre of mass above the ground (m)
SOLE_X, SOLE_Y, SPREAD = 0.1, 0.05, 0.12  # half length, half width, soles' centres at y = +-SPREAD


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _body() -> np.ndarray:
    """A free rigid body, symmetric about its centre of mass: ``M`` (6, 6) for the twist
    ``(v, omega)`` of the centre of mass in world axes."""
    M = np.zeros((6, 6))
    M[:3, :3] = MASS * np.eye(3)
    M[3:, 3:] = np.diag([0.9, 0.7, 0.5])
    return M


def _point_rows(p: np.ndarray) -> np.ndarray:
    """Velocity rows (3, 6) of the body's point ``p`` (from the centre of mass)."""
    J = np.zeros((3, 6))
    J[:, :3] = np.eye(3)
    J[:, 3:] = -_skew(p)
    return J


def _sole_centres() -> list[np.ndarray]:
    return [np.array([0.0, s * SPREAD, -HEIGHT]) for s in (-1.0, 1.0)]


def _corners() -> list[np.ndarray]:
    return [c + np.array([x, y, 0.0]) for c in _sole_centres()
            for x, y in itertools.product((-SOLE_X, SOLE_X), (-SOLE_Y, SOLE_Y))]


def _flat_sole(c: np.ndarray, mu: float, name: str) -> ContactRows:
    """A sole held flat: its centre's velocity and the body's angular velocity (6 rows)."""
    J = np.zeros((6, 6))
    J[:3] = _point_rows(c)
    J[3:, 3:] = np.eye(3)
    return ContactRows(jacobian=J, normal=(2, 3, 4), tangential=(0, 1, 5),
                       tangential_weights=(1.0, 1.0, 1.0 / 0.05),
                       law=ContactLaw(friction=mu), name=name)


def _check_flat_landing_impulse(generalized: np.ndarray, v: np.ndarray) -> None:
    """Momentum balance of the closed form: the body stops, so the generalized impulse is
    ``-M v-`` (a vertical force ``MASS * 1 m/s``, no moment about the centre of mass)."""
    np.testing.assert_allclose(generalized, -_body() @ v, atol=1e-10)


@pytest.mark.parametrize("mu", [0.5, np.inf])
def test_two_flat_soles_landing_flat_stop_the_body_with_an_undetermined_split(mu: float) -> None:
    """A symmetric body dropping flat (``v_z = -1`` m/s) on two coplanar soles held flat.

    Closed form: ``q_dot+ = 0``. The soles stop ``v_z``, ``omega_x``, ``omega_y``; the rest
    ``q_p = (v_x, v_y, omega_z)`` starts at 0 and only the friction impulses ``lambda_t`` move
    it (the body is symmetric: ``M`` is block diagonal), so ``q_p+^T M_p q_p+ = lambda_t .
    u_t+ <= 0`` (friction never does positive work on its row): ``q_p+ = 0``, one outcome.
    The impulse is not determined: each sole alone can stop the body (it carries a moment),
    and any split of the 12 N s between them does too."""
    M = _body()
    v = np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0])
    soles = [_flat_sole(c, mu, f"sole {i}") for i, c in enumerate(_sole_centres())]
    res = resolve_contact_impact(M, v, soles)
    assert res.exhaustive and res.active_sets == (28 if np.isfinite(mu) else 2) ** 2
    assert res.unique is True and res.impulse_unique is False and not res.continuum
    np.testing.assert_allclose(res.velocity_post, 0.0, atol=1e-12)
    assert len(res.solutions) == 1
    assert res.velocity_range is not None
    np.testing.assert_allclose(res.velocity_range, 0.0, atol=1e-12)
    _check_flat_landing_impulse(res.generalized_impulse, v)
    assert res.kkt_residual < 1e-10
    assert res.T_c == pytest.approx(0.5 * MASS, rel=1e-12) and res.T_post < 1e-20


def test_two_sole_polygons_landing_flat_stop_the_body_with_an_undetermined_split() -> None:
    """The same landing on the soles' eight corners (unbounded friction: 2^8 active sets).
    Any three corners around the centre of mass's footprint stop the body; the corner
    impulses are not determined, ``q_dot+ = 0`` is (closed form above)."""
    M = _body()
    v = np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0])
    C = np.array([_point_rows(p) for p in _corners()])  # (8, 3, 6)
    sol = solve_point_contacts(M, v, C[:, 2], tangential=C[:, :2], friction=np.inf)
    assert sol.exhaustive and sol.active_sets == 2 ** 8
    assert sol.unique is True and sol.impulse_unique is False and not sol.continuum
    np.testing.assert_allclose(sol.velocity_post, 0.0, atol=1e-12)
    _check_flat_landing_impulse(np.einsum("kr,krn->n", sol.impulse[:, [1, 2, 0]],
                                          C[:, [0, 1, 2]]), v)
    assert np.all(sol.impulse[:, 0] >= -1e-12)  # every corner pushes
    assert sol.kkt_residual < 1e-10


def test_one_sole_landing_flat_is_unique_in_impulse_too() -> None:
    """One sole held flat under the centre of mass: six independent rows on six coordinates,
    the impulse ``-M v-`` at the sole's centre is the only one (moment ``r x F`` cancelled by
    the sole's own moment rows)."""
    M = _body()
    v = np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0])
    c = np.array([0.0, 0.0, -HEIGHT])
    res = resolve_contact_impact(M, v, [_flat_sole(c, 0.5, "sole")])
    assert res.unique is True and res.impulse_unique is True
    np.testing.assert_allclose(res.impulse, [0.0, 0.0, MASS, 0.0, 0.0, 0.0], atol=1e-12)


# -- Painleve-type impacts: closed forms with exactly representable matrices ------------------
# M = I, rows n = (1, 0, 0), t1 = (2, 1, 0), t2 = (0, 0, 1): the Delassus matrix is
# G = [[1, 2, 0], [2, 5, 0], [0, 0, 1]] (a = 1, c = 2, b = 5), with no round-off.
ROWS = np.array([[1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def _painleve(v: np.ndarray, mu: float) -> tuple[Any, Any]:
    M = np.eye(3)
    sol = solve_point_contacts(M, v, ROWS[:1], tangential=ROWS[None, 1:], friction=mu)
    res = resolve_contact_impact(M, v, [ContactRows(
        jacobian=ROWS, normal=(0,), tangential=(1, 2), law=ContactLaw(friction=mu))])
    return sol, res


def _same_set(a: tuple[np.ndarray, ...], b: list[np.ndarray]) -> bool:
    return len(a) == len(b) and all(any(np.abs(x - y).max() <= 1e-12 for y in b) for x in a)


def test_a_contact_with_three_outcomes_reports_them_and_their_range() -> None:
    """``u- = (u_n, u_t1, u_t2) = (0.1, 1, 0)``, ``mu = 0.6`` (``a - mu c = -0.2 < 0``):

    - separate: ``q_dot+ = q_dot- = (0.1, 0.8, 0)``;
    - slide (``u_t1+ > 0``): ``lambda_t1 = -mu lambda_n``, ``u_n+ = 0.1 + (a - mu c)
      lambda_n = 0`` gives ``lambda_n = 0.5``, ``lambda_t1 = -0.3``, ``u_t1+ = 1 + 2 (0.5)
      - 5 (0.3) = 0.5 > 0``: ``q_dot+ = (0, 0.5, 0)``;
    - stick: ``lambda = -G^-1 u- = (1.5, -0.8, 0)``, ``0.8 <= 0.6 * 1.5``: ``q_dot+ = 0``;
    - sliding the other way needs ``lambda_n = -0.1 / 2.2 < 0``: inconsistent."""
    v = np.array([0.1, 0.8, 0.0])
    expected = [v, np.array([0.0, 0.5, 0.0]), np.zeros(3)]
    for r in _painleve(v, 0.6):
        assert r.exhaustive and r.unique is False and r.impulse_unique is False
        assert not r.continuum
        assert _same_set(r.solutions, expected)
        np.testing.assert_allclose(r.velocity_range, [[0.0, 0.0, 0.0], [0.1, 0.8, 0.0]],
                                   atol=1e-15)
        # the returned one: fewest sliding rows, then fewest active contacts (separate)
        np.testing.assert_allclose(r.velocity_post, v, atol=1e-15)
        assert r.kkt_residual < 1e-12


def test_a_contact_with_a_continuum_of_outcomes_reports_its_ends() -> None:
    """``u- = (0, 1, 0)``, ``mu = 0.5``: ``a - mu c = 0``, so sliding (``lambda_t1 = -mu
    lambda_n``) keeps ``u_n+ = 0`` for every ``lambda_n >= 0`` and ``u_t1+ = 1 - 0.5
    lambda_n >= 0`` for ``lambda_n <= 2``: a segment of outcomes ``q_dot+ = (0, 1, 0) +
    lambda_n (0, -1/2, 0)``, from separation (``lambda_n = 0``) to sticking (``lambda =
    (2, -1, 0)``, on the cone's edge)."""
    v = np.array([0.0, 1.0, 0.0])
    ends = [v, np.array([0.0, 0.0, 0.0])]
    for r in _painleve(v, 0.5):
        assert r.exhaustive and r.continuum and r.unique is False
        assert r.impulse_unique is False
        assert _same_set(r.solutions, ends)
        np.testing.assert_allclose(r.velocity_range, [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                                   atol=1e-15)
        assert r.kkt_residual < 1e-12


def test_a_contact_with_one_outcome() -> None:
    """``u- = (-1, 0, 0)`` with ``mu = 2`` (``a - mu c = -3 < 0`` but approaching): sticking
    gives ``lambda = -G^-1 u- = (5, -2, 0)`` inside the cone (``2 <= 10``), ``q_dot+ = 0``.
    Separation would pass through the ground, sliding ``u_t1+ > 0`` needs ``lambda_n =
    1 / (a - mu c) < 0``, sliding ``u_t1+ < 0`` gives ``lambda_n = 1 / 5``, ``u_t1+ = (2 +
    10) / 5 > 0``: inconsistent. One outcome, one impulse."""
    v = np.array([-1.0, 2.0, 0.0])  # u- = (-1, 0, 0)
    for r in _painleve(v, 2.0):
        assert r.unique is True and r.impulse_unique is True
        assert not r.continuum
        np.testing.assert_allclose(r.velocity_post, 0.0, atol=1e-13)
    sol, _ = _painleve(v, 2.0)
    np.testing.assert_allclose(sol.impulse, [[5.0, -2.0, 0.0]], atol=1e-13)


def test_kkt_residual_sees_a_violation() -> None:
    """The certificate is not vacuous: a pulling normal impulse or an impulse outside the cone
    shows as a residual of its size."""
    from heelstrike.core.complementarity import _kkt_residual, _Layout

    M = np.eye(3)
    v = np.array([-1.0, 2.0, 0.0])
    lay = _Layout(principal=(0,), extra=((),), tangential=((1, 2),))
    f = np.array([5.0, -2.0, 0.0])
    vp = v + ROWS.T @ f
    none = np.zeros((0, 3))
    args = (np.zeros(3), np.array([2.0]), lay)
    assert _kkt_residual(M, v, vp, ROWS, none, f, np.zeros(0), *args) < 1e-15
    bad = np.array([5.0, -12.0, 0.0])  # |lambda_t| = 12 > mu lambda_n = 10
    assert _kkt_residual(M, v, v + ROWS.T @ bad, ROWS, none, bad, np.zeros(0), *args) > 0.1
    assert _kkt_residual(M, v, vp + 0.1, ROWS, none, f, np.zeros(0), *args) > 1e-3


# -- a robot: the symmetric body on two soles, through robot_impact and the command line ------
def _two_sole_body(path: Path) -> Any:
    pytest.importorskip("pinocchio")
    from heelstrike.robots import load_mjcf

    path.write_text(f"""<mujoco model="block">
  <worldbody>
    <body name="body" pos="0 0 {HEIGHT}">
      <freejoint name="root"/>
      <inertial pos="0 0 0" mass="{MASS - 1.0}" diaginertia="0.9 0.7 0.5"/>
      <body name="wheel" pos="0 0 0">
        <joint name="spin" type="hinge" axis="0 0 1"/>
        <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.02"/>
      </body>
      <site name="left_sole" pos="0 {SPREAD} {-HEIGHT}"/>
      <site name="right_sole" pos="0 {-SPREAD} {-HEIGHT}"/>
    </body>
  </worldbody>
</mujoco>
""")
    return load_mjcf(path)


@pytest.mark.parametrize(("kind", "mu"), [("flat-bilateral", 0.5), ("flat", np.inf)])
def test_robot_landing_flat_on_two_soles_reports_the_split_undetermined(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str, mu: float) -> None:
    """The closed form above on a robot file (MJCF, free body, two sole sites, a wheel
    spinning about the vertical through the centre of mass, its centre of mass on the axis: it
    couples to ``omega_z`` only, so the in-plane argument holds with the wheel's rate in
    ``q_p``): ``qdot_plus = 0``, unique; the impulse split between the soles is not
    (``impulse_unique`` false), the vertical impulses add up to the momentum ``MASS * 1
    m/s``."""
    import json

    from heelstrike.cli import main
    from heelstrike.robots import parse_contact, robot_impact

    robot = _two_sole_body(tmp_path / "block.xml")
    sole = f":{kind}:{SOLE_X},{SOLE_Y}"
    q = [0.0, 0.0, HEIGHT, 0.0, 0.0, 0.0, 1.0, 0.0]
    v = [0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0]
    strike = [parse_contact(f"{f}{sole}") for f in ("left_sole", "right_sole")]
    d = robot_impact(robot, q, v, strike=strike, friction=mu).to_dict()
    assert d["unique"] is True and d["impulse_unique"] is False and d["outcomes"] == 1
    np.testing.assert_allclose(d["qdot_plus"], 0.0, atol=1e-12)
    np.testing.assert_allclose(d["velocity_range"], 0.0, atol=1e-12)
    assert sum(c["force_impulse"][2] for c in d["contacts"]) == pytest.approx(MASS, rel=1e-12)
    assert d["T_c"] == pytest.approx(0.5 * MASS, rel=1e-12) and d["kkt_residual"] < 1e-10
    state = tmp_path / "state.json"
    state.write_text(json.dumps({"q": q, "v": v}))
    argv = ["impact", "--mjcf", str(tmp_path / "block.xml"), "--state", str(state),
            "--friction", str(mu)]
    for s in strike:
        argv += ["--strike", f"{s.frame}{sole}"]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["impulse_unique"] is False and out["unique"] is True
    assert set(out["units"]) == set(out) - {"units"}
    assert out["units"]["velocity_range"] == ["m/s"] * 3 + ["rad/s"] * 4


def test_two_sole_polygons_with_finite_friction_landing_flat_stop_the_body() -> None:
    """The flat landing on the soles' eight corners with ``mu = 0.5`` (10^8 active sets: one
    outcome by Lemke's method, whose first pivot ties all eight corners). Closed form: every
    outcome has ``lambda . u+ <= 0`` (normal complementarity, friction never does positive
    work), so ``q_dot+^T M q_dot+ <= q_dot+^T M q_dot- = -MASS v_z+``; the corners are
    symmetric about the centre of mass's footprint, so ``v_z+`` is the mean of their normal
    velocities, ``>= 0``: ``q_dot+ = 0``, and the generalized impulse is ``-M q_dot-``."""
    M = _body()
    v = np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0])
    C = np.array([_point_rows(p) for p in _corners()])  # (8, 3, 6)
    sol = solve_point_contacts(M, v, C[:, 2], tangential=C[:, :2], friction=0.5)
    assert not sol.exhaustive and sol.active_sets == 10 ** 8
    # certified without the enumeration: the normal impulses alone stop the body
    assert sol.unique is True and sol.impulse_unique is False
    np.testing.assert_allclose(sol.velocity_post, 0.0, atol=1e-12)
    _check_flat_landing_impulse(np.einsum("kr,krn->n", sol.impulse[:, [1, 2, 0]],
                                          C[:, [0, 1, 2]]), v)
    assert np.all(sol.impulse[:, 0] >= -1e-12)
    assert np.all(np.abs(sol.impulse[:, 1:]) <= 0.5 * sol.impulse[:, :1] + 1e-12)
    assert sol.kkt_residual < 1e-10


def test_no_stop_certificate_where_normal_impulses_cannot_stop_the_body() -> None:
    """Landing sliding at 2 m/s on the eight corners: stopping needs a horizontal impulse
    (``MASS * 2`` N s), which normal impulses cannot give, so ``q_dot+ = 0`` is not certified
    (nor is it the outcome: the body pitches over the front edges); 10^8 active sets, not
    examined: ``unique`` stays None."""
    M = _body()
    v = np.array([2.0, 0.0, -1.0, 0.0, 0.0, 0.0])
    C = np.array([_point_rows(p) for p in _corners()])
    sol = solve_point_contacts(M, v, C[:, 2], tangential=C[:, :2], friction=0.5)
    assert not sol.exhaustive and sol.unique is None and sol.impulse_unique is None
    assert sol.velocity_post[0] > 0.1 and sol.kkt_residual < 1e-10


def test_robot_two_sole_polygons_with_finite_friction_landing_flat(tmp_path: Path) -> None:
    """The flat landing on the MJCF body's two soles as support polygons (``flat``: eight
    corners, ``mu = 0.5``, 10^8 active sets): certified ``qdot_plus = 0`` and unique, the
    split not, the vertical impulses adding up to ``MASS * 1 m/s``."""
    from heelstrike.robots import parse_contact, robot_impact

    robot = _two_sole_body(tmp_path / "block.xml")
    q = [0.0, 0.0, HEIGHT, 0.0, 0.0, 0.0, 1.0, 0.0]
    v = [0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0]
    strike = [parse_contact(f"{f}:flat:{SOLE_X},{SOLE_Y}")
              for f in ("left_sole", "right_sole")]
    d = robot_impact(robot, q, v, strike=strike, friction=0.5).to_dict()
    assert d["active_sets"] == 10 ** 8
    assert d["unique"] is True and d["impulse_unique"] is False
    np.testing.assert_allclose(d["qdot_plus"], 0.0, atol=1e-12)
    assert sum(c["force_impulse"][2] for c in d["contacts"]) == pytest.approx(MASS, rel=1e-12)
    assert d["kkt_residual"] < 1e-10
