"""Full gaits: single support, hybrid simulation, limit cycles (issue 3).

The point-foot case is checked against an independent classical compass gait written here from
the literature's form of the equations (Goswami, Thuilot & Espiau 1998): absolute leg angles from
the *true* vertical, gravity vertical, the ground line tilted, and the impact solved from
conservation of angular momentum (whole walker about the new contact point; trailing leg about
the hip). heelstrike instead works in a slope-aligned frame with tilted gravity, floating-base
coordinates, and the paper's projector.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from heelstrike.analysis.limit_cycle import (
    continue_limit_cycle,
    find_limit_cycle,
)
from heelstrike.dynamics.hybrid import WalkStatus, ground_reaction, simulate
from heelstrike.dynamics.single_support import SingleSupport
from heelstrike.models.base import gravity_vector
from heelstrike.models.compass import CompassGait

SLOPE3 = np.deg2rad(3.0)
Z_R0_3DEG = np.array([-0.27102868, 1.09238359, -0.71500964])


# --------------------------------------------------------------------------------------------
# Independent classical compass gait (point feet, mH, m, a, b, l), literature form.
# --------------------------------------------------------------------------------------------
class ClassicalCompass:
    def __init__(self, mH=10.0, m=5.0, a=0.5, b=0.5, g=9.81, slope=SLOPE3):
        self.mH, self.m, self.a, self.b, self.g, self.gam = mH, m, a, b, g, slope
        self.l = a + b

    def eom(self, t, x):
        """M(phi) phi_dd + C(phi, phi_dot) + G(phi) = 0, phi = (stance, swing) absolute."""
        p1, p2, w1, w2 = x
        mH, m, a, b, l, g = self.mH, self.m, self.a, self.b, self.l, self.g
        c12 = np.cos(p1 - p2)
        s12 = np.sin(p1 - p2)
        M = np.array([[(mH + m) * l**2 + m * a**2, -m * l * b * c12], [-m * l * b * c12, m * b**2]])
        C = np.array([-m * l * b * s12 * w2**2, m * l * b * s12 * w1**2])
        G = np.array([-(mH * l + m * a + m * l) * g * np.sin(p1), m * b * g * np.sin(p2)])
        acc = np.linalg.solve(M, -C - G)
        return [w1, w2, acc[0], acc[1]]

    def _points(self, p1, p2, w1, w2, foot=None):
        """Positions and velocities of hip, stance COM, swing COM (true-vertical frame)."""
        a, b, l = self.a, self.b, self.l
        foot = np.zeros(2) if foot is None else foot

        def e(t):
            return np.array([-np.sin(t), np.cos(t)])

        def de(t):
            return np.array([-np.cos(t), -np.sin(t)])

        H = foot + l * e(p1)
        vH = l * de(p1) * w1
        return [
            (self.mH, H, vH),
            (self.m, foot + a * e(p1), a * de(p1) * w1),
            (self.m, H - b * e(p2), vH - b * de(p2) * w2),
        ]

    def impact(self, x):
        """Post-impact (new stance, new swing) from angular momentum conservation."""
        p1, p2, w1, w2 = x
        l = self.l
        new_foot = l * np.array([-np.sin(p1) + np.sin(p2), np.cos(p1) - np.cos(p2)])
        H = l * np.array([-np.sin(p1), np.cos(p1)])

        def cross(r, v):
            return r[0] * v[1] - r[1] * v[0]

        pre = self._points(p1, p2, w1, w2)
        L_total = sum(mm * cross(r - new_foot, v) for mm, r, v in pre)
        L_trail = self.m * cross(pre[1][1] - H, pre[1][2])  # old stance leg about the hip
        # unknown post-impact rates (W1 new stance = old swing leg, W2 new swing = old stance)
        rows, rhs = [], [L_total, L_trail]
        cols = []
        for unit in (np.array([1.0, 0.0]), np.array([0.0, 1.0])):
            post = self._points(p2, p1, unit[0], unit[1], foot=new_foot)
            Hn = post[0][1]
            cols.append(
                [
                    sum(mm * cross(r - new_foot, v) for mm, r, v in post),
                    self.m * cross(post[2][1] - Hn, post[2][2]),
                ]
            )
        rows = np.array(cols).T
        W = np.linalg.solve(rows, rhs)
        return np.array([p2, p1, W[0], W[1]])

    def step(self, x0, rtol=1e-12, atol=1e-12):
        """One step from a post-impact state; returns (time, pre-impact, post-impact)."""
        gam = self.gam

        def strike(t, x):  # slope-relative angles: psi1 + psi2 rises through 0
            return (x[0] - gam) + (x[1] - gam)

        strike.terminal, strike.direction = True, 1

        def midstance(t, x):
            return x[0] - gam

        midstance.terminal, midstance.direction = True, 1
        s1 = solve_ivp(
            self.eom, (0, 5), x0, method="DOP853", rtol=rtol, atol=atol, events=midstance
        )
        s2 = solve_ivp(
            self.eom, (s1.t[-1], 5), s1.y[:, -1], method="DOP853", rtol=rtol, atol=atol,
            events=strike,
        )
        pre = s2.y_events[0][0]
        return s2.t_events[0][0], pre, self.impact(pre)


def to_classical(q, q_dot, slope):
    """heelstrike (slope-frame q3, q4) -> absolute true-vertical angles and rates."""
    # heelstrike's angle q3 is measured from the slope normal; the ground rises towards +x
    # (x_hat = (cos, sin) slope), so the normal is the true vertical turned by +slope.
    return np.array([q[2] + slope, q[2] + q[3] + slope, q_dot[2], q_dot[2] + q_dot[3]])


def test_point_foot_matches_classical_compass_gait():
    walker = CompassGait(foot_radius=0.0)
    ref = ClassicalCompass(slope=SLOPE3)
    q, qd = walker.section_to_state(Z_R0_3DEG + np.array([0.01, -0.05, 0.1]))
    res = simulate(walker, q, qd, slope=SLOPE3, steps=4, rtol=1e-12, atol=1e-12)
    assert res.ok
    x = to_classical(q, qd, SLOPE3)
    t_total = 0.0
    for rec in res.impacts:
        t_step, pre, post = ref.step(x)
        t_total += t_step
        assert rec.time == pytest.approx(t_total, abs=1e-8)
        np.testing.assert_allclose(to_classical(rec.q, rec.q_dot_minus, SLOPE3), pre, atol=1e-8)
        q_new, qd_new = walker.swap_legs(rec.q, rec.q_dot_plus)
        np.testing.assert_allclose(to_classical(q_new, qd_new, SLOPE3), post, atol=1e-8)
        x = post


def test_point_foot_fixed_point_matches_classical_and_is_stable_at_3deg():
    walker = CompassGait(foot_radius=0.0)
    cycle = find_limit_cycle(walker, slope=SLOPE3, guess=Z_R0_3DEG + 0.003)
    assert cycle.residual < 1e-9
    assert cycle.stable and cycle.spectral_radius < 1.0
    ref = ClassicalCompass(slope=SLOPE3)
    x = to_classical(cycle.q, cycle.q_dot, SLOPE3)
    t_step, _, post = ref.step(x)
    np.testing.assert_allclose(post, x, atol=1e-8)  # also periodic for the classical model
    assert t_step == pytest.approx(cycle.period, abs=1e-8)
    # symmetric gait: step length 2 l sin(alpha) for point feet
    assert cycle.step_length == pytest.approx(2 * np.sin(cycle.impact_angle), rel=1e-9)


def test_short_step_gait_coexists_and_is_unstable():
    """The compass gait has a second, shorter period-one gait; it is unstable (Goswami 1998)."""
    walker = CompassGait(foot_radius=0.0)
    long = find_limit_cycle(walker, slope=SLOPE3, guess=Z_R0_3DEG)
    short = find_limit_cycle(walker, slope=SLOPE3, guess=[-0.257, 1.21, -0.50])
    assert short.impact_angle < long.impact_angle - 0.005
    assert long.stable and not short.stable
    assert short.collision_loss == pytest.approx(short.potential_energy_released, rel=1e-7)


@pytest.mark.slow
def test_period_doubling_at_steeper_slopes():
    """Goswami et al. (1998): the period-one gait loses stability by period doubling."""
    walker = CompassGait(foot_radius=0.0)
    cont = continue_limit_cycle(
        walker, "slope", np.deg2rad([4.0, 4.2, 4.4, 4.6]), guess=[-0.33, 1.2, -0.9],
        rtol=1e-10, atol=1e-10,
    )
    assert cont.stopped is None
    assert cont.cycles[0].stable and not cont.cycles[-1].stable
    assert cont.period_doubling.size == 1
    assert np.deg2rad(4.2) < cont.period_doubling[0] < np.deg2rad(4.6)


@pytest.mark.slow
def test_period_doubling_slope_has_one_definition():
    """Continuation (any walker, any parameter) and the stable-gait map locate the period
    doubling of the point-foot compass gait by the same refinement: they agree to 1e-4 deg
    although their brackets differ (0.5 deg here, 1 deg in the map), and at the slope found
    the smallest real multiplier is -1 to 1e-3."""
    from heelstrike.analysis.gait_map import gait_map, newton_gait

    walker = CompassGait(foot_radius=0.0)
    cont = continue_limit_cycle(
        walker, "slope", np.deg2rad([4.0, 4.5, 5.0]), guess=[-0.33, 1.2, -0.9],
        method="compiled", rtol=1e-11, atol=1e-11,
    )
    gm = gait_map(walker, [0.0], np.deg2rad([3.0, 4.0, 5.0]))
    assert cont.period_doubling.size == 1
    assert np.degrees(cont.period_doubling[0]) == pytest.approx(
        np.degrees(gm.period_doubling_slope[0]), abs=1e-4)
    g = newton_gait(walker, float(cont.period_doubling[0]), cont.cycles[0].fixed_point)
    assert g.smallest_real == pytest.approx(-1.0, abs=1e-3)


# --------------------------------------------------------------------------------------------
# Single support
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("radius", [0.0, 0.3, 0.7])
def test_energy_conserved_in_single_support(radius):
    walker = CompassGait(foot_radius=radius, leg_inertia=0.05)
    q, qd = walker.section_to_state([-0.25, 1.2, -0.6])
    res = simulate(walker, q, qd, slope=SLOPE3, steps=1, rtol=1e-12, atol=1e-12)
    assert res.t[res.step == 0][-1] > 0.3, res.message  # a substantial stretch of motion
    E = walker.mechanical_energy(res.q, res.q_dot, SLOPE3)
    first_step = res.step == 0
    assert np.ptp(E[first_step]) < 1e-9 * abs(E[0]) + 1e-9


def _random_state(rng, walker):
    q3, q4 = rng.uniform(-0.6, 0.6, 2)
    w3, w4 = rng.uniform(-2, 2, 2)
    R = walker.foot_radius
    q = np.array([rng.uniform(-1, 1), R, q3, q4])
    qd = np.array([-R * w3, 0.0, w3, w4])
    return q, qd


@pytest.mark.parametrize("radius", [0.0, 0.25, 0.8])
def test_reduced_dynamics_equal_constrained_form(radius):
    """J^T M J theta_dd = J^T (Bu - h) agrees with M q_dd + h = Bu + A^T lam, A q_dd = 0."""
    rng = np.random.default_rng(1)
    walker = CompassGait(foot_radius=radius, leg_inertia=0.02, hip_mass=7.0)

    def torque(t, q, qd):
        return np.array([0.3 * np.sin(q[3]) - 0.1 * qd[3]])

    sup = SingleSupport(walker=walker, slope=0.04, torque=torque)
    for _ in range(20):
        q, qd = _random_state(rng, walker)
        M = walker.mass_matrix(q)
        A = walker.contact_jacobian(q, "right")
        h = walker.bias_forces(q, qd, 0.04)
        Bu = walker.actuation_matrix() @ torque(0.0, q, qd)
        K = np.block([[M, -A.T], [A, np.zeros((2, 2))]])
        rhs = np.concatenate((Bu - h, -walker.contact_jacobian_rate(q, qd, "right")))
        sol = np.linalg.solve(K, rhs)
        np.testing.assert_allclose(sup.accelerations(0.0, q, qd), sol[:4], atol=1e-10)
        np.testing.assert_allclose(sup.ground_reaction(0.0, q, qd), sol[4:], atol=1e-9)


def test_ground_reaction_static_weight():
    """Standing still upright: normal force equals the weight, no friction needed."""
    walker = CompassGait(foot_radius=0.2)
    sup = SingleSupport(walker=walker)
    q = np.array([0.0, 0.2, 0.0, 0.0])
    lam = sup.ground_reaction(0.0, q, np.zeros(4))
    assert lam[1] == pytest.approx(float(walker.total_mass) * 9.81)
    assert lam[0] == pytest.approx(0.0, abs=1e-12)


def test_ground_reaction_along_walk_matches_centre_of_mass_acceleration():
    """Newton for the whole walker: F_ground + m g = m a_com (a_com by finite differences)."""
    walker = CompassGait(foot_radius=0.3)
    q, qd = walker.section_to_state([-0.38628396, 1.41932714, -0.96794436])
    walk = simulate(walker, q, qd, slope=SLOPE3, steps=1, max_step=1e-3, rtol=1e-12, atol=1e-12)
    gr = ground_reaction(walker, walk)
    assert np.all(gr.normal > 0) and np.all(gr.required_friction < 1.0)
    pos = walker.positions(walk.q)
    com = (10.0 * pos.hip + 5.0 * pos.right_leg_com + 5.0 * pos.left_leg_com) / 20.0
    sup = SingleSupport(walker=walker, slope=SLOPE3)
    for i in range(50, walk.t.size - 50, 97):
        dt = 1e-4
        qdd = sup.accelerations(0.0, walk.q[i], walk.q_dot[i])

        def c(h, i=i, qdd=qdd):
            qq = walk.q[i] + walk.q_dot[i] * h + 0.5 * qdd * h * h
            p = walker.positions(qq)
            return (10.0 * p.hip + 5.0 * p.right_leg_com + 5.0 * p.left_leg_com) / 20.0

        a_com = (c(dt) - 2 * c(0.0) + c(-dt)) / dt**2
        np.testing.assert_allclose(c(0.0), com[i], atol=1e-12)
        force = 20.0 * (a_com - gravity_vector(9.81, SLOPE3))
        np.testing.assert_allclose([gr.tangential[i], gr.normal[i]], force, atol=1e-4)


# --------------------------------------------------------------------------------------------
# Passive limit cycles and their energy books
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("radius", "slope_deg"),
    [(0.0, 3.0), pytest.param(0.3, 3.0, marks=pytest.mark.slow),
     pytest.param(0.5, 1.5, marks=pytest.mark.slow)],
)
def test_passive_limit_cycle_energy_books_balance(radius, slope_deg):
    walker = CompassGait(foot_radius=radius)
    slope = np.deg2rad(slope_deg)
    cycle = find_limit_cycle(walker, slope=slope)
    assert cycle.residual < 1e-9
    # eq. (14) with gravity doing the work: collision loss = potential energy released
    assert cycle.collision_loss == pytest.approx(cycle.potential_energy_released, rel=1e-7)
    # and the released energy is m_total g sin(slope) L_step
    drop = float(walker.total_mass) * 9.81 * np.sin(slope) * cycle.step_length
    assert cycle.potential_energy_released == pytest.approx(drop, rel=1e-9)
    # the symmetric periodic step has the paper's step length
    alpha = cycle.impact_angle
    assert cycle.step_length == pytest.approx(2 * (1 - radius) * np.sin(alpha) + 2 * radius * alpha)
    assert cycle.eta == pytest.approx(cycle.collision_loss / cycle.step_length)
    assert cycle.stable


def test_trailing_foot_lifts_and_impact_conserves_momentum_along_walk():
    walker = CompassGait(foot_radius=0.3)
    q, qd = walker.section_to_state([-0.38, 1.42, -0.97])
    res = simulate(walker, q, qd, slope=SLOPE3, steps=5)
    assert res.ok
    for rec in res.impacts:
        assert rec.trailing_normal_velocity > 0
        A_L = walker.contact_jacobian(rec.q, "left")
        np.testing.assert_allclose(A_L @ rec.q_dot_plus, 0.0, atol=1e-12)
        M = walker.mass_matrix(rec.q)
        np.testing.assert_allclose(M @ (rec.q_dot_plus - rec.q_dot_minus), A_L.T @ rec.impulse,
                                   atol=1e-10)
        assert rec.energy_lost == pytest.approx(
            walker.kinetic_energy(rec.q, rec.q_dot_minus)
            - walker.kinetic_energy(rec.q, rec.q_dot_plus)
        )


# --------------------------------------------------------------------------------------------
# Failure statuses
# --------------------------------------------------------------------------------------------
def test_walker_launched_too_slowly_falls_back():
    walker = CompassGait(foot_radius=0.0)
    q, qd = walker.section_to_state([-0.27, 0.3, -0.7])
    res = simulate(walker, q, qd, slope=SLOPE3, steps=3)
    assert res.status is WalkStatus.FELL_BACKWARD
    assert not res.ok and res.n_steps == 0
    assert "backward" in res.message


def test_walker_launched_too_fast_loses_contact():
    walker = CompassGait(foot_radius=0.0)
    q, qd = walker.section_to_state([-0.27, 6.0, -0.7])
    res = simulate(walker, q, qd, slope=SLOPE3, steps=3)
    assert res.status is WalkStatus.LOST_CONTACT


def test_bad_initial_state_is_rejected():
    walker = CompassGait(foot_radius=0.2)
    with pytest.raises(ValueError, match="stance foot"):
        simulate(walker, np.array([0.0, 0.3, -0.2, 0.4]), np.zeros(4))


@pytest.mark.slow
def test_period_doubling_of_a_described_walker_has_the_same_definition():
    """The described-walker gait map locates period doubling with the same refinement: on the
    compass walker described in TOML (the paper's compass, built from its description) it finds
    the point-foot compass gait's period doubling to 1e-3 deg from a 0.5 deg grid, where the
    linear interpolation it used before is off by more than the refinement's tolerance."""
    from heelstrike.analysis.gait_map import gait_map, model_gait_map
    from heelstrike.models import load_walker

    slopes = np.deg2rad([4.0, 4.5])
    ref = gait_map(CompassGait(foot_radius=0.0), [0.0], np.deg2rad([3.0, 4.0, 5.0]))
    pd_ref = np.degrees(ref.period_doubling_slope[0])
    gm = model_gait_map(load_walker("compass"), "R", [0.0], slopes)
    pd = np.degrees(float(gm.dataset["period_doubling_slope"].values[0]))
    assert pd == pytest.approx(pd_ref, abs=1e-3)
    m = gm.dataset["smallest_real_multiplier"].values[0]
    linear = 4.0 + 0.5 * (m[0] + 1.0) / (m[0] - m[1])
    assert abs(linear - pd_ref) > 1e-3  # the old rule: a different answer


def test_continuation_says_where_it_stopped_in_degrees():
    """A continuation in the slope that runs out of gaits says at which slope, in degrees (the
    point-foot compass gait has a gait at 3 deg, none at 20 deg)."""
    cont = continue_limit_cycle(CompassGait(), "slope", np.deg2rad([3.0, 20.0]),
                                guess=[-0.2705, 1.2, -0.9], method="compiled")
    assert len(cont.cycles) == 1 and cont.values[0] == pytest.approx(np.deg2rad(3.0))
    assert cont.stopped is not None and cont.stopped.startswith("no gait at slope 20 deg: ")
