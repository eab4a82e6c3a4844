"""A search's time limit does not count one-time kernel compilation (first runs on a new machine).

``heelstrike powered`` bounds its search by :data:`~heelstrike.analysis.powered.DEFAULT_TIME_LIMIT`
(45 s). On an empty cache the first command also builds its kernels (a described walker's
ahead-of-time module takes about 50 s), which used to count against the limit, so the README's
``powered`` commands failed on their first run. :func:`heelstrike.dynamics._aot.compile_seconds`
measures compiling (``pycc`` builds and numba JIT compiles, nested compiles once) and the search
subtracts it.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from numba import njit

from heelstrike.analysis.powered import PoweredGaitNotFoundError, find_powered_gait
from heelstrike.dynamics import _aot, _compass_kernels  # noqa: F401  (registers the listener)
from heelstrike.dynamics.hybrid import simulate
from heelstrike.models.compass import CompassGait


def test_numba_compiles_are_counted_once() -> None:
    @njit  # a new function: compiled now, not loaded from a cache
    def inner(x: float) -> float:
        return np.sin(x) * x + 1.0

    @njit
    def outer(x: float) -> float:
        return inner(x) + inner(2.0 * x)

    before = _aot.compile_seconds()
    t0 = time.monotonic()
    outer(0.3)
    wall = time.monotonic() - t0
    counted = _aot.compile_seconds() - before
    # compiled (outer compiles inner inside its own compile): counted, and only once
    assert 0.0 < counted <= wall + 1e-6
    before = _aot.compile_seconds()
    outer(0.4)  # already compiled: nothing counted
    assert _aot.compile_seconds() == before


class _SlowFirstStep:
    """``simulate`` whose first call takes ``delay`` s on a fake clock, as compiling or not."""

    def __init__(self, delay: float, compiling: bool, clock: list[float]) -> None:
        self.delay, self.compiling, self.clock, self.calls = delay, compiling, clock, 0

    def __call__(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        self.calls += 1
        if self.calls == 1:
            if self.compiling:
                _aot._CLOCK.start()
            self.clock[0] += self.delay
            if self.compiling:
                _aot._CLOCK.end()
        return simulate(*args, **kwargs)


@pytest.fixture
def fake_clock(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    offset = [0.0]
    real = time.monotonic
    monkeypatch.setattr(time, "monotonic", lambda: real() + offset[0])
    return offset


def test_time_limit_excludes_compiling(fake_clock: list[float]) -> None:
    walker = CompassGait()
    sim = _SlowFirstStep(100.0, compiling=True, clock=fake_clock)
    gait = find_powered_gait(walker, speed=0.5, time_limit=45.0, simulator=sim)
    assert gait.speed == pytest.approx(0.5, abs=1e-8)
    assert sim.calls > 1


def test_time_limit_still_bounds_the_search(fake_clock: list[float]) -> None:
    sim = _SlowFirstStep(100.0, compiling=False, clock=fake_clock)
    with pytest.raises(PoweredGaitNotFoundError, match=r"gave up after 45 s \(time limit;"):
        find_powered_gait(CompassGait(), speed=0.5, time_limit=45.0, simulator=sim)
