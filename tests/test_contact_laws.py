"""Per-contact impact laws (core, no robot): inert, restitution, Coulomb friction, energy split."""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.core.contact_laws import (
    ContactLaw,
    ContactRows,
    InertLayout,
    energy_split,
    inert_contact_impact,
    inert_contact_impact_batch,
    inert_velocity,
    inert_velocity_batch,
    resolve_contact_impact,
)
from heelstrike.core.impact import ImpactInputError, impact
from test_contact_patches import _oracle


def _spd(rng: np.random.Generator, n: int) -> np.ndarray:
    B = rng.standard_normal((n, n))
    return B @ B.T + 0.5 * np.eye(n)


def _point(J: np.ndarray, **kw: object) -> ContactRows:
    return ContactRows(jacobian=J, normal=(2,), tangential=(0, 1), **kw)  # type: ignore[arg-type]


def _approaching(M: np.ndarray, A: np.ndarray, v: np.ndarray, row: int) -> np.ndarray:
    """Flip v so that the inert impact pushes (positive impulse) on ``row``."""
    lam = impact(M, A, v).constraint_impulse
    return v if lam[row] > 0 else -v


def _problem(seed: int, n: int = 7) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return _spd(rng, n), rng.standard_normal((3, n)), rng.standard_normal(n)


@pytest.mark.parametrize("seed", range(5))
def test_bilateral_contacts_are_the_papers_inert_impact(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 9
    M, v = _spd(rng, n), rng.standard_normal(n)
    J1, J2 = rng.standard_normal((3, n)), rng.standard_normal((3, n))
    res = resolve_contact_impact(M, v, [
        _point(J1, bilateral=True, name="a"), _point(J2, bilateral=True, name="b")])
    ref = impact(M, np.vstack((J1, J2)), v)
    np.testing.assert_allclose(res.velocity_post, ref.velocity_post, atol=1e-12)
    np.testing.assert_allclose(res.impulse, ref.constraint_impulse, atol=1e-11)
    assert res.modes == ("stick", "stick")
    T_plus = 0.5 * res.velocity_post @ M @ res.velocity_post
    assert res.T == pytest.approx(0.5 * v @ M @ v, rel=1e-13)
    assert res.T_c + res.T_a == pytest.approx(res.T, rel=1e-12)
    assert res.T_a == pytest.approx(T_plus, rel=1e-10)  # inert: the admissible part is kept
    assert res.energy_lost == pytest.approx(res.T_c, rel=1e-10)


def _pressing(M: np.ndarray, J: np.ndarray, seed: int) -> np.ndarray:
    """A velocity whose inert impulse is ``(0.1, -0.05, 1)`` plus a free admissible part.

    The contact then pushes both when sticking and when frictionless (no separation).
    """
    rng = np.random.default_rng(seed + 1000)
    lam = np.array([0.1, -0.05, 1.0])
    v = -np.linalg.solve(M, J.T @ lam)
    r = rng.standard_normal(M.shape[0])
    return v + r - impact(M, J, r).velocity_constrained


@pytest.mark.parametrize("seed", range(6))
def test_huge_friction_is_stick(seed: int) -> None:
    M, J, _ = _problem(seed)
    v = _pressing(M, J, seed)
    ref = impact(M, J, v)
    np.testing.assert_allclose(ref.constraint_impulse, [0.1, -0.05, 1.0], rtol=1e-9)
    res = resolve_contact_impact(M, v, [_point(J, law=ContactLaw(friction=1e9))])
    assert res.modes == ("stick",)
    np.testing.assert_allclose(res.velocity_post, ref.velocity_post, atol=1e-11)
    assert res.T_c == pytest.approx(float(ref.kinetic_energy_constrained), rel=1e-10)
    assert res.energy_lost == pytest.approx(res.T_c, rel=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_zero_friction_is_the_normal_row_alone(seed: int) -> None:
    M, J, v = _problem(seed)
    v = _approaching(M, J[2:3], v, 0)
    ref = impact(M, J[2:3], v)
    res = resolve_contact_impact(M, v, [_point(J, law=ContactLaw(friction=0.0))])
    assert res.modes == ("slip",)
    np.testing.assert_allclose(res.velocity_post, ref.velocity_post, atol=1e-12)
    np.testing.assert_allclose(res.impulse[:2], 0.0, atol=0)
    assert res.impulse[2] == pytest.approx(float(ref.constraint_impulse[0]), rel=1e-12)
    assert res.T_c == pytest.approx(float(ref.kinetic_energy_constrained), rel=1e-12)
    assert res.T_c_tangential[0] == 0.0


def test_intermediate_friction_stays_in_the_cone_and_slipping_dissipates() -> None:
    seen = set()
    for seed in range(12):
        M, J, v = _problem(seed)
        v = _approaching(M, J[2:3], v, 0)
        for mu in (0.05, 0.2, 0.5, 1.0, 3.0):
            res = resolve_contact_impact(M, v, [_point(J, law=ContactLaw(friction=mu))])
            lam, u_plus = res.impulse, res.contact_velocity_post[0]
            mode = res.modes[0]
            seen.add(mode)
            # impulse-momentum balance and a closed contact
            np.testing.assert_allclose(M @ (res.velocity_post - v), J.T @ lam, atol=1e-10)
            assert u_plus[2] == pytest.approx(0.0, abs=1e-11)
            assert lam[2] > 0
            # the pyramid cone: each tangential row its own Coulomb law
            assert np.all(np.abs(lam[:2]) <= mu * lam[2] * (1 + 1e-9))
            assert res.T_post <= res.T * (1 + 1e-12)  # never gains energy
            assert res.kkt_residual < 1e-9
            # the outcome is one of the independent mode enumeration's (full coordinates)
            ref = _oracle(M, v, J[2:3], J[None, :2], np.zeros((0, M.shape[0])), mu,
                          np.zeros(1))
            scale = float(np.abs(v).max())
            assert any(np.abs(res.velocity_post - r).max() <= 1e-9 * scale for r in ref)
            assert res.unique == (len(ref) == 1)
            if mode == "slip":
                # friction opposes the post-impact slip on every sliding row, on the cone's
                # edge (maximum dissipation per row)
                slip = u_plus[:2]
                sliding = np.abs(slip) > 1e-9 * scale
                assert sliding.any()
                np.testing.assert_allclose(lam[:2][sliding],
                                           -mu * lam[2] * np.sign(slip[sliding]), rtol=1e-9)
                # friction work on the slip is dissipative
                assert lam[:2] @ slip < 0
            else:
                assert mode == "stick"
                np.testing.assert_allclose(u_plus[:2], 0.0, atol=1e-11)
    assert seen == {"stick", "slip"}  # both branches exercised


@pytest.mark.parametrize("e", [0.0, 0.3, 0.7, 1.0])
@pytest.mark.parametrize("seed", range(4))
def test_restitution_per_contact(e: float, seed: int) -> None:
    M, J, v = _problem(seed)
    v = _approaching(M, J[2:3], v, 0)
    u_minus = (J @ v)[2]
    assert u_minus < 0
    # frictionless: energy lost (1 - e^2) T_c, separation speed e times the approach speed
    res = resolve_contact_impact(
        M, v, [_point(J, law=ContactLaw(friction=0.0, restitution=e))])
    assert res.energy_lost == pytest.approx((1 - e * e) * res.T_c, rel=1e-10, abs=1e-14)
    assert res.contact_velocity_post[0][2] == pytest.approx(-e * u_minus, rel=1e-10)
    # sticking: the normal rebound still is e times the approach, no tangential slip
    stick = resolve_contact_impact(M, v, [_point(J, law=ContactLaw(restitution=e))])
    if stick.modes[0] == "stick":
        assert stick.contact_velocity_post[0][2] == pytest.approx(-e * u_minus, rel=1e-10)
        np.testing.assert_allclose(stick.contact_velocity_post[0][:2], 0.0, atol=1e-11)
        # T+ = T_a + e^2 T_w, T_w the energy of the rebound velocity with J w = (0, 0, -u-);
        # T_w may exceed T_c (Newton's law with sticking can gain energy: Kane's paradox)
        ref = impact(M, J, v)
        W = J @ np.linalg.solve(M, J.T)
        T_w = 0.5 * u_minus**2 * np.linalg.inv(W)[2, 2]
        assert stick.T_post == pytest.approx(
            float(ref.kinetic_energy_admissible) + e * e * T_w, rel=1e-10)


def test_restitution_of_a_two_contact_impact_applies_per_contact() -> None:
    rng = np.random.default_rng(3)
    n = 10
    M = _spd(rng, n)
    J1, J2 = rng.standard_normal((3, n)), rng.standard_normal((3, n))
    A = np.vstack((J1[2:3], J2[2:3]))
    # velocity that approaches on both normals
    X = np.linalg.solve(M, A.T)
    v = X @ np.linalg.solve(A @ X, [-1.0, -1.5])
    np.testing.assert_allclose(A @ v, [-1.0, -1.5], rtol=1e-12)
    res = resolve_contact_impact(M, v, [
        _point(J1, law=ContactLaw(friction=0.0, restitution=0.2)),
        _point(J2, law=ContactLaw(friction=0.0, restitution=0.8)),
    ])
    assert "slip" in res.modes
    for i, e in enumerate((0.2, 0.8)):
        if res.modes[i] != "separate":
            assert res.contact_velocity_post[i][2] == pytest.approx(
                -e * res.contact_velocity_pre[i][2], rel=1e-9)
        else:
            assert res.contact_velocity_post[i][2] >= -e * res.contact_velocity_pre[i][2]


def test_receding_contact_separates() -> None:
    M, J, v = _problem(1)
    v = -_approaching(M, J[2:3], v, 0)  # frictionless normal impulse would pull
    res = resolve_contact_impact(M, v, [_point(J, law=ContactLaw(friction=0.5))])
    assert res.modes == ("separate",)
    np.testing.assert_array_equal(res.impulse, 0.0)
    np.testing.assert_array_equal(res.velocity_post, v)
    assert res.T_c == 0.0 and res.T_a == pytest.approx(res.T)


@pytest.mark.parametrize("seed", range(8))
def test_multi_contact_solution_is_complementary(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    n = 12
    M, v = _spd(rng, n), rng.standard_normal(n)
    contacts = [
        _point(rng.standard_normal((3, n)), bilateral=True, name="keep"),
        _point(rng.standard_normal((3, n)), law=ContactLaw(friction=0.4), name="s1"),
        _point(rng.standard_normal((3, n)), law=ContactLaw(friction=0.8), name="s2"),
    ]
    res = resolve_contact_impact(M, v, contacts)
    lam = res.impulse.reshape(3, 3)
    np.testing.assert_allclose(M @ (res.velocity_post - v),
                               sum(c.jacobian.T @ lam[i] for i, c in enumerate(contacts)),
                               atol=1e-10)
    np.testing.assert_allclose(res.contact_velocity_post[0], 0.0, atol=1e-10)
    for i, c in enumerate(contacts[1:], start=1):
        u = res.contact_velocity_post[i]
        mu = c.law.friction
        if res.modes[i] == "separate":
            assert np.all(lam[i] == 0) and u[2] >= -1e-10
        else:
            assert lam[i, 2] > 0 and u[2] == pytest.approx(0.0, abs=1e-9)
            assert np.all(np.abs(lam[i, :2]) <= mu * lam[i, 2] * (1 + 1e-8))  # pyramid
            for a in (0, 1):  # a sliding row: on the cone's edge, against its slip
                if abs(u[a]) > 1e-9:
                    assert lam[i, a] == pytest.approx(-mu * lam[i, 2] * np.sign(u[a]),
                                                      rel=1e-8)
            if res.modes[i] == "stick":
                np.testing.assert_allclose(u[:2], 0.0, atol=1e-9)
    assert res.T_post <= res.T * (1 + 1e-12)
    assert res.kkt_residual < 1e-9


def test_flat_contact_cone_weights_the_twist() -> None:
    rng = np.random.default_rng(7)
    n, rho, mu = 10, 0.05, 0.3
    M = _spd(rng, n)
    J = rng.standard_normal((6, n))
    flat = ContactRows(jacobian=J, normal=(2, 3, 4), tangential=(0, 1, 5),
                       tangential_weights=(1, 1, 1 / rho), law=ContactLaw(friction=mu))
    v = _approaching(M, J[[2, 3, 4]], rng.standard_normal(n), 0)
    res = resolve_contact_impact(M, v, [flat])
    lam = res.impulse
    assert res.modes[0] in ("stick", "slip")
    # the pyramid, the twist weighted: |f_x|, |f_y|, |tau_z| / rho <= mu f_z
    assert np.all(np.abs([lam[0], lam[1], lam[5] / rho]) <= mu * lam[2] * (1 + 1e-9))
    u = res.contact_velocity_post[0]
    for r, w in ((0, 1.0), (1, 1.0), (5, 1.0 / rho)):  # sliding rows on the edge, opposed
        if abs(u[r]) > 1e-9 * np.abs(v).max():
            assert w * lam[r] == pytest.approx(-mu * lam[2] * np.sign(u[r]), rel=1e-9)
    np.testing.assert_allclose(res.contact_velocity_post[0][[2, 3, 4]], 0.0, atol=1e-10)


@pytest.mark.parametrize("seed", range(4))
def test_flat_contact_never_separates_into_the_ground(seed: int) -> None:
    """QA sweep 9: a flat sole whose hold needs a pull was reported "separate" while it went on
    into the ground (Bolt's foot at -0.3 m/s: zero impulse, T_c = 0, "admissible"). Every
    result is now complementary, or refused where flat-or-nothing has no consistent answer."""
    rng = np.random.default_rng(300 + seed)
    n = 10
    M = _spd(rng, n)
    J = rng.standard_normal((6, n))
    N = [2, 3, 4]
    flat = ContactRows(jacobian=J, normal=tuple(N), tangential=(0, 1, 5),
                       law=ContactLaw(friction=0.6), name="sole")
    G = J[N] @ np.linalg.solve(M, J[N].T)
    outcomes = {"refused": 0, "separate": 0, "held": 0}
    for _ in range(300):
        v = rng.standard_normal(n)
        u = J @ v
        try:
            res = resolve_contact_impact(M, v, [flat])
        except ImpactInputError as exc:
            assert "'sole': no consistent impact" in str(exc)
            # independently: holding all three normal rows pulls, released it approaches
            assert np.linalg.solve(G, -u[N])[0] <= 0.0 and u[2] < 0.0
            outcomes["refused"] += 1
            continue
        post = res.contact_velocity_post[0]
        if res.modes[0] == "separate":
            assert post[2] >= -1e-10 * np.max(np.abs(u))
            np.testing.assert_array_equal(res.impulse, 0.0)
            outcomes["separate"] += 1
        else:
            assert res.impulse[2] > 0.0
            np.testing.assert_allclose(post[N], 0.0, atol=1e-9 * np.max(np.abs(u)))
            outcomes["held"] += 1
    assert all(outcomes.values()), outcomes  # every branch met


@pytest.mark.parametrize("seed", range(5))
def test_energy_split_shares_add_up_and_normal_part_is_normal_projection(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 11
    M, v = _spd(rng, n), rng.standard_normal(n)
    J1, J2 = rng.standard_normal((3, n)), rng.standard_normal((6, n))
    contacts = [
        _point(J1, bilateral=True),
        ContactRows(jacobian=J2, normal=(2, 3, 4), tangential=(0, 1, 5), bilateral=True),
    ]
    res = resolve_contact_impact(M, v, contacts)
    assert np.all(res.T_c_normal >= 0) and np.all(res.T_c_tangential >= 0)
    assert res.T_c_normal.sum() + res.T_c_tangential.sum() == pytest.approx(res.T_c, rel=1e-12)
    normal_only = impact(M, np.vstack((J1[2:3], J2[2:5])), v)
    assert res.T_c_normal.sum() == pytest.approx(
        float(normal_only.kinetic_energy_constrained), rel=1e-11)
    first = impact(M, J1[2:3], v)
    assert res.T_c_normal[0] == pytest.approx(float(first.kinetic_energy_constrained), rel=1e-11)
    T_c, shares = energy_split(M, v, [J1, J2])
    assert T_c == pytest.approx(res.T_c, rel=1e-12)
    assert shares.sum() == pytest.approx(T_c, rel=1e-12)


def test_bad_input() -> None:
    M, J, v = _problem(0)
    # a striking contact repeating a kept one (rank deficient): solved, not refused (issue
    # #34); the striking rows end at rest with the kept ones and carry no impulse
    rep = resolve_contact_impact(M, v, [_point(J, bilateral=True), _point(J)])
    np.testing.assert_allclose(rep.velocity_post, impact(M, J, v).velocity_post, atol=1e-12)
    assert rep.modes[1] == "separate" and rep.unique
    # only kept (bilateral) contacts that repeat each other: still refused (the direct path)
    with pytest.raises(ImpactInputError, match="rank deficient"):
        resolve_contact_impact(M, v, [_point(J, bilateral=True), _point(J, bilateral=True)])
    with pytest.raises(ImpactInputError, match="restitution"):
        ContactLaw(restitution=1.5)
    with pytest.raises(ImpactInputError, match="friction"):
        ContactLaw(friction=-1.0)
    with pytest.raises(ImpactInputError, match="partition"):
        ContactRows(jacobian=J, normal=(2,), tangential=(0,))
    with pytest.raises(ImpactInputError, match="columns"):
        resolve_contact_impact(M, v, [_point(J[:, :5])])
    with pytest.raises(ImpactInputError, match="positive definite"):
        resolve_contact_impact(-M, v, [_point(J)])


# -- the direct inert path against the reference path ------------------------------------------
def _bilateral_problem(seed: int, n: int = 13) -> tuple[np.ndarray, np.ndarray, list[ContactRows]]:
    """Three bilateral contacts: a point, a flat sole and a normal-only row (empty group)."""
    rng = np.random.default_rng(seed)
    M, v = _spd(rng, n), rng.standard_normal(n)
    contacts = [
        _point(rng.standard_normal((3, n)), bilateral=True),
        ContactRows(jacobian=rng.standard_normal((6, n)), normal=(2, 3, 4),
                    tangential=(0, 1, 5), tangential_weights=(1.0, 1.0, 20.0), bilateral=True),
        ContactRows(jacobian=rng.standard_normal((1, n)), normal=(0,), bilateral=True),
    ]
    return M, v, contacts


def _assert_same_impact(fast, ref, tol: float = 1e-12) -> None:
    scale_v = max(1.0, float(np.abs(ref.velocity_post).max()))
    np.testing.assert_allclose(fast.velocity_post, ref.velocity_post, rtol=0, atol=tol * scale_v)
    np.testing.assert_allclose(fast.impulse, ref.impulse, rtol=0,
                               atol=tol * float(np.abs(ref.impulse).max()))
    for key in ("T", "T_c", "T_a", "T_post", "energy_lost"):
        assert abs(getattr(fast, key) - getattr(ref, key)) <= tol * ref.T, key
    for key in ("T_c_normal", "T_c_tangential"):
        np.testing.assert_allclose(getattr(fast, key), getattr(ref, key), rtol=0, atol=tol * ref.T)


@pytest.mark.parametrize("seed", range(5))
def test_direct_inert_path_equals_the_reference_path(seed: int) -> None:
    M, v, contacts = _bilateral_problem(seed)
    ref = resolve_contact_impact(M, v, contacts)
    A = np.vstack([c.jacobian for c in contacts])
    fast = inert_contact_impact(M, v, A, InertLayout.of(contacts))
    _assert_same_impact(fast, ref)
    assert fast.modes == ref.modes
    np.testing.assert_allclose(fast.generalized_impulse, ref.generalized_impulse, rtol=0,
                               atol=1e-12 * float(np.abs(ref.generalized_impulse).max()))
    for a, b in zip(fast.contact_velocity_post, ref.contact_velocity_post, strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * max(1.0, float(np.abs(v).max())))
    assert fast.T_c_tangential[2] == 0.0  # the normal-only contact has no tangential share


def test_direct_inert_batch_equals_single_direct_and_reference_calls() -> None:
    problems = [_bilateral_problem(seed) for seed in range(6)]
    layout = InertLayout.of(problems[0][2])
    Ms = np.stack([p[0] for p in problems])
    vs = np.stack([p[1] for p in problems])
    As = np.stack([np.vstack([c.jacobian for c in p[2]]) for p in problems])
    batch = inert_contact_impact_batch(Ms, vs, As, layout)
    v_only, lam_only, _ = inert_velocity_batch(Ms, vs, As)
    for i, (M, v, contacts) in enumerate(problems):
        ref = resolve_contact_impact(M, v, contacts)
        one = type("Row", (), {k: (getattr(batch, k)[i] if np.ndim(getattr(batch, k)) > 0
                                   else getattr(batch, k))
                              for k in ("velocity_post", "impulse", "T_c_normal",
                                        "T_c_tangential")})
        for key in ("T", "T_c", "T_a", "T_post", "energy_lost"):
            setattr(one, key, float(getattr(batch, key)[i]))
        _assert_same_impact(one, ref)
        scale = max(1.0, float(np.abs(ref.velocity_post).max()))
        np.testing.assert_allclose(v_only[i], ref.velocity_post, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(lam_only[i], ref.impulse, rtol=0,
                                   atol=1e-12 * float(np.abs(ref.impulse).max()))
        v_one, lam_one = inert_velocity(M, v, As[i])
        np.testing.assert_allclose(v_one, ref.velocity_post, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(lam_one, ref.impulse, rtol=0,
                                   atol=1e-12 * float(np.abs(ref.impulse).max()))


def test_direct_inert_path_rejects_what_the_reference_rejects() -> None:
    M, v, contacts = _bilateral_problem(0)
    layout = InertLayout.of(contacts)
    A = np.vstack([c.jacobian for c in contacts])
    # an exactly redundant row; and one redundant to ~1e-14 (no certificate: the SVD decides)
    d = np.random.default_rng(7).standard_normal(A.shape[1])
    for eps in (0.0, 1e-14):
        A_bad = A.copy()
        A_bad[-1] = A_bad[0] + eps * d
        bad = [*contacts[:2], ContactRows(jacobian=A_bad[-1:], normal=(0,), bilateral=True)]
        with pytest.raises(ImpactInputError, match="rank deficient"):
            resolve_contact_impact(M, v, bad)
        with pytest.raises(ImpactInputError, match="rank deficient"):
            inert_contact_impact(M, v, A_bad, layout)
        with pytest.raises(ImpactInputError, match="rank deficient"):
            inert_contact_impact_batch(M[None], v[None], A_bad[None], layout)
    # nearly but not numerically redundant (no certificate, the SVD accepts): both paths
    # resolve it (ill-conditioned, so only the constraint residual is compared)
    A_ok = A.copy()
    A_ok[-1] = A_ok[0] + 1e-6 * d
    ok = [*contacts[:2], ContactRows(jacobian=A_ok[-1:], normal=(0,), bilateral=True)]
    for r in (inert_contact_impact(M, v, A_ok, layout), resolve_contact_impact(M, v, ok)):
        assert np.abs(A_ok @ r.velocity_post).max() < 1e-6 * np.abs(A_ok @ v).max()
    for fn in (lambda MM: inert_contact_impact(MM, v, A, layout),
               lambda MM: inert_contact_impact_batch(MM[None], v[None], A[None], layout)):
        with pytest.raises(ImpactInputError, match="positive definite"):
            fn(-M)
        M_ns = M.copy()
        M_ns[0, 1] += 1.0
        with pytest.raises(ImpactInputError, match="symmetric"):
            fn(M_ns)
    with pytest.raises(ImpactInputError, match="partition"):
        InertLayout(normal=((2,),), tangential=((0,),))
    with pytest.raises(ImpactInputError, match="exceed"):
        inert_contact_impact(M[:3, :3], v[:3], A[:, :3], layout)
