"""The compiled impact paths equal the reference impact algebra (core.impact) to rounding."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from heelstrike.core.fast import FastImpactResult
from heelstrike.core.impact import ImpactInputError, ImpactResult, impact
from heelstrike.models.compass import CompassGait, heel_strike_state
from heelstrike.models.compass_fast import HeelStrikeImpact, heel_strike_impact

RTOL = 1e-12
# Both paths are backward stable; their difference grows like eps * cond(M) (observed: below
# 1.5e-15 cond(M) over 4e5 random walkers). Walkers with cond(M) <= 200, which includes the
# paper's family, are held to RTOL flat; worse-conditioned ones to RTOL * cond(M) / 200.
COND_REF = 200.0


def _reference(
    q3: np.ndarray,
    walker: CompassGait,
    w: tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray],
    e: float,
) -> tuple[ImpactResult, np.ndarray]:
    """Reference impact and the tolerance factor ``max(1, cond(M) / COND_REF)``."""
    w3, w4, w1, w2 = w
    q, qd = heel_strike_state(walker, q3, q3_dot=w3, q4_dot=w4)
    qd = qd.copy()
    if w1 is not None:
        qd[..., 0] = w1
    qd[..., 1] = w2
    M = walker.mass_matrix(q)
    ref = impact(M, walker.contact_jacobian(q, "left"), qd, restitution=e)
    return ref, np.maximum(1.0, np.linalg.cond(M) / COND_REF)


def _assert_close(
    fast: HeelStrikeImpact | FastImpactResult,
    ref: ImpactResult,
    q_dot_scale: np.ndarray,
    mass: np.ndarray,
    factor: np.ndarray | float = 1.0,
) -> None:
    """``|fast - ref| <= RTOL * factor * scale`` with scales ``T`` (energies), ``max |q_dot-|``
    (velocities) and ``mass * max |q_dot-|`` (impulses)."""
    tol = RTOL * np.asarray(factor)
    T = ref.kinetic_energy
    for name in ("kinetic_energy", "kinetic_energy_constrained", "kinetic_energy_admissible",
                 "energy_lost"):
        got, want = getattr(fast, name), getattr(ref, name)
        assert np.shape(got) == np.shape(want)  # one impact: the reference gives floats
        assert np.all(np.abs(got - want) <= tol * T + 1e-300), name
    assert fast.velocity_post.shape == ref.velocity_post.shape
    err_v = np.max(np.abs(fast.velocity_post - ref.velocity_post), axis=-1)
    assert np.all(err_v <= tol * q_dot_scale), "velocity_post"
    assert fast.constraint_impulse.shape == ref.constraint_impulse.shape
    err_l = np.max(np.abs(fast.constraint_impulse - ref.constraint_impulse), axis=-1)
    assert np.all(err_l <= tol * mass * q_dot_scale), "constraint_impulse"


walkers = st.fixed_dictionaries(
    {
        "hip_mass": st.floats(0.5, 30.0),
        "leg_mass": st.floats(0.5, 30.0),
        "leg_length": st.floats(0.3, 2.0),
        "b_frac": st.floats(0.05, 0.95),
        "r_frac": st.floats(0.0, 1.0),
        "leg_inertia": st.one_of(st.just(0.0), st.floats(0.0, 2.0)),
    }
)


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(
    p=walkers,
    q3=st.floats(-1.3, 1.3, allow_nan=False, allow_infinity=False),
    w3=st.floats(-5.0, 5.0),
    w4=st.floats(-5.0, 5.0),
    w1=st.one_of(st.none(), st.floats(-5.0, 5.0)),
    w2=st.floats(-2.0, 2.0),
    e=st.one_of(st.just(0.0), st.floats(0.0, 1.0)),
)
def test_heel_strike_fast_equals_reference(
    p: dict[str, float], q3: float, w3: float, w4: float, w1: float | None, w2: float, e: float
) -> None:
    l = p["leg_length"]
    walker = CompassGait(
        hip_mass=p["hip_mass"],
        leg_mass=p["leg_mass"],
        leg_length=l,
        leg_com_from_hip=p["b_frac"] * l,
        foot_radius=p["r_frac"] * l,
        leg_inertia=p["leg_inertia"],
    )
    ref, factor = _reference(
        np.asarray(q3),
        walker,
        (np.asarray(w3), np.asarray(w4), None if w1 is None else np.asarray(w1), np.asarray(w2)),
        e,
    )
    mass = np.asarray(walker.total_mass) * max(l, 1.0)
    scale = np.max(np.abs(ref.velocity_pre)) + 1e-300
    for parallel in (True, False):
        fast = heel_strike_impact(
            q3, walker=walker, q3_dot=w3, q4_dot=w4, q1_dot=w1, q2_dot=w2, restitution=e,
            parallel=parallel,
        )
        _assert_close(fast, ref, np.asarray(scale), mass, factor)


@pytest.mark.slow
@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), e=st.floats(0.0, 1.0))
def test_heel_strike_fast_batched_random(seed: int, e: float) -> None:
    """Batches with every input an array (no broadcast scalars) equal the reference."""
    rng = np.random.default_rng(seed)
    n = 257
    l = rng.uniform(0.3, 2.0, n)
    walker = CompassGait(
        hip_mass=rng.uniform(0.5, 30.0, n),
        leg_mass=rng.uniform(0.5, 30.0, n),
        leg_length=l,
        leg_com_from_hip=rng.uniform(0.05, 0.95, n) * l,
        foot_radius=rng.uniform(0.0, 1.0, n) * l,
        leg_inertia=rng.uniform(0.0, 1.0, n),
    )
    q3 = rng.uniform(-1.3, 1.3, n)
    w3, w4, w1, w2 = rng.normal(size=(4, n))
    ref, factor = _reference(q3, walker, (w3, w4, w1, w2), e)
    fast = heel_strike_impact(
        q3, walker=walker, q3_dot=w3, q4_dot=w4, q1_dot=w1, q2_dot=w2, restitution=e
    )
    scale = np.max(np.abs(ref.velocity_pre), axis=-1)
    _assert_close(fast, ref, scale, np.asarray(walker.total_mass) * np.maximum(l, 1.0), factor)


@pytest.mark.slow
@settings(max_examples=100, deadline=None)
@given(
    q3=st.floats(-1.0, 1.0),
    r_frac=st.floats(0.0, 1.0),
    w=st.tuples(*(st.floats(-5.0, 5.0) for _ in range(4))),
)
def test_heel_strike_fast_paper_walker_flat_1e12(
    q3: float, r_frac: float, w: tuple[float, float, float, float]
) -> None:
    """The paper's walker (cond(M) < 150), any velocities: agreement within 1e-12 flat."""
    walker = CompassGait(foot_radius=r_frac)
    arrays = (np.asarray(w[0]), np.asarray(w[1]), np.asarray(w[2]), np.asarray(w[3]))
    ref, factor = _reference(np.asarray(q3), walker, arrays, 0.0)
    assert factor == 1.0
    fast = heel_strike_impact(q3, walker=walker, q3_dot=w[0], q4_dot=w[1], q1_dot=w[2], q2_dot=w[3])
    _assert_close(fast, ref, np.max(np.abs(ref.velocity_pre)) + 1e-300, np.asarray(20.0))


def test_heel_strike_fast_outer_grid_and_paper_facts() -> None:
    """An (impact angle x foot radius) grid broadcasts like the reference; R = l loses nothing."""
    q3 = np.linspace(0.0, np.pi / 4, 7)[:, None]
    R = np.linspace(0.0, 1.0, 5)[None, :]
    walker = CompassGait(foot_radius=R)
    ref, _ = _reference(
        q3, walker, (np.asarray(1.0), np.asarray(0.0), None, np.asarray(0.0)), 0.0
    )
    fast = heel_strike_impact(q3, foot_radius=R)
    assert fast.kinetic_energy.shape == (7, 5)
    assert fast.velocity_post.shape == (7, 5, 4)
    assert fast.constraint_impulse.shape == (7, 5, 2)
    _assert_close(fast, ref, np.asarray(1.0), np.asarray(20.0))
    np.testing.assert_array_equal(fast.q2_dot_post, fast.velocity_post[..., 1])
    assert np.all(fast.kinetic_energy_constrained[:, -1] == 0.0)  # McGeer's wheel
    assert np.all(np.diff(fast.kinetic_energy_constrained[1:], axis=1) < 0.0)


def test_heel_strike_fast_same_from_worker_thread() -> None:
    """Off the main thread the serial kernel runs; results are bitwise identical."""
    q3 = np.linspace(0.05, 0.7, 1001)
    main = heel_strike_impact(q3, foot_radius=0.3)
    out: list[object] = []
    t = threading.Thread(target=lambda: out.append(heel_strike_impact(q3, foot_radius=0.3)))
    t.start()
    t.join()
    other = out[0]
    for a, b in zip(main, other, strict=True):  # type: ignore[call-overload]
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"foot_radius": 1.5}, "foot_radius"),
        ({"foot_radius": -0.1}, "foot_radius"),
        ({"leg_mass": 0.0}, "leg_mass"),
        ({"leg_com_from_hip": 1.0}, "leg_com_from_hip"),
        ({"leg_inertia": -1.0}, "leg_inertia"),
        ({"q3_dot": np.nan}, "non-finite"),
        ({"restitution": 1.5}, "restitution"),
        ({"q3_dot": np.ones(3), "q4_dot": np.ones(4)}, "broadcast"),
    ],
)
def test_heel_strike_fast_rejects_invalid(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ImpactInputError, match=match):
        heel_strike_impact(np.linspace(0.1, 0.3, 12).reshape(3, 4)[..., :1], **kwargs)  # type: ignore[arg-type]


def test_heel_strike_fast_reports_bad_item_in_batch() -> None:
    R = np.full(100, 0.2)
    R[57] = 2.0
    with pytest.raises(ImpactInputError, match="index 57"):
        heel_strike_impact(0.2, foot_radius=R)
