"""The inert robot impact on the kinematic tree (:mod:`heelstrike.robots._inert_kernel`).

Oracles: Pinocchio's own ``parents_fromRow``/``nvSubtree_fromRow`` and tree-sparse
``cholesky.decompose`` (``U``, ``D``), ``pinocchio.impulseDynamics`` (``v+`` and impulses),
heelstrike's dense LAPACK path :func:`heelstrike.core.contact_laws.inert_contact_impact`, and on
synthetic trees the closed form by dense solves (nested energies as ``1/2 b_g^T W_g^-1 b_g`` of
the leading row groups, no Cholesky factor of ``W``).
"""

from __future__ import annotations

import os

import numpy as np
import pytest

try:
    import pinocchio as pin
except ImportError:
    if os.environ.get("CI"):  # CI installs heelstrike[robots]: these tests must run there
        raise
    pytest.skip("needs heelstrike[robots] (pin, example-robot-data)", allow_module_level=True)

from heelstrike.core.contact_laws import InertLayout, inert_contact_impact
from heelstrike.core.impact import ImpactInputError
from heelstrike.robots import (
    ContactSpec,
    RobotError,
    inert_energy_split,
    inert_energy_split_batch,
    load_robot,
    robot_impact,
    robot_matrices,
)
from heelstrike.robots import _inert_kernel as kernel
from heelstrike.robots.contacts import _inert_path

pytestmark = pytest.mark.robots

ROBOTS = ("talos", "g1", "bolt")


@pytest.fixture(scope="module")
def robots() -> dict[str, object]:
    return {name: load_robot(name) for name in ROBOTS}


def _state(robot, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = np.array(pin.integrate(robot.model, robot.reference_q,
                               0.2 * rng.standard_normal(robot.nv)))
    lo, hi = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    q[7:] = np.clip(q[7:], lo[7:], hi[7:])
    return q, rng.standard_normal(robot.nv)


def _contacts(robot, mixed: bool) -> tuple[ContactSpec, ...]:
    left, right = robot.feet
    if not mixed:
        return tuple(ContactSpec(frame=f, kind=robot.foot_contact) for f in robot.feet)
    other = next(str(f.name) for f in robot.model.frames if f.parentJoint == 1)
    return (ContactSpec(frame=left, kind=robot.foot_contact),
            ContactSpec(frame=right, kind="arc", radius=0.05),
            ContactSpec(frame=other, kind="point"))


def _dense(robot, q, v, specs):
    """heelstrike's dense LAPACK path on ``robot_matrices``."""
    M, A = robot_matrices(robot, q, specs)
    layout = InertLayout(normal=tuple(c.normal for c in specs),
                         tangential=tuple(c.tangential for c in specs))
    return inert_contact_impact(M, robot.check_state(q, v)[1], A, layout), A


def _close(fast, ref, tol: float = 1e-12) -> None:
    scale_v = max(1.0, float(np.abs(ref.velocity_post).max()))
    np.testing.assert_allclose(fast.velocity_post, ref.velocity_post, rtol=0, atol=tol * scale_v)
    np.testing.assert_allclose(fast.impulse, ref.impulse, rtol=0,
                               atol=tol * float(np.abs(ref.impulse).max()))
    for key in ("T", "T_c", "T_a", "T_post", "energy_lost"):
        assert abs(float(getattr(fast, key)) - float(getattr(ref, key))) <= tol * float(ref.T), key
    for key in ("T_c_normal", "T_c_tangential"):
        np.testing.assert_allclose(getattr(fast, key), getattr(ref, key), rtol=0,
                                   atol=tol * float(ref.T))


# -- the tree ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
def test_tree_arrays_are_pinocchios(robots, name) -> None:
    robot = robots[name]
    model = robot.model
    parents, nvsub = kernel.tree_arrays(
        [int(p) for p in model.parents], [int(j.idx_v) for j in model.joints],
        [int(j.nv) for j in model.joints], robot.nv)
    data = model.createData()
    np.testing.assert_array_equal(parents, np.array(data.parents_fromRow))
    np.testing.assert_array_equal(nvsub, np.array(data.nvSubtree_fromRow))


@pytest.mark.parametrize("name", ROBOTS)
def test_the_kernel_factorisation_is_pinocchios_cholesky(robots, name) -> None:
    """After a solve the work array holds ``U`` (ancestor entries) and ``1/D``: equal to
    Pinocchio's ``cholesky.decompose`` and ``U D U^T = M``."""
    robot = robots[name]
    q, v = _state(robot, 7)
    specs = _contacts(robot, mixed=False)
    path = _inert_path(robot, specs)
    inert_energy_split(robot, q, v, specs)
    n, k = path.n, path.k
    parents = path.tree[3:3 + n]
    U = np.eye(n)
    for j in range(n):
        i = parents[j]
        while i >= 0:
            U[i, j] = path.work[i * n + j]
            i = parents[i]
    D = 1.0 / path.work[n * n + k * n + 2 * k * k:][:n]
    data = robot.model.createData()
    M = robot.mass_matrix(q, data)
    pin.crba(robot.model, data, robot.check_state(q)[0])
    pin.cholesky.decompose(robot.model, data)
    np.testing.assert_allclose(D, np.array(data.D), rtol=1e-12)
    np.testing.assert_allclose(U, np.triu(np.array(data.U)), rtol=0, atol=1e-12)
    np.testing.assert_allclose(U @ np.diag(D) @ U.T, M, rtol=0, atol=1e-12 * np.abs(M).max())


# -- the robots' impacts -----------------------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("mixed", [False, True])
@pytest.mark.parametrize("seed", range(3))
def test_tree_path_equals_the_dense_path(robots, name, mixed, seed) -> None:
    robot = robots[name]
    q, v = _state(robot, 40 + seed)
    specs = _contacts(robot, mixed)
    ref, _ = _dense(robot, q, v, specs)
    for check in (True, False):
        q_, v_ = robot.check_state(q, v)
        _close(inert_energy_split(robot, q_, v_, specs, check=check), ref)
    res = robot_impact(robot, q, v, keep=specs)
    _close(res.result, ref)
    for key in ("contact_velocity_pre", "contact_velocity_post"):
        for u, u_ref in zip(getattr(res.result, key), getattr(ref, key), strict=True):
            np.testing.assert_allclose(u, u_ref, rtol=0, atol=1e-12 * max(1.0, np.abs(v).max()))
    np.testing.assert_allclose(res.result.generalized_impulse, ref.generalized_impulse, rtol=0,
                               atol=1e-12 * np.abs(ref.generalized_impulse).max())
    # the inert law: T_c is the loss, the split adds up
    assert abs(res.result.T_c - res.result.energy_lost) <= 1e-12 * res.result.T
    assert abs(res.result.T_c + res.result.T_a - res.result.T) <= 1e-12 * res.result.T


@pytest.mark.parametrize("name", ["talos", "g1"])
def test_tree_path_equals_pinocchio_impulse_dynamics(robots, name) -> None:
    robot = robots[name]
    specs = _contacts(robot, mixed=False)
    data = robot.model.createData()
    for seed in range(5):
        q, v = _state(robot, 60 + seed)
        q_, v_ = robot.check_state(q, v)
        _, A = _dense(robot, q, v, specs)
        v_pin = np.array(pin.impulseDynamics(robot.model, data, q_, v_, A, 0.0, 0.0))
        lam_pin = np.array(data.impulse_c)
        res = inert_energy_split(robot, q, v, specs)
        np.testing.assert_allclose(res.velocity_post, v_pin, rtol=0,
                                   atol=1e-12 * max(1.0, np.abs(v_pin).max()))
        np.testing.assert_allclose(res.impulse, lam_pin, rtol=0,
                                   atol=1e-12 * np.abs(lam_pin).max())
        # post-impact contact velocities vanish (bilateral rows, e = 0)
        assert np.abs(A @ res.velocity_post).max() <= 1e-12 * max(1.0, np.abs(v).max())


def test_batch_equals_single_calls(robots) -> None:
    talos = robots["talos"]
    specs = _contacts(talos, mixed=True)
    states = [_state(talos, 80 + i) for i in range(5)]
    qs = np.stack([s[0] for s in states])
    vs = np.stack([s[1] for s in states])
    batch = inert_energy_split_batch(talos, qs, vs, specs, chunk=2)  # chunks 2, 2, 1
    for i, (q, v) in enumerate(states):
        one = inert_energy_split(talos, q, v, specs)
        for key in ("velocity_post", "impulse", "T", "T_c", "T_a", "T_post", "energy_lost",
                    "T_c_normal", "T_c_tangential"):
            np.testing.assert_allclose(getattr(batch, key)[i], getattr(one, key), rtol=1e-13,
                                       atol=1e-13, err_msg=key)


def test_redundant_rows_are_refused_by_every_inert_path(robots) -> None:
    talos = robots["talos"]
    q, v = _state(talos, 5)
    twice = (ContactSpec(frame=talos.feet[0], kind="flat"),
             ContactSpec(frame=talos.feet[0], kind="point"))
    with pytest.raises(ImpactInputError, match="rank deficient"):
        inert_energy_split(talos, q, v, twice)
    qs = np.stack([q, q, q])
    vs = np.stack([v, v, v])
    with pytest.raises(ImpactInputError, match=r"rank deficient.*configuration 0"):
        inert_energy_split_batch(talos, qs, vs, twice)
    with pytest.raises(RobotError, match="nv=38"):
        inert_energy_split(talos, q, v[:-1], _contacts(talos, False), check=False)
    with pytest.raises(RobotError, match="at least one contact"):
        inert_energy_split(talos, q, v, ())
    with pytest.raises(RobotError, match="ContactSpec"):
        inert_energy_split(talos, q, v, ["left_sole_link:flat"])  # type: ignore[list-item]


# -- synthetic trees: the algebra against dense solves -----------------------------------------
def _synthetic(seed: int):
    """A branching tree of 9 dofs (a 3-dof root, two branches, a sub-branch), ``M = U D U^T``
    with the tree's sparsity, rows on the dofs' chains, and the dense closed form."""
    rng = np.random.default_rng(seed)
    parents_joint = [-1, 0, 1, 2, 2, 4, 1]  # joint 0: universe
    nv_joint = [0, 3, 1, 2, 1, 1, 1]
    idx_v = [0, 0, 3, 4, 6, 7, 8]
    n = 9
    parents, nvsub = kernel.tree_arrays(parents_joint, idx_v, nv_joint, n)
    U = np.eye(n)
    for j in range(n):
        i = parents[j]
        while i >= 0:
            U[i, j] = rng.uniform(-1, 1)
            i = parents[i]
    D = rng.uniform(0.5, 2.0, n)
    M = U @ np.diag(D) @ U.T
    joints = [3, 5, 6]  # contacts on these joints' bodies: 2, 1, 2 rows
    rows = [2, 1, 2]
    chains, A = [], np.zeros((5, n))
    r = 0
    for jt, k in zip(joints, rows, strict=True):
        ch = kernel.chain(parents_joint, idx_v, nv_joint, jt)
        for _ in range(k):
            A[r, ch] = rng.uniform(-1, 1, len(ch))
            chains.append(ch)
            r += 1
    layout = InertLayout(normal=((0,), (0,), (1,)), tangential=((1,), (), (0,)))
    return M, A, rng.standard_normal(n), parents, nvsub, chains, layout


def _run(M, A, v, parents, nvsub, chains, layout, check=True):
    n, k = v.shape[0], A.shape[0]
    groups = len(layout.bounds) - 1
    tree = kernel.tree_layout(parents, nvsub, layout.order, layout.bounds, chains)
    out = np.empty(kernel.out_size(n, k, groups))
    status = kernel.inert_item(M, A, v, tree, np.zeros(kernel.work_size(n, k)), out, check)
    return status, out


@pytest.mark.parametrize("seed", range(5))
def test_synthetic_tree_matches_dense_closed_form(seed) -> None:
    M, A, v, parents, nvsub, chains, layout = _synthetic(seed)
    status, out = _run(M, A, v, parents, nvsub, chains, layout)
    assert status == 0
    n, k = 9, 5
    groups = len(layout.bounds) - 1
    Minv_At = np.linalg.solve(M, A.T)
    W = A @ Minv_At
    b = A @ v
    lam = -np.linalg.solve(W, b)
    v_plus = v + Minv_At @ lam
    np.testing.assert_allclose(out[:n], v_plus, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[n:n + k], lam, rtol=0, atol=1e-12 * np.abs(lam).max())
    # nested shares: energies of the leading groups (in the nesting order), differenced
    Ap = A[layout.order]
    Wp, bp = Ap @ np.linalg.solve(M, Ap.T), Ap @ v
    cumulative = [0.0] + [0.5 * bp[:e] @ np.linalg.solve(Wp[:e, :e], bp[:e]) if e else 0.0
                          for e in layout.bounds[1:]]
    shares = np.diff(cumulative)
    T = 0.5 * v @ M @ v
    np.testing.assert_allclose(out[n + k:n + k + groups], shares, rtol=0, atol=1e-12 * T)
    o = n + k + groups
    T_post = 0.5 * v_plus @ M @ v_plus
    np.testing.assert_allclose(out[o:o + 4], [T, T_post, shares.sum(), T - T_post], rtol=0,
                               atol=1e-12 * T)
    np.testing.assert_allclose(out[o + 4:o + 4 + k], A @ v, atol=1e-12)
    np.testing.assert_allclose(out[o + 4 + k:o + 4 + 2 * k], 0.0, atol=1e-12)
    np.testing.assert_allclose(out[o + 4 + 2 * k:], A.T @ lam, atol=1e-12 * np.abs(lam).max())


def test_synthetic_tree_statuses() -> None:
    M, A, v, parents, nvsub, chains, layout = _synthetic(0)
    bad_M = M.copy()
    bad_M[8, 8] = -1.0  # a leaf with negative inertia: M indefinite
    assert _run(bad_M, A, v, parents, nvsub, chains, layout)[0] == 1
    zero = A.copy()
    zero[2] = 0.0  # a contact row that moves nothing: W singular
    assert _run(M, zero, v, parents, nvsub, chains, layout, check=False)[0] == 2
    near = A.copy()
    near[1] = near[0] + 1e-6 * np.eye(9)[0]  # nearly dependent rows: no certificate ...
    status, out = _run(M, near, v, parents, nvsub, chains, layout)
    assert status == 3
    assert np.all(np.isfinite(out))  # ... but solved; the caller runs the reference test
    assert _run(M, near, v, parents, nvsub, chains, layout, check=False)[0] == 0


def test_ahead_of_time_kernel_equals_the_jit_bit_for_bit(robots) -> None:
    """The API calls the kernel's ahead-of-time module (no numba in a new process); it is the
    same numba code as the JIT's, so the outputs are identical, statuses included."""
    from heelstrike.dynamics._aot import aot_enabled, load_library
    from heelstrike.robots.contacts import _inert_library

    if not aot_enabled():
        pytest.skip("HEELSTRIKE_AOT=0: the JIT is the kernel")
    aot = load_library(_inert_library())
    assert aot is not None, "the ahead-of-time module could not be built or loaded"
    talos = robots["talos"]
    specs = _contacts(talos, mixed=True)
    path = _inert_path(talos, specs)
    for seed in range(3):
        q, v = _state(talos, 90 + seed)
        q_, v_ = talos.check_state(q, v)
        M = path.assemble(q_, path.A)
        outs = []
        for fn in (aot.inert_item, kernel.inert_item):
            out = np.empty_like(path.out)
            status = fn(M, path.A, v_, path.tree, np.zeros_like(path.work), out, True, 5)
            outs.append((status, out))
        assert outs[0][0] == outs[1][0] == 0
        np.testing.assert_array_equal(outs[0][1], outs[1][1])
    B = 3
    Ms = np.stack([M] * B)
    As = np.stack([path.A] * B)
    vs = np.stack([v_] * B)
    results = []
    for fn in (aot.inert_batch, kernel.inert_batch):
        out = np.empty((B, path.out.shape[0]))
        status = np.full(B, -1, dtype=np.int64)
        fn(Ms, As, vs, path.tree, np.zeros_like(path.work), out, status, True)
        results.append((status, out))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])


def test_robot_impact_command_with_the_built_module_imports_no_numba(robots, tmp_path) -> None:
    """With the kernel's module built, ``impact --robot`` with kept soles runs the tree path
    in a new process without importing numba (its cold time stays Pinocchio's and Python's)."""
    import json
    import subprocess
    import sys

    from heelstrike.dynamics._aot import ENV, aot_enabled, load_library
    from heelstrike.robots.contacts import _inert_library

    if not aot_enabled():
        pytest.skip("HEELSTRIKE_AOT=0: the JIT is the kernel")
    assert load_library(_inert_library()) is not None
    talos = robots["talos"]
    q, v = _state(talos, 3)
    state = tmp_path / "state.json"
    state.write_text(json.dumps({"q": q.tolist(), "v": v.tolist()}))
    argv = ["impact", "--robot", "talos", "--state", str(state), "--keep",
            f"{talos.feet[0]}:flat", "--keep", f"{talos.feet[1]}:flat", "--json"]
    code = (
        "import sys, io, json, contextlib\n"
        "from heelstrike.cli import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out):\n"
        f"    rc = main({argv!r})\n"
        "print(json.dumps([rc, 'numba' in sys.modules, out.getvalue()]))\n"
    )
    env = {k: val for k, val in os.environ.items() if k != ENV}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          check=False, timeout=600)
    assert done.returncode == 0, done.stderr
    rc, numba_loaded, printed = json.loads(done.stdout.strip().splitlines()[-1])
    assert (rc, numba_loaded) == (0, False)
    report = json.loads(printed)
    ref = inert_energy_split(talos, q, v, _contacts(talos, mixed=False))
    assert abs(report["T_c"] - float(ref.T_c)) <= 1e-12 * float(ref.T)
    np.testing.assert_allclose(report["qdot_plus"], ref.velocity_post, rtol=0,
                               atol=1e-12 * max(1.0, np.abs(ref.velocity_post).max()))
