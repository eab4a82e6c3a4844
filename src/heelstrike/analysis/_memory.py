"""Bounds checked before large computations: one rule for every grid, walk and study.

:func:`require_budget` is the one check every command makes before it allocates or computes
anything: the number of points (a product of grid sizes, times steps walked at each), the
memory they need against what the machine has (:func:`available_memory`), and the estimated
time against :data:`MAX_RUN_SECONDS`. The estimates are stated constants (per point, per
walker-step), not timings of this machine, so the same arguments are refused everywhere.
"""

from __future__ import annotations

import math
import os

__all__ = [
    "GAIT_SEARCH_BYTES",
    "GAIT_SEARCH_STEPS",
    "MAX_RUN_SECONDS",
    "WALKER_STEP_BYTES",
    "WALKER_STEP_SECONDS",
    "RunTooLongError",
    "available_memory",
    "require_budget",
    "require_memory",
]

_GIB = 1024.0**3

#: The longest run (s, estimated) a command starts: 24 hours. Longer ones are refused before
#: computing, with the estimate; split them, or call the library, which checks memory only.
MAX_RUN_SECONDS = 24 * 3600.0

#: Estimated time (s) of one walker-step (a stance phase and its heel strike) by backend, an
#: upper estimate for the shipped walkers: the compiled kernels take tens of microseconds, the
#: scipy reference about 10,000 walker-steps a minute.
WALKER_STEP_SECONDS = {"compiled": 1e-4, "scipy": 6e-3}

#: Memory (bytes) a walker-step keeps when its samples are recorded (``walk``: states at the
#: dense output times, events and energies), an upper estimate.
WALKER_STEP_BYTES = 16384

#: Walker-steps of one gait search (Newton iterations with finite-difference Jacobians), an
#: upper estimate: the cost of a cell of a gait map in walker-steps.
GAIT_SEARCH_STEPS = 200

#: Memory (bytes) of one found gait (fixed point, multipliers, period), files and figures
#: included, an upper estimate: a cell of a gait map.
GAIT_SEARCH_BYTES = 4096


class RunTooLongError(ValueError):
    """A computation whose estimated time exceeds :data:`MAX_RUN_SECONDS`."""


def available_memory() -> int | None:
    """Memory (bytes) available to a new computation without swapping, or None if unknown.

    ``MemAvailable`` of ``/proc/meminfo`` on Linux, else the free physical pages.
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def require_memory(need: int, what: str, hint: str = "use a smaller grid") -> None:
    """Raise ``MemoryError`` (before any computing) if ``need`` bytes exceed the available
    memory (:func:`available_memory`; nothing is checked when it is unknown).

    Parameters
    ----------
    need : int
        Estimated peak memory (bytes) of the computation.
    what : str
        What needs it, for the message (e.g. ``"a 400x400 basin"``).
    hint : str
        What to change, for the message (e.g. ``"use a smaller --grid"``).
    """
    free = available_memory()
    if free is not None and need > free:
        raise MemoryError(
            f"{what} needs about {need / _GIB:.3g} GiB of memory and {free / _GIB:.3g} GiB are "
            f"available: {hint}"
        )


def require_budget(
    what: str,
    points: int,
    *,
    bytes_per_point: float,
    seconds_per_point: float | None = None,
    hint: str = "use a smaller grid",
) -> None:
    """Refuse a computation, before it allocates anything, that would not fit the machine.

    Parameters
    ----------
    what : str
        What is computed, for the message (``"a 400x400 basin"``).
    points : int
        Number of points computed (the product of the grid sizes; times the steps walked at
        each where each point is a walk). Python integers: no overflow.
    bytes_per_point : float
        Estimated memory of a point (bytes), its share of files and figures included.
    seconds_per_point : float, optional
        Estimated time of a point (s); None: time is not checked.
    hint : str
        The options to change, for the message (``"use a smaller --grid"``).

    Raises
    ------
    MemoryError
        The estimated memory exceeds the available memory (:func:`require_memory`).
    RunTooLongError
        The estimated time exceeds :data:`MAX_RUN_SECONDS`.
    """
    points = int(points)
    need = points * bytes_per_point
    require_memory(int(need) if math.isfinite(need) else 2**63, what, hint)
    if seconds_per_point is None:
        return
    seconds = points * seconds_per_point
    if seconds > MAX_RUN_SECONDS:
        raise RunTooLongError(
            f"{what} would take about {seconds / 3600:.3g} hours ({points:,} points at about "
            f"{seconds_per_point:.3g} s each, an estimate); commands start no run longer than "
            f"{MAX_RUN_SECONDS / 3600:g} hours: {hint}"
        )
