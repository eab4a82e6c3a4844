"""The one simulation entry point ``heelstrike.dynamics.simulate`` and its backend registry.

Checked here: every registered implementation gives, through ``simulate``, exactly the numbers
of a direct call; every shipped walker walks on every backend it declares (and the backends
agree); the registry's errors name the walker's backends; and "step length" has one definition
(``PlanarWalker.step_length``) that every backend reports, equal across backends and to the
paper's ``2 (l - R) sin q3 + 2 R q3`` on a symmetric gait.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

import heelstrike
from heelstrike.analysis.heel_strike import step_length as analytic_step_length
from heelstrike.dynamics import BACKENDS, hybrid, kernel_kind, simulate
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.backends import check_backend, simulator
from heelstrike.dynamics.compiled import ensemble_walk, simulate_compiled
from heelstrike.dynamics.compiled_phased import simulate_phased_compiled
from heelstrike.dynamics.phased import (
    PhasedWalkResult,
    TorsoPD,
    load_phased_walker,
    simulate_phased,
)
from heelstrike.models import CompassGait
from heelstrike.models.base import PlanarWalker
from heelstrike.models.builder import shipped_walkers

COMPASS_SLOPE = 0.05
COMPASS_GAIT = [-0.26682122, 1.08394013, -0.68587173]
KNEED_SLOPE = 0.0504
KNEED_GAIT = [-0.2647694, 1.2181144, -1.0955048]
TORSO_GAIT = [-0.1180757, 0.1118158, 0.5531974, -0.0140899, -0.6214368]
#: The compass gait with round feet on a 3 degree slope (a gait state of CompassGait(R=0.3)).
ROUND_SLOPE = float(np.deg2rad(3.0))
ROUND_GAIT = [-0.38628396, 1.41932714, -0.96794436]
#: McGeer's wheel (wheel.toml, its declared guard) walking on 1 deg
WHEEL_START = [-0.25, 0.8, 0.0]
WHEEL_SLOPE = float(np.deg2rad(1.0))


@dataclass(frozen=True, kw_only=True)
class _NoKernelCompass(CompassGait):
    """A hand-written walker without a compiled kernel (kernel kind "planar")."""

    @property
    def compiled_kernel(self) -> Any:
        return None


@dataclass(frozen=True, kw_only=True)
class _GeneratedWithoutDescription(CompassGait):
    """An inconsistent walker: claims the generated kernel but has no description."""

    @property
    def compiled_kernel(self) -> Any:
        return "generated"


@pytest.fixture(scope="module")
def described() -> dict[str, Any]:
    return {name: load_phased_walker(name) for name in shipped_walkers()}


def _setup(name: str, described: dict[str, Any]) -> tuple[PlanarWalker, dict[str, Any]]:
    """A walker and the arguments of a few steps of its gait (passive but for the torso)."""
    if name == "CompassGait":
        return CompassGait(), {"z": COMPASS_GAIT, "slope": COMPASS_SLOPE}
    w = described[name]
    if name == "compass":
        return w, {"z": COMPASS_GAIT, "slope": COMPASS_SLOPE}
    if name == "kneed":
        return w, {"z": KNEED_GAIT, "slope": KNEED_SLOPE}
    if name == "wheel":
        return w, {"z": WHEEL_START, "slope": WHEEL_SLOPE}
    return w, {"z": TORSO_GAIT, "slope": 0.0, "torque": TorsoPD(walker=w),
               "push_off": PushOff(impulse=2.0)}


def _walk(fn: Any, walker: PlanarWalker, args: dict[str, Any], steps: int = 2,
          **kw: Any) -> hybrid.WalkResult:
    a = dict(args)
    q, qd = walker.section_to_state(np.asarray(a.pop("z")))
    return fn(walker, q, qd, steps=steps, **a, **kw)


def _assert_same_walk(a: hybrid.WalkResult, b: hybrid.WalkResult) -> None:
    assert type(a) is type(b)
    assert a.status is b.status
    for name in ("t", "q", "q_dot", "stance_leg", "step", "actuator_work", "final_q",
                 "final_q_dot"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert len(a.impacts) == len(b.impacts)
    for name in ("time", "impact_angle", "kinetic_energy_constrained", "step_length",
                 "actuator_work", "trailing_normal_velocity"):
        np.testing.assert_array_equal(a.impact_array(name), b.impact_array(name), err_msg=name)


WALKERS = ("CompassGait", "compass", "kneed", "torso", "wheel")
DIRECT = {
    ("CompassGait", "scipy"): hybrid.simulate,
    ("CompassGait", "compiled"): simulate_compiled,
    ("compass", "scipy"): simulate_phased,
    ("compass", "compiled"): simulate_phased_compiled,
    ("kneed", "scipy"): simulate_phased,
    ("kneed", "compiled"): simulate_phased_compiled,
    ("torso", "scipy"): simulate_phased,
    ("torso", "compiled"): simulate_phased_compiled,
    ("wheel", "scipy"): simulate_phased,
    ("wheel", "compiled"): simulate_phased_compiled,
}


def test_cases_cover_every_shipped_walker_and_registry_entry(described: dict[str, Any]) -> None:
    # every shipped walker runs on both backends, wheel.toml's declared heel-strike guard
    # ([events]) too
    assert all(w.backends == ("scipy", "compiled") for w in described.values())
    assert set(WALKERS) == {"CompassGait", *shipped_walkers()}
    kinds = {(kernel_kind(_setup(n, described)[0]), b) for n, b in DIRECT}
    assert kinds == set(BACKENDS) - {("planar", "scipy")}  # planar: test_planar_walker_...


def test_package_simulate_is_the_entry_point() -> None:
    assert heelstrike.simulate is simulate


def test_default_backend_gives_hybrid_simulate_numbers() -> None:
    walker = CompassGait(foot_radius=0.2)
    q, qd = walker.section_to_state(COMPASS_GAIT)
    kw = {"slope": COMPASS_SLOPE, "steps": 2}
    _assert_same_walk(simulate(walker, q, qd, **kw), hybrid.simulate(walker, q, qd, **kw))
    # options reach the implementation (here: a coarser time step cap, a restitution)
    kw2 = {**kw, "max_step": 0.01, "restitution": 0.0}
    _assert_same_walk(simulate(walker, q, qd, **kw2), hybrid.simulate(walker, q, qd, **kw2))


@pytest.mark.slow
@pytest.mark.parametrize(("name", "backend"), sorted(DIRECT))
def test_entry_point_equals_direct_call(
    name: str, backend: str, described: dict[str, Any]
) -> None:
    walker, args = _setup(name, described)
    assert walker.supports(backend)
    got = _walk(simulate, walker, args, backend=backend)
    ref = _walk(DIRECT[name, backend], walker, args)
    _assert_same_walk(got, ref)


@pytest.mark.slow
@pytest.mark.parametrize("name", WALKERS)
def test_every_shipped_walker_walks_on_every_declared_backend(
    name: str, described: dict[str, Any]
) -> None:
    walker, args = _setup(name, described)
    assert walker.backends == ("scipy", "compiled")
    walks = {b: _walk(simulate, walker, args, steps=3, rtol=1e-11, atol=1e-11, backend=b)
             for b in walker.backends}
    ref = walks["scipy"]
    assert ref.ok, ref.message
    # one loop (hybrid.simulate) runs every walker's declared schedule on scipy, so every
    # walker's reference walk reports every impact, the compass's heel strikes included
    assert isinstance(ref, PhasedWalkResult)
    heel = [e for e in ref.events if e.kind == "heel_strike"]
    assert [e.time for e in heel] == [r.time for r in ref.impacts]
    for b, walk in walks.items():
        assert walk.status is ref.status, b
        assert walk.n_steps == 3, b
        for field in ("time", "impact_angle", "kinetic_energy_constrained", "step_length",
                      "actuator_work"):
            np.testing.assert_allclose(walk.impact_array(field), ref.impact_array(field),
                                       rtol=1e-8, atol=1e-8, err_msg=f"{b}: {field}")
        np.testing.assert_allclose(walk.final_q_dot, ref.final_q_dot, atol=1e-8, err_msg=b)


def test_unknown_backend_names_the_walkers_backends() -> None:
    walker = CompassGait()
    q, qd = walker.section_to_state(COMPASS_GAIT)
    with pytest.raises(ValueError, match=r"unknown backend 'numba'.*'scipy', 'compiled'"):
        simulate(walker, q, qd, backend="numba")


def test_planar_walker_runs_on_scipy_only() -> None:
    walker = _NoKernelCompass()
    assert kernel_kind(walker) == "planar"
    assert walker.backends == ("scipy",)
    q, qd = walker.section_to_state(COMPASS_GAIT)
    with pytest.raises(ValueError, match=r"unsupported backend 'compiled'.*runs on 'scipy' "):
        simulate(walker, q, qd, slope=COMPASS_SLOPE, backend="compiled")
    with pytest.raises(ValueError, match=r"\(walker\.backends\)"):
        simulator(walker, "compiled")
    kw = {"slope": COMPASS_SLOPE, "steps": 1}
    _assert_same_walk(simulate(walker, q, qd, **kw), hybrid.simulate(walker, q, qd, **kw))


def test_kernel_kind_comes_from_the_contract(described: dict[str, Any]) -> None:
    assert kernel_kind(CompassGait()) == "compass"
    assert {kernel_kind(w) for w in described.values()} == {"described"}
    with pytest.raises(ValueError, match="no description"):
        kernel_kind(_GeneratedWithoutDescription())


def test_compiled_backends_refuse_actuation_they_cannot_run(described: dict[str, Any]) -> None:
    compass = CompassGait()
    q, qd = compass.section_to_state(COMPASS_GAIT)

    def law(t: float, q: Any, qd: Any) -> Any:
        return np.zeros(1)

    for kw in ({"torque": law}, {"restitution": 0.2}):
        with pytest.raises(ValueError, match=r"backend='scipy'"):
            simulate(compass, q, qd, slope=COMPASS_SLOPE, backend="compiled", **kw)
        check_backend(compass, "scipy", **kw)  # the reference runs anything
    # a push-off and a friction limit run on the compass's generated kernel (compass.toml;
    # tests/test_compass_backends.py checks those walks against the reference)
    for kw in ({"push_off": PushOff(impulse=1.0)}, {"friction": 0.6}):
        check_backend(compass, "compiled", **kw)
        check_backend(compass, "scipy", **kw)
    kneed = described["kneed"]
    with pytest.raises(ValueError, match=r"backend='scipy'"):
        check_backend(kneed, "compiled", torque=law)
    check_backend(kneed, "compiled", push_off=PushOff(impulse=1.0), friction=0.6)


def test_simulator_is_simulate_bound_to_a_backend() -> None:
    walker = CompassGait()
    q, qd = walker.section_to_state(COMPASS_GAIT)
    sim = simulator(walker, "compiled")
    _assert_same_walk(sim(walker, q, qd, slope=COMPASS_SLOPE, steps=2),
                      simulate_compiled(walker, q, qd, slope=COMPASS_SLOPE, steps=2))
    with pytest.raises(ValueError, match=r"backend='scipy'"):
        simulator(walker, "compiled", restitution=0.5)


# -- step length: one definition ----------------------------------------------------------------
@pytest.mark.parametrize("radius", [0.0, 0.3, 1.0])
def test_step_length_definition_is_the_paper_formula_on_a_symmetric_step(radius: float) -> None:
    compass = CompassGait(foot_radius=radius)
    built = load_phased_walker("compass", R=radius)
    q3 = np.array([0.05, 0.2, 0.31])
    # start: the legs at -q3 and hip 2 q3; impact: rolled by R 2 q3, symmetric legs (q4 = -2 q3)
    q_start = np.stack((np.zeros(3), np.full(3, radius), -q3, 2 * q3), axis=-1)
    q_imp = np.stack((-2 * radius * q3, np.full(3, radius), q3, -2 * q3), axis=-1)
    expected = analytic_step_length(compass, q3)
    np.testing.assert_allclose(compass.step_length(q_start, q_imp), expected, rtol=0, atol=1e-14)
    np.testing.assert_allclose(built.step_length(q_start, q_imp), expected, rtol=0, atol=1e-14)
    # the definition measures along the ground: shifting the walker does not change it
    shift = np.array([1.7, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(compass.step_length(q_start + shift, q_imp + shift), expected,
                               atol=1e-14)


@pytest.mark.slow
@pytest.mark.parametrize("which", ["compass", "kneed"])
def test_every_backend_reports_the_same_step_length(which: str, described: dict[str, Any]) -> None:
    if which == "compass":
        walkers: list[PlanarWalker] = [CompassGait(foot_radius=0.3),
                                       load_phased_walker("compass", R=0.3)]
        z, slope = ROUND_GAIT, ROUND_SLOPE
    else:
        walkers, z, slope = [described["kneed"]], KNEED_GAIT, KNEED_SLOPE
    lengths = {}
    for w in walkers:
        q0, qd0 = w.section_to_state(z)
        for b in w.backends:
            walk = simulate(w, q0, qd0, slope=slope, steps=2, backend=b, rtol=1e-12, atol=1e-12)
            assert walk.n_steps == 2, (type(w).__name__, b, walk.message)
            # each backend reports the one definition on its own impact states
            first = walk.impacts[0]
            assert first.step_length == float(w.step_length(q0, first.q))
            lengths[type(w).__name__, b] = walk.impact_array("step_length")
    assert len(lengths) == 2 * len(walkers)
    ref = lengths[type(walkers[0]).__name__, "scipy"]
    assert np.all(ref > 0.3)
    for key, got in lengths.items():
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10, err_msg=str(key))
    if which == "compass":
        # the compass kernel's own record (ensemble_walk) is the same definition, compiled
        ens = ensemble_walk(walkers[0], z, slope, steps=2, rtol=1e-12, atol=1e-12)
        assert ens.step_length is not None
        np.testing.assert_allclose(ens.step_length[0], lengths["CompassGait", "compiled"],
                                   rtol=0, atol=1e-14)


@pytest.mark.slow
def test_step_length_equals_the_analytic_formula_at_impact_on_the_gait() -> None:
    from heelstrike.analysis.limit_cycle import find_limit_cycle

    walker = CompassGait(foot_radius=0.3)
    cycle = find_limit_cycle(walker, slope=ROUND_SLOPE, method="compiled", rtol=1e-12,
                             atol=1e-12)
    assert cycle.residual < 1e-11
    for w in (walker, load_phased_walker("compass", R=0.3)):
        q0, qd0 = w.section_to_state(cycle.fixed_point)
        for b in w.backends:
            walk = simulate(w, q0, qd0, slope=ROUND_SLOPE, steps=1, backend=b, rtol=1e-12,
                            atol=1e-12)
            rec = walk.impacts[0]
            np.testing.assert_allclose(
                rec.step_length, analytic_step_length(walker, rec.impact_angle), rtol=0,
                atol=1e-10, err_msg=f"{type(w).__name__} {b}",
            )


START_ERRORS = {
    "foot": "stance foot on the ground (y = R) and rolling without slip",
    "knee": "stance_knee locked at",
    "steps": "steps must be >= 1",
    "finite": "initial state must be finite",
}


def _bad_starts(walker: PlanarWalker, z: list[float]) -> dict[str, tuple[Any, Any, int]]:
    q, qd = walker.section_to_state(np.asarray(z))
    lifted = q.copy()
    lifted[1] += 1e-3  # stance foot 1 mm above the ground
    nan_rate = qd.copy()
    nan_rate[-1] = np.nan
    starts = {"foot": (lifted, qd, 1), "steps": (q, qd, 0), "finite": (q, nan_rate, 1)}
    if "stance_knee" in walker.coordinate_names:
        bent = q.copy()
        bent[walker.coordinate_names.index("stance_knee")] = 0.2  # the stance knee unlocked
        starts["knee"] = (bent, qd, 1)
    return starts


@pytest.mark.parametrize(("name", "backend"), sorted(k for k in DIRECT if k[0] != "torso"))
def test_every_backend_refuses_the_same_invalid_starts(
    name: str, backend: str, described: dict[str, Any]
) -> None:
    """One start check (``check_initial_state``) serves every backend, with one message."""
    walker, args = _setup(name, described)
    for what, (q, qd, steps) in _bad_starts(walker, args["z"]).items():
        with pytest.raises(ValueError, match=re.escape(START_ERRORS[what])):
            simulate(walker, q, qd, slope=args["slope"], steps=steps, backend=backend)


def test_compiled_ensemble_names_the_invalid_start(described: dict[str, Any]) -> None:
    from heelstrike.dynamics.compiled_phased import ensemble_walk_phased

    kneed = described["kneed"]
    good = kneed.section_to_state(np.asarray(KNEED_GAIT))
    for what in ("foot", "knee"):
        bad = _bad_starts(kneed, KNEED_GAIT)[what]
        states = (np.stack([good[0], bad[0]]), np.stack([good[1], bad[1]]))
        with pytest.raises(ValueError, match=r"^state 1: .*" + re.escape(START_ERRORS[what])):
            ensemble_walk_phased(kneed, states=states, slope=KNEED_SLOPE, steps=1)
