"""Where the compiled kernels run in parallel: the one rule (no numba import here)."""

from __future__ import annotations

import threading

__all__ = ["use_parallel"]


def use_parallel(parallel: bool | None) -> bool:
    """Resolve the ``parallel`` option of the fast kernels.

    ``None`` means: parallel on the main thread, serial on any other thread (e.g. a Dask
    worker thread, so that chunk-level and item-level parallelism do not oversubscribe the
    cores).
    """
    if parallel is None:
        return threading.current_thread() is threading.main_thread()
    return bool(parallel)
