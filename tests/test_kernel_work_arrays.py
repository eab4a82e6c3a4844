"""The generated kernel's borrowed work arrays (``_phased_kernels._borrow``) are safe.

The integrator passes its work arrays to the right-hand side and the events as views without a
memory-info pointer (no atomic reference counting per call, which was about 60 % of the
kernel's time), while the owning arrays are kept alive by the segment. A view that outlived its
owner would read freed memory: results would change from run to run, or between the serial and
threaded ensembles, or differ from walks of one walker at a time. None may.
"""

from __future__ import annotations

import gc

import numpy as np
import pytest

from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.dynamics.compiled_phased import ensemble_walk_phased, simulate_phased_compiled
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker

SLOPE = float(np.deg2rad(3.0))


@pytest.fixture(scope="module")
def kneed_states() -> tuple[PhasedWalker, np.ndarray]:
    w = load_phased_walker("kneed")
    z = np.asarray(find_model_gait(w, slope=SLOPE).fixed_point)
    Z = z + np.random.default_rng(7).normal(scale=0.03, size=(120, z.size))
    return w, Z


def _run(w: PhasedWalker, Z: np.ndarray, parallel: bool) -> tuple[np.ndarray, ...]:
    e = ensemble_walk_phased(w, Z, slope=SLOPE, steps=6, rtol=1e-8, atol=1e-9,
                             parallel=parallel)
    return np.asarray(e.z), np.asarray(e.status), np.asarray(e.steps)


def test_ensembles_are_bit_identical_run_to_run_and_across_threads(kneed_states) -> None:  # type: ignore[no-untyped-def]
    w, Z = kneed_states
    first = _run(w, Z, parallel=False)
    # churn the allocator: freed memory that a stale view might read gets overwritten
    junk = [np.full((500, 500), np.nan) for _ in range(8)]
    del junk
    gc.collect()
    again = _run(w, Z, parallel=False)
    threaded = _run(w, Z, parallel=True)
    for a, b, c in zip(first, again, threaded, strict=True):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)
    # the outcomes are varied (walks that converge, fall, lose contact), not one path
    assert len(set(first[1].tolist())) > 1


def test_ensemble_equals_walks_of_one_walker_at_a_time(kneed_states) -> None:  # type: ignore[no-untyped-def]
    w, Z = kneed_states
    z, status, steps = _run(w, Z[:12], parallel=False)
    for i in range(12):
        q, qd = w.section_to_state(Z[i])
        walk = simulate_phased_compiled(w, q, qd, slope=SLOPE, steps=6, rtol=1e-8, atol=1e-9)
        assert walk.n_steps == steps[i]
        assert walk.status.code == status[i]
        if walk.ok:
            np.testing.assert_array_equal(w.state_to_section(walk.final_q, walk.final_q_dot),
                                          z[i])
