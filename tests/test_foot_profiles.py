"""Feet of any convex shape (issue #33, item 3): a ``[[foot]]`` given by its support function.

The circular arc written as a general profile (three ways: about its centre, about the foot's
end, about the hip) must give the arc walker's mass matrix, forces, contact Jacobians, heel
strike and passive step to 1e-10; a non-circular convex profile must roll without slip (the
material contact point's velocity, from finite differences of the link's pose, is zero; the
contact point advances by the profile's arc length, integral of h + h'') and conserve energy
between impacts (scipy backend); non-convex and self-intersecting profiles are refused.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from heelstrike.analysis.model_gaits import model_heel_strike
from heelstrike.dynamics.hybrid import simulate
from heelstrike.dynamics.phased import PhasedWalker
from heelstrike.models.builder import load_walker, walker_description
from heelstrike.models.description import (
    ModelDescriptionError,
    read_description,
    support_function,
)

WALKERS = Path(__file__).resolve().parents[1] / "src" / "heelstrike" / "walkers"
SLOPE = 0.05
Z0 = np.array([-0.2, 0.9, 0.5])  # a post-heel-strike state that takes one full step


def _compass_with_feet(tmp_path: Path, stance: str, swing: str, extra: str = "",
                       name: str = "profiled") -> Path:
    """compass.toml with its two [[foot]] tables replaced (the keys after ``link``) and the
    default foot radius R = 0.3 m."""
    text = (WALKERS / "compass.toml").read_text().replace("R = 0.0 ", "R = 0.3 ")
    head, _, rest = text.partition("[[foot]]")
    tail = rest[rest.index("[[point_mass]]"):]
    feet = (f'[[foot]]\nname = "stance"\nlink = "stance_leg"\n{stance}\n\n'
            f'[[foot]]\nname = "swing"\nlink = "swing_leg"\n{swing}\n\n')
    head = head.replace('name = "compass"', f'name = "{name}"')
    if extra:
        head = head.replace("[params]\n", f"[params]\n{extra}\n")
    path = tmp_path / f"{name}.toml"
    path.write_text(head + feet + tail)
    return path


# the circular arc of radius R whose centre is on the leg at R from its foot end, as a profile
ARC_FORMS = {
    # about the arc centre (origin O = the centre): h = R
    "centre": ('profile = "R"\nphi_range = [-1.2, 1.2]\ncentre = "R"',
               'profile = "R"\nphi_range = [-1.2, 1.2]\ncentre = "l - R"'),
    # about the foot's end (the default origin), the centre R up the leg: h = R - R cos(phi)
    "foot_end": ('profile = "R - R*cos(phi)"\nphi_range = [-1.2, 1.2]',
                 'profile = "R - R*cos(phi)"\nphi_range = [-1.2, 1.2]'),
    # about the hip, the centre l - R down the leg: h = R + (l - R) cos(phi)
    "hip": ('profile = "R + (l - R)*cos(phi)"\nphi_range = [-1.2, 1.2]\ncentre = "l"',
            'profile = "R + (l - R)*cos(phi)"\nphi_range = [-1.2, 1.2]\ncentre = 0.0'),
}


def _states(n: int = 5) -> tuple[np.ndarray, np.ndarray]:
    k = np.arange(1, 8 * n + 1, dtype=float)
    u = np.modf(k * 0.6180339887498949)[0].reshape(2, n, 4)
    return 1.2 * u[0] - 0.6, 4.0 * u[1] - 2.0


@pytest.mark.parametrize("form", sorted(ARC_FORMS))
@pytest.mark.parametrize("R", [0.0, 0.3, 0.7])
def test_arc_written_as_a_profile_is_the_arc(tmp_path: Path, form: str, R: float) -> None:
    arc = load_walker("compass", R=R)
    prof = load_walker(_compass_with_feet(tmp_path, *ARC_FORMS[form]), R=R)
    q, qd = _states()
    tol = 1e-10
    assert np.allclose(prof.foot_radii, arc.foot_radii, rtol=0, atol=tol)
    assert float(prof.scale.leg_length) == pytest.approx(float(arc.scale.leg_length), abs=tol)
    np.testing.assert_allclose(prof.mass_matrix(q), arc.mass_matrix(q), rtol=0, atol=tol)
    np.testing.assert_allclose(prof.bias_forces(q, qd, SLOPE), arc.bias_forces(q, qd, SLOPE),
                               rtol=0, atol=tol)
    np.testing.assert_allclose(prof.potential_energy(q, SLOPE), arc.potential_energy(q, SLOPE),
                               rtol=0, atol=tol)
    for foot in ("right", "left"):
        np.testing.assert_allclose(prof.contact_jacobian(q, foot),
                                   arc.contact_jacobian(q, foot), rtol=0, atol=tol)
        np.testing.assert_allclose(prof.contact_jacobian_rate(q, qd, foot),
                                   arc.contact_jacobian_rate(q, qd, foot), rtol=0, atol=tol)
        np.testing.assert_allclose(prof.contact_point(q, foot), arc.contact_point(q, foot),
                                   rtol=0, atol=tol)
    for a, b in zip(prof.swap_legs(q, qd), arc.swap_legs(q, qd), strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=tol)
    # the heel strike at a generic pre-impact state (the swing foot on the ground)
    q_hs = np.array([0.0, R, 0.2, -0.4])
    qd_hs = np.array([-R * 1.1, 0.0, 1.1, -0.3])
    hs_arc, hs_prof = model_heel_strike(arc, q_hs, qd_hs), model_heel_strike(prof, q_hs, qd_hs)
    np.testing.assert_allclose(hs_prof.q_dot_plus, hs_arc.q_dot_plus, rtol=0, atol=tol)
    np.testing.assert_allclose(hs_prof.impulse, hs_arc.impulse, rtol=0, atol=tol)
    assert hs_prof.step_length == pytest.approx(hs_arc.step_length, abs=tol)
    assert hs_prof.eta == pytest.approx(hs_arc.eta, abs=tol)


@pytest.mark.parametrize("form", sorted(ARC_FORMS))
def test_arc_as_a_profile_takes_the_arc_walkers_passive_step(tmp_path: Path, form: str) -> None:
    R = 0.3
    arc = PhasedWalker(walker_description("compass"), R=R)
    prof = PhasedWalker(walker_description(_compass_with_feet(tmp_path, *ARC_FORMS[form])), R=R)
    runs = []
    for w in (arc, prof):
        q, qd = w.section_to_state(Z0)
        runs.append(simulate(w, q, qd, slope=SLOPE, steps=1))
    a, b = runs
    assert a.status == b.status == "completed"
    ia, ib = a.impacts[0], b.impacts[0]
    for key in ("time", "energy_lost", "step_length", "kinetic_energy", "step_duration"):
        assert getattr(ib, key) == pytest.approx(getattr(ia, key), abs=1e-10), key
    for key in ("q", "q_dot_minus", "q_dot_plus"):
        np.testing.assert_allclose(getattr(ib, key), getattr(ia, key), rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.final_q, a.final_q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.final_q_dot, a.final_q_dot, rtol=0, atol=1e-10)


def test_arc_with_a_forward_offset_written_as_a_profile_is_that_arc(tmp_path: Path) -> None:
    # the arc centre d forward of the leg: h = R - R cos(phi) + d sin(phi) about the foot end
    arc = _compass_with_feet(
        tmp_path, 'radius = "R"\ncentre = "R"\ncentre_offset = "d"',
        'radius = "R"\ncentre = "l - R"\ncentre_offset = "d"', extra="d = 0.04", name="arc")
    foot = 'profile = "R - R*cos(phi) + d*sin(phi)"\nphi_range = [-1.2, 1.2]'
    prof = _compass_with_feet(tmp_path, foot, foot, extra="d = 0.04", name="prof")
    a, b = load_walker(arc), load_walker(prof)
    q, qd = _states()
    for f in ("mass_matrix", "potential_energy"):
        np.testing.assert_allclose(getattr(b, f)(q), getattr(a, f)(q), rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.bias_forces(q, qd, SLOPE), a.bias_forces(q, qd, SLOPE),
                               rtol=0, atol=1e-10)
    for foot_ in ("right", "left"):
        np.testing.assert_allclose(b.contact_jacobian(q, foot_), a.contact_jacobian(q, foot_),
                                   rtol=0, atol=1e-10)
        np.testing.assert_allclose(b.contact_point(q, foot_), a.contact_point(q, foot_),
                                   rtol=0, atol=1e-10)


# a non-circular convex foot: rho = h + h'' = R + k + 3 k cos(2 phi), > 0 on |phi| <= 1 for
# -R / 4 < k < 4 R
OVAL = 'profile = "R - R*cos(phi) + k*(1 - cos(2*phi))"\nphi_range = [-1.0, 1.0]'


def _rolled(R: float, k: float, th0: float, th: np.ndarray) -> np.ndarray:
    """Closed form of the profile's arc length between normal angles th0 and th."""
    return (R + k) * (th - th0) + 1.5 * k * (np.sin(2 * th) - np.sin(2 * th0))


def test_oval_foot_rolling_radius_is_its_curvature_radius_at_zero(tmp_path: Path) -> None:
    path = _compass_with_feet(tmp_path, OVAL, OVAL, extra="k = 0.05")
    for R, k in ((0.3, 0.05), (0.2, -0.04), (0.5, 0.1)):
        w = load_walker(path, R=R, k=k)
        assert float(w.foot_radii[0]) == pytest.approx(R + 4 * k, abs=1e-14)
        assert float(w.foot_radii[1]) == pytest.approx(R + 4 * k, abs=1e-14)


# the rounded sole of docs/walker_files.rst: rho = r + (2 s / pi) (1 + 1.5 cos 2 phi + cos 4 phi
# + 0.5 cos 6 phi) >= r, R0 = r + 8 s / pi
SOLE_H = ("r + (depth - r)*cos(phi) + s*(2 - 4*(cos(2*phi)/4 + cos(4*phi)/30 + "
          "cos(6*phi)/140))/pi")
SOLE = f'profile = "{SOLE_H}"\nphi_range = [-1.2, 1.2]'
SOLE_PARAMS = "r = 0.05\ns = 0.08\ndepth = 0.02"


def _sole_rolled(r: float, s: float, th0: float, th: np.ndarray) -> np.ndarray:
    def F(x: np.ndarray) -> np.ndarray:
        return r * x + 2 * s / np.pi * (x + 0.75 * np.sin(2 * x) + 0.25 * np.sin(4 * x)
                                        + np.sin(6 * x) / 12)
    return F(th) - F(np.asarray(th0))


def test_rounded_sole_is_the_pages_and_convex_with_its_closed_form_radius(tmp_path: Path) -> None:
    page = (Path(__file__).resolve().parents[1] / "docs" / "walker_files.rst").read_text()
    assert page.count(f'profile = "{SOLE_H}"') == 2
    phi = np.linspace(-1.2, 1.2, 61)
    for r, s_ in ((0.05, 0.08), (0.0, 0.1), (0.02, 0.0)):
        h, _, d2h = support_function(SOLE_H, phi, {"r": r, "s": s_, "depth": 0.02})
        rho = r + 2 * s_ / np.pi * (1 + 1.5 * np.cos(2 * phi) + np.cos(4 * phi)
                                    + 0.5 * np.cos(6 * phi))
        np.testing.assert_allclose(h + d2h, rho, rtol=0, atol=1e-14)
        assert np.all(rho >= r - 1e-15)
        w = load_walker(_compass_with_feet(tmp_path, SOLE, SOLE, extra=SOLE_PARAMS), r=r, s=s_)
        assert float(w.foot_radii[0]) == pytest.approx(r + 8 * s_ / np.pi, abs=1e-14)


@pytest.mark.parametrize(("foot", "params", "z", "rolled"), [
    (OVAL, {"R": 0.3, "k": 0.05}, [-0.25, 0.8, 0.2],
     lambda th0, th: _rolled(0.3, 0.05, th0, th)),
    (SOLE, {}, [-0.2, 0.9, 0.5], lambda th0, th: _sole_rolled(0.05, 0.08, th0, th)),
], ids=["oval", "rounded_sole"])
def test_profile_foot_rolls_without_slip_and_conserves_energy(
        tmp_path: Path, foot: str, params: dict[str, float], z: list[float],
        rolled: Callable[[float, np.ndarray], np.ndarray]) -> None:
    extra = "k = 0.05" if "k" in params else SOLE_PARAMS
    w = PhasedWalker(walker_description(_compass_with_feet(tmp_path, foot, foot, extra=extra)),
                     **params)
    assert {"k"} if "k" in params else {"r", "s", "depth"} <= set(w.description.param_names)
    assert not ({"k", "r", "s", "depth"} & w.description.unused_params)
    q0, qd0 = w.section_to_state(np.array(z))
    walk = simulate(w, q0, qd0, slope=SLOPE, steps=1, rtol=1e-11, atol=1e-11)
    assert walk.status == "completed" and len(walk.impacts) == 1
    stance = walk.step == 0
    q, qd = walk.q[stance], walk.q_dot[stance]
    assert q.shape[0] > 10 and np.ptp(q[:, 2]) > 0.3  # the foot rolled through 0.3 rad or more
    P = w.contact_point(q, "right")
    # the contact point stays on the ground and advances by the profile's arc length
    np.testing.assert_allclose(P[:, 1], 0.0, atol=1e-9)
    np.testing.assert_allclose(P[:, 0] - P[0, 0], -rolled(q[0, 2], q[:, 2]), atol=1e-8)
    # the material point at the contact has zero velocity: the stance link's pose from its two
    # end points (finite differences in q, not the generated contact Jacobian)
    def pose(qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pos = w.positions(qs)
        return pos["stance_leg.proximal"], pos["stance_leg.distal"]

    eps = 1e-6
    for qi, qdi, Pi in zip(q[::3], qd[::3], P[::3], strict=True):
        a, b = pose(qi)
        va = sum((pose(qi + eps * e)[0] - pose(qi - eps * e)[0]) / (2 * eps) * qdi[j]
                 for j, e in enumerate(np.eye(4)))
        omega = qdi[2]  # the stance link's absolute angular rate
        r = Pi - a
        v = va + omega * np.array([-r[1], r[0]])
        assert np.linalg.norm(v) < 1e-7 * np.linalg.norm(qdi), (qi, v)
        assert np.linalg.norm(b - a) == pytest.approx(1.0)
    # energy between impacts
    E = 0.5 * np.einsum("ti,tij,tj->t", qd, w.mass_matrix(q), qd) + w.potential_energy(q, SLOPE)
    assert np.ptp(E) < 1e-8 * float(np.max(np.abs(E)))


def test_profile_parameters_change_the_walker(tmp_path: Path) -> None:
    # a profile parameter is an ordinary parameter: the contact point moves with it, by the
    # closed form of the oval's contact point x = -h'(theta) from the foot's end, y = -h
    path = _compass_with_feet(tmp_path, OVAL, OVAL, extra="k = 0.05")
    q = np.array([0.0, 0.0, 0.3, -0.5])
    th = 0.3
    for k in (0.0, 0.05, 0.1):
        w = load_walker(path, R=0.3, k=k)
        end = w.positions(q)["stance_leg.proximal"]
        h = 0.3 - 0.3 * np.cos(th) + k * (1 - np.cos(2 * th))
        dh = 0.3 * np.sin(th) + 2 * k * np.sin(2 * th)
        np.testing.assert_allclose(w.contact_point(q, "right") - end, [-dh, -h], atol=1e-14)


def test_support_function_derivatives_are_sympys() -> None:
    x, a, b = sp.symbols("phi a b", real=True)
    text = "a + b*cos(2*phi) + sqrt(1 + phi**2)/(2 + sin(phi)) - phi**3/(a + 1)"
    f = a + b * sp.cos(2 * x) + sp.sqrt(1 + x**2) / (2 + sp.sin(x)) - x**3 / (a + 1)
    phi = np.linspace(-1.0, 1.0, 7)
    h, dh, d2h = support_function(text, phi, {"a": 0.7, "b": -0.2})
    for order, got in enumerate((h, dh, d2h)):
        ref = sp.lambdify(x, sp.diff(f, x, order).subs({a: 0.7, b: -0.2}), "numpy")(phi)
        np.testing.assert_allclose(got, ref, rtol=1e-14, atol=1e-14)


def test_non_convex_profile_is_refused(tmp_path: Path) -> None:
    # rho = R + k + 3 k cos(2 phi) = 0.3 - 0.4 = -0.1 m at phi = 0
    path = _compass_with_feet(tmp_path, OVAL, OVAL, extra="k = -0.1")
    msg = re.escape("foot[0].profile: not convex: its radius of curvature h + h'' is -0.1 m "
                    "< 0 at phi = 0 rad")
    with pytest.raises(ModelDescriptionError, match=f"^{msg}"):
        read_description(path)
    # and again when a parameter changes to a non-convex value
    ok = _compass_with_feet(tmp_path, OVAL, OVAL, extra="k = 0.05", name="ok")
    with pytest.raises(ModelDescriptionError, match=r"^foot\[0\]\.profile: not convex"):
        load_walker(ok, k=-0.1)
    # only the declared range is checked: with k = 1.5, rho = 1.8 + 4.5 cos(2 phi) < 0 for
    # |phi| > 0.9912 rad only
    narrow = OVAL.replace("[-1.0, 1.0]", "[-0.99, 0.99]")
    load_walker(_compass_with_feet(tmp_path, narrow, narrow, extra="k = 1.5", name="narrow"))
    with pytest.raises(ModelDescriptionError, match=r"^foot\[0\]\.profile: not convex: its "
                                                    r"radius of curvature h \+ h'' is -0\.0726608 m"
                                                    r" < 0 at phi = -?1 rad"):
        load_walker(ok, k=1.5)


def test_self_intersecting_profile_is_refused(tmp_path: Path) -> None:
    wrap = OVAL.replace("[-1.0, 1.0]", "[-3.5, 3.5]")  # convex, but turning through 7 rad
    path = _compass_with_feet(tmp_path, wrap, wrap, extra="k = 0.05")
    with pytest.raises(ModelDescriptionError,
                       match=r"^foot\[0\]\.phi_range: the profile turns through 7 rad, a full "
                             r"turn \(2 pi\) or more, so its contact curve closes on or overlaps"
                             r" itself \(self-intersecting\)"):
        read_description(path)


@pytest.mark.parametrize(("stance", "message"), [
    ('profile = "R"\nradius = "R"\nphi_range = [-1, 1]',
     r"^foot\[0\]\.radius: a foot is either an arc \(radius\) or a profile, not both"),
    ('profile = "R"', r"^foot\[0\]\.phi_range: missing required field"),
    ('profile = "R"\nphi_range = [0.1, 1]', r"^foot\[0\]\.phi_range: must be \[phi_min, "
                                            r"phi_max\] with phi_min < 0 < phi_max"),
    ('profile = "R + psi"\nphi_range = [-1, 1]', r"^foot\[0\]\.profile: unknown parameter "
                                                 r"'psi'"),
    ('radius = "R"\nphi_range = [-1, 1]', r"^foot\[0\]\.phi_range: only a profile foot"),
])
def test_malformed_profile_feet_are_refused(tmp_path: Path, stance: str, message: str) -> None:
    path = _compass_with_feet(tmp_path, stance, 'radius = "R"')
    with pytest.raises(ModelDescriptionError, match=message):
        read_description(path)


@pytest.mark.slow
def test_compiled_backend_walks_a_profile_foot_as_scipy_does(tmp_path: Path) -> None:
    # the generated numba kernel is derived from the same symbolic kinematics
    from heelstrike.dynamics.backends import simulate as simulate_on

    w = PhasedWalker(walker_description(_compass_with_feet(tmp_path, SOLE, SOLE,
                                                           extra=SOLE_PARAMS)))
    q0, qd0 = w.section_to_state(Z0)
    ref = simulate(w, q0, qd0, slope=SLOPE, steps=1)
    got = simulate_on(w, q0, qd0, slope=SLOPE, steps=1, backend="compiled")
    assert ref.status == got.status == "completed"
    np.testing.assert_allclose(got.final_q, ref.final_q, rtol=0, atol=1e-7)
    np.testing.assert_allclose(got.final_q_dot, ref.final_q_dot, rtol=0, atol=1e-7)
    assert got.impacts[0].energy_lost == pytest.approx(ref.impacts[0].energy_lost, abs=1e-8)
    assert got.impacts[0].step_length == pytest.approx(ref.impacts[0].step_length, abs=1e-8)


@pytest.mark.parametrize(("profile", "message"), [
    # an ellipse's support function: its integral is elliptic
    ("sqrt(0.09*sin(phi)**2 + 0.04*cos(phi)**2)", "sympy finds no closed-form antiderivative"),
    ("R + 0.01*sqrt(1 + phi**2)", "its antiderivative (needed for the rolled distance) uses "
                                  "asinh, which walker code does not evaluate"),
])
def test_profile_without_usable_antiderivative_is_refused(tmp_path: Path, profile: str,
                                                          message: str) -> None:
    foot = f'profile = "{profile}"\nphi_range = [-1, 1]'
    with pytest.raises(ModelDescriptionError, match=r"^stance foot: profile .*: "
                                                    + re.escape(message)):
        load_walker(_compass_with_feet(tmp_path, foot, foot), use_cache=False)


# -- a walk leaving a profile's phi_range (review finding) ------------------------------------
def _arc_profile_walker(tmp_path: Path, phi_range: str) -> PhasedWalker:
    """The R = 0.3 arc written as a profile about the foot's end, both feet over ``phi_range``."""
    stance, swing = (f.replace("[-1.2, 1.2]", phi_range) for f in ARC_FORMS["foot_end"])
    name = "ranged_" + re.sub(r"\W", "_", phi_range)
    return PhasedWalker(walker_description(_compass_with_feet(tmp_path, stance, swing,
                                                              name=name)), R=0.3)


def test_walk_ends_where_the_stance_foot_leaves_its_phi_range(tmp_path: Path) -> None:
    """From ``Z0`` the stance angle rises from -0.2 through 0 to the strike at ~0.22 rad. With
    ``phi_range = [-1.2, 0.1]`` the profile holds up to 0.1 rad only: the walk ends in
    ``off_profile`` exactly where the stance foot's contact angle (the stance leg's angle)
    reaches 0.1, its samples before that those of the walk with the full range (the integrator's
    steps do not depend on the events), and the message names the foot and the angle."""
    full_w = _arc_profile_walker(tmp_path, "[-1.2, 1.2]")
    q, qd = full_w.section_to_state(Z0)
    full = simulate(full_w, q, qd, slope=SLOPE, steps=1)
    assert full.status == "completed" and full.impacts[0].q[2] > 0.2
    narrow_w = _arc_profile_walker(tmp_path, "[-1.2, 0.1]")
    assert narrow_w.profile_ranges == ((-1.2, 0.1), (-1.2, 0.1))
    walk = simulate(narrow_w, q, qd, slope=SLOPE, steps=1)
    assert walk.status == "off_profile" and walk.n_steps == 0
    assert float(narrow_w.contact_angle(walk.q[-1], "right")) == pytest.approx(0.1, abs=1e-9)
    assert walk.q[-1][2] == pytest.approx(0.1, abs=1e-9)
    n = walk.t.size - 1
    np.testing.assert_array_equal(walk.t[:n], full.t[:n])
    np.testing.assert_array_equal(walk.q[:n], full.q[:n])
    assert "the stance foot 'stance' (link 'stance_leg') is at contact angle phi = 0.1 rad" \
        in walk.message and "[-1.2, 0.1]" in walk.message
    # a start outside the range ends at once (no sign change to detect from there)
    start = simulate(_arc_profile_walker(tmp_path, "[-0.15, 1.2]"), q, qd, slope=SLOPE)
    assert start.status == "off_profile" and start.t.size == 1
    assert "phi = -0.2 rad" in start.message


def test_walk_ends_where_the_striking_foot_leaves_its_phi_range(tmp_path: Path) -> None:
    """The stance foot starts at -0.2 rad, inside ``[-0.21, 1.2]``, but the swing foot strikes
    at about -0.221 rad (its link's angle ``q3 + q4``): the walk ends in ``off_profile``
    naming the swing foot, where its contact angle reaches -0.21, before the heel strike."""
    full_w = _arc_profile_walker(tmp_path, "[-1.2, 1.2]")
    q, qd = full_w.section_to_state(Z0)
    strike = simulate(full_w, q, qd, slope=SLOPE).impacts[0]
    assert strike.q[2] + strike.q[3] < -0.215
    w = _arc_profile_walker(tmp_path, "[-0.21, 1.2]")
    walk = simulate(w, q, qd, slope=SLOPE)
    assert walk.status == "off_profile" and walk.n_steps == 0
    assert float(w.contact_angle(walk.q[-1], "left")) == pytest.approx(-0.21, abs=1e-9)
    assert walk.t[-1] < strike.time
    assert "the swing (striking) foot 'swing' (link 'swing_leg')" in walk.message


def test_gait_search_returns_no_gait_whose_step_leaves_the_range(tmp_path: Path) -> None:
    """The step map's walk ends in ``off_profile``, so Newton (scipy reference) converges to no
    gait of the narrow-range walker from the full-range walker's fixed point."""
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.analysis.model_gaits import find_model_gait

    full_w = _arc_profile_walker(tmp_path, "[-1.2, 1.2]")
    gait = find_model_gait(full_w, slope=SLOPE, guess=Z0, backend="scipy")
    z = np.array(list(gait.to_dict()["fixed_point"].values()))
    assert abs(z[0]) > 0.15
    narrow = _arc_profile_walker(tmp_path, f"[{-0.5 * abs(z[0]):.4f}, 1.2]")
    with pytest.raises(GaitNotFoundError, match="fails to take a step"):
        find_model_gait(narrow, slope=SLOPE, guess=z, backend="scipy")


def test_a_walk_without_range_guards_is_cut_where_a_foot_leaves_its_range(
        tmp_path: Path) -> None:
    """What the compiled backend (whose kernel has no ``off_profile`` guards) does with its
    walk: the full-range walk, given to the narrow-range walker, is cut at the first sample whose
    stance angle is beyond 0.1 rad (the sample before it inside), with the same samples before;
    a walk inside its ranges is returned as it is."""
    from heelstrike.dynamics.hybrid import cut_off_profile

    full_w = _arc_profile_walker(tmp_path, "[-1.2, 1.2]")
    q, qd = full_w.section_to_state(Z0)
    full = simulate(full_w, q, qd, slope=SLOPE, steps=2)
    assert cut_off_profile(full_w, full) is full
    narrow = _arc_profile_walker(tmp_path, "[-1.2, 0.1]")
    cut = cut_off_profile(narrow, full)
    i = int(np.flatnonzero(full.q[:, 2] > 0.1 + 1e-9)[0])
    assert cut.status == "off_profile" and cut.t.size == i + 1 and cut.n_steps == 0
    assert cut.q[-2][2] <= 0.1 < cut.q[-1][2]
    np.testing.assert_array_equal(cut.q, full.q[: i + 1])
    np.testing.assert_array_equal(cut.final_q, full.q[i])
    assert f"phi = {full.q[i][2]:.6g} rad" in cut.message and "'stance'" in cut.message
    # the striking foot out of range at the first heel strike: the walk ends before it
    strike = full.impacts[0]
    lo = strike.q[2] + strike.q[3] + 0.005  # the swing foot's angle at the strike, + 5 mrad
    assert lo < Z0[0]  # the stance foot starts inside, and stays inside over the first step
    at_strike = cut_off_profile(_arc_profile_walker(tmp_path, f"[{lo:.6f}, 1.2]"), full)
    assert at_strike.status == "off_profile" and at_strike.n_steps == 0
    assert at_strike.events == () and at_strike.t[-1] == strike.time
    assert np.all(at_strike.step == 0)
    assert "the swing (striking) foot 'swing'" in at_strike.message


@pytest.mark.slow
def test_compiled_backend_ends_a_walk_leaving_the_range(tmp_path: Path) -> None:
    """The compiled backend ends the narrow-range walk in ``off_profile`` too, at the first
    sample beyond the range (the scipy reference locates the range's end exactly)."""
    from heelstrike.dynamics.backends import simulate as simulate_on

    w = _arc_profile_walker(tmp_path, "[-1.2, 0.1]")
    q, qd = w.section_to_state(Z0)
    ref = simulate(w, q, qd, slope=SLOPE)
    got = simulate_on(w, q, qd, slope=SLOPE, backend="compiled")
    assert ref.status == got.status == "off_profile" and got.n_steps == 0
    assert got.q[-1][2] > 0.1 and got.q[-2][2] <= 0.1
    assert got.t[-1] >= ref.t[-1] > got.t[-2]


@pytest.mark.slow
def test_compiled_gait_search_returns_no_gait_whose_step_leaves_the_range(
        tmp_path: Path) -> None:
    """As on the scipy reference: the compiled search returns no gait of the narrow-range
    walker from the full-range walker's fixed point (which it finds). Newton converges on the
    batched map, which does not check the ranges; the walk of the converged point does, and
    fails, naming the foot."""
    from heelstrike.analysis.limit_cycle import GaitNotFoundError
    from heelstrike.analysis.model_gaits import find_model_gait

    full_w = _arc_profile_walker(tmp_path, "[-1.2, 1.2]")
    gait = find_model_gait(full_w, slope=SLOPE, guess=Z0, backend="compiled")
    z = np.array(list(gait.to_dict()["fixed_point"].values()))
    narrow = _arc_profile_walker(tmp_path, f"[{-0.5 * abs(z[0]):.4f}, 1.2]")
    with pytest.raises(GaitNotFoundError, match=r"off_profile .*'stance'.*phi_range"):
        find_model_gait(narrow, slope=SLOPE, guess=z, backend="compiled")
