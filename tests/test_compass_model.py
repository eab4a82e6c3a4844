"""The hand-written compass-gait model against an independent sympy Lagrangian derivation.

The derivation below is built from the paper's model only (Font & Kövecses 2008, Fig. 1, as
restated in the module docstring of :mod:`heelstrike.models.compass`): positions of the points,
kinetic and potential energies, ``M = d^2 T / d q_dot^2`` and
``h = d/dt(dT/dq_dot) - M q_ddot - dT/dq + dV/dq``, with leg inertia and gravity tilted by the
slope, ``g (-sin gamma, -cos gamma)``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
import sympy as sp

from heelstrike.models.compass import CompassGait

PARAMS = ("hip_mass", "leg_mass", "leg_length", "leg_com_from_hip", "foot_radius", "leg_inertia",
          "gravity")


@dataclass
class Symbolic:
    M: Callable[..., Any]
    h: Callable[..., Any]
    V: Callable[..., Any]
    T: Callable[..., Any]
    A_right: Callable[..., Any]
    A_left: Callable[..., Any]
    points: Callable[..., Any]


@pytest.fixture(scope="module")
def sym() -> Symbolic:
    q = sp.Matrix(sp.symbols("q1:5", real=True))
    qd = sp.Matrix(sp.symbols("qd1:5", real=True))
    mH, m, l, b, R, I, g, gam = sp.symbols("mH m l b R I g gamma", real=True)

    def e(th: sp.Expr) -> sp.Matrix:
        return sp.Matrix([-sp.sin(th), sp.cos(th)])

    s = l - R
    P_R = sp.Matrix([q[0], q[1]])
    H = P_R + s * e(q[2])
    P_L = H - s * e(q[2] + q[3])
    G_R = H - b * e(q[2])
    G_L = H - b * e(q[2] + q[3])

    def vel(r: sp.Matrix) -> sp.Matrix:
        return r.jacobian(q) * qd

    w_R, w_L = qd[2], qd[2] + qd[3]
    T = (mH * vel(H).dot(vel(H)) + m * (vel(G_R).dot(vel(G_R)) + vel(G_L).dot(vel(G_L)))
         + I * (w_R**2 + w_L**2)) / 2
    gvec = sp.Matrix([-g * sp.sin(gam), -g * sp.cos(gam)])
    V = -(mH * gvec.dot(H) + m * gvec.dot(G_R) + m * gvec.dot(G_L))
    T = sp.expand(T)
    M = sp.hessian(T, qd)
    p = sp.Matrix([sp.diff(T, v) for v in qd])
    # d/dt(dT/dqd) - M qdd = (d p / d q) qd
    h = p.jacobian(q) * qd - sp.Matrix([sp.diff(T, x) for x in q]) + sp.Matrix(
        [sp.diff(V, x) for x in q]
    )
    # contact points: velocity of the arc centre plus R * (leg angular rate) in x
    vc_R = vel(P_R) + sp.Matrix([R * w_R, 0])
    vc_L = vel(P_L) + sp.Matrix([R * w_L, 0])
    A_R = vc_R.jacobian(qd)
    A_L = vc_L.jacobian(qd)
    args = (q, qd, mH, m, l, b, R, I, g, gam)
    down = sp.Matrix([0, -R])
    pts = sp.Matrix.hstack(H, P_R, P_L, P_R + down, P_L + down, G_R, G_L)
    return Symbolic(
        M=sp.lambdify(args, M, "numpy"),
        h=sp.lambdify(args, h, "numpy"),
        V=sp.lambdify(args, V, "numpy"),
        T=sp.lambdify(args, T, "numpy"),
        A_right=sp.lambdify(args, A_R, "numpy"),
        A_left=sp.lambdify(args, A_L, "numpy"),
        points=sp.lambdify(args, pts, "numpy"),
    )


def _random_params(rng: np.random.Generator) -> dict[str, float]:
    l = rng.uniform(0.5, 2.0)
    return {
        "hip_mass": rng.uniform(0.5, 20.0),
        "leg_mass": rng.uniform(0.5, 10.0),
        "leg_length": l,
        "leg_com_from_hip": rng.uniform(0.05, 0.95) * l,
        "foot_radius": rng.choice([0.0, l, rng.uniform(0.0, 1.0) * l]),
        "leg_inertia": rng.choice([0.0, rng.uniform(0.0, 2.0)]),
        "gravity": rng.uniform(1.0, 20.0),
    }


def _random_state(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    q = np.concatenate([rng.normal(size=2), rng.uniform(-1.5, 1.5, size=2)])
    return q, rng.normal(scale=2.0, size=4)


def _sym_args(q, qd, p, slope=0.0):
    return (q, qd, p["hip_mass"], p["leg_mass"], p["leg_length"], p["leg_com_from_hip"],
            p["foot_radius"], p["leg_inertia"], p["gravity"], slope)


SEEDS = range(40)


@pytest.mark.parametrize("seed", SEEDS)
def test_mass_matrix_bias_and_potential_match_lagrangian(sym: Symbolic, seed: int):
    rng = np.random.default_rng(seed)
    p = _random_params(rng)
    q, qd = _random_state(rng)
    slope = rng.uniform(-0.3, 0.3)
    w = CompassGait(**p)
    a = _sym_args(q, qd, p, slope)
    M_ref = np.array(sym.M(*a), dtype=float)
    h_ref = np.array(sym.h(*a), dtype=float).ravel()
    np.testing.assert_allclose(w.mass_matrix(q), M_ref, rtol=1e-11, atol=1e-11)
    np.testing.assert_allclose(w.bias_forces(q, qd, slope), h_ref, rtol=1e-10, atol=1e-10)
    # potential energy up to a constant; the model's zero is the ground frame origin
    assert float(w.potential_energy(q, slope)) == pytest.approx(float(sym.V(*a)), rel=1e-11,
                                                                abs=1e-10)


@pytest.mark.parametrize("seed", range(15))
def test_positions_and_contact_jacobians_match_symbolic(sym: Symbolic, seed: int):
    rng = np.random.default_rng(100 + seed)
    p = _random_params(rng)
    q, qd = _random_state(rng)
    w = CompassGait(**p)
    a = _sym_args(q, qd, p)
    np.testing.assert_allclose(w.contact_jacobian(q, "right"),
                               np.array(sym.A_right(*a), dtype=float), atol=1e-12)
    np.testing.assert_allclose(w.contact_jacobian(q, "left"),
                               np.array(sym.A_left(*a), dtype=float), atol=1e-12)
    pts = np.array(sym.points(*a), dtype=float).T  # (7, 2)
    pos = w.positions(q)
    got = np.stack([pos.hip, pos.right_foot_centre, pos.left_foot_centre, pos.right_contact,
                    pos.left_contact, pos.right_leg_com, pos.left_leg_com])
    np.testing.assert_allclose(got, pts, atol=1e-12)


@pytest.mark.parametrize("R", [0.0, 0.3, 0.7, 1.0])
@pytest.mark.parametrize("q3_deg", [1.0, 12.0, 27.0, 45.0])
def test_left_jacobian_reduces_to_paper_eq5_at_heel_strike(R: float, q3_deg: float):
    l = 1.0
    q3 = np.deg2rad(q3_deg)
    w = CompassGait(foot_radius=R, leg_length=l)
    q = np.array([0.3, R, q3, -2 * q3])
    eq5 = np.array([
        [1.0, 0.0, R, (l - R) * np.cos(q3) + R],
        [0.0, 1.0, -2 * (l - R) * np.sin(q3), -(l - R) * np.sin(q3)],
    ])
    np.testing.assert_allclose(w.contact_jacobian(q, "left"), eq5, atol=1e-14)
    np.testing.assert_allclose(w.contact_jacobian(q, "right"),
                               [[1.0, 0.0, R, 0.0], [0.0, 1.0, 0.0, 0.0]], atol=0)


def test_array_parameters_broadcast_like_loops(sym: Symbolic):
    rng = np.random.default_rng(7)
    R = np.array([0.0, 0.2, 0.5, 1.0])
    m = np.array([[1.0], [5.0]])
    q, qd = _random_state(rng)
    w = CompassGait(foot_radius=R, leg_mass=m, leg_inertia=0.1)
    M = w.mass_matrix(q)
    h = w.bias_forces(q, qd, 0.05)
    assert M.shape == (2, 4, 4, 4)
    for i, j in np.ndindex(2, 4):
        wi = CompassGait(foot_radius=R[j], leg_mass=m[i, 0], leg_inertia=0.1)
        np.testing.assert_allclose(M[i, j], wi.mass_matrix(q), rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(h[i, j], wi.bias_forces(q, qd, 0.05), rtol=1e-13,
                                   atol=1e-13)


@pytest.mark.parametrize("seed", range(10))
def test_swap_legs_preserves_energy_and_positions(seed: int):
    rng = np.random.default_rng(200 + seed)
    w = CompassGait(**_random_params(rng))
    q, qd = _random_state(rng)
    q2, qd2 = w.swap_legs(q, qd)
    T1 = 0.5 * qd @ w.mass_matrix(q) @ qd
    T2 = 0.5 * qd2 @ w.mass_matrix(q2) @ qd2
    assert T2 == pytest.approx(T1, rel=1e-12)
    assert float(w.potential_energy(q2, 0.1)) == pytest.approx(float(w.potential_energy(q, 0.1)),
                                                               rel=1e-12, abs=1e-12)
    a, b = w.positions(q), w.positions(q2)
    np.testing.assert_allclose(b.hip, a.hip, atol=1e-12)
    np.testing.assert_allclose(b.right_foot_centre, a.left_foot_centre, atol=1e-12)
    np.testing.assert_allclose(b.left_foot_centre, a.right_foot_centre, atol=1e-12)
    np.testing.assert_allclose(b.right_contact, a.left_contact, atol=1e-12)
    np.testing.assert_allclose(b.left_leg_com, a.right_leg_com, atol=1e-12)
    np.testing.assert_allclose(b.right_leg_com, a.left_leg_com, atol=1e-12)
    # swapping twice is the identity
    q3, qd3 = w.swap_legs(q2, qd2)
    np.testing.assert_allclose(q3, q, atol=1e-12)
    np.testing.assert_allclose(qd3, qd, atol=1e-12)
    # the foot's contact velocity follows the relabelling
    np.testing.assert_allclose(w.contact_jacobian(q2, "right") @ qd2,
                               w.contact_jacobian(q, "left") @ qd, atol=1e-12)


@pytest.mark.parametrize(
    "params",
    [
        {"foot_radius": 1.2},
        {"foot_radius": -0.1},
        {"leg_com_from_hip": 1.0},
        {"leg_com_from_hip": 1.5},
        {"leg_com_from_hip": 0.0},
        {"leg_mass": -1.0},
        {"hip_mass": -2.0},
        {"hip_mass": 0.0},
        {"leg_inertia": -0.1},
        {"gravity": 0.0},
        {"leg_length": 0.5, "foot_radius": 0.6},
        {"foot_radius": np.array([0.1, 1.1])},
        {"leg_mass": float("nan")},
    ],
)
def test_invalid_parameters_are_rejected(params: dict[str, Any]):
    with pytest.raises(ValueError):
        CompassGait(**params)


def test_valid_extremes_accepted():
    CompassGait(foot_radius=0.0)
    CompassGait(foot_radius=1.0)
    CompassGait(foot_radius=np.linspace(0, 1, 5))
    assert set(PARAMS) <= {f for f in CompassGait.__dataclass_fields__}
