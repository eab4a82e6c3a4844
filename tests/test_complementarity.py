"""Multi-contact impacts: active-set selection by complementarity."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

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
    """Fig. 3b: for R above about 0.4 m the trailing foot lifts for every q3 in [0, 45 deg]."""
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


def _gauss_projection_by_active_sets(
    M: np.ndarray, qd: np.ndarray, Ab: np.ndarray, normals: np.ndarray
) -> list[np.ndarray]:
    """Every KKT point of min 1/2 (v - v-)^T M (v - v-) s.t. A_b v = 0, N v >= 0.

    Exact oracle: for every subset S of the unilateral rows held with equality, solve the
    equality-constrained problem by its KKT system (a linear solve) and keep the candidates that
    are primal feasible (``N v >= 0``) and dual feasible (multipliers of S ``>= 0``). The problem
    is strictly convex, so all kept candidates are the same point.
    """
    n = qd.size
    m = normals.shape[0]
    kept = []
    for mask in range(2**m):
        S = [i for i in range(m) if mask >> i & 1]
        C = np.vstack([Ab, normals[S]]) if S else Ab
        k = C.shape[0]
        K = np.block([[M, -C.T], [C, np.zeros((k, k))]])
        if np.linalg.matrix_rank(K) < n + k:
            continue
        sol = np.linalg.solve(K, np.concatenate([M @ qd, np.zeros(k)]))
        v, mult = sol[:n], sol[n:]
        scale = float(np.sqrt(qd @ M @ qd)) + 1.0
        if np.all(normals @ v >= -1e-12 * scale) and np.all(mult[Ab.shape[0]:] >= -1e-12 * scale):
            kept.append(v)
    return kept


def test_frictionless_contacts_follow_gauss_principle() -> None:
    """Frictionless inert impact = argmin (v - v-)^T M (v - v-) s.t. A_b v = 0, n_i v >= 0.

    Checked against an exact oracle: enumeration of the active sets of that small QP with their
    KKT conditions (an independent method that cannot fail on a solvable problem).
    """
    rng = np.random.default_rng(5)
    n_active = 0
    for _ in range(40):
        n = 5
        L = rng.normal(size=(n, n))
        M = L @ L.T + n * np.eye(n)
        qd = rng.normal(size=n) * 2
        Ab = rng.normal(size=(1, n))
        contacts = [CandidateContact(normal=rng.normal(size=n), name=f"c{i}") for i in range(2)]
        r = resolve_impact(M, qd, Ab, contacts)
        _check_invariants(M, qd, Ab, contacts, r)
        kkt = _gauss_projection_by_active_sets(M, qd, Ab, np.array([c.normal for c in contacts]))
        assert kkt, "a strictly convex QP with a feasible set has a KKT point"
        for v in kkt:
            np.testing.assert_allclose(v, kkt[0], atol=1e-10)
        np.testing.assert_allclose(r.velocity_post, kkt[0], atol=1e-10)
        n_active += sum(m != "separate" for m in r.modes)
    assert n_active > 5  # contacts held in the impact are exercised, not only separations


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
