"""Exact step-map Jacobians (variational equations + saltation matrices) against independent
derivatives of the step map: central differences of the nominal map, and their Richardson
extrapolation at tight tolerances."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.analysis.newton import floquet_multipliers
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.phased import PhasedWalker, TorsoPD, load_phased_walker
from heelstrike.dynamics.variational import (
    ExactJacobianUnavailable,
    StepFailedError,
    step_jacobian,
)
from heelstrike.models import CompassGait

KNEED_SLOPE = 0.0504
KNEED_GUESS = [-0.2647694, 1.2181144, -1.0955048]
TORSO_GUESS = [-0.1180757, 0.1118158, 0.5531974, -0.0140899, -0.6214368]


def _gait(R: float, slope_deg: float) -> tuple[PoincareMap, np.ndarray]:
    walker = CompassGait(foot_radius=R)
    slope = float(np.deg2rad(slope_deg))
    cycle = find_limit_cycle(walker, slope=slope)
    return PoincareMap(walker=walker, slope=slope), cycle.fixed_point


@pytest.mark.parametrize(("R", "slope_deg"), [(0.0, 1.0), (0.0, 3.0), (0.0, 4.3), (0.0, 5.0),
                                              (0.3, 1.0), (0.3, 3.0), (0.3, 4.3)])
def test_compass_exact_jacobian_matches_central_differences(R: float, slope_deg: float) -> None:
    pmap, z = _gait(R, slope_deg)
    exact = pmap.exact_jacobian(z)
    central = pmap.jacobian(z, 1e-6)
    assert np.allclose(exact.z_next, z, atol=1e-9)  # at the fixed point
    assert np.max(np.abs(exact.jacobian - central)) < 1e-7
    # the multipliers of the exact Jacobian are those of the search (central differences)
    m_exact = np.sort(np.abs(np.linalg.eigvals(exact.jacobian)))
    m_central = np.sort(np.abs(np.linalg.eigvals(central)))
    assert np.allclose(m_exact, m_central, atol=1e-6)


def test_compass_exact_jacobian_matches_richardson_extrapolation() -> None:
    """At rtol = atol = 1e-13 the Richardson extrapolation of central differences
    ``(4 D(h/2) - D(h)) / 3`` (truncation O(h^4)) agrees with the exact Jacobian far below
    central differences' own accuracy: the variational part is exact, not just consistent."""
    walker = CompassGait()
    slope = float(np.deg2rad(3.0))
    z = find_limit_cycle(walker, slope=slope).fixed_point
    tight = PoincareMap(walker=walker, slope=slope, rtol=1e-13, atol=1e-13)
    exact = tight.exact_jacobian(z).jacobian
    h = 2.5e-4
    richardson = (4.0 * tight.jacobian(z, h / 2) - tight.jacobian(z, h)) / 3.0
    plain = tight.jacobian(z, h)
    assert np.max(np.abs(plain - exact)) > 1e-5  # the comparison resolves an O(h^2) error
    assert np.max(np.abs(richardson - exact)) < 1e-9  # measured 2.2e-10 (h^4 = 4e-15)


def test_naive_product_gives_wrong_multipliers() -> None:
    """Without the event-time corrections (saltation and section projection) the product of
    reset and flow Jacobians is a different matrix with different multipliers: on the stable
    3 deg gait it even predicts instability."""
    pmap, z = _gait(0.0, 3.0)
    res = pmap.exact_jacobian(z)
    central = pmap.jacobian(z)
    rho_exact = np.max(np.abs(np.linalg.eigvals(res.jacobian)))
    rho_naive = np.max(np.abs(np.linalg.eigvals(res.naive)))
    rho_central = np.max(np.abs(np.linalg.eigvals(central)))
    assert abs(rho_exact - rho_central) < 1e-6
    assert rho_exact < 1.0 < rho_naive
    assert np.max(np.abs(res.naive - central)) > 1.0


def test_jacobian_method_argument() -> None:
    pmap, z = _gait(0.0, 3.0)
    assert np.array_equal(pmap.jacobian(z, method="exact"), pmap.exact_jacobian(z).jacobian)
    with pytest.raises(ValueError, match="'central' or 'exact'"):
        pmap.jacobian(z, method="forward")


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


def test_kneed_exact_jacobian_through_the_knee_strike(kneed: PhasedWalker) -> None:
    gait = find_model_gait(kneed, slope=KNEED_SLOPE, guess=KNEED_GUESS)
    z = gait.fixed_point
    pmap = PoincareMap(walker=kneed, slope=KNEED_SLOPE)
    res = pmap.exact_jacobian(z)
    assert res.events == ("knee_strike", "heel_strike")
    central = pmap.jacobian(z, 1e-6)
    assert np.max(np.abs(res.jacobian - central)) < 1e-7
    assert np.max(np.abs(res.naive - central)) > 1.0


def test_torso_exact_jacobian_with_torque_and_push_off() -> None:
    """The torso walker's PD torque (stiff: central differences' truncation error is
    ``~1e4 h^2``) and push-off: the difference to central differences falls as ``h^2``, and
    the Richardson extrapolation agrees with the exact Jacobian."""
    torso = load_phased_walker("torso")
    law, push = TorsoPD(walker=torso), PushOff(impulse=2.0)
    gait = find_model_gait(torso, slope=0.0, guess=TORSO_GUESS, torque=law, push_off=push)
    z = gait.fixed_point
    pmap = PoincareMap(walker=torso, slope=0.0, torque=law, push_off=push)
    exact = pmap.exact_jacobian(z).jacobian
    errors = [np.max(np.abs(pmap.jacobian(z, h) - exact)) for h in (1e-3, 1e-4)]
    assert 50.0 < errors[0] / errors[1] < 200.0  # O(h^2): the exact Jacobian is their limit
    h = 1e-4
    richardson = (4.0 * pmap.jacobian(z, h / 2) - pmap.jacobian(z, h)) / 3.0
    assert np.max(np.abs(richardson - exact)) < 1e-6 * max(1.0, np.max(np.abs(exact)))


def test_errors() -> None:
    walker = CompassGait()
    with pytest.raises(StepFailedError, match="no step"):
        step_jacobian(walker, [-0.3, -2.0, 0.0], slope=0.05)

    class OwnStep(CompassGait):  # a hand-written walker without a description
        @property
        def compiled_kernel(self) -> None:  # type: ignore[override]
            return None

    with pytest.raises(ExactJacobianUnavailable, match="no generated equations"):
        step_jacobian(OwnStep(), [-0.27, 1.09, -0.72], slope=0.05)

    class CurvedSection(CompassGait):  # a section map that is not affine in z
        def section_to_state(self, z: Any) -> tuple[np.ndarray, np.ndarray]:
            q, qd = super().section_to_state(z)
            qd = qd.copy()
            qd[3] = qd[3] * (1.0 + 0.01 * q[2] ** 2)
            return q, qd

    with pytest.raises(ExactJacobianUnavailable, match="not affine"):
        step_jacobian(CurvedSection(), [-0.27, 1.09, -0.72], slope=0.05)
    with pytest.raises(ValueError, match="scipy reference"):
        PoincareMap(walker=walker, slope=0.05, method="compiled").exact_jacobian([-0.27, 1, 0])


# -- a 30-digit reference: independent Lagrangian, Gragg-Bulirsch-Stoer in mpmath -----------------
def _mp_compass_step_map(walker: CompassGait, slope_deg: float, *, pd: Any = None,
                         impulse: float = 0.0) -> Any:
    """The compass gait's step map in 30-digit arithmetic, derived here from its Lagrangian
    (sympy; the stance foot's arc of radius ``R`` rolls: its centre at ``(-R q3, R)``),
    integrated by Gragg-Bulirsch-Stoer extrapolation (order 18, macro step 1/40 s), the heel
    strike ``2 q3 + q4 = 0`` located by ``mpmath.findroot`` and resolved by the inert impact
    with the swing foot's rolling-contact Jacobian in floating-base coordinates.

    Actuated: ``pd = (kp, kd, A)`` adds the hip torque ``u = kp (-2 A - q4) - kd q4_dot``
    (unsaturated) to the ``q4`` equation (``B = e4``; the stance foot's rolling leaves it
    there); ``impulse`` ``p`` adds, just before the strike, ``M^-1 A_st^T p e(q3)`` to the
    velocities, ``A_st`` the stance foot's rolling-contact Jacobian, ``e = (-sin, cos)``."""
    import mpmath as mp
    import sympy as sp

    par = {k: sp.nsimplify(repr(float(v))) for k, v in walker.parameters.items()}
    mH, m, ln, b = par["hip_mass"], par["leg_mass"], par["leg_length"], par["leg_com_from_hip"]
    inertia, g, R = par["leg_inertia"], par["gravity"], par["foot_radius"]
    x, y, q3, q4, xd, yd, w3, w4, gam = sp.symbols("x y q3 q4 xd yd w3 w4 gamma", real=True)

    def e(th: Any) -> Any:
        return sp.Matrix([-sp.sin(th), sp.cos(th)])

    q, qd = [x, y, q3, q4], [xd, yd, w3, w4]
    hip = sp.Matrix([x, y]) + (ln - R) * e(q3)  # (x, y): the stance foot's arc centre
    points = [(mH, hip), (m, hip - b * e(q3)), (m, hip - b * e(q3 + q4))]
    swing_centre = hip - (ln - R) * e(q3 + q4)
    # the swing foot's contact point moves with its arc centre plus R times the leg's rate
    roll = sp.Matrix([[0, 0, R, R], [0, 0, 0, 0]])

    def vel(r: Any) -> Any:
        return r.jacobian(q) * sp.Matrix(qd)

    T = sum(mi * (vel(r).T * vel(r))[0] for mi, r in points) / 2 \
        + inertia * (w3**2 + (w3 + w4) ** 2) / 2
    V = sum(mi * g * (sp.sin(gam) * r[0] + sp.cos(gam) * r[1]) for mi, r in points)
    pinned = {x: -R * q3, y: R, xd: -R * w3, yd: 0}  # rolling without slip
    if pd is not None:
        kp, kd, amp = (sp.nsimplify(repr(float(v))) for v in pd)
        hip_torque = sp.Matrix([0, kp * (-2 * amp - q4) - kd * w4])
    else:
        hip_torque = sp.zeros(2, 1)
    T2, V2 = T.subs(pinned), V.subs(pinned)
    th, om = [q3, q4], [w3, w4]
    M2 = sp.hessian(T2, om)
    rhs = -(sp.Matrix([sp.diff(T2, o) for o in om]).jacobian(th) * sp.Matrix(om)
            - sp.Matrix([sp.diff(T2, t) for t in th]) + sp.Matrix([sp.diff(V2, t) for t in th])) \
        + hip_torque
    f_M2 = sp.lambdify((q3, q4), list(M2), "mpmath", cse=True)
    f_rhs = sp.lambdify((q3, q4, w3, w4, gam), list(rhs), "mpmath", cse=True)
    f_M = sp.lambdify((q3, q4), sp.hessian(T, qd).subs(pinned), "mpmath")
    f_A = sp.lambdify((q3, q4), (swing_centre.jacobian(q) + roll).subs(pinned), "mpmath")
    roll_stance = sp.Matrix([[0, 0, R, 0], [0, 0, 0, 0]])
    f_As = sp.lambdify((q3, q4), (sp.Matrix([x, y]).jacobian(q) + roll_stance).subs(pinned),
                       "mpmath")
    p_mp = mp.mpf(repr(float(impulse)))
    gamma = mp.radians(slope_deg)
    R_mp = mp.mpf(float(walker.foot_radius))

    def field(s: list[Any]) -> list[Any]:
        m11, m12, m21, m22 = f_M2(s[0], s[1])
        r1, r2 = f_rhs(s[0], s[1], s[2], s[3], gamma)
        det = m11 * m22 - m12 * m21
        return [s[2], s[3], (m22 * r1 - m12 * r2) / det, (m11 * r2 - m21 * r1) / det]

    def gbs(y0: list[Any], H: Any, k: int = 9) -> list[Any]:
        rows: list[list[list[Any]]] = []
        for j in range(1, k + 1):
            n = 2 * j
            h = H / n
            z0, z1 = y0, [a + h * f for a, f in zip(y0, field(y0), strict=True)]
            for _ in range(n - 1):
                z0, z1 = z1, [a + 2 * h * f for a, f in zip(z0, field(z1), strict=True)]
            row = [[(a + c + h * f) / 2 for a, c, f in zip(z0, z1, field(z1), strict=True)]]
            for i in range(1, j):
                r = (mp.mpf(n) / (n - 2 * i)) ** 2
                row.append([c + (c - p) / (r - 1)
                            for c, p in zip(row[i - 1], rows[-1][i - 1], strict=True)])
            rows.append(row)
        return rows[-1][-1]

    def step(z: list[Any], t_guess: float) -> list[Any]:
        H = mp.mpf(1) / 40
        nodes = [[z[0], -2 * z[0], z[1], z[2]]]
        while H * len(nodes) < t_guess - H / 2:
            nodes.append(gbs(nodes[-1], H))
        base = H * (len(nodes) - 1)
        t_e = mp.findroot(lambda t: (lambda s: 2 * s[0] + s[1])(gbs(nodes[-1], t - base)),
                          mp.mpf(t_guess))
        s = gbs(nodes[-1], t_e - base)
        M, A = mp.matrix(f_M(s[0], s[1])), mp.matrix(f_A(s[0], s[1]))
        v = mp.matrix([-R_mp * s[2], 0, s[2], s[3]])
        if impulse:
            push = mp.matrix([-mp.sin(s[0]), mp.cos(s[0])]) * p_mp
            v = v + M**-1 * (mp.matrix(f_As(s[0], s[1])).T * push)
        MiAt = M**-1 * A.T
        vp = v - MiAt * mp.lu_solve(A * MiAt, A * v)
        return [s[0] + s[1], vp[2] + vp[3], -vp[3]]  # relabelled: (q3, q3_dot, q4_dot)

    return step


@pytest.mark.slow
@pytest.mark.parametrize(("R", "slope_deg"), [(0.0, 4.3), (0.0, 1.0), (0.3, 3.0)])
def test_compass_exact_jacobian_matches_30_digit_reference(R: float, slope_deg: float) -> None:
    """The exact Jacobian (rtol = atol = 1e-13) against central differences of the 30-digit
    step map with steps of 1e-10 (truncation ~1e-20, integration error ~1e-26 / 1e-10), to
    1e-10; 4.3 deg is near the period doubling."""
    import mpmath as mp

    walker = CompassGait(foot_radius=R)
    slope = float(np.deg2rad(slope_deg))
    z = find_limit_cycle(walker, slope=slope).fixed_point
    pmap = PoincareMap(walker=walker, slope=slope, rtol=1e-13, atol=1e-13)
    res = pmap.exact_jacobian(z)
    with mp.workdps(30):
        step = _mp_compass_step_map(walker, slope_deg)
        zm = [mp.mpf(float(v)) for v in z]
        t_e = res.event_times[-1]
        delta = mp.mpf("1e-10")
        ref = np.empty((3, 3))
        for k in range(3):
            zp, zn = list(zm), list(zm)
            zp[k] += delta
            zn[k] -= delta
            col = [(a - c) / (2 * delta) for a, c in zip(step(zp, t_e), step(zn, t_e),
                                                          strict=True)]
            ref[:, k] = [float(c) for c in col]
        assert np.allclose([float(c) for c in step(zm, t_e)], res.z_next, atol=1e-11)
    assert np.max(np.abs(res.jacobian - ref)) < 1e-10


def test_passive_gait_multipliers_are_exact_by_default() -> None:
    """A passive gait found on the scipy reference reports the eigenvalues of the exact
    Jacobian (not those of central differences, which differ by ~1e-8)."""
    walker = CompassGait()
    slope = float(np.deg2rad(4.3))
    cycle = find_limit_cycle(walker, slope=slope)
    pmap = PoincareMap(walker=walker, slope=slope)
    exact = floquet_multipliers(pmap.exact_jacobian(cycle.fixed_point).jacobian)
    central = floquet_multipliers(pmap.jacobian(cycle.fixed_point))
    assert np.allclose(cycle.multipliers, exact, rtol=0, atol=1e-13)
    assert not np.allclose(cycle.multipliers, central, rtol=0, atol=1e-13)


# -- actuated steps: a torque law's derivatives in the variational equations, the push-off in
# the heel strike's reset, actuation parameters as zero-rate states ------------------------------
Z_POWERED = [-0.2, 1.0, -0.4]


def _actuated_map(walker: CompassGait, torque: Any, push: Any) -> PoincareMap:
    return PoincareMap(walker=walker, slope=0.0, torque=torque, push_off=push, rtol=1e-12,
                       atol=1e-12)


def _law_column(walker: CompassGait, torque: Any, push: Any, name: str, z: Any) -> np.ndarray:
    """``dP/da`` by central differences (step 1e-6 relative) of the map with the actuation's
    parameter ``a = name`` changed."""
    import dataclasses

    owner = push if name == "impulse" else torque
    a = float(getattr(owner, name))
    h = 1e-6 * max(1.0, abs(a))
    changed = [dataclasses.replace(owner, **{name: a + s}) for s in (h, -h)]
    maps = [_actuated_map(walker, torque, c) if name == "impulse"
            else _actuated_map(walker, c, push) for c in changed]
    return np.asarray((maps[0](z) - maps[1](z)) / (2.0 * h))


@pytest.mark.parametrize("R", [0.0, 0.3])
def test_hip_pd_step_jacobian_matches_central_differences(R: float) -> None:
    """A compass step driven by the swing-leg PD law (the torque's derivatives in ``q4``,
    ``q4_dot`` and in its amplitude and gains enter the variational equations): ``DP`` and
    ``dP/d(A, kp, kd)`` agree with central differences of the map."""
    from heelstrike.dynamics.actuation import SwingLegPD

    walker = CompassGait(foot_radius=R)
    law = SwingLegPD(amplitude=0.2)
    names = ("amplitude", "kp", "kd")
    res = step_jacobian(walker, Z_POWERED, slope=0.0, torque=law, parameters=names,
                        rtol=1e-12, atol=1e-12)
    pmap = _actuated_map(walker, law, None)
    assert np.allclose(res.z_next, pmap(Z_POWERED), atol=1e-10)
    assert np.max(np.abs(res.jacobian - pmap.jacobian(Z_POWERED, 1e-6))) < 1e-7
    passive = PoincareMap(walker=walker, slope=0.0, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(res.jacobian - passive.jacobian(Z_POWERED, 1e-6))) > 0.1  # the law acts
    for i, name in enumerate(names):
        column = _law_column(walker, law, None, name, Z_POWERED)
        assert np.max(np.abs(res.parameter_jacobian[:, i] - column)) < 1e-7, name
    assert np.max(np.abs(res.parameter_jacobian[:, 0])) > 0.1


def test_push_off_step_jacobian_matches_central_differences() -> None:
    """A compass step with a push-off impulse (its Jacobian in the state and in the impulse in
    the heel strike's reset), parameters in the caller's order (``impulse`` after a walker
    parameter)."""
    walker = CompassGait(foot_radius=0.3)
    push = PushOff(impulse=3.0)
    res = step_jacobian(walker, Z_POWERED, slope=0.0, push_off=push,
                        parameters=("leg_mass", "impulse"), rtol=1e-12, atol=1e-12)
    pmap = _actuated_map(walker, None, push)
    scale = max(1.0, float(np.max(np.abs(res.jacobian))))  # entries up to ~19 here
    assert np.max(np.abs(res.jacobian - pmap.jacobian(Z_POWERED, 1e-6))) < 1e-7 * scale
    column = _law_column(walker, None, push, "impulse", Z_POWERED)
    assert np.max(np.abs(res.parameter_jacobian[:, 1] - column)) < 1e-7
    assert np.max(np.abs(column)) > 1e-2
    alone = step_jacobian(walker, Z_POWERED, slope=0.0, push_off=push, parameters=("leg_mass",),
                          rtol=1e-12, atol=1e-12)
    assert np.allclose(res.parameter_jacobian[:, 0], alone.parameter_jacobian[:, 0],
                       rtol=0, atol=1e-12)


def test_energy_tracking_and_saturated_laws_match_central_differences() -> None:
    """The energy-tracking law (``E = T + V`` from the generated equations) with its target
    and gain, and a sum of laws saturated for part of the step (the constant torque has no
    derivative there), against central differences."""
    from heelstrike.dynamics.actuation import EnergyTracking, SwingLegPD, mechanical_energy

    walker = CompassGait()
    E0 = float(mechanical_energy(walker, *walker.section_to_state(np.array(Z_POWERED))))
    law = EnergyTracking(walker=walker, energy=E0 + 2.0)
    res = step_jacobian(walker, Z_POWERED, slope=0.0, torque=law,
                        parameters=("gain", "energy"), rtol=1e-12, atol=1e-12)
    pmap = _actuated_map(walker, law, None)
    assert np.max(np.abs(res.jacobian - pmap.jacobian(Z_POWERED, 1e-6))) < 1e-7
    for i, name in enumerate(("gain", "energy")):
        column = _law_column(walker, law, None, name, Z_POWERED)
        assert np.max(np.abs(res.parameter_jacobian[:, i] - column)) < 1e-7, name
    both = law + SwingLegPD(amplitude=0.2, kp=50.0, max_torque=8.0)
    sat = step_jacobian(walker, Z_POWERED, slope=0.0, torque=both, rtol=1e-12, atol=1e-12)
    central = _actuated_map(walker, both, None).jacobian(Z_POWERED, 1e-6)
    assert np.max(np.abs(sat.jacobian - central)) < 1e-6
    assert np.max(np.abs(sat.jacobian - res.jacobian)) > 0.1


def test_unknown_actuation_parameter_is_refused() -> None:
    from heelstrike.dynamics.actuation import SwingLegPD

    with pytest.raises(ValueError, match=r"'impulse' is not a parameter of CompassGait "
                                         r".*; its actuation's: amplitude"):
        step_jacobian(CompassGait(), Z_POWERED, slope=0.0, torque=SwingLegPD(amplitude=0.2),
                      parameters=("impulse",))
    # the documented parameters are those differentiated
    from heelstrike.dynamics.actuation import EnergyTracking
    from heelstrike.dynamics.variational import ACTUATION_PARAMETERS, _Actuation

    walker = CompassGait()
    for torque, push in ((SwingLegPD(amplitude=0.2), None), (None, PushOff(impulse=1.0)),
                         (EnergyTracking(walker=walker, energy=150.0), None)):
        owner = push if torque is None else torque
        assert tuple(_Actuation.of(torque, push, ()).values) == \
            ACTUATION_PARAMETERS[type(owner).__name__]


@pytest.mark.slow
@pytest.mark.parametrize(("R", "actuation"), [(0.3, "pd"), (0.0, "push"), (0.3, "push")])
def test_actuated_exact_jacobian_matches_30_digit_reference(R: float, actuation: str) -> None:
    """The actuated step's exact Jacobian (rtol = atol = 1e-13) against central differences
    (steps 1e-10) of the 30-digit step map derived independently with the hip PD torque or the
    push-off, to 1e-10."""
    import mpmath as mp

    from heelstrike.dynamics.actuation import SwingLegPD

    walker = CompassGait(foot_radius=R)
    law = SwingLegPD(amplitude=0.2, max_torque=np.inf) if actuation == "pd" else None
    push = PushOff(impulse=3.0) if actuation == "push" else None
    res = step_jacobian(walker, Z_POWERED, slope=0.0, torque=law, push_off=push,
                        rtol=1e-13, atol=1e-13)
    with mp.workdps(30):
        step = _mp_compass_step_map(
            walker, 0.0, pd=None if law is None else (law.kp, law.kd, law.amplitude),
            impulse=0.0 if push is None else push.impulse)
        zm = [mp.mpf(repr(v)) for v in Z_POWERED]
        t_e = res.event_times[-1]
        delta = mp.mpf("1e-10")
        ref = np.empty((3, 3))
        for k in range(3):
            zp, zn = list(zm), list(zm)
            zp[k] += delta
            zn[k] -= delta
            ref[:, k] = [float((a - c) / (2 * delta))
                         for a, c in zip(step(zp, t_e), step(zn, t_e), strict=True)]
        assert np.allclose([float(c) for c in step(zm, t_e)], res.z_next, atol=1e-11)
    assert np.max(np.abs(res.jacobian - ref)) < 1e-10  # measured 2e-13 to 3.5e-12


@pytest.fixture(scope="module")
def powered_gaits() -> dict[str, Any]:
    from heelstrike.analysis.powered import find_powered_gait

    walker = CompassGait(foot_radius=0.3)
    return {act: find_powered_gait(walker, actuation=act, speed=0.5)
            for act in ("hip-pd", "pushoff")}


@pytest.mark.parametrize("actuation", ["hip-pd", "pushoff"])
def test_powered_gait_multipliers_are_exact_and_agree_with_differences(
        powered_gaits: dict[str, Any], actuation: str) -> None:
    """A powered gait's multipliers come from the exact Jacobian by default, and agree with
    those of central differences (the former default) to 1e-6."""
    from heelstrike.analysis.powered import _Problem, _section_jacobian, actuation_family

    gait = powered_gaits[actuation]
    walker = CompassGait(foot_radius=0.3)
    prob = _Problem(walker=walker, family=actuation_family(actuation), target="speed",
                    rtol=1e-10, atol=1e-10)
    x = np.append(gait.fixed_point, gait.actuation.parameter)
    DP, kind = _section_jacobian(prob, x, 1e-6)
    central, kind_c = _section_jacobian(prob, x, 1e-6, "central")
    assert (kind, kind_c) == ("exact", "central")
    np.testing.assert_array_equal(gait.multipliers, floquet_multipliers(DP))
    np.testing.assert_allclose(gait.multipliers, floquet_multipliers(central), rtol=0,
                               atol=1e-6)
    # the exact Jacobian is the limit of the differences, not a copy of them
    assert 0.0 < np.max(np.abs(DP - central)) < 1e-5


def test_powered_limit_cycle_newton_runs_on_the_exact_jacobian(
        powered_gaits: dict[str, Any]) -> None:
    """``find_limit_cycle`` with the hip PD law of a powered gait: Newton on the exact
    Jacobian (built-in laws are differentiable), to the same fixed point."""
    from heelstrike.analysis.limit_cycle import _exact_newton_ok
    from heelstrike.analysis.powered import actuation_family

    gait = powered_gaits["hip-pd"]
    walker = CompassGait(foot_radius=0.3)
    law, _ = actuation_family("hip-pd").build(walker, gait.actuation.parameter)
    assert _exact_newton_ok(PoincareMap(walker=walker, slope=0.0, torque=law))
    cycle = find_limit_cycle(walker, slope=0.0, torque=law, guess=gait.fixed_point + 1e-3)
    assert cycle.newton_jacobian == "exact"
    np.testing.assert_allclose(cycle.fixed_point, gait.fixed_point, rtol=0, atol=1e-7)
    np.testing.assert_allclose(cycle.multipliers, gait.multipliers, rtol=0, atol=1e-6)


@pytest.mark.parametrize(("actuation", "names"), [("hip-pd", ("amplitude", "kd", "leg_mass")),
                                                  ("pushoff", ("impulse",))])
def test_powered_gait_sensitivity_to_actuation_parameters(
        powered_gaits: dict[str, Any], actuation: str, names: tuple[str, ...]) -> None:
    """``gait_sensitivity`` of a powered gait in its actuation's amplitude, gain or impulse
    (and a walker parameter): exact, and equal to central differences of the map."""
    from heelstrike.analysis.powered import actuation_family
    from heelstrike.analysis.sensitivity import gait_sensitivity

    gait = powered_gaits[actuation]
    walker = CompassGait(foot_radius=0.3)
    law, push = actuation_family(actuation).build(walker, gait.actuation.parameter)
    kw: dict[str, Any] = {"slope": 0.0, "torque": law, "push_off": push, "multipliers": False}
    exact = gait_sensitivity(walker, gait.fixed_point, names, **kw)
    central = gait_sensitivity(walker, gait.fixed_point, names, method="central", **kw)
    assert all(exact.exact) and not any(central.exact)
    scale = np.maximum(1.0, np.abs(exact.fixed_point))
    assert np.max(np.abs(exact.fixed_point - central.fixed_point) / scale) < 1e-6
    assert np.max(np.abs(exact.fixed_point)) > 1e-2
    for key in ("period", "speed", "step_length"):
        np.testing.assert_allclose(exact.quantities[key], central.quantities[key], rtol=1e-5,
                                   atol=1e-7)
    with pytest.raises(ValueError, match="its actuation's"):
        gait_sensitivity(walker, gait.fixed_point, ("nonsense",), **kw)


@pytest.mark.parametrize("function", [
    # reduces over its input: on a batch of states it would mix them
    lambda t, q, qd: -0.3 * np.sum(qd * np.array([0.0, 0.0, 0.0, 1.0])),
    # written for one state
    lambda t, q, qd: -3.0 * qd[3] + 2.0 * np.sin(q[2]),
])
def test_a_sum_with_a_user_function_matches_central_differences(function: Any) -> None:
    """Review finding: in a sum, a :class:`CustomTorque` part was handed the whole batch of
    complex states, so a function reducing over its input mixed the Jacobian's columns (off
    by 0.25, silently) and a one-state function crashed. Every user function is called state
    by state (a torque law takes one state)."""
    from heelstrike.dynamics.actuation import CustomTorque, SwingLegPD

    walker = CompassGait(foot_radius=0.3)
    law = SwingLegPD(amplitude=0.0675) + CustomTorque(function=function)
    res = step_jacobian(walker, Z_POWERED, slope=0.0, torque=law, rtol=1e-12, atol=1e-12)
    pmap = _actuated_map(walker, law, None)
    assert np.allclose(res.z_next, pmap(Z_POWERED), atol=1e-10)
    assert np.max(np.abs(res.jacobian - pmap.jacobian(Z_POWERED, 1e-6))) < 1e-6


def test_a_law_written_as_its_own_call_still_works() -> None:
    """Review finding: a :class:`HipTorque` subclass written as ``__call__`` (the one way
    before ``evaluate``) raised ``NotImplementedError`` in a sum and in the exact Jacobian.
    It is called as it is: the sum is the sum of the parts, and a law that takes complex
    states gets an exact Jacobian equal to central differences."""
    from dataclasses import dataclass

    from heelstrike.dynamics.actuation import HipTorque, SwingLegPD

    @dataclass(frozen=True, kw_only=True)
    class Damper(HipTorque):
        c: float = 0.5
        max_torque: float = np.inf

        def __call__(self, t: float, q: Any, q_dot: Any) -> Any:
            return np.asarray(-self.c * np.asarray(q_dot)[..., 3])[..., None]

    pd = SwingLegPD(amplitude=0.2)
    q, qd = np.array([0.0, 0.0, -0.2, 0.4]), np.array([0.0, 0.0, 1.0, -2.0])
    total = (pd + Damper())(0.1, q, qd)
    np.testing.assert_allclose(total, pd(0.1, q, qd) + Damper()(0.1, q, qd), rtol=1e-15)
    walker = CompassGait(foot_radius=0.3)
    law = pd + Damper(c=0.1)  # the walk of the PD law, with some damping
    res = step_jacobian(walker, Z_POWERED, slope=0.0, torque=law, rtol=1e-12, atol=1e-12)
    pmap = _actuated_map(walker, law, None)
    assert np.max(np.abs(res.jacobian - pmap.jacobian(Z_POWERED, 1e-6))) < 1e-6
