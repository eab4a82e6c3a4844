"""Issue #34, items 1-4: soles as support polygons, redundant contacts, several outcomes, and
an energetic restitution law.

The oracle here is independent of :func:`heelstrike.core.complementarity.solve_point_contacts`:
it enumerates every contact's mode of the same pyramid-cone law (``|lambda_t| <= mu
lambda_n`` per tangential row) and solves each mode's saddle-point (KKT) system in the
unknowns ``(q_dot+, impulses)`` with numpy's least squares, in the full coordinates (no
elimination of the kept rows, no Delassus matrix), then checks every sign condition. No
iterative optimiser is involved: the outcomes are the exact solutions of finitely many linear
systems.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest

from heelstrike.core.complementarity import solve_point_contacts
from heelstrike.core.contact_laws import ContactLaw, ContactRows, resolve_contact_impact
from heelstrike.core.impact import impact

SOLE = (-0.1, 0.1, -0.05, 0.05)
CORNERS = ((SOLE[0], SOLE[2]), (SOLE[1], SOLE[2]), (SOLE[1], SOLE[3]), (SOLE[0], SOLE[3]))
# pre-impact twist of the foot (vz, wx, wy) of each landing: heel first (toe rising), toe
# first, on the right edge (y < 0) first, flat
LANDINGS = {"heel": (-0.3, 0.0, -5.0), "toe": (-0.3, 0.0, 5.0), "edge": (-0.3, 6.0, 0.0),
            "flat": (-0.3, 0.0, 0.0)}


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _oracle(M: np.ndarray, v: np.ndarray, N: np.ndarray, T: np.ndarray, A_b: np.ndarray,
            mu: float, tau: np.ndarray) -> list[np.ndarray]:
    """Every distinct ``q_dot+`` of the pyramid-cone law with normal targets ``tau``."""
    n, m, kb = v.shape[0], N.shape[0], A_b.shape[0]
    if mu == 0.0:
        per: list[list[Any]] = [["sep", "free"]] * m
    elif np.isinf(mu):
        per = [["sep", (0, 0)]] * m
    else:
        per = [["sep", *itertools.product((0, 1, -1), repeat=2)]] * m
    scale = max(float(np.abs(N @ v).max()), float(np.abs(T @ v).max()), 1e-300)
    tol = 1e-9 * scale
    out: list[np.ndarray] = []
    for modes in itertools.product(*per):
        dirs, rows, target, kinds = [], [], [], []
        for i, md in enumerate(modes):
            if md == "sep":
                continue
            g = N[i].copy()
            if md != "free":
                for a in (0, 1):
                    if md[a] != 0:
                        g = g - md[a] * mu * T[i, a]  # lambda_t = -s mu lambda_n
            dirs.append(g)
            rows.append(N[i])
            target.append(tau[i])
            kinds.append(("n", i, 0))
            if md != "free":
                for a in (0, 1):
                    if md[a] == 0:
                        dirs.append(T[i, a])
                        rows.append(T[i, a])
                        target.append(0.0)
                        kinds.append(("t", i, a))
        p = len(dirs)
        K = np.zeros((n + kb + p, n + kb + p))
        rhs = np.zeros(n + kb + p)
        K[:n, :n] = M
        K[:n, n:n + kb] = -A_b.T
        if p:
            K[:n, n + kb:] = -np.array(dirs).T
            K[n + kb:, :n] = np.array(rows)
            rhs[n + kb:] = target
        K[n:n + kb, :n] = A_b
        rhs[:n] = M @ v
        bad = 1e-9 * max(float(np.abs(rhs).max()), 1.0)
        try:
            z = np.linalg.solve(K, rhs)
            if not np.abs(K @ z - rhs).max() <= bad:
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:  # singular (redundant rows): least squares
            z = np.linalg.lstsq(K, rhs, rcond=None)[0]
        if np.abs(K @ z - rhs).max() > bad:
            continue
        vp, x = z[:n], z[n + kb:]
        un, ut = N @ vp, T @ vp
        lam_n = {i: x[j] for j, (k, i, _) in enumerate(kinds) if k == "n"}
        xtol = 1e-9 * max(float(np.abs(x).max(initial=0.0)), 1e-300)
        ok = True
        for i, md in enumerate(modes):
            if md == "sep":
                ok &= bool(un[i] >= tau[i] - tol)
                continue
            ok &= bool(lam_n[i] >= -xtol)
            if md == "free":
                continue
            for a in (0, 1):
                if md[a] == 0 and np.isfinite(mu):
                    j = kinds.index(("t", i, a))
                    ok &= bool(abs(x[j]) <= mu * lam_n[i] + xtol)
                elif md[a] != 0:
                    ok &= bool(md[a] * ut[i, a] >= -tol)
        if ok and all(np.abs(vp - w).max() > 1e-8 * scale for w in out):
            out.append(vp)
    return out


def _same_set(a: list[np.ndarray] | tuple[np.ndarray, ...], b: list[np.ndarray],
              atol: float) -> bool:
    return len(a) == len(b) and all(any(np.abs(x - y).max() <= atol for y in b) for x in a)


def _foot_system(seed: int, joints: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A rigid box foot (6 dof, mass 1.2 kg, 0.2 x 0.1 x 0.05 m) under a chain of ``joints``
    leg links (random offsets, masses and joint axes; link ``k`` moves with the foot's twist
    and joints ``0..k``): ``M`` (n, n), corner rows ``N`` (4, n) and ``T`` (4, 2, n) (world
    x, y), the foot horizontal at the origin."""
    rng = np.random.default_rng(seed)
    n = 6 + joints
    m, (a, b, c) = 1.2, (0.2, 0.1, 0.05)
    inertia = m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    M = np.zeros((n, n))
    M[:3, :3] = m * np.eye(3)
    M[3:6, 3:6] = inertia
    for k in range(joints):  # leg links above the foot, moved by its twist and the joints
        J = np.zeros((6, n))
        r = np.array([rng.uniform(-0.02, 0.02), rng.uniform(-0.01, 0.01), 0.2 * (k + 1)])
        J[:3, :3], J[:3, 3:6], J[3:, 3:6] = np.eye(3), -_skew(r), np.eye(3)
        J[:, 6:6 + k + 1] = 0.1 * rng.standard_normal((6, k + 1))
        mass = rng.uniform(0.5, 3.0)
        M += J.T @ np.diag([mass] * 3 + [0.02 * mass] * 3) @ J
    M = 0.5 * (M + M.T)
    N = np.zeros((4, n))
    T = np.zeros((4, 2, n))
    for k, (x, y) in enumerate(CORNERS):
        Jc = np.zeros((3, n))
        Jc[:, :3] = np.eye(3)
        Jc[:, 3:6] = -_skew(np.array([x, y, 0.0]))
        N[k], T[k, 0], T[k, 1] = Jc[2], Jc[0], Jc[1]
    return M, N, T


def _landing(seed: int, kind: str, n: int) -> np.ndarray:
    rng = np.random.default_rng(seed + 100)
    vz, wx, wy = LANDINGS[kind]
    v = np.zeros(n)
    v[:6] = [rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2), vz, wx, wy, rng.uniform(-1, 1)]
    v[6:] = 0.5 * rng.standard_normal(n - 6)
    return v


def _corner_rows(N: np.ndarray, T: np.ndarray, mu: float, e: float) -> list[ContactRows]:
    law = ContactLaw(friction=mu, restitution=e)
    return [ContactRows(jacobian=np.vstack((T[k, 0], T[k, 1], N[k])), normal=(2,),
                        tangential=(0, 1), law=law, name=f"corner {k}") for k in range(4)]


# -- 1. the sole as its support polygon, against the oracle ----------------------------------
@pytest.mark.parametrize("kind", list(LANDINGS))
@pytest.mark.parametrize("e", [0.0, 0.5])
@pytest.mark.parametrize("mu", [0.0, 0.3, np.inf])
def test_support_polygon_landings_match_the_mode_enumeration(kind: str, e: float,
                                                              mu: float) -> None:
    for seed in (0,) if mu == 0.3 else (0, 1):
        M, N, T = _foot_system(seed)
        v = _landing(seed, kind, M.shape[0])
        u_pre = N @ v
        tau = -e * np.minimum(u_pre, 0.0)
        ref = _oracle(M, v, N, T, np.zeros((0, M.shape[0])), mu, tau)
        sol = solve_point_contacts(M, v, N, tangential=T, friction=mu, restitution=e)
        scale = float(np.abs(v).max())
        assert sol.exhaustive and ref
        assert _same_set(sol.solutions, ref, 1e-9 * scale)
        res = resolve_contact_impact(M, v, _corner_rows(N, T, mu, e))
        np.testing.assert_allclose(res.velocity_post, sol.velocity_post, atol=1e-12 * scale)
        # no corner moves into the ground after the impact; a rebound is e times the approach
        un = N @ res.velocity_post
        assert np.all(un >= tau - 1e-10 * scale)
        np.testing.assert_allclose(un[un < tau + 1e-9 * scale] - tau[un < tau + 1e-9 * scale],
                                   0.0, atol=1e-9 * scale)
        assert res.T_c_normal.sum() + res.T_c_tangential.sum() == pytest.approx(res.T_c,
                                                                               rel=1e-10)
        assert np.all(res.T_c_normal >= 0.0) and np.all(res.T_c_tangential >= 0.0)
        assert res.T_c + res.T_a == pytest.approx(res.T, rel=1e-12)
        if e == 0.0:  # inert: T_c >= 0, nothing gained, and the loss is at least T_c
            assert res.T_c >= 0.0 and res.T_post <= res.T * (1 + 1e-12)
            assert res.energy_lost >= res.T_c * (1 - 1e-9) - 1e-12 * res.T
        if kind == "heel" and np.isinf(mu):  # heel first: the toe corners do not dig in
            assert un[1] >= -1e-12 and un[2] >= -1e-12


def test_lemke_outcome_is_one_of_the_enumerated_ones() -> None:
    """Above the enumeration budget one outcome comes from Lemke's method: it is one of the
    oracle's (the same law), for each landing with friction 0.3 and e 0 / 0.5."""
    for seed, kind in itertools.product((2,), LANDINGS):
        for e in (0.5,):
            M, N, T = _foot_system(seed)
            v = _landing(seed, kind, M.shape[0])
            tau = -e * np.minimum(N @ v, 0.0)
            ref = _oracle(M, v, N, T, np.zeros((0, M.shape[0])), 0.3, tau)
            lem = solve_point_contacts(M, v, N, tangential=T, friction=0.3, restitution=e,
                                       budget=0)
            assert not lem.exhaustive and lem.unique is None and lem.active_sets == 10 ** 4
            assert any(np.abs(lem.velocity_post - r).max() <= 1e-9 for r in ref)


# -- 2. redundant contacts: solved, not refused -----------------------------------------------
def _pinv_projection(M: np.ndarray, v: np.ndarray, A: np.ndarray) -> np.ndarray:
    """``q_dot+ = q_dot- - M^-1 A^T (A M^-1 A^T)^+ A q_dot-`` (any rank of ``A``)."""
    X = np.linalg.solve(M, A.T)
    return v - X @ (np.linalg.pinv(A @ X, rcond=1e-12, hermitian=True) @ (A @ v))


@pytest.mark.parametrize("seed", [0, 3, 4, 5])
def test_four_corner_flat_landing_is_the_pinv_projection_and_the_bilateral_sole(seed) -> None:
    M, N, T = _foot_system(seed, joints=1)
    v = np.zeros(M.shape[0])
    v[2] = -0.3  # straight down, flat
    rows = _corner_rows(N, T, np.inf, 0.0)
    A = np.vstack([r.jacobian for r in rows])  # 12 rows of rank 6
    assert np.linalg.matrix_rank(A) == 6
    res = resolve_contact_impact(M, v, rows)
    assert res.unique and res.exhaustive
    scale = float(np.abs(v).max())
    np.testing.assert_allclose(res.velocity_post, _pinv_projection(M, v, A), rtol=0,
                               atol=1e-12 * scale)
    np.testing.assert_allclose(A @ res.velocity_post, 0.0, atol=1e-12 * scale)
    # the same as the bilateral six-row sole (closed form, full rank), whose centre of
    # pressure lies on the sole: both hold it flat
    J6 = np.zeros((6, M.shape[0]))
    J6[:, :6] = np.eye(6)
    flat = impact(M, J6, v)
    lam = flat.constraint_impulse
    cop = (-lam[4] / lam[2], lam[3] / lam[2])
    assert lam[2] > 0 and SOLE[0] <= cop[0] <= SOLE[1] and SOLE[2] <= cop[1] <= SOLE[3]
    np.testing.assert_allclose(res.velocity_post, flat.velocity_post, rtol=0,
                               atol=1e-12 * scale)
    assert res.T_c == pytest.approx(float(flat.kinetic_energy_constrained), rel=1e-10)
    assert res.energy_lost == pytest.approx(res.T_c, rel=1e-9)
    assert res.T_c_normal.sum() + res.T_c_tangential.sum() == pytest.approx(res.T_c, rel=1e-10)
    # corner impulses by the stated rule (the smallest active set): all push, and they
    # reproduce the momentum change
    assert all(res.impulse[3 * k + 2] >= -1e-12 for k in range(4))
    np.testing.assert_allclose(M @ (res.velocity_post - v), A.T @ res.impulse, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 3, 4, 5])
def test_two_heel_corners_are_a_heel_edge(seed: int) -> None:
    """Two corners of one heel: 6 rows of rank 5. Sticking, q_dot+ is the projection onto the
    kernel of any 5 independent rows of them: corner 0's 3 rows plus corner 3's x and z (its
    y velocity repeats corner 0's). It differs from the four-corner answer."""
    M, N, T = _foot_system(seed, joints=1)
    v = np.zeros(M.shape[0])
    v[2], v[4] = -0.3, -5.0  # heel first, toe rising
    heel = [r for k, r in enumerate(_corner_rows(N, T, np.inf, 0.0)) if k in (0, 3)]
    A = np.vstack([r.jacobian for r in heel])
    assert np.linalg.matrix_rank(A) == 5
    independent = np.vstack((A[:3], A[3], A[5]))  # corner 0 (x, y, z), corner 3 (x, z)
    ref = impact(M, independent, v)
    assert ref.constraint_impulse[2] > 0 and ref.constraint_impulse[4] > 0  # both push
    res = resolve_contact_impact(M, v, heel)
    assert res.modes == ("stick", "stick") and res.unique
    scale = float(np.abs(v).max())
    np.testing.assert_allclose(res.velocity_post, ref.velocity_post, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(res.velocity_post, _pinv_projection(M, v, A), rtol=0,
                               atol=1e-12 * scale)
    oracle = _oracle(M, v, N[[0, 3]], T[[0, 3]], np.zeros((0, M.shape[0])), np.inf,
                     np.zeros(2))
    assert _same_set(res.solutions, oracle, 1e-12 * scale)
    assert res.T_c == pytest.approx(float(ref.kinetic_energy_constrained), rel=1e-10)
    assert res.T_c_normal.sum() + res.T_c_tangential.sum() == pytest.approx(res.T_c, rel=1e-10)
    # both heel corners end at rest; impulses push, and reproduce the momentum change
    for r in heel:
        np.testing.assert_allclose(r.jacobian @ res.velocity_post, 0.0, atol=1e-12 * scale)
    assert res.impulse[2] >= 0.0 and res.impulse[5] >= 0.0
    np.testing.assert_allclose(M @ (res.velocity_post - v), A.T @ res.impulse, atol=1e-12)
    # the toe is not held: a different answer from the bilateral flat sole (which stops the
    # rising toe too and loses more), and the same as the whole support polygon, whose toe
    # corners lift (the same law)
    J6 = np.zeros((6, M.shape[0]))
    J6[:, :6] = np.eye(6)
    flat = impact(M, J6, v)
    assert np.abs(flat.velocity_post - res.velocity_post).max() > 1e-2 * scale
    assert float(flat.kinetic_energy_constrained) > res.T_c * (1 + 1e-3)
    whole = resolve_contact_impact(M, v, _corner_rows(N, T, np.inf, 0.0))
    assert whole.modes[1] == whole.modes[2] == "separate" and whole.unique
    np.testing.assert_allclose(whole.velocity_post, res.velocity_post, atol=1e-12 * scale)


def test_unbounded_friction_without_a_stick_or_separate_outcome_slides() -> None:
    """Two heel corners that can neither both stick (one would pull) nor leave one free (it
    would pass through): a Painleve-type case. The unbounded cone then takes the exact
    large-mu limit: the corner slides with a vanishing normal impulse and a finite friction
    impulse, and the outcome is the limit of the finite law's (oracle) as ``mu -> inf``, with
    an error of order ``1 / mu``."""
    M, N, T = _foot_system(1, joints=2)
    v = np.zeros(M.shape[0])
    v[2], v[4] = -0.3, -5.0
    idx = [0, 3]
    assert _oracle(M, v, N[idx], T[idx], np.zeros((0, M.shape[0])), np.inf, np.zeros(2)) == []
    sol = solve_point_contacts(M, v, N[idx], tangential=T[idx], friction=np.inf)
    assert "slip" in sol.modes and sol.unique
    sliding = sol.modes.index("slip")
    assert sol.impulse[sliding, 0] == 0.0 and np.abs(sol.impulse[sliding, 1:]).max() > 0.1
    errors = []
    for mu in (1e3, 1e4, 1e5):
        finite = _oracle(M, v, N[idx], T[idx], np.zeros((0, M.shape[0])), mu, np.zeros(2))
        assert len(finite) == 1
        errors.append(float(np.abs(finite[0] - sol.velocity_post).max()))
    assert errors[1] < 0.2 * errors[0] and errors[2] < 0.2 * errors[1] < 1e-5
    assert np.all(N[idx] @ sol.velocity_post >= -1e-12)
    assert sol.kkt_residual < 1e-12


# -- 3. several outcomes are reported -----------------------------------------------------------
def _two_outcome_case() -> tuple[np.ndarray, np.ndarray, list[ContactRows]]:
    """One contact, unbounded friction, whose normal and tangential rows couple
    (``W = [[1, -1/2], [-1/2, 1]]``): moving away at 0.1 m/s and sliding at -1 m/s it may
    separate untouched, or stick, the tangential stop pressing it onto the ground
    (``lambda_n = 0.4 / 0.75 > 0``). Both satisfy the law (Painleve-type)."""
    M = np.eye(3)
    J = np.array([[-0.5, np.sqrt(0.75), 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])  # t1, t2, n
    v = np.linalg.solve(J, [-1.0, 0.0, 0.1])
    return M, v, [ContactRows(jacobian=J, normal=(2,), tangential=(0, 1), name="c")]


def test_a_contact_with_two_outcomes_is_reported(capsys) -> None:
    M, v, rows = _two_outcome_case()
    res = resolve_contact_impact(M, v, rows)
    assert res.exhaustive and res.unique is False and res.outcomes == 2
    J = rows[0].jacobian
    ref = _oracle(M, v, J[2:3], J[None, :2], np.zeros((0, 3)), np.inf, np.zeros(1))
    assert _same_set(res.solutions, ref, 1e-12)
    kinds = sorted("separate" if np.allclose(s, v) else "stick" for s in res.solutions)
    assert kinds == ["separate", "stick"]
    stuck = next(s for s in res.solutions if not np.allclose(s, v))
    np.testing.assert_allclose(J @ stuck, 0.0, atol=1e-14)  # at rest, pushed (not pulled):
    assert float(np.linalg.solve(J.T, stuck - v)[2]) == pytest.approx(0.4 / 0.75, rel=1e-12)
    d = res.to_dict()
    assert len(d["solutions"]) == 2 and d["exhaustive"] is True
    # the robot result's JSON keys and the command line's note
    pytest.importorskip("pinocchio")
    from heelstrike.cli.robot import _note_outcomes
    from heelstrike.robots.contacts import ContactSpec, RobotImpact

    rob = RobotImpact(contacts=(ContactSpec(frame="c"),), bilateral=(False,), result=res, M=M,
                      jacobians=(J,))
    rd = rob.to_dict()
    assert rd["unique"] is False and rd["outcomes"] == 2 and len(rd["solutions"]) == 2
    _note_outcomes(rd, {})
    err = capsys.readouterr().err
    assert "admits 2 outcomes" in err and "'solutions'" in err
    # a single-outcome impact says nothing and reports unique
    M2, N, T = _foot_system(0)
    one = resolve_contact_impact(M2, _landing(0, "flat", M2.shape[0]),
                                 _corner_rows(N, T, np.inf, 0.0))
    assert one.unique is True and one.outcomes == 1


# -- 4. the energetic restitution law ---------------------------------------------------------
def _kane_cases(count: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                         float, float]]:
    """Random impacts where Newton's law with sticking friction gains energy."""
    rng = np.random.default_rng(34)
    found = []
    for _ in range(40 * count):
        m = int(rng.integers(1, 3))
        n = int(rng.integers(3 * m + 1, 3 * m + 4))  # independent rows
        B = rng.standard_normal((n, n))
        M = B @ B.T + 0.2 * np.eye(n)
        N = rng.standard_normal((m, n))
        T = rng.standard_normal((m, 2, n))
        v = rng.standard_normal(n)
        mu = float(rng.choice([np.inf, np.inf, np.inf, 5.0]))
        e = float(rng.uniform(0.2, 1.0))
        newton = solve_point_contacts(M, v, N, tangential=T, friction=mu, restitution=e)
        vp = newton.velocity_post
        if 0.5 * vp @ M @ vp > 0.5 * v @ M @ v * (1 + 1e-9):
            found.append((M, v, N, T, mu, e))
            if len(found) == count:
                break
    return found


def test_energetic_law_never_gains_energy_where_newton_does() -> None:
    cases = _kane_cases(1000)
    assert len(cases) == 1000
    worst = -np.inf
    for M, v, N, T, mu, e in cases:
        T0 = 0.5 * v @ M @ v
        en = solve_point_contacts(M, v, N, tangential=T, friction=mu, restitution=e,
                                  law="energetic")
        vp = en.velocity_post
        worst = max(worst, (0.5 * vp @ M @ vp - T0) / T0)
        # and no contact ends moving into the ground
        assert np.all(N @ vp >= -1e-9 * max(float(np.abs(N @ v).max()), 1.0))
    assert worst <= 1e-12


def test_energetic_law_is_newton_without_restitution_and_differs_in_kanes_regime() -> None:
    # e = 0: the same law
    for seed in range(3):
        M, N, T = _foot_system(seed)
        v = _landing(seed, "heel", M.shape[0])
        a = solve_point_contacts(M, v, N, tangential=T, friction=0.3, restitution=0.0)
        b = solve_point_contacts(M, v, N, tangential=T, friction=0.3, restitution=0.0,
                                 law="energetic")
        np.testing.assert_array_equal(a.velocity_post, b.velocity_post)
    # one frictionless contact: both give u_n+ = -e u_n- (Newton's closed form)
    M, v, N = np.diag([2.0, 3.0]), np.array([-1.0, 0.5]), np.array([[1.0, 0.0]])
    for law in ("newton", "energetic"):
        s = solve_point_contacts(M, v, N, restitution=0.6, law=law)  # type: ignore[arg-type]
        np.testing.assert_allclose(s.velocity_post, [0.6, 0.5], atol=1e-15)
    # Kane's regime: Newton gains energy, the energetic law returns at most e^2 of what the
    # compression absorbed
    M, v, N, T, mu, e = _kane_cases(1)[0]
    newton = solve_point_contacts(M, v, N, tangential=T, friction=mu, restitution=e)
    en = solve_point_contacts(M, v, N, tangential=T, friction=mu, restitution=e,
                              law="energetic")
    T0 = 0.5 * v @ M @ v
    Tc_end = 0.5 * en.compression_velocity @ M @ en.compression_velocity
    assert 0.5 * newton.velocity_post @ M @ newton.velocity_post > T0
    assert 0.5 * en.velocity_post @ M @ en.velocity_post <= Tc_end + e * e * (T0 - Tc_end) + 1e-12
    assert np.abs(newton.velocity_post - en.velocity_post).max() > 1e-6


# -- a Pinocchio robot: Talos's left sole as its support polygon ---------------------------------
def _talos_corner_rows(robot: Any, q: np.ndarray, frame: str) -> np.ndarray:
    """Corner rows (4, 3, nv) from frames added at the corners (Pinocchio's own Jacobians)."""
    pin = pytest.importorskip("pinocchio")
    model = pin.Model(robot.model)
    sole = model.frames[model.getFrameId(frame)]
    ids = []
    for k, (x, y) in enumerate(CORNERS):
        place = sole.placement * pin.SE3(np.eye(3), np.array([x, y, 0.0]))
        ids.append(model.addFrame(pin.Frame(f"corner{k}", sole.parentJoint,
                                            model.getFrameId(frame), place,
                                            pin.FrameType.OP_FRAME)))
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    return np.array([pin.getFrameJacobian(model, data, i,
                                          pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3]
                     for i in ids])


TALOS_CASES = [("heel", 0.5, 0.3), ("toe", 0.0, np.inf), ("edge", 0.5, 0.0), ("flat", 0.0, 0.3)]


@pytest.mark.parametrize(("kind", "e", "mu"), TALOS_CASES)
def test_talos_sole_landings_match_the_mode_enumeration(kind: str, e: float, mu: float) -> None:
    pin = pytest.importorskip("pinocchio")
    from heelstrike.robots import load_robot, parse_contact, robot_impact
    from heelstrike.robots.states import gait_state

    talos = load_robot("talos")
    q, v = gait_state(talos, 0.3, 0.3)
    v = np.array(v)
    model = talos.model
    pitch = model.joints[model.getJointId("leg_left_5_joint")].idx_v
    roll = model.joints[model.getJointId("leg_left_6_joint")].idx_v
    v[pitch] += {"heel": -5.0, "toe": 5.0}.get(kind, 0.0)
    v[roll] += 5.0 if kind == "edge" else 0.0
    res = robot_impact(talos, q, v, strike=[parse_contact("left_sole_link:flat")],
                       keep=[parse_contact("right_sole_link:flat-bilateral")], friction=mu,
                       restitution=e)
    data = model.createData()
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    A_b = np.array(pin.getFrameJacobian(model, data, model.getFrameId("right_sole_link"),
                                        pin.ReferenceFrame.LOCAL_WORLD_ALIGNED))
    C = _talos_corner_rows(talos, q, "left_sole_link")
    N, T = C[:, 2], C[:, :2]
    tau = -e * np.minimum(N @ v, 0.0)
    ref = _oracle(M, v, N, T, A_b, mu, tau)
    r = res.result
    assert r.exhaustive and _same_set(r.solutions, ref, 1e-9)
    scale = float(np.abs(v).max())
    un = N @ r.velocity_post
    assert np.all(un >= tau - 1e-9 * scale)  # no corner into the ground
    np.testing.assert_allclose(A_b @ r.velocity_post, 0.0, atol=1e-10 * scale)
    if e == 0.0:
        assert r.T_c >= 0.0 and r.T_post <= r.T * (1 + 1e-12)
    d = res.to_dict()
    corners = d["contacts"][0]["corners"]
    assert len(corners) == 4 and d["unique"] is True
    assert min(c["normal_velocity_post"] for c in corners) >= -1e-9 * scale
    assert sum(c["T_c_normal"] + c["T_c_tangential"] for c in d["contacts"][0]["corners"]) \
        == pytest.approx(d["contacts"][0]["T_c_normal"] + d["contacts"][0]["T_c_tangential"],
                         rel=1e-12)


def test_talos_issue_example_polygon_against_the_bilateral_sole() -> None:
    """The issue's example: heel-first with e = 0.5. The bilateral sole reverses the tilt and
    drives the toe into the ground; the polygon rebounds the heel at e times its approach
    and leaves no corner moving into the ground. With e = 0 and a flat landing the polygon
    and the bilateral sole agree (the sole's centre of pressure is on it)."""
    pytest.importorskip("pinocchio")
    from heelstrike.robots import load_robot, parse_contact, robot_impact
    from heelstrike.robots.states import gait_state

    talos = load_robot("talos")
    q, v = gait_state(talos, 0.3, 0.3)
    flat_v = np.array(v)
    v = np.array(v)
    v[talos.model.joints[talos.model.getJointId("leg_left_5_joint")].idx_v] -= 5.0
    C = _talos_corner_rows(talos, q, "left_sole_link")
    feet = ("left_sole_link", "right_sole_link")
    kw: dict[str, Any] = {"friction": 0.8, "restitution": 0.5}
    poly = robot_impact(talos, q, v, strike=[parse_contact(f"{f}:flat") for f in feet], **kw)
    bil = robot_impact(talos, q, v, strike=[parse_contact(f"{f}:flat-bilateral") for f in feet],
                       **kw)
    u_pre = C[:, 2] @ v
    assert u_pre.min() < -0.7 and u_pre.max() > 0.1  # heel approaching, toe rising
    assert (C[:, 2] @ bil.result.velocity_post).min() < -0.05  # the toe digs in
    u_poly = C[:, 2] @ poly.result.velocity_post
    assert u_poly.min() >= -1e-9
    heel = u_pre < 0
    np.testing.assert_allclose(u_poly[heel], -0.5 * u_pre[heel], atol=1e-9)
    # e = 0, flat landing: the same impact (and no tilting kept sole)
    a = robot_impact(talos, q, flat_v, strike=[parse_contact("left_sole_link:flat")],
                     keep=[parse_contact("right_sole_link:flat")])
    b = robot_impact(talos, q, flat_v, strike=[parse_contact("left_sole_link:flat-bilateral")],
                     keep=[parse_contact("right_sole_link:flat")])
    np.testing.assert_allclose(a.result.velocity_post, b.result.velocity_post, atol=1e-12)
    assert a.result.T_c == pytest.approx(b.result.T_c, rel=1e-10)


@pytest.mark.parametrize("law", ["newton", "energetic"])
def test_cli_sole_polygon_json_and_text(law: str, tmp_path, capsys) -> None:
    """``impact --robot`` with a FRAME:flat strike lists the corners, the outcome count and
    the restitution law (JSON keys with units, a text line)."""
    pytest.importorskip("pinocchio")
    import json

    from heelstrike.cli import main
    from heelstrike.robots import load_robot
    from heelstrike.robots.states import gait_state

    talos = load_robot("talos")
    q, v = gait_state(talos, 0.3, 0.3)
    v = np.array(v)
    v[talos.model.joints[talos.model.getJointId("leg_left_5_joint")].idx_v] -= 5.0
    state = tmp_path / "state.json"
    state.write_text(json.dumps({"q": [float(x) for x in q], "v": [float(x) for x in v]}))
    argv = ["impact", "--robot", "talos", "--state", str(state), "--strike",
            "left_sole_link:flat:0.1,0.05", "--keep", "right_sole_link:flat", "--friction", "0.8",
            "--restitution", "0.5", "--restitution-law", law]
    assert main([*argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    sole = d["contacts"][0]
    assert sole["type"] == "flat" and len(sole["corners"]) == 4
    assert min(c["normal_velocity_post"] for c in sole["corners"]) >= -1e-9
    heel = [c for c in sole["corners"] if c["corner"][0] < 0]
    assert all(c["normal_velocity_pre"] == pytest.approx(-0.8, abs=1e-6) for c in heel)
    if law == "newton":
        assert all(c["normal_velocity_post"] == pytest.approx(-0.5 * c["normal_velocity_pre"],
                                                              abs=1e-9) for c in heel)
    else:
        assert d["T_plus"] <= d["T"] and all(
            0.0 < c["normal_velocity_post"] <= -0.5 * c["normal_velocity_pre"] for c in heel)
    assert d["restitution_law"] == law and d["unique"] is True and d["outcomes"] == 1
    assert d["active_sets"] == 10 ** 4 and len(d["solutions"]) == 1
    assert len(d["impulse"]) == 4 * 3 + 6 and len(d["units"]["impulse"]) == 18
    assert set(d["units"]) == set(d) - {"units"}
    assert set(d["units"]["contacts"]["corners"]) == set(sole["corners"][0])
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert f"unique          yes ({law} restitution)" in out and out.count("corner (") == 4


def test_kept_flat_sole_says_when_a_corner_would_pull(tmp_path, capsys) -> None:
    """A kept (bilateral) flat sole whose ankle spins pushes on the ground with its centre of
    pressure 0.55 m behind its frame, far off its 0.2 m sole: held flat, a corner would have
    to pull. It is named (tilting_contacts, a note); struck as a polygon it tilts instead,
    with no corner moving into the ground."""
    pytest.importorskip("pinocchio")
    import json

    from heelstrike.cli import main
    from heelstrike.robots import load_robot, parse_contact, robot_impact
    from heelstrike.robots.states import gait_state

    talos = load_robot("talos")
    q, v = gait_state(talos, 0.3, 0.3)
    v = np.array(v)
    v[talos.model.joints[talos.model.getJointId("leg_right_5_joint")].idx_v] -= 5.0
    left = parse_contact("left_sole_link:flat")
    kept = robot_impact(talos, q, v, strike=[left], keep=[parse_contact("right_sole_link:flat")])
    d = kept.to_dict()
    assert kept.tilting == ("right_sole_link",) and d["tilting_contacts"] == ["right_sole_link"]
    assert d["admissible"] is True  # its normal impulse pushes: not a pulling contact
    f_z = d["contacts"][1]["force_impulse"][2]
    cop = d["contacts"][1]["centre_of_pressure"]
    assert f_z > 0.1 and cop[0] < -0.5
    state = tmp_path / "state.json"
    state.write_text(json.dumps({"q": [float(x) for x in q], "v": [float(x) for x in v]}))
    assert main(["impact", "--robot", "talos", "--state", str(state), "--strike",
                 "left_sole_link:flat", "--keep", "right_sole_link:flat-bilateral"]) == 0
    err = capsys.readouterr().err
    assert "kept sole right_sole_link is held flat although one of its corners would have to " \
           "pull" in err and "--strike right_sole_link:flat" in err
    both = robot_impact(talos, q, v, strike=[left, parse_contact("right_sole_link:flat")])
    corners = both.to_dict()["contacts"][1]["corners"]
    assert any(c["mode"] == "separate" for c in corners)  # it tilts
    assert min(c["normal_velocity_post"] for c in corners) >= -1e-9
    # a sole whose centre of pressure is on it is not named (the flat landing)
    q, v = gait_state(talos, 0.3, 0.3)
    assert robot_impact(talos, q, v, strike=[left],
                        keep=[parse_contact("right_sole_link:flat")]).tilting == ()


def test_parse_sole_polygons() -> None:
    pytest.importorskip("pinocchio")
    from heelstrike.robots import parse_contact
    from heelstrike.robots.contacts import DEFAULT_SOLE
    from heelstrike.robots.loading import RobotError

    assert parse_contact("foot:flat").sole == DEFAULT_SOLE
    assert parse_contact("foot:flat:0.12,0.06").sole == (-0.12, 0.12, -0.06, 0.06)
    s = parse_contact("foot:flat-bilateral:-0.11,0.1,-0.07,0.07")
    assert s.kind == "flat-bilateral" and s.sole == (-0.11, 0.1, -0.07, 0.07) and s.rows == 6
    assert s.corners == ((-0.11, -0.07), (0.1, -0.07), (0.1, 0.07), (-0.11, 0.07))
    for bad in ("foot:flat:0.1", "foot:flat:x,y", "foot:flat:0.1,0.1,0.2,-0.2", "foot:flat:-1,1"):
        with pytest.raises(RobotError, match="sole"):
            parse_contact(bad)
