"""Memory checks before large grid computations: one rule for basins, impact maps and studies."""

from __future__ import annotations

import os

__all__ = ["available_memory", "require_memory"]

_GIB = 1024.0**3


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


def require_memory(need: int, what: str) -> None:
    """Raise ``MemoryError`` (before any computing) if ``need`` bytes exceed the available
    memory (:func:`available_memory`; nothing is checked when it is unknown).

    Parameters
    ----------
    need : int
        Estimated peak memory (bytes) of the computation.
    what : str
        What needs it, for the message (e.g. ``"a 400x400 basin"``).
    """
    free = available_memory()
    if free is not None and need > free:
        raise MemoryError(
            f"{what} needs about {need / _GIB:.3g} GiB of memory and {free / _GIB:.3g} GiB are "
            "available: use a smaller grid"
        )
