"""The ahead-of-time tier: the kernels' own numba source, compiled once, identical results.

:mod:`heelstrike.dynamics._aot` compiles the serial entry points of the compiled kernels with
numba's ``pycc`` into an extension module that later processes load without numba. The module
must give the JIT kernels' results bit for bit, refuse arguments its machine code would misread,
be rebuilt when its source changes, never be loaded from an unsafe cache, and fall back to the
JIT (with a warning) when it cannot be built.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from heelstrike.dynamics import _aot, _compass_kernels, compiled
from heelstrike.dynamics._aot import AotExport, AotLibrary, AotWarning, load_library
from heelstrike.dynamics.compiled import ensemble_walk, walker_parameters
from heelstrike.models.compass import CompassGait

#: The R = 0.3 m gait on a 0.05 rad slope (post-impact section state, rad and rad/s).
Z_GAIT = np.array([-0.37984746, 1.40667572, -0.92691387])


@pytest.fixture(scope="module")
def compass_aot() -> Any:
    lib = load_library(compiled._LIBRARY)
    if lib is None:
        pytest.fail("the compass kernels' ahead-of-time module could not be built or loaded")
    return lib


def _ensemble_args(n: int, steps: int, seed: int) -> tuple[Any, ...]:
    rng = np.random.default_rng(seed)
    z = Z_GAIT + rng.normal(0.0, 0.05, (n, 3))
    radii = rng.uniform(0.0, 0.45, n)
    slopes = rng.uniform(0.0, 0.08, n)
    P = np.ascontiguousarray(walker_parameters(CompassGait(foot_radius=radii), slopes))
    Y = np.ascontiguousarray(np.stack((z[:, 0], -2.0 * z[:, 0], z[:, 1], z[:, 2]), axis=-1))
    recs = tuple(np.full((n, steps), np.nan) for _ in range(4))
    return (P, Y, np.arange(n, dtype=np.int64), steps, 1e-10, 1e-10, 5.0, np.zeros(3), 0.0,
            np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n), *recs, True)


def _copy(args: tuple[Any, ...]) -> tuple[Any, ...]:
    return tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args)


def test_aot_ensemble_equals_the_jit_kernel_bit_for_bit(compass_aot: Any) -> None:
    args = _ensemble_args(150, 6, seed=11)
    a, b = _copy(args), _copy(args)
    compass_aot.ensemble(*a)
    _compass_kernels.SERIAL["ensemble"](*b)
    status = a[9]
    assert len(set(status.tolist())) >= 3  # walks, falls and other endings all exercised
    assert np.any(a[10] == 6)  # some walkers take every step
    for x, y in zip(a, b, strict=True):
        if isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, y)


def test_aot_phase_impact_and_dynamics_equal_the_jit_kernels(compass_aot: Any) -> None:
    p = walker_parameters(CompassGait(foot_radius=0.3), 0.05)
    y0 = np.array([Z_GAIT[0], -2.0 * Z_GAIT[0], Z_GAIT[1], Z_GAIT[2]])
    jit = _compass_kernels.SERIAL
    for phase in (1, 2):
        ya, yb = y0.copy(), y0.copy()
        ra = compass_aot.integrate_phase(p, ya, 0.0, 5.0, phase, 0.0, 1e-10, 1e-10,
                                         np.empty((7, 4)))
        rb = jit["integrate_phase"](p, yb, 0.0, 5.0, phase, 0.0, 1e-10, 1e-10, np.empty((7, 4)))
        assert ra == rb
        np.testing.assert_array_equal(ya, yb)
        if phase == 2:
            assert ra[0] == compiled._EV_STRIKE
            qa, qb = np.empty(4), np.empty(4)
            assert compass_aot.impact(p, ya, qa) == jit["impact"](p, yb, qb)
            np.testing.assert_array_equal(qa, qb)
    assert compass_aot.dynamics(p, y0) == jit["dynamics"](p, y0)
    for ev in range(-2, 6):
        assert compass_aot.phase_status(ev) == jit["phase_status"](ev)
    oa, ob = np.empty((500, 4)), np.empty((500, 4))
    na = compass_aot.integrate_plain(p, y0.copy(), 0.3, 1e-10, 1e-10, oa)
    nb = jit["integrate_plain"](p, y0.copy(), 0.3, 1e-10, 1e-10, ob)
    assert na == nb > 0
    np.testing.assert_array_equal(oa[:na], ob[:nb])


def test_aot_and_jit_ensembles_conserve_energy_between_impacts_alike(compass_aot: Any) -> None:
    # physics through the compiled module: single support conserves T + V to the tolerance
    w = CompassGait(foot_radius=0.3)
    y0 = np.array([Z_GAIT[0], -2.0 * Z_GAIT[0], Z_GAIT[1], Z_GAIT[2]])
    p = walker_parameters(w, 0.05)
    out = np.empty((2000, 4))
    n = compass_aot.integrate_plain(p, y0.copy(), 0.25, 1e-10, 1e-10, out)

    def energy(y: Any) -> float:
        R = 0.3
        q = np.array([-R * y[0], R, y[0], y[1]])
        qd = np.array([-R * y[2], 0.0, y[2], y[3]])
        return float(0.5 * qd @ w.mass_matrix(q) @ qd + w.potential_energy(q, 0.05))

    e = [energy(y) for y in (y0, *out[:n])]
    assert max(abs(x - e[0]) for x in e) < 1e-7 * abs(e[0])


def test_aot_calls_refuse_arrays_the_machine_code_would_misread(compass_aot: Any) -> None:
    args = list(_ensemble_args(4, 2, seed=1))
    args[0] = np.asfortranarray(args[0])  # F order: rows would be read as columns
    with pytest.raises(TypeError, match="C-ordered 2-d float64"):
        compass_aot.ensemble(*args)
    args = list(_ensemble_args(4, 2, seed=1))
    args[2] = args[2].astype(np.int32)
    with pytest.raises(TypeError, match="argument 2"):
        compass_aot.ensemble(*args)
    with pytest.raises(TypeError, match="takes 3 arguments"):
        compass_aot.impact(np.zeros(8), np.zeros(4))


def test_ensemble_walk_runs_the_aot_module_or_the_jit_alike(
    compass_aot: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    w = CompassGait(foot_radius=0.2)
    rng = np.random.default_rng(5)
    z = Z_GAIT + rng.normal(0.0, 0.02, (20, 3))
    a = ensemble_walk(w, z, 0.05, steps=4, parallel=False)
    monkeypatch.setenv(_aot.ENV, "0")
    assert load_library(compiled._LIBRARY) is None
    b = ensemble_walk(w, z, 0.05, steps=4, parallel=False)
    for field in ("z", "state", "status", "steps", "time", "impact_angle", "collision_loss"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_the_module_name_follows_sources_key_and_signatures() -> None:
    base = compiled._LIBRARY
    names = {
        _aot.module_name(base),
        _aot.module_name(AotLibrary(name=base.name, exports=base.exports,
                                    functions=base.functions, source_modules=base.source_modules,
                                    key="another walker")),
        _aot.module_name(AotLibrary(name=base.name, exports=base.exports[:-1],
                                    functions=base.functions,
                                    source_modules=base.source_modules)),
        _aot.module_name(AotLibrary(name=base.name, exports=base.exports,
                                    functions=base.functions,
                                    source_modules=base.source_modules[:-1])),
    }
    assert len(names) == 4
    assert all(n.startswith("_heelstrike_aot_compass_") for n in names)


def _command_in_new_process(argv: list[str], modules: tuple[str, ...]) -> tuple[Any, ...]:
    """Run ``heelstrike argv`` in a new interpreter: exit status, which of ``modules`` it
    imported, and whether it printed a result."""
    code = (
        "import sys, io, json, contextlib\n"
        "from heelstrike.cli import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out):\n"
        f"    rc = main({argv!r})\n"
        f"print(json.dumps([rc, {{m: m in sys.modules for m in {list(modules)!r}}}, "
        "len(out.getvalue()) > 100]))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != _aot.ENV}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=False, timeout=900)
    assert done.returncode == 0, done.stderr
    return tuple(json.loads(done.stdout.strip().splitlines()[-1]))


def _axpy(a: float, x: Any, y: Any) -> None:
    for i in range(x.shape[0]):
        y[i] += a * x[i]


def _typo(x: float) -> float:
    return x.no_such_attribute  # type: ignore[attr-defined]


AXPY = AotLibrary(
    name="axpy_test",
    exports=(AotExport(name="axpy", args=("f8", "f8[::1]", "f8[::1]"), returns="void"),),
    functions=lambda: {"axpy": _axpy},
    source_modules=("heelstrike.dynamics._aot",),
)


@pytest.fixture
def private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("HEELSTRIKE_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_aot, "_LOADED", _aot._LoadedLibraries())
    return tmp_path


def test_a_library_is_built_once_then_loaded(private_cache: Path) -> None:
    assert load_library(AXPY, build_missing=False) is None  # nothing built yet
    lib = load_library(AXPY)
    assert lib is not None
    path = Path(lib.path)
    assert path.parent == private_cache / "aot"
    assert oct(os.stat(path).st_mode & 0o777) == "0o700"
    assert oct(os.stat(path.parent).st_mode & 0o777) == "0o700"
    y = np.ones(5)
    lib.axpy(2.0, np.arange(5.0), y)
    np.testing.assert_array_equal(y, 1.0 + 2.0 * np.arange(5.0))
    assert load_library(AXPY) is lib
    stamp = os.stat(path).st_mtime_ns
    _aot._LOADED.by_name.clear()
    assert load_library(AXPY) is not None  # loaded from the cache, not rebuilt
    assert os.stat(path).st_mtime_ns == stamp
    assert not any(p.name.startswith(".build-") for p in path.parent.iterdir())


def test_an_unsafe_cached_module_is_not_loaded(private_cache: Path) -> None:
    lib = load_library(AXPY)
    assert lib is not None
    path = Path(lib.path)
    _aot._LOADED.by_name.clear()
    os.chmod(path, 0o722)  # writable by group and others: anyone could have replaced it
    with pytest.warns(AotWarning, match="writable by group or others"):
        assert load_library(AXPY) is None
    _aot._LOADED.by_name.clear()
    os.chmod(path, 0o700)
    os.chmod(path.parent, 0o777)
    with pytest.warns(AotWarning, match="writable by group or others"):
        assert load_library(AXPY) is None
    os.chmod(path.parent, 0o700)


def test_a_failed_build_warns_and_falls_back(private_cache: Path) -> None:
    bad = AotLibrary(
        name="typo_test",
        exports=(AotExport(name="typo", args=("f8",), returns="f8"),),
        functions=lambda: {"typo": _typo},
        source_modules=(),
    )
    with pytest.warns(AotWarning, match="could not build typo_test"):
        assert load_library(bad) is None
    assert not list((private_cache / "aot").glob("*typo_test*"))


def test_unsupported_argument_types_are_refused_when_declared() -> None:
    with pytest.raises(ValueError, match="unsupported ahead-of-time argument type"):
        _aot._array_rank("f8[:, :]")


@pytest.mark.slow
def test_gait_command_with_a_built_module_imports_no_numba() -> None:
    # the gait search runs on the serial kernels: with their module built, a new process
    # loads it and never imports numba (what makes `gait` cheap to start)
    load_library(compiled._LIBRARY)
    rc, loaded, printed = _command_in_new_process(
        ["gait", "--radius", "0.3", "--slope", "3deg", "--json"], ("numba",))
    assert (rc, loaded, printed) == (0, {"numba": False}, True)


# -- described walkers --------------------------------------------------------------------------
#: The kneed walker's gait on a 0.0504 rad slope (``gait --model kneed``; rad, rad/s).
Z_KNEED = np.array([-0.26476942921497637, 1.2181144245144957, -1.0955048313544355])


def _kneed_args(z: Any, steps: int) -> tuple[Any, ...]:
    from heelstrike.dynamics import compiled_phased as cp
    from heelstrike.dynamics.phased import PhasedWalker
    from heelstrike.models import load_walker

    w = PhasedWalker.from_built(load_walker("kneed"))
    q, qd = w.section_to_state(z)
    stance, swing, lockv = cp._locks(w)
    p, cfg = cp._configuration(w, 0.0504, None, None, None, 1e-6)
    return (p, cfg, np.ascontiguousarray(q), np.ascontiguousarray(qd), steps,
            np.asarray(stance, dtype=np.int64), np.asarray(swing, dtype=np.int64), lockv, 5.0,
            1e-10, 1e-10, np.inf)


@pytest.mark.slow
def test_kneed_aot_walk_and_ensemble_equal_the_jit_kernel_bit_for_bit() -> None:
    from heelstrike.dynamics import compiled_phased as cp
    from heelstrike.dynamics._phased_kernels import JitBound
    from heelstrike.models import load_walker

    walker = load_walker("kneed")
    aot = load_library(cp._library(walker))
    assert aot is not None
    jit = JitBound(cp.numba_model(walker))
    rng = np.random.default_rng(4)
    statuses = set()
    for z in Z_KNEED + rng.normal(0.0, 0.02, (6, 3)):
        args = _kneed_args(z, 3)
        a, b = aot.walk(*args), jit.walk(*args)
        status, ns, ni = a[0], a[2], a[4]
        statuses.add(int(status))
        assert (status, ns, ni) == (b[0], b[2], b[4])
        np.testing.assert_array_equal(a[1][:ns], b[1][:ns])  # samples
        np.testing.assert_array_equal(a[3][:ni], b[3][:ni])  # impact rows
        for x, y in zip(a[5:], b[5:], strict=True):  # step starts, final state
            np.testing.assert_array_equal(x, y)
    assert len(statuses) >= 2  # completed walks and a failure
    # the ensemble kernel, walker by walker with a stop on arrival
    base = _kneed_args(Z_KNEED, 4)
    Z = Z_KNEED + rng.normal(0.0, 0.01, (8, 3))
    states = [_kneed_args(z, 4)[2:4] for z in Z]
    Q = np.ascontiguousarray([s[0] for s in states])
    QD = np.ascontiguousarray([s[1] for s in states])
    outs = []
    for kern in (aot, jit):
        out = (np.zeros(8, np.int64), np.zeros(8, np.int64), np.zeros_like(Q), np.zeros_like(Q))
        kern.ensemble(*base[:2], Q, QD, *base[4:], np.array([2], np.int64),
                      np.array([2, 4], np.int64), Z_KNEED.copy(), 1e-4, 0, 8, *out)
        outs.append(out)
    for x, y in zip(*outs, strict=True):
        np.testing.assert_array_equal(x, y)


def test_the_aot_kernel_needs_no_lapack_for_the_rank_test() -> None:
    # numpy's matrix_rank would make the compiled module load scipy's LAPACK at run time; the
    # kernel's own test must give numpy's answer
    from heelstrike.dynamics._phased_kernels import independent_rows

    rng = np.random.default_rng(8)
    for trial in range(400):
        n = int(rng.integers(1, 9))
        k = int(rng.integers(0, n + 2))
        A = rng.normal(size=(k + 1, n)) * 10.0 ** rng.integers(-6, 7)
        if trial % 3 == 1 and k >= 2:
            A[k - 1] = 2.0 * A[0] - A[1]  # exactly dependent in exact arithmetic
        expected = k <= n and (k == 0 or np.linalg.matrix_rank(A[:k]) == k)
        assert independent_rows(np.ascontiguousarray(A), k) == expected


def test_own_walker_files_use_the_jit_unless_asked(
    private_cache: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from importlib.resources import files

    from heelstrike.dynamics import compiled_phased as cp
    from heelstrike.models import load_walker

    text = (files("heelstrike") / "walkers" / "kneed.toml").read_text()
    own = tmp_path / "my_kneed.toml"
    own.write_text(text)
    walker = load_walker(own)
    assert not cp._builds_ahead_of_time(walker)
    assert cp._builds_ahead_of_time(load_walker("kneed"))
    monkeypatch.setenv(_aot.ENV, "all")
    assert cp._builds_ahead_of_time(walker)
    monkeypatch.setenv(_aot.ENV, "1")
    # no module built for this structure yet in the private cache: the JIT kernel runs it
    from heelstrike.dynamics._phased_kernels import JitBound

    assert isinstance(cp._kernels(walker), JitBound)
    assert not (private_cache / "aot").exists() or not list((private_cache / "aot").iterdir())


@pytest.mark.slow
def test_kneed_gait_command_with_a_built_module_imports_no_numba() -> None:
    from heelstrike.dynamics import compiled_phased as cp
    from heelstrike.models import load_walker

    assert load_library(cp._library(load_walker("kneed"))) is not None
    rc, loaded, printed = _command_in_new_process(
        ["gait", "--model", "kneed", "--slope", "0.0504rad", "--json"], ("numba", "scipy.linalg"))
    assert (rc, loaded, printed) == (0, {"numba": False, "scipy.linalg": False}, True)
