"""The numba kernels written once: serial/parallel twins and the shared DP5 drivers.

A batch kernel is one Python function compiled twice (:func:`heelstrike.core.fast.
serial_and_parallel`); each compile must keep its own disk-cache entry (numba keys the cache by
the function's name and bytecode, not by ``parallel=True``), and both must give the same
results. The DP5 drivers of :func:`heelstrike.dynamics._dp5.integrator` are compiled into the
walking kernels, which must stay disk-cacheable.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from heelstrike.core.fast import serial_and_parallel
from heelstrike.core.impact import impact
from heelstrike.dynamics import _compass_kernels, compiled
from heelstrike.dynamics.compiled import ensemble_walk, walker_parameters
from heelstrike.models import compass_fast
from heelstrike.models.compass import CompassGait
from heelstrike.models.compass_fast import heel_strike_impact

TWINS = {
    "ensemble_walk": (_compass_kernels._ensemble_serial, _compass_kernels._ensemble_parallel),
    "heel_strike_impact": compass_fast._KERNELS,
}


def _index_path(dispatcher: Any) -> Path:
    return Path(dispatcher._cache._cache_file._index_path)


@pytest.mark.parametrize("name", sorted(TWINS))
def test_twin_kernels_are_serial_and_parallel_with_their_own_cache(name: str) -> None:
    serial, parallel = TWINS[name]
    assert serial.py_func.__code__ is parallel.py_func.__code__  # one body, written once
    assert parallel.targetoptions.get("parallel") is True
    assert not serial.targetoptions.get("parallel", False)
    assert _index_path(serial) != _index_path(parallel)


def test_serial_and_parallel_compile_a_prange_loop_both_ways() -> None:
    from numba import prange

    def double(x: Any, out: Any) -> None:
        for i in prange(x.shape[0]):
            out[i] = 2.0 * x[i]

    serial, parallel = serial_and_parallel(double)
    x = np.linspace(-1.0, 1.0, 101)
    outs = [np.empty_like(x), np.empty_like(x)]
    serial(x, outs[0])
    parallel(x, outs[1])
    np.testing.assert_array_equal(outs[0], 2.0 * x)
    np.testing.assert_array_equal(outs[1], 2.0 * x)
    assert serial.py_func.__qualname__.endswith("double_serial")
    assert parallel.py_func.__qualname__.endswith("double_parallel")


def test_ensemble_walk_serial_equals_parallel_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    z = np.array([-0.26682122, 1.08394013, -0.68587173]) + rng.normal(0.0, 0.02, (12, 3))
    radii = rng.uniform(0.0, 0.4, 12)
    runs = [ensemble_walk(CompassGait(foot_radius=radii), z, 0.05, steps=3, parallel=par)
            for par in (False, True)]
    assert len(set(runs[0].status.tolist())) >= 2  # walks and falls both exercised
    for field in ("z", "state", "status", "steps", "time", "impact_angle", "step_time",
                  "collision_loss", "step_length"):
        np.testing.assert_array_equal(getattr(runs[0], field), getattr(runs[1], field))


def test_impact_kernels_serial_equal_parallel_bit_for_bit() -> None:
    angles = np.linspace(-0.45, -0.05, 37)
    a, b = (heel_strike_impact(angles, foot_radius=0.3, q4_dot=-0.4, parallel=par)
            for par in (False, True))
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(a.q2_dot_post, b.q2_dot_post)
    w = CompassGait(foot_radius=0.3)
    qs = [np.array([0.0, 0.3, t, -2.0 * t]) for t in angles]
    M = np.array([w.mass_matrix(q) for q in qs])
    A = np.array([w.contact_jacobian(q, "left") for q in qs])
    qd = np.column_stack((np.full(37, -0.3), np.zeros(37), np.ones(37), np.full(37, -0.4)))
    c = impact(M, A, qd)
    # the compass closed form and the general (reference) solve agree: same impact, two codes
    np.testing.assert_allclose(a.velocity_post, c.velocity_post, rtol=1e-12, atol=1e-12)


def test_walking_kernel_with_shared_drivers_is_disk_cacheable() -> None:
    # functions passed as arguments would be lowered as process addresses ("dynamic globals"),
    # which numba refuses to cache; the drivers take them as closure constants instead
    p = walker_parameters(CompassGait(), 0.05)
    y = np.array([-0.26682122, 0.53364244, 1.08394013, -0.68587173])
    integrate_phase = _compass_kernels._integrate_phase
    ev, t, _ = integrate_phase(p, y, 0.0, 5.0, 1, 0.0, 1e-10, 1e-10, np.empty((7, 4)))
    assert ev == compiled._EV_MID and 0.0 < t < 1.0
    overloads: dict[Any, Any] = _compass_kernels._integrate_phase.overloads
    assert overloads
    for cres in overloads.values():
        assert not cres.library.has_dynamic_globals
