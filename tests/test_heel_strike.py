"""The paper's heel-strike study: an independent momentum check and the facts of its model.

The impact is checked without the impact algebra: the only external impulse acts at the new
contact point C (ground point below the left foot's centre P_L), so the walker's angular
momentum about C is conserved; the trailing (right) leg receives an impulse only at the hip, so
its angular momentum about the hip is conserved. With the no-slip contact ``A_L q+ = 0`` these
are four linear equations for ``q+``. Kinematics here are written from the paper (Fig. 1,
restated in :mod:`heelstrike.models.compass`'s docstring), not taken from the model.
"""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.analysis.heel_strike import heel_strike_study, step_length
from heelstrike.analysis.paper import figure2_data, figure3b_data, heel_strike_table
from heelstrike.models.compass import CompassGait

DEG = np.pi / 180.0


def _cross(r: np.ndarray, v: np.ndarray) -> float:
    return float(r[0] * v[1] - r[1] * v[0])


def _e(th: float) -> np.ndarray:
    return np.array([-np.sin(th), np.cos(th)])


def _de(th: float) -> np.ndarray:
    return np.array([-np.cos(th), -np.sin(th)])


def _momentum_rows(w: CompassGait, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows ``a, c`` with ``a @ qd`` = angular momentum of the walker about the contact point C
    and ``c @ qd`` = angular momentum of the right leg about the hip; and the paper's ``A_L``."""
    l, b, R = w.leg_length, w.leg_com_from_hip, w.foot_radius
    mH, m, I = w.hip_mass, w.leg_mass, w.leg_inertia
    s = l - R
    q3, q34 = q[2], q[2] + q[3]
    P_R = q[:2]
    H = P_R + s * _e(q3)
    P_L = H - s * _e(q34)
    C = P_L + np.array([0.0, -R])
    G_R, G_L = H - b * _e(q3), H - b * _e(q34)
    # velocity Jacobians (2 x 4) of the points, from their positions in the paper's Fig. 1
    ex = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])

    def jac(c3: np.ndarray, c34: np.ndarray) -> np.ndarray:
        J = ex.copy()
        J[:, 2] += c3 + c34
        J[:, 3] += c34
        return J

    J_H = jac(s * _de(q3), np.zeros(2))
    J_GR = jac((s - b) * _de(q3), np.zeros(2))
    J_GL = jac(s * _de(q3), -b * _de(q34))
    w_R = np.array([0.0, 0.0, 1.0, 0.0])
    w_L = np.array([0.0, 0.0, 1.0, 1.0])

    def moment_row(point: np.ndarray, mass: float, J: np.ndarray, about: np.ndarray) -> np.ndarray:
        r = point - about
        return mass * (r[0] * J[1] - r[1] * J[0])

    a = (moment_row(H, mH, J_H, C) + moment_row(G_R, m, J_GR, C) + moment_row(G_L, m, J_GL, C)
         + I * (w_R + w_L))
    c = moment_row(G_R, m, J_GR, H) + I * w_R
    A_L = np.array([
        [1.0, 0.0, R, s * np.cos(q3) + R],
        [0.0, 1.0, -2 * s * np.sin(q3), -s * np.sin(q3)],
    ])
    return a, c, A_L


CASES = [
    (R, q3, inertia)
    for R in (0.0, 0.1, 0.25, 0.4, 0.5, 0.75, 0.95, 1.0)
    for q3 in (0.5, 5.0, 15.0, 25.0, 35.0, 45.0)
    for inertia in (0.0, 0.3)
]


@pytest.mark.parametrize(("R", "q3_deg", "inertia"), CASES)
def test_impact_conserves_angular_momenta_and_matches_momentum_solve(
    R: float, q3_deg: float, inertia: float
):
    w = CompassGait(foot_radius=R, leg_inertia=inertia)
    q3 = q3_deg * DEG
    s = heel_strike_study(w, q3, q3_dot=1.0, q4_dot=0.0)
    q = np.array([0.0, R, q3, -2 * q3])
    qd_minus = np.array([-R, 0.0, 1.0, 0.0])
    np.testing.assert_array_equal(s.state, q)
    np.testing.assert_array_equal(s.velocity_pre, qd_minus)
    a, c, A_L = _momentum_rows(w, q)
    qd_plus = s.velocity_post
    scale = 10.0
    assert a @ qd_plus == pytest.approx(a @ qd_minus, abs=1e-12 * scale)
    assert c @ qd_plus == pytest.approx(c @ qd_minus, abs=1e-12 * scale)
    np.testing.assert_allclose(A_L @ qd_plus, 0.0, atol=1e-13)
    # the four momentum / contact equations solved directly
    K = np.vstack([a, c, A_L])
    rhs = np.array([a @ qd_minus, c @ qd_minus, 0.0, 0.0])
    expected = np.linalg.solve(K, rhs)
    np.testing.assert_allclose(qd_plus, expected, rtol=0, atol=1e-12)
    # the impulse on the foot equals the jump in linear momentum of the walker
    p_jump = sum(
        mass * (J @ (qd_plus - qd_minus))
        for mass, J in _linear_momentum_jacobians(w, q)
    )
    np.testing.assert_allclose(s.constraint_impulse, p_jump, atol=1e-11)


def _linear_momentum_jacobians(w: CompassGait, q: np.ndarray) -> list[tuple[float, np.ndarray]]:
    l, b, R = w.leg_length, w.leg_com_from_hip, w.foot_radius
    s = l - R
    q3, q34 = q[2], q[2] + q[3]
    out = []
    for mass, c3, c34 in [(w.hip_mass, s, 0.0), (w.leg_mass, s - b, 0.0), (w.leg_mass, s, -b)]:
        J = np.zeros((2, 4))
        J[:, :2] = np.eye(2)
        J[:, 2] = c3 * _de(q3) + c34 * _de(q34)
        J[:, 3] = c34 * _de(q34)
        out.append((mass, J))
    return out


def test_energy_identities_and_restitution():
    w = CompassGait(foot_radius=np.linspace(0, 1, 11)[None, :])
    q3 = np.linspace(1, 45, 23)[:, None] * DEG
    for e in (0.0, 0.4, 1.0):
        s = heel_strike_study(w, q3, restitution=e)
        np.testing.assert_allclose(s.kinetic_energy,
                                   s.kinetic_energy_constrained + s.kinetic_energy_admissible,
                                   rtol=1e-12)
        np.testing.assert_allclose(s.energy_lost, (1 - e**2) * s.kinetic_energy_constrained,
                                   rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(s.kinetic_energy - s.kinetic_energy_post, s.energy_lost,
                                   rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(s.eta, s.energy_lost / s.step_length, rtol=1e-12)


def test_step_length_is_contact_distance_plus_rolled_arc():
    for R in (0.0, 0.3, 1.0):
        w = CompassGait(foot_radius=R)
        for q3 in np.array([2.0, 20.0, 45.0]) * DEG:
            pos = w.positions(np.array([0.0, R, q3, -2 * q3]))
            gap = pos.right_contact[0] - pos.left_contact[0]  # leading foot is towards -x
            assert gap > 0 if R < 1.0 else gap == pytest.approx(0.0, abs=1e-15)
            assert pos.left_contact[1] == pytest.approx(0.0, abs=1e-14)  # it touches the ground
            assert float(step_length(w, q3)) == pytest.approx(gap + 2 * R * q3, rel=1e-13)


def test_wheel_R_equals_l_loses_nothing_and_is_degenerate():
    w = CompassGait(foot_radius=1.0)
    q3 = np.linspace(0.5, 45, 40) * DEG
    s = heel_strike_study(w, q3)
    np.testing.assert_allclose(s.kinetic_energy_constrained, 0.0, atol=1e-13)
    np.testing.assert_allclose(s.velocity_post, s.velocity_pre, atol=1e-13)
    np.testing.assert_allclose(s.velocity_post[:, 1], 0.0, atol=1e-14)
    np.testing.assert_allclose(s.eta, 0.0, atol=1e-13)
    assert not s.trailing_foot_lifts.any()
    assert s.degenerate_wheel.all()


def test_Tc_falls_and_Ta_grows_with_radius():
    """At fixed q3: T_c falls with R everywhere; T_a grows with R over the admissible
    impacts (Fig. 2). Among non-admissible ones (q3 = 45 deg, R < 0.07 m) T_a dips slightly."""
    R = np.linspace(0.0, 1.0, 101)
    q3 = np.array([2.0, 10.0, 20.0, 30.0, 40.0, 45.0]) * DEG
    s = heel_strike_study(CompassGait(foot_radius=R[None, :]), q3[:, None])
    assert (np.diff(s.kinetic_energy_constrained, axis=1) < 0).all()
    assert (s.kinetic_energy_constrained[:, :-1] > 0).all()
    ok = s.trailing_foot_lifts | s.degenerate_wheel
    for i in range(len(q3)):
        T_a = s.kinetic_energy_admissible[i, ok[i]]
        assert len(T_a) > 50
        assert (np.diff(T_a) > 0).all()


@pytest.mark.parametrize("R", [0.0, 0.25, 0.5, 0.75, 0.9])
def test_shorter_steps_are_cheaper(R: float):
    """eta increases with q3 over the admissible impacts."""
    q3 = np.linspace(0.2, 45, 300) * DEG
    s = heel_strike_study(CompassGait(foot_radius=R), q3)
    ok = s.trailing_foot_lifts
    assert ok[:10].all()
    eta = s.eta[ok]
    assert (np.diff(eta) > 0).all()
    # and T_c grows with q3 too
    assert (np.diff(s.kinetic_energy_constrained[ok]) > 0).all()


def test_trailing_foot_lifts_for_all_angles_when_R_at_least_0p4():
    R = np.linspace(0.4, 0.999, 60)
    q3 = np.linspace(0.1, 45, 200) * DEG
    s = heel_strike_study(CompassGait(foot_radius=R[None, :]), q3[:, None])
    assert s.trailing_foot_lifts.all()
    assert (s.trailing_foot_velocity > 0).all()


def test_point_foot_stops_lifting_below_45_degrees():
    q3 = np.linspace(0.1, 45, 500) * DEG
    s = heel_strike_study(CompassGait(foot_radius=0.0), q3)
    lifts = s.trailing_foot_lifts
    assert lifts[0] and not lifts[-1]
    # a single switch: lifts below some angle, not above it
    switch = np.flatnonzero(np.diff(lifts.astype(int)))
    assert len(switch) == 1
    boundary = q3[switch[0]] / DEG
    assert 15.0 < boundary < 40.0
    # smaller R values stop lifting at smaller angles: the boundary moves right with R
    bounds = []
    for R in (0.0, 0.1, 0.2, 0.3):
        sr = heel_strike_study(CompassGait(foot_radius=R), q3)
        bounds.append(q3[np.argmin(sr.trailing_foot_lifts)])
    assert np.all(np.diff(bounds) > 0)


def test_broadcast_equals_looped_scalar_calls():
    R = np.array([0.0, 0.3, 0.8, 1.0])
    q3 = np.array([3.0, 17.0, 40.0]) * DEG
    w = CompassGait(foot_radius=R[None, :], leg_inertia=0.05)
    s = heel_strike_study(w, q3[:, None], q3_dot=1.3, q4_dot=-0.2, restitution=0.2)
    assert s.kinetic_energy.shape == (3, 4)
    for i, j in np.ndindex(3, 4):
        si = heel_strike_study(CompassGait(foot_radius=R[j], leg_inertia=0.05), q3[i],
                               q3_dot=1.3, q4_dot=-0.2, restitution=0.2)
        for name in ("kinetic_energy", "kinetic_energy_constrained", "kinetic_energy_admissible",
                     "energy_lost", "eta", "step_length", "velocity_post",
                     "constraint_impulse"):
            np.testing.assert_allclose(getattr(s, name)[i, j], getattr(si, name),
                                       rtol=1e-12, atol=1e-14, err_msg=name)
        assert s.trailing_foot_lifts[i, j] == si.trailing_foot_lifts
        assert s.foot_radius[i, j] == R[j] and s.impact_angle[i, j] == q3[i]


def test_zero_angle_has_undefined_eta():
    s = heel_strike_study(CompassGait(foot_radius=0.3), np.array([0.0, 0.1]))
    assert np.isnan(s.eta[0]) and np.isfinite(s.eta[1])


def test_figure_data_follow_the_admissibility_rules():
    fig2 = figure2_data()
    assert set(fig2["R_m"]) == {0.0, 0.25, 0.5, 0.75, 1.0}
    assert (fig2["q3_deg"] > 0).all() and fig2["q3_deg"].max() == pytest.approx(45.0)
    regular = ~fig2["degenerate_wheel"]
    assert (fig2.loc[regular, "q2_dot_plus_m_per_s"] > 0).all()
    assert (fig2.loc[~regular, "R_m"] == 1.0).all()
    # R = 0 stops before 45 deg, R = 0.5 covers the whole range
    assert fig2.loc[fig2["R_m"] == 0.0, "q3_deg"].max() < 40.0
    assert fig2.loc[fig2["R_m"] == 0.5, "q3_deg"].max() == pytest.approx(45.0)
    full = heel_strike_table()
    assert len(full) == 5 * 180 and len(fig2) < len(full)
    d = figure3b_data()
    assert d.eta.shape == (len(d.foot_radius), len(d.impact_angle))
    # white region = not admissible = nan; only at small R and large q3
    white = np.isnan(d.eta)
    assert white.any()
    assert not white[d.foot_radius > 0.4].any()
    assert (white == ~d.shown).all()
    # McGeer's wheel is shown (as in the paper), but its impacts are not admissible
    regular = ~d.degenerate_wheel
    np.testing.assert_array_equal(d.trailing_foot_lifts[regular], d.q2_dot_plus[regular] > 0)
    assert d.shown[d.degenerate_wheel].all()
    assert not d.trailing_foot_lifts[d.degenerate_wheel].any()
    np.testing.assert_allclose(d.eta[d.degenerate_wheel], 0.0, atol=1e-12)


def test_a_striking_foot_moving_up_is_not_a_heel_strike() -> None:
    """The paper's rates bring the leading foot down; reversed, it leaves the ground and the
    bilateral impact law would need a pulling (negative) normal impulse."""
    import math

    from heelstrike.analysis.heel_strike import (
        NotAHeelStrikeError,
        check_striking_foot_approaches,
    )
    from heelstrike.core.impact import impact
    from heelstrike.models import CompassGait, heel_strike_state

    w = CompassGait(foot_radius=0.25)
    q, qd = heel_strike_state(w, math.radians(20.0), q3_dot=1.0, q4_dot=0.0)
    check_striking_foot_approaches(w, q, qd)
    assert impact(w.mass_matrix(q), w.contact_jacobian(q, "left"), qd).constraint_impulse[1] > 0
    q, qd = heel_strike_state(w, math.radians(20.0), q3_dot=-1.0, q4_dot=0.0)
    with pytest.raises(NotAHeelStrikeError, match="moves away from the ground"):
        check_striking_foot_approaches(w, q, qd)
    assert impact(w.mass_matrix(q), w.contact_jacobian(q, "left"), qd).constraint_impulse[1] < 0


@pytest.mark.parametrize("e", [0.0, 0.35])
def test_compiled_heel_strike_study_agrees_with_the_reference(e: float) -> None:
    """The numba compass kernel (backend="compiled": an explicit Cholesky, no projectors) and
    the reference projectors (eqs. 5-13) are independent computations of one heel strike; over
    radii, angles, pre-impact rates and restitution they agree to round-off, and the compiled
    result satisfies T = T_c + T_a and A q_dot+ = -e A q_dot- on its own."""
    walker = CompassGait(foot_radius=np.linspace(0.0, 0.9, 7)[:, None], leg_inertia=0.02)
    angles = np.deg2rad(np.linspace(5.0, 40.0, 9))
    kw = {"q3_dot": 1.2, "q4_dot": -0.3, "restitution": e}
    ref = heel_strike_study(walker, angles, **kw)
    fast = heel_strike_study(walker, angles, backend="compiled", **kw)
    assert fast.impact is None and ref.impact is not None
    for name in ("kinetic_energy", "kinetic_energy_constrained", "kinetic_energy_admissible",
                 "kinetic_energy_post", "energy_lost", "eta", "step_length", "velocity_post",
                 "constraint_impulse", "velocity_pre"):
        np.testing.assert_allclose(getattr(fast, name), getattr(ref, name), rtol=1e-12,
                                   atol=1e-12, err_msg=name)
    np.testing.assert_array_equal(fast.trailing_foot_lifts, ref.trailing_foot_lifts)
    np.testing.assert_allclose(fast.kinetic_energy,
                               fast.kinetic_energy_constrained + fast.kinetic_energy_admissible,
                               rtol=1e-13)
    A = walker.contact_jacobian(fast.state, "left")
    np.testing.assert_allclose(np.einsum("...ij,...j->...i", A, fast.velocity_post),
                               -e * np.einsum("...ij,...j->...i", A, fast.velocity_pre),
                               atol=1e-12)
    with pytest.raises(ValueError, match="backend"):
        heel_strike_study(walker, angles, backend="numba")  # type: ignore[arg-type]


def test_symmetric_step_length_is_one_definition_and_its_inverse_any_walker() -> None:
    # QA sweep 6 (layout audit): L = 2 (l - R) sin q3 + 2 R q3 was written three times, and the
    # powered search built a CompassGait from a described walker to invert it
    from heelstrike.analysis.heel_strike import step_length, symmetric_step_length
    from heelstrike.analysis.powered import impact_angle_for_step_length
    from heelstrike.dynamics.phased import load_phased_walker
    from heelstrike.models.compass import CompassGait

    q3 = np.linspace(0.05, 1.4, 7)
    w = CompassGait(foot_radius=0.3)
    np.testing.assert_array_equal(step_length(w, q3), symmetric_step_length(q3, 1.0, 0.3))
    # the chord between the contact points plus the arc rolled, from the geometry itself
    chord = 2 * 0.7 * np.sin(q3)
    np.testing.assert_allclose(symmetric_step_length(q3, 1.0, 0.3), chord + 0.6 * q3, rtol=1e-15)
    kneed = load_phased_walker("kneed")
    l, R = float(kneed.scale.leg_length), float(kneed.foot_radii[0])
    for walker, (ll, rr) in ((w, (1.0, 0.3)), (kneed, (l, R))):
        for a in (0.1, 0.4, 1.2):
            L = float(symmetric_step_length(a, ll, rr))
            assert impact_angle_for_step_length(walker, L) == pytest.approx(a, abs=1e-12)
        assert np.isnan(impact_angle_for_step_length(walker, 2.0 * (ll - rr) + np.pi * rr + 0.1))


def test_loss_per_metre_is_eq_16_with_one_guard() -> None:
    # QA sweep 6 (layout audit): eta = loss / L was written six times, three without a guard
    # for L <= 0 (a divide-by-zero warning and inf)
    import warnings

    from heelstrike.analysis.heel_strike import loss_per_metre

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        eta = loss_per_metre([1.0, 2.0, 3.0, 0.5], [0.5, 0.0, -1.0, 0.25])
    np.testing.assert_array_equal(eta[[0, 3]], [2.0, 2.0])
    assert np.isnan(eta[1]) and np.isnan(eta[2])
    # the compass study's eta is it, with the study's own step length (eq. 16)
    from heelstrike.analysis.heel_strike import heel_strike_study
    from heelstrike.models.compass import CompassGait

    s = heel_strike_study(CompassGait(foot_radius=0.4), np.deg2rad([10.0, 25.0]))
    np.testing.assert_array_equal(s.eta, loss_per_metre(s.energy_lost, s.step_length))
