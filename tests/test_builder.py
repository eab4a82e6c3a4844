"""Model builder: descriptions -> derived equations, checked against physics and CompassGait."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from heelstrike.models import CompassGait
from heelstrike.models import builder as builder_mod
from heelstrike.models.builder import BuiltWalker, build, load_walker, shipped_walkers
from heelstrike.models.description import ModelDescriptionError, read_description


@pytest.fixture(scope="module", autouse=True)
def _cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Keep generated code out of the user's cache; derivations are memoised per session."""
    d = tmp_path_factory.mktemp("hs_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("HEELSTRIKE_CACHE_DIR", str(d))
        yield d


def _rel_err(a: np.ndarray, b: np.ndarray) -> float:
    scale = max(float(np.max(np.abs(b))), 1.0)
    return float(np.max(np.abs(a - b))) / scale


# -- compass: builder == hand-written CompassGait --------------------------------------------------


@pytest.mark.parametrize("R", [0.0, 0.13, 0.5, 1.0])
@pytest.mark.parametrize("inertia", [0.0, 0.07])
def test_compass_builder_equals_compassgait(R: float, inertia: float) -> None:
    w = load_walker("compass", R=R, I=inertia)
    cg = CompassGait(foot_radius=R, leg_inertia=inertia)
    rng = np.random.default_rng(int(100 * R + 1000 * inertia))
    q = rng.uniform(-1.0, 1.0, (20, 4)) * [1.0, 1.0, 0.8, 1.5]
    qd = rng.normal(size=(20, 4)) * 2.0
    slope = rng.uniform(-0.2, 0.2, 20)
    tol = 1e-12
    assert _rel_err(w.mass_matrix(q), cg.mass_matrix(q)) < tol
    assert _rel_err(w.bias_forces(q, qd, slope), cg.bias_forces(q, qd, slope)) < tol
    assert _rel_err(w.potential_energy(q, slope), cg.potential_energy(q, slope)) < tol
    for foot in ("right", "left"):
        assert _rel_err(w.contact_jacobian(q, foot), cg.contact_jacobian(q, foot)) < tol
        assert (
            _rel_err(w.contact_jacobian_rate(q, qd, foot), cg.contact_jacobian_rate(q, qd, foot))
            < tol
        )
        assert _rel_err(w.contact_point(q, foot), cg.contact_point(q, foot)) < tol
        assert _rel_err(w.foot_clearance(q, foot), cg.foot_clearance(q, foot)) < tol
    pos, cpos = w.positions(q), cg.positions(q)
    pairs = {
        "hip": cpos.hip,
        "stance_leg.distal": cpos.hip,
        "swing_leg.proximal": cpos.hip,
        "stance_foot.centre": cpos.right_foot_centre,
        "swing_foot.centre": cpos.left_foot_centre,
        "stance_foot.contact": cpos.right_contact,
        "swing_foot.contact": cpos.left_contact,
        "stance_leg.com": cpos.right_leg_com,
        "swing_leg.com": cpos.left_leg_com,
    }
    for name, ref in pairs.items():
        assert _rel_err(pos[name], ref) < tol, name
    qs, qds = w.swap_legs(q, qd)
    cqs, cqds = cg.swap_legs(q, qd)
    assert _rel_err(qs, cqs) < tol
    assert _rel_err(qds, cqds) < tol
    np.testing.assert_allclose(w.total_mass, cg.total_mass, rtol=1e-15)
    np.testing.assert_allclose(w.foot_radii, cg.foot_radii, rtol=0)
    np.testing.assert_array_equal(w.actuation_matrix(), cg.actuation_matrix())


def test_parameter_arrays_broadcast_like_a_loop() -> None:
    """Array-valued parameters (a grid of radii) broadcast against batched states."""
    radii = np.linspace(0.0, 1.0, 6)[:, None]  # (6, 1)
    w = load_walker("compass", R=radii)
    rng = np.random.default_rng(3)
    q = rng.normal(size=(1, 5, 4))[0]  # (5, 4) -> broadcast to (6, 5)
    qd = rng.normal(size=(5, 4))
    M = w.mass_matrix(q)
    h = w.bias_forces(q, qd, 0.1)
    A = w.contact_jacobian(q, "left")
    assert M.shape == (6, 5, 4, 4) and h.shape == (6, 5, 4) and A.shape == (6, 5, 2, 4)
    for i, R in enumerate(radii[:, 0]):
        cg = CompassGait(foot_radius=R)
        np.testing.assert_allclose(M[i], cg.mass_matrix(q), rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(h[i], cg.bias_forces(q, qd, 0.1), rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(A[i], cg.contact_jacobian(q, "left"), atol=1e-14)


# -- the combined (M, h) of a right-hand side evaluation --------------------------------------


@pytest.mark.parametrize("name", ["compass", "kneed", "torso"])
def test_dynamics_terms_equals_the_separate_functions(name: str) -> None:
    """One generated function (one CSE over M and h) gives what mass_matrix and bias_forces
    give: single states (the integrator's Python-float path), batches, mixed broadcasting."""
    w = load_walker(name)
    n = w.n_coordinates
    rng = np.random.default_rng(sum(map(ord, name)))
    for lead in [(), (), (), (7,), (3, 4)]:
        q = rng.uniform(-np.pi, np.pi, (*lead, n))
        qd = rng.normal(size=(*lead, n)) * 3.0
        slope = float(rng.uniform(-0.3, 0.3))
        M, h = w.dynamics_terms(q, qd, slope)
        assert M.shape == (*lead, n, n) and h.shape == (*lead, n)
        assert _rel_err(M, w.mass_matrix(q)) < 1e-13
        assert _rel_err(h, w.bias_forces(q, qd, slope)) < 1e-13
    q, qd, slopes = rng.normal(size=n), rng.normal(size=(5, n)), rng.uniform(-0.2, 0.2, 5)
    M, h = w.dynamics_terms(q, qd, slopes)
    assert M.shape == (n, n) and h.shape == (5, n)
    assert _rel_err(M, w.mass_matrix(q)) < 1e-13
    assert _rel_err(h, w.bias_forces(q, qd, slopes)) < 1e-13


def test_dynamics_terms_of_the_compass_equals_compassgait() -> None:
    w, cg = load_walker("compass", R=0.3), CompassGait(foot_radius=0.3)
    rng = np.random.default_rng(11)
    for _ in range(20):
        q, qd = rng.uniform(-1.0, 1.0, 4), rng.normal(size=4) * 2.0
        slope = float(rng.uniform(-0.2, 0.2))
        (M, h), (Mc, hc) = w.dynamics_terms(q, qd, slope), cg.dynamics_terms(q, qd, slope)
        assert _rel_err(M, Mc) < 1e-12 and _rel_err(h, hc) < 1e-12


def test_dynamics_terms_with_parameter_arrays_and_overflow() -> None:
    radii = np.array([0.0, 0.3, 0.6])
    w = load_walker("compass", R=radii)
    q, qd = np.array([0.1, 0.2, 0.3, -0.5]), np.array([-0.2, 0.0, 1.0, 0.4])
    M, h = w.dynamics_terms(q, qd, 0.05)
    assert M.shape == (3, 4, 4) and h.shape == (3, 4)
    for i, R in enumerate(radii):
        Mc, hc = CompassGait(foot_radius=R).dynamics_terms(q, qd, 0.05)
        assert _rel_err(M[i], Mc) < 1e-12 and _rel_err(h[i], hc) < 1e-12
    # where Python floats would raise (u**2 overflows), numpy semantics: inf, like bias_forces
    huge = np.array([0.0, 0.0, 1e200, 0.0])
    with np.errstate(over="ignore", invalid="ignore"):
        _, h_big = load_walker("compass").dynamics_terms(q, huge, 0.05)
        ref = load_walker("compass").bias_forces(q, huge, 0.05)
    assert not np.all(np.isfinite(h_big))
    np.testing.assert_array_equal(h_big, ref)


def test_scipy_right_hand_side_evaluates_dynamics_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 9 item 6: one (M, h) evaluation per right-hand side call, nothing built twice."""
    from heelstrike.dynamics.single_support import SingleSupport

    w = load_walker("kneed")
    sup = SingleSupport(walker=w, slope=0.05, torque=None, locked=w.lockable_joints[:1])
    rng = np.random.default_rng(2)
    q, qd = _rolling_state(w, rng)
    m = len(sup.free_coordinates)
    x = np.concatenate((sup.pack(q, qd), [0.0]))
    q, qd = sup.unpack(x[: 2 * m], q)  # the locked knee at rest
    expected = sup.accelerations(0.0, q, qd)  # from mass_matrix and bias_forces
    calls = {"dynamics_terms": 0}
    original = BuiltWalker.dynamics_terms

    def counted(self: BuiltWalker, *args: object) -> tuple[np.ndarray, np.ndarray]:
        calls["dynamics_terms"] += 1
        return original(self, *args)  # type: ignore[arg-type]

    def forbidden(*_: object, **__: object) -> None:
        raise AssertionError("the right-hand side evaluated M or h separately")

    monkeypatch.setattr(BuiltWalker, "dynamics_terms", counted)
    monkeypatch.setattr(BuiltWalker, "mass_matrix", forbidden)
    monkeypatch.setattr(BuiltWalker, "bias_forces", forbidden)
    dx = sup.rhs(0.0, x, q)
    assert calls["dynamics_terms"] == 1
    _, qdd_free = sup.unpack(np.concatenate((x[m : 2 * m], dx[m : 2 * m])), q)
    assert _rel_err(qdd_free, expected) < 1e-12


# -- derived equations conserve energy (kneed, torso) -------------------------------------------


def _flight_rhs(w: BuiltWalker, slope: float):  # type: ignore[no-untyped-def]
    n = w.n_coordinates

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        q, qd = x[:n], x[n:]
        qdd = np.linalg.solve(w.mass_matrix(q), -w.bias_forces(q, qd, slope))
        return np.concatenate((qd, qdd))

    return rhs


def _stance_rhs(w: BuiltWalker, slope: float):  # type: ignore[no-untyped-def]
    """Stance foot rolling: [M -A^T; A 0][qdd; lam] = [-h; -A_dot qd] (KKT)."""
    n = w.n_coordinates

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        q, qd = x[:n], x[n:]
        A = w.contact_jacobian(q, "right")
        K = np.block([[w.mass_matrix(q), -A.T], [A, np.zeros((2, 2))]])
        rhs_ = np.concatenate(
            (-w.bias_forces(q, qd, slope), -w.contact_jacobian_rate(q, qd, "right"))
        )
        return np.concatenate((qd, np.linalg.solve(K, rhs_)[:n]))

    return rhs


def _rolling_state(w: BuiltWalker, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    n = w.n_coordinates
    q = np.concatenate(([0.0, 0.0], rng.uniform(-0.4, 0.4, n - 2)))
    q[1] = float(w.foot_radii[0])
    qd = np.concatenate(([0.0, 0.0], rng.normal(size=n - 2)))
    qd[0] = -float(w.foot_radii[0]) * qd[2]
    return q, qd


@pytest.mark.parametrize("name", ["kneed", "torso"])
@pytest.mark.parametrize("mode", ["flight", "stance"])
def test_energy_is_conserved_by_derived_equations(name: str, mode: str) -> None:
    """T + V is a first integral of M qdd + h = 0 (free) and of rolling single support (KKT).

    A wrong sign or factor in any Coriolis/centrifugal/gravity term, an M inconsistent with h,
    or a wrong contact-Jacobian rate would make the energy drift.
    """
    overrides = {"kneed": {"R": 0.2, "It": 0.01, "Is": 0.002}, "torso": {"R": 0.3, "I": 0.05}}
    w = load_walker(name, **overrides[name])
    slope = 0.04
    rng = np.random.default_rng(7)
    q0, qd0 = _rolling_state(w, rng)
    if mode == "flight":
        qd0 = qd0 + rng.normal(size=qd0.shape) * 0.5
        rhs = _flight_rhs(w, slope)
    else:
        rhs = _stance_rhs(w, slope)
    n = w.n_coordinates
    sol = solve_ivp(
        rhs,
        (0.0, 0.6),
        np.concatenate((q0, qd0)),
        method="DOP853",
        rtol=1e-11,
        atol=1e-12,
        dense_output=False,
    )
    assert sol.success
    q, qd = sol.y[:n].T, sol.y[n:].T
    E = w.mechanical_energy(q, qd, slope)
    T = w.kinetic_energy(q, qd)
    V = w.potential_energy(q, slope)
    scale = float(np.ptp(T) + np.ptp(V))
    assert scale > 1e-2  # the motion actually exchanges energy
    assert float(np.ptp(E)) < 1e-7 * scale
    if mode == "stance":  # the rolling constraint holds along the motion
        Aqd = np.einsum("tij,tj->ti", w.contact_jacobian(q, "right"), qd)
        assert float(np.max(np.abs(Aqd))) < 1e-7


# -- leg swap -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["compass", "kneed", "torso"])
def test_swap_is_an_involution_and_preserves_energy(name: str) -> None:
    w = load_walker(name, R=0.15)
    rng = np.random.default_rng(11)
    q = rng.uniform(-0.5, 0.5, (8, w.n_coordinates))
    qd = rng.normal(size=(8, w.n_coordinates))
    q1, qd1 = w.swap_legs(q, qd)
    q2, qd2 = w.swap_legs(q1, qd1)
    np.testing.assert_allclose(q2, q, atol=1e-12)
    np.testing.assert_allclose(qd2, qd, atol=1e-12)
    np.testing.assert_allclose(w.kinetic_energy(q1, qd1), w.kinetic_energy(q, qd), rtol=1e-12)
    np.testing.assert_allclose(
        w.potential_energy(q1, 0.1), w.potential_energy(q, 0.1), rtol=1e-12, atol=1e-12
    )
    # the old swing foot is the new stance foot, and vice versa
    np.testing.assert_allclose(q1[:, :2], w.foot_centre(q, "left"), atol=1e-12)
    np.testing.assert_allclose(w.foot_centre(q1, "left"), q[:, :2], atol=1e-12)
    if name == "torso":  # the torso keeps its absolute angle
        a0, a1 = w.link_angles(q)["torso"], w.link_angles(q1)["torso"]
        np.testing.assert_allclose(a1, a0, atol=1e-12)


def test_asymmetric_mirror_is_rejected(tmp_path: Path) -> None:
    text = read_toml_text("compass").replace('com = "b"', 'com = "0.3"')
    p = tmp_path / "bad.toml"
    p.write_text(text)
    # the message names what does not mirror (QA sweep 12: it was always "link[0].mirror")
    with pytest.raises(ModelDescriptionError, match=r"^link\[0\]\.com: after the leg swap the "
                       "centre of mass of 'stance_leg' is not where 'swing_leg''s was"):
        load_walker(p)


# -- kneed specifics ---------------------------------------------------------------------------


def test_kneed_locks_and_actuation() -> None:
    w = load_walker("kneed")
    assert w.coordinate_names == ("x", "y", "stance_shank", "stance_knee", "hip", "swing_knee")
    assert w.lockable_joints == (3, 5)
    assert w.actuated_joints == (4,)
    A = w.lock_jacobian()
    np.testing.assert_array_equal(A, np.eye(6)[[3, 5]])
    np.testing.assert_array_equal(w.lock_jacobian((5,)), np.eye(6)[[5]])
    with pytest.raises(ValueError, match="not a lockable"):
        w.lock_jacobian((4,))
    # straight, vertical legs: the hip is at the height of a straight leg above the ground
    q = np.array([0.3, 0.1, 0.0, 0.0, 0.0, 0.0])
    pos = w.positions(q)
    p = w.parameters
    np.testing.assert_allclose(pos["hip"], [0.3, p["a1"] + p["b1"] + p["a2"] + p["b2"]])
    np.testing.assert_allclose(pos["swing_foot.contact"], [0.3, 0.0], atol=1e-15)
    np.testing.assert_allclose(w.total_mass, p["mH"] + 2 * p["mt"] + 2 * p["ms"])


def test_hip_torque_does_no_net_work_on_rigid_motion() -> None:
    """``B u`` is a pure internal torque: it does no work on a rigid-body motion of the walker.

    A rigid motion (all joint rates 0) has power ``qd . B u = 0``; a relative hip rotation has
    power ``u * hip_rate``.
    """
    w = load_walker("torso")
    B = w.actuation_matrix()
    rigid = np.array([0.3, -0.2, 0.7, 0.0, 0.0])
    assert np.allclose(rigid @ B, 0.0)
    np.testing.assert_array_equal(B, np.eye(5)[:, [3, 4]])


# -- malformed descriptions ---------------------------------------------------------------------


def read_toml_text(name: str) -> str:
    path = Path(builder_mod.__file__).parent.parent / "walkers" / f"{name}.toml"
    return path.read_text()


_BAD = [
    ('mass = "m"\ncom = "l - b"', 'mass = -1.0\ncom = "l - b"', r"^link\[0\]\.mass: must be > 0"),
    ('mass = "m"\ncom = "b"', 'mass = "m - 6"\ncom = "b"', r"^link\[1\]\.mass: must be > 0"),
    ('parent = "stance_leg"', 'parent = "pelvis"', r"^link\[1\]\.parent: unknown link 'pelvis'"),
    ('com = "l - b"', 'cmo = "l - b"', r"^link\[0\]\.cmo: unknown key"),
    (
        'name = "stance_leg"       # root',
        'nam = "stance_leg"       # root',
        r"^link\[0\]\.nam: unknown key",
    ),
    (
        'length = "l"\nmass = "m"\ncom = "b"',
        'mass = "m"\ncom = "b"',
        r"^link\[1\]\.length: missing required field",
    ),
    ('com = "b"', 'com = "b + q"', r"^link\[1\]\.com: unknown parameter 'q'"),
    ('com = "b"', "com = \"__import__('os')\"", r"^link\[1\]\.com: unsupported expression"),
    (
        'inertia = "I"\nmirror = "stance_leg"',
        'inertia = "-0.1"\nmirror = "stance_leg"',
        r"^link\[1\]\.inertia: must be >= 0",
    ),
    ('direction = "down"', 'direction = "sideways"', r"^link\[1\]\.direction"),
    (
        'joint = { name = "hip", actuated = true }',
        'joint = { name = "hip", actuated = "yes" }',
        r"^link\[1\]\.joint\.actuated",
    ),
    (
        'radius = "R"\ncentre = "l - R"',
        'radius = "-R - 0.1"\ncentre = "l - R"',
        r"^foot\[1\]\.radius: must be >= 0",
    ),
    ('mass = "mH"', "mass = 0.0", r"^point_mass\[0\]\.mass: must be > 0"),
    ("R = 0.0 ", "R = 'x' ", r"^params\.R: must be a finite number"),
]


@pytest.mark.parametrize(("old", "new", "pattern"), _BAD)
def test_malformed_description_names_the_field(
    tmp_path: Path, old: str, new: str, pattern: str
) -> None:
    text = read_toml_text("compass")
    assert old in text, old
    p = tmp_path / "bad.toml"
    p.write_text(text.replace(old, new, 1))
    with pytest.raises(ModelDescriptionError, match=pattern):
        read_description(p)


EXTRA_ROOT = '\n[[link]]\nname = "extra"\nlength = 1.0\nmass = 1.0\ncom = 0.5\n'


def test_structural_errors(tmp_path: Path) -> None:
    text = read_toml_text("compass")
    cases = {
        # third foot
        text + '\n[[foot]]\nlink = "swing_leg"\nradius = 0.0\n': r"^foot: exactly two",
        # cycle: the root gets a parent, so no root and a loop
        text.replace(
            'com = "l - b"', 'com = "l - b"\nparent = "swing_leg"'
        ): r"^link\[\d\]\.parent: cycle",
        # second root
        text.replace(
            'parent = "stance_leg"\ndirection = "down"', 'direction = "down"'
        ): r"^link\[1\]\.joint: the root link has no joint",
        text + EXTRA_ROOT: r"^link: exactly one root",
        # both feet on the swing leg
        text.replace(
            'link = "stance_leg"\nradius = "R"', 'link = "swing_leg"\nradius = "R"'
        ): r"^foot\[0\]",
        # mirror that does not mirror back
        text.replace('mirror = "stance_leg"', 'mirror = "swing_leg"'): r"^link\[\d\]\.mirror",
        # unknown top-level key
        "colour = 'red'\n" + text: r"^colour: unknown key",
    }
    for i, (body, pattern) in enumerate(cases.items()):
        p = tmp_path / f"bad{i}.toml"
        p.write_text(body)
        with pytest.raises(ModelDescriptionError, match=pattern):
            read_description(p)
    with pytest.raises(ModelDescriptionError, match=r"^params\.Rx: unknown parameter"):
        load_walker("compass", Rx=0.1)
    with pytest.raises(ModelDescriptionError, match=r"^foot\[0\]\.radius: must be >= 0"):
        load_walker("compass", R=-0.1)


# -- disk cache ---------------------------------------------------------------------------------


def test_second_build_hits_the_disk_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HEELSTRIKE_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(builder_mod, "_MEMORY", {})
    desc = read_description(Path(builder_mod.__file__).parent.parent / "walkers" / "torso.toml")
    first = build(desc)
    assert not first.from_cache
    assert first.path is not None and first.path.parent.parent == tmp_path
    assert first.path.read_text().startswith(first.source)  # then its length and checksum
    # a fresh process: empty memory cache, and any sympy derivation would fail
    monkeypatch.setattr(builder_mod, "_MEMORY", {})
    import heelstrike.models._codegen as codegen

    def boom(*_a: object, **_k: object) -> str:
        raise AssertionError("derivation must not run on a cache hit")

    monkeypatch.setattr(codegen, "generate_source", boom)
    second = build(desc)
    assert second.from_cache and second.key == first.key
    w1 = BuiltWalker(desc)  # from memory now
    q = np.linspace(-0.3, 0.4, 5)
    M_first = first.fn("mass_matrix")(q, w1._p)
    np.testing.assert_array_equal(second.fn("mass_matrix")(q, w1._p), M_first)
    # parameter values are not part of the key: other values reuse the same code
    assert BuiltWalker(desc, R=0.4, mT=2.0).model is second


def test_shipped_walkers_load() -> None:
    assert {"compass", "kneed", "torso"} <= set(shipped_walkers())
    for name in ("compass", "kneed", "torso"):
        w = load_walker(name)
        n = w.n_coordinates
        q = np.zeros(n)
        M = w.mass_matrix(q)
        assert M.shape == (n, n)
        np.linalg.cholesky(M)  # positive definite in flight
        assert w.description.name == name


@pytest.mark.parametrize(("change", "name"), [({"b1": 0.0}, "b1"), ({"b2": 0.0}, "b2")])
def test_kneed_refuses_a_massless_degree_of_freedom(change: dict[str, float], name: str,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """QA sweep 11: ``--param b1=0`` (a shank COM at the knee) or ``b2=0`` (a thigh COM at the
    hip), with the file's point-mass segments (It = Is = 0), passed the file's constraints and
    ended in "division by zero": the mass matrix is singular (a joint moves no mass). The
    file's constraints now refuse them, naming the parameter; with inertia they are fine."""
    from heelstrike.cli import main

    kneed = load_walker("kneed")
    with pytest.raises(ModelDescriptionError, match=rf"violated \(.*{name}=0"):
        kneed.replace(**change)
    # the singularity is real: M's smallest eigenvalue vanishes with the COM offset
    q = np.zeros(kneed.n_coordinates)  # straight legs, knees at their lock angle 0
    near = kneed.replace(**{name: 1e-4})
    lam = np.linalg.eigvalsh(near.mass_matrix(q))
    assert lam[0] < 1e-7 * lam[-1]
    # with inertia the same offset is a regular walker (positive definite M)
    held = kneed.replace(**change, Is=1e-3, It=1e-3)
    assert np.linalg.eigvalsh(held.mass_matrix(q))[0] > 1e-5
    assert main(["gait", "--model", "kneed", "--param", f"{name}=0"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and f"{name}=0" in err and "division" not in err


@pytest.mark.parametrize(("param", "said"), [
    ("mH=-1", "mH=-1 kg: point_mass[0].mass: must be > 0"),
    ("It=-1", "It=-1 kg m^2: link[1].inertia: must be >= 0"),
    ("a1=-0.1", "a1=-0.1 m: constraints[0]: '0 <= a1' is violated"),
])
def test_cli_param_errors_name_the_value_and_its_unit(param: str, said: str,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """QA sweep 11: a refused ``--param`` value was reported by the file's element alone
    (``point_mass[0].mass: must be > 0`` for ``--param mH=-1``)."""
    from heelstrike.cli import main

    assert main(["gait", "--model", "kneed", "--param", param]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert f"model 'kneed' with {said}" in err
