"""Multi-contact impacts: active-set selection by complementarity."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize

from heelstrike.core import impact
from heelstrike.core.complementarity import CandidateContact, MultiContactImpact, resolve_impact
from heelstrike.models import CompassGait, heel_strike_state


def _check_invariants(
    M: np.ndarray,
    qd: np.ndarray,
    Ab: np.ndarray,
    contacts: list[CandidateContact],
    r: MultiContactImpact,
) -> None:
    v = r.velocity_post
    vs = float(np.sqrt(qd @ M @ qd)) + 1.0
    ps = float(np.max(np.abs(r.impact.constraint_impulse), initial=0.0)) + 1.0
    # momentum balance with the reported impulses
    f = Ab.T @ r.bilateral_impulse if Ab.size else np.zeros_like(qd)
    for i, c in enumerate(contacts):
        f = f + c.normal * r.normal_impulse[i]
        if c.tangential is not None:
            f = f + c.tangential * r.tangential_impulse[i]
    np.testing.assert_allclose(M @ (v - qd), f, atol=1e-9 * ps)
    # complementarity
    assert np.all(r.normal_impulse >= 0.0)
    for i, c in enumerate(contacts):
        vn = c.normal @ v
        assert vn >= -1e-9 * vs
        if r.modes[i] == "separate":
            assert r.normal_impulse[i] == 0.0 and r.tangential_impulse[i] == 0.0
        else:
            assert abs(vn) < 1e-9 * vs
            if r.modes[i] == "stick":
                assert c.tangential is not None and abs(c.tangential @ v) < 1e-9 * vs
            else:
                assert r.tangential_impulse[i] == 0.0
    if Ab.size:
        np.testing.assert_allclose(Ab @ v, 0.0, atol=1e-9 * vs)
    np.testing.assert_allclose(r.active_rows @ v, 0.0, atol=1e-9 * vs)
    # energy: T = T_c + T_a, T+ = T_a <= T
    T, Tc, Ta = r.kinetic_energy, r.kinetic_energy_constrained, r.kinetic_energy_admissible
    assert T == pytest.approx(Tc + Ta, rel=1e-10, abs=1e-12)
    assert 0.5 * v @ M @ v == pytest.approx(Ta, rel=1e-9, abs=1e-12)
    assert Tc >= -1e-12


# -- the compass heel-strike study grid ------------------------------------------------------------

_RADII = np.linspace(0.0, 1.0, 11)
_ANGLES = np.linspace(0.01, np.pi / 4, 25)


def test_compass_grid_matches_single_contact_when_trailing_foot_lifts() -> None:
    n_lift = n_kept = 0
    for R in _RADII:
        cg = CompassGait(foot_radius=R)
        for q3 in _ANGLES:
            q, qd = heel_strike_state(cg, q3)
            M = cg.mass_matrix(q)
            AL = cg.contact_jacobian(q, "left")
            AR = cg.contact_jacobian(q, "right")
            contact = CandidateContact.from_jacobian(AR, "trailing")
            r = resolve_impact(M, qd, AL, [contact])
            _check_invariants(M, qd, AL, [contact], r)
            single = impact(M, AL, qd)
            if single.velocity_post[1] > 1e-9:  # the paper's admissibility: q2_dot+ > 0
                n_lift += 1
                assert r.modes == ("separate",)
                np.testing.assert_allclose(r.velocity_post, single.velocity_post, atol=1e-13)
                np.testing.assert_allclose(
                    r.impact.constrained_projector, single.constrained_projector, atol=1e-13
                )
                assert r.kinetic_energy_constrained == pytest.approx(
                    float(single.kinetic_energy_constrained), rel=1e-13
                )
            elif single.velocity_post[1] < -1e-9:
                # the single-contact answer would push the trailing foot into the ground
                n_kept += 1
                assert r.modes[0] in ("stick", "slip")
                assert r.normal_impulse[0] > 0.0
    assert n_lift > 100 and n_kept > 5  # both regimes are exercised (R = 0 at large q3)


def test_paper_fact_trailing_foot_lifts_for_large_radii() -> None:
    """MODEL.md: for R above about 0.4 m the trailing foot lifts for every q3 in [0, 45 deg]."""
    for R in (0.45, 0.7, 1.0):
        cg = CompassGait(foot_radius=R)
        for q3 in _ANGLES:
            q, qd = heel_strike_state(cg, q3)
            r = resolve_impact(
                cg.mass_matrix(q),
                qd,
                cg.contact_jacobian(q, "left"),
                [CandidateContact.from_jacobian(cg.contact_jacobian(q, "right"))],
            )
            assert r.modes == ("separate",)


def test_frictionless_contacts_follow_gauss_principle() -> None:
    """Frictionless inert impact = argmin (v - v-)^T M (v - v-) s.t. A_b v = 0, n_i v >= 0.

    Checked against scipy's SLSQP on the kinetic-metric projection (an independent method).
    """
    rng = np.random.default_rng(5)
    for _ in range(20):
        n = 5
        L = rng.normal(size=(n, n))
        M = L @ L.T + n * np.eye(n)
        qd = rng.normal(size=n) * 2
        Ab = rng.normal(size=(1, n))
        contacts = [CandidateContact(normal=rng.normal(size=n), name=f"c{i}") for i in range(2)]
        r = resolve_impact(M, qd, Ab, contacts)
        _check_invariants(M, qd, Ab, contacts, r)
        cons = [{"type": "eq", "fun": lambda v, Ab=Ab: Ab @ v, "jac": lambda v, Ab=Ab: Ab}]
        for c in contacts:
            cons.append(
                {
                    "type": "ineq",
                    "fun": lambda v, c=c: c.normal @ v,
                    "jac": lambda v, c=c: c.normal[None, :],
                }
            )
        opt = minimize(
            lambda v, M=M, qd=qd: 0.5 * (v - qd) @ M @ (v - qd),
            np.zeros(n),
            jac=lambda v, M=M, qd=qd: M @ (v - qd),
            constraints=cons,
            method="SLSQP",
            options={"ftol": 1e-12, "maxiter": 500},
        )
        assert opt.success
        np.testing.assert_allclose(r.velocity_post, opt.x, atol=1e-6)


# -- random cases (hypothesis) ---------------------------------------------------------------------


@st.composite
def _cases(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[CandidateContact]]:
    n = draw(st.integers(3, 6))
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    k_b = draw(st.integers(0, 2))
    m = draw(st.integers(1, 3))
    L = rng.normal(size=(n, n))
    M = L @ L.T + 0.1 * np.eye(n)
    qd = rng.normal(size=n) * draw(st.floats(0.1, 10.0))
    Ab = rng.normal(size=(k_b, n))
    frictionless = draw(st.lists(st.booleans(), min_size=m, max_size=m))
    contacts = [
        CandidateContact(
            normal=rng.normal(size=n), tangential=None if fl else rng.normal(size=n), name=f"c{i}"
        )
        for i, fl in enumerate(frictionless)
    ]
    return M, qd, Ab, contacts


@settings(max_examples=150, deadline=None)
@given(_cases())
def test_random_impacts_satisfy_complementarity(
    case: tuple[np.ndarray, np.ndarray, np.ndarray, list[CandidateContact]],
) -> None:
    M, qd, Ab, contacts = case
    rows = np.vstack(
        [Ab]
        + [c.normal[None] for c in contacts]
        + [c.tangential[None] for c in contacts if c.tangential is not None]
    )
    if rows.shape[0] <= M.shape[0] and np.linalg.matrix_rank(rows) < rows.shape[0]:
        return  # degenerate constraint geometry: not a well-posed impact
    r = resolve_impact(M, qd, Ab if Ab.size else None, contacts)
    _check_invariants(M, qd, Ab, contacts, r)
    if r.modes == ("separate",) * len(contacts) and Ab.size:
        # nothing but the bilateral rows act: the single-constraint answer
        np.testing.assert_allclose(r.velocity_post, impact(M, Ab, qd).velocity_post, atol=1e-10)
